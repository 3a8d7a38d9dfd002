"""The planner's array form: the Trajectory layout, reading programs as arrays or as moves,
batches and threads, and the numpy behaviour the vectorised planner relies on."""

from __future__ import annotations

import math
from types import SimpleNamespace

import motion_reference as reference
import numpy as np
import pytest
from motion_helpers import assert_same, random_program

from machinesim import load_machine
from machinesim.exceptions import InputError, NCProgramError
from machinesim.motion import Segment, Trajectory, chords, plan, planner
from machinesim.nc import ProgramBuilder
from machinesim.sampling import random_errors


@pytest.fixture(scope="module")
def grooving():
    return load_machine("grooving_4axis")


@pytest.fixture(scope="module")
def sts():
    return load_machine("sts_lathe")


def test_the_trajectory_holds_all_samples_end_to_end(grooving):
    program = ProgramBuilder().rapid(X=1e-3, Y=0.0, Z=1e-3, C=0.0).linear(
        C=math.radians(30.0), feed_mm_per_min=600.0).dwell(0.5).linear(X=2e-3).build()
    tr = plan(program, grooving)
    assert isinstance(tr, Trajectory) and len(tr) == 4
    assert tr.offsets[0] == 0 and tr.offsets[-1] == len(tr.q) == len(tr.t)
    assert list(tr.kinds) == [0, 1, 2, 1] and list(tr.lines) == [1, 2, 3, 4]
    for array in (tr.q, tr.t, tr.offsets, tr.kinds, tr.lines):
        assert not array.flags.writeable
    segments = tr.segments
    assert len(segments) == 4 and isinstance(segments[0], Segment)
    assert isinstance(segments[1:3], tuple) and len(segments[1:3]) == 2
    assert segments[-1].line == 4 and segments[-1].kind == "linear"
    with pytest.raises(IndexError):
        segments[4]
    for i, s in enumerate(segments):
        a, b = tr.offsets[i], tr.offsets[i + 1]
        assert np.array_equal(s.q, tr.q[a:b]) and np.array_equal(s.t, tr.t[a:b])
        assert s.q.flags.c_contiguous and not s.q.flags.writeable
    # a move ends where the next starts, both samples kept
    assert np.array_equal(segments[0].q[-1], segments[1].q[0])
    assert tr.substeps == sum(len(s.q) - 1 for s in segments) > 4
    rows = tr.rows(("rapid", "linear"))
    expected = np.vstack([s.q for s in segments if s.kind != "dwell"])
    assert np.array_equal(tr.q[rows], expected)
    assert tr.rows(("dwell",)).tolist() == list(range(tr.offsets[2], tr.offsets[3]))
    assert len(tr.rows(())) == 0


def test_an_object_with_moves_only_plans_as_the_program_does(grooving):
    """`plan` reads a Program's arrays; any object with ``moves`` is read move by move."""
    program = random_program(grooving, np.random.default_rng(3), 30)
    duck = SimpleNamespace(moves=tuple(program.moves), source=program.source)
    assert_same(plan(duck, grooving), reference.plan(program, grooving))


def _duck(kind, target, feed, dwell):
    move = SimpleNamespace(kind=kind, target=target, feed_m_per_s=feed, dwell_s=dwell, line=7)
    return SimpleNamespace(moves=(move,), source="duck.nc")


@pytest.mark.parametrize(("move", "key", "said"), [
    # a feed of 0 took inf s (samples at NaN s), a negative one the axis' limit (0.04 s for
    # 1 mm at 25 mm/s), a dwell of -1 s ran the clock back: a Move refuses each when made
    (("linear", {"X": 1e-3}, 0.0, 0.0), "feed_m_per_s", "feed must be > 0"),
    (("linear", {"X": 1e-3}, -1e-3, 0.0), "feed_m_per_s", "feed must be > 0"),
    (("linear", {"X": 1e-3}, math.inf, 0.0), "feed_m_per_s", "feed must be > 0"),
    (("rapid", {"X": 1e-3}, 1e-3, 0.0), "feed_m_per_s", "feed must be None for a rapid"),
    (("dwell", {}, None, -1.0), "dwell_s", "got -1.0 for a dwell move"),
    (("dwell", {}, None, math.nan), "dwell_s", "got nan for a dwell move"),
    (("rapid", {"X": 1e-3}, None, 2.0), "dwell_s", "got 2.0 for a rapid move"),
    (("arc", {"X": 1e-3}, 1e-3, 0.0), "kind", "got 'arc'"),
    (("rapid", {"X": "1"}, None, 0.0), "X", "got '1'"),
    (("rapid", {"X": math.inf}, None, 0.0), "X", "got inf"),
])
def test_an_object_with_moves_is_refused_a_move_a_move_would_refuse(grooving, move, key,
                                                                      said):
    with pytest.raises(NCProgramError, match=said) as caught:
        plan(_duck(*move), grooving)
    assert (caught.value.source, caught.value.line, caught.value.key) == ("duck.nc", 7, key)


def test_an_object_with_moves_plans_a_feed_and_a_dwell_by_hand(grooving):
    """1 mm at 60 mm/min: 1 s; a dwell of 0.5 s."""
    duck = _duck("linear", {"X": 1e-3}, 1e-3, 0.0)
    assert plan(duck, grooving).duration == pytest.approx(1.0, rel=1e-15)
    assert plan(_duck("dwell", {}, None, 0.5), grooving).duration == 0.5


def test_batches_and_threads_change_nothing(grooving, monkeypatch):
    """Tiny batches (many of them, run on several threads) and one thread: the same."""
    rng = np.random.default_rng(11)
    program = random_program(grooving, rng, 60)
    errors = random_errors(grooving, rng)
    whole = plan(program, grooving, errors, chord_tolerance=3e-9)
    monkeypatch.setattr(chords, "_ROWS_PER_BATCH", 40)
    for workers in (1, 3):
        monkeypatch.setattr(chords, "WORKERS", workers)
        small = plan(program, grooving, errors, chord_tolerance=3e-9)
        assert np.array_equal(small.q, whole.q) and np.array_equal(small.t, whole.t)
        assert np.array_equal(small.offsets, whole.offsets)


def test_samples_by_linspace_or_by_product_and_in_chunks_are_the_same(grooving, monkeypatch):
    program = random_program(grooving, np.random.default_rng(2), 40)
    whole = plan(program, grooving)
    assert whole.substeps > 2 * len(whole)  # moves of many sub-steps, some over a chunk
    for by_product in (True, False):
        for chunk in (7, 1 << 20):
            monkeypatch.setattr(planner, "_BY_PRODUCT", by_product)
            monkeypatch.setattr(planner, "_SAMPLES_PER_CHUNK", chunk)
            other = plan(program, grooving)
            assert np.array_equal(other.q, whole.q) and np.array_equal(other.t, whole.t)


def test_turns_across_the_series_range_plan_as_the_reference_does(sts):
    """The kinematics evaluate a rotation by a series under SERIES_MAX_RAD and by cos/sin
    above, per batch: C 0 -> 0.0105 rad puts the node at 7/8 (0.0092) under 0.01 and the end
    (0.0105) over it; the planner groups its poses as `Machine.tool_pose` would and gives
    the reference's samples, number for number."""
    program = ProgramBuilder().rapid(X=5e-3, Z=0.0, C=0.0).linear(
        C=0.0105, feed_mm_per_min=10.0).linear(C=0.0).linear(C=1.0).linear(C=1.0105).build()
    new, old = plan(program, sts), reference.plan(program, sts)
    assert [len(s.q) for s in new.segments] == [len(s.q) for s in old.segments]
    assert_same(new, old)


def test_numpy_sums_in_the_order_the_planner_reproduces():
    """The planner forms norms as (x**2 + y**2) + z**2, as numpy's norm and sum do."""
    rng = np.random.default_rng(0)
    for k in (1, 4):
        x = rng.normal(size=(500, 3, k)) * rng.uniform(0, 1, size=(500, 3, k))
        s = x * x
        assert np.array_equal(np.linalg.norm(x, axis=1), np.sqrt((s[:, 0] + s[:, 1]) + s[:, 2]))
    assert planner._BY_PRODUCT  # linspace is i * (1 / n): the fast sample path is taken


def test_bad_arguments_are_refused(grooving):
    program = ProgramBuilder().linear(X=1e-3, feed_mm_per_min=10.0).build()
    with pytest.raises(InputError, match="start must be finite"):
        plan(program, grooving, start=[0.0, np.nan, 0.0, 0.0])
    with pytest.raises(InputError, match="start must have shape"):
        plan(program, grooving, start=[0.0, 0.0])
    with pytest.raises(InputError, match="chord_tolerance must be positive"):
        plan(program, grooving, chord_tolerance=float("nan"))

    class Short:
        def follow(self, t, q):
            return q[:1]

    with pytest.raises(InputError, match="servo.follow must return"):
        plan(program, grooving, servo=Short())


def test_a_large_program_plans_in_arrays(sts):
    """10^5 rotary moves plan (identity is checked on smaller programs)."""
    n = 100_000
    k = np.arange(n)
    targets = np.full((n, 6), np.nan)
    targets[:, 0] = 10e-3 * (1.0 - k / n)
    targets[:, 5] = np.radians(k * 0.36)
    from machinesim.nc import Program

    program = Program.from_arrays(targets, np.ones(n, dtype=np.int8), np.full(n, 1e-3))
    tr = plan(program, sts)
    steps = np.diff(tr.offsets) - 1
    assert len(tr) == n and steps.min() >= 1 and steps.max() <= 8
    # the chord of each sub-step of an arc of radius r over dtheta: sagitta r (1 - cos(d/2))
    r = np.abs(targets[1:, 0] + targets[:-1, 0]) / 2
    sagitta = r * (1 - np.cos(np.radians(0.36) / steps[1:] / 2))
    assert np.all(sagitta <= 1.05e-9)
