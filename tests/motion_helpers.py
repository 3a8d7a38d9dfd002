"""What the planner's test files (tests/test_motion_identity.py, test_motion_arrays.py) share
(not collected: no test_ prefix): two trajectories compared field by field, a chord's
deviation checked independently of the planner, and random programs."""

from __future__ import annotations

import numpy as np

from machinesim.motion import Trajectory
from machinesim.nc import ProgramBuilder

#: Points sampled along each sub-step for the independent chord check.
DENSE = 32


def chord_deviation(machine, errors, points, q: np.ndarray, dense: int = DENSE) -> float:
    """Largest distance (m) of any tool point, sampled ``dense`` times along each sub-step
    (axis values linear between the segment's samples), from the line of the chord between
    the sub-step's ends: the path's geometric deviation from the straight sweep."""
    f = np.linspace(0.0, 1.0, dense + 1)
    a, b = q[:-1], q[1:]
    samples = a[:, None, :] + f[None, :, None] * (b - a)[:, None, :]  # (steps, dense + 1, n)
    poses = machine.tool_pose(samples.reshape(-1, q.shape[1]), errors)
    p = (poses[:, :3, :3] @ points.T + poses[:, :3, 3:4]).reshape(len(a), dense + 1, 3, -1)
    r = p - p[:, :1]
    chord = r[:, -1:]  # (steps, 1, 3, k)
    length = np.linalg.norm(chord, axis=2, keepdims=True)
    u = np.divide(chord, length, out=np.zeros_like(chord), where=length > 0)
    off = r - np.sum(r * u, axis=2, keepdims=True) * u
    return float(np.max(np.linalg.norm(off, axis=2)))


def assert_same(new: Trajectory, old, *, check=None) -> None:
    """Every field of the two trajectories equal, segment by segment; a rotary segment split
    into another number of sub-steps has the same ends and time and, with ``check`` =
    (machine, errors, points, tolerance), chords within the tolerance."""
    assert new.axes == old.axes
    assert len(new.segments) == len(old.segments)
    recounted = 0
    for i, (a, b) in enumerate(zip(new.segments, old.segments, strict=True)):
        assert (a.kind, a.line) == (b.kind, b.line), i
        assert not a.q.flags.writeable and not a.t.flags.writeable
        assert a.duration == b.duration, i
        if a.q.shape != b.q.shape:
            recounted += 1
            assert np.array_equal(a.q[[0, -1]], b.q[[0, -1]]), i
            assert np.array_equal(a.t[[0, -1]], b.t[[0, -1]]), i
            if check is not None:
                machine, errors, points, tolerance = check
                assert chord_deviation(machine, errors, points, a.q) <= tolerance, i
            continue
        assert np.array_equal(a.q, b.q), i
        assert np.array_equal(a.t, b.t), i
    assert new.duration == old.duration
    assert new.cutting_time == old.cutting_time
    if not recounted:
        assert new.substeps == old.substeps
    assert new.notes == old.notes


def random_program(machine, rng: np.random.Generator, moves: int, *, big_turns: bool = True):
    """A feed move first, then rapids, feeds (some changing the feed), dwells, and rotary
    moves small (the kinematics' series range), medium and large, setting a few axes at a
    time."""
    b = ProgramBuilder(source="random").linear(feed_mm_per_min=200.0,
                                               **{machine.axes[0]: 1e-3})
    lower, upper = np.maximum(machine.lower, -4.0), np.minimum(machine.upper, 4.0)
    for _ in range(moves):
        r = rng.random()
        if r < 0.08:
            b.dwell(float(rng.choice([0.0, 0.25, 1.5])))
            continue
        values = {}
        for i, a in enumerate(machine.axes):
            if rng.random() < 0.5:
                continue
            if machine.rotary[i]:
                scale = rng.choice([1e-4, 3e-3, 0.02, 0.3] + ([1.5] if big_turns else []))
                values[a] = float(np.clip(rng.normal(0.0, scale), lower[i], upper[i]))
            else:
                values[a] = float(rng.uniform(lower[i], upper[i]) * 0.1)
        values = values or {machine.axes[0]: float(rng.uniform(-1e-3, 1e-3))}
        if r < 0.3:
            b.rapid(**values)
        elif r < 0.4:
            b.linear(feed_mm_per_min=float(rng.choice([50.0, 300.0, 1234.5])), **values)
        elif r < 0.45:
            b.linear(feed_m_per_s=float(rng.uniform(1e-4, 1e-2)), **values)
        else:
            b.linear(**values)
    return b.build()
