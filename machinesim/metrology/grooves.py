"""V grooves on a profile: depth, width, centre and flank angles; the pitch of several.

A V groove is read from a profile across it, as a laser microscope section is read by hand
(seed 002, Fig. 8; seed 003): the reference surface either side is fitted as a line, each
flank is fitted as a line over the middle of its height (``flank_band``, so that the tool's
nose at the bottom and burrs or edge rounding at the top stay out), and the apex is where the
two flank lines intersect. The apex is robust to noise (it uses every point of both flanks)
and needs no sample at the bottom of the groove. From it:

- centre: the s of the apex;
- depth: the reference line's height at the centre minus the apex height, along z (what a
  microscope reads; for a reference tilted by t the depth normal to it is cos(t) times this);
- width: the distance in s between the two points where the flank lines meet the reference;
- flank angles: the angle of each flank line to the reference line.

The fit runs twice more after a first estimate: the flank points are then chosen by their
position s between the fitted edge and apex, never by their noisy height (choosing by height
would bias the lines), and the reference line takes every land point outside the fitted edges.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_floats, as_number, frozen, profile_arrays

__all__ = ["Pitch", "VGroove", "fit_v_groove", "fit_v_grooves", "groove_pitch"]

#: Noise is estimated from second differences, whose spread is sqrt(6) noise sigmas; 1.4826
#: turns a median absolute deviation into a sigma for normal noise.
MAD_TO_SIGMA = 1.4826
#: A point within this many noise sigmas below the reference line still counts as reference:
#: one land point in ~30000 falls further, while flank points that shallow are a tiny share.
REFERENCE_SIGMAS = 4.0
#: Default groove-detection threshold, in noise sigmas (~1e-9 false alarm per land point).
DETECT_SIGMAS = 6.0
#: Default detection floor as a fraction of the deepest point: dips, scratches and burrs
#: shallower than this are not grooves (pass ``threshold`` for shallower grooves).
DETECT_FRACTION = 0.05
#: Round-off floor of heights, in ulps of the largest |z| (noise-free profiles have ~1 ulp).
ROUND_OFF_ULPS = 64.0
#: The first reference line stops shrinking its band at this fraction of the deepest point,
#: so that heights quantised by an instrument's resolution (a staircase no noise estimate from
#: second differences sees) keep both sides of the staircase; the refit drops the rest.
REFERENCE_FRACTION = 0.01
#: Passes that refine the reference set from the first least-squares line; each halves the
#: band of accepted depths, so 60 passes take any float64 band to the floor.
REFERENCE_PASSES = 60
#: A land sample further than this many robust sigmas (from its own line's residuals) from
#: the line is left out of the reference: shallow ends of a neighbouring groove, burrs, dust.
LAND_SIGMAS = 4.0
#: A line's noise is estimated from its own residuals when they leave it at least this many
#: degrees of freedom; a shorter line takes the pooled residual of all three (with fewer,
#: its own estimate is left to chance: with 3 it stays below 3.1 times the true variance at
#: 95 %, with 1 below 3.8 times and above 0.004 times).
OWN_NOISE_DOF = 3
#: The reference (land) samples of a groove lie on their line within this many noise sigmas
#: (their RMS about it; fits of the tests' grooves stay below 0.31 of the bound) ...
LEVEL_LAND_SIGMAS = 3.0
#: ... plus this fraction of the groove's depth: heights rounded to an instrument's
#: resolution leave a staircase that second differences do not see (1 nm / sqrt(12) on a
#: tilted land, 1e-3 of a 0.3 um groove). The crests of a wave, a ridge's top or a bump's
#: shoulders taken as land bend by up to the reference band, 1 % of the depth (a 2 um sine:
#: 33 nm RMS against 2.3 nm allowed).
LEVEL_LAND_FRACTION = 1e-3
#: Passes of the fit after the first estimate: the second chooses flank points by position,
#: the third settles the edges that the second moved (by far less than a sample spacing).
REFINE_PASSES = 2


@dataclass(frozen=True, repr=False)
class VGroove:
    """A V groove fitted on a profile; lengths in m along the profile (s) and in z, angles in rad.

    Attributes
    ----------
    centre : float
        s of the apex, the intersection of the two flank lines.
    apex_height : float
        z of the apex.
    depth : float
        Reference line at the centre minus the apex height (along z).
    width : float
        Distance in s between the flank lines' crossings with the reference line.
    left_edge, right_edge : float
        s of those crossings.
    left_flank_angle, right_flank_angle : float
        Angle of each flank line to the reference line (positive for a V).
    reference_slope : float
        dz/ds of the reference line (its tilt along the profile).
    residual_rms : float
        Pooled RMS residual of the three line fits (m); an estimate of the profile noise.
    centre_sigma, depth_sigma : float
        Standard uncertainties of centre and depth from the line fits' covariances, each line
        with the noise of its own residuals (`OWN_NOISE_DOF`; else ``residual_rms``): height
        noise is alike on all three, lateral jitter shows on the flanks only (NaN when the
        fits leave no degree of freedom).
    """

    centre: float
    apex_height: float
    depth: float
    width: float
    left_edge: float
    right_edge: float
    left_flank_angle: float
    right_flank_angle: float
    reference_slope: float
    residual_rms: float
    centre_sigma: float
    depth_sigma: float

    @property
    def included_angle(self) -> float:
        """Angle between the two flanks (rad): the tool's included angle for a V tool."""
        return math.pi - self.left_flank_angle - self.right_flank_angle

    def __repr__(self) -> str:
        return (f"VGroove(centre {self.centre * 1e3:.6g} mm +- {self.centre_sigma * 1e9:.3g} nm "
                f"along the profile, depth {self.depth * 1e6:.6g} um +- "
                f"{self.depth_sigma * 1e9:.3g} nm, width {self.width * 1e6:.6g} um, flanks "
                f"{math.degrees(self.left_flank_angle):.6g} and "
                f"{math.degrees(self.right_flank_angle):.6g} deg, residual RMS "
                f"{self.residual_rms * 1e9:.3g} nm)")


@dataclass(frozen=True, eq=False)
class Pitch:
    """Spacing of groove centres (m).

    Attributes
    ----------
    mean : float
        Mean spacing, (last centre - first centre) / (count - 1).
    spacings : ndarray, shape (count - 1,), read-only
        Each spacing, centre[k + 1] - centre[k].
    """

    mean: float
    spacings: np.ndarray


def fit_v_grooves(s, z, *, threshold: float | None = None,
                  flank_band: tuple[float, float] = (0.1, 0.9)) -> tuple[VGroove, ...]:
    """Fit every whole V groove of a profile.

    Parameters
    ----------
    s : array-like, shape (k,)
        Position along the profile, m, strictly increasing.
    z : array-like, shape (k,)
        Height, m; NaN where no surface was seen (those samples are left out).
    threshold : float, optional
        Depth below the reference line (m) from which a sample belongs to a groove. Default:
        the larger of 6 noise sigmas (estimated from the profile's second differences) and 5 %
        of the deepest point. A groove must reach twice the threshold.
    flank_band : (float, float)
        Part of each flank fitted, as fractions of the way from its edge (0) to the apex (1).

    Returns
    -------
    tuple of VGroove
        The grooves in order of s. A groove cut by either end of the profile is left out.
        Neighbouring grooves need some reference surface (land) between them: grooves that
        meet in a ridge leave no reference level to measure from.

    Raises
    ------
    InputError
        For malformed arrays, a bad band or threshold, a groove with fewer than two samples
        on a flank band or on the reference, or a "groove" whose reference samples are no
        level land: they scatter about their line by more than `LEVEL_LAND_SIGMAS` noise
        sigmas plus `LEVEL_LAND_FRACTION` of its depth (a ridge, a bump or a wave holds no
        V below level land on both sides).
    """
    s, z = profile_arrays(s, z, 5)
    lo, hi = _band(flank_band)
    noise = _noise_sigma(z)
    floor = ROUND_OFF_ULPS * np.finfo(np.float64).eps * float(np.abs(z).max())
    keep = _reference_set(s, z, REFERENCE_SIGMAS * noise + floor)
    line = _line(s[keep], z[keep])
    residual = z - (line[0] + line[1] * s)
    if threshold is None:
        threshold = max(DETECT_SIGMAS * noise + floor,
                        DETECT_FRACTION * max(0.0, -float(residual.min())))
    else:
        threshold = as_number(threshold, "threshold", sign="> 0")
    runs = _groove_runs(residual, threshold)
    # A groove cut by an end of the profile bounds the land beside it but is not fitted.
    lead = s[runs[0][1]] if runs and runs[0][0] == 0 else -np.inf
    tail = s[runs[-1][0]] if runs and runs[-1][1] == s.size - 1 else np.inf
    # First estimate: flanks chosen by depth between the nearest reference samples either
    # side, reference samples by closeness to the line through all of them.
    reference = np.flatnonzero(keep)
    grooves = []
    for k, (first, last) in enumerate(runs):
        if first == 0 or last == s.size - 1:
            continue
        apex = first + int(np.argmin(residual[first:last + 1]))
        before = reference[(reference > (runs[k - 1][1] if k else -1)) & (reference < first)]
        after = reference[(reference > last)
                          & (reference < (runs[k + 1][0] if k + 1 < len(runs) else s.size))]
        left = np.arange(before[-1] if before.size else first, apex)
        right = np.arange(apex + 1, (after[0] if after.size else last) + 1)
        fraction = residual / residual[apex]
        band = (fraction >= lo) & (fraction <= hi)
        grooves.append(_fit(s, z, np.r_[before, after], left[band[left]], right[band[right]],
                            s[apex], floor, noise))
    for _ in range(REFINE_PASSES):
        grooves = _refine(s, z, grooves, lo, hi, floor, noise, lead, tail)
    return tuple(grooves)


def fit_v_groove(s, z, *, threshold: float | None = None,
                 flank_band: tuple[float, float] = (0.1, 0.9)) -> VGroove:
    """Fit the one whole V groove of a profile (see `fit_v_grooves` for the parameters).

    Raises
    ------
    InputError
        When the profile holds no whole groove or more than one, or what dips below its
        crests is no V below level land (a ridge, a bump, a wave; see `fit_v_grooves`).
    """
    grooves = fit_v_grooves(s, z, threshold=threshold, flank_band=flank_band)
    if len(grooves) != 1:
        centres = [round(g.centre, 12) for g in grooves]
        raise InputError(f"Expected one whole V groove in the profile, found {len(grooves)} "
                         f"(centres {centres} m)")
    return grooves[0]


def groove_pitch(centres) -> Pitch:
    """Mean and individual spacings of groove centres.

    Parameters
    ----------
    centres : array-like, shape (count,)
        Groove centres along a profile, m, strictly increasing, count >= 2.
    """
    centres = as_floats(centres, "centres")
    if centres.ndim != 1 or centres.size < 2 or not np.isfinite(centres).all():
        raise InputError(f"Expected at least two finite centres, got {centres!r}", key="centres")
    spacings = np.diff(centres)
    if np.any(spacings <= 0.0):
        raise InputError(f"Expected strictly increasing centres, got {centres!r}", key="centres")
    return Pitch(float((centres[-1] - centres[0]) / (centres.size - 1)), frozen(spacings))


def _band(flank_band) -> tuple[float, float]:
    """``flank_band`` as two numbers (never text, whose characters "01" had read as (0, 1),
    nor bools) with 0 <= lo < hi <= 1."""
    try:
        values = () if isinstance(flank_band, str | bytes) else tuple(flank_band)
    except TypeError:
        values = ()
    if len(values) != 2:
        raise InputError(f"Expected flank_band as two fractions, got {flank_band!r}",
                         key="flank_band")
    lo, hi = (as_number(v, "flank_band", unit="fraction of the flank") for v in values)
    if not 0.0 <= lo < hi <= 1.0:
        raise InputError(f"Expected 0 <= lo < hi <= 1 in flank_band, got {flank_band!r}",
                         key="flank_band")
    return lo, hi


def _noise_sigma(z: np.ndarray) -> float:
    """Noise sigma from second differences: zero on every straight stretch, robust to kinks."""
    second = z[:-2] - 2.0 * z[1:-1] + z[2:]
    return float(MAD_TO_SIGMA * np.median(np.abs(second - np.median(second))) / math.sqrt(6.0))


def _line(s: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Least-squares (a, b) of z = a + b s."""
    design = np.column_stack([np.ones_like(s), s])
    return np.linalg.lstsq(design, z, rcond=None)[0]


def _reference_set(s: np.ndarray, z: np.ndarray, tol: float) -> np.ndarray:
    """Samples on the reference surface: a line fit that drops deeper samples in halving bands.

    Grooves lie below the reference, so the least-squares line through all samples lies below
    it too; accepting only samples above a band under the line, and halving the band until it
    reaches the noise ``tol``, walks the line up onto the reference.
    """
    line = _line(s, z)
    deepest = max(0.0, -float(np.min(z - (line[0] + line[1] * s))))
    tol = max(tol, REFERENCE_FRACTION * deepest)
    band = max(0.5 * deepest, tol)
    for _ in range(REFERENCE_PASSES):
        keep = z - (line[0] + line[1] * s) >= -band
        if keep.sum() < 2:
            raise InputError("Expected a reference surface of at least two samples beside the "
                             "grooves, found fewer")
        line = _line(s[keep], z[keep])
        if band == tol:
            break
        band = max(0.5 * band, tol)
    return keep


def _groove_runs(residual: np.ndarray, threshold: float) -> list[tuple[int, int]]:
    """Index ranges (first, last) of the runs deeper than the threshold that reach twice it."""
    below = residual < -threshold
    edges = np.flatnonzero(np.diff(np.r_[False, below, False].astype(np.int8)))
    return [(int(first), int(stop) - 1) for first, stop in zip(edges[::2], edges[1::2], strict=True)
            if -residual[first:stop].min() >= 2.0 * threshold]


def _refine(s, z, grooves, lo, hi, floor, noise, lead, tail):
    """Refit each groove with flank samples chosen by s and every land sample outside edges."""
    refined = []
    for k, groove in enumerate(grooves):
        before = grooves[k - 1].right_edge if k > 0 else lead
        after = grooves[k + 1].left_edge if k + 1 < len(grooves) else tail
        lands = np.flatnonzero(((s > before) & (s < groove.left_edge))
                               | ((s > groove.right_edge) & (s < after)))
        left_run = groove.centre - groove.left_edge
        right_run = groove.right_edge - groove.centre
        left = np.flatnonzero((s >= groove.left_edge + lo * left_run)
                              & (s <= groove.left_edge + hi * left_run))
        right = np.flatnonzero((s <= groove.right_edge - lo * right_run)
                               & (s >= groove.right_edge - hi * right_run))
        refined.append(_fit(s, z, lands, left, right, groove.centre, floor, noise))
    return refined


def _fit(s, z, lands, left, right, origin, floor, noise) -> VGroove:
    """Fit reference and flank lines about ``origin`` and derive the groove with uncertainties."""
    where = f"groove near s = {origin:.9g} m"
    lands = _trim(s, z, lands, floor)
    for name, index in (("reference", lands), ("left flank", left), ("right flank", right)):
        if index.size < 2:
            raise InputError(f"{where}: expected at least two samples on the {name}, got "
                             f"{index.size}; sample the profile more finely or widen flank_band")
    # Local coordinates keep the normal equations well conditioned far from s = 0.
    level = float(np.mean(z[lands]))
    fits = [_local_fit(s[i] - origin, z[i] - level) for i in (lands, left, right)]
    (ar, br), (a1, b1), (a2, b2) = (fit[0] for fit in fits)
    if not b1 < br < b2:
        raise InputError(f"{where}: expected a V (left flank falling, right rising against the "
                         f"reference), got slopes {b1:.3g}, {br:.3g}, {b2:.3g}")
    t = (a2 - a1) / (b1 - b2)
    apex = a1 + b1 * t
    depth = ar + br * t - apex
    # A V needs level land beside it: the reference's samples on their line within the
    # noise. A ridge's top, a bump's shoulders or a wave's crests bend away from it.
    if lands.size > 2:
        scatter = math.sqrt(fits[0][1] / (lands.size - 2))
        level_tol = LEVEL_LAND_SIGMAS * noise + LEVEL_LAND_FRACTION * abs(depth) + floor
        if scatter > level_tol:
            raise InputError(f"{where}: expected a V below level land, got a reference whose "
                             f"{lands.size} samples scatter {scatter:.3g} m about their line "
                             f"(level land within {level_tol:.3g} m: noise {noise:.3g} m): a "
                             f"ridge, bump or wave is no V groove")
    left_edge = (ar - a1) / (b1 - br)
    right_edge = (ar - a2) / (b2 - br)
    squares = sum(fit[1] for fit in fits)
    dof = lands.size + left.size + right.size - 6
    sigma = math.sqrt(squares / dof) if dof > 0 else math.nan
    # Derivatives of t and depth with respect to (ar, br, a1, b1, a2, b2).
    dt = np.array([0.0, 0.0, -1.0, -t, 1.0, t]) / (b1 - b2)
    dd = np.array([1.0, t, -1.0, -t, 0.0, 0.0]) + (br - b1) * dt
    # Each line with its own noise: lateral jitter shows on a flank as its slope times the
    # jitter and not at all on the land, so one pooled figure would understate the flanks.
    covariance = np.zeros((6, 6))
    for k, (fit, index) in enumerate(zip(fits, (lands, left, right), strict=True)):
        own = index.size - 2
        variance = fit[1] / own if own >= OWN_NOISE_DOF else sigma * sigma
        covariance[2 * k:2 * k + 2, 2 * k:2 * k + 2] = variance * fit[2]
    return VGroove(
        centre=float(origin + t),
        apex_height=float(level + apex),
        depth=float(depth),
        width=float(right_edge - left_edge),
        left_edge=float(origin + left_edge),
        right_edge=float(origin + right_edge),
        left_flank_angle=math.atan2(br - b1, 1.0 + b1 * br),
        right_flank_angle=math.atan2(b2 - br, 1.0 + b2 * br),
        reference_slope=float(br),
        residual_rms=sigma,
        centre_sigma=math.sqrt(dt @ covariance @ dt),
        depth_sigma=math.sqrt(dd @ covariance @ dd),
    )


def _trim(s, z, index, floor) -> np.ndarray:
    """Drop samples far from the line through the rest, judged by the rest's robust spread."""
    for _ in range(REFERENCE_PASSES):
        if index.size < 3:
            break
        line = _line(s[index], z[index])
        residual = z[index] - (line[0] + line[1] * s[index])
        # About the median: a line pulled off the land by a few stray samples still has most
        # land samples at one common offset from it.
        deviation = np.abs(residual - np.median(residual))
        close = deviation <= LAND_SIGMAS * MAD_TO_SIGMA * float(np.median(deviation)) + floor
        if close.all():
            break
        index = index[close]
    return index


def _local_fit(t: np.ndarray, u: np.ndarray):
    """Line u = a + b t: parameters, sum of squared residuals, (A^T A)^-1."""
    design = np.column_stack([np.ones_like(t), t])
    params = np.linalg.lstsq(design, u, rcond=None)[0]
    residual = u - design @ params
    return params, float(residual @ residual), np.linalg.inv(design.T @ design)


