"""Rotary moves split to the chord tolerance, for many moves at once.

A move that turns a rotary axis is split into uniform sub-steps whose chords stay within the
tolerance of the true path of every tool point (see `machinesim.motion`). The count is
predicted from the deviation of the whole move as one chord and then checked (`substeps`);
deviations are measured at sub-step midpoints, where an arc's sagitta peaks.

Here every move goes through that rule in lockstep: each round evaluates the deviation of
all the moves still searching, in one batch, so a program of 10^6 rotary moves costs a
few dozen numpy passes instead of 10^6 Python loops. The numbers are those of evaluating
each move alone with `Machine.tool_pose`:

* the axis values of the samples are formed by the same operations (``start + f * delta``,
  ``f`` from `numpy.linspace`);
* `ToolPaths` (`machinesim.motion.tool_paths`) walks the machine's kinematic plan with the
  operations of the batched evaluator of `machinesim.batched_kinematics`, in the same
  order, so each position is the same float64 number;
* the evaluator picks a series or numpy's ``cos``/``sin`` for a rotation by the largest
  angle in each batch it is given (`machinesim.batched_kinematics._cos_sin`); the batches of
  `Machine.tool_pose` as the rule calls it (a move's nodes or midpoints, in blocks of
  `batched_kinematics._BLOCK`) are kept as groups here and decided one by one;
* deviations are summed in numpy's order (x**2 + y**2, then + z**2) and compared as before;
  the largest is the square root of the largest square (sqrt is monotonic and correctly
  rounded, so that is the largest norm, bit for bit).

Batches of moves run on up to `WORKERS` threads (numpy releases the GIL in its loops). The
cost that stays is that of the rule itself: for a slow-tool-servo point list whose every
move turns C, 3 poses for the one-chord prediction and 2n + 1 to check n sub-steps (the
bisection from 8 sub-steps this replaced took about 36).

The reference planner, kept in the tests, is held to this segment by segment, except where
the two rules pick different counts (tests/test_motion_identity.py).

Where a path steps, so that no count holds it, is found in `machinesim.motion.steps`.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from machinesim._cores import usable_cores
from machinesim.batched_kinematics import _BLOCK
from machinesim.motion.tool_paths import ToolPaths

if TYPE_CHECKING:
    from machinesim.motion.steps import Stall

#: A move is split into at most this many sub-steps: beyond it the request is unreasonable
#: (a 1 nm chord over a full turn at 1 m radius needs ~70,000).
MAX_SUBSTEPS = 1_000_000
#: Rows (samples times tool points) evaluated in one batch: large enough that numpy's
#: per-call cost vanishes, small enough that the working arrays stay in cache.
_ROWS_PER_BATCH = 1 << 17
#: Threads that evaluate batches at once: the cores there are, up to 4.
WORKERS = min(4, usable_cores())
#: The first trial number of sub-steps of the rule.
_FIRST_TRIAL = 8


@lru_cache(maxsize=256)
def _fractions(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Node and midpoint fractions of ``n`` uniform sub-steps (as the rule computes them)."""
    f = np.linspace(0.0, 1.0, n + 1)
    mid = (f[:-1] + f[1:]) / 2
    f.flags.writeable = mid.flags.writeable = False
    return f, mid


def _blocks(count: int) -> tuple[np.ndarray, np.ndarray]:
    """Starts and sizes of the blocks `Kinematics.poses` cuts ``count`` rows into."""
    starts = np.arange(0, count, _BLOCK)
    return starts, np.diff(np.append(starts, count))


def _columns(start: np.ndarray, delta: np.ndarray, f: np.ndarray) -> list[np.ndarray]:
    """Axis values ``start + f * delta`` at every fraction for every move, fraction after
    fraction: one (len(f) * M,) array per axis."""
    return [(start[None, :, i] + f[:, None] * delta[None, :, i]).ravel()
            for i in range(start.shape[1])]


def _chord_error(nodes, mids, a, b, at_mid) -> np.ndarray:
    """Per move, the largest squared distance of the midpoint rows ``at_mid`` from the
    chords between node rows ``a`` and ``b`` (arrays (rows, M[, k]) per coordinate)."""
    total = None
    for c in range(3):
        x = mids[c][at_mid] - (nodes[c][a] + nodes[c][b]) / 2
        x *= x
        total = x if total is None else total + x
    if total.ndim == 3:
        total = total.max(axis=2)
    return total.max(axis=0)


def _deviation_batch(paths: ToolPaths, start: np.ndarray, delta: np.ndarray, n: int):
    """Deviations of ``M`` moves all split into ``n`` sub-steps."""
    m = len(start)
    f_nodes, f_mids = _fractions(n)
    if n + 1 <= _BLOCK:
        nodes = paths.positions(_columns(start, delta, f_nodes), n + 1)
        mids = paths.positions(_columns(start, delta, f_mids), n)
    else:  # one move, in the blocks tool_pose would cut it into
        nodes = paths.positions(_columns(start, delta, f_nodes), _blocks(n + 1))
        mids = paths.positions(_columns(start, delta, f_mids), _blocks(n))
    shape = (-1, m) if paths.k == 1 else (-1, m, paths.k)
    nodes_c = [p.reshape(shape) for p in nodes[:3]]
    mids_c = [p.reshape(shape) for p in mids[:3]]
    every = slice(None)
    # sqrt is monotonic and correctly rounded: the sqrt of the largest square is the
    # largest norm, bit for bit
    out = np.sqrt(_chord_error(nodes_c, mids_c, slice(0, -1), slice(1, None), every))
    return out


class _Batches:
    """Runs batch jobs on up to `WORKERS` threads (numpy releases the GIL in its loops)."""

    def __init__(self) -> None:
        self.jobs = []

    def add(self, job) -> None:
        self.jobs.append(job)

    def run(self) -> None:
        if len(self.jobs) > 1 and WORKERS > 1:
            with ThreadPoolExecutor(min(WORKERS, len(self.jobs))) as pool:
                for future in [pool.submit(job) for job in self.jobs]:
                    future.result()
        else:
            for job in self.jobs:
                job()


def _batches(n: int, k: int, count: int) -> tuple[range, int]:
    """First moves and size of the batches of ``count`` moves of ``n`` sub-steps; a move
    that `Kinematics.poses` would cut into blocks is a batch of its own."""
    per_batch = 1 if n + 1 > _BLOCK else max(1, _ROWS_PER_BATCH // ((2 * n + 1) * k))
    return range(0, count, per_batch), per_batch


def deviations(paths: ToolPaths, start: np.ndarray, delta: np.ndarray, ns: np.ndarray,
               index: np.ndarray | None = None) -> np.ndarray:
    """Largest chord deviation (m) of each move split into ``ns`` uniform sub-steps.

    ``start``, ``delta``: (M, n_axes) axis values at the start of each move and the move;
    ``index``: the moves to evaluate (default all), one per value of ``ns``. Moves are
    evaluated in batches of equal ``n``.
    """
    out = np.empty(len(ns))
    if len(ns) and ns.max() <= 64:  # bisection rounds: a few small values, no sort
        values = np.flatnonzero(np.bincount(ns))
        groups = [np.flatnonzero(ns == n) for n in values] if len(values) > 1 else [
            np.arange(len(ns))]
    else:
        values = np.unique(ns)
        order = np.argsort(ns, kind="stable")
        bounds = [*np.searchsorted(ns[order], values).tolist(), len(ns)]
        groups = [order[bounds[j]:bounds[j + 1]] for j in range(len(values))]
    batches = _Batches()
    for n, chosen in zip(values.tolist(), groups, strict=True):
        firsts, per_batch = _batches(n, paths.k, len(chosen))
        for a in firsts:
            some = chosen[a:a + per_batch]

            def job(some=some, n=n):
                moves = some if index is None else index[some]
                out[some] = _deviation_batch(paths, start[moves], delta[moves], n)
            batches.add(job)
    batches.run()
    return out


def substeps(paths: ToolPaths, start: np.ndarray, delta: np.ndarray,
             tolerance: float) -> tuple[np.ndarray, np.ndarray, list[Stall]]:
    """Sub-steps of each rotary move, which moves would need more than `MAX_SUBSTEPS`
    (their count is left 0), and where a path steps (`machinesim.motion.steps.Stall`, in
    move order; each of those moves is also among the failed).

    The deviation ``d1`` of the whole move as one chord (three poses) predicts the count:
    a sub-step of a smooth path deviates from its chord by ``h**2 |p''| / 8`` to leading
    order, so ``n`` sub-steps give about ``d1 / n**2``, and ``n = ceil(sqrt(d1 / tol))``.
    For an arc this is the fewest that can hold: ``1 - cos(x / n) >= (1 - cos x) / n**2``,
    so ``n - 1`` sub-steps deviate by more than ``d1 / (n - 1)**2 > tol``. A move that one
    chord keeps within tolerance is one sub-step. A predicted count up to 8 is checked at
    its own sub-step midpoints. A larger one (a long turn, where one chord is no guide),
    or one whose check failed (a path that is not an arc), is found from the deviation at
    8 sub-steps: the fewest in between by bisection if 8 hold, otherwise
    ``n = ceil(8 sqrt(d8 / tol))`` raised by 10 % until it holds. Every count returned has
    been checked at its sub-step midpoints, where the deviation of a smooth path (a
    rotation, a spiral) peaks. An error table bends the path at its breakpoints, where the
    peak is not at a midpoint (the midpoints alone let chords reach 2.7 times the tolerance
    on random moves with random error tables): every breakpoint a move crosses is checked
    against the line of its sub-step's chord, and the count raised by 25 % until it holds
    (`_corner_failures`). Sampled densely (16 points a sub-step) on the random programs of
    tests/test_motion_identity.py, 3 seeds, 5 machines, with and without errors, no chord of
    1388 rotary segments then leaves the tolerance (largest 0.99998 of it).

    A path that steps (an error table whose value changes by more than the tolerance over
    a span shorter than a sub-step) never holds: the deviation stays at about half the step
    however many sub-steps, and the 10 % rounds went on towards `MAX_SUBSTEPS` (a 1 um step
    in a straightness table over 1 pm: 93 rounds, 2.9 s for the edge alone, not done in 10
    min with a nose tool's 397 points). A move whose deviation has not halved while its
    count grew fourfold (a smooth path's falls 16-fold, one with a corner 4-fold) is looked
    into (`steps._zoom`), and refused (0.04 s there) as soon as its path leaves the chord of a
    piece of 1 / `MAX_SUBSTEPS` of the move by more than the tolerance: no count the cap
    allows follows it. One that only stalls while its sub-steps are longer than a dense
    table's spacing is cleared by the look and raised on as before.
    """
    count = len(start)
    steps = np.zeros(count, dtype=np.int64)
    failed = np.zeros(count, dtype=bool)
    stalls: list[Stall] = []
    if not count:
        return steps, failed, stalls
    first = deviations(paths, start, delta, np.ones(count, dtype=np.int64))
    within = first <= tolerance
    if paths.smooth_axes.size:
        bends = np.any(delta[:, paths.smooth_axes] != 0.0, axis=1)
        looked = np.flatnonzero(within & bends)
        within[looked[_bowed(paths, start, delta, looked, tolerance)]] = False
    steps[within] = 1
    short = np.flatnonzero(~within)
    guess = np.maximum(2, np.ceil(np.sqrt(first[short] / tolerance))).astype(np.int64)
    # a guess up to 8 sub-steps, checked at its own midpoints
    few = guess <= _FIRST_TRIAL
    checked, guess = short[few], guess[few]
    ok = deviations(paths, start, delta, guess, checked) <= tolerance
    steps[checked[ok]] = guess[ok]
    # the rest (long turns, and paths one chord misjudged) by the deviation at 8
    rest = np.concatenate([short[~few], checked[~ok]])
    lo = np.concatenate([np.ones(int((~few).sum()), dtype=np.int64), guess[~ok]])
    d8 = deviations(paths, start, delta, np.full(len(rest), _FIRST_TRIAL), rest)
    fine = d8 <= tolerance
    steps[rest[fine]] = _fewest(paths, start, delta, tolerance, rest[fine], lo[fine])
    todo = rest[~fine]
    n = np.ceil(_FIRST_TRIAL * np.sqrt(d8[~fine] / tolerance))
    _raise_until_within(paths, start, delta, tolerance, steps, failed, stalls, todo, n,
                        (np.full(len(todo), _FIRST_TRIAL), d8[~fine]))
    hold_corners(paths, start, delta, tolerance, steps, failed, stalls)
    return steps, failed, sorted(stalls, key=lambda stall: stall.move)


def hold_corners(paths, start, delta, tolerance, steps, failed, stalls,
                  moves: np.ndarray | None = None) -> None:
    """Corners of the error tables (`_corner_failures`) and the bows of polynomials of
    degree 3 or more between the midpoints (`machinesim.motion.bows`): checked, the counts of
    ``moves`` (default all) raised by 25 % until held, in place."""
    from machinesim.motion.bows import bowed_steps  # bows imports this module

    skip = failed if moves is None else failed | ~np.isin(np.arange(len(steps)), moves)
    for _ in range(64):
        bad = np.union1d(_corner_failures(paths, start, delta, steps, skip, tolerance),
                         bowed_steps(paths, start, delta, steps, skip, tolerance))
        if not bad.size:
            break
        _raise_until_within(paths, start, delta, tolerance, steps, failed, stalls, bad,
                            np.ceil(steps[bad] * 1.25 + 1))
        skip = skip | failed


def hold_raised(paths: ToolPaths, start: np.ndarray, delta: np.ndarray, tolerance: float,
                steps: np.ndarray, failed: np.ndarray, stalls: list[Stall],
                least: np.ndarray) -> None:
    """Raise the `substeps` counts ``steps`` to ``least`` (another rule's fewest: a rotary
    turn of at most 45 deg a sub-step), in place, checking each raised count at its own
    sub-step midpoints and raising it by 10 % until they hold, as `substeps` does
    (``failed`` and ``stalls`` as there; a ``least`` beyond `MAX_SUBSTEPS` is left to the
    caller's refusal).

    A count that held is not always one that holds once raised: the midpoints see a path
    only at the fractions they sample, and a move that turns a rotary axis by 720 deg is at
    one point at its ends and at its middle, so one chord "held" (deviation 0) and the 16
    sub-steps of 45 deg it was raised to left their chords by 0.38 mm at 5 mm from the axis.
    A count that holds on a smooth path stays one when raised (its deviation falls), so such
    a move keeps the count ``least``.

    Nor does a raised count hold an error table's corners because the count before did: a
    corner at (or near) a node of the old sub-steps lies inside a new one, where the line
    of its chord can pass it by more than the tolerance while the midpoints hold (C turned
    260 deg with the edge on the axis, EXC 0.64 um and EYC 0.2 um at 60 deg, 0 at 0 and 260:
    5 sub-steps held 160 nm, the 6 they were raised to left the corner 184 nm off its
    chord). The raised moves' corners are checked again and raised until they hold, as
    `substeps` does (`hold_corners`).
    """
    raised = np.flatnonzero(~failed & (least > steps) & (least <= MAX_SUBSTEPS))
    if not raised.size:
        return
    _raise_until_within(paths, start, delta, tolerance, steps, failed, stalls, raised,
                        least[raised].astype(np.float64))
    hold_corners(paths, start, delta, tolerance, steps, failed, stalls, raised)
    stalls.sort(key=lambda stall: stall.move)


def _bowed(paths: ToolPaths, start: np.ndarray, delta: np.ndarray, moves: np.ndarray,
           tolerance: float) -> np.ndarray:
    """Which of ``moves``, whose one chord holds at its midpoint, leave it by more than
    ``tolerance`` at a quarter and three quarters of the move (each point against the chord's
    point at the same fraction, as the midpoint is).

    One chord's midpoint sees a path only there: a straightness polynomial odd about the
    move's middle (an S, ``EYX = c x**3`` on a move from -a to a, or x (x - 5)(x - 10) of
    1 um on X from 0 to 10 mm) lies on the chord's middle, and the move was one sub-step
    1 um off its path. A smooth bow (an arc, a parabola) is off by less at its quarters than
    at its middle, so such a move still holds in one.
    """
    out = np.zeros(len(moves), dtype=bool)
    f = np.array([0.0, 0.25, 0.75, 1.0])
    per = max(1, _ROWS_PER_BATCH // (len(f) * paths.k))
    for a in range(0, len(moves), per):
        some = moves[a:a + per]
        pos = paths.positions(_columns(start[some], delta[some], f), len(f))
        shape = (len(f), len(some)) + ((paths.k,) if paths.k > 1 else ())
        quarter = three = 0.0
        for c in range(3):
            p = pos[c].reshape(shape)
            quarter = quarter + (p[1] - (0.75 * p[0] + 0.25 * p[3])) ** 2
            three = three + (p[2] - (0.25 * p[0] + 0.75 * p[3])) ** 2
        total = np.maximum(quarter, three)
        if paths.k > 1:
            total = total.max(axis=1)
        out[a:a + per] = np.sqrt(total) > tolerance
    return out


def _raise_until_within(paths, start, delta, tolerance, steps, failed, stalls, todo, n,
                        since=None) -> None:
    """Counts ``n`` for moves ``todo``, raised by 10 % until their midpoints hold (into
    ``steps``; moves beyond `MAX_SUBSTEPS` into ``failed``).

    ``since``: (counts, deviations) already tried on the moves (default: their first round
    here). A move whose deviation has not halved since while its count grew fourfold is
    looked into (`steps._zoom`): if its path leaves a piece's chord by more than ``tolerance``
    where the pieces are 1 / `MAX_SUBSTEPS` of the move, it goes into ``failed`` and
    ``stalls``; if not, the comparison starts again from this round.
    """
    from machinesim.motion.steps import Stall, _zoom  # steps imports this module

    base_n, base_d = (None, None) if since is None else (
        np.asarray(since[0], dtype=np.int64), np.asarray(since[1], dtype=np.float64))
    while todo.size:
        over = n > MAX_SUBSTEPS
        failed[todo[over]] = True
        todo, n = todo[~over], n[~over]
        if base_n is not None:
            base_n, base_d = base_n[~over], base_d[~over]
        if not todo.size:
            break
        trial = n.astype(np.int64)
        dev = deviations(paths, start, delta, trial, todo)
        ok = dev <= tolerance
        steps[todo[ok]] = trial[ok]
        if base_n is None:
            base_n, base_d = trial.copy(), dev.copy()
        due = ~ok & (trial >= 4 * base_n)
        stuck = np.zeros(len(todo), dtype=bool)
        for i in np.flatnonzero(due & (dev > base_d / 2)).tolist():
            move = int(todo[i])
            low, high, worst = _zoom(paths, start[move], delta[move], int(trial[i]))
            if worst > tolerance:
                stuck[i] = True
                failed[move] = True
                stalls.append(Stall(move, low, high, worst, (
                    (int(base_n[i]), float(base_d[i])), (int(trial[i]), float(dev[i])))))
        base_n[due], base_d[due] = trial[due], dev[due]
        keep = ~ok & ~stuck
        todo, n = todo[keep], np.ceil(n[keep] * 1.1)
        base_n, base_d = base_n[keep], base_d[keep]


def _corner_failures(paths, start, delta, steps, failed, tolerance) -> np.ndarray:
    """Moves whose path, at a breakpoint of an error table it crosses inside a sub-step,
    lies farther than ``tolerance`` from that sub-step's chord.

    A table interpolates linearly, so the path turns a corner where its axis crosses a
    breakpoint; the deviation from a chord peaks there, not at the sub-step's midpoint
    (on random five-axis moves with error tables the midpoints missed up to 2.7 times the
    tolerance). Each crossing is evaluated with the ends of its sub-step.
    """
    moves, fractions = [], []
    for axis, knots, period in paths.corners:
        d = delta[:, axis]
        live = np.flatnonzero((d != 0.0) & (steps > 0) & ~failed)
        if not live.size:
            continue
        if period is not None:
            move, at = _each_turn(knots, period, start[live, axis], d[live])
            f = (at - start[live[move], axis]) / d[live[move]]
            inside = (f > 0.0) & (f < 1.0)
            moves.append(live[move[inside]])
            fractions.append(f[inside])
            continue
        f = (knots[None, :] - start[live, axis][:, None]) / d[live][:, None]
        row, col = np.nonzero((f > 0.0) & (f < 1.0))
        moves.append(live[row])
        fractions.append(f[row, col])
    if not moves:
        return np.zeros(0, dtype=np.int64)
    move = np.concatenate(moves)
    f = np.concatenate(fractions)
    if not move.size:
        return move
    if len(move) * paths.k > 4 * _ROWS_PER_BATCH:  # many turns of a spindle: in parts
        per = max(1, 4 * _ROWS_PER_BATCH // paths.k)
        bad = [_off_chord(paths, start, delta, steps, move[a:a + per], f[a:a + per],
                          tolerance) for a in range(0, len(move), per)]
        return np.unique(np.concatenate(bad))
    return np.unique(_off_chord(paths, start, delta, steps, move, f, tolerance))


def _each_turn(knots, period, start, d):
    """Every breakpoint ``knots + k * period`` inside each move's range [start, start + d]:
    (move index, axis value) pairs."""
    low, high = np.minimum(start, start + d), np.maximum(start, start + d)
    first = np.ceil((low[:, None] - knots[None, :]) / period)
    count = np.maximum(np.floor((high[:, None] - knots[None, :]) / period) - first + 1, 0)
    count = count.astype(np.int64).ravel()
    pair = np.repeat(np.arange(count.size), count)
    turn = (np.arange(pair.size) - np.repeat(np.cumsum(count) - count, count)
            + first.ravel()[pair])
    return pair // len(knots), knots[pair % len(knots)] + turn * period


def _off_chord(paths, start, delta, steps, move, f, tolerance) -> np.ndarray:
    """The moves (with repeats) whose corner at fraction ``f`` lies off its chord."""
    n = steps[move]
    j = np.minimum(np.floor(f * n), n - 1)
    rows = len(move)
    q = [np.concatenate([start[move, i] + g * delta[move, i] for g in (j / n, (j + 1) / n, f)])
         for i in range(start.shape[1])]
    pos = paths.positions(q, _blocks(3 * rows))
    # distance of the corner from the line of its sub-step's chord (each tool point)
    a, b, c = zip(*(p.reshape((3, rows) + p.shape[1:]) for p in pos[:3]), strict=True)
    chord = [b[i] - a[i] for i in range(3)]
    off = [c[i] - a[i] for i in range(3)]
    length2 = sum(x * x for x in chord)
    along = sum(off[i] * chord[i] for i in range(3)) / np.where(length2 > 0, length2, 1.0)
    total = sum((off[i] - along * chord[i]) ** 2 for i in range(3))
    if np.ndim(total) == 2:
        total = total.max(axis=1)
    return move[np.sqrt(total) > tolerance]


def _fewest(paths, start, delta, tolerance, moves, lo) -> np.ndarray:
    """The fewest sub-steps in (lo, 8] within tolerance, by bisection (8 holds, lo not)."""
    lo = lo.copy()
    hi = np.full(len(moves), _FIRST_TRIAL, dtype=np.int64)
    while True:
        active = np.flatnonzero(hi - lo > 1)
        if not active.size:
            return hi
        mid = (lo[active] + hi[active]) // 2
        ok = deviations(paths, start, delta, mid, moves[active]) <= tolerance
        hi[active[ok]] = mid[ok]
        lo[active[~ok]] = mid[~ok]
