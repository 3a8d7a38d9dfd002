"""Sub-steps along an axis with a polynomial error of degree 3 or more, checked between
their midpoints: such a polynomial can vanish at the points the chord rule looks at
(`machinesim.motion.chords`), so each sub-step is looked at where its degree says.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from machinesim.motion.chords import _ROWS_PER_BATCH, MAX_SUBSTEPS, _columns

__all__ = ["bowed_steps"]

#: Points a sub-step is evaluated at, in `bowed_steps`, beyond the degree of the path's
#: error polynomial: one for the lever arm of a second axis moving with it (its position
#: times an angular error), one to spare.
_BOW_EXTRA = 2
#: Points of the interpolant evaluated per sub-step point where its bound fails.
_BOW_DENSE = 32


@lru_cache(maxsize=64)
def _lobatto(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``k + 1`` Chebyshev-Lobatto points on [0, 1] (0 and 1 among them), the matrix
    from values there to the Chebyshev coefficients of their interpolant of degree ``k``,
    and the Chebyshev polynomials at `_BOW_DENSE` * k + 1 uniform points (rows)."""
    x = -np.cos(np.pi * np.arange(k + 1) / k)  # -1 .. 1
    to_coefficients = np.linalg.inv(np.polynomial.chebyshev.chebvander(x, k))
    dense = np.polynomial.chebyshev.chebvander(np.linspace(-1.0, 1.0, _BOW_DENSE * k + 1), k)
    f = (x + 1.0) / 2.0
    f[0], f[-1] = 0.0, 1.0
    for a in (f, to_coefficients, dense):
        a.flags.writeable = False
    return f, to_coefficients, dense


def bowed_steps(paths, start, delta, steps, skip, tolerance) -> np.ndarray:
    """Moves (not ``skip``) along an axis with a polynomial error of degree ``d >= 3`` one of
    whose sub-steps leaves its chord by more than ``tolerance`` anywhere, not only at the
    midpoint the rule checks (and one chord's quarters, `chords._bowed`).

    The deviation of a sub-step from its chord is the path's polynomial less the chord: a
    straightness of degree ``d`` has ``d - 2`` zeros inside a sub-step to hide at, and at the
    five points 0, 1/4, 1/2, 3/4, 1 of a move ``k t (t - 1/4)(t - 1/2)(t - 3/4)(t - 1)``
    (1 um at its peaks, X over +-250 mm) left one chord, or two sub-steps, 1 um off the
    path. Points that a degree chooses cannot be so avoided: each sub-step is evaluated at
    the ``d + 3`` Chebyshev-Lobatto points of degree ``d + 2`` (`_BOW_EXTRA`), where the
    deviation determines the interpolant of that degree, exactly the path's for a
    polynomial one (a straightness: degree ``d``; an angular error times another moving
    axis' lever: ``d + 1``). Its Chebyshev coefficients ``a_j`` bound it: ``|sum a_j T_j|
    <= sum |a_j|``; a sub-step beyond that bound is evaluated at `_BOW_DENSE` points per
    degree, and fails beyond the tolerance there. Moves along axes with polynomials of
    degree 2 or less keep the midpoint rule, exact for them (a parabola's deviation from
    its chord peaks at its middle).
    """
    moving = np.abs(delta) > 0.0
    degree = np.where(moving, paths.degrees[None, :], 0).max(axis=1) if len(delta) else (
        np.zeros(0, dtype=np.int64))
    live = np.flatnonzero((degree >= 3) & (steps > 0) & ~skip)
    if not live.size:
        return np.zeros(0, dtype=np.int64)
    bad = []
    keys = degree[live] * (MAX_SUBSTEPS + 1) + steps[live]
    for key in np.unique(keys).tolist():
        moves = live[keys == key]
        d, n = divmod(key, MAX_SUBSTEPS + 1)
        k = int(d) + _BOW_EXTRA
        # sub-steps a batch (of one move: a long one in pieces), moves a batch
        chunk = max(1, _ROWS_PER_BATCH // ((k + 1) * paths.k))
        per = max(1, chunk // n)
        for a in range(0, len(moves), per):
            some = moves[a:a + per]
            off = np.zeros(len(some), dtype=bool)
            for j in range(0, n, chunk):
                off |= _off_between(paths, start[some], delta[some], n, range(j, min(j + chunk, n)),
                                    k, tolerance)
            bad.extend(some[off].tolist())
    return np.array(sorted(bad), dtype=np.int64)


def _off_between(paths, start, delta, n, pieces, k, tolerance) -> np.ndarray:
    """Which moves (``start``, ``delta``: (M, n_axes), each split into ``n`` sub-steps) leave
    the chord of one of the sub-steps ``pieces`` by more than ``tolerance``, by the
    interpolant of degree ``k`` at each sub-step's Chebyshev-Lobatto points (`bowed_steps`)."""
    f, to_coefficients, dense = _lobatto(k)
    # the Lobatto points of the sub-steps, sub-step after sub-step
    fractions = ((np.asarray(pieces, dtype=np.float64)[:, None] + f[None, :]) / n).ravel()
    pos = paths.positions(_columns(start, delta, fractions), len(fractions))
    shape = (len(pieces), k + 1, len(start)) + ((paths.k,) if paths.k > 1 else ())
    coefficients = []
    for c in range(3):
        p = pos[c].reshape(shape)
        chord = p[:, :1] + f.reshape((1, -1) + (1,) * (p.ndim - 2)) * (p[:, -1:] - p[:, :1])
        coefficients.append(np.tensordot(to_coefficients, p - chord, axes=(1, 1)))
    # coefficients[c]: (k + 1, sub-steps, moves[, points]); |sum a_j T_j| <= sum |a_j|
    bound = np.sqrt(sum(x * x for x in coefficients)).sum(axis=0)
    if bound.ndim == 3:
        bound = bound.max(axis=2)
    out = np.zeros(len(start), dtype=bool)
    for piece, move in zip(*np.nonzero(bound > tolerance), strict=True):
        if out[move]:
            continue
        values = [dense @ x[:, piece, move] for x in coefficients]
        out[move] = np.sqrt(sum(v * v for v in values)).max() > tolerance
    return out
