"""Paper 000's prism pattern under the microscope: a section levelled on its land
(`level_on_land`, which the calibration ramps' sections use too), the apexes read in it
(`measure_pattern`, `PatternReading`), and why the uncompensated pattern may be no pattern to
read, as the identified arm predicts its grooves (`unread_before`).

`machinesim.procedures.tool_rotation_arm_reading` (the calibration ramps) re-exports these;
the procedure that cuts the pattern is `machinesim.procedures.tool_rotation_arm`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.cam.prisms import PrismPattern
from machinesim.exceptions import InputError
from machinesim.identification.tool_rotation_arm import height_change, lateral_change
from machinesim.metrology.prisms import fit_apexes
from machinesim.units import M_PER_UM

__all__ = ["PatternReading", "level_on_land", "measure_pattern", "unread_before"]

#: A pattern apex is a local minimum rising by at least this fraction of the pattern depth to
#: the ridges either side. Neighbouring 90-deg grooves at 20 um pitch meet in ridges >= 5 um
#: above the shallower apex (0-20 deg, depth changes of 3 um per deg), while noise (12 nm)
#: makes minima of ~0.05 um prominence.
APEX_PROMINENCE = 0.2
#: Part of the pattern's margin (from each end of the section) taken as land to level the
#: section on: 0.5 x 0.3 mm less the 0.03 mm guard leaves 0.12 mm clear of the first groove's
#: 10 um half width and the last's steep flank (<= 0.5 x its depth of up to 70 um before
#: compensation) with 30 um of pitch error.
LEVEL_LAND_FRACTION = 0.5
#: Fewest samples on the part in a section's land that level it (`level_on_land`).
LAND_SAMPLES = 4


# ---------------------------------------------------------------------------- readings


@dataclass(frozen=True, eq=False)
class PatternReading:
    """Apexes of a machined prism pattern read in one section across it (m).

    Attributes
    ----------
    angles : ndarray, shape (n,)
        Tool angle of each groove (rad).
    depth, depth_sigma : ndarray, shape (n,)
        Apex depth below the surface, and its standard uncertainty.
    centre, centre_sigma : ndarray, shape (n,)
        Apex y, and its standard uncertainty.
    nominal_depth, nominal_pitch : float
        As programmed.
    """

    angles: np.ndarray
    depth: np.ndarray
    depth_sigma: np.ndarray
    centre: np.ndarray
    centre_sigma: np.ndarray
    nominal_depth: float
    nominal_pitch: float

    @property
    def depth_variation(self) -> float:
        """Largest minus smallest apex depth (m)."""
        return float(self.depth.max() - self.depth.min())

    @property
    def depth_error(self) -> float:
        """Largest deviation of an apex depth from the programmed depth (m)."""
        return float(np.abs(self.depth - self.nominal_depth).max())

    @property
    def pitch_error(self) -> float:
        """Largest deviation of an apex from its programmed place relative to the first (m)."""
        offsets = self.centre - self.centre[0] - self.nominal_pitch * np.arange(self.centre.size)
        return float(np.abs(offsets).max())


# ---------------------------------------------------------------------------- measuring


def _land_samples(s, z, land: float) -> np.ndarray:
    """Which samples of a profile (``s``, ``z``) lie in its first or last ``land`` (m) and on
    the part (a finite height)."""
    s, z = np.asarray(s, dtype=np.float64), np.asarray(z, dtype=np.float64)
    return ((s <= s[0] + land) | (s >= s[-1] - land)) & np.isfinite(z)


def _levelled(s, z, land: float, section: str, expected: str) -> np.ndarray:
    """`level_on_land`, refusing a section with fewer than `LAND_SAMPLES` samples on the part
    in its land (key ``part``) by what it is, ``section`` (the piece, the section's x and its
    ends), and what part was ``expected``, where level_on_land names neither."""
    found = np.count_nonzero(_land_samples(s, z, land))
    if found < LAND_SAMPLES:
        raise InputError(f"{section}, reads {found} samples on the part in its first and last "
                         f"{land:g} m, where its land should be (at least {LAND_SAMPLES}): the "
                         f"section runs off the part. {expected}", key="part")
    return level_on_land(s, z, land)


def level_on_land(s, z, land: float) -> np.ndarray:
    """Heights less the line through the first and last ``land`` (m) of a profile.

    A microscope's stage holds the part tilted (`Realism`'s registration: 0.2 mrad, 0.2 um
    over a 1 mm section), as one levels a section by hand before reading it. `fit_apexes`
    finds the land against a line over the grooves itself, and a shear changes neither an
    apex's depth below the land line nor where its two flank lines cross, so levelling
    first leaves both as they were.
    """
    s, z = np.asarray(s, dtype=np.float64), np.asarray(z, dtype=np.float64)
    ends = _land_samples(s, z, land)
    if np.count_nonzero(ends) < LAND_SAMPLES:
        raise InputError(f"Expected land over the first and last {land:g} m of the section, "
                         f"got {np.count_nonzero(ends)} samples there", key="land")
    slope, intercept = np.polyfit(s[ends], z[ends], 1)
    return z - (intercept + slope * s)


def measure_pattern(part, pattern: PrismPattern, microscope, x: float | None = None
                    ) -> PatternReading:
    """Read a prism pattern's apexes in a microscope section across it at ``x`` (m).

    The section spans the stock from land to land (at mid-length by default) at the
    microscope's own spacing; see `fit_apexes`.

    Raises
    ------
    InputError
        When the section does not show one apex per groove (grooves not cut, or merged), or
        has no land on the part at its ends (key ``part``: a part not cut on
        ``pattern.stock``).
    """
    x = pattern.origin[0] + 0.5 * pattern.length if x is None else float(x)
    guard = 0.1 * pattern.margin
    y0, y1 = pattern.origin[1] + guard, pattern.origin[1] + pattern.width - guard
    prof = microscope.profile(part, (x, y0), (x, y1))
    degrees = [round(math.degrees(a), 6) for a in (pattern.angles[0], pattern.angles[-1])]
    level = _levelled(
        prof.s, prof.z, LEVEL_LAND_FRACTION * pattern.margin,
        f"prism pattern {degrees[0]:g} to {degrees[1]:g} deg ({len(pattern.angles)} grooves): "
        f"the section across it at x = {x:g} m, from y = {y0:g} to {y1:g} m (its block less "
        f"{guard:g} m at each end)",
        f"Expected the part cut by pattern.program on pattern.stock ({pattern.stock}); a part "
        "cut on another stock, or for another pattern (its origin, length, margin, pitch and "
        "angles place the block), leaves the section's ends off it")
    centre, depth, centre_sigma, depth_sigma = fit_apexes(
        prof.s, level, len(pattern.angles), prominence=APEX_PROMINENCE * pattern.depth)
    return PatternReading(np.array(pattern.angles), depth, depth_sigma, y0 + centre,
                          centre_sigma, pattern.depth, pattern.pitch)


def unread_before(estimate, pattern: PrismPattern) -> str | None:
    """Why the uncompensated ``pattern`` is no pattern to read, as the arm ``estimate`` (the
    identified one, an `ArmEstimate`) predicts its grooves; None where it finds no reason.

    Touched off at 0 deg, the groove at angle t is eq 1's rise off 0 deg shallower than
    programmed and eq 2's shift aside: depth ``D = depth - rise(t)`` at ``y + shift(t)``,
    its flanks ``(pi - tool_angle) / 2 -+ t`` from the surface towards -y and +y. Reasons,
    each as `fit_apexes` and `measure_pattern` need it: a groove at least `APEX_PROMINENCE`
    x depth deep (not cut at all where D <= 0); two neighbours' flanks crossing between
    their apexes, that much above the shallower (else the deeper one takes the other's
    apex away); every groove clear of the land the section is levelled on.
    """
    angles, half = np.asarray(pattern.angles), (math.pi - pattern.tool_angle) / 2.0
    args = (estimate.r, estimate.e_ys, estimate.r0)
    depth = pattern.depth - height_change(angles, *args)
    y = pattern.centres + lateral_change(angles, *args)
    least = APEX_PROMINENCE * pattern.depth
    degrees = np.round(np.degrees(angles), 6)
    um = 1.0 / M_PER_UM
    reasons = []
    if (depth <= 0.0).any():
        reasons.append(f"the edge stays above the block's top at {_angles(degrees, depth <= 0.0)}"
                       " (not cut)")
    shallow = (depth > 0.0) & (depth < least)
    if shallow.any():
        reasons.append(f"the grooves at {_angles(degrees, shallow)} are less than the "
                       f"{least * um:g} um deep an apex must rise to its ridges")
    a, b = np.tan(half + angles[:-1]), np.tan(half - angles[1:])  # k's +y, k+1's -y flank
    ridge_y = (depth[:-1] - depth[1:] + a * y[:-1] + b * y[1:]) / (a + b)
    ridge = np.minimum(0.0, -depth[:-1] + a * (ridge_y - y[:-1]))
    rise = ridge + np.minimum(depth[:-1], depth[1:])
    bad = (depth[:-1] >= least) & (depth[1:] >= least) & (
        (rise < least) | (ridge_y < y[:-1]) | (ridge_y > y[1:]))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        reasons.append(
            f"neighbours meet too low, or one takes the other's apex away ({np.count_nonzero(bad)}"
            f" of {len(bad)} pairs), first the {degrees[k]:g} and {degrees[k + 1]:g} deg grooves, "
            f"{depth[k] * um:.2f} and {depth[k + 1] * um:.2f} um deep and "
            f"{(y[k + 1] - y[k]) * um:.2f} um apart: their flanks cross {rise[k] * um:.2f} um "
            f"over the shallower apex (at least {least * um:g} um, between the two apexes)")
    guard = 0.1 * pattern.margin  # the section's ends (`measure_pattern`)
    ends = pattern.origin[1] + guard, pattern.origin[1] + pattern.width - guard
    cut = depth > 0.0
    if cut.any():
        low = (y - depth / np.tan(half - angles))[cut].min()
        high = (y + depth / np.tan(half + angles))[cut].max()
        if low < ends[0] or high > ends[1]:
            reasons.append(f"the grooves span y = {low:.6g} to {high:.6g} m, beyond an end of "
                           f"the section across them ({ends[0]:.6g} to {ends[1]:.6g} m): no "
                           "land left there to level it on")
    if not reasons:
        return None
    return (f"by the identified arm (r - r0 = {(estimate.r - estimate.r0) * um:.2f} um, e_ys = "
            f"{estimate.e_ys * um:.2f} um) the uncompensated grooves run {depth[0] * um:.2f} to "
            f"{depth[-1] * um:.2f} um deep (a groove's depth less eq 1's rise off 0 deg): "
            + "; ".join(reasons))


def _angles(degrees: np.ndarray, chosen: np.ndarray) -> str:
    """The chosen tool angles (deg) as text: 'a to b deg' for a run of neighbours."""
    index = np.flatnonzero(chosen)
    if len(index) > 2 and index[-1] - index[0] + 1 == len(index):
        return f"{degrees[index[0]]:g} to {degrees[index[-1]]:g} deg"
    return ", ".join(f"{d:g}" for d in degrees[index]) + " deg"
