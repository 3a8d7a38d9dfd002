"""Error budget: quadrature shares of sources switched off one at a time."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

from machinesim.budget import (
    FIGURES_PER_PANEL,
    Budget,
    BudgetRow,
    clipped_shares,
    error_budget,
    quadrature_share,
)
from machinesim.exceptions import InputError, MachineSimError
from machinesim.experiment import Figure
from machinesim.report import ReportFolder, check_summary

#: Independent synthetic sources: each adds its error, um, in quadrature to each figure.
SOURCES = {"instrument_noise": (0.3, 1.2), "artefact_errors": (0.4, 0.0),
           "background": (1.2, 0.5)}
#: What no listed source explains (the identification's own residual), um.
RESIDUAL = (0.1, 0.2)


def synthetic_run(off):
    """A result whose "after" figures are the quadrature sum of the sources that are on."""
    figures = []
    for k, name in enumerate(("a_dx", "a_dy")):
        squares = RESIDUAL[k] ** 2 + sum(v[k] ** 2 for s, v in SOURCES.items() if s != off)
        figures.append(Figure(name, "um", 100.0, -math.sqrt(squares)))
    figures.append(Figure("not_measured", "um", 1.0, None))
    return SimpleNamespace(figures=tuple(figures))


def test_shares_of_independent_sources_are_their_squares_over_the_total():
    budget = error_budget(synthetic_run, list(SOURCES))
    assert budget.figures == ("a_dx", "a_dy") and budget.sources == tuple(SOURCES)
    for k, figure in enumerate(budget.figures):
        total = RESIDUAL[k] ** 2 + sum(v[k] ** 2 for v in SOURCES.values())
        for source, values in SOURCES.items():
            assert budget.share(source, figure) == pytest.approx(values[k] ** 2 / total,
                                                                 abs=1e-12)
        # the shares of independent sources sum to 1 - residual^2 / total
        assert budget.unexplained(figure) == pytest.approx(RESIDUAL[k] ** 2 / total, abs=1e-12)
    row = budget.rows[0]
    assert row.after_all == pytest.approx(-math.sqrt(0.1**2 + 0.3**2 + 0.4**2 + 1.2**2))


def test_quadrature_share_by_hand():
    assert quadrature_share(5.0, 3.0) == pytest.approx(16.0 / 25.0)  # 3-4-5 triangle
    assert quadrature_share(-5.0, 4.0) == pytest.approx(9.0 / 25.0)
    assert math.isnan(quadrature_share(0.0, 2.0))  # a share of nothing: undefined
    assert quadrature_share(1.0, 2.0) == pytest.approx(-3.0)  # switching off made it worse
    with pytest.raises(InputError, match="finite"):
        quadrature_share(np.nan, 1.0)


def test_table_dict_and_plot_round_trip(tmp_path):
    budget = error_budget(synthetic_run, list(SOURCES))
    assert Budget.from_dict(json.loads(json.dumps(budget.to_dict()))) == budget
    table = budget.table()
    lines = [line for line in table.splitlines() if line.startswith("| a_dy |")]
    assert len(lines) == len(SOURCES) + 1
    total = RESIDUAL[1] ** 2 + sum(v[1] ** 2 for v in SOURCES.values())
    assert f"{100 * 1.2**2 / total:.1f} %" in lines[0]
    budget.plot(tmp_path / "budget.png")
    assert (tmp_path / "budget.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_plot_clips_shares_beyond_its_axis_and_writes_their_values(tmp_path):
    """A figure near 0 with every source on gives shares of -40000 % when one source off
    moves it: drawn to the axis's edge with the value beside it, the other bars readable."""
    heights, labels = clipped_shares([50.0, -40169.9, 100.0, 250.4, -100.0], 100.0)
    assert heights == [50.0, -100.0, 100.0, 100.0, -100.0]
    assert labels == ["", "-40170 %", "", "250 %", ""]
    # many figures go to panels one under the other: the picture grows down, not across
    rows = [BudgetRow(source, f"figure_{i}", "um", 1.0, 0.5, 0.75)
            for i in range(3 * FIGURES_PER_PANEL) for source in SOURCES]
    sizes = {}
    for n in (FIGURES_PER_PANEL, 3 * FIGURES_PER_PANEL):
        path = tmp_path / f"budget_{n}.png"
        Budget(tuple(r for r in rows if int(r.figure.split("_")[1]) < n)).plot(path)
        header = path.read_bytes()[16:24]
        sizes[n] = (int.from_bytes(header[:4], "big"), int.from_bytes(header[4:], "big"))
    wide, tall = sizes[FIGURES_PER_PANEL], sizes[3 * FIGURES_PER_PANEL]
    assert tall[0] == wide[0] and tall[1] > 2.5 * wide[1]


def test_the_report_writes_the_budget_and_the_summary_accepts_it(tmp_path):
    budget = error_budget(synthetic_run, list(SOURCES))
    folder = ReportFolder(tmp_path / "out")
    text = folder.write_budget(budget)
    assert budget.table() in text
    # the budget's figures are the summary's (a budget of figures it has not is refused)
    figures = [f.as_dict() for f in synthetic_run(None).figures]
    base = {"paper": "001", "procedure": "p", "machine": "m", "seed": 0, "noise": False,
            "injected": {}, "identified": {}, "figures": figures, "budget": budget.to_dict()}
    folder.write_summary(base)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert Budget.from_dict(summary["budget"]) == budget
    assert {"budget.md", "budget.png"} <= set(summary["files"])
    bad_row = {**budget.to_dict()[0], "share": "big"}
    for rows, message in (({"a": 1}, "as a list"), ([{"source": "x"}], "exactly the keys"),
                          ([bad_row], "share must be a finite number"),
                          ([{**bad_row, "share": 0.1, "unit": ""}], "unit must be")):
        with pytest.raises(InputError, match=message):
            check_summary({**base, "budget": rows})


#: A misfit note as `machinesim.experiment.fit_notes` leads it, with its numbers as {}.
MISFIT = ("fit_check (heights): the readings do not fit the model: normalised residual {} "
          "(about 1 when the model holds every error the readings show and sigma is right; "
          "above {} by chance with probability {} at {} degrees of freedom; residual RMS {} "
          "m): an error missing from the parameters or the prior, or sigma "
          "too small; the values may be far off")


def test_a_reruns_notes_reach_its_rows_budget_md_and_summary_json(tmp_path):
    """The identification's notes of a run with one source off (a misfit) reach its budget
    rows, budget.md under the table and its rows in summary.json; a rerun that notes nothing,
    or only what the run with every source on notes (numbers aside), adds none. Before, the
    reruns' notes were dropped: a row resting on a misfit looked as sound as any."""
    misfit = MISFIT.format(7.25, 1.34, 0.001, 42, "3.1e-08")
    notes = {None: (), "instrument_noise": (), "artefact_errors": (misfit,),
             "background": ()}

    def noting(off):
        return SimpleNamespace(figures=synthetic_run(off).figures, notes=notes[off])

    budget = error_budget(noting, list(SOURCES))
    assert budget.notes == {"artefact_errors": (misfit,)}
    assert {row.source: row.notes for row in budget.rows} == {
        "instrument_noise": (), "artefact_errors": (misfit,), "background": ()}
    rows = budget.to_dict()
    assert [row["notes"] for row in rows if "notes" in row] == [[misfit]] * 2  # two figures
    assert all(("notes" in row) == (row["source"] == "artefact_errors") for row in rows)
    folder = ReportFolder(tmp_path / "out")
    text = folder.write_budget(budget)
    assert text == (tmp_path / "out" / "budget.md").read_text()
    assert text.endswith(budget.table() + "\nThe identification of a run with one source "
                         "off noted what the run with every source on did not (numbers "
                         "aside): its rows' 'after, source off' rest on that "
                         f"identification.\n\n- artefact_errors off: {misfit}\n")
    figures = [f.as_dict() for f in synthetic_run(None).figures]  # the budget's figures
    base = {"paper": "001", "procedure": "p", "machine": "m", "seed": 0, "noise": False,
            "injected": {}, "identified": {}, "figures": figures, "budget": rows}
    folder.write_summary(base)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    check_summary(summary)
    assert summary["budget"] == rows and Budget.from_dict(summary["budget"]) == budget
    for bad in ("one", [], [""], [3]):
        with pytest.raises(InputError, match="notes must be a non-empty list"):
            check_summary({**base, "budget": [{**rows[1], "notes": bad}]})

    # the run with every source on misfits too: the same kind of note, other numbers, is not
    # the rerun's own; another kind is
    apart = "fit_check (heights): tool.y and tool.z are barely told apart (correlation 0.999)"
    notes.update({None: (MISFIT.format(3.5, 1.34, 0.001, 42, "1.2e-08"),),
                  "background": (misfit, apart)})
    budget = error_budget(noting, list(SOURCES))
    assert budget.notes == {"background": (apart,)}
    assert "artefact_errors off" not in budget.notes_text()
    assert error_budget(synthetic_run, list(SOURCES)).notes_text() == ""  # no notes at all


def test_bad_sources_and_runs_are_refused_clearly():
    for sources, message in (("background", "the string"), ([], "non-empty"),
                             (["a", "a"], "given twice"), ([None], "non-empty")):
        with pytest.raises(MachineSimError, match=message):
            error_budget(synthetic_run, sources)
    with pytest.raises(MachineSimError, match="expected a machinesim.experiment.Result"):
        error_budget(lambda off: 3.0, ["background"])

    def loses_a_figure(off):
        result = synthetic_run(off)
        return result if off is None else SimpleNamespace(figures=result.figures[1:])

    with pytest.raises(MachineSimError, match="'background' off the result has no 'after' "
                                              "for figure 'a_dx'"):
        error_budget(loses_a_figure, ["background"])
    with pytest.raises(MachineSimError, match="no row for source 'x'"):
        Budget((BudgetRow("s", "f", "um", 1.0, 0.5, 0.75),)).share("x", "f")


def test_a_budget_asked_for_with_no_source_on_says_so():
    """``--realism ideal`` with the budget on: no budget, and one progress line saying why
    (the folder had no budget.md and nothing said so)."""
    from machinesim.budget import realism_budget
    from machinesim.realism import Realism

    class Procedure:
        realism_sources = ("instrument_noise",)

    told = []

    def stage(name):
        return lambda text: told.append((name, text))

    assert realism_budget(Procedure(), None, Realism.ideal(), None, True, progress=stage) is None
    assert told == [("budget", "none: no source it shares out is on (realism ideal), so "
                               "budget.md and budget.png are not written")]
    told.clear()
    assert realism_budget(Procedure(), None, Realism.ideal(), None, False, progress=stage) is None
    assert told == []  # not asked for: nothing to say


def test_a_budget_without_the_all_on_result_names_the_result_before_any_rerun():
    """``result=None`` with a source on: refused by its name before any lab is built (with
    jobs=2 the refusal had named a realism switch None, from the worker's run(None))."""
    from machinesim.budget import realism_budget
    from machinesim.realism import Realism

    class Procedure:
        realism_sources = ("instrument_noise",)

    def make_lab(realism):
        raise AssertionError("no rerun before the result is checked")

    for jobs in (1, 2):
        with pytest.raises(InputError, match=r"realism_budget: expected result, the run with "
                           r"every switch on .*got NoneType") as raised:
            realism_budget(Procedure(), None, Realism.lab(), make_lab, jobs=jobs)
        assert raised.value.key == "result"


def test_a_procedure_budgets_only_the_switches_of_the_instruments_it_reads():
    # the laser's air (Realism.air_refraction) acts on the laser interferometer alone: paper
    # 002's budget had run it again and printed a 0.0 % row for every figure
    from machinesim.procedures.sts_turning import STSTurning
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm
    from machinesim.procedures.tool_setting_6axis import ToolSetting6Axis
    from machinesim.procedures.workpiece_setting import RobotLoadedWorkpiece
    from machinesim.procedures.xy_plane_errors import XYPlaneErrors
    from machinesim.realism import Realism

    for procedure in (STSTurning, ToolRotationArm, ToolSetting6Axis, RobotLoadedWorkpiece,
                      XYPlaneErrors):
        sources = set(procedure.realism_sources)
        assert sources <= set(Realism.names()), procedure
        reads_a_laser = any("laser_interferometer" in uses
                            for uses in procedure.lab_uses.values())
        assert ("air_refraction" in sources) == reads_a_laser, procedure


def test_a_run_that_cannot_be_called_or_rows_that_are_no_numbers_are_refused():
    # error_budget(5, [...]) ended in TypeError: 'int' object is not callable; a summary's
    # budget row with "after_all": "x" in ValueError from float(), rows that are no list in
    # TypeError: 'int' object is not iterable
    from machinesim.budget import Budget, error_budget
    from machinesim.exceptions import InputError

    with pytest.raises(InputError, match=r"error_budget: expected run as a callable, "
                                         r"run\(source or None\) -> Result, got 5") as info:
        error_budget(5, ["registration"])
    assert info.value.key == "run"
    row = {"source": "s", "figure": "f", "unit": "um", "after_all": 0.5,
           "after_without": 0.3, "share": 0.64}
    assert Budget.from_dict([row]).rows[0].share == 0.64
    for bad, message in (([{**row, "after_all": "x"}], r"budget\[0\]\.after_all must be a "
                                                        r"finite number, got 'x'"),
                         ([{**row, "share": None}], r"budget\[0\]\.share must be a finite "
                                                    r"number, got None"),
                         (5, r"budget: expected a list of rows, got int"),
                         # read as the source 'None', the figure '3' and the unit 'furlong'
                         ([{**row, "source": None}], r"budget\[0\]\.source must be a "
                                                     r"non-empty string, got None"),
                         ([{**row, "figure": 3}], r"budget\[0\]\.figure must be a non-empty "
                                                  r"string, got 3"),
                         ([{**row, "unit": "furlong"}], r"budget\[0\]\.unit 'furlong'; "
                                                        r"expected one of m, mm, um"),
                         # an int beyond float64 (JSON takes it): math.isfinite's OverflowError
                         ([{**row, "after_all": 10**400}], r"budget\[0\]\.after_all must be "
                                                           r"a finite number, got 1000000000"
                                                           r"000000000000000000000000000000"
                                                           r"\.\.\.000000000000 \(401 "
                                                           r"characters\)")):
        with pytest.raises(InputError, match=message):
            Budget.from_dict(bad)


def test_a_rerun_giving_a_figure_in_another_unit_is_refused():
    """A run function whose rerun gave the figure in nm where the all-on run gave um was
    compared number for number: 1 um against 500 nm, a share of -24999900 %."""
    def run(off):
        unit, after = ("um", 1.0) if off is None else ("nm", 500.0)
        return SimpleNamespace(figures=(Figure("a_dx", unit, 100.0, after),))

    with pytest.raises(InputError, match="figure 'a_dx' is in 'nm', with every source on "
                                         "in 'um'; expected one unit"):
        error_budget(run, ["instrument_noise"])


def test_a_share_of_a_figure_of_zero_is_undefined_in_the_table_plot_and_json(tmp_path):
    # a figure whose after is exactly 0 with every source on: (a^2 - b^2) / a^2 is 0/0, or
    # -b^2/0, and was written 0.0 % (the source "explains none of it", though switching it
    # off moved the figure to 0.4); now NaN: n/a in the table and the plot, null in
    # summary.json, read back as NaN
    def run(off):
        after = {None: 0.0, "instrument_noise": 0.4, "background": 0.0}[off]
        return SimpleNamespace(figures=(Figure("a_dx", "um", 1.0, after),
                                        Figure("a_dy", "um", 1.0, 0.5 if off else 1.0)))

    budget = error_budget(run, ["instrument_noise", "background"])
    assert all(math.isnan(budget.share(s, "a_dx")) for s in budget.sources)
    assert math.isnan(budget.unexplained("a_dx"))
    assert budget.share("instrument_noise", "a_dy") == pytest.approx(0.75)  # 1 - 0.5^2
    table = budget.table().splitlines()
    assert table[2:5] == ["| a_dx | um | instrument_noise | 0 | 0.4 | n/a |",
                          "| a_dx | um | background | 0 | 0 | n/a |",
                          "| a_dx | um | (none of these) | | | n/a |"]
    assert table[5] == "| a_dy | um | instrument_noise | 1 | 0.5 | 75.0 % |"
    assert clipped_shares([math.nan, 50.0], 100.0) == ([0.0, 50.0], ["n/a", ""])
    rows = budget.to_dict()
    assert [r["share"] for r in rows] == [None, None, pytest.approx(0.75),
                                          pytest.approx(0.75)]
    folder = ReportFolder(tmp_path / "out")
    folder.write_budget(budget)
    assert (tmp_path / "out" / "budget.png").stat().st_size > 0
    figures = [f.as_dict() for f in run(None).figures]
    folder.write_summary({"paper": "001", "procedure": "p", "machine": "m", "seed": 0,
                          "noise": False, "injected": {}, "identified": {},
                          "figures": figures, "budget": rows})
    read = json.loads((tmp_path / "out" / "summary.json").read_text())["budget"]
    assert [r["share"] for r in read[:2]] == [None, None]
    back = Budget.from_dict(read)
    assert math.isnan(back.share("background", "a_dx"))
    assert back.share("instrument_noise", "a_dy") == budget.share("instrument_noise", "a_dy")
    # null stays refused where the figure is not 0: there the share is a number
    with pytest.raises(InputError, match=r"budget\[2\]\.share must be a finite number, got "
                                         r"None \(null only where after_all is 0"):
        Budget.from_dict([*read[:2], {**read[2], "share": None}])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    summary["budget"][2]["share"] = None
    with pytest.raises(InputError, match=r"budget\[2\]\.share must be a finite number, got "
                                         r"None \(null only where after_all is 0"):
        check_summary(summary)


def test_a_budgets_reruns_keep_their_warnings_to_themselves(monkeypatch):
    # a procedure's MachineSimWarning (paper 003's uncut pyramids) was said once by the run
    # and again by each rerun with a source off, with the variant's figures: six lines
    import warnings
    from types import SimpleNamespace

    from machinesim import experiment
    from machinesim.budget import realism_budget
    from machinesim.exceptions import MachineSimWarning
    from machinesim.realism import Realism
    from machinesim.results import Figure

    class Procedure:
        realism_sources = ("instrument_noise", "lateral_noise")

    def rerun(procedure, lab, progress=None):
        warnings.warn(f"variant {lab}", MachineSimWarning, stacklevel=2)
        return SimpleNamespace(figures=(Figure("depth", "um", 1.0, 2.0),))

    monkeypatch.setattr(experiment, "run", rerun)
    everything = SimpleNamespace(figures=(Figure("depth", "um", 1.0, 3.0),))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        budget = realism_budget(Procedure(), everything, Realism.lab(), str)
    assert said == []
    # the reruns ran: each source's share of the 3 um is (9 - 4) / 9
    assert [row["share"] for row in budget.to_dict()] == pytest.approx([5 / 9] * 2)
