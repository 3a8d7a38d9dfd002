"""Paper 000's test pieces under the microscope: the calibration ramps and the prism pattern.

`measure_calibration` finds each ramp groove's start and reads its edge height and lateral
position at stations along it (`AngleReading`), with the sections turned by the stage's
rotation found on the block (`stage_rotation`, `AlignedMicroscope`); `measure_pattern` reads
the apexes of the angle-variable prism pattern in one levelled section (`PatternReading`), and
`unread_before` says why an uncompensated one could not be read: those three and the
levelling live in `machinesim.procedures.tool_rotation_arm_pattern`, re-exported here.
The procedure that cuts them and uses the readings is
`machinesim.procedures.tool_rotation_arm`; docs/procedures/tool_rotation_arm.md gives the
plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NoReturn

import numpy as np

from machinesim.arrays import frozen
from machinesim.cam.prisms import CalibrationPlan
from machinesim.exceptions import InputError
from machinesim.metrology import MeshIndex, fit_v_groove
from machinesim.metrology.prisms import SIGMA_FLOOR_M
from machinesim.procedures.tool_rotation_arm_pattern import (
    APEX_PROMINENCE,
    LAND_SAMPLES,
    LEVEL_LAND_FRACTION,
    PatternReading,
    _levelled,
    level_on_land,
    measure_pattern,
    unread_before,
)
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = [
    "APEX_PROMINENCE", "LAND_SAMPLES", "LEVEL_LAND_FRACTION",
    "AlignedMicroscope", "AngleReading", "PatternReading", "level_on_land",
    "measure_calibration", "measure_pattern", "stage_rotation", "unread_before",
]

#: The coarse search calls a ramp groove found where the section is this deep (m): 160
#: microscope noise sigmas (12 nm), yet shallow enough to be met early on the ramp.
FIND_DEPTH_M = 2e-6
#: Noise of a coarse section whose std times this reaches `FIND_DEPTH_M` reads dips of that
#: depth where there is no groove: at 6 std, one chance in 1e9 a reading, some 1e-4 over
#: the 2600 readings of a section and a hundred stations (a 1 mm capture's window).
NOISE_FINDS = 6.0
#: Depth step (m) between the coarse sections that look for the start of a ramp groove: the
#: whole V of a 90-deg tool stays visible up to 24 um deep at 40 deg (its flank top).
SCAN_DEPTH_M = 10e-6
#: Sample spacing of the coarse sections (m): a 2 um deep 90-deg groove is >= 4 um wide.
COARSE_SPACING_M = 1e-6
#: The bisection for the groove's start stops at this step along x (m): 0.1 um of depth at
#: the default ramp slope 0.1, well inside the 8-16 um band of the stations.
BISECTION_STEP_M = 1e-6
#: Sample spacing of the fine sections (m): the microscope's finest objective (0.1 um pixel
#: pitch, see `Microscope`); a 90-deg V tilted by 40 deg has a flank only 0.09 D wide at
#: depth D, which this still samples 7 times at the shallowest station.
FINE_SPACING_M = 0.1e-6
#: Land kept either side of a groove in a fine section (m), at least: 33 samples at 0.3 um.
FINE_LAND_M = 10e-6
#: Least land (m) at each end of a coarse section that levels it (`_coarse_land`): 20
#: samples at 1 um, where the plan leaves no land the groove cannot reach.
COARSE_LAND_M = 20e-6
#: Where the calibration block's low-y edge is looked for (`stage_rotation`): this far (m)
#: in from each end of the block (both uncut: the ramps start 0.5 mm in and leave the
#: surface before the block's last millimetre), +- this window across it (the stage's
#: offset and its rotation over the block's length: 5 um and 1 mrad x 25 mm, a few
#: sigmas), at this spacing.
EDGE_INSET_M, EDGE_WINDOW_M, EDGE_SPACING_M = 0.25 * M_PER_MM, 0.1 * M_PER_MM, 0.1e-6


# ---------------------------------------------------------------------------- readings


@dataclass(frozen=True, eq=False)
class AngleReading:
    """What the microscope read of one calibration groove (m).

    Attributes
    ----------
    angle : float
        Tool angle (rad).
    x : ndarray, shape (k,)
        The stations along the ramp.
    dz, dy : ndarray, shape (k,)
        Apex height above, and apex position beside, the programmed edge at each station.
    dz_sigma, dy_sigma : ndarray, shape (k,)
        Their standard uncertainties from the groove fits.
    y_edge, z_edge : ndarray, shape (k,), optional
        The programmed edge (y, z) at each station (what the plan asked for there); needed
        to place the stations on the machine (`fit_observations`).
    """

    angle: float
    x: np.ndarray
    dz: np.ndarray
    dy: np.ndarray
    dz_sigma: np.ndarray
    dy_sigma: np.ndarray
    y_edge: np.ndarray | None = None
    z_edge: np.ndarray | None = None

    def mean(self, which: str) -> tuple[float, float]:
        """Weighted mean of ``"dz"`` or ``"dy"`` over the stations, and its uncertainty."""
        values = getattr(self, which)
        weights = 1.0 / np.maximum(getattr(self, f"{which}_sigma"), SIGMA_FLOOR_M) ** 2
        return float(weights @ values / weights.sum()), float(1.0 / math.sqrt(weights.sum()))


# ---------------------------------------------------------------------------- measuring


def measure_calibration(part, plan: CalibrationPlan, microscope) -> tuple[AngleReading, ...]:
    """Read every ramp groove of a calibration part with the microscope.

    Finds where each groove starts by bisection on coarse sections, then reads fine sections
    at the stations where it is ``plan.station_depths`` deep and fits each (`fit_v_groove`).

    Parameters
    ----------
    part : Part
        The calibration part cut by ``plan.program``.
    plan : CalibrationPlan
    microscope : Microscope
        Its noise, resolution and stream are the reading's; the lateral spacing is the plan's.

    Returns
    -------
    tuple of AngleReading
        One per ``plan.angles``, in that order.

    Raises
    ------
    InputError
        When a groove lies outside the ramp's search range, or does not go on down the
        ramp from where it was found (a part not cut by ``plan.program``).
    """
    index = MeshIndex.from_surface(part)
    aligned = AlignedMicroscope(microscope, stage_rotation(index, plan, microscope))
    return tuple(_read_ramp(index, plan, k, aligned) for k in range(len(plan.angles)))


class AlignedMicroscope:
    """A microscope whose sections are turned by the stage rotation found on the part.

    A microscope's stage holds the part turned by some rotation (`Realism`'s registration:
    1 mrad), so a section asked for at x along a ramp 20 mm from the stage's origin falls
    20 um off in x, and a ramp of slope 0.1 reads 2 um deeper or shallower: different at
    every ramp, so a bias of r and e_ys, not an offset. Turning each requested section by
    ``-rotation`` (the rotation found by `stage_rotation`) puts every section where it was
    asked for up to a common offset, which eq 1's free offset takes.
    """

    def __init__(self, microscope, rotation: float) -> None:
        self.microscope = microscope
        self.rotation = float(rotation)
        self.readout = microscope.readout
        self.stage_sigma = microscope.stage_sigma

    def profile(self, part, start, end, spacing=None):
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        turn = np.array([[c, s], [-s, c]])
        return self.microscope.profile(part, turn @ np.asarray(start, dtype=np.float64),
                                       turn @ np.asarray(end, dtype=np.float64),
                                       spacing=spacing)


def stage_rotation(index, plan: CalibrationPlan, microscope) -> float:
    """The rotation (rad) of the microscope's frame from the part's, from the calibration
    block's low-y edge (a straight edge along X, uncut) found at both ends of the block.

    Each of two sections across the edge (``EDGE_WINDOW_M`` either side of where the plan
    put it, at ``EDGE_SPACING_M``) finds its first sample on the part; the edge's slope in
    the microscope's frame is minus the rotation. The edge is found to a sample spacing at
    each end, so the rotation to 0.1 um over the block's length (4e-6 rad at 24 mm).
    """
    y_edge = plan.origin[1]
    x_end = plan.origin[0] + plan.length
    found = []
    for x in (plan.origin[0] + EDGE_INSET_M, x_end - EDGE_INSET_M):
        prof = microscope.profile(index, (x, y_edge - EDGE_WINDOW_M),
                                  (x, y_edge + EDGE_WINDOW_M), spacing=EDGE_SPACING_M)
        on = np.flatnonzero(np.isfinite(prof.z))
        if on.size == 0 or on[0] == 0:
            raise InputError(f"calibration block: expected its edge within "
                             f"{EDGE_WINDOW_M:g} m of y = {y_edge:g} m at x = {x:g} m under "
                             "the microscope", key="edge")
        found.append((x, y_edge - EDGE_WINDOW_M + prof.s[on[0]]))
    (x1, y1), (x2, y2) = found
    return -math.atan2(y2 - y1, x2 - x1)


def height_scatter(h) -> float:
    """The robust standard deviation (m) of a section's heights ``h`` about a piecewise
    straight profile: 1.4826 x the median |second difference| / sqrt(6) (iid noise of std s
    gives second differences of std sqrt(6) s), which the land and a V's flanks, straight,
    leave at zero but at their few kinks; NaN with fewer than 3 readings (off the part)."""
    h = np.asarray(h, dtype=np.float64)
    d2 = h[:-2] - 2.0 * h[1:-1] + h[2:]
    d2 = d2[np.isfinite(d2)]
    return float(1.4826 * np.median(np.abs(d2)) / math.sqrt(6.0)) if d2.size else math.nan


def _too_noisy(scatter: float, at: str) -> str | None:
    """Why a coarse section whose heights scatter by ``scatter`` (m, `height_scatter`, read
    ``at`` some station) likely read a false groove: noise of `NOISE_FINDS` x its std reaches
    the `FIND_DEPTH_M` dip that finds one; None where it does not (or NaN, off the part)."""
    if not NOISE_FINDS * scatter >= FIND_DEPTH_M:
        return None
    return (f"the section's heights scatter by {scatter / M_PER_UM:.3g} um (robust std of "
            f"their second differences, {at}), where a dip of {FIND_DEPTH_M / M_PER_UM:g} um "
            f"finds a groove: a scatter of {FIND_DEPTH_M / NOISE_FINDS / M_PER_UM:.2g} um or "
            "more reads such dips where there is none, so the microscope's readings are likely "
            "too noisy to find it")


def _no_groove_at(where: str, depth: float, x: float, start: float) -> NoReturn:
    """Refuse a ramp whose groove, found to start at ``start`` (m), shows no sample
    ``0.1 x depth`` below the land in the coarse section at the station ``x`` where it
    should be ``depth`` (m) deep."""
    raise InputError(f"{where}: found starting at x = {start:g} m, but the section across the "
                     f"ramp at x = {x:g} m, where it should be {depth / M_PER_UM:.3g} um deep, "
                     f"reads nothing {0.1 * depth / M_PER_UM:.3g} um below its land: the "
                     "groove does not go on down the ramp; expected the calibration part cut "
                     "by plan.program", key="part")


def _coarse_land(plan: CalibrationPlan, k: int) -> float:
    """Land (m) at each end of ramp ``k``'s coarse sections that its groove cannot reach: the
    search window less the groove's lateral offset (up to ``capture``) and the spread of its
    low flank, ``(pi - tool_angle) / 2 - |angle|`` from the surface, at the deepest station
    and the `FIND_DEPTH_M` that finds it; at least `COARSE_LAND_M`. The default plan: 268 um
    at 0 deg, 80 um at 40 deg (1.286 mm - 1 mm - 18 um / tan 5 deg)."""
    flank = (math.pi - plan.tool_angle) / 2.0 - abs(plan.angles[k])
    depth = max(plan.station_depths) + FIND_DEPTH_M
    return max(COARSE_LAND_M, plan.window - plan.capture - depth / math.tan(flank))


def _section(index, microscope, x: float, y0: float, y1: float, spacing, land: float,
             where: str, plan: CalibrationPlan):
    """A section across Y at ``x``: (y, height below its land), levelled on the line fitted
    to its first and last ``land`` (m, `level_on_land`). Taken from its median, a coarse
    section (+-1.286 mm for the default plan, more with a larger capture) on a stage tilted
    by 0.63 mrad (3.15 sigma of `machinesim.realism.MICROSCOPE`'s 0.2 mrad) had one end
    0.8 um below it, the 0.1 x depth that marks the groove at the first station: land read
    as groove. A section with no land on the part is refused naming ``where`` (the ramp)."""
    prof = microscope.profile(index, (x, y0), (x, y1), spacing=spacing)
    return y0 + prof.s, _levelled(
        prof.s, prof.z, land, f"{where}: the section across it at x = {x:g} m, from y = "
        f"{y0:g} to {y1:g} m (its search window about the programmed edge)",
        f"Expected the part cut by plan.program on plan.stock ({plan.stock}); a part cut on "
        "another stock, or for another plan (its origin, capture, spacing and angles place "
        "the ramps), leaves the ramp's window off it")


def _read_ramp(index, plan: CalibrationPlan, k: int, microscope) -> AngleReading:
    x_a, x_b = plan.ramp
    window = plan.window
    where = f"ramp groove at {math.degrees(plan.angles[k]):g} deg"
    land = _coarse_land(plan, k)

    def coarse(x):
        y = float(plan.edge(k, x)[0])
        return _section(index, microscope, x, y - window, y + window, COARSE_SPACING_M, land,
                        f"{where} (ramp {k} of the plan)", plan)

    def found(x):
        return bool(np.nanmin(coarse(x)[1]) < -FIND_DEPTH_M)

    # Walk down the ramp in steps of SCAN_DEPTH_M, then bisect: deeper down, where the whole
    # V profile is buried, the section no longer shows the groove.
    step = SCAN_DEPTH_M / plan.slope
    stations = x_a + step * np.arange(1, int((x_b - x_a) / step))
    first = next((i for i, x in enumerate(stations) if found(x)), 0)
    lo, hi = stations[max(first - 1, 0)], stations[first]
    while hi - lo > BISECTION_STEP_M:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if found(mid) else (mid, hi)
    dz_guess = -FIND_DEPTH_M - float(plan.edge(k, hi)[1])
    x_stations = x_a + (plan.search + dz_guess + np.array(plan.station_depths)) / plan.slope
    # not found, or already cut at the first station (the edge may start below the surface)
    if first == 0 or x_stations.max() >= x_b:
        beyond = (f"the edge's offset |(e_ys, r - r0)| exceeds the plan's capture range "
                  f"{plan.capture / M_PER_MM:g} mm (search range {plan.search:g} m): give a "
                  "larger CalibrationPlan(capture=...) (scenario: --capture-mm)")
        noisy = _too_noisy(height_scatter(coarse(stations[0])[1]),
                           "at the ramp's first station")
        if noisy is None:
            raise InputError(f"{where}: the groove does not start on the ramp; {beyond}",
                             key="capture")
        # a microscope's noise of 1 mm was refused as an offset beyond the capture range:
        # the first section's noise read as a dip of FIND_DEPTH_M, a groove found at once
        raise InputError(f"{where}: the groove does not start on the ramp; {noisy}; "
                         f"else {beyond}", key="microscope")
    rows = []
    floor = microscope.readout.resolution / math.sqrt(12.0)
    # Each fine section is its own placement of the stage (its stated positioning, in x and
    # y): off by ox along the ramp, it reads the groove where the edge stood slope * ox
    # higher and slope * tan(angle) * ox aside (`plan.edge`); off by oy, its centre by oy.
    stage = microscope.stage_sigma
    z_stage = plan.slope * stage
    y_stage = stage * math.hypot(1.0, plan.slope * math.tan(plan.angles[k]))
    for depth, x in zip(plan.station_depths, x_stations, strict=True):
        y, h = coarse(x)
        inside = y[h < -0.1 * depth]
        if inside.size == 0:
            # Found at hi, the groove is not in the section (depth - FIND_DEPTH_M) / slope
            # further down the ramp: a part not cut by plan.program (a 5 um pit 60 um long
            # raised a bare IndexError here). Noise does not: a false find of FIND_DEPTH_M
            # needs a std of ~0.3 um or more, which reads dips of 0.1 x depth (>= 0.8 um) in
            # every section of 2500 samples.
            _no_groove_at(where, depth, x, hi)
        margin = max(FINE_LAND_M, 0.25 * (inside[-1] - inside[0]))
        y0 = float(inside[0] - margin)
        prof = microscope.profile(index, (x, y0), (x, float(inside[-1] + margin)),
                                  spacing=FINE_SPACING_M)
        try:
            groove = fit_v_groove(prof.s, prof.z)
        except InputError as error:
            # a microscope's noise of 0.5 um read a dip of FIND_DEPTH_M at a later station,
            # a groove's start where none is, and the stations below it hold no groove
            noisy = _too_noisy(height_scatter(coarse(stations[first])[1]),
                               "in the coarse section at the ramp station where the walk "
                               "down it found the groove")
            if noisy is None:
                raise
            raise InputError(f"{where}: no groove fitted {depth / M_PER_UM:.3g} um below its "
                             f"start found on the ramp (x = {x:g} m): {error}; {noisy}",
                             key="microscope") from error
        y_prog, z_prog = plan.edge(k, x)
        # A reading is never better than the display's rounding (resolution / sqrt(12)),
        # which a fit with no residual would not show.
        rows.append((x, -groove.depth - z_prog, y0 + groove.centre - y_prog,
                     math.hypot(max(groove.depth_sigma, floor), z_stage),
                     math.hypot(max(groove.centre_sigma, floor), y_stage), y_prog, z_prog))
    return AngleReading(plan.angles[k], *(frozen(c) for c in zip(*rows, strict=True)))
