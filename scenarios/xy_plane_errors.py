"""Paper 003 replayed: the grooving machine's XY-plane errors and its C table's squareness.

Run: ``.venv/bin/python scenarios/xy_plane_errors.py [--errors FILE.toml] [--noise on|off]
[--realism ideal|noise_only|lab] [--budget on|off] [--jobs N] [--seed N]
[--out reports/xy_plane_errors]`` (about 75 s with the default lab realism and its error
budget; 19 s with ``--budget off``; on 2 idle cores). ``--jobs N``: the budget's reruns N
at a time, each on a worker process (default 1, one after the other here; the same budget
either way, docs/budget.md).

The grooving_4axis gets the errors of ``models/errors/xy_plane_grooving_4axis.toml`` (chosen
to give paper 003's magnitudes: 2-D errors of 11.59 um in X and 12.33 um in Y over the
400 mm plate, a diagonal deviation of 17.3 um), or those of ``--errors``. The procedure
(`machinesim.procedures.xy_plane_errors.XYPlaneErrors`) measures the plate with the lab's
laser interferometer (ISO 230-2 positioning and straightness on the centre lines, ISO 230-6
diagonals at the corners, read level with the cut as the paper's beam was, and 120 mm above
the table), builds eq 1's 2-D map, fits the same parameters with
`machinesim.identification.fit`, compensates by a control table of re-shaped commands (eq
1's map, as the paper; and with the table's yaw) and by the identified model, and measures
again; it reads the C table's
squareness by simultaneous XY + C motion (Figs 7-9) with displacement sensors. Writes
summary.json (docs/reports.md), the paper's table, the 2-D error maps (Figs 2 and 5), the
diagonal curves (Figs 4 and 6), h(theta) (Fig. 9) and the pyramid apex heights of five
1 x 1 mm windows across the plate, before and after. The lab is as real as ``--realism``
says, but for the optical instruments' registration (one frame for the whole 400 mm plate,
which a lab reading window by window levels away; docs/procedures/xy_plane_errors.md), and
the error budget reruns it with each source off in turn (docs/budget.md). With the instrument
noise off the laser readings have neither noise nor the 1 nm display rounding (ideal but
for each set-up's air scale with the lab realism's ``air_refraction``).
"""

from __future__ import annotations

import machinesim.scenario_start  # noqa: F401  (first: Ctrl-C while loading is one line)

import io
import time
from pathlib import Path

import numpy as np

from machinesim._io import write_atomic
from machinesim.budget import LabInputs, realism_budget
from machinesim.errors import ErrorModel
from machinesim.experiment import run
from machinesim.machines import load_machine
from machinesim.procedures.pyramid_windows import WINDOWS, capture, path_errors, rapid_reach
from machinesim.procedures.xy_plane_errors import XYPlaneErrors, compensations
from machinesim.procedures.xy_plane_measurements import (
    DIAGONALS,
    PLATE,
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

DEFAULT_ERRORS = (Path(__file__).resolve().parents[1] / "models" / "errors"
                  / "xy_plane_grooving_4axis.toml")
UM = 1e-6


def main() -> None:
    parser = scenario_arguments(__doc__.splitlines()[0], "reports/xy_plane_errors")
    realism_options(parser)
    run_scenario(report, parser.parse_args())


def report(args) -> None:
    began = time.perf_counter()
    machine = load_machine("grooving_4axis")  # for the notes on --errors, and the labs
    errors = (errors_file(args.errors, machine) if args.errors is not None
              else ErrorModel.from_toml(DEFAULT_ERRORS))
    realism = realism_from(args).without("registration")
    ideal = not realism.instrument_noise

    # plain data, so that --jobs can build the budget's labs on worker processes
    make_lab = LabInputs(machine, errors, seed=args.seed)

    lab = make_lab(realism)
    refuse_off_windows(args, lab.machine, errors)
    print(f"Paper 003 on grooving_4axis: realism {realism}, seed {args.seed}"
          + laser_note(realism) + "\n")
    procedure = XYPlaneErrors(interferometer_resolution=0.0 if ideal else None)
    stage = progress_printer("xy_plane_errors")
    result = run(procedure, lab, progress=stage("run"))
    budget = realism_budget(procedure, result, realism, make_lab, args.budget == "on",
                            progress=stage, jobs=args.jobs)
    out = ReportFolder(args.out)
    detail = result.identification.detail
    xy = result.measurements["xy"]
    after = result.evaluation.details
    vector_map(out, "xy_map_before.png", detail["map"], "Estimated 2-D errors (eq 1), before")
    table, _ = compensations(result.identification)
    # the evaluation's after tests through eq 1's table, read again on the same set-up (the
    # same draws: its scale and noise), so the plot shows the figure's map
    after_xy = procedure.plane_tests(lab, "_after", table)
    vector_map(out, "xy_map_after.png", after_xy.map,
               "Estimated 2-D errors (eq 1), after table compensation")
    diagonal_plot(out, "diagonals_before.png", xy, "Diagonals before compensation")
    diagonal_plot(out, "diagonals_after.png", after_xy, "Diagonals after compensation")
    sep = detail["c"]
    deg = np.degrees(sep.theta)
    out.plot("c_heights.png", [
        ("h(theta), following test", deg, sep.h / UM),
        ("table tilt (fixed tests)", deg, sep.table_tilt / UM),
        ("perpendicularity (EA0C, EB0C)", deg, sep.perpendicularity / UM),
        ("tilt motion (EAC, EBC)", deg, sep.wobble / UM),
        ("XY motion errors", deg, sep.xy_motion / UM)],
        xlabel="C (deg)", ylabel="height (um)", title="C squareness test (paper 003 Fig. 9)")
    pyramid_map(out, "pyramid_heights.png", after)
    print(paper_table(result))
    print(f"\nmodel-based route after: X {after['xy_error_x_model_after_um']:.3f} um, "
          f"Y {after['xy_error_y_model_after_um']:.3f} um, diagonal "
          f"{after['diagonal_model_after_um']:.3f} um")
    print(out.write_result(result, budget=budget))
    out.publish(last=True)
    print(f"Report written to {out.final} ({time.perf_counter() - began:.1f} s)")


def laser_note(realism) -> str:
    """What the header says of the laser's readings under ``realism``: ideal with the
    instrument noise off (no 1 nm display rounding either), but for the scale of the air
    each set-up's compensation misses where ``air_refraction`` is on (``--realism lab
    --noise off`` called those readings ideal)."""
    if realism.instrument_noise:
        return ""
    if realism.air_refraction:
        return (" (laser readings without noise or 1 nm display rounding, each set-up on "
                "the scale of the air its compensation misses)")
    return " (laser readings ideal: no noise, no 1 nm display rounding)"


def refuse_off_windows(args, machine, errors) -> None:
    """Refuse, before anything is measured or cut, injected ``errors`` that cut the pyramid
    windows' grooves beyond what their reading captures (`capture`: 0.2 mm across or along,
    7.5 um shallower; through ``machine``'s kinematics at the ends of each window's outer
    grooves), or so deep that the rapids run into the plate (`rapid_reach`: 0.5 mm; a tool
    1 mm low ran for more than 7 min without a word), naming the ``--errors`` file and the
    keys that move the tool most there. The
    run refused only at the first window, after the laser tests, the fits and its cut (10 s
    of 16 with the default errors x 1000, naming neither the file nor a key), and a tool cut
    8 to 15 um high read the apexes low with no word (10 um high read 8.3 um)."""
    q, off = path_errors(machine, errors)
    plane, above = capture()
    below = rapid_reach()
    beyond_plane = np.abs(off[:, :2]) - plane
    if beyond_plane.max() <= 0.0 and off[:, 2].max() <= above and off[:, 2].min() >= -below:
        return
    if beyond_plane.max() > 0.0:
        row, col = np.unravel_index(np.argmax(beyond_plane), beyond_plane.shape)
        found = (f"the tool tip {abs(off[row, col]) / UM:.4g} um off its path in "
                 f"{'xy'[col]} at a pyramid window's groove end")
    elif off[:, 2].max() > above:
        row, col = int(np.argmax(off[:, 2])), 2
        found = (f"the tool tip {off[row, 2] / UM:.4g} um above its path at a pyramid "
                 "window's groove end")
    else:
        row, col = int(np.argmin(off[:, 2])), 2
        found = (f"the tool tip {-off[row, 2] / UM:.4g} um below its path at a pyramid "
                 "window's groove end")
    values = errors.parameters()
    names = [name for name, value in values.items() if value]
    share = machine.error_jacobian(q[row], errors, names)[col] * [values[n] for n in names]
    order = np.argsort(-np.abs(share))
    keys = [names[k] for k in order[:4] if abs(share[k]) >= 0.1 * abs(off[row, col])]
    refuse_beyond_capture(
        args, {}, keys or ["its errors"], found,
        f"(the 1 mm windows' grooves are read within {plane / UM:g} um of their place "
        f"and at most {above / UM:g} um shallower than cut, and the program's rapids run "
        f"{below / UM:g} um over the plate, which a tip lower runs them into, a crash: "
        "docs/procedures/xy_plane_errors.md)",
        f"the tool tip within {plane / UM:g} um of its path in x and y, at most "
        f"{above / UM:g} um above it and less than {below / UM:g} um below it")


def paper_table(result) -> str:
    lines = ["| figure | unit | before | after | paper before | paper after |",
             "|---|---|---|---|---|---|"]
    for f in result.figures:
        cells = [f.before, f.after, f.paper_before, f.paper_after]
        lines.append(f"| {f.name} | {f.unit} | " + " | ".join(
            "-" if v is None else f"{v:.3f}" for v in cells) + " |")
    return "\n".join(lines)


def vector_map(out: ReportFolder, name: str, xy_map, title: str) -> None:
    """Arrows of (dPx, dPy) on the plate (paper 003 Figs 2 and 5)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    gx, gy, dx, dy = xy_map.grid(PLATE, PLATE, count=11, reference="y")
    figure, axes = plt.subplots(figsize=(6.5, 6), dpi=120)
    scale = max(float(np.hypot(dx, dy).max()), 1e-12)
    q = axes.quiver(gx * 1e3, gy * 1e3, dx / UM, dy / UM, angles="xy",
                    scale_units="xy", scale=scale / UM / 30.0)
    axes.quiverkey(q, 0.9, -0.09, scale / UM, f"{scale / UM:.3g} um")
    axes.set_xlabel("X (mm)")
    axes.set_ylabel("Y (mm)")
    rx, ry = xy_map.ranges(PLATE, PLATE, reference="y")
    axes.set_title(f"{title}\nrange X {rx / UM:.2f} um, Y {ry / UM:.2f} um")
    axes.set_aspect("equal")
    buffer = io.BytesIO()
    figure.tight_layout()
    figure.savefig(buffer, format="png")
    plt.close(figure)
    write_atomic(out.path / name, buffer.getvalue())
    out.files.append(name)


def pyramid_map(out: ReportFolder, name: str, details) -> None:
    """Mean pyramid apex height of each window at its place on the plate, before and after
    (a colour map of the plate)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    xy = np.array(WINDOWS) * 1e3
    before = np.array(details["pyramid_apex_mean_before_um"])
    after_ = np.array(details["pyramid_apex_mean_after_um"])
    low, high = min(before.min(), after_.min()), max(before.max(), after_.max())
    figure, axes = plt.subplots(1, 2, figsize=(11, 5), dpi=120)
    for ax, values, title in ((axes[0], before, "before"), (axes[1], after_, "after (model)")):
        dots = ax.scatter(xy[:, 0], xy[:, 1], c=values, s=900, marker="s", cmap="viridis",
                          vmin=low, vmax=high)
        for (x, y), v in zip(xy, values, strict=True):
            ax.annotate(f"{v:.2f}", (x, y), ha="center", va="center", color="white")
        ax.set_xlim(-230, 230)
        ax.set_ylim(-230, 230)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_title(f"pyramid apex height (um), {title}")
    figure.colorbar(dots, ax=axes, label="mean apex height (um)")
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    plt.close(figure)
    write_atomic(out.path / name, buffer.getvalue())
    out.files.append(name)


def diagonal_plot(out: ReportFolder, name: str, xy, title: str) -> None:
    """Measured (beam height) and eq-1-estimated diagonal deviations (paper 003 Figs 4
    and 6), and the same diagonals read at the tool tip."""
    series = []
    for (corner, opposite), d in zip(DIAGONALS, xy.diagonals, strict=True):
        label = f"({corner[0] * 1e3:+.0f},{corner[1] * 1e3:+.0f})->" \
                f"({opposite[0] * 1e3:+.0f},{opposite[1] * 1e3:+.0f}) mm"
        s = d.targets
        series.append((f"measured {label}", s * 1e3, d.mean / UM))
        series.append((f"estimated {label}", s * 1e3,
                       xy.map.diagonal(corner, opposite, s) / UM))
    for (corner, opposite), d in zip(DIAGONALS, xy.work_diagonals, strict=True):
        label = f"({corner[0] * 1e3:+.0f},{corner[1] * 1e3:+.0f})->" \
                f"({opposite[0] * 1e3:+.0f},{opposite[1] * 1e3:+.0f}) mm"
        series.append((f"at the tool tip {label}", d.targets * 1e3, d.mean / UM))
    out.plot(name, series, xlabel="distance along the diagonal (mm)",
             ylabel="deviation (um)", title=title)


if __name__ == "__main__":
    main()
