"""Paper 000 replayed: tool setting error e_ys and arm radius r of a 4-axis planer.

Run: ``.venv/bin/python scenarios/seed000_angle_variable_prisms.py [--e-ys-um -178]
[--r-mm 120.555] [--noise on|off] [--seed N] [--out reports/seed000]`` (about 5 s).

The planer_4axis gets the paper's errors (arm radius r = 120.555 mm against the nominal
120.5 mm, tool setting error e_ys = -0.178 mm). Calibration ramp grooves at 0, 10, 20, 30 and
40 deg are cut and read with the virtual laser microscope; eq 1 is fitted to the depth
changes; the angle-variable prism pattern (0-20 deg by 1 deg, 10 um deep, 20 um pitch, 90-deg
tool) is cut with the edge touched off at 0 deg only (before) and with the program rewritten
by the identified r and e_ys (after), and its apex depths are read again. See
docs/procedures/seed000.md.
"""

from __future__ import annotations

import math
import time

import numpy as np

from machinesim import ErrorModel, ToolSetting, load_machine
from machinesim.cutting import cut
from machinesim.exceptions import InputError
from machinesim.identification import seed000
from machinesim.metrology import Microscope
from machinesim.report import ReportFolder, scenario_arguments
from machinesim.units import M_PER_MM, M_PER_UM

PAPER = {"r_mm": 120.555, "e_ys_um": -178.0, "depth_error_before_um": "> 50",
         "depth_error_after_um": "< 1"}
UM, MM = M_PER_UM, M_PER_MM


def main() -> None:
    parser = scenario_arguments(__doc__.splitlines()[0], "reports/seed000")
    parser.add_argument("--e-ys-um", type=float, default=-178.0,
                        help="injected tool setting error e_ys, um (default -178, the paper's)")
    parser.add_argument("--r-mm", type=float, default=120.555,
                        help="injected arm radius r, mm (default 120.555, the paper's)")
    args = parser.parse_args()
    began = time.perf_counter()
    noise = args.noise == "on"
    machine = load_machine("planer_4axis")
    r0 = seed000.arm_radius(machine)
    r, e_ys = args.r_mm * MM, args.e_ys_um * UM
    # the arm radius error lowers the edge at t = 0; e_ys sets it beside the arm (tool_mount)
    errors = ErrorModel(tool=ToolSetting([0.0, e_ys, -(r - r0)], [0.0, 0.0, 0.0]))
    microscope = Microscope(rng=args.seed, noise=noise)
    out = ReportFolder(args.out)
    print(f"Paper 000 on planer_4axis (nominal arm r0 = {r0 / MM:.3f} mm): injected r = "
          f"{r / MM:.3f} mm, e_ys = {e_ys / UM:.1f} um; microscope noise {args.noise}, "
          f"seed {args.seed}\n")

    plan = seed000.CalibrationPlan()
    calibration = plan.program(r0)
    part, _ = cut(calibration, machine, tool="v:90", stock=plan.stock, errors=errors)
    readings = seed000.measure_calibration(part, plan, microscope)
    paper_fit = seed000.fit_arm(readings, r0)
    joint_fit = seed000.fit_arm(readings, r0, lateral=True)
    out.write_part("calibration.ply", part)
    out.write_program("calibration.nc", calibration)
    print(calibration_table(out, readings, paper_fit))
    print(identification_table(out, r0, r, e_ys, paper_fit, joint_fit))

    pattern = seed000.PrismPattern()
    nominal = pattern.program(r0)
    states = {"before": seed000.touch_off(readings, r0), "after": paper_fit}
    results = {}
    for name, estimate in states.items():
        program = seed000.compensate(nominal, estimate)
        part, _ = cut(program, machine, tool="v:90", stock=pattern.stock, errors=errors)
        out.write_part(f"pattern_{name}.ply", part)
        out.write_program("pattern_compensated.nc" if name == "after" else "pattern_before.nc",
                          program)
        try:
            results[name] = seed000.measure_pattern(part, pattern, microscope)
        except InputError as error:
            print(f"pattern {name}: not measurable ({error})")
            results[name] = None
    print(pattern_tables(out, pattern, results))
    summary = {name: pattern_summary(reading) for name, reading in results.items()}
    out.write_summary(
        injected={"r_mm": r / MM, "e_ys_um": e_ys / UM},
        identified={**estimate_summary(paper_fit),
                    "with_lateral": estimate_summary(joint_fit)},
        before=summary["before"], after=summary["after"],
        paper=PAPER, machine="planer_4axis", noise=noise, seed=args.seed,
        r0_mm=r0 / MM, elapsed_s=time.perf_counter() - began)
    print(f"\nReport written to {out.path} ({time.perf_counter() - began:.1f} s)")


def calibration_table(out, readings, fit) -> str:
    """Per calibration angle: the measured edge rise and shift from 0 deg against eqs 1-2."""
    z0, y0 = readings[0].mean("dz")[0], readings[0].mean("dy")[0]
    rows = []
    for reading in readings:
        (dz, dz_sigma), (dy, _) = reading.mean("dz"), reading.mean("dy")
        rows.append([math.degrees(reading.angle), (dz - z0) / UM, dz_sigma / 1e-9,
                     float(seed000.height_change(reading.angle, fit.r, fit.e_ys, fit.r0)) / UM,
                     (dy - y0) / UM,
                     float(seed000.lateral_change(reading.angle, fit.r, fit.e_ys, fit.r0)) / UM])
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


def identification_table(out, r0, r, e_ys, paper_fit, joint_fit) -> str:
    rows = [["r (mm)", PAPER["r_mm"], r / MM, paper_fit.r / MM, paper_fit.r_sigma / MM,
             joint_fit.r / MM, joint_fit.r_sigma / MM],
            ["e_ys (um)", PAPER["e_ys_um"], e_ys / UM, paper_fit.e_ys / UM,
             paper_fit.e_ys_sigma / UM, joint_fit.e_ys / UM, joint_fit.e_ys_sigma / UM]]
    return out.write_table(
        "identification", ["quantity", "paper", "injected", "eq 1 fit", "sigma",
                           "eqs 1+2 fit", "sigma"], rows,
        title=f"Identified arm (nominal r0 = {r0 / MM:.3f} mm)", digits=6)


def pattern_tables(out, pattern, results) -> str:
    angles = np.degrees(pattern.angles)
    series = {name: reading.depth / UM for name, reading in results.items()
              if reading is not None}
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
    text = out.write_table("pattern_depths", ["angle_deg", "depth_before_um",
                                              "depth_after_um"], rows,
                           title="Apex depth of each prism groove", digits=4)

    def value(name, attribute):
        reading = results[name]
        return math.nan if reading is None else getattr(reading, attribute) / UM

    summary = [
        ["depth error (um)", PAPER["depth_error_before_um"], value("before", "depth_error"),
         PAPER["depth_error_after_um"], value("after", "depth_error")],
        ["depth variation 0-20 deg (um)", "", value("before", "depth_variation"), "",
         value("after", "depth_variation")],
        ["pitch error (um)", "", value("before", "pitch_error"), "",
         value("after", "pitch_error")]]
    return text + "\n" + out.write_table(
        "pattern", ["angle-variable prisms", "paper before", "before", "paper after", "after"],
        summary, title="Prism pattern 0-20 deg, 10 um deep, 20 um pitch", digits=4)


def estimate_summary(fit) -> dict:
    return {"r_mm": fit.r / MM, "e_ys_um": fit.e_ys / UM, "r_sigma_um": fit.r_sigma / UM,
            "e_ys_sigma_um": fit.e_ys_sigma / UM, "z_offset_um": fit.z_offset / UM,
            "y_offset_um": fit.y_offset / UM}


def pattern_summary(reading) -> dict:
    if reading is None:
        return {"measured": False}
    return {"depth_error_um": reading.depth_error / UM,
            "depth_variation_um": reading.depth_variation / UM,
            "pitch_error_um": reading.pitch_error / UM,
            "depth_um": reading.depth / UM}


if __name__ == "__main__":
    main()
