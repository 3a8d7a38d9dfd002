"""Rotary moves split to the chord tolerance, for many moves at once.

A move that turns a rotary axis is split into the fewest uniform sub-steps whose chords stay
within the tolerance of the true path of every tool point (see `machinesim.motion`). The
rule, for each move: the deviation at ``n = 8`` sub-steps; if within tolerance, the fewest
``n <= 8`` by bisection; otherwise ``n = ceil(8 sqrt(d / tolerance))``, raised by 10 % until
it holds. Deviations are measured at sub-step midpoints, where an arc's sagitta peaks.

Here every move goes through that rule in lockstep: each round evaluates the deviation of
all the moves still searching, in one batch, so a program of 10^6 rotary moves costs a
few dozen numpy passes instead of 10^6 Python loops. The numbers are those of evaluating
each move alone with `Machine.tool_pose`:

* the axis values of the samples are formed by the same operations (``start + f * delta``,
  ``f`` from `numpy.linspace`);
* `ToolPaths` walks the machine's kinematic plan with the operations of the batched
  evaluator of `machinesim.kinematics`, in the same order, so each position is the same
  float64 number; constants are folded (a product with an exact 0 or 1, a sum with an exact
  0 are skipped), which can only change the sign of a zero;
* the evaluator picks a series or numpy's ``cos``/``sin`` for a rotation by the largest
  angle in each batch it is given (`machinesim.kinematics._cos_sin`); the batches of
  `Machine.tool_pose` as the rule calls it (a move's nodes or midpoints, in blocks of
  `kinematics._BLOCK`) are kept as groups here and decided one by one;
* deviations are summed in numpy's order (x**2 + y**2, then + z**2) and compared as before;
  the largest is the square root of the largest square (sqrt is monotonic and correctly
  rounded, so that is the largest norm, bit for bit);
* the poses at 8 sub-steps serve 4, 2 and 1 sub-steps too (the same fractions, bit for
  bit), except for a move where such a smaller group would have picked the other cos/sin
  method: that move is evaluated afresh.

Batches of moves run on up to `WORKERS` threads (numpy releases the GIL in its loops). The
cost that stays is that of the rule itself: for a slow-tool-servo point list whose every
move turns C, about 36 poses a move (a cos and a sin each, ~22 ns together).

The reference planner, kept in the tests, is held to this segment by segment.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache

import numpy as np

from machinesim.kinematics import _BLOCK, _cos_sin
from machinesim.tolerances import SERIES_MAX_RAD

#: A move is split into at most this many sub-steps: beyond it the request is unreasonable
#: (a 1 nm chord over a full turn at 1 m radius needs ~70,000).
MAX_SUBSTEPS = 1_000_000
#: Rows (samples times tool points) evaluated in one batch: large enough that numpy's
#: per-call cost vanishes, small enough that the working arrays stay in cache.
_ROWS_PER_BATCH = 1 << 17
#: Threads that evaluate batches at once: the cores there are, up to 4.
WORKERS = min(4, os.cpu_count() or 1)
#: The first trial number of sub-steps of the rule.
_FIRST_TRIAL = 8


# ------------------------------------------------------------------- folded arithmetic
# A value is a Python float (the same for every row) or an ndarray (one per row).


def _mul(a, b):
    if type(a) is float:
        a, b = b, a
    if type(b) is float:
        if type(a) is float:
            return a * b
        if b == 0.0:
            return 0.0
        if b == 1.0:
            return a
    return a * b


def _add(a, b):
    if type(a) is float and type(b) is float:
        return a + b
    if type(a) is float and a == 0.0:
        return b
    if type(b) is float and b == 0.0:
        return a
    return a + b


def _sub(a, b):
    if type(a) is float and type(b) is float:
        return a - b
    if type(b) is float and b == 0.0:
        return a
    if type(a) is float and a == 0.0:
        return -b
    return a - b


def _dot(terms):
    """Sum of products in order (numpy's einsum order), exact zero terms skipped."""
    total = None
    for a, b in terms:
        p = _mul(a, b)
        if type(p) is float and p == 0.0:
            continue
        total = p if total is None else _add(total, p)
    return 0.0 if total is None else total


class ToolPaths:
    """Positions of tool points in the workpiece frame for many axis vectors at once.

    Parameters
    ----------
    machine : machinesim.Machine
    errors : ErrorModel or None
    points : ndarray, shape (k, 3)
        Points in the tool_tip frame, m; the first is the edge (origin).
    """

    def __init__(self, machine, errors, points: np.ndarray) -> None:
        binding = machine.binding(errors)
        kin = machine.kin
        self._tool_ops = kin._plan("tool_tip", binding)
        self._wp_ops = kin._plan("workpiece", binding)
        self.points = points
        self.k = len(points)
        self._edge_only = self.k == 1 and not np.any(points)

    def positions(self, q: list[np.ndarray], groups, keep_angles: bool = False):
        """x, y, z of every point at every row (each (N,) or (N, k)).

        ``q``: one (N,) array of values per axis. ``groups``: the groups of rows that
        `Machine.tool_pose` would have been given in one call (one block) each, an int
        ``g`` (consecutive groups of ``g`` rows) or (starts, sizes); they decide the
        series/cos choice of rotations. With ``keep_angles``, a fourth item lists the angle
        (N,) of every rotation evaluated.
        """
        n = len(q[0])
        angles = [] if keep_angles else None
        rt, pt = self._run(self._tool_ops, q, groups, angles)
        rw, pw = self._run(self._wp_ops, q, groups, angles)
        d = [_sub(pt[k], pw[k]) for k in range(3)]
        pos = [_dot((rw[k][i], d[k]) for k in range(3)) for i in range(3)]
        if self._edge_only:
            return [np.full(n, p) if type(p) is float else p for p in pos] + [angles]
        out = np.zeros((n, 4, 4))
        for i in range(3):
            for j in range(3):
                out[:, i, j] = _dot((rw[k][i], rt[k][j]) for k in range(3))
            out[:, i, 3] = pos[i]
        p = out[:, :3, :3] @ self.points.T + out[:, :3, 3:4]
        return [p[:, 0, :], p[:, 1, :], p[:, 2, :], angles]

    @staticmethod
    def _run(ops, q, groups, angles):
        """`Kinematics._run` on folded values: rot[i][j] and pos[i] of the plan's frame."""
        rot = pos = None
        for op in ops:
            if op[0] == "C":
                c_rot, c_pos = op[1], op[2]
                if rot is None:
                    rot = [[float(c_rot[i, j]) for j in range(3)] for i in range(3)]
                    pos = [float(c_pos[i]) for i in range(3)]
                    continue
                terms = [k for k in range(3) if c_pos[k]]
                for i in range(3):
                    total = 0.0
                    for k in terms:
                        total = _add(total, _mul(rot[i][k], float(c_pos[k])))
                    pos[i] = _add(pos[i], total)
                if not np.array_equal(c_rot, np.eye(3)):
                    new = [[0.0] * 3 for _ in range(3)]
                    for j in range(3):
                        ks = [k for k in range(3) if c_rot[k, j]]
                        for i in range(3):
                            total = 0.0
                            for k in ks:
                                total = _add(total, _mul(rot[i][k], float(c_rot[k, j])))
                            new[i][j] = total
                    rot = new
                continue
            _, kind, k, source = op
            if source[0] == "axis":
                _, i, offset, sign = source
                value = sign * (q[i] + offset) if offset else sign * q[i]
            else:
                _, var, sign = source
                value = (sign * var.sign) * var.component.evaluate(q[var.axis])
            if kind == "P":
                for i in range(3):
                    pos[i] = _add(pos[i], _mul(rot[i][k], value))
                continue
            i1, i2 = (k + 1) % 3, (k + 2) % 3
            if angles is not None:
                angles.append(value)
            c, s = _grouped_cos_sin(value, groups)
            for i in range(3):
                col1, col2 = rot[i][i1], rot[i][i2]
                rot[i][i1] = _add(_mul(col1, c), _mul(col2, s))
                rot[i][i2] = _sub(_mul(col2, c), _mul(col1, s))
        return rot, pos


def _grouped_cos_sin(value: np.ndarray, groups):
    """`kinematics._cos_sin` applied to each group of rows on its own.

    ``groups``: an int ``g`` (the rows are ``g`` blocks of ``M``, fraction after fraction,
    and each of the ``M`` columns is a group) or (starts, sizes) of consecutive rows.
    """
    low, high = float(value.min()), float(value.max())
    if max(-low, high) < SERIES_MAX_RAD:
        return _cos_sin(value)  # every group in series range
    if low >= SERIES_MAX_RAD or high <= -SERIES_MAX_RAD:
        return np.cos(value), np.sin(value)  # no group in series range
    size = np.abs(value)
    if isinstance(groups, int):
        series = size.reshape(groups, -1).max(axis=0) < SERIES_MAX_RAD
        rows = np.tile(series, groups)
    else:
        starts, sizes = groups
        series = np.maximum.reduceat(size, starts) < SERIES_MAX_RAD
        rows = np.repeat(series, sizes)
    if not series.any():
        return np.cos(value), np.sin(value)
    c, s = np.empty_like(value), np.empty_like(value)
    c[rows], s[rows] = _cos_sin(value[rows])
    others = ~rows
    c[others], s[others] = np.cos(value[others]), np.sin(value[others])
    return c, s


@lru_cache(maxsize=256)
def _fractions(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Node and midpoint fractions of ``n`` uniform sub-steps (as the rule computes them)."""
    f = np.linspace(0.0, 1.0, n + 1)
    mid = (f[:-1] + f[1:]) / 2
    f.flags.writeable = mid.flags.writeable = False
    return f, mid


def _dyadic_rows() -> dict[int, tuple[np.ndarray, np.ndarray]] | None:
    """Rows of the nodes of 8 sub-steps that are the nodes and midpoints of 4, 2 and 1
    (the same fractions, bit for bit), or None if linspace were ever to differ."""
    nodes8 = _fractions(_FIRST_TRIAL)[0]
    rows = {}
    for n in (4, 2, 1):
        f, mid = _fractions(n)
        step = _FIRST_TRIAL // n
        at, at_mid = np.arange(0, _FIRST_TRIAL + 1, step), np.arange(step // 2, _FIRST_TRIAL,
                                                                      step)
        if not (np.array_equal(nodes8[at], f) and np.array_equal(nodes8[at_mid], mid)):
            return None
        rows[n] = (at, at_mid)
    return rows


_DYADIC = _dyadic_rows()


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


def _deviation_batch(paths: ToolPaths, start: np.ndarray, delta: np.ndarray, n: int,
                     dyadic: bool = False):
    """Deviations of ``M`` moves all split into ``n`` sub-steps; with ``dyadic`` (n = 8)
    also those of 4, 2 and 1 sub-steps from the same poses, and where they are valid (the
    series/cos choice of every rotation the same as that group alone would get)."""
    m = len(start)
    f_nodes, f_mids = _fractions(n)
    if n + 1 <= _BLOCK:
        nodes = paths.positions(_columns(start, delta, f_nodes), n + 1, keep_angles=dyadic)
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
    if not dyadic:
        return out
    angles = [np.abs(v).reshape(n + 1, m) for v in nodes[3]]
    fewer = {}
    for k, (at, at_mid) in _DYADIC.items():
        valid = np.ones(m, dtype=bool)
        for size in angles:
            used = size.max(axis=0) < SERIES_MAX_RAD
            for rows in (at, at_mid):
                valid &= (size[rows].max(axis=0) < SERIES_MAX_RAD) == used
        d = np.sqrt(_chord_error(nodes_c, nodes_c, at[:-1], at[1:], at_mid))
        fewer[k] = (d, valid)
    return out, fewer


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


def _first_trial(paths: ToolPaths, start: np.ndarray, delta: np.ndarray):
    """Deviations at 8 sub-steps, and at 4, 2, 1 from the same poses: {n: (d, valid)}."""
    count = len(start)
    out = np.empty(count)
    if _DYADIC is None:
        return deviations(paths, start, delta, np.full(count, _FIRST_TRIAL)), {}
    fewer = {k: (np.empty(count), np.empty(count, dtype=bool)) for k in _DYADIC}
    batches = _Batches()
    firsts, per_batch = _batches(_FIRST_TRIAL, paths.k, count)
    for a in firsts:
        def job(a=a):
            b = min(count, a + per_batch)
            out[a:b], some = _deviation_batch(paths, start[a:b], delta[a:b], _FIRST_TRIAL,
                                              dyadic=True)
            for k, (d, valid) in some.items():
                fewer[k][0][a:b] = d
                fewer[k][1][a:b] = valid
        batches.add(job)
    batches.run()
    return out, fewer


def substeps(paths: ToolPaths, start: np.ndarray, delta: np.ndarray,
             tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Sub-steps of each rotary move by the rule above, and which moves would need more
    than `MAX_SUBSTEPS` (their count is left 0)."""
    count = len(start)
    steps = np.zeros(count, dtype=np.int64)
    failed = np.zeros(count, dtype=bool)
    if not count:
        return steps, failed
    first, fewer = _first_trial(paths, start, delta)
    within = first <= tolerance
    # within at 8: the fewest n <= 8 by the same bisection
    fine = np.flatnonzero(within)
    lo = np.zeros(len(fine), dtype=np.int64)
    hi = np.full(len(fine), _FIRST_TRIAL, dtype=np.int64)
    while True:
        active = np.flatnonzero(hi - lo > 1)
        if not active.size:
            break
        mid = (lo[active] + hi[active]) // 2
        d = np.empty(len(active))
        fresh = np.ones(len(active), dtype=bool)
        for k, (known, valid) in fewer.items():
            take = (mid == k) & valid[fine[active]]
            d[take] = known[fine[active[take]]]
            fresh &= ~take
        if fresh.any():
            d[fresh] = deviations(paths, start, delta, mid[fresh], fine[active[fresh]])
        ok = d <= tolerance
        hi[active[ok]] = mid[ok]
        lo[active[~ok]] = mid[~ok]
    steps[fine] = hi
    # beyond: predicted from the 1/n**2 fall of the sagitta, raised by 10 % until it holds
    todo = np.flatnonzero(~within)
    n = np.ceil(_FIRST_TRIAL * np.sqrt(first[todo] / tolerance))
    while todo.size:
        over = n > MAX_SUBSTEPS
        failed[todo[over]] = True
        todo, n = todo[~over], n[~over]
        if not todo.size:
            break
        trial = n.astype(np.int64)
        ok = deviations(paths, start, delta, trial, todo) <= tolerance
        steps[todo[ok]] = trial[ok]
        todo, n = todo[~ok], np.ceil(n[~ok] * 1.1)
    return steps, failed
