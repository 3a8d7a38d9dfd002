"""Paper 004's tool test: the residual check of the tilted test plane (`sts_turning.test_cut`).

The plane's fit (`machinesim.identification.turning_tool.fit_centre_height`) models the
twist dy puts on z = k x, with a piston and a tilt; it leaves out the nose radius error's
form, which on a plane is exact and known once the sphere has read dR:
-dR (sqrt(1 + k^2 cos^2 C) - 1) ~ -dR k^2 (1 + cos 2C) / 4, its cos 2C part 10 nm for
dR = 100 um and k = 0.02 (7.1 nm RMS: the fit's residual RMS through the lab is 7.06-7.28
nm). With that form taken as known (``residual_rms_known_radius``) what the working test
leaves is the interferometer's noise: its stated height noise per pixel and its lateral
noise, each column of the map off in x by its own deviate, which moves the column's pixels
by the plane's slope k times it (0.2 nm for 10 nm). So the misfit is that RMS less both in
quadrature, as the sphere's is (`sts_turning.SPHERE_MISFIT_LIMIT`), and the plane is refused
above `PLANE_MISFIT_LIMIT`. Through the lab (docs/procedures/sts_turning.md, "The sign of
dy: a tilted test plane") the default scenario's plane leaves 0.19-0.23 nm (seeds 0-2) and
0.20 nm with the noise off.
"""

from __future__ import annotations

import math

from machinesim.exceptions import InputError
from machinesim.procedures.sts_plans import TEST_PLANE

NM, UM = 1e-9, 1e-6

#: Largest misfit (m) of the tilted test plane's fit (its residual RMS with the nose radius
#: error's form taken as known, less the interferometer's stated height noise and its lateral
#: noise times the plane's slope, in quadrature) for which its dy is taken: the sphere's
#: limit, the same rule on the same instrument (a model that describes the map leaves the
#: noise and at most a few tenths of a nm); the near-alias limits of dy
#: (`sts_aliases.near_aliases`) were derived with it standing for the plane.
PLANE_MISFIT_LIMIT = 0.6 * NM


def plane_misfit(residual_rms: float, noise: float, lateral: float, slope: float) -> float:
    """The plane fit's misfit (m): ``residual_rms`` (with dR's form known) less the stated
    height ``noise`` and the ``lateral`` noise times ``slope``, in quadrature."""
    return math.sqrt(max(residual_rms**2 - noise**2 - (slope * lateral) ** 2, 0.0))


def turned_rim(dx: float, d_radius: float) -> float:
    """The least radius (m) out to which the tilted test plane (`sts_plans.TEST_PLANE`) is
    cut by a tool with radial offset ``dx`` and nose radius error ``d_radius`` (m).

    The program puts the nose's centre where a nose of the nominal R touches the plane; a nose
    of R + dR touches it dR s / sqrt(1 + s^2) farther out along the ray, s = k cos C the
    plane's slope along it, and dx moves every cut by dx along the ray. So the last cut on
    the ray at C lies at turned_radius + dx + dR k cos C / sqrt(1 + k^2 cos^2 C), least
    turned_radius + dx - |dR| k / sqrt(1 + k^2) (C = 0 for dR < 0, 180 deg for dR > 0); a dy
    moves it out, by about dy^2 / (2 turned_radius). Beyond it the stock rises along the nose.
    Through the lab (noise off, dR -850 um): 98.00 um at dx -5 um, and the fit's residuals
    above 2 nm lie at 98.0-100 um from the axis, within 26 deg of C = 0; at dx -10 um 93 um
    (misfit 10.9 nm, 0.25 nm with the fit's aperture at 85 um)."""
    k = TEST_PLANE.slope
    return TEST_PLANE.turned_radius + dx - abs(d_radius) * abs(k) / math.sqrt(1.0 + k * k)


def refuse_plane_misfit(centre, found, noise: float, lateral: float, label: str) -> float:
    """Refuse (`InputError`, key ``tool_test``) a test plane (`sts_plans.TEST_PLANE`) whose
    fit leaves a misfit above `PLANE_MISFIT_LIMIT`: ``centre`` its `CentreHeight`, fitted with
    the sphere's dR known, ``found`` the sphere's `TurnedToolErrors`, ``noise`` and
    ``lateral`` the interferometer's stated height and lateral noise (m). The message names
    the residual, the noise, the misfit, the limit, the readings and what can cause it.
    Returns the misfit (m)."""
    slope, core = TEST_PLANE.slope, TEST_PLANE.core
    misfit = plane_misfit(centre.residual_rms_known_radius, noise, lateral, slope)
    if not misfit > PLANE_MISFIT_LIMIT:  # NaN (no residual given) is not refused
        return misfit
    rim, read = turned_rim(found.dx, found.d_radius), TEST_PLANE.read_half_width
    inside = "" if not rim < read else (
        f"the turned plane's rim, which a tool so far off the axis with such a nose radius "
        f"error (the sphere's dx and dR) leaves {rim / UM:.2f} um from it ("
        f"{TEST_PLANE.turned_radius / UM:g} um turned + dx - |dR| k), inside the "
        f"{read / UM:g} um the plane is read to, so the stock the nose leaves there lies in "
        "the fit (with dR -850 um from dx about -5 um whatever dy); ")
    raise InputError(
        f"{label}: the turned test plane does not fit its model: residual RMS "
        f"{centre.residual_rms_known_radius / NM:.2f} nm with the nose radius error's form "
        f"(dR {found.d_radius / UM:.2f} um, the sphere's) taken as known, against the "
        f"interferometer's stated {noise / NM:.2f} nm and {slope * lateral / NM:.2f} nm of its "
        f"lateral noise on the plane's slope, a misfit of {misfit / NM:.2f} nm (at most "
        f"{PLANE_MISFIT_LIMIT / NM:.2f} nm); the fit reads dy {centre.dy / UM:+.4f} um, which "
        f"is not taken as a centre height (the sphere reads dx {found.dx / UM:+.2f} um, |dy| "
        f"{found.dy_abs / UM:.2f} um). Something on the plane the model leaves out: "
        f"{inside}a tool so far off the axis (with dR 100 um, tool.x below about -6 um, or "
        "|tool.y| from about 8 um at tool.x -3.5 um; with dR 300 um tool.x below about -4.6 "
        "um) that its nose "
        f"cuts across the axis beyond the {core / UM:g} um about it the fit leaves out "
        "(docs/procedures/sts_turning.md, \"The plane's residual check\"), an uncut, chipped "
        "or damaged area of the plane, the spindle's runout or the machine's geometric errors, "
        "the tool's height or rotation (tool.z, tool.rx, tool.ry, tool.rz) or the workpiece's "
        "setting (workpiece.*); check them and cut the plane again", key="tool_test")


__all__ = ["PLANE_MISFIT_LIMIT", "plane_misfit", "refuse_plane_misfit", "turned_rim"]
