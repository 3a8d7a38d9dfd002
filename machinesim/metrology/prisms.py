"""Apexes of V grooves that meet in ridges (prism patterns), between uncut land at both ends.

`fit_v_grooves` needs land between grooves; a prism pattern has none: neighbouring grooves
share their ridges. Here each apex is the intersection of its two flank lines, and its depth
is measured from the line through the land at both ends of the profile.
"""

from __future__ import annotations

import math

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_number, frozen, profile_arrays, shown
from machinesim.metrology.grooves import OWN_NOISE_DOF, _band

#: Lower bound of a fit's standard uncertainty (m): noise-free profiles can fit with a zero
#: residual; 1 pm, below any instrument resolution here, keeps the uncertainties finite.
SIGMA_FLOOR_M = 1e-12
#: Land samples lie within this many noise sigmas of the land line.
LAND_SIGMAS = 6.0


def fit_apexes(s, z, count: int, *, prominence: float, flank_band=(0.1, 0.9)):
    """Apexes of ``count`` V grooves that may meet in ridges, between uncut land at both ends.

    Each apex is the intersection of its two flank lines, each fitted over ``flank_band`` of
    the way from the ridge (or the land, for grooves apart) beside it to the lowest sample;
    its depth is measured along z from the line through the land at both ends of the
    profile. The land is found against a line over the grooves (the upper convex hull's edge
    spanning them, then the line fitted to the land found), so a profile read tilted, as a
    microscope's stage holds a part, gives the same apexes: a shear moves neither where two
    flank lines cross in s nor an apex's depth below the land line. Centres and depths are
    in the profile's own frame (s as given; depth along its z).

    Parameters
    ----------
    s, z : array-like, shape (k,)
        Profile (m), s increasing; NaN heights are left out.
    count : int
        Number of grooves expected, >= 1.
    prominence : float
        Rise (m) from an apex to the lower ridge beside it, at least; > 0.
    flank_band : (float, float)
        Part of each flank fitted, as fractions of the way from the ridge (0) to the apex (1),
        0 <= lo < hi <= 1.

    Returns
    -------
    centre, depth, centre_sigma, depth_sigma : ndarray, shape (count,), read-only
        Apex s and depth (m), with standard uncertainties from the line fits, each line with
        the noise of its own residuals (with fewer than `OWN_NOISE_DOF` degrees of freedom,
        the pooled residual of the three), at least `SIGMA_FLOOR_M`.

    Raises
    ------
    InputError
        For a count, prominence or band not as above (naming it), a profile without land at
        both ends, another number of apexes than ``count``, or a groove that is no V.
    """
    s, z = profile_arrays(s, z, 10)
    if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 1:
        raise InputError(f"Expected count as a whole number >= 1 of grooves, got {shown(count)}",
                         key="count")
    prominence = as_number(prominence, "prominence", sign="> 0")
    lo, hi = _band(flank_band)
    second = np.diff(z, 2)
    # noise from second differences (their spread is sqrt(6) sigmas; 1.4826 MAD -> sigma)
    noise = 1.4826 * float(np.median(np.abs(second - np.median(second)))) / math.sqrt(6.0)
    # land within the noise, or within 1 % of the prominence when rounding hides the noise
    tol = max(LAND_SIGMAS * noise, 0.01 * prominence)
    # Land is found against a line over the grooves, never against the heights themselves:
    # a stage's tilt of 0.2 mrad (0.08 um over 0.4 mm) would read a whole end as cut. First
    # the upper hull's edge over the deepest point, then the line fitted to the land found.
    level = z - _bridge(s, z)
    below = _cut(level < np.percentile(level, 90) - tol)
    land = np.r_[0:below[0], below[-1] + 1:s.size]
    ar, br = np.polyfit(s[land], z[land], 1)[::-1]
    below = _cut(z - (ar + br * s) < -tol)
    land = np.r_[0:below[0], below[-1] + 1:s.size]
    ar, br = np.polyfit(s[land], z[land], 1)[::-1]
    residual = z - (ar + br * s)
    from scipy.signal import find_peaks  # here: scipy.signal costs 2 s to import

    apexes = find_peaks(-residual, prominence=prominence)[0]
    if apexes.size != count:
        raise InputError(f"Expected {count} groove apexes in the profile, found {apexes.size} "
                         f"(prominence {prominence:g} m)", key="count")
    ridges = [a + int(np.argmax(residual[a:b])) for a, b in zip(apexes[:-1], apexes[1:],
                                                                strict=True)]
    bounds = [below[0] - 1, *ridges, below[-1] + 1]
    # Grooves that stand apart have land between them, no ridge: a flank runs from the land
    # sample nearest its apex (a ridge found on that land would take land into the flank).
    land_at = np.flatnonzero(residual >= -tol)
    after = np.searchsorted(land_at, apexes)
    lefts = s[np.maximum(bounds[:-1], land_at[after - 1])]
    rights = s[np.minimum(bounds[1:], land_at[after])]
    out = []
    for apex, left, right in zip(s[apexes], lefts, rights, strict=True):
        flanks = [(s >= left + lo * (apex - left)) & (s <= left + hi * (apex - left)),
                  (s <= right - lo * (right - apex)) & (s >= right - hi * (right - apex))]
        out.append(_apex(s - apex, z, [land, *flanks], apex))
    return tuple(frozen(column) for column in zip(*out, strict=True))


def _bridge(s, z):
    """Heights of the upper convex hull's edge over the profile's deepest point, at each s.

    The grooves lie below the land at both ends, so the hull spans them by one edge from
    land to land (or to a ridge as high as the land): a line on the land's noise peaks
    whatever the profile's tilt.
    """
    u, v = s - s[0], z - z.max()
    hull, uu, vv = [], u.tolist(), v.tolist()
    for k in range(u.size):
        while len(hull) >= 2 and ((uu[hull[-1]] - uu[hull[-2]]) * (vv[k] - vv[hull[-2]])
                                  >= (vv[hull[-1]] - vv[hull[-2]]) * (uu[k] - uu[hull[-2]])):
            hull.pop()
        hull.append(k)
    deepest = int(np.argmin(v - v[0] - (v[-1] - v[0]) * u / u[-1]))
    k = min(max(int(np.searchsorted(hull, deepest, side="right")), 1), len(hull) - 1)
    left, right = hull[k - 1], hull[k]
    slope = (z[right] - z[left]) / (s[right] - s[left])
    return z[left] + slope * (s - s[left])


def _cut(below: np.ndarray) -> np.ndarray:
    """Indices of the samples below the land, or an InputError when an end is not land."""
    index = np.flatnonzero(below)
    if index.size == 0 or index[0] < 2 or index[-1] > below.size - 3:
        raise InputError("Expected uncut land at both ends of the profile around the grooves",
                         key="z")
    return index


def _apex(u, z, parts, origin):
    """Centre, depth and their uncertainties from the land and two flank lines (local u)."""
    if min(np.count_nonzero(flank) for flank in parts[1:]) < 2:
        raise InputError(f"groove near s = {origin:.9g} m: fewer than two samples on a flank; "
                         "sample more finely", key="z")
    fits = []
    for index in parts:
        design = np.column_stack([np.ones_like(u[index]), u[index]])
        params = np.linalg.lstsq(design, z[index], rcond=None)[0]
        residual = z[index] - design @ params
        fits.append((params, float(residual @ residual), np.linalg.inv(design.T @ design),
                     len(residual)))
    (ar, br), (a1, b1), (a2, b2) = (fit[0] for fit in fits)
    if not b1 < br < b2:
        raise InputError(f"groove near s = {origin:.9g} m: expected a V, got flank slopes "
                         f"{b1:.3g} and {b2:.3g}", key="z")
    t = (a2 - a1) / (b1 - b2)
    dof = max(sum(fit[3] for fit in fits) - 6, 1)
    pooled = math.sqrt(sum(fit[1] for fit in fits) / dof)
    # derivatives of the apex position t and the depth with respect to (ar, br, a1, b1, a2, b2)
    dt = np.array([0.0, 0.0, -1.0, -t, 1.0, t]) / (b1 - b2)
    dd = np.array([1.0, t, -1.0, -t, 0.0, 0.0]) + (br - b1) * dt
    # each line with the noise of its own residuals, as `fit_v_groove`'s: lateral noise shows
    # on a flank as its slope times the jitter, not on the land, so a pooled noise (the long
    # land's mostly) understated the flanks' and the apex's uncertainty
    covariance = np.zeros((6, 6))
    for k, fit in enumerate(fits):
        own = fit[3] - 2
        sigma = max(math.sqrt(fit[1] / own) if own >= OWN_NOISE_DOF else pooled, SIGMA_FLOOR_M)
        covariance[2 * k:2 * k + 2, 2 * k:2 * k + 2] = sigma * sigma * fit[2]
    return (origin + t, ar + br * t - (a1 + b1 * t), math.sqrt(dt @ covariance @ dt),
            math.sqrt(dd @ covariance @ dd))
