"""Paper 004 as an experiment: slow-tool-servo turning with every error factor compensated
before the cut, the form error predicted and then measured.

`STSTurning` runs paper 004's flow (Fig. 14) on a `machinesim.Lab` with machine ``sts_lathe``
whose tool carries setting errors dx, dy (``tool.x``, ``tool.y``) and a nose radius error dR
(``tool_geometry.nose_radius``), and whose axes follow through servo loops
(`machinesim.servo`):

1. *measure*: a test sphere and a tilted test plane turned with the tool and read by the
   white-light interferometer (`sts_plans.TEST_SPHERE`, `TEST_PLANE`);
2. *identify*: dx, dR and |dy| from the sphere, the signed dy from the plane
   (`machinesim.identification.turning_tool`);
3. *compensate*: the programs of the four cases (`PROGRAM_OF`): as found (Table 4
   "before", nose compensation for the nominal R, Case 1); compensated for R + dR (eqs
   18-19, Case 2); modified (Table 4 "after", for R + dR, Cases 3 and 4);
4. *evaluate*: the cases in order on the one lab, as the paper's operator did: Case 1; the
   tool-workpiece alignment (the tool moved by -dx and -dy with the holder's adjuster, the
   residual read by a second test cut); Cases 2 and 3; the
   servo tuned to Table 6 "after" (`Lab.tune_servo`); Case 4. Before each cut the form error
   is predicted from what the lab can know: the program, the identified tool errors, and the
   follow-up error the control's encoders record for that program (`sts_prediction`); then
   the part is turned and measured (`sts_plans.MEASURE_LINE`, `SA_WINDOW`).

The truth stays in the lab: the prediction uses the nominal machine, the identified tool
errors and the encoder recording, never the injected values (docs/procedures/sts_turning.md).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from machinesim.cam import spiral as sp
from machinesim.cutting.lathe import turning_tool
from machinesim.exceptions import InputError, MachineSimWarning, NotConvergedError
from machinesim.experiment import Evaluation, Figure, Identified, check_lab
from machinesim.identification.turning_tool import fit_centre_height, identify_tool_errors
from machinesim.metrology.fits import roughness_sa
from machinesim.procedures.step_inputs import (
    check_identified,
    check_measurements,
    check_programs,
)
from machinesim.procedures.sts_cases import (
    CASES,
    GRID_TOP,
    PROGRAM_OF,
    CaseResult,
    details,
    uncut_share,
)
from machinesim.procedures.sts_plane_check import refuse_plane_misfit
from machinesim.procedures.sts_plans import (
    MEASURE_LINE,
    PAPER,
    PAPER_BOUNDS,
    PLANS,
    SA_L_CUTOFF,
    SA_WINDOW,
    TEST_PLANE,
    TEST_SPHERE,
    profile_error,
)
from machinesim.procedures.sts_prediction import predict
from machinesim.servo import TABLE6, table6_servo

__all__ = ["CASES", "PROGRAM_OF", "STSTurning", "test_cut"]

NM, UM = 1e-9, 1e-6

#: Largest misfit (m) of the test sphere's fit, its residual RMS less the interferometer's
#: stated noise in quadrature, for which the tool errors are taken: the exact form
#: (`identify_tool_errors`) describes the sphere where the nose does not reach across the
#: spindle axis, so a tip far outside the axis (dx above about +5 um) or far across it leaves
#: a misfit, and dR comes out wrong. Measured through the lab (docs/procedures/sts_turning.md,
#: "Identifying the tool errors"): dx -10 .. +5 um misfit 0.06-0.43 nm, dR within 0.6 %;
#: +7 um 0.78-0.82 nm, dR 2 % off; +10 um 1.7 nm, 8 % off; +-20 um 3.9-7.3 nm, dR 12-88 % off.
SPHERE_MISFIT_LIMIT = 0.6 * NM
#: The radial offsets dx (m) within which the test sphere reads dR within 0.6 % (above).
DX_RANGE = (-10 * UM, 5 * UM)
#: The nose radius errors dR (m) the test sphere reads, within 0.4 % (through the lab, dx = dy
#: = -3.5 um, noise on or off): -850 um reads -852.8, +300 um 299.4. Beyond, the exact form
#: no longer describes the sphere: -900 um leaves a misfit of 0.81-0.85 nm, +320 um 0.64-0.80
#: nm, +350 um 1.9 nm, +400 um 5.5 nm, and from about +450 um the sphere's flat top reads as
#: an uncut core (26 um at +500 um, 85 um at +1 mm: Table 1's printed 2 mm nose).
D_RADIUS_RANGE = (-850 * UM, 300 * UM)
#: Largest uncut core (|dy| read from the sphere, m) for which the tool test is taken: the
#: plane's fit leaves out 30 um about the axis (`TEST_PLANE.core`); through the lab (noise
#: off) dy = 10 um is read 0.4 % off, 15 and 20 um 1.7-2 %, 30 um 12 %, and at 40 um the
#: sphere still fits (0.08 nm) but reads dR -1815 um for 100 um. The plane's residual check
#: (`sts_plane_check`) takes less: with dR 100 um, dx down to about -6 um at dy 0 and |dy| up
#: to about 8 um at dx -3.5 um, with dR 300 um dx to about -4.6 um at dy 0; with dR -850 um
#: dx to about -5 um whatever |dy| (up to 12 um), where the cause is the turned plane's rim
#: inside the read disc, not the core (`sts_plane_check.turned_rim`); scenarios/sts_turning.py
#: refuses the rest before the cut (`refuse_unfit_plane`).
CORE_LIMIT = 20 * UM
#: Deepest (m) the test sphere may be cut below its programmed surface for the tool test:
#: the plan cuts it 1 to 4.6 um deep (the stock's top `TEST_SPHERE.top` over the sphere's
#: pole and its rim), and a tool or workpiece set lower in Z cuts it deeper, the uncut core
#: left that much taller. Through the lab (Table 5's tool errors, a workpiece set 2.9, 5, 8,
#: 10 and 15 um high) the fit read dx and dR as for 0 (99.88 um for 100, each in 14-25 s,
#: `identification.turning_tool.PISTON_START`); 20 um high it read dR = -1815 um, and 50 um
#: high it gave up after 250 s.
DEPTH_RANGE = 15 * UM
#: How far (a fraction of the end) a reading may lie beyond `DX_RANGE`, `D_RADIUS_RANGE` or
#: `CORE_LIMIT` and still be taken when the sphere fits (`_refuse_out_of_range`): set at the
#: ends, the fit reads a little beyond them (through the lab, noise on or off: dx -10 um reads
#: -10.013, +5 um 4.98; dR -850 um -852.8, +300 um 299.4; the plane reads dy 20 um 1.7-2 %
#: off).
READ_MARGIN = 0.05

@dataclass(frozen=True)
class ToolTest:
    """The tool errors as a test cut shows them, m: dx, dR and |dy| from the test sphere,
    the signed dy from the tilted plane (`sts_plans.TEST_PLANE`); each ``*_std`` the fit's
    first-order standard uncertainty of it, m (`machinesim.identification.turning_tool`),
    NaN where not given."""

    dx: float
    dy: float
    d_radius: float
    dy_abs: float
    dx_std: float = float("nan")
    dy_std: float = float("nan")
    d_radius_std: float = float("nan")


def test_cut(lab, nose_radius: float, tool: str, label: str) -> ToolTest:
    """Turn the test sphere and the tilted test plane with ``tool`` (programs compensated
    for ``nose_radius``) and read the tool errors from the interferometer's maps.

    Refused (`InputError`, key ``tool_test``), saying what the readings show and which
    settings can cause it: a test piece the tool did not cut (`TurningReport.empty_cut`); a
    sphere with no cut pixel in the interferometer's window; an uncut core wider than
    `CORE_LIMIT`; a sphere that does not fit the tool-error model (misfit above
    `SPHERE_MISFIT_LIMIT`), blamed on dx when the fit reads it outside `DX_RANGE`, else on
    dR when the fit reads it outside `D_RADIUS_RANGE`; a sphere that fits but reads dx or dR
    outside those ranges (`_refuse_out_of_range`); a plane that reads dy beyond
    `CORE_LIMIT`, or that does not fit its model with the sphere's dR known (misfit above
    `sts_plane_check.PLANE_MISFIT_LIMIT`). The plane is turned and read only once the sphere
    is taken: a refused sphere is refused without it (each instrument draws from its own
    stream, so the readings do not depend on that order)."""
    # the interferometers' stated height and lateral noise (m)
    stated, lateral = {}, {}

    def turned(piece, plan):
        """The height map of the test ``piece`` turned by ``plan``."""
        part, report = lab.turn(sp.spiral_program(plan.path(nose_radius)), tool, top=plan.top)
        if report.empty_cut:
            raise InputError(f"{label}: the test {piece} was not cut; the turn reports "
                             f"{report.notes[0]}", key="tool_test")
        w = plan.read_half_width
        interferometer = lab.white_light_interferometer(label=f"{label}_{piece}")
        stated[piece] = interferometer.readout.std
        lateral[piece] = interferometer.lateral_sigma
        return interferometer.height_map(part, -w, w, -w, w, plan.pixel)

    sphere = turned("sphere", TEST_SPHERE)
    _refuse_unseen_cut(sphere, label)
    depth = _depth_from_design(sphere)
    if depth < -(DEPTH_RANGE + depth_slack()):  # the fit would take minutes to fail
        raise InputError(f"{label}: {_too_deep(depth)}", key="tool_test")
    try:
        found = identify_tool_errors(TEST_SPHERE.design(), sphere.x, sphere.y, sphere.z,
                                     core_step=TEST_SPHERE.core_step,
                                     aperture=TEST_SPHERE.read_half_width,
                                     lateral_sigma=lateral["sphere"])
    except NotConvergedError as exc:
        raise InputError(f"{label}: {exc}; the turned test sphere lies "
                         f"{_depth_from_design(sphere) / UM:+.4g} um from the design's heights "
                         "(median over the window; the tool-error model takes a sphere cut a "
                         "few um deep). A tool or workpiece set that far in Z (tool.z, "
                         "workpiece.z) cuts so, or a tool far off the spindle axis (tool.x, "
                         "tool.y): set them within a few um first", key="tool_test") from None
    reads = (f"the fit reads dx {found.dx / UM:.2f} um, dR {found.d_radius / UM:.2f} um, "
             f"|dy| {found.dy_abs / UM:.2f} um")
    if found.dy_abs > CORE_LIMIT:
        raise InputError(
            f"{label}: the turned test sphere has an uncut centre {found.dy_abs / UM:.2f} um "
            f"in radius (pixels more than {TEST_SPHERE.core_step / NM:g} nm above the fitted "
            f"sphere; {reads}); the tool test reads an uncut core, |dy|, up to "
            f"{CORE_LIMIT / UM:g} um. A tool that far off the centre height (tool.y), or set "
            f"so high that the top of the sphere stays uncut (tool.z more than about "
            f"{TEST_SPHERE.top / UM:g} um up: the stock's top over the sphere), leaves it, and "
            f"so does a nose radius more than about {D_RADIUS_RANGE[1] / UM:+g} um larger than "
            "the one the programs are compensated for (tool_geometry.nose_radius): set the "
            "tool that close first, as the paper's tool was, with a nose of about that radius",
            key="tool_test")
    noise = stated["sphere"]
    misfit = float(np.sqrt(max(found.residual_rms**2 - noise**2, 0.0)))
    if misfit > SPHERE_MISFIT_LIMIT:
        low, high = DX_RANGE
        smallest, largest = D_RADIUS_RANGE
        if not low <= found.dx <= high:
            cause = (f"The dx read is outside the range this test identifies (dx from about "
                     f"{low / UM:+g} to {high / UM:+g} um, docs/procedures/sts_turning.md): "
                     "set the tool that close first, as the paper's tool was")
        elif not smallest <= found.d_radius <= largest:
            cause = (f"The dR read is outside the range this test identifies (dR from about "
                     f"{smallest / UM:+g} to {largest / UM:+g} um, "
                     "docs/procedures/sts_turning.md): the tool's nose radius is that far "
                     "from the one the programs are compensated for (tool_geometry.nose_radius, "
                     "or a tool of another radius than the procedure's); use a tool within it")
        else:
            cause = ("The dx, |dy| and dR read are within the test's range, so the misfit is "
                     "something the tool-error model leaves out: the tool's height (tool.z "
                     "above the sphere's top leaves a flat uncut top), its rotation (tool.rx, "
                     "tool.ry, tool.rz), the workpiece's setting (workpiece.*) or the machine's "
                     "geometric errors; check them, or whether dx itself, read from a "
                     "misfitting sphere, is off")
        raise InputError(
            f"{label}: the turned test sphere does not fit the tool-error model: residual "
            f"RMS {found.residual_rms / NM:.2f} nm against the interferometer's stated "
            f"{noise / NM:.2f} nm, a misfit of {misfit / NM:.2f} nm (at most "
            f"{SPHERE_MISFIT_LIMIT / NM:.2f} nm); {reads}. {cause}",
            key="tool_test")
    _refuse_out_of_range(found, misfit, depth, nose_radius, label)
    plane = turned("plane", TEST_PLANE)
    centre = fit_centre_height(plane.x, plane.y, plane.z, TEST_PLANE.slope,
                               aperture=TEST_PLANE.read_half_width, core=TEST_PLANE.core,
                               dx=found.dx, noise=stated["plane"],
                               lateral_sigma=lateral["plane"], d_radius=found.d_radius)
    if abs(centre.dy) > CORE_LIMIT * (1.0 + READ_MARGIN):
        raise InputError(
            f"{label}: the turned test plane reads dy {centre.dy / UM:+.2f} um, outside the "
            f"-{CORE_LIMIT / UM:g} to +{CORE_LIMIT / UM:g} um this test identifies (with "
            f"{READ_MARGIN:.0%} for what it reads off at the ends), while the sphere's uncut "
            f"core reads |dy| {found.dy_abs / UM:.2f} um: not a centre height to compensate "
            "with. A tool that far off the centre height (tool.y) leaves a wider core, so the "
            "plane's fit read the form of something else (the plane's setting, tool.z, "
            "workpiece.*, or the tool's rotation, tool.rx, tool.ry, tool.rz): set them within "
            "a few um first", key="tool_test")
    refuse_plane_misfit(centre, found, stated["plane"], lateral["plane"], label)
    return ToolTest(found.dx, centre.dy, found.d_radius, found.dy_abs, dx_std=found.dx_std,
                    dy_std=centre.dy_std, d_radius_std=found.d_radius_std)


def _refuse_out_of_range(found, misfit: float, depth: float, nose_radius: float,
                         label: str) -> None:
    """Refuse a fit that reads dx outside `DX_RANGE` or dR outside `D_RADIUS_RANGE` (each
    widened by `READ_MARGIN`) however small its residual: the fit can settle on a wrong
    minimum that fits as well as the right one (dR = -1815 um for 100, RMS 0.083 nm: a
    sphere cut 20 um deeper than programmed, or with an uncut core of 40 um, which
    `CORE_LIMIT` refuses first), and such a reading is no tool error to compensate with (a
    nose radius of -815 um for the 1 mm one)."""
    low, high = DX_RANGE
    smallest, largest = D_RADIUS_RANGE
    wide = 1.0 + READ_MARGIN
    out = []
    if not low * wide <= found.dx <= high * wide:
        out.append(f"dx {found.dx / UM:+.2f} um, outside the {low / UM:+g} to {high / UM:+g} um "
                   "it identifies")
    nose = nose_radius + found.d_radius
    impossible = (f" (a nose radius of {nose / UM:+.4g} um for the {nose_radius / UM:g} um "
                  "the programs are compensated for: no tool has one)" if nose <= 0.0 else "")
    nose_out = not smallest * wide <= found.d_radius <= largest * wide
    if nose_out:
        out.append(f"dR {found.d_radius / UM:+.2f} um, outside the {smallest / UM:+g} to "
                   f"{largest / UM:+g} um it identifies{impossible}")
    elif impossible:  # a tool of a smaller nose than the 1 mm the ranges were measured with
        out.append(f"dR {found.d_radius / UM:+.2f} um{impossible}")
    if not out:
        return
    nose_cause = ("" if nose <= 0.0 or not nose_out else
                  ", or a nose radius that far from the one the programs are compensated for "
                  "(tool_geometry.nose_radius)")
    raise InputError(
        f"{label}: the turned test sphere fits the tool-error model (a misfit of "
        f"{misfit / NM:.2f} nm, at most {SPHERE_MISFIT_LIMIT / NM:.2f} nm), but the fit reads "
        f"{'; and '.join(out)} (with {READ_MARGIN:.0%} for what it reads off at their ends; "
        "docs/procedures/sts_turning.md): not a tool error to compensate with. The fit "
        "settled on the form of something else: a sphere cut deeper than programmed (its "
        f"median lies {depth / UM:+.4g} um from the design's heights; tool.z, workpiece.z), "
        f"a tool off the centre height (tool.y; the uncut core reads |dy| "
        f"{found.dy_abs / UM:.2f} um){nose_cause}: set the tool and the workpiece within a "
        "few um first, as the paper's tool was", key="tool_test")


def _too_deep(depth: float) -> str:
    """Why a test sphere cut ``depth`` (m, negative) from its design is not read."""
    return (f"the turned test sphere lies {depth / UM:+.4g} um from the design's heights "
            f"(median over the window), cut deeper than the {DEPTH_RANGE / UM:g} um below "
            f"its programmed surface the tool-error fit reads dx and dR from, with "
            f"{depth_slack() / UM:.2f} um for what dx and dR within the test's ranges move "
            f"the median (the plan cuts it {plan_depths()[0] / UM:.2g} to "
            f"{plan_depths()[1] / UM:.2g} um deep). A tool or workpiece set that far in Z "
            f"(tool.z, workpiece.z) cuts so: set them within {DEPTH_RANGE / UM:g} um first")


def depth_slack() -> float:
    """The most (m) a tool offset dx within `DX_RANGE` and a nose radius error dR within
    `D_RADIUS_RANGE` move the test sphere's heights within its read radius: dx shifts the
    sphere sideways, by dx times its slope, and dR lowers it by dR (1 / cos phi - 1)
    (`machinesim.cutting.tool_form_error.nose_radius_error`, paper 004 eq 20), both largest
    at the read radius. The map's median depth is taken for the tool's height only beyond
    `DEPTH_RANGE` by more than this: 0.50 + 1.06 um."""
    r, rs = TEST_SPHERE.read_half_width, TEST_SPHERE.radius
    slope = r / math.sqrt(rs * rs - r * r)
    return (slope * max(abs(v) for v in DX_RANGE)
            + max(abs(v) for v in D_RADIUS_RANGE) * (math.sqrt(1.0 + slope * slope) - 1.0))


def plan_depths() -> tuple[float, float]:
    """How deep (m) the test sphere's plan cuts, at its pole and at its turned radius: the
    stock's top less the design's heights there."""
    design = TEST_SPHERE.design()
    return tuple(TEST_SPHERE.top - float(design(r, 0.0))
                 for r in (0.0, TEST_SPHERE.turned_radius))


def _depth_from_design(sphere) -> float:
    """Median height (m) of the test sphere's map less the design's, within its read radius
    (negative: cut deeper than programmed)."""
    gx, gy = np.meshgrid(sphere.x, sphere.y)
    rho = np.hypot(gx, gy)
    inside = (rho < TEST_SPHERE.read_half_width) & np.isfinite(sphere.z)
    return float(np.median(sphere.z[inside] - TEST_SPHERE.design()(rho[inside], 0.0)))


def _refuse_unseen_cut(sphere, label: str) -> None:
    """Refuse a test sphere of which the interferometer's window (within its read radius)
    shows no cut: every pixel at the stock's top."""
    gx, gy = np.meshgrid(sphere.x, sphere.y)
    inside = (np.hypot(gx, gy) < TEST_SPHERE.read_half_width) & np.isfinite(sphere.z)
    if (sphere.z[inside] < TEST_SPHERE.top - TEST_SPHERE.core_step).any():
        return
    raise InputError(
        f"{label}: the test sphere was turned, but the interferometer's window (r < "
        f"{TEST_SPHERE.read_half_width / UM:g} um about the workpiece's origin) shows no cut: "
        f"every pixel reads the stock's top ({TEST_SPHERE.top / UM:g} um). The tool cut "
        f"elsewhere: its tip is set more than about {TEST_SPHERE.read_half_width / UM:g} um "
        "off the spindle axis (tool.x, tool.y), or so high that only the sphere's rim, "
        "outside the window, is cut (tool.z), or the workpiece is set that far off the "
        "spindle (workpiece.*); set the tool within a few um first", key="tool_test")


@dataclass(frozen=True)
class STSTurning:
    """Paper 004's procedure (module docstring).

    Attributes
    ----------
    tool : str
        The tool as programmed (Table 1: R 1.0 mm).
    servo_after : str
        The Table 6 preset the control is tuned to before Case 4.
    """

    tool: str = "nose:1.0:90"
    servo_after: str = "after"
    name: ClassVar[str] = "sts_turning"
    paper: ClassVar[str] = "004"
    #: The lab's realism switches this procedure's figures depend on (its error budget).
    realism_sources: ClassVar[tuple[str, ...]] = ("instrument_noise", "lateral_noise",
                                                  "background_errors")
    #: What it reads of the lab beyond the machine's errors, by step
    #: (`machinesim.experiment.LAB_USES`): its round-nose tool's radius, the white-light
    #: interferometer.
    lab_uses: ClassVar[dict[str, tuple[str, ...]]] = {
        "measure": ("tool_geometry", "white_light_interferometer"),
        "evaluate": ("tool_geometry", "white_light_interferometer")}

    def __post_init__(self) -> None:
        # here, not after the test cuts and three cases: a V tool ended in an AttributeError
        # (no nose_radius), an unknown preset at Case 4
        turning_tool(self.tool)
        if not isinstance(self.servo_after, str) or self.servo_after not in TABLE6:
            raise InputError(f"unknown servo preset {self.servo_after!r} for servo_after; "
                             f"expected one of {sorted(TABLE6)} (Table 6)", key="servo_after")

    @property
    def nose_radius(self) -> float:
        return turning_tool(self.tool).nose_radius

    def measure(self, lab) -> dict:
        """The tool test on the machine as found."""
        check_lab(lab)
        return {"tool_test": test_cut(lab, self.nose_radius, self.tool, "tool_test")}

    def identify(self, measurements) -> Identified:
        check_measurements(measurements, "STSTurning", {"tool_test": ToolTest})
        found = measurements["tool_test"]
        return Identified({"tool.x": (found.dx, found.dx_std),
                           "tool.y": (found.dy, found.dy_std),
                           "tool_geometry.nose_radius": (found.d_radius, found.d_radius_std)},
                          detail=found)

    def compensate(self, identified: Identified) -> dict:
        check_identified(identified, "STSTurning", "compensate", ToolTest)
        found = identified.detail
        design = sp.sine_grid()
        compensated = self.nose_radius + found.d_radius
        paths = {"as_found": PLANS["before"].path(design, self.nose_radius),
                 "nose_compensated": PLANS["before"].path(design, compensated),
                 "modified": PLANS["after"].path(design, compensated)}
        return {name: sp.spiral_program(path) for name, path in paths.items()}

    def evaluate(self, lab, identified: Identified, programs) -> Evaluation:
        # at the door: a program missing was a KeyError at its case, after the cases before
        # it were turned and the tool aligned (the lab moved)
        check_lab(lab)
        check_identified(identified, "STSTurning", "evaluate", ToolTest)
        check_programs(programs, "STSTurning", dict.fromkeys(PROGRAM_OF.values()))
        found = identified.detail
        design = sp.sine_grid()
        cases, alignment = {}, {}
        known = found  # the tool errors as the lab knows them before each case
        for name in CASES:
            if name == "case_2":
                known, alignment = self.align(lab, found)
            if name == "case_4":
                lab.tune_servo(table6_servo(self.servo_after))
            radius = self.nose_radius + (0.0 if name == "case_1" else found.d_radius)
            cases[name] = self.run_case(lab, name, programs[PROGRAM_OF[name]], design, known,
                                        radius)
            if cases[name].uncut_note():
                warnings.warn(f"STSTurning{cases[name].uncut_note()}", MachineSimWarning,
                              stacklevel=2)
        return Evaluation(figures=self.figures(cases), details=details(cases, alignment),
                          parts={}, programs={})

    def align(self, lab, found: ToolTest):
        """The tool-workpiece alignment: move the tool by -dx and -dy with the holder's
        adjuster, then read what is left with a second test cut."""
        lab.adjust_tool((-found.dx, -found.dy, 0.0), label="align")
        residual = test_cut(lab, self.nose_radius, self.tool, "tool_test_aligned")
        return residual, {"dx_after_alignment_um": residual.dx / UM,
                          "dy_after_alignment_um": residual.dy / UM,
                          "dy_abs_after_alignment_um": residual.dy_abs / UM,
                          "nose_radius_after_alignment_um": residual.d_radius / UM,
                          "dy_abs_identified_um": found.dy_abs / UM,
                          "dx_after_alignment_std_um": residual.dx_std / UM,
                          "dy_after_alignment_std_um": residual.dy_std / UM,
                          "nose_radius_after_alignment_std_um": residual.d_radius_std / UM}

    def run_case(self, lab, name: str, program, design, known, radius) -> CaseResult:
        """Predict, then turn and measure, one case."""
        recording = lab.encoders(label=f"{name}_encoders").record_turning(program)
        prediction = predict(lab.machine, design, recording, known, self.nose_radius, radius)
        part, report = lab.turn(program, self.tool, top=GRID_TOP)
        wli = lab.white_light_interferometer(label=name)
        start, end, spacing = MEASURE_LINE
        profile = wli.profile(part, start, end, spacing)
        r = profile.xy[:, 0]
        measured = profile_error(r, profile.z, design(r, 0.0 * r))
        x0, x1, y0, y1, step = SA_WINDOW
        window = wli.height_map(part, x0, x1, y0, y1, step)
        gx, gy = np.meshgrid(window.x, window.y)
        sa = roughness_sa(window.x, window.y, window.z - design(gx, gy), l_cutoff=SA_L_CUTOFF)
        return CaseResult(name, prediction, measured.pv, r, measured.residual, sa,
                          report.points, report.machining_time_s,
                          (window.x, window.y, np.asarray(window.z)),
                          uncut_share(profile.z), uncut_share(window.z))

    def figures(self, cases) -> tuple:
        one, four = cases["case_1"], cases["case_4"]
        ends = one.uncut_note() + four.uncut_note()
        rows = [
            Figure("form_error_pv", "nm", one.measured_pv / NM, four.measured_pv / NM,
                   PAPER["case_1"], PAPER["case_4"],
                   note="measured, Case 1 -> Case 4; paper prints um for Case 1, read nm"
                        + ends),
            Figure("form_error_pv_predicted", "nm", one.prediction.total / NM,
                   four.prediction.total / NM,
                   note=f"predicted before cutting; paper: Case 4 < "
                        f"{PAPER_BOUNDS['predicted_case_4']:g} nm"),
            Figure("sa", "nm", one.sa / NM, four.sa / NM,
                   note=f"design removed, L-filter 8 um; paper: Case 4 < "
                        f"{PAPER_BOUNDS['sa']:g} nm{ends}"),
            Figure("program_form_error_pv", "nm", one.prediction.program / NM,
                   four.prediction.program / NM, *PAPER["program"],
                   note="Table 4 before -> after, predicted"),
            Figure("servo_form_error_pv", "nm", cases["case_3"].prediction.servo / NM,
                   four.prediction.servo / NM, *PAPER["servo"],
                   note="Table 6 before -> after, from the encoders' follow-up error"),
        ]
        for name, case in cases.items():
            rows.append(Figure(f"form_error_pv_{name}", "nm", case.prediction.total / NM,
                               case.measured_pv / NM, None, PAPER[name],
                               note="before: predicted, after: measured"
                                    + case.uncut_note()))
        return tuple(rows)
