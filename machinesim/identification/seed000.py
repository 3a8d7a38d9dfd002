"""Paper 000: the tool setting error e_ys and arm radius r of a planer's tool-rotation axis.

The planer (``planer_4axis``) carries its V (prism) tool on an arm below the A axis (tool
rotation about X). The NC program places the edge with the nominal arm radius r0: for an edge
point (y, z) at tool angle t it commands ``Y = y - r0 sin t``, ``Z = z - r0 (1 - cos t)``.
The real edge hangs at radius r and sits e_ys sideways of the arm's centre line, so at angle
t it lands at ``(y + dy(t), z + dz(t))`` with

    dz(t) = e_ys sin t - (r - r0) cos t,     dy(t) = e_ys cos t + (r - r0) sin t.

Measured from t = 0, as the paper measures them (its eqs 1 and 2, missing from the text and
derived in docs/procedures/seed000.md):

    e_z,total(t) = dz(t) - dz(0) = (r - r0) (1 - cos t) + e_ys sin t          (eq 1)
    e_y,total(t) = dy(t) - dy(0) = (r - r0) sin t + e_ys (cos t - 1)          (eq 2)

e_z,total is the rise of the edge: a groove gets shallower by it (with e_ys = -0.178 mm the
0-20 deg pattern deepens by up to 58 um).

Plan (`CalibrationPlan`, `measure_calibration`): one ramp groove per angle (0, 10, 20, 30,
40 deg) whose programmed depth spans the plan's search range, since the edge may be off by
hundreds of um; the laser microscope finds where each groove starts and reads its apex at
stations 8-16 um deep. `fit_arm` fits eq 1 by weighted least squares; `compensate` rewrites
an NC program; `measure_pattern` reads the prism pattern's apexes. Only the microscope's
readings enter (the honesty rule of DESIGN.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology import MeshIndex, fit_v_groove
from machinesim.metrology._arrays import frozen
from machinesim.metrology.prisms import SIGMA_FLOOR_M, fit_apexes
from machinesim.nc import ProgramBuilder
from machinesim.nc.program import Program
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = [
    "AngleReading", "ArmEstimate", "CalibrationPlan", "PatternReading", "PrismPattern",
    "arm_radius", "compensate", "fit_arm", "height_change", "lateral_change",
    "measure_calibration", "measure_pattern", "nominal_axes", "touch_off",
]

#: The coarse search calls a ramp groove found where the section is this deep (m): 160
#: microscope noise sigmas (12 nm), yet shallow enough to be met early on the ramp.
FIND_DEPTH_M = 2e-6
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
#: Extra depth step between calibration stations (m): 1/9 of the microscope's 1 nm display
#: step, so the nine stations' apexes fall at nine places on that step and its rounding
#: averages out (with stations whole um apart, it repeats at every station when the noise
#: is off).
STATION_DITHER_M = 1e-9 / 9
#: Land kept either side of a groove in a fine section (m), at least: 33 samples at 0.3 um.
FINE_LAND_M = 10e-6
#: A pattern apex is a local minimum rising by at least this fraction of the pattern depth to
#: the ridges either side. Neighbouring 90-deg grooves at 20 um pitch meet in ridges >= 5 um
#: above the shallower apex (0-20 deg, depth changes of 3 um per deg), while noise (12 nm)
#: makes minima of ~0.05 um prominence.
APEX_PROMINENCE = 0.2


def height_change(angle, r: float, e_ys: float, r0: float):
    """Paper 000 eq 1: rise of the edge at tool angle ``angle`` (rad) from angle 0 (m)."""
    return (r - r0) * (1.0 - np.cos(angle)) + e_ys * np.sin(angle)


def lateral_change(angle, r: float, e_ys: float, r0: float):
    """Paper 000 eq 2: shift of the edge along +Y at ``angle`` (rad) from angle 0 (m)."""
    return (r - r0) * np.sin(angle) + e_ys * (np.cos(angle) - 1.0)


def arm_radius(machine) -> float:
    """Nominal arm radius r0 (m) of a machine's A axis, from its nominal kinematics."""
    if "A" not in machine.axes:
        raise InputError(f"Expected a machine with a tool-rotation axis A, got axes "
                         f"{machine.axes}", key="machine")
    q = np.zeros((2, len(machine.axes)))
    q[:, machine.axes.index("A")] = (-0.5, 0.5)
    y = machine.tool_pose(q)[:, 1, 3]
    return float((y[1] - y[0]) / (2.0 * math.sin(0.5)))


def nominal_axes(y, z, angle, r0: float):
    """Y and Z (m) that put the nominal edge at (y, z) at tool angle ``angle`` (rad)."""
    return y - r0 * np.sin(angle), z - r0 * (1.0 - np.cos(angle))


@dataclass(frozen=True)
class ArmEstimate:
    """The edge on the A-axis arm as identified (or as assumed before identification).

    Attributes
    ----------
    r0, r : float
        Nominal and identified arm radius (m).
    e_ys : float
        Tool setting error: the edge's offset along Y from the arm's centre line at t = 0 (m).
    z_offset, y_offset : float
        Height and lateral error of the edge at t = 0 (m): dz(0), dy(0).
    r_sigma, e_ys_sigma, z_offset_sigma : float
        Standard uncertainties (m) from the readings' uncertainties; NaN when not fitted.
    residual_z, residual_y : tuple of float
        Reading minus model at each angle (m); empty when not fitted.
    """

    r0: float
    r: float
    e_ys: float
    z_offset: float = 0.0
    y_offset: float = 0.0
    r_sigma: float = math.nan
    e_ys_sigma: float = math.nan
    z_offset_sigma: float = math.nan
    residual_z: tuple[float, ...] = field(default=())
    residual_y: tuple[float, ...] = field(default=())

    def edge_error(self, angle):
        """(dy, dz) of the edge from where the nominal program puts it, at ``angle`` (m)."""
        return (self.y_offset + lateral_change(angle, self.r, self.e_ys, self.r0),
                self.z_offset + height_change(angle, self.r, self.e_ys, self.r0))


def compensate(program: Program, estimate: ArmEstimate) -> Program:
    """Rewrite a nominal program so the edge lands where it was programmed at every angle.

    Each target gets ``Y - dy(A)`` and ``Z - dz(A)`` (`ArmEstimate.edge_error`), so a move at
    constant A is exact. A move that turns A is corrected at its two ends only. An axis not
    yet programmed counts as at 0, the machine's start.

    Parameters
    ----------
    program : Program
        Written for the nominal arm (`nominal_axes`), axis values in m and rad.
    estimate : ArmEstimate
        From `fit_arm` (or `touch_off` for the uncompensated state).

    Returns
    -------
    Program
        The same moves, kinds, feeds and line numbers with corrected Y and Z.
    """
    moves = []
    for move in program.moves:
        target = dict(move.target)
        dy, dz = estimate.edge_error(target.get("A", 0.0))
        target["Y"] = target.get("Y", 0.0) - float(dy)
        target["Z"] = target.get("Z", 0.0) - float(dz)
        moves.append(replace(move, target=target))
    return Program.from_moves(moves, number=program.number, source=program.source,
                              work_offsets=program.work_offsets)


def _groove_program(r0: float, clearance: float, x_out: float, grooves, feed: float,
                    number: int) -> Program:
    """Grooves along +X: ``grooves`` of (angle, edge points (x, y, z)), the first by rapids."""
    b, current = ProgramBuilder(number), 0.0

    def axes(y, z, angle):
        Y, Z = nominal_axes(y, z, angle, r0)
        return {"Y": float(Y), "Z": float(Z), "A": float(angle)}

    for angle, path in grooves:
        # A turns only with the edge before the stock in x: turning A swings the edge by tens
        # of mm on its arm, far below a straight-line interpolation of Y and Z.
        b.rapid(Z=float(nominal_axes(0.0, clearance, current, r0)[1])).rapid(X=x_out)
        (x0, y0, z0), current = path[0], angle
        b.rapid(**axes(y0, clearance, angle)).rapid(X=x0).rapid(Z=axes(y0, z0, angle)["Z"])
        for x, y, z in path[1:]:
            b.linear(X=x, **axes(y, z, angle), feed_mm_per_min=feed)
        b.rapid(Z=axes(path[-1][1], clearance, angle)["Z"])
    return b.rapid(X=x_out).build()


def _angles(angles, tool_angle: float, name: str) -> tuple[float, ...]:
    values = tuple(float(a) for a in angles)
    limit = (math.pi - tool_angle) / 2.0
    if not values or not all(math.isfinite(a) and abs(a) < limit for a in values):
        raise InputError(f"Expected tool angles within +-{math.degrees(limit):g} deg (a flank "
                         f"of the {math.degrees(tool_angle):g}-deg tool turns flat there), got "
                         f"{[round(math.degrees(a), 6) for a in values]} deg", key=name)
    return values


@dataclass(frozen=True)
class CalibrationPlan:
    """Ramp grooves at the calibration angles (paper 000: 0, 10, 20, 30, 40 deg).

    Attributes
    ----------
    angles : tuple of float
        Tool angles (rad); 0 first for `touch_off`.
    search : float
        Half range of each ramp's programmed depth (m): it must exceed the largest
        ``sqrt(e_ys**2 + (r - r0)**2)`` expected, the length of the edge's offset vector.
    slope : float
        Descent of the ramp per unit of x.
    spacing : float
        Distance between the ramps' starts along Y (m).
    station_depths : tuple of float
        Groove depths (m) at which the microscope reads each groove.
    origin : (float, float)
        Corner (x, y) of the stock (m), away from the workpiece origin where the edge starts.
    tool_angle, clearance, feed_mm_per_min : float
        Included angle of the V tool (rad), edge clearance over the surface for rapids (m),
        feed (the paper's 12,000 mm/min).
    """

    angles: tuple[float, ...] = tuple(math.radians(a) for a in (0, 10, 20, 30, 40))
    search: float = 0.35 * M_PER_MM
    slope: float = 0.1
    spacing: float = 3.0 * M_PER_MM
    station_depths: tuple[float, ...] = tuple((8 + k) * M_PER_UM + k * STATION_DITHER_M
                                              for k in range(9))
    origin: tuple[float, float] = (1.0 * M_PER_MM, 1.0 * M_PER_MM)
    tool_angle: float = math.pi / 2
    clearance: float = 1.0 * M_PER_MM
    feed_mm_per_min: float = 12000.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "angles", _angles(self.angles, self.tool_angle, "angles"))
        for name in ("search", "slope", "spacing"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise InputError(f"Expected {name} > 0, got {value!r}", key=name)
        if self.clearance <= self.search:
            raise InputError(f"Expected a clearance above the search range {self.search:g} m, "
                             f"got {self.clearance!r}", key="clearance")

    @property
    def ramp(self) -> tuple[float, float]:
        """x (m) where the ramps start (edge ``search`` above the surface) and end (below)."""
        x_a = self.origin[0] + 0.5 * M_PER_MM
        return x_a, x_a + 2.0 * self.search / self.slope

    def edge(self, k: int, x):
        """Programmed edge (y, z) (m) of ramp ``k`` at ``x``: down the tool's own axis."""
        x_a = self.ramp[0]
        z = self.search - self.slope * (np.asarray(x) - x_a)
        # Descending along the tilted tool's axis keeps the move in the tool's X-Z plane: the
        # edge cuts forward, never dragged sideways.
        y = self.origin[1] + 1.0 * M_PER_MM + k * self.spacing + (self.search - z) * math.tan(
            self.angles[k])
        return y, z

    @property
    def stock(self) -> str:
        """Stock spec of the calibration block (mm)."""
        length = (self.ramp[1] - self.origin[0]) / M_PER_MM + 2.0 * self.search / M_PER_MM + 1.0
        width = len(self.angles) * self.spacing / M_PER_MM + 1.0
        return (f"block:{length:.6g}x{width:.6g}x1@{self.origin[0] / M_PER_MM:.6g},"
                f"{self.origin[1] / M_PER_MM:.6g},0")

    def program(self, r0: float, number: int = 1) -> Program:
        """The calibration program for the nominal arm radius ``r0`` (m)."""
        x_a, x_b = self.ramp
        # each ramp leaves the stock climbing the tool axis back at slope 1
        grooves = [(angle, [(x_a, *self.edge(k, x_a)), (x_b, *self.edge(k, x_b)),
                            (x_b + 2.0 * self.search, *self.edge(k, x_a))])
                   for k, angle in enumerate(self.angles)]
        return _groove_program(r0, self.clearance, self.origin[0] - 0.5 * M_PER_MM, grooves,
                               self.feed_mm_per_min, number)


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
    """

    angle: float
    x: np.ndarray
    dz: np.ndarray
    dy: np.ndarray
    dz_sigma: np.ndarray
    dy_sigma: np.ndarray

    def mean(self, which: str) -> tuple[float, float]:
        """Weighted mean of ``"dz"`` or ``"dy"`` over the stations, and its uncertainty."""
        values = getattr(self, which)
        weights = 1.0 / np.maximum(getattr(self, f"{which}_sigma"), SIGMA_FLOOR_M) ** 2
        return float(weights @ values / weights.sum()), float(1.0 / math.sqrt(weights.sum()))


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
        Its noise, resolution and seed are the reading's; the lateral spacing is the plan's.

    Returns
    -------
    tuple of AngleReading
        One per ``plan.angles``, in that order.

    Raises
    ------
    InputError
        When a groove lies outside the ramp's search range.
    """
    index = MeshIndex.from_surface(part)
    return tuple(_read_ramp(index, plan, k, microscope) for k in range(len(plan.angles)))


def _section(index, microscope, x: float, y0: float, y1: float, spacing=None):
    """A section across Y at ``x``: (y, height below the land's median)."""
    prof = microscope.profile(index, (x, y0), (x, y1), spacing=spacing)
    return y0 + prof.s, prof.z - np.nanmedian(prof.z)


def _read_ramp(index, plan: CalibrationPlan, k: int, microscope) -> AngleReading:
    x_a, x_b = plan.ramp
    window = plan.search + 0.25 * M_PER_MM
    where = f"ramp groove at {math.degrees(plan.angles[k]):g} deg"

    def coarse(x):
        y = float(plan.edge(k, x)[0])
        return _section(index, microscope, x, y - window, y + window, COARSE_SPACING_M)

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
        raise InputError(f"{where}: the groove does not start on the ramp; the edge's offset "
                         f"exceeds the plan's search range {plan.search:g} m", key="search")
    rows = []
    floor = microscope.readout.resolution / math.sqrt(12.0)
    for depth, x in zip(plan.station_depths, x_stations, strict=True):
        y, h = coarse(x)
        inside = y[h < -0.1 * depth]
        margin = max(FINE_LAND_M, 0.25 * (inside[-1] - inside[0]))
        y0 = float(inside[0] - margin)
        prof = microscope.profile(index, (x, y0), (x, float(inside[-1] + margin)),
                                  spacing=FINE_SPACING_M)
        groove = fit_v_groove(prof.s, prof.z)
        y_prog, z_prog = plan.edge(k, x)
        # A reading is never better than the display's rounding (resolution / sqrt(12)),
        # which a fit with no residual would not show.
        rows.append((x, -groove.depth - z_prog, y0 + groove.centre - y_prog,
                     max(groove.depth_sigma, floor), max(groove.centre_sigma, floor)))
    return AngleReading(plan.angles[k], *(frozen(c) for c in zip(*rows, strict=True)))


def fit_arm(readings: Sequence[AngleReading], r0: float, *, lateral: bool = False
            ) -> ArmEstimate:
    """Identify r and e_ys from the calibration readings (paper 000 eq 1, least squares).

    Parameters
    ----------
    readings : sequence of AngleReading
        At least three distinct angles (the offset at t = 0 is a third unknown).
    r0 : float
        Nominal arm radius (m).
    lateral : bool
        Also fit the apex positions with eq 2 (with their own offset). Default False, the
        paper's fit of depths alone; the lateral offset and residuals are then reported with
        eq 2 evaluated at the fitted constants.

    Returns
    -------
    ArmEstimate
        Uncertainties propagated from the readings' (weighted least squares).
    """
    if len({round(reading.angle, 12) for reading in readings}) < 3:
        raise InputError(f"Expected readings at three or more distinct angles, got "
                         f"{[math.degrees(r.angle) for r in readings]} deg", key="readings")
    t = np.array([reading.angle for reading in readings])
    z, z_sigma = np.array([reading.mean("dz") for reading in readings]).T
    y, y_sigma = np.array([reading.mean("dy") for reading in readings]).T
    one, zero = np.ones_like(t), np.zeros_like(t)
    # unknowns: z offset, rho = r - r0, e_ys, y offset
    rows = np.column_stack([one, 1.0 - np.cos(t), np.sin(t), zero])
    values, sigmas = z, z_sigma
    if lateral:
        rows = np.vstack([rows, np.column_stack([zero, np.sin(t), np.cos(t) - 1.0, one])])
        values, sigmas = np.r_[z, y], np.r_[z_sigma, y_sigma]
    else:
        rows = rows[:, :3]
    weight = 1.0 / np.maximum(sigmas, SIGMA_FLOOR_M)
    solution = np.linalg.lstsq(rows * weight[:, None], values * weight, rcond=None)[0]
    covariance = np.linalg.inv((rows * weight[:, None]).T @ (rows * weight[:, None]))
    c, rho, e = solution[:3]
    r = r0 + rho
    change = lateral_change(t, r, e, r0)
    # without the lateral fit, eq 2 at the fitted constants gives the offset at t = 0
    y_offset = solution[3] if lateral else np.average(y - change, weights=1.0 / np.maximum(
        y_sigma, SIGMA_FLOOR_M) ** 2)
    sigma = np.sqrt(np.diag(covariance))
    return ArmEstimate(r0=r0, r=float(r), e_ys=float(e), z_offset=float(c),
                       y_offset=float(y_offset), r_sigma=float(sigma[1]),
                       e_ys_sigma=float(sigma[2]), z_offset_sigma=float(sigma[0]),
                       residual_z=tuple(z - c - height_change(t, r, e, r0)),
                       residual_y=tuple(y - y_offset - change))


def touch_off(readings: Sequence[AngleReading], r0: float) -> ArmEstimate:
    """The state before compensation: the edge set by its reading at t = 0 only.

    As a tool touch at t = 0 would, this corrects the edge's height and lateral offset at
    t = 0 and assumes the nominal arm (r = r0, e_ys = 0) at every other angle.
    """
    at_zero = [reading for reading in readings if reading.angle == 0.0]
    if not at_zero:
        raise InputError("Expected a reading at tool angle 0 to touch off from, got angles "
                         f"{[math.degrees(r.angle) for r in readings]} deg", key="readings")
    (dz, dz_sigma), (dy, _) = at_zero[0].mean("dz"), at_zero[0].mean("dy")
    return ArmEstimate(r0=r0, r=r0, e_ys=0.0, z_offset=dz, y_offset=dy,
                       z_offset_sigma=dz_sigma)


@dataclass(frozen=True)
class PrismPattern:
    """The angle-variable prism pattern (paper 000: 0-20 deg by 1 deg, 10 um deep, 20 um pitch).

    Grooves along +X across the whole stock, one per angle, at increasing Y.

    Attributes
    ----------
    angles : tuple of float
        Tool angle of each groove (rad).
    depth, pitch : float
        Programmed apex depth below the surface and groove spacing (m).
    length, margin : float
        Stock length along X, and uncut land either side of the pattern along Y (m).
    origin : (float, float)
        Corner (x, y) of the stock (m).
    tool_angle, clearance, feed_mm_per_min : float
        As in `CalibrationPlan`.
    """

    angles: tuple[float, ...] = tuple(math.radians(a) for a in range(21))
    depth: float = 10.0 * M_PER_UM
    pitch: float = 20.0 * M_PER_UM
    length: float = 1.0 * M_PER_MM
    margin: float = 0.3 * M_PER_MM
    origin: tuple[float, float] = (1.0 * M_PER_MM, 1.0 * M_PER_MM)
    tool_angle: float = math.pi / 2
    clearance: float = 1.0 * M_PER_MM
    feed_mm_per_min: float = 12000.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "angles", _angles(self.angles, self.tool_angle, "angles"))
        for name in ("depth", "pitch", "length", "margin"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise InputError(f"Expected {name} > 0, got {value!r}", key=name)

    @property
    def centres(self) -> np.ndarray:
        """Programmed edge y of each groove (m), shape (n,)."""
        return self.origin[1] + self.margin + self.pitch * np.arange(len(self.angles))

    @property
    def width(self) -> float:
        """Stock width along Y (m)."""
        return 2.0 * self.margin + self.pitch * (len(self.angles) - 1)

    @property
    def stock(self) -> str:
        """Stock spec of the pattern block (mm)."""
        return (f"block:{self.length / M_PER_MM:.9g}x{self.width / M_PER_MM:.9g}x0.5"
                f"@{self.origin[0] / M_PER_MM:.9g},{self.origin[1] / M_PER_MM:.9g},0")

    def program(self, r0: float, number: int = 2) -> Program:
        """The nominal pattern program for the arm radius ``r0`` (m): `compensate` it."""
        x_in = self.origin[0] - 0.2 * M_PER_MM
        x_out = self.origin[0] + self.length + 0.2 * M_PER_MM
        grooves = [(angle, [(x_in, float(y), -self.depth), (x_out, float(y), -self.depth)])
                   for angle, y in zip(self.angles, self.centres, strict=True)]
        return _groove_program(r0, self.clearance, x_in, grooves, self.feed_mm_per_min, number)


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


def measure_pattern(part, pattern: PrismPattern, microscope, x: float | None = None
                    ) -> PatternReading:
    """Read a prism pattern's apexes in a microscope section across it at ``x`` (m).

    The section spans the stock from land to land (at mid-length by default) at the
    microscope's own spacing; see `fit_apexes`.

    Raises
    ------
    InputError
        When the section does not show one apex per groove (grooves not cut, or merged).
    """
    x = pattern.origin[0] + 0.5 * pattern.length if x is None else float(x)
    guard = 0.1 * pattern.margin
    y0 = pattern.origin[1] + guard
    prof = microscope.profile(part, (x, y0), (x, pattern.origin[1] + pattern.width - guard))
    centre, depth, centre_sigma, depth_sigma = fit_apexes(
        prof.s, prof.z, len(pattern.angles), prominence=APEX_PROMINENCE * pattern.depth)
    return PatternReading(np.array(pattern.angles), depth, depth_sigma, y0 + centre,
                          centre_sigma, pattern.depth, pattern.pitch)
