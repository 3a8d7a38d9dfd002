"""The lab keeps the truth: no public door to the injected errors, with or without realism,
seeded per-instrument noise, a scan that keeps identification and compensation away from
the truth, and instruments that read what the truth makes them read."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from lab_helpers import TRUTH, groove

import machinesim
from machinesim import ErrorModel, Lab
from machinesim.exceptions import InputError

ROOT = Path(__file__).resolve().parents[1]


def _holds_truth(value, truth) -> bool:
    if value is truth or isinstance(value, ErrorModel):
        return True
    if isinstance(value, dict | list | tuple):
        items = value.values() if isinstance(value, dict) else value
        return any(_holds_truth(v, truth) for v in items)
    return False


def _public(obj):
    for name in dir(obj):
        if name.startswith("_"):
            continue
        value = getattr(obj, name)
        if callable(value):
            continue
        yield name, value


def test_no_public_attribute_of_the_lab_or_its_instruments_holds_the_truth():
    lab = Lab("robonano_a0ib", TRUTH, seed=3)
    truth = lab.reveal()
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    things = [lab, lab.touch_probe(part), lab.laser_interferometer(), lab.microscope(),
              lab.white_light_interferometer(), lab.r_test(), lab.encoders()]
    for thing in things:
        for name, value in _public(thing):
            assert not _holds_truth(value, truth), f"{type(thing).__name__}.{name}"
    methods = {name for name in dir(lab) if not name.startswith("_")}
    assert methods == {"adjust_tool", "artefact_scatter", "cut", "encoders",
                       "laser_interferometer", "machine",
                       "make_artefacts", "microscope", "noise", "r_test", "realism", "reveal",
                       "reveal_adjustments", "reveal_artefacts", "reveal_background",
                       "reveal_instruments", "reveal_servo", "reuse_cuts", "seed",
                       "touch_probe", "tune_servo", "turn", "white_light_interferometer"}


def test_with_realism_no_public_attribute_holds_the_truth_or_an_imperfection():
    from machinesim.metrology.imperfections import Lobing, Registration, ZonalForm
    from machinesim.realism import Realism

    lab = Lab("robonano_a0ib", TRUTH, seed=3, realism=Realism.lab())
    truth = lab.reveal()
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    things = [lab, lab.touch_probe(part), lab.laser_interferometer(), lab.microscope(),
              lab.white_light_interferometer(), lab.r_test()]
    hidden = (Registration, Lobing, ZonalForm)
    for thing in things:
        for name, value in _public(thing):
            assert not _holds_truth(value, truth), f"{type(thing).__name__}.{name}"
            assert not isinstance(value, hidden), f"{type(thing).__name__}.{name}"


def test_the_lab_cuts_with_its_truth_as_cut_does_with_the_errors():
    lab = Lab("robonano_a0ib", TRUTH, noise=False)
    part, report = lab.cut(groove(), "v:90", "block:10x10x2")
    direct, direct_report = machinesim.cut(groove(), "robonano_a0ib", "v:90", "block:10x10x2",
                                           ErrorModel.from_dict(TRUTH))
    assert np.array_equal(part.mesh()[0], direct.mesh()[0])
    assert report.removed_volume_m3 == direct_report.removed_volume_m3
    with pytest.raises(InputError, match="own errors"):
        lab.cut(groove(), errors=None)


def test_the_inner_cutters_lab_cut_calls_default_as_the_public_ones():
    # Lab.cut hands the inner cutters only the options it was given: each option left out
    # must default as the public cutter's does, or a lab would cut otherwise than
    # machinesim.cut with the same errors
    import inspect

    from machinesim.cutting import cut, cut_turned
    from machinesim.cutting.program import _cut
    from machinesim.cutting.windows import _cut_turned

    def defaults(function):
        return {name: p.default for name, p in inspect.signature(function).parameters.items()
                if p.kind is p.KEYWORD_ONLY}

    for public, inner in ((cut, _cut), (cut_turned, _cut_turned)):
        inner_defaults = defaults(inner)
        assert inner_defaults.pop("file_notes") is inspect.Parameter.empty  # always said
        assert inner_defaults == defaults(public), inner.__name__


def test_the_lab_cuts_turned_with_its_truth_as_cut_turned_does_with_the_errors():
    lab = Lab("robonano_a0ib", TRUTH, noise=False)
    part, report = lab.cut(groove(), "v:90", "block:10x10x2", turn_step=0.5)
    direct, direct_report = machinesim.cutting.cut_turned(
        groove(), "robonano_a0ib", "v:90", "block:10x10x2", ErrorModel.from_dict(TRUTH),
        turn_step=0.5)
    for a, b in zip(part.mesh(), direct.mesh(), strict=True):
        assert np.array_equal(a, b)
    # the same notes but those on the errors, which name the lab's truth
    assert report.notes == direct_report.notes[:len(report.notes)]
    assert not any("EX0C" in note for note in report.notes)
    assert any("EX0C" in note for note in direct_report.notes)
    assert report.removed_volume_m3 == direct_report.removed_volume_m3


def test_a_reading_does_not_change_when_another_instrument_reads_first():
    def read(extra: bool):
        lab = Lab("robonano_a0ib", TRUTH, seed=11)
        part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
        if extra:
            lab.touch_probe(part).touch([5e-3, 5e-3, 1e-3, 0.0, 0.0], "-Z", 2e-3)
            lab.white_light_interferometer().profile(part, (2e-3, 0.0), (2e-3, 2e-3))
            lab.microscope(label="elsewhere").profile(part, (1e-3, 0.0), (1e-3, 2e-3))
        return lab.microscope().profile(part, (5e-3, 0.0), (5e-3, 2e-3), spacing=1e-5).z

    alone, after_others = read(False), read(True)
    assert np.array_equal(alone, after_others)
    # and the noise is there: a second microscope has its own stream
    lab = Lab("robonano_a0ib", TRUTH, seed=11)
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    first = lab.microscope().profile(part, (5e-3, 0.0), (5e-3, 2e-3), spacing=1e-5).z
    second = lab.microscope().profile(part, (5e-3, 0.0), (5e-3, 2e-3), spacing=1e-5).z
    assert np.array_equal(first, alone) and not np.array_equal(first, second)


def test_noise_off_reads_exactly_and_seeds_differ_with_noise_on():
    lab = Lab("robonano_a0ib", TRUTH, noise=False, seed=1)
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    z = lab.microscope(resolution=0.0).profile(part, (5e-3, 0.0), (5e-3, 0.5e-3)).z
    assert np.all(z == 0.0)  # land far from the groove: exactly the top face
    noisy = [Lab("robonano_a0ib", TRUTH, seed=s).microscope().profile(
        part, (5e-3, 0.0), (5e-3, 0.5e-3)).z for s in (1, 2)]
    assert not np.array_equal(*noisy)


#: Where the truth must never be reached: identification, compensation, and the shipped
#: procedures (whose measure and evaluate hold a lab, to cut and read with, never to reveal).
HONEST = [*sorted((ROOT / "machinesim" / "identification").glob("*.py")),
          ROOT / "machinesim" / "compensation.py", ROOT / "machinesim" / "compensation_table.py",
          *sorted((ROOT / "machinesim" / "procedures").glob("*.py"))]


def _violations(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            attr = node.attr
            owner = node.value.id if isinstance(node.value, ast.Name) else None
            if attr == "reveal":
                found.append(f"{path.name}:{node.lineno} calls reveal()")
            elif attr.startswith("_") and not attr.startswith("__") and owner not in (
                    "self", "cls"):
                found.append(f"{path.name}:{node.lineno} reaches private .{attr}")
            elif "_Lab__" in attr:
                found.append(f"{path.name}:{node.lineno} reaches the lab's truth")
            elif attr in ("__dict__", "__closure__", "__globals__"):
                found.append(f"{path.name}:{node.lineno} reaches .{attr}")
            elif attr == "seed":
                found.append(f"{path.name}:{node.lineno} reads a seed (the noise replayed)")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.args:
            name, args = node.func.id, node.args
            private = (len(args) > 1 and isinstance(args[1], ast.Constant)
                       and str(args[1].value).startswith("_"))
            if name == "vars" or (name in ("getattr", "setattr") and private):
                found.append(f"{path.name}:{node.lineno} uses {name}() past the public API")
            elif name in ("stream", "default_rng"):
                found.append(f"{path.name}:{node.lineno} builds a noise stream ({name})")
        elif isinstance(node, ast.Name) and node.id in ("Lab",):
            found.append(f"{path.name}:{node.lineno} names the Lab")
    return found


def test_identification_and_compensation_never_reach_the_truth():
    assert HONEST, "nothing to scan"
    found = [v for path in HONEST if path.exists() for v in _violations(path)]
    assert not found, "\n".join(found)


def test_the_honesty_scan_catches_what_it_must(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("def f(lab, probe):\n    t = lab.reveal()\n    e = probe._pose\n"
                   "    n = stream(lab.seed, 'r_test', 'ball')\n"
                   "    return getattr(lab, '_Lab__truth'), vars(probe), f.__closure__\n")
    found = _violations(bad)
    assert len(found) == 7, found


def test_no_instrument_hands_out_its_noise_stream():
    # With the generator a procedure could draw the noise again and subtract it: the R-test's
    # fit then came within 0.1 nm of the injected errors instead of its 10-30 nm of noise.
    from machinesim.realism import Realism

    lab = Lab("robonano_a0ib", TRUTH, seed=3, realism=Realism.lab())
    part, _ = lab.cut(groove(), "v:90", "block:10x10x2")
    things = [lab.touch_probe(part), lab.laser_interferometer(), lab.microscope(),
              lab.white_light_interferometer(), lab.r_test(), lab.encoders()]
    for thing in things:
        for name, value in _public(thing):
            assert not isinstance(value, np.random.Generator), f"{type(thing).__name__}.{name}"


def test_whether_a_tool_adjustment_is_taken_does_not_depend_on_the_hidden_tool(tmp_path):
    # The check is of the move alone, against the adjuster's stroke: a check of where the
    # tool lands would tell, by refusing or not, where the hidden tool is.
    from machinesim.realism import TOOL_ADJUSTER_STROKE_M

    messages = set()
    for offset_um in (-995_000.0, -4000.0, 0.0, 4000.0, 995_000.0):
        lab = Lab("robonano_a0ib", {"tool": {"offset_um": [offset_um, 0.0, 0.0]}}, seed=1)
        lab.adjust_tool([0.75 * TOOL_ADJUSTER_STROKE_M, 0.0, 0.0])
        with pytest.raises(InputError, match="beyond its stroke") as info:
            lab.adjust_tool([0.25 * TOOL_ADJUSTER_STROKE_M * (1 + 1e-6), 0.0, 0.0])
        lab.adjust_tool([0.25 * TOOL_ADJUSTER_STROKE_M, 0.0, 0.0])  # to the stroke's end
        messages.add(str(info.value))
    assert len(messages) == 1  # word for word the same, wherever the tool is
    # an injected offset that leaves no room for the stroke is refused when the lab is made
    with pytest.raises(InputError, match="1 m less the tool adjuster's stroke"):
        Lab("robonano_a0ib", {"tool": {"offset_um": [995_001.0, 0.0, 0.0]}})
    # given in a file (in metres), the message names the file and its table
    path = tmp_path / "far.toml"
    path.write_text("# far off\n[tool]\noffset_m = [0.0, 1.0, 0.0]\n")
    with pytest.raises(InputError) as info:
        Lab("robonano_a0ib", path)
    assert str(info.value).startswith(f"{path}, line 3, key '[tool] offset': a tool offset of "
                                      "[0.0, 1000.0, 0.0] mm")


def test_the_r_test_reads_the_ball_displacement_of_a_tool_offset_turned_by_b_and_c():
    # A tool offset d (tool_mount frame) on robonano_a0ib is carried by B (about Y) and seen
    # from the workpiece turned by -C: at B = 0 and C = 0 the ball is displaced by d itself.
    d = np.array([5.0, -3.0, 2.0]) * 1e-6
    lab = Lab("robonano_a0ib", {"tool": {"offset_um": (d * 1e6).tolist()}}, noise=False)
    reading = lab.r_test(resolution=0.0).read(np.zeros((1, 5)))
    assert np.allclose(reading.displacement[0], d, rtol=0, atol=1e-15)
    # the length of the displacement is the offset's, whatever B and C (a rigid offset)
    q = np.zeros((6, 5))
    q[:, 3] = np.radians([-30, 0, 30, 10, -20, 45])
    q[:, 4] = np.radians([0, 90, 180, 270, 33, -120])
    shown = lab.r_test(resolution=0.0).read(q).displacement
    assert np.allclose(np.linalg.norm(shown, axis=1), np.linalg.norm(d), rtol=0, atol=1e-15)
