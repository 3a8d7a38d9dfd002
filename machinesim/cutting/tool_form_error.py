"""Form error that tool errors leave on a turned surface, predicted from the design alone.

Paper 004, eqs 12-20: the tool set off the spindle centre by dx (along the radial X) and dy
(centre height), and its nose radius off by dR from the R the program was compensated for.
Each function gives z_actual - z_design at the points (rho, theta) of the design, both in the
paper's first-order form and in the exact form derived here (docs/procedures/sts_turning.md,
"Tool errors"); the turning engine (`turned_surface`) is the third, independent, method.

Conventions: the tip at programmed radius a and spindle angle C sits at a u(C) + dx u(C) +
dy u_perp(C) (u the radial edge-plane direction, u_perp = u turned +90 deg); the nose is set by
its tip (tool setting touches the tip), so with radius R + dR its centre is dR higher than the
program assumed.
"""

from __future__ import annotations

import numpy as np

from machinesim.cam.spiral import Design
from machinesim.exceptions import InputError

_FORMS = ("paper", "exact")


def _check(design, rho, theta, form):
    if not isinstance(design, Design):
        raise InputError(f"Expected a Design, got {type(design).__name__}", key="design")
    if form not in _FORMS:
        raise InputError(f"Expected form in {_FORMS}, got {form!r}", key="form")
    rho, theta = np.broadcast_arrays(np.asarray(rho, dtype=np.float64),
                                     np.asarray(theta, dtype=np.float64))
    return rho, theta


def _z(design, rho, theta):
    return design(rho * np.cos(theta), rho * np.sin(theta))


def radial_slope(design: Design, rho, theta) -> np.ndarray:
    """tan phi = dz/drho of the design at (rho, theta) (eq 13)."""
    rho, theta = np.broadcast_arrays(np.asarray(rho, dtype=np.float64),
                                     np.asarray(theta, dtype=np.float64))
    gx, gy = design.slope(rho * np.cos(theta), rho * np.sin(theta))
    return gx * np.cos(theta) + gy * np.sin(theta)


def alignment_error_x(design: Design, rho, theta, dx: float, *, form: str = "exact"):
    """Form error of a radial tool offset ``dx`` (m): eq 12, -dx tan phi; exact: the surface
    cut at rho is the design's at rho - dx, z(rho - dx) - z(rho)."""
    rho, theta = _check(design, rho, theta, form)
    if form == "paper":
        return -dx * radial_slope(design, rho, theta)
    return _z(design, rho - dx, theta) - _z(design, rho, theta)


def alignment_error_y(design: Design, rho, theta, dy: float, *, form: str = "exact"):
    """Form error of a centre-height error ``dy`` (m): eqs 14-17.

    The tip at programmed radius a reaches radius sqrt(a^2 + dy^2) at angle C + atan(dy/a),
    so the point (rho, theta) is cut by the program point a = sqrt(rho^2 - dy^2),
    C = theta - atan(dy / a) (exact; NaN inside the uncut core rho < |dy|). The paper (eqs
    15-16) takes rho (1 + (dy/rho)^2)^0.5 - rho for rho - a and atan(dy / rho) for the angle:
    the same to second order in dy / rho.
    """
    rho, theta = _check(design, rho, theta, form)
    if form == "paper":
        with np.errstate(divide="ignore", invalid="ignore"):
            d_rho = rho * (np.sqrt(1.0 + (dy / rho) ** 2) - 1.0)
            d_theta = np.arctan(dy / rho)
        return _z(design, rho - d_rho, theta - d_theta) - _z(design, rho, theta)
    with np.errstate(invalid="ignore"):
        a = np.sqrt(rho * rho - dy * dy)
    return _z(design, a, theta - np.arctan2(dy, a)) - _z(design, rho, theta)


def nose_radius_error(design: Design, rho, theta, d_radius: float, *, form: str = "exact"):
    """Form error of a nose radius R + ``d_radius`` cutting a path compensated for R (eq 20).

    Paper: -dR (1 / cos phi - 1). Exact: the nose centres lie on the design offset by R along
    its normal, raised by dR (the tip is set); the nose of radius R + dR leaves that curve
    offset back by R + dR, i.e. the design offset inwards by dR and raised by dR: the profile
    point at rho' maps to (rho' + dR sin phi, z - dR cos phi + dR), read at rho by
    interpolation along the radial profile at theta (per point, 1-D Newton on rho').
    """
    rho, theta = _check(design, rho, theta, form)
    c, s = np.cos(theta), np.sin(theta)  # once: the Newton steps below only move rho

    def slope_at(r):
        gx, gy = design.slope(r * c, r * s)
        return gx * c + gy * s

    slope = slope_at(rho)
    if form == "paper":
        return -d_radius * (np.sqrt(1.0 + slope * slope) - 1.0)
    source = rho.copy()
    for _ in range(8):  # solve rho' + dR sin phi(rho') = rho
        tan = slope_at(source)
        sin = tan / np.sqrt(1.0 + tan * tan)
        source = source - (source + d_radius * sin - rho)
    tan = slope_at(source)
    cos = 1.0 / np.sqrt(1.0 + tan * tan)
    return (design(source * c, source * s) - d_radius * cos + d_radius
            - design(rho * c, rho * s))


__all__ = ["alignment_error_x", "alignment_error_y", "nose_radius_error", "radial_slope"]
