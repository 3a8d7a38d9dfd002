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
from machinesim.cutting.turning_search import _Engine
from machinesim.exceptions import InputError, check_length
from machinesim.tools import RoundNoseTool

__all__ = ["EdgePath", "NoseProfile", "edge_path_from_poses", "edge_path_from_tips",
           "nose_profile", "turned_heights", "turned_surface"]

#: Grid points per chunk: bounds the memory of the candidate pairs (a few arrays of
#: chunk x candidates float64), ~100 MB at the paper's densities.
CHUNK_POINTS = 1 << 16


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
    gx, gy = _vector(x, "x"), _vector(y, "y")
    px, py = np.meshgrid(gx, gy)
    heights = turned_heights(path, tool, px.ravel(), py.ravel(), top=top, sectors=sectors)
    return frozen(heights.reshape(gy.size, gx.size), copy=False)


def turned_heights(path: EdgePath, tool, px, py, *, top: float | None = None,
                   sectors: int | None = None) -> np.ndarray:
    """Heights the tool leaves along ``path`` at the points ``(px[i], py[i])``.

    As `turned_surface` (same parameters and result), at scattered points instead of over a
    grid: ``px`` and ``py`` are 1-D arrays of one length, m.

    Returns
    -------
    ndarray, shape (n,), float64, read-only
    """
    if not isinstance(path, EdgePath):
        raise InputError(f"Expected an EdgePath, got {type(path).__name__}", key="path")
    profile = nose_profile(tool)
    px, py = _vector(px, "px"), _vector(py, "py", np.size(px))
    if top is not None:
        top = float(top)
        if not math.isfinite(top):
            raise InputError(f"Expected a finite top (m), got {top!r}", key="top")
    if sectors is not None and (isinstance(sectors, bool)
                                or not isinstance(sectors, int | np.integer) or sectors < 1):
        raise InputError(f"Expected sectors as an int >= 1, got {sectors!r}", key="sectors")
    engine = _Engine(path, profile, sectors)
    heights = np.empty(px.size)
    for start in range(0, px.size, CHUNK_POINTS):
        stop = min(start + CHUNK_POINTS, px.size)
        heights[start:stop] = engine.heights(px[start:stop], py[start:stop])
    if top is None:
        heights[np.isinf(heights)] = np.nan
    else:
        np.minimum(heights, top, out=heights)
    return frozen(heights, copy=False)
