"""The search of the turning engine: the exact lower envelope of the nose arc over a path.

Split from `machinesim.cutting.turning` (which holds the public pieces: the path, the nose
profile, `turned_surface`); the method is described there and in
docs/procedures/sts_turning.md ("Finding the minimum").
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from machinesim.cutting.turning import EdgePath, NoseProfile

TWO_PI = 2.0 * math.pi
#: Revolutions the walk takes on each side before the block bounds take over. The walk ends
#: after about R * slope / f revolutions (the contact's distance from the nearest
#: revolution): 2 on the paper's sine grid (R 1 mm, slope 3e-3, f 2 um).
WALK_STEPS = 24
#: Most fixed-point steps for the crossing angle when the offset d varies along the path;
#: each divides the error by rho / |d'| (>= 10 beyond ten times the offset's amplitude).
_CROSSING_STEPS = 64
#: An offset (centre height) that varies by at most this along the path (m), about the
#: path's fitted spindle axis, is taken as constant, and one that is then within this of
#: zero as zero (a tool on the centre height: the poses' round-off, ~1e-17 m, would leave
#: an uncut core of that radius on the axis): the crossings then move by at most
#: 1e-15 m / rho rad and the heights by less than 1e-15 m times the surface slope. A path
#: of many turns far out carries more round-off (the angle's, `_ANGLE_ROUNDOFF` of the
#: largest angle, times the radius), and the bound grows with it (`_spindle_axis`).
OFFSET_CONSTANT_M = 1e-15
#: Most path points in one bin of the angle lookup before it falls back to binary search.
_BIN_STEPS = 8
#: Largest table of sectors (revolutions x sectors per revolution) of the lower bound.
_MAX_SECTORS = 1 << 21
#: Relative round-off margin of angles (x the largest |angle| of the path): a crossing
#: computed as phase + 2 pi k lies in its sector up to a few ulp; 1e-13 is ~500 ulp.
_ANGLE_ROUNDOFF = 1e-13


class _Points:
    """Grid points of one branch: polar coordinates, crossing phase, sector, coordinate range
    in the edge plane, revolutions on the path, and the best height found so far."""

    def __init__(self, engine: _Engine, rho, theta, sigma: float, best) -> None:
        self.rho, self.theta, self.sigma, self.best = rho, theta, sigma, best
        d = engine.d_ref
        root = np.nan_to_num(_root(rho, d), nan=0.0)
        target = theta - np.arctan2(d, sigma * root)
        start = engine.alpha0 - engine.half_sector
        self.phase = start + np.mod(target - start, TWO_PI)
        self.sector = np.clip(((self.phase - start) / engine.sector_width).astype(np.int64), 0,
                              engine.sectors - 1)
        self.first = (self.phase < engine.alpha0).astype(np.int64)
        self.last = np.floor((engine.alpha_end - self.phase) / TWO_PI).astype(np.int64)
        self.low, self.high = engine.coordinates(rho, sigma)

    def take(self, index: np.ndarray) -> _Points:
        part = object.__new__(_Points)
        for name in ("rho", "theta", "best", "phase", "sector", "first", "last", "low",
                     "high"):
            setattr(part, name, getattr(self, name)[index])
        part.sigma = self.sigma
        return part


class _Engine:
    """The path's lookup tables and the per-point search (state of one `turned_surface`)."""

    def __init__(self, path: EdgePath, profile: NoseProfile, sectors: int | None) -> None:
        self.profile = profile
        alpha = path.angle
        self.alpha, self.z = alpha, path.z
        self.centre, self.along, self.offset = _spindle_axis(alpha, path.along, path.offset)
        self.alpha0, self.alpha_end = float(alpha[0]), float(alpha[-1])
        n = alpha.size
        span = self.alpha_end - self.alpha0
        self.d_ref = float(np.median(self.offset))
        self.d_min, self.d_max = float(self.offset.min()), float(self.offset.max())
        self.d_varies = self.d_max > self.d_min
        # equal-angle bins, each pointing at the first path point beyond its start; where a
        # bin holds many points (a dwell, a path far denser in places) binary search instead
        self.bin_width = span / n
        starts = self.alpha0 + self.bin_width * np.arange(n + 1)
        self.bin_first = np.searchsorted(alpha, starts, side="right")
        self.bin_steps = int(np.diff(self.bin_first).max()) + 1
        if self.bin_steps > _BIN_STEPS:
            self.bin_first = None
        # sectors: revolution k, sector j covers alpha0 + 2 pi k + (j - 1/2 .. j + 1/2) w
        turns = math.floor(span / TWO_PI) + 2
        if sectors is None:
            sectors = int(np.clip(4 * round(n * TWO_PI / span), 8, 4096))
        sectors = max(1, min(int(sectors), _MAX_SECTORS // turns))
        self.block = max(1, math.isqrt(turns))
        self.blocks = -(-turns // self.block)
        self.turns = self.blocks * self.block
        self.sectors = sectors
        self.sector_width = TWO_PI / sectors
        self.half_sector = 0.5 * self.sector_width
        self.roundoff = _ANGLE_ROUNDOFF * max(abs(self.alpha0), abs(self.alpha_end), TWO_PI)
        self.levels = {0: self._sector_table()}
        self.block_levels: dict[int, tuple[np.ndarray, ...]] = {}
        # the walk: orientation of the revolutions and the tail certificate's constants
        self.inward = bool(path.along[-1] <= path.along[0])
        if not self.d_varies:
            self._walk_constants()

    # --- exact evaluation --------------------------------------------------------------
    def locate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Segment index i (points i-1, i) and fraction t of each angle; i = 0 off the path."""
        alpha_path = self.alpha
        n = alpha_path.size
        if self.bin_first is None:
            i = np.searchsorted(alpha_path, alpha, side="right")
        else:
            bin_index = np.clip(((alpha - self.alpha0) / self.bin_width).astype(np.int64), 0,
                                n - 1)
            i = self.bin_first[bin_index]
            # an index rounded up across a bin start: one step back
            i -= (i > 0) & (alpha_path[np.maximum(i - 1, 0)] > alpha)
            for _ in range(self.bin_steps):
                ahead = (i < n) & (alpha_path[np.minimum(i, n - 1)] <= alpha)
                if not ahead.any():
                    break
                i += ahead
        inside = (alpha >= self.alpha0) & (alpha <= self.alpha_end)
        i = np.clip(i, 1, n - 1)
        a0, a1 = alpha_path[i - 1], alpha_path[i]
        step = a1 - a0
        t = np.clip((alpha - a0) / np.where(step > 0.0, step, 1.0), 0.0, 1.0)
        return np.where(inside, i, 0), np.where(step > 0.0, t, 1.0)

    @staticmethod
    def _at(values: np.ndarray, i: np.ndarray, t: np.ndarray) -> np.ndarray:
        j = np.maximum(i, 1)
        return values[j - 1] + t * (values[j] - values[j - 1])

    def evaluate(self, points: _Points, k: np.ndarray) -> np.ndarray:
        """H at the crossing of revolution ``k`` per point (inf where not cut)."""
        rho, sigma = points.rho, points.sigma
        alpha = points.phase + TWO_PI * k
        d = self.d_ref
        if self.d_varies:
            alpha, d = self._crossing(points, alpha)
        i, t = self.locate(alpha)
        s = sigma * _root(rho, d) - self._at(self.along, i, t)
        height = self._at(self.z, i, t) + self.profile(s)
        return np.where((i == 0) | np.isnan(s), np.inf, height)

    def _crossing(self, points: _Points, alpha: np.ndarray):
        """Crossing angle near ``alpha`` and the offset there, for a varying offset: the
        fixed point of alpha = theta - atan2(d(alpha), sigma sqrt(rho^2 - d(alpha)^2)),
        which contracts by |d'(alpha)| / rho; iterated to round-off (at most
        `_CROSSING_STEPS`; a point nearer the axis than the offset may not settle, and is
        not crossed there anyway)."""
        rho, theta, sigma = points.rho, points.theta, points.sigma
        alpha = alpha.copy()
        d = np.empty(alpha.size)
        active = np.arange(alpha.size)
        for _ in range(_CROSSING_STEPS):
            i, t = self.locate(alpha[active])
            d[active] = self._at(self.offset, i, t)
            r, dd = rho[active], d[active]
            target = theta[active] - np.arctan2(dd, sigma * np.nan_to_num(_root(r, dd)))
            step = _wrap(target - alpha[active])
            alpha[active] += step
            active = active[np.abs(step) > self.roundoff]
            if not active.size:
                break
        i, t = self.locate(alpha)
        return alpha, self._at(self.offset, i, t)

    def coordinates(self, rho, sigma):
        """Range (low, high) of a point's coordinate sigma sqrt(rho^2 - d^2) in the edge
        plane over the path's offsets (NaN where it is never in the plane)."""
        d_min, d_max = self.d_min, self.d_max
        near = 0.0 if d_min <= 0.0 <= d_max else min(abs(d_min), abs(d_max))
        far = max(abs(d_min), abs(d_max))
        high = _root(rho, near)
        low = np.where(np.isnan(high), np.nan,
                       np.sqrt(np.maximum((rho - far) * (rho + far), 0.0)))
        return (low, high) if sigma > 0 else (-high, -low)

    # --- lower bounds ------------------------------------------------------------------
    def _sector_table(self):
        """Least tip height and range of ``along`` over each sector (flat, turns x sectors),
        widened by the angle round-off; +inf / -inf where the path is not."""
        count = self.turns * self.sectors
        edges = self.alpha0 - self.half_sector + self.sector_width * np.arange(count + 1)
        eps = self.roundoff
        located = [self.locate(shifted) for shifted in (edges - eps, edges + eps)]

        def edge_values(values, op, fill):
            low, high = (np.where(i == 0, fill, self._at(values, i, t)) for i, t in located)
            both = op(low, high)
            return op(both[:-1], both[1:])

        start = np.searchsorted(self.alpha, edges[:-1] - eps, side="right")
        stop = np.searchsorted(self.alpha, edges[1:] + eps, side="left")
        tables = []
        for values, op, fill in ((self.z, np.minimum, np.inf), (self.along, np.minimum, np.inf),
                                 (self.along, np.maximum, -np.inf)):
            inner = _range(values, start, stop, op, fill)
            tables.append(op(edge_values(values, op, fill), inner))
        return tuple(tables)

    def _level(self, level: int):
        if level not in self.levels:
            below = self._level(level - 1)
            shift = 1 << (level - 1)
            self.levels[level] = tuple(
                _widen(values, shift, op)
                for values, op in zip(below, (np.minimum, np.minimum, np.maximum), strict=True))
        return self.levels[level]

    def _block_level(self, level: int):
        if level not in self.block_levels:
            shape = (self.blocks, self.block, self.sectors)
            z_low, a_low, a_high = self._level(level)
            self.block_levels[level] = (z_low.reshape(shape).min(axis=1),
                                        a_low.reshape(shape).min(axis=1),
                                        a_high.reshape(shape).max(axis=1))
        return self.block_levels[level]

    def level_of(self, rho: np.ndarray) -> np.ndarray:
        """Level of the widened sectors each point needs (0 for a constant offset)."""
        if not self.d_varies:
            return np.zeros(rho.size, dtype=np.int64)

        def angle(d):
            return np.arcsin(np.clip(d / np.maximum(rho, 1e-300), -1.0, 1.0))

        ref = angle(self.d_ref)
        spread = np.maximum(np.abs(angle(self.d_max) - ref), np.abs(angle(self.d_min) - ref))
        spread = np.where(rho <= max(abs(self.d_max), abs(self.d_min)), math.pi, spread)
        margin = np.minimum(np.ceil(spread / self.sector_width), self.sectors).astype(np.int64)
        return np.ceil(np.log2(margin + 1)).astype(np.int64)

    def bound(self, points: _Points, k: np.ndarray, level: np.ndarray | None = None):
        """Lower bound of H at revolution ``k`` per point (inf off the path)."""
        g = np.clip(k, 0, self.turns - 1) * self.sectors + points.sector
        off = (k < 0) | (k >= self.turns)
        if level is None or not level.any():
            z_low, a_low, a_high = self.levels[0]
            low = z_low[g] + self.profile(_gap(points.low, points.high, a_low[g], a_high[g]))
            return np.where(off, np.inf, low)
        out = np.empty(g.size)
        for value in np.unique(level):
            z_low, a_low, a_high = self._level(int(value))
            sel = level == value
            gg = g[sel]
            out[sel] = z_low[gg] + self.profile(_gap(points.low[sel], points.high[sel],
                                                     a_low[gg], a_high[gg]))
        return np.where(off, np.inf, out)

    def block_bound(self, points: _Points, b: int, level: np.ndarray):
        out = np.empty(points.rho.size)
        for value in np.unique(level):
            z_low, a_low, a_high = self._block_level(int(value))
            sel = slice(None) if value == level[0] and (level == value).all() else level == value
            j = points.sector[sel]
            out[sel] = z_low[b, j] + self.profile(_gap(points.low[sel], points.high[sel],
                                                       a_low[b, j], a_high[b, j]))
        return out

    # --- the walk ----------------------------------------------------------------------
    def _walk_constants(self) -> None:
        """Per sector: the largest drop of the tip-height bound from one revolution to the
        next inwards (``drop_in``) and outwards (``drop_out``), and the least spacing of the
        ``along`` ranges of consecutive revolutions (``spacing``; <= 0: no certificate)."""
        z_low, a_low, a_high = (v.reshape(self.turns, self.sectors) for v in self.levels[0])
        with np.errstate(invalid="ignore"):
            step = z_low[1:] - z_low[:-1]           # k -> k + 1
            finite = np.isfinite(step)
            self.drop_next = np.where(finite, np.maximum(-step, 0.0), 0.0).max(axis=0)
            self.drop_previous = np.where(finite, np.maximum(step, 0.0), 0.0).max(axis=0)
            if self.inward:
                gaps = a_low[:-1] - a_high[1:]
            else:
                gaps = a_low[1:] - a_high[:-1]
            gaps = np.where(np.isfinite(gaps), gaps, np.inf)
        self.spacing = gaps.min(axis=0)

    def _start(self, points: _Points) -> np.ndarray:
        """Per point, the first revolution whose ``along`` range lies wholly past the point
        in the path's direction (binary search in the sector's column of the table)."""
        _, a_low, a_high = self.levels[0]
        lo, hi = points.first.copy(), np.maximum(points.last + 1, points.first)
        sector, edge = points.sector, points.low if self.inward else points.high
        active = np.flatnonzero(lo < hi)
        while active.size:
            mid = (lo[active] + hi[active]) // 2
            g = mid * self.sectors + sector[active]
            past = a_high[g] < edge[active] if self.inward else a_low[g] > edge[active]
            hi[active[past]] = mid[past]
            lo[active[~past]] = mid[~past] + 1
            active = active[lo[active] < hi[active]]
        return lo

    def _walk(self, points: _Points, start: np.ndarray, direction: int) -> np.ndarray:
        """Walk from revolution ``start`` in ``direction`` (+1: increasing k); returns the
        indices of the points whose walk did not end (certificate) within WALK_STEPS."""
        _, a_low, a_high = self.levels[0]
        along_next = direction * (1 if self.inward else -1) > 0  # walking towards lower along
        drop = self.drop_next if direction > 0 else self.drop_previous
        active = np.arange(points.rho.size)
        k = start.copy()
        for _ in range(WALK_STEPS):
            if not active.size:
                break
            part = points.take(active)
            kk = k[active]
            low = self.bound(part, kk)
            need = low < part.best
            if need.any():
                height = self.evaluate(part.take(np.flatnonzero(need)), kk[need])
                points.best[active[need]] = np.minimum(points.best[active[need]], height)
            g = np.clip(kk, 0, self.turns - 1) * self.sectors + part.sector
            gap = part.low - a_high[g] if along_next else a_low[g] - part.high
            with np.errstate(invalid="ignore"):  # 0 x inf: no certificate (NaN >= x)
                certified = ((gap >= 0.0)
                             & (self.profile.slope(gap) * self.spacing[part.sector]
                                >= drop[part.sector])
                             & (low >= points.best[active]))
            beyond = (kk >= part.last) if direction > 0 else (kk <= part.first)
            done = certified | beyond
            k[active] += direction
            active = active[~done]
        return active

    def _blocks(self, points: _Points) -> None:
        """Evaluate every revolution whose block and own bounds are below the best."""
        level = self.level_of(points.rho)
        pairs_p, pairs_k = [], []
        for b in range(self.blocks):
            hit = np.flatnonzero(self.block_bound(points, b, level) < points.best)
            if hit.size:
                pairs_p.append(np.repeat(hit, self.block))
                pairs_k.append(b * self.block + np.tile(np.arange(self.block), hit.size))
        if not pairs_p:
            return
        p, k = np.concatenate(pairs_p), np.concatenate(pairs_k)
        keep = (k >= points.first[p]) & (k <= points.last[p])
        p, k = p[keep], k[keep]
        part = points.take(p)
        keep = self.bound(part, k, level[p]) < points.best[p]
        p, k = p[keep], k[keep]
        if p.size:
            np.minimum.at(points.best, p, self.evaluate(points.take(p), k))

    # --- all of it -----------------------------------------------------------------------
    def heights(self, px: np.ndarray, py: np.ndarray) -> np.ndarray:
        px, py = px - self.centre[0], py - self.centre[1]
        rho, theta = np.hypot(px, py), np.arctan2(py, px)
        best = np.full(rho.size, np.inf)
        points = _Points(self, rho, theta, 1.0, best)
        start = self._start(points)
        for k in (start - 1, start):
            inside = (k >= points.first) & (k <= points.last)
            if inside.any():
                index = np.flatnonzero(inside)
                best[index] = np.minimum(best[index],
                                         self.evaluate(points.take(index), k[index]))
        if self.d_varies:
            self._blocks(points)
        else:
            left = self._walk(points, start - 2, -1)
            right = self._walk(points, start + 1, +1)
            rest = np.union1d(left, right)
            if rest.size:
                part = points.take(rest)
                self._blocks(part)
                best[rest] = part.best
        # the branch across the axis, where any revolution's bound can beat the best
        across = _Points(self, rho, theta, -1.0, best)
        z_low, a_low, a_high = self.levels[0]
        finite = np.isfinite(z_low)
        floor = z_low[finite].min() + self.profile(_gap(across.low, across.high,
                                                        a_low[finite].min(),
                                                        a_high[finite].max()))
        if self.d_varies:
            floor = np.full(rho.size, -np.inf)
        index = np.flatnonzero(floor < best)
        if index.size:
            part = across.take(index)
            self._blocks(part)
            best[index] = part.best
        return best


def _spindle_axis(alpha, along, offset):
    """The path about its own spindle axis: centre e (m, workpiece frame) and the path's
    ``along`` and ``offset`` about it.

    A spindle axis off the workpiece origin by e adds u . e to ``along`` and u x e =
    e_y cos(alpha) - e_x sin(alpha) to ``offset``; e is the least-squares fit of the offset
    over (1, cos, sin). Any e is a mere change of coordinates (the engine then works on
    points minus e); the fit makes the offset constant where the tool's centre height
    does not change, so that the crossings have their closed form. Offsets that then vary
    by at most `OFFSET_CONSTANT_M` are taken as their median, and as zero when that is
    within `OFFSET_CONSTANT_M` of it.
    """
    centre = (0.0, 0.0)
    if np.ptp(offset) > 0.0:
        cos, sin = np.cos(alpha), np.sin(alpha)
        basis = np.column_stack([np.ones_like(alpha), cos, sin])
        coefficients = np.linalg.solve(basis.T @ basis, basis.T @ offset)
        e_x, e_y = -coefficients[2], coefficients[1]
        along = along - (cos * e_x + sin * e_y)
        offset = offset - (cos * e_y - sin * e_x)
        centre = (float(e_x), float(e_y))
    # the poses' round-off grows with the spindle angle and the radius: a facing cut of 500
    # turns from X 1 mm carries 2.2e-15 m (1e-15 m from 0.45 mm out), which read as a
    # varying centre height left the top standing on the axis
    tolerance = max(OFFSET_CONSTANT_M, _ANGLE_ROUNDOFF * float(np.max(np.abs(alpha), initial=0.0))
                    * float(np.max(np.abs(along), initial=0.0)))
    if np.ptp(offset) <= tolerance:
        level = float(np.median(offset))
        # within the tolerance of zero: on the centre height. The uncut core of radius |d|
        # it would leave is round-off (the poses' ~1e-17 m of a nominal tool), and a
        # point that near the axis (an interferometer's pixel on it) would read the top
        offset = np.full(offset.size, 0.0 if abs(level) <= tolerance else level)
    return centre, along, offset


def _range(values, start, stop, op, fill):
    """op over values[start[g]:stop[g]] (``fill`` where empty); start non-decreasing and
    stop[g] >= start[g + 1] (neighbouring ranges meet or overlap)."""
    n = values.size
    empty = stop <= start
    index = np.minimum(start, n - 1)
    out = op.reduceat(values, index)  # [start[g], start[g + 1]), or values[start[g]]
    following = np.append(index[1:], n)
    out[-1] = op.reduce(values[index[-1]:max(stop[-1], index[-1] + 1)])
    steps = int((stop - following).max()) if stop.size else 0
    for step in range(max(steps, 0)):
        at = np.minimum(following + step, n - 1)
        out = np.where(following + step < stop, op(out, values[at]), out)
    return np.where(empty, fill, out)


def _gap(c_low, c_high, low, high):
    """Distance between the intervals [c_low, c_high] and [low, high] (0 where they meet;
    inf for an empty [low, high], NaN for a NaN coordinate)."""
    with np.errstate(invalid="ignore"):
        gap = np.maximum(np.maximum(low - c_high, c_low - high), 0.0)
    gap = np.where(np.isnan(c_low), np.nan, gap)
    return np.where(low <= high, gap, np.inf)


def _widen(values: np.ndarray, shift: int, op) -> np.ndarray:
    """op of values at g - shift, g, g + shift (the window of level l from level l - 1)."""
    out = values.copy()
    if shift < values.size:
        out[shift:] = op(out[shift:], values[:-shift])
        out[:-shift] = op(out[:-shift], values[shift:])
    else:
        out[:] = op.reduce(values)
    return out


def _root(rho, d):
    """sqrt(rho^2 - d^2), NaN where the point lies nearer the axis than the edge plane."""
    with np.errstate(invalid="ignore"):
        return np.sqrt((rho - d) * (rho + d))


def _wrap(angle):
    """Angle in [-pi, pi)."""
    return np.mod(angle + math.pi, TWO_PI) - math.pi
