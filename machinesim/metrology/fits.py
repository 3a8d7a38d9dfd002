"""Feature fits on measured points: sphere, plane and inclination, form error, roughness Sa.

Inputs are plain float64 arrays in SI: point clouds (N, 3), profiles (s, z) and height maps
(x (nx,), y (ny,), z (ny, nx)) as `machinesim.metrology.height_map` and `profile` return them,
with NaN where no surface was seen (such samples are left out). Results are frozen dataclasses
in m and rad.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._arrays import (
    as_flag,
    as_floats,
    as_number,
    frozen,
    map_arrays,
    point_rows,
    regular_step,
    shown,
)
from machinesim.units import M_PER_UM

__all__ = [
    "FormError",
    "PlaneFit",
    "SphereFit",
    "fit_plane",
    "fit_sphere",
    "form_error",
    "height_map_points",
    "plane_angle",
    "roughness_sa",
    "sphere_centre_from_touch",
]

#: Gauss-Newton iterations stop when a step moves the centre (or radius) by less than this
#: fraction of the point cloud's size: ~20 ulps, where float64 stops improving a fit.
STEP_TOL = 4e-15
#: Points whose second singular value is below this fraction of the first lie on one line
#: (`fit_plane`'s test), and a plane whose normal's z is below it is vertical.
COLLINEAR = 1e-12
#: A held radius smaller than the points' circle by more than this many RMS scatters of the
#: points about the circle is refused; within it (noise on a ring round the equator) the
#: centre is put in the circle's plane.
CIRCLE_SCATTERS = 3.0
#: With the radius held, points off one plane keep their own (algebraic) centre over the
#: one on the side the caller names only when it fits them with less than this fraction of
#: that one's RMS residual: on a cap the other side misses by millimetres, on a ring with
#: noisy heights both sides fit alike and the caller's side stands.
OTHER_SIDE_RMS = 0.5
#: A sphere fit's step has also settled when no parameter moves by more than this many times
#: its round-off: float64's eps times the largest distance, through the Jacobian's
#: pseudo-inverse. On a shallow cap the centre's height and the radius move together, so
#: round-off steps grow with the distances over the cap's spread: measured 0.1-1.3 of it on
#: caps of 0.005-0.5 rad, where `STEP_TOL` times the spread (1e-19 m on a 0.05 rad cap of a
#: 0.5 mm sphere, whose steps stay at ~1e-17 m) refused caps below about 0.1 rad.
ROUNDOFF_STEPS = 10.0
#: Gauss-Newton gives up after this many iterations (it takes ~3-6 on a sphere cap).
MAX_ITERATIONS = 100
#: A held-radius sphere fit that does not settle on points within this fraction of the
#: radius of one plane, on a circle whose plane lies within this fraction of the radius of
#: the centre, is said to be a ring near the equator (`fit_sphere`): moving the centre
#: along the ring's axis by h changes the distances by about h^2 / 2R only.
GREAT_CIRCLE = 0.1
#: `form_error`'s shift has settled when a step no longer shrinks and is within this many of
#: the shift's standard uncertainties (from the residual): round-off then drives the steps.
#: The shift's columns nearly match the tilt's (a shifted quadratic is a tilted one), so
#: on exact data (sphere R 5 mm over 1 mm: residual 4e-19 m, from R - sqrt(R^2 - r^2)'s
#: cancellation) the steps stay at 0.3-7 of those uncertainties, ~1e-16 m, far above
#: STEP_TOL times the map's size (4e-18 m), which they never reach.
SHIFT_SETTLED_STDS = 10.0
#: Singular values of the shift fit's design (unit columns) below this fraction of the
#: largest count as zero: the central-difference gradient is good to ~2e-10 (GRADIENT_STEP),
#: so a shift column that differs from the tilt's by less (a quadratic's: 1e-11) is a tilt.
#: A sphere of 5 mm radius over 1 mm leaves 1e-3.
SHIFT_RCOND = 1e-8
#: Central-difference step of the nominal surface's gradient, as a fraction of the map's size:
#: truncation ~1e-12 and round-off ~eps / 1e-6 = 2e-10 relative. The gradient only steers
#: Gauss-Newton: where the residual vanishes the fixed point is exact whatever its error.
GRADIENT_STEP = 1e-6
#: Shortest L-filter cut-off of `roughness_sa`, in sample spacings: the Nyquist wavelength,
#: the shortest a sampled grid holds; a Gaussian high-pass below it passes nothing.
MIN_CUTOFF_SPACINGS = 2.0


@dataclass(frozen=True, eq=False)
class SphereFit:
    """A least-squares sphere (m).

    Attributes
    ----------
    centre : ndarray, shape (3,), read-only
        Centre of the sphere.
    radius : float
        Its radius (the one given when the fit held the radius fixed).
    residual_rms, residual_max : float
        RMS and largest absolute distance of the points from the sphere surface.
    """

    centre: np.ndarray
    radius: float
    residual_rms: float
    residual_max: float


@dataclass(frozen=True, eq=False)
class PlaneFit:
    """A total-least-squares plane (m).

    Attributes
    ----------
    point : ndarray, shape (3,), read-only
        Centroid of the points, on the plane.
    normal : ndarray, shape (3,), read-only
        Unit normal, with normal[2] >= 0 (pointing up out of a measured face).
    residual_rms : float
        RMS distance of the points from the plane.
    flatness : float
        Largest minus smallest signed distance of the points from the plane (P-V).
    """

    point: np.ndarray
    normal: np.ndarray
    residual_rms: float
    flatness: float

    @property
    def inclination(self) -> float:
        """Angle of the plane to the XY plane (rad), in [0, pi/2]."""
        return math.atan2(math.hypot(self.normal[0], self.normal[1]), abs(self.normal[2]))


@dataclass(frozen=True, eq=False)
class FormError:
    """Deviation of a height map from a nominal surface after best-fit alignment (m, rad).

    Attributes
    ----------
    pv, rms : float
        Peak-to-valley and RMS of the residual (its mean is zero: the piston is fitted).
    piston : float
        Fitted height offset at the centre of the map's xy box.
    tilt : ndarray, shape (2,), read-only
        Fitted slopes dz/dx and dz/dy.
    shift : ndarray, shape (2,), read-only
        Fitted (x, y) shift of the measured surface against the nominal; zeros unless fitted.
    residual : ndarray, shape (ny, nx), read-only
        Measured minus aligned nominal; NaN where the map is NaN.
    """

    pv: float
    rms: float
    piston: float
    tilt: np.ndarray
    shift: np.ndarray
    residual: np.ndarray


def fit_sphere(points, radius: float | None = None, *, concave: bool = True) -> SphereFit:
    """Least-squares sphere through points (seed 002, Fig. 4b: two orthogonal scans).

    The algebraic fit (linear in the centre and radius^2 - |centre|^2) starts Gauss-Newton
    on the geometric distances |p - c| - R. On a cap (a probe or a microscope sees one side of
    a sphere) the centre's height and the radius are strongly correlated, so a small form
    error moves both while the xy centre stays put: seed 002 therefore takes xy from this fit
    and z from a bottom touch, see `sphere_centre_from_touch`.

    With ``radius`` held, Gauss-Newton starts from the circle through the points (fitted in
    their least-squares plane, radius rho) with the centre on its axis, sqrt(R^2 - rho^2)
    from its plane on the side ``concave`` names. Three points, or a ring of touches at one
    height, fix the centre only up to that mirror side. Points off one plane also start from
    the algebraic fit, whose centre is kept when it fits them clearly better (RMS below
    `OTHER_SIDE_RMS` of the other's: a cap read from its other side); a ring whose heights
    scatter fits both sides alike and keeps the side named.

    Parameters
    ----------
    points : array-like, shape (N, 3)
        Points on the sphere, m; rows with NaN are left out. N >= 4, not all on one plane
        (with ``radius``: N >= 3, not all on one line).
    radius : float, optional
        Hold the radius at this value (m) and fit the centre only.
    concave : bool
        With ``radius``: True (default) for points on a cavity, the centre above them (on
        the +z side of their plane, as in `sphere_centre_from_touch`); False for a bump, the
        centre below. Unused without ``radius``.

    Returns
    -------
    SphereFit

    Raises
    ------
    InputError
        Too few points, points on one plane (one line with ``radius``), a held radius
        smaller than the points' circle, or a vertical plane of points with ``radius`` (no
        side above or below it).
    """
    points = point_rows(points, 3, "points")
    minimum = 4 if radius is None else 3
    if len(points) < minimum:
        raise InputError(f"Expected at least {minimum} points on the sphere, got {len(points)}")
    concave = as_flag(concave, "concave")
    origin = points.mean(axis=0)
    local = points - origin
    size = float(np.abs(local).max())
    design = np.column_stack([2.0 * local, np.ones(len(local))])
    solution, _, rank, _ = np.linalg.lstsq(design, np.einsum("ij,ij->i", local, local),
                                           rcond=None)
    if radius is None:
        if rank < 4:
            raise InputError("Expected points spread over a sphere, got points on one plane or "
                             "line (give the radius to fit a circle of points)")
        centre, fitted = _settle(local, solution[:3],
                                 math.sqrt(max(solution[3] + solution[:3] @ solution[:3], 0.0)),
                                 False, size)
    else:
        fitted = radius = as_number(radius, "radius", sign="> 0")
        if rank < 4:
            centre = _settle(local, _centre_on_axis(local, radius, concave), radius, True,
                             size)[0]
        else:
            centre = _either_side(local, solution[:3], radius, concave, size)
    residual = np.linalg.norm(local - centre, axis=1) - fitted
    return SphereFit(frozen(origin + centre), float(fitted),
                     float(np.sqrt(np.mean(residual**2))), float(np.abs(residual).max()))


def _settle(local, centre, fitted, held: bool, size: float):
    """Gauss-Newton on the distances |p - c| - R from a start: (centre, radius)."""
    for _ in range(MAX_ITERATIONS):
        offset = local - centre
        distance = np.linalg.norm(offset, axis=1)
        jacobian = -offset / distance[:, None]
        if not held:
            jacobian = np.column_stack([jacobian, -np.ones(len(local))])
        step = np.linalg.lstsq(jacobian, fitted - distance, rcond=None)[0]
        centre = centre + step[:3]
        if not held:
            fitted += step[3]
        if np.abs(step).max() <= STEP_TOL * size or np.all(
                np.abs(step) <= ROUNDOFF_STEPS * _roundoff(jacobian, float(distance.max()))):
            return centre, fitted
    last = f"The sphere fit did not settle in {MAX_ITERATIONS} steps (last step " \
           f"{np.abs(step).max():.3g} m)"
    if held:
        near = _near_great_circle(local, fitted)
        if near is not None:
            raise InputError(f"{last}: {near}")
    raise InputError(f"{last}: are the points on a sphere?")


def _roundoff(jacobian: np.ndarray, scale: float) -> np.ndarray:
    """Each parameter's step from round-off of eps ``scale`` in every distance: eps scale
    times the norm of its row of the pseudo-inverse (zeros where the Jacobian is singular)."""
    _, singular, vt = np.linalg.svd(jacobian, full_matrices=False)
    if singular[-1] <= 0.0:
        return np.zeros(len(singular))
    return np.finfo(np.float64).eps * scale * np.sqrt(((vt.T / singular) ** 2).sum(axis=1))


def _either_side(local, algebraic, radius: float, concave: bool, size: float) -> np.ndarray:
    """Centre with the radius held, of points off one plane: from the algebraic start, unless
    the start on the circle's axis on the ``concave`` side fits about as well (RMS within
    `OTHER_SIDE_RMS`): noise on a ring's heights would otherwise choose the side."""

    def rms(centre):
        return float(np.sqrt(np.mean((np.linalg.norm(local - centre, axis=1) - radius) ** 2)))

    try:
        sided = _settle(local, _centre_on_axis(local, radius, concave), radius, True, size)[0]
    except InputError:  # no circle on that side (a vertical plane, a circle > R): the data's
        return _settle(local, algebraic, radius, True, size)[0]
    try:
        found = _settle(local, algebraic, radius, True, size)[0]
    except InputError:  # a start far off (noisy heights of a ring) that does not settle
        return sided
    return found if rms(found) < OTHER_SIDE_RMS * rms(sided) else sided


def _circle(local: np.ndarray):
    """The least-squares plane and circle of ``local``: (singular values, plane axes vt,
    circle centre (a, b) in the plane's first two axes, radius rho, radial scatter)."""
    _, singular, vt = np.linalg.svd(local, full_matrices=False)
    u, v = local @ vt[0], local @ vt[1]
    design = np.column_stack([2.0 * u, 2.0 * v, np.ones_like(u)])
    (a, b, c), *_ = np.linalg.lstsq(design, u * u + v * v, rcond=None)
    rho = math.sqrt(max(c + a * a + b * b, 0.0))
    return singular, vt, a, b, rho, np.hypot(u - a, v - b) - rho


def _near_great_circle(local: np.ndarray, radius: float) -> str | None:
    """Why a held-radius fit of ``local`` cannot settle when its points are a ring near the
    sphere's equator (`GREAT_CIRCLE`), or None."""
    singular, _, _, _, rho, _ = _circle(local)
    height = math.sqrt(max(radius * radius - rho * rho, 0.0))
    if (singular[2] / math.sqrt(len(local)) > GREAT_CIRCLE * radius
            or height > GREAT_CIRCLE * radius):
        return None
    return (f"with the radius held ({radius:.6g} m) the points are a ring of radius "
            f"{rho:.6g} m, {height:.3g} m from the plane of the sphere's great circle (near "
            "its equator), where moving the centre along the ring's axis by h changes the "
            "distances by about h^2 / 2R only, so their noise leaves it unsettled. Touch "
            "points off that circle (a cap, or a second ring), or fit without the radius")


def _centre_on_axis(local: np.ndarray, radius: float, concave: bool) -> np.ndarray:
    """Centre (m, about the points' mean) on the axis of the circle through ``local``, at
    sqrt(R^2 - rho^2) from the points' least-squares plane: above it if ``concave``."""
    singular, vt, a, b, rho, scatter = _circle(local)
    if singular[1] <= COLLINEAR * singular[0]:
        raise InputError("Expected points spanning a plane, got points on one line")
    normal = vt[2]
    if abs(normal[2]) <= COLLINEAR:
        raise InputError(f"Expected points whose plane has an up side for concave={concave}, "
                         f"got a vertical plane (normal {normal.round(12).tolist()})",
                         key="concave")
    normal = normal if (normal[2] > 0.0) == concave else -normal
    # a circle larger than the sphere by more than the points' scatter about it
    if rho > radius + CIRCLE_SCATTERS * float(np.sqrt(np.mean(scatter**2))):
        raise InputError(f"Expected the points' circle within the sphere, got its radius "
                         f"{rho!r} m > radius {radius!r} m", key="radius")
    return a * vt[0] + b * vt[1] + math.sqrt(max(radius * radius - rho * rho, 0.0)) * normal


def sphere_centre_from_touch(xy, z_touch: float, radius: float, *, probe_radius: float = 0.0,
                             concave: bool = True) -> np.ndarray:
    """Sphere centre from its least-squares xy and a vertical touch there (seed 002, Fig. 4c).

    Seed 002 feeds the probe along -Z at the fitted xy centre until it touches the sphere's
    bottom point; the centre lies the sphere radius R above it (R the mean radius of the
    three reference spheres). The probe ball of radius r touches that point with its lowest
    point, so the surface point is ``z_touch - r`` when ``z_touch`` is the ball centre.

    Parameters
    ----------
    xy : array-like, shape (2,)
        Fitted centre (x, y), m (``SphereFit.centre[:2]``).
    z_touch : float
        Z of the probe ball centre at contact, m (of the surface point when r = 0).
    radius : float
        Known sphere radius R, m.
    probe_radius : float
        Probe ball radius r, m (0.25 mm ruby in seed 002).
    concave : bool
        True for a cavity (ball-end-milled, as in seed 002: touched at its bottom, centre
        above); False for a bump (touched at its top, centre below).

    Returns
    -------
    ndarray, shape (3,), read-only
        The centre, m.
    """
    xy = as_floats(xy, "xy", "two numbers (m)").reshape(-1)
    if xy.shape != (2,) or not np.isfinite(xy).all():
        raise InputError(f"Expected xy as two finite numbers (m), got {xy!r}", key="xy")
    z_touch = as_number(z_touch, "z_touch")
    radius = as_number(radius, "radius", sign="> 0")
    probe_radius = as_number(probe_radius, "probe_radius", sign=">= 0")
    concave = as_flag(concave, "concave")
    surface = z_touch - probe_radius
    return frozen([xy[0], xy[1], surface + radius if concave else surface - radius])


def fit_plane(points) -> PlaneFit:
    """Total-least-squares plane through points (rows with NaN are left out).

    Parameters
    ----------
    points : array-like, shape (N, 3)
        Points, m, N >= 3, not all on one line (`height_map_points` makes them from a map).
    """
    points = point_rows(points, 3, "points")
    if len(points) < 3:
        raise InputError(f"Expected at least 3 points on the plane, got {len(points)}")
    centroid = points.mean(axis=0)
    _, singular, vt = np.linalg.svd(points - centroid, full_matrices=False)
    if singular[1] <= COLLINEAR * singular[0]:
        raise InputError("Expected points spanning a plane, got points on one line")
    normal = vt[2] if vt[2][2] >= 0.0 else -vt[2]
    distance = (points - centroid) @ normal
    return PlaneFit(frozen(centroid), frozen(normal), float(np.sqrt(np.mean(distance**2))),
                    float(np.ptp(distance)))


def plane_angle(first: PlaneFit, second: PlaneFit) -> float:
    """Angle between two planes (rad), in [0, pi/2]: e.g. a side face against the bottom face."""
    for name, plane in (("first", first), ("second", second)):
        if not isinstance(plane, PlaneFit):
            raise InputError(f"Expected {name} as a PlaneFit (from fit_plane), got "
                             f"{shown(plane)}", key=name)
    n1, n2 = first.normal, second.normal
    return math.atan2(float(np.linalg.norm(np.cross(n1, n2))), abs(float(n1 @ n2)))


def height_map_points(x, y, z) -> np.ndarray:
    """The measured points of a height map as (N, 3) rows (x, y, z), m; NaN samples left out."""
    x, y, z = map_arrays(x, y, z)
    grid_x, grid_y = np.meshgrid(x, y)
    seen = ~np.isnan(z)
    return np.column_stack([grid_x[seen], grid_y[seen], z[seen]])


def form_error(x, y, z, nominal, *, shift: bool = False) -> FormError:
    """P-V and RMS of a height map against a nominal surface after best-fit alignment.

    The alignment is least squares over piston and tilt (the measured surface may sit at any
    height and lean on its fixture): residual = z - nominal(x, y) - (p + tx (x - xm) + ty
    (y - ym)), (xm, ym) the centre of the map's box. With ``shift=True`` a rigid xy shift
    (sx, sy) of the measured surface is fitted as well, nominal(x - sx, y - sy) (Gauss-Newton
    with a central-difference gradient of ``nominal``). The shift is defined only when the
    nominal has terms above second order: a shifted plane or quadratic surface is the same
    surface tilted and raised, so its shift cannot be told apart (InputError). The shift has
    settled when a step moves it by less than `STEP_TOL` of the map's size or, once the steps
    have shrunk, when they stop shrinking within `SHIFT_SETTLED_STDS` of its standard
    uncertainties (from the residual): round-off then drives them, ~1e-16 m on an exact
    sphere cap, where the shift's columns nearly match the tilt's. Steps that do neither in
    `MAX_ITERATIONS` are an InputError.

    Parameters
    ----------
    x : array-like, shape (nx,)
    y : array-like, shape (ny,)
    z : array-like, shape (ny, nx)
        The height map, m, NaN where not seen.
    nominal : callable
        ``nominal(X, Y)`` -> Z, the design surface, vectorised over arrays of x and y (m).
    shift : bool
        Also fit a rigid xy shift.
    """
    x, y, z = map_arrays(x, y, z)
    if not callable(nominal):
        raise InputError(f"Expected nominal as a function nominal(X, Y) -> Z (m), got "
                         f"{shown(nominal)}", key="nominal")
    shift = as_flag(shift, "shift")
    grid_x, grid_y = np.meshgrid(x, y)
    seen = ~np.isnan(z)
    if np.count_nonzero(seen) < (5 if shift else 3) or x.size < 2 or y.size < 2:
        raise InputError(f"Expected a map of at least 2 x 2 samples, {5 if shift else 3} of "
                         f"them measured, got {z.shape} with {np.count_nonzero(seen)} measured")
    px, py, pz = grid_x[seen], grid_y[seen], z[seen]
    centre = np.array([0.5 * (x[0] + x[-1]), 0.5 * (y[0] + y[-1])])
    size = max(float(x[-1] - x[0]), float(y[-1] - y[0]))

    def nominal_at(dx, dy):
        values = np.asarray(nominal(px - dx, py - dy), dtype=np.float64)
        if values.shape != px.shape or not np.isfinite(values).all():
            raise InputError(f"Expected nominal(X, Y) to return finite heights of shape "
                             f"{px.shape}, got {values.shape}", key="nominal")
        return values

    plane = np.column_stack([np.ones_like(px), px - centre[0], py - centre[1]])
    moved = np.zeros(2)
    values = nominal_at(0.0, 0.0)
    params = np.linalg.lstsq(plane, pz - values, rcond=None)[0]
    if shift:
        h = GRADIENT_STEP * size
        last, shrank = math.inf, False
        for _ in range(MAX_ITERATIONS):
            gradient = [(nominal_at(moved[0] - h, moved[1]) - nominal_at(moved[0] + h, moved[1]))
                        / (2.0 * h),
                        (nominal_at(moved[0], moved[1] - h) - nominal_at(moved[0], moved[1] + h))
                        / (2.0 * h)]
            design = np.column_stack([plane, -gradient[0], -gradient[1]])
            # Unit columns, so that the rank test compares shapes, not units.
            norms = np.linalg.norm(design, axis=0)
            norms[norms == 0.0] = 1.0
            unit = design / norms
            misfit = pz - values - plane @ params
            step, _, rank, _ = np.linalg.lstsq(unit, misfit, rcond=SHIFT_RCOND)
            if rank < 5:
                raise InputError("The nominal surface does not fix an xy shift (a shifted "
                                 "plane or quadratic is a tilted one): fit without shift",
                                 key="shift")
            left = misfit - unit @ step
            sigma = (math.sqrt(float(left @ left) / max(len(left) - 5, 1))
                     * np.sqrt(np.diag(np.linalg.inv(unit.T @ unit))[3:]) / norms[3:])
            step = step / norms
            params = params + step[:3]
            moved = moved + step[3:]
            values = nominal_at(*moved)
            moves = float(np.abs(step[3:]).max())
            # settled: at the tolerance, or the steps shrank and then stopped shrinking, at
            # the round-off of a shift that the data fix (within their uncertainty)
            if moves <= STEP_TOL * size or (
                    shrank and moves >= last
                    and np.all(np.abs(step[3:]) <= SHIFT_SETTLED_STDS * sigma)):
                break
            shrank, last = shrank or moves < last, moves
        else:
            raise InputError(f"The shift fit did not settle in {MAX_ITERATIONS} steps (last "
                             f"step {np.abs(step[3:]).max():.3g} m)", key="shift")
        params = np.linalg.lstsq(plane, pz - values, rcond=None)[0]
    residual = np.full(z.shape, np.nan)
    residual[seen] = pz - values - plane @ params
    residual.flags.writeable = False
    finite = residual[seen]
    return FormError(float(np.ptp(finite)), float(np.sqrt(np.mean(finite**2))), float(params[0]),
                     frozen(params[1:]), frozen(moved), residual)


def roughness_sa(x, y, z, *, l_cutoff: float | None = None) -> float:
    """Arithmetic mean height Sa (ISO 25178-2) of a height map through surfalize, m.

    Filters: the F-operator is the least-squares plane (surfalize ``level``); no S-filter.
    Without ``l_cutoff`` no L-filter is applied, so Sa is that of the whole levelled map:
    mean |z - plane|. With it, surfalize's Gaussian high-pass of that cut-off (the nesting
    index, ISO 25178-3) removes the longer wavelengths first: Sa of the S-L surface. NaN
    samples are masked (left out of both the plane and the mean); a filtered map must have
    none.

    Parameters
    ----------
    x : array-like, shape (nx,)
    y : array-like, shape (ny,)
        Regular grid axes, m, nx, ny >= 2.
    z : array-like, shape (ny, nx)
        Heights, m.
    l_cutoff : float, optional
        The L-filter's cut-off wavelength, m; at least `MIN_CUTOFF_SPACINGS` sample spacings
        (of the finer axis): no wavelength on the grid is shorter than two spacings, so a
        high-pass below that would leave nothing and read Sa = 0.
    """
    from surfalize import Surface

    x, y, z = map_arrays(x, y, z)
    step_x = regular_step(x, "x")
    step_y = regular_step(y, "y")
    missing = np.isnan(z)
    if np.count_nonzero(~missing) < 3:
        raise InputError("Expected at least three measured samples for Sa", key="z")
    if l_cutoff is not None:
        l_cutoff = as_number(l_cutoff, "l_cutoff", sign="> 0")
        shortest = MIN_CUTOFF_SPACINGS * min(step_x, step_y)
        if l_cutoff < shortest:
            raise InputError(f"Expected l_cutoff >= {MIN_CUTOFF_SPACINGS:g} sample spacings "
                             f"({shortest:.4g} m, the shortest wavelength the grid holds), got "
                             f"{l_cutoff!r} m: the L-filter would leave nothing (Sa = 0)",
                             key="l_cutoff")
    with warnings.catch_warnings():
        # surfalize warns for unequal steps; levelling and Sa do not depend on them.
        warnings.filterwarnings("ignore", message=".*different pixel size.*")
        surface = Surface(np.where(missing, 0.0, z) / M_PER_UM, step_x / M_PER_UM,
                          step_y / M_PER_UM, mask=missing if missing.any() else None)
        surface = surface.level()
        if l_cutoff is not None:
            if missing.any():
                raise InputError("Expected a map without NaN samples for an L-filtered Sa",
                                 key="z")
            surface = surface.filter("highpass", l_cutoff / M_PER_UM)
        # surfalize's Sa computes Ssk and Sku too, 0 / 0 on a flat map, where Sa = 0 is right
        with np.errstate(divide="ignore", invalid="ignore"):
            sa = float(surface.Sa())
    return sa * M_PER_UM


