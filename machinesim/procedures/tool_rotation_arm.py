"""Paper 000 as an experiment: the tool-rotation arm of a planer (r and e_ys).

`ToolRotationArm` runs paper 000's procedure on a `machinesim.Lab` (machine
``planer_4axis``): cut the calibration ramps (`machinesim.cam.prisms.CalibrationPlan`) at 0,
10, 20, 30 and 40 deg with the nominal program, read them with the lab's laser microscope
(`measure_calibration`), fit eq 1 (`machinesim.identification.tool_rotation_arm.fit_arm`),
rewrite the angle-variable prism pattern (`machinesim.cam.prisms.PrismPattern`) by the
paper's correction (`compensate_program`, through `machinesim.compensation.map_program`),
and cut and read it before (edge touched off at 0 deg only) and after compensation
(`measure_pattern`). docs/procedures/tool_rotation_arm.md gives the geometry and figures.

>>> import machinesim
>>> from machinesim.experiment import run
>>> from machinesim.procedures.tool_rotation_arm import ToolRotationArm
>>> lab = machinesim.Lab("planer_4axis", {"tool": {"offset_um": [0, -178, -55]}})
>>> result = run(ToolRotationArm(), lab)  # doctest: +SKIP
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from machinesim.arrays import frozen
from machinesim.cam.prisms import CalibrationPlan, PrismPattern
from machinesim.compensation import map_program, model_based, program_axes
from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError
from machinesim.experiment import Evaluation, Figure, Identified
from machinesim.identification.tool_rotation_arm import (
    ArmCheck,
    ArmEstimate,
    arm_radius,
    fit_arm,
    fit_check,
    touch_off,
)
from machinesim.metrology import MeshIndex, fit_v_groove
from machinesim.metrology.prisms import SIGMA_FLOOR_M, fit_apexes
from machinesim.nc.program import Program
from machinesim.units import M_PER_MM, M_PER_NM, M_PER_UM, from_si

__all__ = [
    "AngleReading", "ArmIdentification", "Calibration", "PatternReading", "ToolRotationArm",
    "arm_correction", "compensate_program", "measure_calibration", "measure_pattern",
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
#: Land kept either side of a groove in a fine section (m), at least: 33 samples at 0.3 um.
FINE_LAND_M = 10e-6
#: A pattern apex is a local minimum rising by at least this fraction of the pattern depth to
#: the ridges either side. Neighbouring 90-deg grooves at 20 um pitch meet in ridges >= 5 um
#: above the shallower apex (0-20 deg, depth changes of 3 um per deg), while noise (12 nm)
#: makes minima of ~0.05 um prominence.
APEX_PROMINENCE = 0.2
#: The tool of paper 000: a 90-deg V (prism) tool.
TOOL = "v:90"


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
                     max(groove.depth_sigma, floor), max(groove.centre_sigma, floor),
                     y_prog, z_prog))
    return AngleReading(plan.angles[k], *(frozen(c) for c in zip(*rows, strict=True)))


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


# -------------------------------------------------------------------------- compensation


def arm_correction(estimate: ArmEstimate, axes: Sequence[str]):
    """Paper 000's correction as a function for `machinesim.compensation.map_program`.

    Every row of axis values gets ``Y - dy(A)`` and ``Z - dz(A)`` (`ArmEstimate.edge_error`,
    eqs 1 and 2 with the offsets at 0 deg), so the edge lands where the nominal program put
    it at every angle. A move that turns A is corrected at its two ends only.

    Parameters
    ----------
    estimate : ArmEstimate
        From `fit_arm` (or `touch_off` for the uncompensated state).
    axes : sequence of str
        The machine's axes (`Machine.axes`), with Y, Z and A among them.

    Returns
    -------
    callable
        ``function(q) -> q``, q of shape (N, len(axes)) in m and rad.
    """
    missing = [a for a in ("Y", "Z", "A") if a not in axes]
    if missing:
        raise InputError(f"Expected a machine with axes Y, Z and A, got {''.join(axes)}",
                         key="machine")
    y, z, a = (list(axes).index(name) for name in ("Y", "Z", "A"))

    def function(q: np.ndarray) -> np.ndarray:
        dy, dz = estimate.edge_error(q[:, a])
        q[:, y] -= dy
        q[:, z] -= dz
        return q

    return function


def compensate_program(program: Program, machine, estimate: ArmEstimate, *,
                       rounded: bool = True) -> Program:
    """A nominal program rewritten by paper 000's correction (`arm_correction`).

    By the rule of `machinesim.compensation` (axes not yet programmed at the machine's zero,
    every axis on every motion block, rounded to the machine's resolution unless
    ``rounded=False``).
    """
    return map_program(program, machine, arm_correction(estimate, machine.axes),
                       rounded=rounded)


# ---------------------------------------------------------------------------- procedure


@dataclass(frozen=True)
class Calibration:
    """What `ToolRotationArm.measure` returns: the calibration part, as cut and as read.

    Attributes
    ----------
    machine : Machine
        The nominal machine (its kinematics, no errors).
    r0 : float
        Nominal arm radius (m), read from the nominal kinematics (`arm_radius`).
    readings : tuple of AngleReading
        One per calibration angle.
    program : Program
        The calibration program as cut.
    part : Part
        The calibration part.
    """

    machine: object
    r0: float
    readings: tuple[AngleReading, ...]
    program: Program
    part: object


@dataclass(frozen=True)
class ArmIdentification:
    """The detail of paper 000's identification (`Identified.detail`).

    Attributes
    ----------
    estimate : ArmEstimate
        Eq 1 fitted to the edge heights (the paper's fit): r, r0, e_ys and the offsets.
    lateral : ArmEstimate
        Eqs 1 and 2 fitted to heights and lateral positions.
    touched_off : ArmEstimate
        The state before compensation: the edge set at 0 deg only (`touch_off`).
    check, check_lateral : ArmCheck
        The same quantities by the generic `fit` (`fit_check`), heights and heights with
        lateral positions.
    machine : Machine
        The nominal machine the programs are written for.
    """

    estimate: ArmEstimate
    lateral: ArmEstimate
    touched_off: ArmEstimate
    check: ArmCheck
    check_lateral: ArmCheck
    machine: object

    @property
    def r(self) -> float:
        """Identified arm radius (m), the paper's fit."""
        return self.estimate.r

    @property
    def r0(self) -> float:
        """Nominal arm radius (m)."""
        return self.estimate.r0

    @property
    def e_ys(self) -> float:
        """Identified tool setting error (m), the paper's fit."""
        return self.estimate.e_ys

    def model(self) -> ErrorModel:
        """The identified errors as an `ErrorModel`, for the model-based route.

        The tool setting (tool.y = e_ys, tool.z = -(r - r0)) and the workpiece translation
        that takes the offsets at 0 deg (workpiece.y, workpiece.z as `fit_check` names them):
        on this model the edge misses the nominal path by exactly `ArmEstimate.edge_error`.
        """
        e = self.estimate
        return ErrorModel().with_parameters({
            "tool.y": e.e_ys, "tool.z": -(e.r - e.r0),
            "workpiece.y": e.e_ys - e.y_offset, "workpiece.z": -(e.r - e.r0) - e.z_offset})


@dataclass(frozen=True)
class ToolRotationArm:
    """Paper 000's procedure: r and e_ys of the tool-rotation arm, and the prism pattern.

    Parameters
    ----------
    plan : CalibrationPlan
        The calibration ramps (default: the paper's 0-40 deg by 10 deg).
    pattern : PrismPattern
        The angle-variable prism pattern (default: the paper's 0-20 deg by 1 deg).
    """

    plan: CalibrationPlan = CalibrationPlan()
    pattern: PrismPattern = PrismPattern()
    name: ClassVar[str] = "tool_rotation_arm"
    paper: ClassVar[str] = "000"

    def measure(self, lab) -> Calibration:
        """Cut the calibration ramps with the nominal program and read them (microscope
        labelled ``"calibration"``)."""
        machine = lab.machine
        r0 = arm_radius(machine)
        program = self.plan.program(r0)
        part, _ = lab.cut(program, TOOL, self.plan.stock)
        readings = measure_calibration(part, self.plan, lab.microscope(label="calibration"))
        return Calibration(machine, r0, readings, program, part)

    def identify(self, measurements: Calibration) -> Identified:
        """Eq 1 fitted to the readings (`fit_arm`), with `fit_check` beside it.

        Parameters identified: ``tool.y`` = e_ys and ``tool.z`` = -(r - r0), SI, with the
        fit's standard uncertainties.
        """
        readings, r0, machine = measurements.readings, measurements.r0, measurements.machine
        estimate = fit_arm(readings, r0)
        detail = ArmIdentification(
            estimate=estimate, lateral=fit_arm(readings, r0, lateral=True),
            touched_off=touch_off(readings, r0), check=fit_check(readings, machine, r0),
            check_lateral=fit_check(readings, machine, r0, lateral=True), machine=machine)
        return Identified(parameters={"tool.y": (estimate.e_ys, estimate.e_ys_sigma),
                                      "tool.z": (-(estimate.r - r0), estimate.r_sigma)},
                          detail=detail)

    def compensate(self, identified: Identified) -> dict[str, Program]:
        """The pattern program touched off at 0 deg (``pattern_before``, the uncompensated
        state) and rewritten by the identified arm (``pattern_compensated``)."""
        detail = identified.detail
        nominal = self.pattern.program(detail.r0)
        return {"pattern_before": compensate_program(nominal, detail.machine,
                                                     detail.touched_off),
                "pattern_compensated": compensate_program(nominal, detail.machine,
                                                          detail.estimate)}

    def evaluate(self, lab, identified: Identified, programs) -> Evaluation:
        """Cut the pattern before and after compensation and read its apexes (microscopes
        labelled ``"pattern_before"`` and ``"pattern_after"``)."""
        detail = identified.detail
        readings, parts = {}, {}
        for state, program in (("before", programs["pattern_before"]),
                               ("after", programs["pattern_compensated"])):
            part, _ = lab.cut(program, TOOL, self.pattern.stock)
            parts[f"pattern_{state}"] = part
            try:
                readings[state] = measure_pattern(part, self.pattern,
                                                  lab.microscope(label=f"pattern_{state}"))
            except InputError:
                readings[state] = None  # the uncompensated grooves may not be cut at all

        def value(state, attribute):
            reading = readings[state]
            return None if reading is None else getattr(reading, attribute) / M_PER_UM

        figures = (
            Figure("depth_error", "um", value("before", "depth_error"),
                   value("after", "depth_error"), note="paper: > 50 before, < 1 after"),
            Figure("depth_variation", "um", value("before", "depth_variation"),
                   value("after", "depth_variation")),
            Figure("pitch_error", "um", value("before", "pitch_error"),
                   value("after", "pitch_error")),
        )
        return Evaluation(figures=figures, details=self._details(detail, readings, programs),
                          parts=parts)

    def _details(self, detail: ArmIdentification, readings, programs) -> dict:
        nominal = self.pattern.program(detail.r0)
        model = model_based(nominal, detail.machine, detail.model())
        linear, rotary = _axis_difference(model.program, programs["pattern_compensated"],
                                          detail.machine)
        out = {"r0_mm": detail.r0 / M_PER_MM,
               "paper_fit": _estimate(detail.estimate),
               "lateral_fit": _estimate(detail.lateral),
               "fit_check": {"r_mm": detail.check.r / M_PER_MM,
                             "e_ys_um": detail.check.e_ys / M_PER_UM,
                             "r_difference_nm": (detail.check.r - detail.r) / M_PER_NM,
                             "e_ys_difference_nm": (detail.check.e_ys - detail.e_ys) / M_PER_NM},
               "fit_check_lateral": {
                   "r_mm": detail.check_lateral.r / M_PER_MM,
                   "e_ys_um": detail.check_lateral.e_ys / M_PER_UM,
                   "r_difference_nm": (detail.check_lateral.r - detail.lateral.r) / M_PER_NM,
                   "e_ys_difference_nm": (detail.check_lateral.e_ys
                                          - detail.lateral.e_ys) / M_PER_NM},
               "model_based": {"max_linear_axis_difference_nm": linear / M_PER_NM,
                               "max_rotary_axis_difference_urad": from_si(rotary, "urad"),
                               "max_position_residual_nm":
                                   model.max_position_residual / M_PER_NM}}
        for state, reading in readings.items():
            out[f"pattern_{state}"] = ({"measured": False} if reading is None else {
                "depth_um": (reading.depth / M_PER_UM).tolist(),
                "centre_um": (reading.centre / M_PER_UM).tolist()})
        return out


def _estimate(estimate: ArmEstimate) -> dict:
    return {"r_mm": estimate.r / M_PER_MM, "e_ys_um": estimate.e_ys / M_PER_UM,
            "r_sigma_um": estimate.r_sigma / M_PER_UM,
            "e_ys_sigma_um": estimate.e_ys_sigma / M_PER_UM,
            "z_offset_um": estimate.z_offset / M_PER_UM,
            "y_offset_um": estimate.y_offset / M_PER_UM}


def _axis_difference(a: Program, b: Program, machine) -> tuple[float, float]:
    """Largest difference of a linear (m) and of a rotary (rad) axis between two programs of
    the same blocks."""
    difference = np.abs(program_axes(a, machine) - program_axes(b, machine))
    rotary = np.asarray(machine.rotary)
    return float(difference[:, ~rotary].max()), float(difference[:, rotary].max())
