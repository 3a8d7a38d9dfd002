"""Paper 001 as an experiment: the tool edge's offset from the A, B and C rotary centres.

`ToolSetting6Axis` runs paper 001's procedure (Nakamoto et al., 6-axis ROBOnano Ui) on a
`machinesim.Lab` (machine ``robonano_ui``), staged as the paper stages it: each plate
(`machinesim.cam.tool_setting_plates`) is cut with what the earlier ones found, and read
with the lab's confocal microscope only (`machinesim.procedures.tool_setting_6axis_reading`).

0. Touch-off: a groove stepping down in Z finds the Z at which the edge meets the plate.
1. A plate, cut with the touch-off: two sets of two grooves sharing a start point, whose
   end points give dx, dy (`machinesim.identification.tool_setting_6axis.a_axis_sets`).
2. C plate, cut with dx, dy compensated: the triangle's centre gives e (`c_axis_triangle`).
3. B plate, cut with dx, dy compensated: the depths at three B tilts give dZ (eqs 1-2,
   `b_axis_tilts`).

Then the paper's rewrite of the NC data (`corrected_axes` through
`machinesim.compensation.map_program`), and the A, C and B plates cut and read again (Table
1). docs/procedures/tool_setting_6axis.md derives each step.

>>> import machinesim
>>> from machinesim.experiment import run
>>> from machinesim.procedures.tool_setting_6axis import ToolSetting6Axis
>>> lab = machinesim.Lab("robonano_ui", {"tool": {"offset_um": [245.02, 340.06, 150.0]}})
>>> result = run(ToolSetting6Axis(), lab)  # doctest: +SKIP
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import lru_cache, partial
from types import MappingProxyType
from typing import ClassVar

import numpy as np

from machinesim._frozen import reduce_frozen
from machinesim.cam.tool_setting_plates import (
    PARKED,
    SET_LENGTH,
    Plan,
    a_grooves,
    mark_point,
    plate_cuts,
)
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
from machinesim.identification.tool_setting_6axis import (
    AAxisResult,
    CAxisResult,
    Compensation,
    GrooveReading,
    Identification,
    a_axis_sets,
    corrected_axes,
    identify,
    read_stages,
)
from machinesim.identification.tool_setting_6axis_fit import fit_check
from machinesim.identification.tool_setting_6axis_uncertainty import after_std, propagated_std
from machinesim.machines import load_machine
from machinesim.nc import Program
from machinesim.procedures.step_inputs import (
    check_identified,
    check_measurements,
    check_programs,
)
from machinesim.procedures.tool_setting_6axis_reading import a_direction, read_plate, touch_off_z
from machinesim.units import M_PER_NM, M_PER_UM, from_si

__all__ = [
    "DEFAULT_INJECTED", "PAPER_TABLE_1", "Readings", "ToolSetting6Axis", "compensate_program",
    "layout_lines", "read_plate", "touch_off_z",
]

#: The tool of paper 001: a single-crystal diamond V tool, 90 deg included angle.
TOOL = "v:90"
#: Table 1 of paper 001: distances between grooves (um), original and compensated NC data.
PAPER_TABLE_1 = {"a_dx": (490.04, 4.06), "a_dy": (680.12, 2.97), "c_dx": (108.97, 0.74),
                 "c_dy": (852.81, 1.40)}
#: The errors a replay injects by default (scenario and campaign): round values of the
#: paper's order (a tool set by hand, a C centre line found to the better part of a
#: millimetre), chosen so that the "before" distances land within 25 % of Table 1's (2 dx,
#: 2 dy for the A sets; e for the triangle), not Table 1 itself; 150 um along the tool (the
#: paper gives no B value). SI, by `Machine.parameter_names`.
DEFAULT_INJECTED = MappingProxyType({
    "tool.x": 250.0 * M_PER_UM, "tool.y": 350.0 * M_PER_UM, "tool.z": 150.0 * M_PER_UM,
    "location.C.EX0C": 100.0 * M_PER_UM, "location.C.EY0C": 850.0 * M_PER_UM})
#: File stems of the plates as the procedure cuts them, and of the compensated re-cuts.
AS_CUT = {"touch": "00_touch_off_as_cut", "a": "01_a_axis_as_cut", "c": "02_c_axis_as_cut",
          "b": "03_b_axis_as_cut"}
COMPENSATED = {"a": "04_a_axis_compensated", "c": "05_c_axis_compensated",
               "b": "06_b_axis_compensated"}


# ---------------------------------------------------------------------------- compensation


def compensate_program(program: Program, machine, compensation: Compensation) -> Program:
    """A plate program rewritten by the paper's formulas (`corrected_axes`) through
    `machinesim.compensation.map_program` (from `PARKED`, rounded to the machine's
    resolution)."""
    if tuple(machine.axes) != ("X", "Y", "Z", "A", "B", "C"):
        raise InputError(f"Expected a machine with axes X Y Z A B C, got "
                         f"{' '.join(machine.axes)}", key="machine")
    return map_program(program, machine, partial(corrected_axes, compensation=compensation),
                       start=PARKED)


def layout_lines(stage: str, points) -> list[tuple[str, np.ndarray]]:
    """Polylines (label, (k, 2) m) for a layout plot of a measured plate.

    Parameters
    ----------
    stage : str
        ``"a"``: ``points`` are the A grooves' end points (4, 2), each drawn as a groove of
        the programmed length back from it; ``"c"``: the triangle's vertices (3, 2), with
        their centroid.
    points : array_like
        m.
    """
    points = np.asarray(points, dtype=np.float64)
    if stage == "c":
        return [("triangle (crossings)", np.vstack([points, points[:1]])),
                ("centre", points.mean(axis=0)[None, :])]
    if stage != "a":
        raise InputError(f"Expected stage 'a' or 'c', got {stage!r}", key="stage")
    out = []
    for (angle, turn), end in zip(a_grooves(), points, strict=True):
        name = f"A={math.degrees(angle):g} C={math.degrees(turn):g}"
        out.append((f"groove {name}",
                    np.vstack([end - SET_LENGTH * a_direction(angle, turn), end])))
    return out


# ---------------------------------------------------------------------------- procedure


@dataclass(frozen=True, eq=False)
class Readings:
    """What `ToolSetting6Axis.measure` returns: the plates as commanded and as read.

    The plates themselves are not here: their exact meshes and cut reports (the volume
    removed, to the last bit, gives the tool's Z setting) read no instrument, and the
    identification gets only what the microscopes read (docs/lab.md, the honesty rule).
    `evaluate` asks the lab for them again, for the report.

    Attributes
    ----------
    z_touch : float
        The touch-off Z (m).
    a, c, b : tuple of GrooveReading
        The A, C and B plates' grooves, in cutting order.
    programs : Mapping[str, Program]
        File stem (`AS_CUT`) -> the program each plate was cut with.
    registration : Mapping[str, RegistrationScatter or None]
        Plate ("a", "c", "b") -> the stated scatter of its microscope's registration
        (``registration_scatter``; None: read in the workpiece frame), for the uncertainty.
    """

    z_touch: float
    a: tuple[GrooveReading, ...]
    c: tuple[GrooveReading, ...]
    b: tuple[GrooveReading, ...]
    programs: Mapping[str, Program]
    registration: Mapping[str, object] = field(default_factory=dict)

    __reduce__ = reduce_frozen  # pickles (a Result holds it), its read-only mappings too


@lru_cache(maxsize=4)
def _nominal(name: str):
    return load_machine(name)


@dataclass(frozen=True)
class ToolSetting6Axis:
    """Paper 001's procedure: the tool edge's offset d from the A/B centres and the C centre
    line e, and Table 1 before and after compensation.

    Parameters
    ----------
    plan : Plan
        Groove depths, tilts and feed (default: the paper's).
    machine : str
        The machine the programs are written for (a 6-axis X Y Z A B C machine).
    """

    plan: Plan = Plan()
    machine: str = "robonano_ui"
    name: ClassVar[str] = "tool_setting_6axis"
    paper: ClassVar[str] = "001"
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
        check_instance(self.plan, Plan, "plan",
                       "a Plan (machinesim.cam.tool_setting_plates), e.g. Plan()")
        check_instance(self.machine, str, "machine",
                       "the name of a 6-axis X Y Z A B C machine, e.g. 'robonano_ui'")

    def measure(self, lab) -> Readings:
        """Cut and read the four plates in the paper's order, each cut with what the earlier
        ones found (microscopes labelled ``"touch-off"``, ``"a"``, ``"c"``, ``"b"``)."""
        check_lab(lab)
        machine = self._machine()
        if lab.machine.name != machine.name:
            raise InputError(f"{self.name} writes its programs for {machine.name}; the lab "
                             f"has {lab.machine.name}", key="machine")
        cuts = plate_cuts(self.plan)
        plates = {}

        def cut(stage, program):
            part, _ = lab.cut(program, TOOL, cuts[stage].stock, start=PARKED)
            plates[AS_CUT[stage]] = program
            return part

        touch = cut("touch", cuts["touch"].program)
        z_touch = touch_off_z(touch, lab.microscope(label="touch-off"))
        readings, registration = {}, {}

        def stage(name, known):
            program = compensate_program(cuts[name].program, machine, known)
            microscope = lab.microscope(label=name)
            readings[name] = read_plate(name, cut(name, program), microscope, program,
                                        machine, self.plan)
            registration[name] = microscope.registration_scatter
            return readings[name]

        a = a_axis_sets(stage("a", Compensation(z_shift=z_touch)), SET_LENGTH)
        known = Compensation(tool_offset=[a.offset[0], a.offset[1], 0.0], z_shift=z_touch)
        stage("c", known)
        stage("b", known)
        return Readings(z_touch, readings["a"], readings["c"], readings["b"],
                        MappingProxyType(plates), MappingProxyType(registration))

    def identify(self, measurements: Readings) -> Identified:
        """The paper's formulas on the readings (`identify`), with the model-based
        cross-check (`fit_check`) beside them in ``detail.check``.

        Parameters identified (SI, std propagated from the readings'): ``tool.x``,
        ``tool.y``, ``tool.z`` (d, with dZ from the B tilts), ``location.C.EX0C``,
        ``location.C.EY0C`` (e).
        """
        check_measurements(measurements, "ToolSetting6Axis", Readings)
        m = measurements
        found = identify(m.z_touch, m.a, m.c, m.b, SET_LENGTH, self.plan.theta2,
                         self.plan.theta3, mark_at=mark_point(), registration=m.registration)
        machine = self._machine()
        # the fit's covariance holds the readings' own errors, and the plates cut with the A
        # result move with the programs the fit reads (docs/procedures): the registration
        # is what it lacks
        check = fit_check(machine, m.a, m.c, m.b)
        frames = propagated_std(lambda a, c, b: fit_check(machine, a, c, b).values,
                                m.a, m.c, m.b, SET_LENGTH, m.registration,
                                own_errors=False)
        check_std = np.hypot(check.std, frames)
        found = replace(found, check=check, check_std=MappingProxyType(
            dict(zip(check.names, check_std.tolist(), strict=True))), readings=m)
        return Identified(parameters=found.parameters, detail=found,
                          notes=fit_notes("fit_check", check, sigma_leaves_out=(
                              "the microscope's stated registration of each plate"
                              if any(r is not None for r in m.registration.values())
                              else None)))

    def compensate(self, identified: Identified) -> dict[str, Program]:
        """The A, C and B plate programs rewritten by the identified d and e (`COMPENSATED`
        names); no touch-off needed: the tool length is dZ."""
        check_identified(identified, "ToolSetting6Axis", "compensate", Identification)
        cuts = plate_cuts(self.plan)
        compensation = identified.detail.compensation
        return {COMPENSATED[s]: compensate_program(cuts[s].program, self._machine(),
                                                   compensation) for s in "acb"}

    def evaluate(self, lab, identified: Identified, programs) -> Evaluation:
        """Cut the compensated plates, read them (microscopes ``"a/compensated"``, ...), and
        give Table 1: before from the identification's own plates, after from these.

        The parts and cut reports: the plates `measure` cut (the same cuts, asked for again:
        the lab hands them back, `machinesim.Lab.cut`), with their programs, then the
        compensated ones."""
        check_lab(lab)
        check_identified(identified, "ToolSetting6Axis", "evaluate", Identification)
        check_programs(programs, "ToolSetting6Axis", COMPENSATED.values())
        machine = self._machine()
        cuts = plate_cuts(self.plan)
        before: Identification = identified.detail
        parts, reports, after, registration, as_cut = {}, {}, {}, {}, {}
        if before.readings is not None:
            for stage, name in AS_CUT.items():
                as_cut[name] = before.readings.programs[name]
                part, report = lab.cut(as_cut[name], TOOL, cuts[stage].stock, start=PARKED)
                parts[name], reports[name] = part, cut_summary(report)
        for s in "acb":
            name = COMPENSATED[s]
            part, report = lab.cut(programs[name], TOOL, cuts[s].stock, start=PARKED)
            parts[name], reports[name] = part, cut_summary(report)
            microscope = lab.microscope(label=f"{s}/compensated")
            after[s] = read_plate(s, part, microscope, programs[name], machine, self.plan)
            registration[s] = microscope.registration_scatter
        a_after, c_after, b_after = self._stages(after["a"], after["c"], after["b"])
        old, new = (_table(before.a, before.b, before.c), _table(a_after, b_after, c_after))
        spread = dict.fromkeys(old)
        if before.readings is not None:
            m = before.readings
            spread = dict(zip(old, after_std(
                self._table_values, self._compensation_values, (m.a, m.c, m.b),
                (after["a"], after["c"], after["b"]), SET_LENGTH, m.registration,
                registration).tolist(), strict=True))
        figures = tuple(Figure(k, "um", old[k], new[k], *PAPER_TABLE_1.get(k, (None, None)),
                               after_std=spread[k]) for k in old)
        details = {
            "before": _stage_dict(before.a, before.b, before.c),
            "after": _stage_dict(a_after, b_after, c_after),
            "identification": {"touch_off_z_um": before.z_touch / M_PER_UM,
                               "b_dx_um": before.b.offset_x / M_PER_UM},
            "fit_check": _check_dict(before),
            "model_based": self._model_based(before, cuts),
            "plan": {"depth_um": self.plan.depth / M_PER_UM,
                     "b_depth_um": self.plan.b_depth / M_PER_UM,
                     "theta1_deg": math.degrees(self.plan.theta1),
                     "theta2_deg": math.degrees(self.plan.theta2),
                     "theta3_deg": math.degrees(self.plan.theta3)},
            "cuts": reports,
        }
        return Evaluation(figures=figures, details=details, parts=parts, programs=as_cut)

    def _machine(self):
        return _nominal(self.machine)

    def _stages(self, a, c, b):
        """The A, C and B results from one set of plate readings."""
        return read_stages(a, c, b, SET_LENGTH, self.plan.theta2, self.plan.theta3,
                           mark_point())

    def _table_values(self, a, c, b) -> np.ndarray:
        """Table 1's quantities (um) from one set of plate readings, in `_table`'s order."""
        ra, rc, rb = self._stages(a, c, b)
        return np.array(list(_table(ra, rb, rc).values()))

    def _compensation_values(self, a, c, b) -> tuple[np.ndarray, np.ndarray]:
        """The compensation (d, e) (m) the identification finds from plate readings."""
        ra, rc, rb = self._stages(a, c, b)
        return np.r_[ra.offset, rb.offset_z], rc.centre

    def _model_based(self, found: Identification, cuts) -> dict:
        """Both routes of `machinesim.compensation` on the identified model: how far the
        paper's rewrite and the model-based one put the tool edge (and its orientation)
        from where the nominal programs put them, over the A, C and B plates.

        The axis values themselves may differ: at B = 0, A and C turn about parallel axes,
        so the model-based solver may split a rotation between them differently."""
        machine = self._machine()
        model = ErrorModel().with_parameters(found.values)
        worst = {"paper": [0.0, 0.0], "model": [0.0, 0.0]}
        for s in "acb":
            nominal = cuts[s].program
            want = machine.tool_pose(program_axes(nominal, machine, start=PARKED))
            routes = {"paper": compensate_program(nominal, machine, found.compensation),
                      "model": model_based(nominal, machine, model, start=PARKED).program}
            for route, program in routes.items():
                got = machine.tool_pose(program_axes(program, machine, start=PARKED), model)
                position = np.linalg.norm(got[:, :3, 3] - want[:, :3, 3], axis=1).max()
                cosine = (np.trace(np.swapaxes(got[:, :3, :3], 1, 2) @ want[:, :3, :3],
                                   axis1=1, axis2=2) - 1.0) / 2.0
                angle = np.arccos(np.clip(cosine, -1.0, 1.0)).max()
                worst[route] = [max(worst[route][0], float(position)),
                                max(worst[route][1], float(angle))]
        return {f"{route}_route": {"max_edge_position_error_nm": pos / M_PER_NM,
                                   "max_orientation_error_urad": from_si(angle, "urad")}
                for route, (pos, angle) in worst.items()}


def cut_summary(report) -> dict:
    """A `CutReport` as the report's details hold it (units in the keys)."""
    return {"removed_volume_mm3": report.removed_volume_m3 * 1e9,
            "machining_time_s": report.machining_time_s,
            "sweeps_count": report.sweeps,
            "sideways_sweeps_count": report.sideways_sweeps,
            "rapids_that_cut_count": len(report.rapids_that_cut),
            "empty_cut": report.empty_cut}


def _table(a: AAxisResult, b, c: CAxisResult) -> dict[str, float]:
    """Table 1's quantities (um) and the B depth changes, from one set of measured plates."""
    rise = b.depths[1:] - b.depths[0]
    return {"a_dx": a.distances[0, 0] / M_PER_UM, "a_dy": a.distances[0, 1] / M_PER_UM,
            "c_dx": c.centre[0] / M_PER_UM, "c_dy": c.centre[1] / M_PER_UM,
            "b_depth_change_theta2": rise[0] / M_PER_UM,
            "b_depth_change_theta3": rise[1] / M_PER_UM}


def _stage_dict(a, b, c) -> dict:
    return {"a_ends_um": a.ends / M_PER_UM,
            "a_set_relations_um": a.relations / M_PER_UM,
            "a_distance_um": a.distances[0] / M_PER_UM,
            "a_c_centre_um": a.centre / M_PER_UM,
            "c_centre_displacement_um": c.centre / M_PER_UM,
            "c_vertices_um": c.vertices / M_PER_UM,
            "b_depths_um": b.depths / M_PER_UM,
            "b_depth_change_um": (b.depths[1:] - b.depths[0]) / M_PER_UM}


def _check_dict(found: Identification) -> dict:
    """The fit cross-check beside the paper's values, per parameter (um and nm)."""
    check = found.check
    fitted = dict(zip(check.names, check.values, strict=True))
    std = found.check_std
    out = {name: {"paper_um": value / M_PER_UM, "fit_um": fitted[name] / M_PER_UM,
                  "difference_nm": (fitted[name] - value) / M_PER_NM,
                  "paper_std_nm": found.std[name] / M_PER_NM,
                  "fit_std_nm": std[name] / M_PER_NM}
           for name, value in found.values.items()}
    out["rank_count"] = check.rank
    out["normalised_residual_rms_ratio"] = check.normalised_residual_rms
    return out
