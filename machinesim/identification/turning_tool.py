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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from machinesim.cam.spiral import Design
from machinesim.cutting.tool_form_error import nose_radius_error
from machinesim.exceptions import InputError, NotConvergedError


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
    """

    dx: float
    dy_abs: float
    d_radius: float
    centre: tuple
    residual_rms: float


def identify_tool_errors(design: Design, x, y, heights, *, core_step: float,
                         aperture: float) -> TurnedToolErrors:
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
        Height (m) above the fitted surface from which a point counts as uncut core.
    aperture : float
        Only points within this distance (m) of the map's origin are used: the turned area.
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    z = np.asarray(heights, dtype=np.float64)
    if z.shape != (y.size, x.size):
        raise InputError(f"Expected heights of shape ({y.size}, {x.size}), got {z.shape}",
                         key="heights")
    if not isinstance(design, Design):
        raise InputError(f"Expected a Design, got {type(design).__name__}", key="design")
    px, py = np.meshgrid(x, y)
    valid = np.isfinite(z) & (np.hypot(px, py) < aperture)
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
    for _ in range(4):  # fit, mark the core (points well above the fit), refit without it
        result = least_squares(residual, p, args=(cut,), x_scale=[1e-6, 1e-6, 1e-8, 1e-6, 1e-5])
        if not result.success:
            raise NotConvergedError(f"tool error fit did not converge: {result.message}")
        p = result.x
        above = np.zeros(z.shape, dtype=bool)
        above[valid] = residual(p, valid) * -1e-9 > core_step
        cut = valid & ~above
        dy_abs = float(np.sqrt(above.sum() * pixel / np.pi))
    rms = float(np.sqrt(np.mean(residual(p, cut) ** 2)) * 1e-9)
    return TurnedToolErrors(dx=float(p[3]), dy_abs=dy_abs, d_radius=float(p[4]),
                            centre=(float(p[0]), float(p[1])), residual_rms=rms)


def identify_centre_height(x, y, heights, slope: float, *, aperture: float, core: float,
                           dx: float = 0.0) -> float:
    """The signed centre-height error dy from a turned tilted plane z = ``slope`` x.

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
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    z = np.asarray(heights, dtype=np.float64)
    if z.shape != (y.size, x.size):
        raise InputError(f"Expected heights of shape ({y.size}, {x.size}), got {z.shape}",
                         key="heights")
    k = float(slope)
    if not (abs(k) > 0.0) or not np.isfinite(k):
        raise InputError(f"Expected a tilted plane (finite slope != 0), got {slope!r}",
                         key="slope")
    px, py = np.meshgrid(x, y)
    rho = np.hypot(px, py)
    use = np.isfinite(z) & (rho < aperture) & (rho > core)
    if np.count_nonzero(use) < 10:
        raise InputError("Expected at least 10 measured points between the core and the "
                         "aperture", key="heights")
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
    return float(result.x[0])


__all__ = ["TurnedToolErrors", "identify_centre_height", "identify_tool_errors"]
