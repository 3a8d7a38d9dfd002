"""Paper 000 as an experiment: the tool-rotation arm of a planer (r and e_ys).

`ToolRotationArm` runs paper 000's procedure on a `machinesim.Lab` (machine
``planer_4axis``): cut the calibration ramps (`machinesim.cam.prisms.CalibrationPlan`) at 0,
10, 20, 30 and 40 deg with the nominal program, read them with the lab's laser microscope
(`measure_calibration`), fit eq 1 (`machinesim.identification.tool_rotation_arm.fit_arm`),
rewrite the angle-variable prism pattern (`machinesim.cam.prisms.PrismPattern`) by the
paper's correction (`compensate_program`, through `machinesim.compensation.map_program`),
and cut and read it before (edge touched off at 0 deg only) and after compensation
(`measure_pattern`). The readings live in `machinesim.procedures.tool_rotation_arm_reading`,
the tool and the sizes of the plan and pattern in `machinesim.procedures.tool_rotation_arm_sizing`
(both re-exported here); docs/procedures/tool_rotation_arm.md gives the geometry and figures.

>>> import machinesim
>>> from machinesim.experiment import run
>>> from machinesim.procedures.tool_rotation_arm import ToolRotationArm
>>> lab = machinesim.Lab("planer_4axis", {"tool": {"offset_um": [0, -178, -55]}})
>>> result = run(ToolRotationArm(), lab)  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from machinesim.cam.prisms import CalibrationPlan, PrismPattern
from machinesim.compensation import map_program, model_based, program_axes
from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError
from machinesim.experiment import (
    Evaluation,
    Figure,
    Identified,
    check_instance,
    check_lab,
    fit_notes,
)
from machinesim.identification.tool_rotation_arm import (
    ArmCheck,
    ArmEstimate,
    arm_radius,
    fit_arm,
    fit_check,
    touch_off,
)
from machinesim.nc.program import Program
from machinesim.procedures.step_inputs import (
    check_identified,
    check_measurements,
    check_programs,
)
from machinesim.procedures.tool_rotation_arm_reading import (
    AlignedMicroscope,
    AngleReading,
    PatternReading,
    level_on_land,
    measure_calibration,
    measure_pattern,
    stage_rotation,
    unread_before,
)
from machinesim.procedures.tool_rotation_arm_sizing import (
    PATTERN_FLOOR_M,
    PLAN_EXPECTED,
    PRISM_FLANK_M,
    TOOL,
    check_pattern_fits,
    deepest_before,
    holder_depth,
    max_capture,
    pattern_clearance,
    pattern_height,
)
from machinesim.units import M_PER_MM, M_PER_NM, M_PER_UM, from_si

__all__ = [
    "PATTERN_FLOOR_M", "PRISM_FLANK_M", "TOOL",
    "AlignedMicroscope", "AngleReading", "ArmIdentification", "Calibration", "PatternReading",
    "ToolRotationArm", "arm_correction", "compensate_program", "deepest_before", "holder_depth",
    "level_on_land", "max_capture", "measure_calibration", "measure_pattern",
    "pattern_clearance", "pattern_height", "stage_rotation",
]

#: Set on the pattern `ToolRotationArm` sized itself (its ``pattern`` left None), so that a
#: copy with another plan sizes it again.
_SIZED = "_sized_by_tool_rotation_arm"


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
    """What `ToolRotationArm.measure` returns: the calibration part as read.

    The part itself is not here: its exact mesh read no instrument, and the identification
    gets only what the microscope read (docs/lab.md, the honesty rule). `evaluate` asks the
    lab for it again, for the report (``Evaluation.parts["calibration"]``).

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
    """

    machine: object
    r0: float
    readings: tuple[AngleReading, ...]
    program: Program


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
    pattern : PrismPattern, optional
        The angle-variable prism pattern (default: the paper's 0-20 deg by 1 deg, on a block
        sized for the plan's capture: its 0.5 mm, or `pattern_height` where that is more,
        and its rapids 1 mm up, or `pattern_clearance` where that is more; sized again in
        a copy with another plan, `dataclasses.replace(arm, plan=...)`). Cut before
        compensation, its grooves go down to `deepest_before` (10 um programmed; 1 mm
        capture: 0.357 mm; 2.8 mm: 0.982 mm); a pattern whose ``height`` is below
        `pattern_height`, or whose ``clearance`` is below `pattern_clearance`, is refused,
        naming both.
    """

    plan: CalibrationPlan = CalibrationPlan()
    pattern: PrismPattern | None = None
    name: ClassVar[str] = "tool_rotation_arm"
    paper: ClassVar[str] = "000"
    #: The `machinesim.realism.Realism` switches this procedure feels (it reads with the
    #: microscope only: no probe, no reference artefacts), for an error budget.
    realism_sources: ClassVar[tuple[str, ...]] = (
        "instrument_noise", "lateral_resolution", "lateral_noise", "registration",
        "stage_positioning", "background_errors")
    #: What it reads of the lab beyond the machine's errors, by step
    #: (`machinesim.experiment.LAB_USES`): the microscope; its tool is a V, no robot.
    lab_uses: ClassVar[dict[str, tuple[str, ...]]] = {"measure": ("microscope",),
                                                      "evaluate": ("microscope",)}

    def __post_init__(self) -> None:
        check_instance(self.plan, CalibrationPlan, "plan", PLAN_EXPECTED)
        if self.pattern is None or getattr(self.pattern, _SIZED, False):
            # sized here (again, in a copy with another plan: dataclasses.replace hands it
            # back as given, and it kept the old capture's block and clearance)
            pattern = PrismPattern()
            sizes = {"height": pattern_height(self.plan, pattern),
                     "clearance": pattern_clearance(self.plan, pattern)}
            sizes = {name: value for name, value in sizes.items()
                     if value > getattr(pattern, name)}
            pattern = PrismPattern(**sizes) if sizes else pattern
            object.__setattr__(pattern, _SIZED, True)
            object.__setattr__(self, "pattern", pattern)
        check_instance(self.pattern, PrismPattern, "pattern",
                       "a PrismPattern (machinesim.cam.prisms), e.g. PrismPattern()")
        check_pattern_fits(self.plan, self.pattern)

    def measure(self, lab) -> Calibration:
        """Cut the calibration ramps with the nominal program and read them (microscope
        labelled ``"calibration"``)."""
        check_lab(lab)
        machine = lab.machine
        r0 = arm_radius(machine)
        program = self.plan.program(r0)
        part, _ = lab.cut(program, TOOL, self.plan.stock)
        readings = measure_calibration(part, self.plan, lab.microscope(label="calibration"))
        return Calibration(machine, r0, readings, program)

    def identify(self, measurements: Calibration) -> Identified:
        """Eq 1 fitted to the readings (`fit_arm`), with `fit_check` beside it.

        Parameters identified: ``tool.y`` = e_ys and ``tool.z`` = -(r - r0), SI, with the
        fit's standard uncertainties.
        """
        check_measurements(measurements, "ToolRotationArm", Calibration)
        readings, r0, machine = measurements.readings, measurements.r0, measurements.machine
        estimate = fit_arm(readings, r0)
        detail = ArmIdentification(
            estimate=estimate, lateral=fit_arm(readings, r0, lateral=True),
            touched_off=touch_off(readings, r0), check=fit_check(readings, machine, r0),
            check_lateral=fit_check(readings, machine, r0, lateral=True), machine=machine)
        return Identified(parameters={"tool.y": (estimate.e_ys, estimate.e_ys_sigma),
                                      "tool.z": (-(estimate.r - r0), estimate.r_sigma)},
                          detail=detail,
                          notes=fit_notes("fit_check (heights)", detail.check.estimate)
                          + fit_notes("fit_check (lateral)", detail.check_lateral.estimate))

    def compensate(self, identified: Identified) -> dict[str, Program]:
        """The pattern program touched off at 0 deg (``pattern_before``, the uncompensated
        state) and rewritten by the identified arm (``pattern_compensated``)."""
        check_identified(identified, "ToolRotationArm", "compensate", ArmIdentification)
        detail = identified.detail
        nominal = self.pattern.program(detail.r0)
        return {"pattern_before": compensate_program(nominal, detail.machine,
                                                     detail.touched_off),
                "pattern_compensated": compensate_program(nominal, detail.machine,
                                                          detail.estimate)}

    def evaluate(self, lab, identified: Identified, programs) -> Evaluation:
        """Cut the pattern before and after compensation and read its apexes (microscopes
        labelled ``"pattern_before"`` and ``"pattern_after"``). The parts: the calibration
        part `measure` cut (the same cut, asked for again: the lab hands it back,
        `machinesim.Lab.cut`) and the two patterns."""
        check_lab(lab)
        check_identified(identified, "ToolRotationArm", "evaluate", ArmIdentification)
        check_programs(programs, "ToolRotationArm", ("pattern_before", "pattern_compensated"))
        detail = identified.detail
        calibration, _ = lab.cut(self.plan.program(detail.r0), TOOL, self.plan.stock)
        readings, parts, unread = {}, {"calibration": calibration}, {}
        for state, program in (("before", programs["pattern_before"]),
                                ("after", programs["pattern_compensated"])):
            part, _ = lab.cut(program, TOOL, self.pattern.stock)
            parts[f"pattern_{state}"] = part
            try:
                readings[state] = measure_pattern(part, self.pattern,
                                                  lab.microscope(label=f"pattern_{state}"))
            except InputError as error:
                # the uncompensated grooves may not be cut at all, and a compensation that
                # missed may leave the compensated ones as unreadable: said, not left blank,
                # with what the identified arm says of the uncompensated ones
                why = unread_before(detail.estimate, self.pattern) if state == "before" else None
                readings[state] = None
                unread[state] = str(error) + ("" if why is None else f" ({why})")

        def value(state, attribute):
            reading = readings[state]
            return None if reading is None else getattr(reading, attribute) / M_PER_UM

        why = "".join(f"; {state} not measured, the {what} pattern: {unread[state]}"
                      for state, what in (("before", "uncompensated"),
                                          ("after", "compensated")) if state in unread)
        figures = (
            Figure("depth_error", "um", value("before", "depth_error"),
                   value("after", "depth_error"), note="paper: > 50 before, < 1 after" + why),
            Figure("depth_variation", "um", value("before", "depth_variation"),
                   value("after", "depth_variation"), note=why[2:]),
            Figure("pitch_error", "um", value("before", "pitch_error"),
                   value("after", "pitch_error"), note=why[2:]),
        )
        details = self._details(detail, readings, programs)
        for state, message in unread.items():
            details[f"pattern_{state}"]["why"] = message
        return Evaluation(figures=figures, details=details, parts=parts)

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
