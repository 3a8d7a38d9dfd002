"""Paper 001 replay: tool setting errors of a 6-axis ultraprecision machine (A, B, C axes).

Run: ``.venv/bin/python scenarios/tool_setting_6axis.py`` (about 45 s with the
default lab realism and its error budget, 9 s with ``--budget off``, 3 s with
``--realism noise_only --budget off``, on 2 idle cores) with options

    --tool-offset-um dx,dy,dz   edge offset from the A/B centres, tool_mount axes: tool.x,
                                tool.y, tool.z (default 250,350,150: round values of the
                                paper's order, a tool set by hand to a few hundred um; the
                                paper gives no B value)
    --c-offset-um x,y           C-axis centre line from the edge: location.C.EX0C, EY0C
                                (default 100,850, the same: round values of the paper's order)
    --errors FILE.toml          any error model instead of those defaults (the two options
                                above, when given, on top)
    --realism ideal|noise_only|lab   how real the lab is (default lab: microscope spot,
                                lateral noise and stage registration, the machine's own
                                residual errors; docs/metrology.md)
    --budget on|off             the error budget: the run again with each source of the
                                realism off in turn (default on; docs/budget.md)
    --jobs N                    the budget's reruns at a time, each on a worker process
                                (default 1: one after the other, in this process; the
                                same budget to the bit either way)
    --noise on|off --seed N --out DIR   (default reports/tool_setting_6axis)

On robonano_ui with those errors injected, the procedure
(`machinesim.procedures.tool_setting_6axis.ToolSetting6Axis`: touch-off, A sets, C
triangle, B tilts) identifies them from virtual-microscope readings of the cut grooves,
rewrites the NC data, re-cuts and re-measures. It prints Table 1 of the paper beside the
simulated distances before and after compensation, the identified errors, and the
model-based cross-check (`fit`), and writes the report folder (docs/reports.md): figures and
identified tables, summary.json, the plates (PLY), the NC programs as cut and compensated,
the cut reports and groove layout plots. See docs/procedures/tool_setting_6axis.md.
"""

from __future__ import annotations

import machinesim.scenario_start  # noqa: F401  (first: Ctrl-C while loading is one line)

import math
import sys

import numpy as np

from machinesim.budget import LabInputs, realism_budget
from machinesim.cam.tool_setting_plates import CAPTURE_RANGE, CENTRE_RANGE, OFFSET_RANGE, Plan
from machinesim.errors import LARGEST_ERROR
from machinesim.exceptions import InputError
from machinesim.experiment import run
from machinesim.identification.tool_setting_6axis import PARAMETERS
from machinesim.procedures.tool_setting_6axis import (
    DEFAULT_INJECTED,
    ToolSetting6Axis,
    layout_lines,
)
from machinesim.report import ReportFolder, identified_notes
from machinesim.scenario_runs import (
    injected_errors,
    parse_floats,
    progress_printer,
    realism_from,
    realism_options,
    refuse_beyond_capture,
    scenario_arguments,
    scenario_status,
)
from machinesim.units import M_PER_MM, M_PER_NM, M_PER_UM

#: Printed under the identification when the machine's background errors are on.
BACKGROUND_NOTE = (
    "The procedure finds the edge's offsets from the machine's real A, B and C centres. "
    "With its background errors on, those sit 0.1-0.3 um off their nominal places "
    "(models/errors/background_robonano_ui.toml): the errors above include that, the std "
    "does not (docs/procedures/tool_setting_6axis.md).")
#: The injected errors without --errors (shared with the campaign, see the procedure).
DEFAULTS = DEFAULT_INJECTED
#: Table 1's row labels for the figures.
LABELS = {"a_dx": "A dx", "a_dy": "A dy", "c_dx": "C dx", "c_dy": "C dy",
          "b_depth_change_theta2": "B depth change at theta2",
          "b_depth_change_theta3": "B depth change at theta3"}


def main(argv=None) -> int:
    parser = scenario_arguments(__doc__.splitlines()[0], "reports/tool_setting_6axis")
    parser.add_argument("--tool-offset-um", default=None,
                        help="edge offset dx,dy,dz from the A/B centres (um; default "
                        f"250,350,150; each within +-{OFFSET_RANGE / M_PER_UM:g}, the plan's "
                        "capture range)")
    parser.add_argument("--c-offset-um", default=None,
                        help="C-axis centre line x,y from the edge (um; default "
                        f"100,850; |(x, y)| <= {CENTRE_RANGE / M_PER_UM:g}, the plan's capture "
                        "range)")
    realism_options(parser)
    args = parser.parse_args(argv)
    return scenario_status(_configured, args, "tool_setting_6axis")


def _configured(args) -> None:
    """The run the command line asks for: its errors, then `report`."""
    given = {}
    if args.tool_offset_um is not None:
        values = _lengths(args.tool_offset_um, 3, "--tool-offset-um")
        given.update(zip(PARAMETERS[:3], (v * M_PER_UM for v in values), strict=True))
    if args.c_offset_um is not None:
        values = _lengths(args.c_offset_um, 2, "--c-offset-um")
        given.update(zip(PARAMETERS[3:], (v * M_PER_UM for v in values), strict=True))
    errors, realism = injected_errors(args, DEFAULTS, given, "robonano_ui"), realism_from(args)
    _check_capture(args, errors.parameters())
    # plain data, so that --jobs can build the budget's labs on worker processes
    report(args, LabInputs("robonano_ui", errors, seed=args.seed), realism)


def _lengths(text: str, count: int, option: str) -> list[float]:
    """``option``'s ``count`` lengths (um), refused naming the option beyond the largest
    length error an error model takes (1 m): the model's own refusal named its key
    (``key 'offset': 1000 m is no length error``), no option of this command line."""
    values = parse_floats(text, count, option)
    largest = LARGEST_ERROR["length"] / M_PER_UM
    worst = max(values, key=abs)
    if abs(worst) > largest:
        raise InputError(f"{option} {text!r}: {worst:g} um is no length error: expected at "
                         f"most {largest:g} um (1 m) either way", key=option.lstrip("-"))
    return values


def _check_capture(args, injected: dict[str, float]) -> None:
    """Refuse, before anything is cut, a tool offset d or C centre line e (``injected``,
    SI by `ErrorModel.parameters`) beyond the plan's capture range (`CAPTURE_RANGE`: each of
    dx, dy, dz within `OFFSET_RANGE`, |e| within `CENTRE_RANGE`), naming the option or the
    ``--errors`` file and key that set it: beyond it a plate reading finds no groove, or no
    end face, only after the plates are cut (docs/procedures/tool_setting_6axis.md)."""
    limit = OFFSET_RANGE / M_PER_UM
    for label, name in zip(("dx", "dy", "dz"), PARAMETERS[:3], strict=True):
        value = injected.get(name, 0.0)
        if abs(value) > OFFSET_RANGE:
            refuse_beyond_capture(
                args, {"--tool-offset-um": (args.tool_offset_um,
                                            f"dx, dy, dz each within +-{limit:g} um")},
                (name,), f"the tool offset {label} = {value / M_PER_UM:.12g} um",
                f"({CAPTURE_RANGE})", f"{name} within +-{limit:g} um")
    x, y = (injected.get(name, 0.0) for name in PARAMETERS[3:])
    if math.hypot(x, y) > CENTRE_RANGE:
        limit = CENTRE_RANGE / M_PER_UM
        refuse_beyond_capture(
            args, {"--c-offset-um": (args.c_offset_um, f"|(x, y)| <= {limit:g} um")},
            PARAMETERS[3:], f"the C centre line |e| = {math.hypot(x, y) / M_PER_UM:.12g} um",
            f"({CAPTURE_RANGE})", f"|({', '.join(PARAMETERS[3:])})| <= {limit:g} um")


def report(args, make_lab, realism) -> None:
    """Run the procedure on ``make_lab(realism)``, with the error budget when asked for."""
    procedure = ToolSetting6Axis()
    print(f"Paper 001 on robonano_ui: realism {realism}, seed {args.seed}\n")
    stage = progress_printer("tool_setting_6axis")
    result = run(procedure, make_lab(realism), progress=stage("run"))
    budget = realism_budget(procedure, result, realism, make_lab, args.budget == "on",
                            progress=stage, jobs=args.jobs)
    folder = ReportFolder(args.out)
    folder.write_json("cuts.json", result.evaluation.details["cuts"])
    details = result.evaluation.details
    for stage, key, title in (
            ("a", "a_ends_um", "A-axis grooves back from their measured end points"),
            ("c", "c_vertices_um", "C-axis triangle from the groove crossings")):
        series = [(f"{state}: {what}", xy[:, 0] / M_PER_MM, xy[:, 1] / M_PER_MM)
                  for state in ("before", "after")
                  for what, xy in layout_lines(stage, np.asarray(details[state][key])
                                               * M_PER_UM)]
        folder.plot(f"layout_{stage}_axis.png", series, xlabel="x (mm)", ylabel="y (mm)",
                    title=title)
    table = table_1(folder, result)
    ident = identification_table(folder, result, procedure.plan)
    check = check_table(folder, details["fit_check"])
    budget_text = folder.write_result(result, budget=budget).split("### Error budget")
    folder.publish(last=True)
    print(table)
    print(ident)
    notes = identified_notes(result)  # identified.md's; this script prints its own table
    if notes:
        print(notes + "\n")
    if realism.background_errors:
        print(BACKGROUND_NOTE + "\n")
    print(check)
    if budget is not None:
        print("### Error budget" + budget_text[-1])
    print(f"report folder: {folder.final}")


def table_1(folder, result) -> str:
    """Table 1 of the paper beside the simulated distances (um), with the after's standard
    uncertainty over labs (`Figure.after_std`) and the paper's after in units of it."""
    rows = [[LABELS[f.name], _cell(f.paper_before), _cell(f.paper_after), f.before, f.after,
             _cell(f.after_std), _in_stds(f.paper_after, f.after_std)]
            for f in result.figures]
    return folder.write_table(
        "table1", ["distance between grooves", "paper original (um)",
                   "paper compensated (um)", "simulated before (um)", "simulated after (um)",
                   "after std over labs (um)", "paper compensated / std"],
        rows, title="Paper 001, Table 1: measured machining errors against A and C axis",
        digits=4)


def identification_table(folder, result, plan: Plan) -> str:
    """Injected and identified d and e, and the two second readings of the procedure."""
    found = result.identification.detail
    truth = result.injected
    # dX: the edge's offset from the B centre in machine X at A = theta1 (docs/procedures)
    dx = (truth["tool.x"] * math.cos(plan.theta1) - truth["tool.y"] * math.sin(plan.theta1))
    names = ["tool dx", "tool dy", "tool dz (B: dZ)", "C centre x", "C centre y"]
    rows = [[label, truth[name] / M_PER_UM, result.identified[name][0] / M_PER_UM,
             (result.identified[name][0] - truth[name]) / M_PER_NM,
             result.identified[name][1] / M_PER_NM]
            for label, name in zip(names, PARAMETERS, strict=True)]
    rows += [["B: dX (machine X at A = theta1)", dx / M_PER_UM, found.b.offset_x / M_PER_UM,
              (found.b.offset_x - dx) / M_PER_NM, math.nan],
             ["tool length from touch-off", truth["tool.z"] / M_PER_UM,
              -found.z_touch / M_PER_UM, (-found.z_touch - truth["tool.z"]) / M_PER_NM,
              math.nan]]
    return folder.write_table(
        "identification", ["quantity", "injected (um)", "identified (um)", "error (nm)",
                           "std (nm)"], rows, title="Injected and identified", digits=4)


def check_table(folder, check) -> str:
    """The paper's formulas beside the model-based fit on the same readings."""
    rows = [[name, check[name]["paper_um"], check[name]["fit_um"],
             check[name]["difference_nm"], check[name]["paper_std_nm"],
             check[name]["fit_std_nm"]] for name in PARAMETERS]
    return folder.write_table(
        "fit_check", ["parameter", "paper's formulas (um)", "fit (um)", "fit - paper (nm)",
                      "paper std (nm)", "fit std (nm)"], rows,
        title="Cross-check: machinesim.identification.fit on the same readings", digits=4)


def _cell(value):
    return math.nan if value is None else value


def _in_stds(value, std):
    """``value`` in units of ``std`` (NaN where either is missing or std is 0)."""
    return math.nan if value is None or not std else value / std


if __name__ == "__main__":
    sys.exit(main())
