"""A cut asked for again with every input the same is handed back, not cut again; any input
that differs cuts anew, and the memo keeps no error model."""

from __future__ import annotations

import numpy as np
import pytest

from machinesim import ErrorModel, Lab, load_machine
from machinesim.cutting.memo import REUSED_NOTE, CutMemo
from machinesim.lab import CUTS
from machinesim.nc import ProgramBuilder
from machinesim.realism import Realism
from machinesim.workpiece import Part, block

TRUTH = {"tool": {"offset_um": [5.0, -3.0, 1.0]}, "location": {"C": {"EX0C_um": 2.0}}}


def groove():
    return (ProgramBuilder(1).rapid(X=1e-3, Y=1e-3, Z=1e-3).linear(Z=-1e-5, feed_mm_per_min=100)
            .linear(X=8e-3, feed_mm_per_min=100).rapid(Z=1e-3).build())


@pytest.fixture(autouse=True)
def empty_memo():
    CUTS.clear()
    yield
    CUTS.clear()


def _cut(lab, told=None):
    return lab.cut(groove(), "v:90", "block:10x10x2",
                   progress=None if told is None else lambda done, total: told.append(
                       (done, total)))


def test_a_lab_that_differs_only_in_its_instruments_gets_the_same_cut_back():
    machine = load_machine("robonano_a0ib")
    first, first_report = _cut(Lab(machine, TRUTH, seed=1, realism=Realism.lab()))
    told = []
    # another seed and no lateral noise: the instruments differ, the machine does not
    second, second_report = _cut(Lab(machine, TRUTH, seed=7,
                                     realism=Realism.lab().without("lateral_noise")), told)
    assert second is first
    assert second_report.notes[-1] == REUSED_NOTE
    assert REUSED_NOTE not in first_report.notes
    assert told == [(first_report.sweeps, first_report.sweeps)]
    # the memo hands back what cutting again makes: a second method, the cut made anew
    fresh_lab = Lab(machine, TRUTH, seed=7, realism=Realism.lab())
    fresh_lab.reuse_cuts = False
    fresh, fresh_report = _cut(fresh_lab)
    assert fresh is not first and REUSED_NOTE not in fresh_report.notes
    for a, b in zip(fresh.mesh(), first.mesh(), strict=True):
        assert np.array_equal(a, b)


def test_any_difference_in_the_machine_as_it_is_cuts_anew():
    machine = load_machine("robonano_a0ib")
    lab = Lab(machine, TRUTH, realism=Realism.lab())
    first, _ = _cut(lab)
    # without its own background errors the machine is another machine
    other, report = _cut(Lab(machine, TRUTH, realism=Realism.lab().without(
        "background_errors")))
    assert other is not first and REUSED_NOTE not in report.notes
    # a tenth of a nanometre more tool offset
    nudged = ErrorModel.from_dict({**TRUTH, "tool": {"offset_um": [5.0001, -3.0, 1.0]}})
    other, report = _cut(Lab(machine, nudged, realism=Realism.lab()))
    assert other is not first and REUSED_NOTE not in report.notes
    # the operator moves the tool: the lab's own machine changes under the same lab
    lab.adjust_tool([1e-6, 0.0, 0.0])
    moved, report = _cut(lab)
    assert moved is not first and REUSED_NOTE not in report.notes
    assert moved.bounds[0, 0] != first.bounds[0, 0] or not np.array_equal(
        moved.mesh()[0], first.mesh()[0])
    # another tool, another stock, another program
    for kwargs in ({"tool": "v:60"}, {"stock": "block:10x10x3"}):
        args = {"tool": "v:90", "stock": "block:10x10x2", **kwargs}
        other, report = Lab(machine, TRUTH, realism=Realism.lab()).cut(groove(), **args)
        assert REUSED_NOTE not in report.notes
    longer = (ProgramBuilder(1).rapid(X=1e-3, Y=1e-3, Z=1e-3)
              .linear(Z=-1e-5, feed_mm_per_min=100).linear(X=8.000001e-3, feed_mm_per_min=100)
              .rapid(Z=1e-3).build())
    _, report = Lab(machine, TRUTH, realism=Realism.lab()).cut(longer, "v:90", "block:10x10x2")
    assert REUSED_NOTE not in report.notes


def test_the_memo_keeps_no_error_model_and_drops_the_least_recently_used():
    lab = Lab("robonano_a0ib", TRUTH, realism=Realism.lab())
    _cut(lab)
    kept = list(CUTS._cuts.items())
    assert kept and all(isinstance(key, str) and len(key) == 64 for key, _ in kept)
    for _part, report, _ in (value for _, value in kept):
        assert not any(isinstance(getattr(report, name), ErrorModel)
                       for name in report.__dataclass_fields__)

    memo = CutMemo(max_cuts=2)
    parts = [block(1e-3, 1e-3, 1e-3 * (k + 1)) for k in range(3)]
    keys = [memo.key("cut", part) for part in parts]
    assert len(set(keys)) == 3
    # the same solid built twice has one key; moved by 1e-18 m, another
    assert memo.key("cut", block(1e-3, 1e-3, 1e-3)) == keys[0]
    assert memo.key("cut", block(1e-3, 1e-3, 1e-3, origin=(1e-18, 0.0, 0.0))) != keys[0]
    # its triangles listed in another order, each turned: the same solid, the same key;
    # turned inside out, another
    vertices, triangles = parts[0].mesh()
    shuffled = np.roll(triangles[np.random.default_rng(0).permutation(len(triangles))], 1,
                       axis=1)
    assert memo.key("cut", Part._closed(vertices, shuffled)) == keys[0]
    assert memo.key("cut", Part._closed(vertices, triangles[:, ::-1])) != keys[0]
    report = _cut(lab)[1]
    memo.put(keys[0], parts[0], report)
    memo.put(keys[1], parts[1], report)
    assert memo.get(keys[0])[0] is parts[0]  # now the most recently used
    memo.put(keys[2], parts[2], report)
    assert memo.get(keys[1]) is None and memo.get(keys[0])[0] is parts[0]
    assert memo.get(keys[2])[0] is parts[2]
    # a part over the triangle bound is not kept; an input that does not pickle, no key
    small = CutMemo(max_triangles=parts[0].triangle_count - 1)
    small.put(keys[0], parts[0], report)
    assert len(small) == 0
    assert memo.key("cut", lambda: None) is None
    memo.put(None, parts[0], report)
    assert len(memo) == 2
