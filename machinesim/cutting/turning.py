"""Turning engine: the surface a round-nose tool leaves along a spiral, as an exact height field.

Slow-tool-servo (STS) and face turning (paper 004): the work spindle turns, the tool's nose
arc sweeps the end face. The nose is an arc of radius R in a vertical plane (the *edge
plane*, normal to the cutting velocity), its lowest point the tool tip; the machined surface
is the lower envelope of that arc over the whole motion. It is returned as heights over a
measuring grid, float64 throughout, with no polygon of the nose and no chord of the path
between the given points (the path is interpolated linearly in the spindle angle, as the
controller interpolates linear moves in axis space).

The path (`EdgePath`) is what the edge plane does in the workpiece frame, point by point:

* ``angle`` alpha: direction of the edge plane's horizontal axis u = (cos alpha, sin alpha)
  (on ``sts_lathe`` the tool's X axis, i.e. the C angle), monotonic (unwrapped);
* ``along`` a: the tip's coordinate along u (on ``sts_lathe`` the X slide);
* ``offset`` d: the edge plane's distance from the spindle axis (workpiece Z), along
  u_perp = (-sin alpha, cos alpha); the tool's centre-height error, paper 004's dy;
* ``z``: the tip height.

Build it from tip positions and angles (`edge_path_from_tips`), from tool poses wMt
(`edge_path_from_poses`, e.g. the servo-lagged, erroneous poses of
``Machine.tool_pose(trajectory.q, errors)``), or from its four arrays (`EdgePath`).

A grid point p = (rho cos theta, rho sin theta) lies in the edge plane when
p . u_perp = d, i.e. at alpha = theta - atan2(d, sigma sqrt(rho^2 - d^2)) (mod 2 pi), on
the branch sigma = +1 (p on the tip's side of the spindle axis) or -1 (the arc reaching
across the axis). At each such crossing, one per revolution k, the arc's height over p is

    H_k = z(alpha_k) + h(sigma sqrt(rho^2 - d^2) - a(alpha_k)),

h the nose profile (`nose_profile`: R - sqrt(R^2 - s^2), then the flanks, nothing beyond
the shank), and the machined height is min over k and sigma of H_k.

The minimum is found without visiting every revolution for every point; the result is the
exact minimum whatever the path (servo ripple, errors, gouging), the path's structure only
decides how much work it takes (docs/procedures/sts_turning.md):

* the path is cut into sectors of 1/S revolution; per revolution and sector, the least tip
  height and the range of ``along`` over the sector (path points inside it and the linear
  interpolant at its edges) bound H_k from below for every point whose crossing falls in it;
* a start: the revolution whose ``along`` range passes the point (binary search in the
  sector's column), and its neighbour, evaluated exactly;
* a walk outwards on both sides, one revolution a step, evaluating exactly where the bound
  is below the best height found, until a tail certificate holds: with L the largest drop
  of the bound's tip height from one revolution to the next and f_min the least spacing of
  the ``along`` ranges (per sector), the bounds of all further revolutions are at least the
  current one once h'(gap) f_min >= L (h is convex), and the current one is >= the best;
* where the walk does not end within `WALK_STEPS` steps (steep surfaces, paths whose
  revolutions overlap), and for the branch across the axis, the bounds over blocks of
  revolutions decide which revolutions to evaluate.

The engine works about the path's own spindle axis, fitted to the offsets (an off-centre
spindle, a workpiece setting error, leave an offset d that varies as e x u; about the fitted
axis it is constant again). Where d still varies, the crossing angle of a revolution depends
on d there: it is found by fixed-point iteration (which
contracts by |d'(alpha)| / rho) to round-off, the sectors of the bound are widened
by the largest change of asin(d / rho) over the path, and the block bounds do all the work.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.arrays import frozen
from machinesim.exceptions import InputError, check_length
from machinesim.tools import RoundNoseTool

__all__ = ["EdgePath", "NoseProfile", "edge_path_from_poses", "edge_path_from_tips",
           "nose_profile", "turned_surface"]

TWO_PI = 2.0 * math.pi
#: Grid points per chunk: bounds the memory of the candidate pairs (a few arrays of
#: chunk x candidates float64), ~100 MB at the paper's densities.
CHUNK_POINTS = 1 << 16
#: Revolutions the walk takes on each side before the block bounds take over. The walk ends
#: after about R * slope / f revolutions (the contact's distance from the nearest
#: revolution): 2 on the paper's sine grid (R 1 mm, slope 3e-3, f 2 um).
WALK_STEPS = 24
#: Most fixed-point steps for the crossing angle when the offset d varies along the path;
#: each divides the error by rho / |d'| (>= 10 beyond ten times the offset's amplitude).
_CROSSING_STEPS = 64
#: An offset (centre height) that varies by at most this along the path (m), about the
#: path's fitted spindle axis, is taken as constant: the crossings then move by at most
#: 1e-15 m / rho rad and the heights by less than 1e-15 m times the surface slope.
OFFSET_CONSTANT_M = 1e-15
#: Most path points in one bin of the angle lookup before it falls back to binary search.
_BIN_STEPS = 8
#: Largest table of sectors (revolutions x sectors per revolution) of the lower bound.
_MAX_SECTORS = 1 << 21
#: Relative round-off margin of angles (x the largest |angle| of the path): a crossing
#: computed as phase + 2 pi k lies in its sector up to a few ulp; 1e-13 is ~500 ulp.
_ANGLE_ROUNDOFF = 1e-13


@dataclass(frozen=True)
class NoseProfile:
    """Lower envelope of a round-nose tool's edge in its plane, heights above the tip (m).

    The arc R - sqrt(R^2 - s^2) for |s| <= ``arc_half_width``, then straight flanks rising
    at ``flank_slope`` up to ``reach`` (the half width at the flank height); beyond, the
    shank's vertical sides, so the tool leaves nothing there (height +inf).
    """

    radius: float
    arc_half_width: float
    arc_top: float
    flank_slope: float
    reach: float

    def __call__(self, s) -> np.ndarray:
        """Height of the edge above the tip at ``s`` (m) from it in the edge plane; +inf
        beyond ``reach``."""
        s = np.abs(np.asarray(s, dtype=np.float64))
        radius = self.radius
        inside = np.minimum(s, self.arc_half_width)
        # s^2 / (R + sqrt(R^2 - s^2)): R - sqrt(R^2 - s^2) without the cancellation.
        arc = inside * inside / (radius + np.sqrt((radius - inside) * (radius + inside)))
        flank = self.arc_top + (np.minimum(s, self.reach) - self.arc_half_width) * self.flank_slope
        height = np.where(s <= self.arc_half_width, arc, flank)
        return np.where(s <= self.reach, height, np.inf)

    def slope(self, s) -> np.ndarray:
        """dh/d|s| at ``s`` (m): s / sqrt(R^2 - s^2) on the arc, the flank slope beyond,
        +inf beyond ``reach``. Non-decreasing in |s| (h is convex)."""
        s = np.abs(np.asarray(s, dtype=np.float64))
        radius = self.radius
        inside = np.minimum(s, self.arc_half_width)
        with np.errstate(divide="ignore"):
            arc = inside / np.sqrt((radius - inside) * (radius + inside))
        height = np.where(s <= self.arc_half_width, arc, self.flank_slope)
        return np.where(s <= self.reach, height, np.inf)


def nose_profile(tool) -> NoseProfile:
    """The edge profile of ``tool``: a `RoundNoseTool`, or a nose radius (m) for a bare
    half-circle nose (reach R, no flanks).

    For a `RoundNoseTool` the arc spans +-included_angle/2 and the flanks continue tangent
    to it up to ``flank_height``, as `RoundNoseTool.vertices` draws them, but exactly (no
    chords).
    """
    if isinstance(tool, RoundNoseTool):
        radius = tool.nose_radius
        end = tool.included_angle / 2.0
        top_end = math.acos(max(-1.0, 1.0 - tool.flank_height / radius))
        if top_end <= end:  # the arc already reaches the flank height
            width = radius * math.sin(top_end)
            return NoseProfile(radius, width, radius * (1.0 - math.cos(top_end)), 0.0, width)
        arc_width = radius * math.sin(end)
        arc_top = radius * (1.0 - math.cos(end))
        slope = math.tan(end)
        reach = arc_width + (tool.flank_height - arc_top) / slope
        return NoseProfile(radius, arc_width, arc_top, slope, reach)
    radius = check_length(tool, "nose_radius", positive=True)
    return NoseProfile(radius, radius, radius, 0.0, radius)


@dataclass(frozen=True)
class EdgePath:
    """The edge plane along the path, point by point, in the workpiece frame (see module).

    Attributes
    ----------
    angle : ndarray, shape (N,)
        Direction of the edge plane's horizontal axis, rad, monotonic (unwrapped).
    along : ndarray, shape (N,)
        Tip coordinate along that axis, m.
    offset : ndarray, shape (N,)
        Distance of the edge plane from the spindle axis, m (positive towards u_perp).
    z : ndarray, shape (N,)
        Tip height, m.

    Consecutive points are joined linearly in all four, about the path's spindle axis (the
    engine fits it to the offsets, see `turned_surface`). The arrays are read-only float64;
    a path given with decreasing angle is stored reversed (the envelope does not depend on
    the order), and one whose tip lies mostly on the negative side of u is stored with u
    turned by pi (angle + pi, along and offset negated: the same edge planes).
    """

    angle: np.ndarray
    along: np.ndarray
    offset: np.ndarray
    z: np.ndarray

    def __post_init__(self) -> None:
        angle = _vector(self.angle, "angle")
        n = angle.size
        if n < 2:
            raise InputError(f"Expected an edge path of at least 2 points, got {n}", key="angle")
        arrays = [angle]
        for name in ("along", "offset", "z"):
            value = getattr(self, name)
            arrays.append(_vector(np.full(n, value, dtype=np.float64) if np.ndim(value) == 0
                                  else value, name, n))
        steps = np.diff(angle)
        turning = steps[steps != 0.0]
        if turning.size == 0:
            raise InputError("Expected the spindle angle to turn along the path, it stays at "
                             f"{angle[0]!r} rad", key="angle")
        back = np.flatnonzero(steps * turning[0] < 0.0)
        if back.size:
            i = int(back[0])
            raise InputError(f"Expected a monotonic spindle angle along the path, it turns back "
                             f"between points {i} and {i + 1} ({angle[i]!r} -> "
                             f"{angle[i + 1]!r} rad)", key="angle")
        if turning[0] < 0.0:
            arrays = [array[::-1] for array in arrays]
        if np.median(arrays[1]) < 0.0:  # the same planes, u turned by pi: the tip on +u
            arrays = [arrays[0] + math.pi, -arrays[1], -arrays[2], arrays[3]]
        for name, array in zip(("angle", "along", "offset", "z"), arrays, strict=True):
            object.__setattr__(self, name, frozen(array))

    def __len__(self) -> int:
        return self.angle.size


def _vector(values, name: str, n: int | None = None) -> np.ndarray:
    try:
        array = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected {name} as an array of numbers, got {values!r:.80}",
                         key=name) from error
    if array.ndim != 1 or (n is not None and array.size != n):
        want = "(N,)" if n is None else f"({n},)"
        raise InputError(f"Expected {name} of shape {want}, got {array.shape}", key=name)
    if not np.isfinite(array).all():
        i = int(np.flatnonzero(~np.isfinite(array))[0])
        raise InputError(f"Expected finite {name}, got {array[i]!r} at index {i}", key=name)
    return array


def edge_path_from_tips(tips, angles) -> EdgePath:
    """The edge path of tool tips at given edge-plane directions.

    Parameters
    ----------
    tips : array-like, shape (N, 3)
        Tool tip positions in the workpiece frame, m.
    angles : array-like, shape (N,)
        Direction of the edge plane's horizontal axis, rad, monotonic; on ``sts_lathe``
        (tip = (X cos C, X sin C, Z)) the C values. Needed because the tip alone does not
        say on which side of the spindle axis the edge plane points, nor where it is at the
        centre.
    """
    tips = np.array(tips, dtype=np.float64)
    if tips.ndim != 2 or tips.shape[1] != 3:
        raise InputError(f"Expected tips of shape (N, 3), got {tips.shape}", key="tips")
    angles = _vector(angles, "angles", tips.shape[0])
    cos, sin = np.cos(angles), np.sin(angles)
    return EdgePath(angles, cos * tips[:, 0] + sin * tips[:, 1],
                    cos * tips[:, 1] - sin * tips[:, 0], tips[:, 2])


def edge_path_from_poses(wMt, nose_radius: float, *, edge_axis: int = 0) -> EdgePath:
    """The edge path of tool poses (tool_tip frames in the workpiece frame).

    The nose arc is taken about its centre, tip + R z_tool, with its lowest point R below
    it; so a tilt of the tool within the edge plane moves nothing but the arc's ends. The
    edge plane is vertical, through that centre, along the tool axis ``edge_axis`` projected
    on the workpiece XY plane: on ``sts_lathe`` the tool's X (0), which is the radial
    direction (the tool cuts along its Y there, the tangential direction of the spindle).
    A tilt of the tool out of the edge plane is not modelled (second order in the tilt).

    Parameters
    ----------
    wMt : array-like, shape (N, 4, 4)
        Poses of the ``tool_tip`` frame in the workpiece frame, m.
    nose_radius : float
        The tool's nose radius R, m.
    edge_axis : {0, 1}
        Column of the tool rotation that spans the edge plane with the tool Z.
    """
    poses = np.asarray(wMt, dtype=np.float64)
    if poses.ndim != 3 or poses.shape[1:] != (4, 4):
        raise InputError(f"Expected wMt of shape (N, 4, 4), got {poses.shape}", key="wMt")
    if edge_axis not in (0, 1):
        raise InputError(f"Expected edge_axis 0 or 1, got {edge_axis!r}", key="edge_axis")
    radius = check_length(nose_radius, "nose_radius", positive=True)
    centre = poses[:, :3, 3] + radius * poses[:, :3, 2]
    u = poses[:, :2, edge_axis]
    norm = np.hypot(u[:, 0], u[:, 1])
    if (norm < 0.5).any():
        i = int(np.flatnonzero(norm < 0.5)[0])
        raise InputError(f"Expected the tool's axis {edge_axis} near the workpiece XY plane, "
                         f"pose {i} has it {math.degrees(math.acos(norm[i])):.1f} deg out of it",
                         key="wMt")
    angles = np.unwrap(np.arctan2(u[:, 1], u[:, 0]))
    tips = np.column_stack([centre[:, :2], centre[:, 2] - radius])
    return edge_path_from_tips(tips, angles)


def turned_surface(path: EdgePath, tool, x, y, *, top: float | None = None,
                   sectors: int | None = None) -> np.ndarray:
    """Heights the tool leaves along ``path`` over the grid ``x`` x ``y``.

    Parameters
    ----------
    path : EdgePath
    tool : RoundNoseTool or float
        The tool as it is (with its nose radius error, if any), or a nose radius (m).
    x : array-like, shape (nx,)
    y : array-like, shape (ny,)
        Grid axes in the workpiece frame, m (finite, any order).
    top : float, optional
        Stock top (m): heights above it, and points the edge never reaches, read ``top``.
        Without it they read NaN.
    sectors : int, optional
        Sectors per revolution of the lower bound (default: four per path point of a
        revolution, within 8 .. 4096). Changes the speed, never the result.

    Returns
    -------
    ndarray, shape (ny, nx), float64, read-only
        ``z[j, i]`` the machined height over ``(x[i], y[j])``, m.
    """
    if not isinstance(path, EdgePath):
        raise InputError(f"Expected an EdgePath, got {type(path).__name__}", key="path")
    profile = nose_profile(tool)
    gx, gy = _vector(x, "x"), _vector(y, "y")
    if top is not None:
        top = float(top)
        if not math.isfinite(top):
            raise InputError(f"Expected a finite top (m), got {top!r}", key="top")
    if sectors is not None and (isinstance(sectors, bool)
                                or not isinstance(sectors, int | np.integer) or sectors < 1):
        raise InputError(f"Expected sectors as an int >= 1, got {sectors!r}", key="sectors")
    engine = _Engine(path, profile, sectors)
    px, py = np.meshgrid(gx, gy)
    px, py = px.ravel(), py.ravel()
    heights = np.empty(px.size)
    for start in range(0, px.size, CHUNK_POINTS):
        stop = min(start + CHUNK_POINTS, px.size)
        heights[start:stop] = engine.heights(px[start:stop], py[start:stop])
    if top is None:
        heights[np.isinf(heights)] = np.nan
    else:
        np.minimum(heights, top, out=heights)
    return frozen(heights.reshape(gy.size, gx.size), copy=False)


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
    by at most `OFFSET_CONSTANT_M` are taken as their median.
    """
    if np.ptp(offset) == 0.0:
        return (0.0, 0.0), along, offset
    cos, sin = np.cos(alpha), np.sin(alpha)
    basis = np.column_stack([np.ones_like(alpha), cos, sin])
    coefficients = np.linalg.solve(basis.T @ basis, basis.T @ offset)
    e_x, e_y = -coefficients[2], coefficients[1]
    along = along - (cos * e_x + sin * e_y)
    offset = offset - (cos * e_y - sin * e_x)
    if np.ptp(offset) <= OFFSET_CONSTANT_M:
        offset = np.full(offset.size, np.median(offset))
    return (float(e_x), float(e_y)), along, offset


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
