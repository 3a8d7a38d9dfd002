"""Paper 004 replayed: slow-tool-servo turning of a sine grid, its form error predicted.

Every error factor is compensated before the cut, the form error predicted and then measured.

Run: ``.venv/bin/python scenarios/sts_turning.py [--errors FILE.toml] [--noise on|off]
[--realism ideal|noise_only|lab] [--budget on|off] [--jobs N] [--seed N]
[--out reports/sts_turning]``
(about 3 min with the default lab realism and its error budget, which runs it once
more per realism source, 1.55 times the time before the lathe's chord rule; 43 s with
``--budget off`` before it; on 2 idle cores: docs/procedures/sts_turning.md, "Results").
``--jobs N``: the budget's reruns N at a time, each on a worker process (default 1, one
after the other here; the same budget either way, docs/budget.md).

The sts_lathe gets the tool errors of Table 5 "before" (dx = dy = -3.5 um, dR = 100 um) and
the servo loops of Table 6 "before" (`machinesim.servo.table6_servo`), or the errors of
``--errors``. The procedure (`machinesim.procedures.sts_turning.STSTurning`) identifies the
tool errors from a turned test sphere read by the white-light interferometer, then runs the
paper's four cases on the one lab: Case 1 as found, Case 2 after the tool-workpiece alignment
(the tool moved with the holder's adjuster, the program compensated for the measured nose
radius), Case 3 with the modified program (Table 4), Case 4 with the servo tuned (Table 6
"after"). Each case's form error is predicted before the cut (program, tool, servo shares,
Fig. 16) and measured after it along theta = 0, r 150-350 um (Figs 17-18); Sa over 100 x
100 um. Writes summary.json (docs/reports.md), the case table (cases.md), the profiles, the shares,
a 3-D view of the Case 4 surface, the tool against the spindle axis and the errors the tool
test reads as the tool's, exactly and nearly (`machinesim.procedures.sts_aliases`). The white-light
interferometer reads the turned height field without spot or registration (modelled for
meshes only), and without stage positioning (the profile is evaluated over piston and tilt,
not a lateral shift): the lab's realism is used without the three.
"""

from __future__ import annotations

import machinesim.scenario_start  # noqa: F401  (first: Ctrl-C while loading is one line)

import io
import math
import time

import numpy as np

from machinesim._io import write_atomic
from machinesim.budget import LabInputs, realism_budget
from machinesim.cam.spiral import spiral_program
from machinesim.cutting.lathe import turning_tool
from machinesim.cutting.turning import edge_path_from_poses
from machinesim.errors import ErrorModel
from machinesim.experiment import run
from machinesim.identification.turning_tool import fit_centre_height
from machinesim.machines import load_machine
from machinesim.procedures.sts_aliases import (
    ALIAS_NOTE,
    NEAR_ALIAS_NOTE,
    alias_lists,
    alias_rows,
    near_alias_rows,
    term_model,
)
from machinesim.procedures.sts_plane_check import (
    PLANE_MISFIT_LIMIT,
    plane_misfit,
    turned_rim,
)
from machinesim.procedures.sts_plans import PAPER, TABLE5, TEST_PLANE, TEST_SPHERE
from machinesim.procedures.sts_turning import (
    CASES,
    CORE_LIMIT,
    D_RADIUS_RANGE,
    DEPTH_RANGE,
    DX_RANGE,
    STSTurning,
    plan_depths,
)
from machinesim.report import ReportFolder
from machinesim.scenario_runs import (
    errors_file,
    progress_printer,
    realism_from,
    realism_options,
    refuse_beyond_capture,
    run_scenario,
    scenario_arguments,
)
from machinesim.servo import table6_servo
from machinesim.tools import with_nose_radius_error

NM, UM = 1e-9, 1e-6


def default_errors() -> ErrorModel:
    """Table 5 "before": dx, dy (tool.x, tool.y) and dR (tool_geometry.nose_radius)."""
    dx, dy, dr = TABLE5["before"]
    return ErrorModel().with_parameters({"tool.x": dx, "tool.y": dy,
                                         "tool_geometry.nose_radius": dr})


def main() -> None:
    parser = scenario_arguments(__doc__.splitlines()[0], "reports/sts_turning")
    realism_options(parser)
    run_scenario(report, parser.parse_args())


def report(args) -> None:
    began = time.perf_counter()
    machine = load_machine("sts_lathe")  # for the notes on --errors, and the labs
    errors = errors_file(args.errors, machine) if args.errors is not None else default_errors()
    realism = realism_from(args).without("lateral_resolution", "registration",
                                         "stage_positioning")

    # plain data, so that --jobs can build the budget's labs on worker processes
    make_lab = LabInputs(machine, errors, seed=args.seed, servo=table6_servo("before"))

    print(f"Paper 004 on sts_lathe: realism {realism}, seed {args.seed}\n")
    procedure = STSTurning()
    stage = progress_printer("sts_turning")
    lab = make_lab(realism)
    refuse_too_deep(args, lab.machine, errors)
    refuse_too_high(args, lab.machine, errors)
    refuse_unread_tool(args, lab.machine, errors)
    refuse_unfit_plane(args, make_lab(realism.without(*NOISE)), errors)
    result = run(procedure, lab, progress=stage("run"))
    budget = realism_budget(procedure, result, realism, make_lab, args.budget == "on",
                            progress=stage, jobs=args.jobs)
    out = ReportFolder(args.out)
    details = result.evaluation.details
    print(case_table(out, details))
    profiles(out, "profiles.png", result)
    shares(out, "shares.png", details)
    surface_3d(out, "case_4_surface.png", result)
    against_axis = tool_against_axis(out, lab, result)  # before the summary lists the files
    aliases = alias_table(out, lab.machine)
    print(out.write_result(result, budget=budget))
    print(against_axis)
    print(aliases)
    out.publish(last=True)
    print(f"Report written to {out.final} ({time.perf_counter() - began:.1f} s)")


#: The errors that set the tool tip's height against the workpiece, named when it is too low.
HEIGHT_KEYS = ("tool.z", "workpiece.z", "tool.rx", "tool.ry", "workpiece.alpha",
               "workpiece.beta")


def _tip_drop(machine, errors) -> tuple[np.ndarray, np.ndarray]:
    """The test sphere's programmed radii (m, each point of its path) and how far (m) the
    injected ``errors`` put the tool tip below its programmed height there (negative:
    above), through ``machine``'s kinematics."""
    path = TEST_SPHERE.path(STSTurning().nose_radius)
    q = np.zeros((path.x.size, len(machine.axes)))
    for letter, values in (("X", path.x), ("Z", path.z), ("C", path.c)):
        q[:, machine.axes.index(letter)] = values
    return np.abs(path.x), machine.tool_pose(q)[:, 2, 3] - machine.tool_pose(q, errors)[:, 2, 3]


def refuse_too_deep(args, machine, errors) -> None:
    """Refuse, before anything is cut, injected ``errors`` that put the tool tip more than
    `DEPTH_RANGE` below the test sphere's programmed tips (the most over its program, through
    ``machine``'s kinematics), naming the ``--errors`` file and the keys that set the height:
    the tool test would cut the sphere that much deeper and refuse it only after the cut and
    a fit of minutes (a workpiece set 50 um high: about 150 s to 'did not converge')."""
    below = float(np.max(_tip_drop(machine, errors)[1]))
    if below <= DEPTH_RANGE:
        return
    parameters = errors.parameters()
    keys = [name for name in HEIGHT_KEYS if parameters.get(name)] or ["its errors"]
    pole, rim = plan_depths()
    refuse_beyond_capture(
        args, {}, keys,
        f"the tool tip {below / UM:.4g} um below the test sphere's programmed surface",
        f"(the test sphere is cut {pole / UM:.2g} to {rim / UM:.2g} um deep; the tool-error "
        f"fit reads dx and dR from a sphere cut at most {DEPTH_RANGE / UM:g} um deeper)",
        f"the tool tip at most {DEPTH_RANGE / UM:g} um below it (tool.z, workpiece.z)")


def refuse_too_high(args, machine, errors) -> None:
    """Refuse, before anything is cut, injected ``errors`` that put the tool tip higher over
    every point of the test sphere's path within `CORE_LIMIT` (20 um) of its pole than the
    plan cuts there (1 um at the pole, 1.1 um at 20 um), naming the ``--errors`` file and the
    keys that set the height: the sphere's top stays uncut, an uncut core wider than the
    tool test reads, and the test refuses the sphere after the cut and its fit. Through the
    lab (Table 5's tool, noise off): tool.z 0.9 um ran; 1.2 um was refused after the turn
    (the sphere misfits the model by 16 nm), 3.4 um too (an uncut centre 59 um across), 5 um
    as 'no cut' in the window, and 10 um by the plane check before the cut, naming tool.x,
    tool.y and the nose radius for the misfit that tool.z made."""
    radius, drop = _tip_drop(machine, errors)
    core = radius <= CORE_LIMIT
    depth = TEST_SPHERE.top - TEST_SPHERE.design()(radius[core], 0.0)
    if not np.all(-drop[core] > depth):
        return
    parameters = errors.parameters()
    keys = [name for name in HEIGHT_KEYS if parameters.get(name)] or ["its errors"]
    edge = float(np.max(depth))
    refuse_beyond_capture(
        args, {}, keys,
        f"the tool tip {float(np.min(-drop[core])) / UM:.4g} um above the test sphere's "
        "programmed surface",
        f"(the test sphere is cut {float(np.min(depth)) / UM:.2g} to {edge / UM:.2g} um deep "
        f"within {CORE_LIMIT / UM:g} um of its pole, the widest uncut core the tool test "
        "reads: a tip higher than that leaves the sphere's top uncut)",
        f"the tool tip less than {edge / UM:.2g} um above it (tool.z, workpiece.z)")


def refuse_unread_tool(args, machine, errors) -> None:
    """Refuse, before anything is cut, injected ``errors`` whose tool the test sphere does
    not identify: its offset dx from the spindle axis outside `DX_RANGE`, its centre height
    |dy| beyond `CORE_LIMIT` (`tool_from_spindle_axis`, through ``machine``'s kinematics) or
    its nose radius error dR outside `D_RADIUS_RANGE` (one leaving no nose is the tool's
    own refusal, `with_nose_radius_error`'s, asked here: the lab's names the tool as
    commanded, not the file, the key as written or the value, which are its truth), naming
    the ``--errors`` file and the keys. The tool test cut the sphere and refused its reading
    after 13 to 80 s (a nose radius error of 100 mm, um typed for mm: 78 s), blaming the
    sphere's depth or centre height for a dx of -11 um."""
    with_nose_radius_error(turning_tool(STSTurning().tool), errors)
    dx, dy = tool_from_spindle_axis(machine, errors, STSTurning().nose_radius)
    d_radius = errors.parameters().get("tool_geometry.nose_radius", 0.0)
    nose = STSTurning().nose_radius
    (low, high), (smallest, largest) = DX_RANGE, D_RADIUS_RANGE
    slack = 1e-9  # the kinematics' round-off, far under the ranges' own accuracy
    if not low - slack <= dx <= high + slack:
        found, keys = f"the tool's offset from the spindle axis dx = {dx / UM:.4g} um", (
            "tool.x", "location.C.EX0C", "location.C.EY0C")
        expected = f"dx within {low / UM:g} .. {high / UM:g} um"
    elif abs(dy) > CORE_LIMIT + slack:
        found, keys = f"the tool's centre height |dy| = {abs(dy) / UM:.4g} um", (
            "tool.y", "location.C.EX0C", "location.C.EY0C")
        expected = f"|dy| at most {CORE_LIMIT / UM:g} um"
    elif not smallest <= d_radius <= largest and nose + d_radius > 0.0:  # no nose: the
        # tool refuses itself, naming the file and key (tool_geometry.nose_radius_um)
        found, keys = (f"the nose radius error dR = {d_radius / UM:.6g} um (a nose of "
                       f"{(nose + d_radius) / UM:.6g} um for {nose / UM:g} um)",
                       ("tool_geometry.nose_radius",))
        expected = f"dR within {smallest / UM:g} .. {largest / UM:g} um"
    else:
        return
    given = errors.parameters()
    refuse_beyond_capture(
        args, {}, [k for k in keys if given.get(k)] or ["its errors"], found,
        "(the test sphere identifies dx from about -10 to +5 um, |dy| up to 20 um and dR from "
        "about -850 to +300 um, and the tilted test plane less: dx below about -6 um, or "
        "|dy| from about 8 um at dx = -3.5 um, is refused by its residual check, "
        "refuse_unfit_plane; docs/procedures/sts_turning.md)", expected)


#: The realism switches of the interferometer's noise, off for `refuse_unfit_plane`'s turn.
NOISE = ("instrument_noise", "lateral_noise")


def refuse_unfit_plane(args, quiet_lab, errors) -> None:
    """Refuse, before the tool test cuts anything, injected ``errors`` whose tilted test
    plane (`sts_plans.TEST_PLANE`) the plane's residual check (`sts_plane_check`) would
    refuse after both test pieces are cut: the plane turned on ``quiet_lab`` (the scenario's
    lab with the interferometer's noise off, `NOISE`), read, and fitted with the tool's dx
    against the spindle axis (`tool_from_spindle_axis` of ``errors``, as `refuse_unread_tool`
    takes it: without the lab's background, whose 75 nm move the misfit by about 0.03 nm)
    and dR as injected, its misfit set against `PLANE_MISFIT_LIMIT`. A tool far enough
    across the axis (dx < 0) or off the centre height (dy), for its nose radius error, cuts
    the plane across the axis beyond the fit's 30 um core; no range of dx and dy alone says
    where (docs/procedures/sts_turning.md, "The plane's residual check"). A smaller nose
    (dR < 0) with dx < 0 ends the cut inside the read disc instead (`turned_rim`: with dR
    -850 um from dx about -5 um whatever dy), and the message says so. About 2 s; the
    noise adds to the misfit only what the check subtracts (0.19-0.23 nm with it, 0.20 nm
    without, Table 5's tool)."""
    nose = STSTurning().nose_radius
    dx, dy = tool_from_spindle_axis(quiet_lab.machine, errors, nose)
    d_radius = errors.parameters().get("tool_geometry.nose_radius", 0.0)
    part, _ = quiet_lab.turn(spiral_program(TEST_PLANE.path(nose)), STSTurning().tool,
                             top=TEST_PLANE.top)
    w = TEST_PLANE.read_half_width
    interferometer = quiet_lab.white_light_interferometer(label="plane_check")
    plane = interferometer.height_map(part, -w, w, -w, w, TEST_PLANE.pixel)
    noise, lateral = interferometer.readout.std, interferometer.lateral_sigma
    centre = fit_centre_height(plane.x, plane.y, plane.z, TEST_PLANE.slope, aperture=w,
                               core=TEST_PLANE.core, dx=dx, noise=noise,
                               lateral_sigma=lateral, d_radius=d_radius)
    misfit = plane_misfit(centre.residual_rms_known_radius, noise, lateral, TEST_PLANE.slope)
    if not misfit > PLANE_MISFIT_LIMIT:
        return
    rim, read = turned_rim(dx, d_radius), TEST_PLANE.read_half_width
    if rim < read:
        cause = (f"(the plane is turned to {TEST_PLANE.turned_radius / UM:g} um from the "
                 f"axis, and this tool's cut ends {rim / UM:.2f} um from it on one side "
                 f"({TEST_PLANE.turned_radius / UM:g} um + dx - |dR| k), inside the "
                 f"{read / UM:g} um the plane is read to: the stock the nose leaves there lies "
                 "in the fit; docs/procedures/sts_turning.md, \"The plane's residual check\")")
    else:
        cause = (f"(the plane's fit leaves out {TEST_PLANE.core / UM:g} um about the spindle "
                 "axis, and a nose cutting across the axis beyond it is refused by the plane's "
                 "residual check after both test pieces are cut: with dR = 100 um, dx below "
                 "about -6 um at dy = 0, -5 um at |dy| = 6 um, -1.5 um at 10 um; "
                 "docs/procedures/sts_turning.md, \"The plane's residual check\")")
    given = errors.parameters()
    keys = [k for k in ("tool.x", "tool.y", "tool_geometry.nose_radius", "location.C.EX0C",
                        "location.C.EY0C") if given.get(k)]
    refuse_beyond_capture(
        args, {}, keys or ["its errors"],
        f"the tool's offsets from the spindle axis dx = {dx / UM:.4g} um, dy = {dy / UM:.4g} "
        f"um with dR = {d_radius / UM:.4g} um, whose tilted test plane (turned before the "
        f"cut with the noise off) misfits its model by {misfit / NM:.2f} nm; that", cause,
        f"a misfit of at most {PLANE_MISFIT_LIMIT / NM:g} nm: set the tool nearer the axis "
        "(tool.x less negative, |tool.y| smaller)")


def tool_against_axis(out: ReportFolder, lab, result) -> str:
    """The identified tool offsets against the tool's offsets from the spindle axis as the
    lab's machine has them (`tool_from_spindle_axis`, from the lab's truth, after the run).

    The test pieces are turned about the spindle axis, so they show the tool's offset from
    that axis: the injected offset plus what the background adds to it (the C axis's
    location errors, docs/procedures/sts_turning.md, "What the tests read"). A workpiece
    setting error moves the axis in the workpiece frame, not the tool against it."""
    truth = tool_from_spindle_axis(lab.machine, lab.reveal(), STSTurning().nose_radius)
    rows = []
    for name, against in zip(("tool.x", "tool.y"), truth, strict=True):
        value, std = result.identified[name]
        injected = result.injected[name]
        rows.append([name, injected / NM, (against - injected) / NM, against / NM, value / NM,
                     std / NM, (value - against) / NM, _in_stds(value - against, std)])
    return out.write_table(
        "tool_against_axis", ["parameter", "injected (nm)", "added by the machine (nm)",
                              "tool against the spindle axis (nm)", "identified (nm)",
                              "std (nm)", "error against the axis (nm)", "error / std"],
        rows, title="Tool offsets against the spindle axis (the tests read the tool from it)",
        digits=2)


def _in_stds(error: float, std: float) -> float:
    """``error`` in units of ``std``; NaN (null in the table's JSON: undefined) where the std
    is 0 or not a number. A fit whose residuals vanish states a std of 0 (`_fit_std`:
    s^2 = sum(r^2) / (n - p)), and a 0 std makes no unit: the Python division ended the
    scenario in ZeroDivisionError after the run, and a numpy one's inf, which the table
    had written as null, is now refused (an infinite figure is no measurement)."""
    return error / std if std > 0.0 else math.nan


def alias_table(out: ReportFolder, machine) -> str:
    """The error terms the tool test reads as the tool's at its poses, from ``machine``'s
    model (`machinesim.procedures.sts_aliases`), beside how far each moves the tool against
    the spindle axis (`tool_from_spindle_axis`, the same model): what the test is meant to
    read where the two agree. The exact aliases, then the near ones (`near_aliases`), each
    its own table."""
    nose = STSTurning().nose_radius
    size = 1e-9

    def against_axis(alias):
        if alias.reading not in ("tool.x", "tool.y"):
            return 0.0  # nothing but the tool's own nose moves the nose radius
        moved = tool_from_spindle_axis(machine, term_model(machine, alias.term, alias.form,
                                                           size), nose)
        return moved[("tool.x", "tool.y").index(alias.reading)] / size

    exact, near = alias_lists(machine, nose)
    columns = ["error", "term", "read as", "nm per unit", "tool against the spindle axis, "
               "nm per unit", "unit", "misfit share"]
    text = out.write_table(
        "tool_test_aliases", columns, alias_rows(exact, against_axis),
        title="Errors the tool test reads as the tool's (the machine's model at its poses)",
        digits=4, note=ALIAS_NOTE)
    return text + "\n" + out.write_table(
        "tool_test_near_aliases", [*columns, "near limit", "sphere misfit, nm RMS per unit"],
        near_alias_rows(near, against_axis),
        title="Errors the tool test reads as the tool's with a small misfit (near aliases)",
        digits=4, note=NEAR_ALIAS_NOTE)


def tool_from_spindle_axis(machine, errors, nose_radius: float,
                           radius: float = 60e-6) -> tuple[float, float]:
    """The tool's offsets from the spindle axis (m): dx, radial (along the tool's X, less
    the commanded X), and dy, the centre height (along its Y), with ``errors``.

    The tool's poses over a turn of C at X = ``radius``, as the turning engine takes them
    (`edge_path_from_poses`: the edge plane's direction and the nose's position in it). With
    the spindle axis at e in the workpiece frame, the path's ``along`` is X + dx + u . e and
    its ``offset`` dy + u x e, u the edge plane's direction (the tool's X, turned by C): over
    a whole turn sampled evenly u averages to zero, so the means are X + dx and dy, wherever
    the axis lies (an `EdgePath` with its tip mostly on -u is stored with u turned by pi:
    turned back here)."""
    turn = np.linspace(0.0, 2.0 * np.pi, 73)[:-1]
    q = np.zeros((turn.size, len(machine.axes)))
    q[:, machine.axes.index("X")] = radius
    q[:, machine.axes.index("C")] = turn
    path = edge_path_from_poses(machine.tool_pose(q, errors), nose_radius)
    sign = -1.0 if np.cos(path.angle[0] - turn[0]) < 0.0 else 1.0  # stored turned by pi
    return sign * float(np.mean(path.along)) - radius, sign * float(np.mean(path.offset))


def case_table(out: ReportFolder, details) -> str:
    """The cases side by side with the paper's (Figs 16 and 18), as ``cases.md`` and
    ``cases.json`` (the paper's measured P-V n/a, null, where it gives none)."""
    rows = [[name[-1], details[name]["compensated"],
             details[name]["predicted_program_pv_nm"], details[name]["predicted_tool_pv_nm"],
             details[name]["predicted_servo_pv_nm"], details[name]["predicted_pv_nm"],
             details[name]["measured_pv_nm"],
             math.nan if PAPER[name] is None else PAPER[name], details[name]["sa_nm"]]
            for name in CASES]
    return out.write_table(
        "cases", ["case", "compensated", "predicted P-V, program (nm)",
                  "predicted P-V, tool (nm)", "predicted P-V, servo (nm)",
                  "predicted P-V, total (nm)", "measured P-V (nm)", "paper measured (nm)",
                  "Sa (nm)"], rows,
        title="The four cases: form error predicted before the cut and measured after",
        digits=2)


def _save(out: ReportFolder, name: str, figure) -> None:
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    plt.close(figure)
    write_atomic(out.path / name, buffer.getvalue())
    out.files.append(name)


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def profiles(out: ReportFolder, name: str, result) -> None:
    """The measured form error of each case along theta = 0 (paper 004 Fig. 17)."""
    plt = _pyplot()
    figure, axes = plt.subplots(2, 2, figsize=(11, 7), dpi=120, sharex=True)
    details = result.evaluation.details
    for ax, case in zip(axes.ravel(), CASES, strict=True):
        d = details[case]
        ax.plot(d["profile_r_um"], d["profile_form_error_nm"], lw=0.8)
        ax.set_title(f"Case {case[-1]} ({CASES[case]}): P-V {d['measured_pv_nm']:.2f} nm")
        ax.set_ylabel("form error (nm)")
        ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("r at theta = 0 (um)")
    figure.tight_layout()
    _save(out, name, figure)


def shares(out: ReportFolder, name: str, details) -> None:
    """Predicted P-V of each factor alone, the whole prediction and the measurement, per case
    (paper 004 Figs 16 and 18)."""
    plt = _pyplot()
    keys = [("predicted_program_pv_nm", "program"), ("predicted_tool_pv_nm", "tool"),
            ("predicted_servo_pv_nm", "servo"), ("predicted_pv_nm", "predicted"),
            ("measured_pv_nm", "measured")]
    figure, ax = plt.subplots(figsize=(9, 5), dpi=120)
    width = 0.16
    for k, (key, label) in enumerate(keys):
        values = [details[case][key] for case in CASES]
        ax.bar(np.arange(len(CASES)) + (k - 2) * width, values, width, label=label)
    paper = [PAPER[case] if PAPER[case] is not None else np.nan for case in CASES]
    ax.plot(np.arange(len(CASES)), paper, "k*", markersize=12, label="paper, measured")
    ax.set_xticks(np.arange(len(CASES)), [f"Case {c[-1]}\n{CASES[c]}" for c in CASES])
    ax.set_ylabel("form error P-V (nm)")
    ax.set_title("Form error predicted (each factor alone, all) and measured")
    ax.legend()
    ax.grid(True, axis="y", alpha=0.3)
    figure.tight_layout()
    _save(out, name, figure)


def surface_3d(out: ReportFolder, name: str, result) -> None:
    """The Case 4 surface as the interferometer read it, 100 x 100 um (paper 004 Fig. 19)."""
    plt = _pyplot()
    window = result.evaluation.details["case_4"]
    gx, gy = np.meshgrid(window["window_x_um"], window["window_y_um"])
    z = np.asarray(window["window_height_nm"])
    figure = plt.figure(figsize=(8, 6), dpi=120)
    ax = figure.add_subplot(projection="3d")
    ax.plot_surface(gx, gy, z, cmap="viridis", linewidth=0)
    ax.set_xlabel("x (um)")
    ax.set_ylabel("y (um)")
    ax.set_zlabel("height (nm)")
    ax.set_title("Case 4, machined sine grid (white-light interferometer)")
    _save(out, name, figure)


if __name__ == "__main__":
    main()
