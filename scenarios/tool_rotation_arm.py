"""Paper 000 replayed: tool setting error e_ys and arm radius r of a 4-axis planer.

Run: ``.venv/bin/python scenarios/tool_rotation_arm.py [--e-ys-um -178] [--r-mm 120.555]
[--capture-mm 1] [--realism ideal|noise_only|lab] [--budget on|off] [--jobs N]
[--errors FILE.toml] [--noise on|off] [--seed N] [--out reports/tool_rotation_arm]``
(about 21 s on two idle cores with the default lab realism and its error budget; 5 s with
``--budget off``; 3 s with ``--realism noise_only``). ``--jobs N``: the budget's reruns
N at a time, each on a worker process (default 1, one after the other here; the same
budget either way, docs/budget.md).

The planer_4axis gets the paper's errors (arm radius r = 120.555 mm against the nominal
120.5 mm, tool setting error e_ys = -0.178 mm: ``tool.y = e_ys``, ``tool.z = -(r - r0)``),
or those of ``--errors`` with ``--e-ys-um`` / ``--r-mm`` on top when given. The procedure
(`machinesim.procedures.tool_rotation_arm.ToolRotationArm`) cuts calibration ramp grooves at
0, 10, 20, 30 and 40 deg, reads them with the lab's laser microscope, fits eq 1 to the depth
changes, and cuts the angle-variable prism pattern (0-20 deg by 1 deg, 10 um deep, 20 um
pitch, 90-deg tool) with the edge touched off at 0 deg only (before) and with the program
rewritten by the identified r and e_ys (after). The lab is as real as ``--realism`` says
(default ``lab``: the microscope's spot, lateral noise and stage registration, and the
planer's own residual errors, docs/metrology.md); the error budget reruns it with each of
those switched off in turn (docs/budget.md). See docs/procedures/tool_rotation_arm.md.
"""

from __future__ import annotations

import machinesim.scenario_start  # noqa: F401  (first: Ctrl-C while loading is one line)

import math
import time

import numpy as np

from machinesim import load_machine
from machinesim._arguments import typed_number
from machinesim.budget import LabInputs, realism_budget
from machinesim.cam.prisms import CalibrationPlan
from machinesim.exceptions import InputError
from machinesim.experiment import run
from machinesim.identification.tool_rotation_arm import (
    arm_radius,
    height_change,
    lateral_change,
)
from machinesim.procedures.tool_rotation_arm import TOOL, ToolRotationArm, max_capture
from machinesim.report import ReportFolder
from machinesim.scenario_runs import (
    injected_errors,
    progress_printer,
    realism_from,
    realism_options,
    refuse_beyond_capture,
    run_scenario,
    scenario_arguments,
)
from machinesim.units import M_PER_MM, M_PER_NM, M_PER_UM

PAPER = {"r_mm": 120.555, "e_ys_um": -178.0, "depth_error_before_um": "> 50",
         "depth_error_after_um": "< 1"}
UM, MM = M_PER_UM, M_PER_MM
#: Largest --capture-mm, 2.848 (`max_capture` of the paper's plan and tool): a ramp goes
#: down to its search range, capture + 36 um, and an offset of length capture can put the
#: edge that much lower again; at 40 deg the top of the 10 mm tool body, where its holder
#: begins, stands only 10 cos 40 - 3 sin 40 = 5.732 mm over the edge.
MAX_CAPTURE_MM = max_capture() / MM
#: Decimals of the identification table (r in mm, e_ys in um) and of the header's injected
#: r and e_ys, which the table's "injected" column repeats.
IDENTIFICATION_DIGITS = 6


#: Printed under the identification when the machine's background errors are on.
BACKGROUND_NOTE = (
    "The procedure finds r and e_ys from the real rotation axis. With the machine's "
    "background errors on, that axis sits 0.3 um off its nominal place in y and z "
    "(models/errors/background_planer_4axis.toml): the identified values include that, "
    "the sigma does not (docs/procedures/tool_rotation_arm.md).")

def main() -> None:
    parser = scenario_arguments(__doc__.splitlines()[0], "reports/tool_rotation_arm")
    parser.add_argument("--e-ys-um", type=typed_number, default=None,
                        help="injected tool setting error e_ys (tool.y), um (default -178, "
                        "the paper's)")
    parser.add_argument("--r-mm", type=typed_number, default=None,
                        help="injected arm radius r, mm: tool.z = -(r - r0) (default 120.555, "
                        "the paper's)")
    parser.add_argument("--capture-mm", type=typed_number, default=None,
                        help="largest edge offset |(e_ys, r - r0)| the calibration ramps find, "
                        f"mm (default 1; the ramps grow with it; at most {MAX_CAPTURE_MM:.4g}: "
                        "deeper ramps would take the top of the tool's "
                        f"{TOOL.height / MM:g} mm body, where its holder begins, under the "
                        "stock at 40 deg)")
    realism_options(parser)
    run_scenario(report, parser.parse_args())


def report(args) -> None:
    began = time.perf_counter()
    plan = calibration_plan(args.capture_mm)
    machine = load_machine("planer_4axis")
    r0 = arm_radius(machine)
    defaults = {"tool.y": PAPER["e_ys_um"] * UM, "tool.z": -(PAPER["r_mm"] * MM - r0)}
    given = {}
    if args.e_ys_um is not None:
        given["tool.y"] = args.e_ys_um * UM
    if args.e_ys_um is not None and not math.isfinite(args.e_ys_um):
        raise InputError(f"--e-ys-um {args.e_ys_um!r}: expected a length in um",
                         key="e-ys-um")
    if args.r_mm is not None:
        if not (math.isfinite(args.r_mm) and args.r_mm > 0.0):
            raise InputError(f"--r-mm {args.r_mm!r}: expected the arm radius, a length in mm "
                             f"above 0 (the nominal arm is r0 = {r0 / MM:.3f} mm, and the "
                             "plan finds r within --capture-mm of it)", key="r-mm")
        given["tool.z"] = -(args.r_mm * MM - r0)
    read = injected_errors(args, defaults, {}, machine.name)  # the file read (and noted) once
    base = read.parameters()
    check_offset(args, plan.capture, r0, given.get("tool.y", base.get("tool.y", 0.0)),
                 -given.get("tool.z", base.get("tool.z", 0.0)))
    errors = read.with_parameters(given) if given else read
    realism = realism_from(args)

    # plain data, so that --jobs can build the budget's labs on worker processes
    make_lab = LabInputs(machine, errors, seed=args.seed)

    lab = make_lab(realism)
    injected = lab.reveal(background=False).parameters()
    r, e_ys = r0 - injected["tool.z"], injected["tool.y"]
    print(header(r0, r, e_ys, realism, args.seed))

    procedure = ToolRotationArm(plan=plan)
    stage = progress_printer("tool_rotation_arm")
    result = run(procedure, lab, progress=stage("run"))
    budget = realism_budget(procedure, result, realism, make_lab, args.budget == "on",
                            progress=stage, jobs=args.jobs)
    out = ReportFolder(args.out)
    calibration, detail = result.measurements, result.identification.detail
    out.write_program("calibration.nc", calibration.program)
    print(calibration_table(out, calibration.readings, detail.estimate))
    print(identification_table(out, r0, r, e_ys, detail))
    if realism.background_errors:
        print(BACKGROUND_NOTE + "\n")
    print(pattern_tables(out, procedure.pattern, result.evaluation.details))
    print(paper_table(out, result))
    print(out.write_result(result, budget=budget))
    out.publish(last=True)
    print(f"Report written to {out.final} ({time.perf_counter() - began:.1f} s)")


def calibration_plan(capture_mm) -> CalibrationPlan:
    """The paper's plan, with ``--capture-mm`` when given."""
    if capture_mm is None:
        return CalibrationPlan()
    if not (math.isfinite(capture_mm) and 0.0 < capture_mm <= MAX_CAPTURE_MM):
        raise InputError(f"--capture-mm {capture_mm!r}: expected a length in mm above 0 and "
                         f"at most {MAX_CAPTURE_MM:.4g} (larger ramps go so deep that for an "
                         "edge offset near the capture the top of the tool's "
                         f"{TOOL.height / MM:g} mm body, where its holder begins, comes under "
                         "the stock at 40 deg)", key="capture-mm")
    return CalibrationPlan(capture=capture_mm * MM)


#: How far past the capture an edge offset may lie and still be taken as at it (m): the
#: rounding of r - r0 in metres, not an offset the ramps would miss.
CAPTURE_ROUNDING_M = 1e-12


def check_offset(args, capture: float, r0: float, e_ys: float, rho: float) -> None:
    """Refuse, naming the options that set it, an edge offset (e_ys, r - r0) (m) longer than
    the plan's ``capture`` (m), the length its ramps find: every offset within it is found
    and cut (up to `MAX_CAPTURE_MM`), so e_ys is admitted within +-sqrt(capture**2 - (r -
    r0)**2) at the given r, and r within r0 +- sqrt(capture**2 - e_ys**2) at the given e_ys.
    """
    length = math.hypot(e_ys, rho)
    # r - r0 in metres rounds: --r-mm 121.5 is 1.0000000000000009 mm off r0 = 120.5 mm, at
    # the capture of 1 mm as given; 1 pm is far below any edge the ramps resolve
    if length <= capture + CAPTURE_ROUNDING_M:
        return

    def room(other):
        return math.sqrt(capture ** 2 - other ** 2) if abs(other) <= capture else None

    half = room(rho)
    e_ys_range = (f"e_ys within +-{math.floor(half / UM * 100) / 100:.2f} um at r - r0 = "
                  f"{rho / UM:.2f} um" if half is not None else
                  f"no e_ys at r - r0 = {rho / UM:.6g} um")
    half = room(e_ys)
    r_range = (f"r within {math.ceil((r0 - half) / MM * 1e4) / 1e4:.4f} to "
               f"{math.floor((r0 + half) / MM * 1e4) / 1e4:.4f} mm at e_ys = "
               f"{e_ys / UM:.2f} um" if half is not None else
               f"no r at e_ys = {e_ys / UM:.6g} um")
    shown = f"{length / MM:.6g}"
    if shown == f"{capture / MM:.6g}":  # just beyond: as many digits as tell them apart
        shown = f"{length / MM:.12g}"
    # without --e-ys-um or --r-mm the offset is the error file's, or the paper's own with a
    # --capture-mm below it
    refuse_beyond_capture(
        args, {"--e-ys-um": (args.e_ys_um, e_ys_range), "--r-mm": (args.r_mm, r_range)},
        ("tool.y", "tool.z"), f"the edge offset |(e_ys, r - r0)| = {shown} mm",
        f"{capture / MM:g} mm (--capture-mm, at most {MAX_CAPTURE_MM:.4g})",
        f"--capture-mm at least {math.ceil(length / MM * 1e6) / 1e6:.6f} mm"
        if length <= MAX_CAPTURE_MM * MM else
        f"an offset of at most {MAX_CAPTURE_MM:.4g} mm, the largest capture",
        otherwise=(f"--capture-mm {args.capture_mm!r} with the paper's errors (e_ys = "
                   f"{PAPER['e_ys_um']:g} um, r = {PAPER['r_mm']:g} mm)", "--capture-mm"))


def calibration_table(out, readings, fit) -> str:
    """Per calibration angle: the measured edge rise and shift from 0 deg against eqs 1-2."""
    z0, y0 = readings[0].mean("dz")[0], readings[0].mean("dy")[0]
    rows = []
    for reading in readings:
        (dz, dz_sigma), (dy, _) = reading.mean("dz"), reading.mean("dy")
        rows.append([math.degrees(reading.angle), (dz - z0) / UM, dz_sigma / M_PER_NM,
                     float(height_change(reading.angle, fit.r, fit.e_ys, fit.r0)) / UM,
                     (dy - y0) / UM,
                     float(lateral_change(reading.angle, fit.r, fit.e_ys, fit.r0)) / UM])
    angles = [row[0] for row in rows]
    out.plot("calibration_height_change.png",
             [("measured e_z,total", angles, [row[1] for row in rows]),
              ("eq 1, fitted", angles, [row[3] for row in rows])],
             xlabel="tool angle (deg)", ylabel="edge rise from 0 deg (um)",
             title="Calibration grooves: edge height change (paper 000 eq 1)")
    return out.write_table(
        "calibration", ["angle_deg", "e_z_measured_um", "sigma_nm", "e_z_eq1_um",
                        "e_y_measured_um", "e_y_eq2_um"], rows,
        title="Calibration ramps: edge rise e_z,total and shift e_y,total from 0 deg", digits=4)


def header(r0: float, r: float, e_ys: float, realism, seed: int) -> str:
    """The run's first lines: the injected r and e_ys (m) with the identification table's
    `IDENTIFICATION_DIGITS` decimals, so the two show one value (the nominal r0 as the
    table's title gives it)."""
    digits = IDENTIFICATION_DIGITS
    return (f"Paper 000 on planer_4axis (nominal arm r0 = {r0 / MM:.3f} mm): injected r = "
            f"{r / MM:.{digits}f} mm, e_ys = {e_ys / UM:.{digits}f} um; realism {realism}, "
            f"seed {seed}\n")


def identification_table(out, r0, r, e_ys, detail) -> str:
    paper, joint, check = detail.estimate, detail.lateral, detail.check
    rows = [["r (mm)", PAPER["r_mm"], r / MM, paper.r / MM, paper.r_sigma / MM,
             joint.r / MM, joint.r_sigma / MM, check.r / MM, (check.r - paper.r) / M_PER_NM],
            ["e_ys (um)", PAPER["e_ys_um"], e_ys / UM, paper.e_ys / UM, paper.e_ys_sigma / UM,
             joint.e_ys / UM, joint.e_ys_sigma / UM, check.e_ys / UM,
             (check.e_ys - paper.e_ys) / M_PER_NM]]
    return out.write_table(
        "identification", ["quantity", "paper", "injected", "eq 1 fit", "sigma",
                           "eqs 1+2 fit", "sigma", "fit() check", "check - eq 1 (nm)"], rows,
        title=f"Identified arm (nominal r0 = {r0 / MM:.3f} mm)", digits=IDENTIFICATION_DIGITS)


def pattern_tables(out, pattern, details) -> str:
    angles = np.degrees(pattern.angles)
    series = {state: np.asarray(details[f"pattern_{state}"]["depth_um"])
              for state in ("before", "after") if "depth_um" in details[f"pattern_{state}"]}
    out.plot("pattern_depth.png", [(f"apex depth, {name}", angles, depth)
                                   for name, depth in series.items()],
             xlabel="tool angle (deg)", ylabel="apex depth (um)",
             title="Angle-variable prism pattern before and after compensation",
             hlines=[(pattern.depth / UM, "programmed 10 um")])
    if "after" in series:
        out.plot("pattern_depth_after.png",
                 [("apex depth - 10 um, after", angles, (series["after"] - pattern.depth / UM)
                   * 1e3)], xlabel="tool angle (deg)", ylabel="apex depth - 10 um (nm)",
                 title="Prism pattern after compensation: depth deviation")
    rows = [[float(a)] + [float(series[n][k]) if n in series else math.nan
                          for n in ("before", "after")] for k, a in enumerate(angles)]
    return out.write_table("pattern_depths", ["angle_deg", "depth_before_um",
                                              "depth_after_um"], rows,
                           title="Apex depth of each prism groove", digits=4)


def paper_table(out, result) -> str:
    """The paper's table (its values are bounds, so they stay text) beside the simulated."""
    paper = {"depth_error": (PAPER["depth_error_before_um"], PAPER["depth_error_after_um"])}
    labels = {"depth_error": "depth error (um)",
              "depth_variation": "depth variation 0-20 deg (um)",
              "pitch_error": "pitch error (um)"}

    def cell(value):
        return math.nan if value is None else value

    rows = [[labels[f.name], paper.get(f.name, ("", ""))[0], cell(f.before),
             paper.get(f.name, ("", ""))[1], cell(f.after)] for f in result.figures]
    return out.write_table(
        "pattern", ["angle-variable prisms", "paper before", "before", "paper after", "after"],
        rows, title="Prism pattern 0-20 deg, 10 um deep, 20 um pitch", digits=4)


if __name__ == "__main__":
    main()
