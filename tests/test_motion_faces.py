"""`machinesim.motion.faces.edge_substeps` reads an edge's waist only where its bound (the
edge's length times the change of the tool's rotation over a sub-step, over 4) could raise
a move's count: the bound holds, and the counts are those of reading every edge."""

import math
from pathlib import Path

import numpy as np
import pytest

import machinesim
from machinesim.motion import faces
from machinesim.tool_specs import tool_from_spec

ERRORS = Path(__file__).parents[1] / "models" / "errors" / "background_robonano_a0ib.toml"


def _profile(spec, top):
    tool = tool_from_spec(spec)
    return faces.ProfileEdges(np.asarray(tool.vertices())[tool.edges()], top)


def _random_moves(machine, n, most, seed):
    """``n`` moves of up to 0.1 mm along X while each rotary axis turns up to 0.2 rad from
    within 0.3 rad, in 1 to ``most`` sub-steps (seeded)."""
    rng = np.random.default_rng(seed)
    starts = np.zeros((n, len(machine.axes)))
    delta = np.zeros((n, len(machine.axes)))
    delta[:, 0] = rng.uniform(-1e-4, 1e-4, n)
    for i, axis in enumerate(machine.axes):
        if axis in "ABC":
            starts[:, i] = rng.uniform(-0.3, 0.3, n)
            delta[:, i] = rng.uniform(-0.2, 0.2, n)
    return starts, delta, rng.integers(1, most, n)


@pytest.mark.parametrize("name, spec, errors", [
    ("robonano_a0ib", "v:90", None), ("robonano_a0ib", "nose:0.1:90", ERRORS),
    ("grooving_4axis", "nose:1.0:90", None)])
def test_the_bound_holds_each_edge_s_waist_in_random_moves(name, spec, errors):
    """Each edge's exact largest waist over each of 12 random moves (cut at z = 20 um, the
    stock's top) is at most L turn / 4 (`faces._uncleared`), with no room for rounding;
    the waists read are not all 0."""
    machine = machinesim.load_machine(name)
    if errors is not None:
        errors = machinesim.ErrorModel.from_toml(errors)
    edges = _profile(spec, 2e-5).edges
    length = np.linalg.norm(edges[:, 1] - edges[:, 0], axis=1)
    starts, delta, steps = _random_moves(machine, 12, 300, 7)
    read = 0.0
    for i in range(len(steps)):
        q = starts[i] + np.arange(steps[i] + 1)[:, None] / steps[i] * delta[i]
        poses = machine.tool_pose(q, errors)
        first = np.array([0])
        turn = faces._largest_turn(poses, first)[0]
        waist = np.array([faces._largest_waist(poses, first, edges[e:e + 1], 2e-5)[0]
                          for e in range(len(edges))])
        bound = length * turn / 4.0
        assert np.all(waist <= bound), (i, np.max(waist / bound))
        read = max(read, float(waist.max()))
    assert read > 1e-12, read


@pytest.mark.parametrize("name, spec, errors", [
    ("robonano_a0ib", "v:90", None), ("robonano_a0ib", "nose:0.1:90", ERRORS),
    ("grooving_4axis", "nose:1.0:90", None)])
def test_counts_are_those_of_reading_every_edge(name, spec, errors):
    """Random moves (a smaller set than the commit's 360 calls, the same kind) under the
    stock's top at 0 and 20 um and none, at 1 nm: the bounded counts equal those of every
    edge read (``bounded=False``, the old rule), with the errors on one, and some of them
    are raised."""
    machine = machinesim.load_machine(name)
    if errors is not None:
        errors = machinesim.ErrorModel.from_toml(errors)
    starts, delta, steps = _random_moves(machine, 16, 400, 1)
    raised = 0
    for top in (math.inf, 0.0, 2e-5):
        profile = _profile(spec, top)
        found = faces.edge_substeps(machine, errors, starts, delta, steps, profile, 1e-9)
        largest = faces._largest_waists(machine, errors, starts, delta, steps, profile.edges,
                                        top, 1e-9, bounded=False)
        every = np.maximum(steps, np.ceil(steps * largest / 1e-9 * faces._MARGIN))
        np.testing.assert_array_equal(found, every.astype(np.int64))
        raised += int(np.sum(found > steps))
    assert raised > 0


def test_a_c_turn_under_a_nose_reads_only_its_flanks_and_top(monkeypatch):
    """C36 at X5 on grooving_4axis under nose:1.0:90 in 826 sub-steps (C360's 8,256 at
    1 nm, 0.76 mrad each): an arc chord of 2.8 um has L turn / 4 = 0.53 nm, under
    1 nm / 1.01, so of the 559 edges only the two flanks (13.7 mm) and the top (20.8 mm)
    are read; it read all 559. The count is the one of every edge read (826: the nose's
    plane holds the C axis's radius, so its edges' waists vanish to first order)."""
    machine = machinesim.load_machine("grooving_4axis")
    profile = _profile("nose:1.0:90", 0.0)
    start = np.zeros((1, len(machine.axes)))
    start[0, machine.axes.index("X")] = 5e-3
    delta = np.zeros((1, len(machine.axes)))
    delta[0, machine.axes.index("C")] = math.radians(36.0)
    steps = np.array([826])
    every = faces._largest_waists(machine, None, start, delta, steps, profile.edges, 0.0,
                                  1e-9, bounded=False)
    read = []
    waist = faces._largest_waist

    def counted(poses, first, edges, top):
        read.append(np.linalg.norm(edges[:, 1] - edges[:, 0], axis=1))
        return waist(poses, first, edges, top)

    monkeypatch.setattr(faces, "_largest_waist", counted)
    found = faces.edge_substeps(machine, None, start, delta, steps, profile, 1e-9)
    lengths = np.concatenate(read)
    assert len(lengths) == 3 * len(read) and np.all(lengths > 1e-2), lengths
    expected = np.maximum(steps, np.ceil(steps * every / 1e-9 * faces._MARGIN))
    np.testing.assert_array_equal(found, expected.astype(np.int64))
    assert found[0] == 826
