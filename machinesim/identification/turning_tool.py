"""Tool errors dx, dR and |dy| from the measured height map of a turned test sphere.

How the errors show on a turned, nose-compensated sphere (machinesim.cutting.tool_form_error;
docs/procedures/sts_turning.md, "Identifying the tool errors"):

* dx (radial offset): the surface at rho is the design's at rho - dx, a cone about the centre,
  ~ dx |rho| / Rs, with its kink at the spindle axis: not a lateral shift, so it is told apart
  from the part's placement in the measurement.
* dR (nose radius): the design offset inwards by dR and raised by dR, ~ -dR rho^2 / (2 Rs^2):
  the W (or M) with the cone.
* dy (centre height): outside the core only a piston (~ dy^2 / 2Rs); the edge never reaches
  rho < |dy|, which stays uncut: the core's area gives |dy| (its sign is not seen).

Only the measured map and the design are used (heights, and the uncut core above the cut
surface); the fit is a least-squares of the exact forms with the spindle centre (x0, y0) and a
piston free.

Each fitted error comes with its first-order standard uncertainty, the square root of the
diagonal of s^2 (J^T J)^-1, J the fit's Jacobian at the solution (`_fit_std`). On the sphere s^2
is the residuals' sum of squares over n - p: the model fits the sphere (to 0.06 nm RMS with
the noise off), so the residuals are the map's noise. On the tilted plane it is the
interferometer's stated noise when given (``noise``): the plane's model leaves out the nose
radius error's form, -dR k^2 cos^2(theta) / 2 (10 nm of cos 2 theta for dR = 100 um, k = 0.02),
which is orthogonal to dy's regressor y / rho and would inflate s, and so dy's std, tenfold.
The instrument's lateral noise, given as ``lateral_sigma``, is added as what it is: each column
of the map read off in x and each row in y by its own deviate, which moves every pixel of a
column by the surface's x slope times the shift, correlated along the column. Its covariance
enters between the fit's inverse normal matrices (the sandwich (J^T J)^-1 J^T S J
(J^T J)^-1). Taken as independent pixel noise instead, the std of dx and dR came out four
times below the scatter of re-readings (docs/procedures/sts_turning.md, "Identifying the
tool errors").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from machinesim.cam.spiral import Design
from machinesim.cutting.tool_form_error import nose_radius_error
from machinesim.exceptions import InputError, NotConvergedError
from machinesim.metrology._arrays import as_number

#: A map whose median lies deeper (m) below the design's heights than this is fitted from
#: that median as its piston, not from 0: from 0 the fit settled on dR = -1815 um (for 100,
#: with a residual as small as the right one's) for a sphere cut 4, 6, 8 or 20 um deeper
#: than programmed, and through the lab 2.9 um deeper, or gave up after 250 s 50 um deeper;
#: from the median it read dR right 4, 6, 8 and 20 um deeper on the engine's map, and
#: through the lab 2.9 to 15 um deeper (`procedures.sts_turning.DEPTH_RANGE`; 20 um deeper
#: there it still settled on -1815 um). A map within it (a sphere cut
#: as programmed: dx and dR move the median by 0.2 um for Table 5's) keeps the start of 0,
#: and so its figures bit for bit, as does a map above the design (a tool set high, whose
#: uncut top the core check reads).
PISTON_START = 0.5e-6


@dataclass(frozen=True)
class TurnedToolErrors:
    """Tool errors read from a turned surface, m.

    Attributes
    ----------
    dx : float
        Radial tool offset (parameter ``tool.offset_um`` x, in m here).
    dy_abs : float
        |centre height error|, from the uncut core (resolution: the map's pixel).
    d_radius : float
        Nose radius error (parameter ``tool_geometry.nose_radius``, in m here).
    centre : tuple[float, float]
        Spindle axis in the map's coordinates, m.
    residual_rms : float
        RMS of the fit's residuals, m.
    dx_std : float
        First-order standard uncertainty of ``dx`` from the fit, m (module docstring).
    d_radius_std : float
        First-order standard uncertainty of ``d_radius`` from the fit, m.
    """

    dx: float
    dy_abs: float
    d_radius: float
    centre: tuple
    residual_rms: float
    dx_std: float = float("nan")
    d_radius_std: float = float("nan")


@dataclass(frozen=True)
class CentreHeight:
    """The signed centre-height error read from a turned tilted plane, m.

    Attributes
    ----------
    dy : float
        Centre-height error (parameter ``tool.offset_um`` y, in m here).
    dy_std : float
        First-order standard uncertainty of ``dy`` from the fit, m (module docstring); the
        uncertainty of the ``dx`` it was given is not in it (dy's regressor y / rho is
        orthogonal to dx's x / rho: on paper 004's test plane dy moves by 0.09 nm per nm
        of dx).
    residual_rms : float
        RMS of the fit's residuals, m.
    residual_rms_known_radius : float
        RMS of the residuals the fit leaves once the nose radius error's form on the plane
        (the ``d_radius`` given, the sphere's) is a known term of its model, m: the fit's
        residuals plus that form, least squares of the sum on the fit's columns removed (to
        first order about its solution, the refit's residuals). With the right dR, what the
        instrument's noise and what the model leaves out put on the map. NaN where not given.
    """

    dy: float
    dy_std: float
    residual_rms: float
    residual_rms_known_radius: float = float("nan")


def _fit_std(result, noise: float | None = None, shifts=()) -> np.ndarray:
    """Standard uncertainties of a `least_squares` result's parameters, in their units.

    s^2 (J^T J)^-1 with s = ``noise`` (in the residuals' unit) when given, else s^2 =
    sum(r^2) / (n - p); the residuals and the Jacobian in the fit's units (nm, nm per
    parameter unit), so the variances come out in the parameters' units squared. J's columns
    are normalised before the inverse (they differ by orders of magnitude: nm per m of a
    centre, per m of a piston).

    ``shifts``: (sigma, group, slope) for each family of shifts that move whole groups of
    residuals together: group k moves by a normal deviate of ``sigma`` (m), which moves
    residual i of the group by ``slope[i]`` (residual unit per m) times it. Each adds
    sigma^2 sum_k v_k v_k^T, v_k = sum over group k of J_i slope_i, to J^T S J.
    """
    jac, fun = np.asarray(result.jac, dtype=np.float64), np.asarray(result.fun)
    n, p = jac.shape
    if n <= p:
        return np.full(p, np.nan)
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0.0] = 1.0
    normed = jac / scale
    s2 = float(fun @ fun) / (n - p) if noise is None else float(noise) ** 2
    inverse = np.linalg.pinv(normed.T @ normed)
    middle = s2 * (normed.T @ normed)
    for sigma, group, slope in shifts:
        v = np.zeros((int(group.max()) + 1, p))
        np.add.at(v, group, normed * np.asarray(slope, dtype=np.float64)[:, None])
        middle += float(sigma) ** 2 * (v.T @ v)
    cov = inverse @ middle @ inverse / np.outer(scale, scale)
    return np.sqrt(np.maximum(np.diag(cov), 0.0))


def _check_lateral(lateral_sigma) -> float:
    """The stated lateral noise (m), 0 for None: a number >= 0, not a str or a bool (True
    is no 1 m)."""
    if lateral_sigma is None:
        return 0.0
    return as_number(lateral_sigma, "lateral_sigma", sign=">= 0")


def identify_tool_errors(design: Design, x, y, heights, *, core_step: float,
                         aperture: float, lateral_sigma: float | None = None) -> TurnedToolErrors:
    """Fit dx, dR (and read |dy|) from ``heights`` (ny, nx) measured over ``x`` x ``y``.

    Parameters
    ----------
    design : Design
        The rotationally symmetric surface the program was made for.
    x, y : array-like
        Grid axes of the map, m.
    heights : array-like, shape (ny, nx)
        Measured heights, m; NaN where the instrument saw nothing.
    core_step : float
        Height (m) above the fitted surface from which a point counts as uncut core; > 0
        (at 0, every point the noise lifts above the fit would count as core).
    aperture : float
        Only points within this distance (m) of the map's origin are used: the turned area;
        > 0, and holding at least as many finite heights as the fit has unknowns (5).
    lateral_sigma : float, optional
        The instrument's stated lateral noise, m: each column of the map off in x and each
        row in y by its own normal deviate (`machinesim.metrology.optical`). Enters the
        std (module docstring); None or 0: pixels independent.
    """
    lateral = _check_lateral(lateral_sigma)
    core_step = as_number(core_step, "core_step", sign="> 0")
    aperture = as_number(aperture, "aperture", sign="> 0")
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    z = np.asarray(heights, dtype=np.float64)
    if z.shape != (y.size, x.size):
        raise InputError(f"Expected heights of shape ({y.size}, {x.size}), got {z.shape}",
                         key="heights")
    if not isinstance(design, Design):
        raise InputError(f"Expected a Design, got {type(design).__name__}", key="design")
    px, py = np.meshgrid(x, y)
    valid = np.isfinite(z) & (np.hypot(px, py) < aperture)
    if valid.sum() < 5:  # x0, y0, piston, dx, dR
        raise InputError(f"Expected the map to hold at least 5 finite heights within aperture "
                         f"{aperture!r} m of its origin (the fit's unknowns), got "
                         f"{int(valid.sum())} of {int(np.isfinite(z).sum())}", key="aperture")
    cut = valid.copy()
    pixel = abs(x[1] - x[0]) * abs(y[1] - y[0]) if x.size > 1 and y.size > 1 else 0.0
    dy_abs = 0.0

    def residual(p, mask):
        x0, y0, piston, dx, dr = p
        rho = np.hypot(px[mask] - x0, py[mask] - y0)
        # the point at rho is cut by the program point a = sqrt(rho^2 - dy^2), its tip dx out
        a = np.sqrt(np.maximum(rho * rho - dy_abs * dy_abs, 0.0)) - dx
        model = design(a, 0.0) + nose_radius_error(design, a, 0.0, dr) + piston
        return (model - z[mask]) * 1e9  # nm: a well-scaled problem

    p = np.zeros(5)
    offset = float(np.median(z[valid] - design(np.hypot(px[valid], py[valid]), 0.0)))
    if offset < -PISTON_START:
        p[2] = offset
    for _ in range(4):  # fit, mark the core (points well above the fit), refit without it
        fitted = cut
        try:
            result = least_squares(residual, p, args=(cut,),
                                   x_scale=[1e-6, 1e-6, 1e-8, 1e-6, 1e-5])
        except ValueError:  # scipy's "array must not contain infs or NaNs", from the Jacobian
            raise NotConvergedError("tool error fit did not converge: it stepped to where its "
                                    "model is not finite (a map far from the design's "
                                    "form)") from None
        if not result.success:
            raise NotConvergedError(f"tool error fit did not converge: {result.message}")
        p = result.x
        above = np.zeros(z.shape, dtype=bool)
        above[valid] = residual(p, valid) * -1e-9 > core_step
        cut = valid & ~above
        dy_abs = float(np.sqrt(above.sum() * pixel / np.pi))
    rms = float(np.sqrt(np.mean(residual(p, cut) ** 2)) * 1e-9)
    # of the last fit, the one that gave p; a column read off by s in x moves its pixels by
    # the surface's x slope times s, which is d(residual)/d(x0) times s (and rows, y0)
    rows, cols = np.nonzero(fitted)
    shifts = [(lateral, cols, result.jac[:, 0]), (lateral, rows, result.jac[:, 1])]
    std = _fit_std(result, shifts=shifts if lateral > 0.0 else ())
    return TurnedToolErrors(dx=float(p[3]), dy_abs=dy_abs, d_radius=float(p[4]),
                            centre=(float(p[0]), float(p[1])), residual_rms=rms,
                            dx_std=float(std[3]), d_radius_std=float(std[4]))


def identify_centre_height(x, y, heights, slope: float, *, aperture: float, core: float,
                           dx: float = 0.0) -> float:
    """The signed centre-height error dy (m) from a turned tilted plane z = ``slope`` x: the
    ``dy`` of `fit_centre_height` (parameters there)."""
    return fit_centre_height(x, y, heights, slope, aperture=aperture, core=core, dx=dx).dy


def fit_centre_height(x, y, heights, slope: float, *, aperture: float, core: float,
                      dx: float = 0.0, noise: float | None = None,
                      lateral_sigma: float | None = None,
                      d_radius: float = 0.0) -> CentreHeight:
    """The signed centre-height error dy from a turned tilted plane z = ``slope`` x, with
    its standard uncertainty.

    The tip at program radius a and spindle angle C sits at (a + dx) u(C) + dy u_perp(C)
    (`machinesim.cutting.tool_form_error`), so the point (rho, theta) is cut by
    a = sqrt(rho^2 - dy^2) - dx at C = theta - atan(dy / (a + dx)), where the program's
    height is slope a cos(C):

        z(rho, theta) = slope a cos(theta - atan(dy / (a + dx))),

    to first order slope (x + dy y / rho - dx x / rho): the plane twisted about the centre,
    the twist's sign the sign of dy, which a rotationally symmetric test (the sphere) cannot
    show. Fitted by least squares over dy, a height offset and a tilt (the part as it lies
    in the instrument), with ``dx`` known (the sphere's), from the first-order estimate.

    Parameters
    ----------
    x, y : array-like
        Grid axes of the map, m, with the spindle axis at the origin.
    heights : array-like, shape (ny, nx)
        Measured heights, m; NaN where the instrument saw nothing.
    slope : float
        The plane's designed slope dz/dx.
    aperture : float
        Only points within this radius (m) are used: the turned area.
    core : float
        Points nearer the axis than this (m) are left out: the uncut core and the centre.
    dx : float
        The radial tool offset, m (from the sphere).
    noise : float, optional
        The map's stated height noise per pixel, m: the s of ``dy_std`` (module docstring).
        None: the residuals' RMS, which counts the model's misfit as noise.
    lateral_sigma : float, optional
        The instrument's stated lateral noise, m, as in `identify_tool_errors`.
    d_radius : float
        The nose radius error, m (from the sphere): its form on the plane, left out of the
        fit, is taken as known for ``residual_rms_known_radius`` only (dy, its std and
        ``residual_rms`` are the fit's without it). On the plane the radial slope is
        tan phi = k cos C along the whole ray, so eq 20's form is exact there:
        -dR (sqrt(1 + k^2 cos^2 C) - 1) ~ -dR k^2 (1 + cos 2C) / 4.

    Returns
    -------
    CentreHeight
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    z = np.asarray(heights, dtype=np.float64)
    if z.shape != (y.size, x.size):
        raise InputError(f"Expected heights of shape ({y.size}, {x.size}), got {z.shape}",
                         key="heights")
    if noise is not None:
        noise = as_number(noise, "noise", sign=">= 0")
    lateral = _check_lateral(lateral_sigma)
    # numbers, not a str or a bool (True is no 1 m radius error, nor a slope of 1)
    k = as_number(slope, "slope", unit="m per m")
    aperture = as_number(aperture, "aperture", sign="> 0")
    core = as_number(core, "core", sign=">= 0")
    dx = as_number(dx, "dx")
    d_radius = as_number(d_radius, "d_radius")
    if not (abs(k) > 0.0):
        raise InputError(f"Expected a tilted plane (finite slope != 0), got {slope!r}",
                         key="slope")
    px, py = np.meshgrid(x, y)
    rho = np.hypot(px, py)
    use = np.isfinite(z) & (rho < aperture) & (rho > core)
    if np.count_nonzero(use) < 10:
        raise InputError("Expected at least 10 measured points between the core and the "
                         "aperture", key="heights")
    rows, cols = np.nonzero(use)
    px, py, rho, z = px[use], py[use], rho[use], z[use]
    theta = np.arctan2(py, px)
    basis = np.column_stack([np.ones(px.size), px, py, px / rho, py / rho])
    first = np.linalg.lstsq(basis, z - k * px, rcond=None)[0]

    def residual(p):
        dy, piston, tx, ty = p
        a = np.sqrt(np.maximum(rho * rho - dy * dy, 0.0)) - dx
        model = k * a * np.cos(theta - np.arctan2(dy, a + dx)) + piston + tx * px + ty * py
        return (model - z) * 1e9  # nm

    start = np.array([first[4] / k, first[0], first[1], first[2]])
    result = least_squares(residual, start, x_scale=[1e-6, 1e-8, 1e-4, 1e-4])
    if not result.success:
        raise NotConvergedError(f"centre height fit did not converge: {result.message}")
    rms = float(np.sqrt(np.mean(result.fun**2)) * 1e-9)
    # a column read off by s in x moves its pixels by the plane's x slope times s (rows: y)
    _, _, tx, ty = result.x
    shifts = [(lateral, cols, np.full(cols.size, (k + tx) * 1e9)),
              (lateral, rows, np.full(rows.size, ty * 1e9))] if lateral > 0.0 else ()
    std = _fit_std(result, None if noise is None else noise * 1e9, shifts)  # nm
    return CentreHeight(dy=float(result.x[0]), dy_std=float(std[0]), residual_rms=rms,
                        residual_rms_known_radius=_known_radius_rms(result, rho, theta, k,
                                                                    dx, d_radius))


def _known_radius_rms(result, rho, theta, k: float, dx: float, d_radius: float) -> float:
    """RMS (m) of the plane fit's residuals with the nose radius error's form (eq 20, exact on
    a plane) a known term of its model, refitted to first order about ``result``: the model
    plus the form, less z, is result.fun + form; the fit's columns (J) take their least-squares
    share of it, and what stays is the refit's residual (`fit_centre_height`)."""
    dy = result.x[0]
    a = np.sqrt(np.maximum(rho * rho - dy * dy, 0.0)) - dx
    cos = np.cos(theta - np.arctan2(dy, a + dx))  # the program's angle C at each point
    form = -d_radius * (np.sqrt(1.0 + (k * cos) ** 2) - 1.0) * 1e9  # nm, as result.fun
    total = result.fun + form
    jac = np.asarray(result.jac, dtype=np.float64)
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0.0] = 1.0
    step = np.linalg.lstsq(jac / scale, total, rcond=None)[0]
    left = total - (jac / scale) @ step
    return float(np.sqrt(np.mean(left**2)) * 1e-9)


__all__ = ["CentreHeight", "TurnedToolErrors", "fit_centre_height", "identify_centre_height",
           "identify_tool_errors"]
