"""Paper 001 replay: tool setting errors of a 6-axis ultraprecision machine (A, B, C axes).

Run: ``.venv/bin/python scenarios/seed001_tool_setting_6axis.py`` (about 5 s with the
defaults, which are small enough for a test) with options

    --tool-offset-um dx,dy,dz   edge offset from the A/B centres, tool_mount axes
                                (default 245.02,340.06,150: half of Table 1's A distances;
                                the paper gives no B value, 150 um is a plausible setting)
    --c-offset-um x,y           C-axis centre line from the edge (default 108.97,852.81,
                                Table 1's C distances)
    --noise on|off --seed N --out DIR   (default reports/seed001)

On robonano_ui with those errors injected, the procedure of
`machinesim.identification.seed001` (touch-off, A pairs, C triangle, B tilts) identifies
them from virtual-microscope readings of the cut grooves, rewrites the NC data, re-cuts and
re-measures. It prints Table 1 of the paper beside the simulated distances before and after
compensation, and writes the report folder: tables (md + json), summary.json, the plates
(PLY), the NC programs as cut and compensated, and groove layout plots.
"""

from __future__ import annotations

import sys

import numpy as np

from machinesim import ErrorModel, ToolSetting, load_machine
from machinesim.cutting import cut
from machinesim.exceptions import MachineSimError
from machinesim.identification import seed001
from machinesim.metrology import Microscope
from machinesim.report import ReportFolder, parse_floats, scenario_arguments

UM = 1e-6
#: Table 1 of paper 001: distances between grooves (um), original and compensated NC data.
PAPER = {"A dx": (490.04, 4.06), "A dy": (680.12, 2.97), "C dx": (108.97, 0.74),
         "C dy": (852.81, 1.40)}


def _um(values):
    return (np.asarray(values, dtype=np.float64) / UM).tolist()


def distances(a, b, c) -> dict[str, float]:
    """Table 1's quantities (um) and the B depth changes, from one set of measured plates."""
    rise = b.depths[1:] - b.depths[0]
    return {"A dx": a.distances[0, 0] / UM, "A dy": a.distances[0, 1] / UM,
            "C dx": c.centre[0] / UM, "C dy": c.centre[1] / UM,
            "B depth change at theta2": rise[0] / UM, "B depth change at theta3": rise[1] / UM}


def stage_dict(a, b, c) -> dict:
    return {"a_x_pair_distance_um": _um(a.distances[0]),
            "a_y_pair_distance_um": _um(a.distances[1]),
            "c_centre_displacement_um": _um(c.centre), "c_vertices_um": _um(c.vertices),
            "b_depths_um": _um(b.depths),
            "b_depth_change_um": _um(b.depths[1:] - b.depths[0])}


def layout_plot(folder, name, before, after, title):
    series = []
    for label, result in (("before", before), ("after", after)):
        for what, xy in seed001.layout_lines(result):
            series.append((f"{label}: {what}", xy[:, 0] / 1e-3, xy[:, 1] / 1e-3))
    folder.plot(name, series, xlabel="x (mm)", ylabel="y (mm)", title=title)


def main(argv=None) -> int:
    parser = scenario_arguments(__doc__.splitlines()[0], "reports/seed001")
    parser.add_argument("--tool-offset-um", default="245.02,340.06,150",
                        help="edge offset dx,dy,dz from the A/B centres (um)")
    parser.add_argument("--c-offset-um", default="108.97,852.81",
                        help="C-axis centre line x,y from the edge (um)")
    args = parser.parse_args(argv)
    try:
        offset = np.array(parse_floats(args.tool_offset_um, 3, "--tool-offset-um")) * UM
        centre = np.array(parse_floats(args.c_offset_um, 2, "--c-offset-um")) * UM
        run(args, offset, centre)
    except MachineSimError as error:
        print(f"seed001: {error}", file=sys.stderr)
        return 2
    return 0


def run(args, offset, centre) -> None:
    machine = load_machine("robonano_ui")
    errors = ErrorModel(tool=ToolSetting(offset, [0.0, 0.0, 0.0]),
                        location={"C": {"EX0C": centre[0], "EY0C": centre[1]}})
    folder = ReportFolder(args.out)
    cuts, reports = [], {}

    def cut_plate(program, stock):
        part, report = cut(program, machine, tool="v:90", stock=stock, errors=errors,
                            start=seed001.PARKED)
        # the first four plates are the procedure's own (touch-off, A, C, B), then the re-cuts
        stage = program.source.split(" ", 1)[1].replace(" ", "_").replace("-", "_").lower()
        name = f"{len(cuts):02d}_{stage}_{'compensated' if len(cuts) >= 4 else 'as_cut'}"
        cuts.append((name, program, part))
        reports[name] = {"removed_volume_mm3": report.removed_volume_m3 * 1e9,
                         "machining_time_s": report.machining_time_s,
                         "sweeps_count": report.sweeps,
                         "sideways_sweeps_count": report.sideways_sweeps,
                         "rapids_that_cut_count": len(report.rapids_that_cut),
                         "empty_cut": report.empty_cut}
        return part

    microscope = Microscope(rng=args.seed, noise=args.noise == "on")
    found = seed001.identify(cut_plate, microscope)
    plates = seed001.plate_cuts()
    after = {}
    for stage in "acb":
        program = seed001.compensate(plates[stage].program, found.compensation)
        after[stage] = seed001.measure(stage, cut_plate(program, plates[stage].stock), microscope)
    for name, program, part in cuts:
        folder.write_program(f"{name}.nc", program)
        folder.write_part(f"{name}.ply", part)

    before_d = distances(found.a, found.b, found.c)
    after_d = distances(after["a"], after["b"], after["c"])
    rows = [[k, *PAPER.get(k, (float("nan"), float("nan"))), before_d[k], after_d[k]]
            for k in before_d]
    table = folder.write_table(
        "table1", ["distance between grooves", "paper original (um)",
                   "paper compensated (um)", "simulated before (um)", "simulated after (um)"],
        rows, title="Paper 001, Table 1: measured machining errors against A and C axis",
        digits=4)
    d, e = found.compensation.tool_offset, found.compensation.c_centre
    # dX: the edge offset the A stage left, in machine X at A = theta1 (docs/procedures)
    plan = seed001.Plan()
    left = offset[:2] - d[:2]
    left_x = left[0] * np.cos(plan.theta1) - left[1] * np.sin(plan.theta1)
    truth = np.r_[offset, centre, left_x, offset[2]]
    got = np.r_[d, e, found.b.offset_x, -found.z_touch]
    names = ["tool dx", "tool dy", "tool dz (B: dZ)", "C centre x", "C centre y",
             "B: dX (left by the A stage)", "tool length from touch-off"]
    ident = folder.write_table(
        "identification", ["quantity", "injected (um)", "identified (um)", "error (nm)"],
        [[n, t / UM, g / UM, (g - t) * 1e9] for n, t, g in zip(names, truth, got, strict=True)],
        title="Injected and identified", digits=4)
    layout_plot(folder, "layout_a_axis.png", found.a, after["a"],
                "A-axis grooves from their measured start points")
    layout_plot(folder, "layout_c_axis.png", found.c, after["c"],
                "C-axis triangle from the groove crossings")
    folder.write_summary(
        injected={"tool_offset_um": _um(offset), "c_centre_um": _um(centre)},
        identified={"tool_offset_um": _um(d), "c_centre_um": _um(e),
                    "b_dx_after_a_compensation_um": found.b.offset_x / UM,
                    "touch_off_z_um": found.z_touch / UM,
                    "error_nm": {"tool_offset_nm": ((d - offset) * 1e9).tolist(),
                                 "c_centre_nm": ((e - centre) * 1e9).tolist()}},
        before=stage_dict(found.a, found.b, found.c),
        after=stage_dict(after["a"], after["b"], after["c"]),
        paper_table1={f"{k.replace(' ', '_').lower()}_{w}_um": v[i] for k, v in PAPER.items()
                      for i, w in enumerate(("original", "compensated"))},
        plan={"depth_um": plan.depth / UM, "b_depth_um": plan.b_depth / UM,
              "theta1_deg": np.degrees(plan.theta1), "theta2_deg": np.degrees(plan.theta2),
              "theta3_deg": np.degrees(plan.theta3)},
        cuts=reports, machine="robonano_ui", noise=args.noise, seed=args.seed,
        paper="001_344dbe0517c0ab8a")
    print(table)
    print(ident)
    print(f"report folder: {folder.path}")


if __name__ == "__main__":
    sys.exit(main())
