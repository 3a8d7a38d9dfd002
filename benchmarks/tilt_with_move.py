"""A tool tilting while it moves, cut through the user's path, against the same move cut in
many more sub-steps.

Each case is an NC program on robonano_a0ib (B tilts the tool about the Y line through its
edge point): plunge ``--depth-um`` into a 10 x 10 x 2 mm block at B0, then one feed
``G01 X.. B..`` (or ``Y.. B..``) that moves ``L`` mm while B turns to the tilt, then
retract. The default cut is `machinesim.cut` as a user calls it (the planner's default
chord for the tool: 1 nm for a V, 100 nm for a ball or flat end mill drawn within 1 um; the
exact, boolean engine). The reference is the same trajectory with every sub-step of the
tilting move split into ``--refine`` equal sub-steps in axis space (the planner's own
interpolation, start + f * delta), cut by `remove` given those poses.

The parts are compared where they differ: ``over`` is the material the default cut
removed and the reference kept (overcut), ``under`` the reverse (undercut), each as its
volume and its largest thickness: the farthest any vertex of one side of the sliver lies
from the other side's triangles (exact point-to-triangle distances). A first-order error
of the sweeps (the hull of two poses filling a waist) leaves the reference 1/refine of it,
so the figure is (1 - 1/refine) of the default's own.

    .venv/bin/python benchmarks/tilt_with_move.py [--tools v:90,ball:0.5,flat:0.5]
        [--tilts 2,10,30] [--moves 0.1,1] [--along X,Y] [--refine 8] [--depth-um 50]
"""

from __future__ import annotations

import argparse
import pickle
import sys
import time
from pathlib import Path

import numpy as np

import machinesim
from machinesim import motion
from machinesim.cutting.engine import remove
from machinesim.cutting.program import _Moves, _ToolSections
from machinesim.end_mills import BallEndMill, FlatEndMill
from machinesim.machines import load_machine
from machinesim.motion.faces import ProfileEdges
from machinesim.nc import parse_program
from machinesim.tool_specs import tool_from_spec
from machinesim.tools import flat_face_radius, path_chord_tolerance
from machinesim.workpiece import Part, stock_from_spec

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from tilted_cuts import sliver  # noqa: E402

MACHINE = "robonano_a0ib"
STOCK = "block:10x10x2"
#: Sub-steps of the default's each for the round ball's centre path (its polyline's chords
#: then lie within 1e-4 of the default's chord tolerance of the true path).
DENSE = 128


def program_text(along: str, move_mm: float, tilt_deg: float, depth_um: float) -> str:
    """The case's NC text: the tilting feed is line 4."""
    x0, y0 = 4.0, 5.0
    end = f"X{x0 + move_mm:.4f}" if along == "X" else f"Y{y0 + move_mm:.4f}"
    return (f"G21 G90\nG00 X{x0:.4f} Y{y0:.4f} Z1. B0.\nG01 Z-{depth_um / 1e3:.4f} F10.\n"
            f"{end} B{tilt_deg:g} F100.\nG00 Z3.\nM30\n")


def planned_poses(program, machine, tool, refine: int, line: int):
    """The paths (list of pose arrays) `cut` makes of ``program``, with every sub-step of
    the moves on ``line`` split into ``refine`` (1: as `cut` makes them), and that count."""
    sections = _ToolSections(program, tool)
    trajectory = motion.plan(program, machine, None, tool_points=sections.points(),
                             chord_tolerance=path_chord_tolerance([tool]),
                             face_radius=flat_face_radius([tool]),
                             profile=ProfileEdges.of(sections.setups(),
                                                     stock_from_spec(STOCK)))
    moves = _Moves(trajectory, len(machine.axes))
    q, starts, lines = [], [], []
    for i in range(len(moves.q)):
        if i and not moves.path_start[i] and moves.line[i] == line and refine > 1:
            f = np.arange(1, refine)[:, None] / refine
            q.extend(moves.q[i - 1] + f * (moves.q[i] - moves.q[i - 1]))
            starts.extend([False] * (refine - 1))
            lines.extend([line] * (refine - 1))
        q.append(moves.q[i])
        starts.append(bool(moves.path_start[i]))
        lines.append(int(moves.line[i]))
    q = np.array(q)
    poses = machine.tool_pose(q)
    breaks = np.flatnonzero(starts)[1:]
    tilting = int(np.sum(np.array(lines)[1:] == line))
    return np.split(poses, breaks), tilting


def past_round_ball(part: Part, radius: float, paths) -> tuple[float, float]:
    """How far (m) the part's cut surface lies outside (overcut) and inside (undercut) the
    true sweep of the round ball of ``radius`` whose tip follows ``paths`` (pose arrays,
    dense): every vertex below the stock's top and off its box's faces, its distance from
    the ball centre's polyline less the radius (exact for the polyline: the union of the
    balls along it is that polyline's tube)."""
    vertices, _ = part.mesh()
    box = stock_from_spec(STOCK).bounds
    inside = np.all((vertices > box[0] + 1e-12) & (vertices < box[1] - 1e-12), axis=1)
    points = vertices[inside]
    gaps = np.full(len(points), np.inf)
    for poses in paths:
        centre = poses[:, :3, 3] + radius * poses[:, :3, 2]
        a, b = centre[:-1], centre[1:]
        ab = b - a
        length2 = np.maximum((ab * ab).sum(axis=1), 1e-300)
        for start in range(0, len(points), 256):
            p = points[start:start + 256, None, :]
            f = np.clip(((p - a) * ab).sum(axis=2) / length2, 0.0, 1.0)
            d = np.sqrt(((a + f[..., None] * ab - p) ** 2).sum(axis=2)).min(axis=1)
            gaps[start:start + 256] = np.minimum(gaps[start:start + 256], d)
    gaps -= radius
    return float(max(gaps.max(initial=0.0), 0.0)), float(max(-gaps.min(initial=0.0), 0.0))


def past_round_flat(part: Part, radius: float, height: float, paths) -> float:
    """How far (m) the part's cut surface lies outside the sweep of the round flat end mill
    (a cylinder of ``radius`` and ``height`` on its end face) at the poses ``paths`` (dense):
    every vertex below the stock's top and off its box's faces, its distance from the
    nearest of the posed cylinders (0 inside one)."""
    vertices, _ = part.mesh()
    box = stock_from_spec(STOCK).bounds
    inside = np.all((vertices > box[0] + 1e-12) & (vertices < box[1] - 1e-12), axis=1)
    points = vertices[inside]
    poses = np.concatenate(paths)
    rotation, origin = poses[:, :3, :3], poses[:, :3, 3]
    worst = 0.0
    for start in range(0, len(points), 64):
        p = points[start:start + 64, None, :] - origin[None]
        local = np.einsum("pni,nij->pnj", p, rotation)  # R^T (p - o)
        r = np.sqrt(local[..., 0] ** 2 + local[..., 1] ** 2)
        z = local[..., 2]
        out = np.sqrt(np.maximum(r - radius, 0.0) ** 2
                      + np.maximum(np.maximum(-z, z - height), 0.0) ** 2)
        worst = max(worst, float(out.min(axis=1).max()))
    return worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tools", default="v:90,ball:0.5,flat:0.5")
    parser.add_argument("--tilts", default="2,10,30", help="deg")
    parser.add_argument("--moves", default="0.1,1", help="mm")
    parser.add_argument("--along", default="X,Y")
    parser.add_argument("--refine", type=int, default=8)
    parser.add_argument("--depth-um", type=float, default=50.0)
    parser.add_argument("--keep", type=Path, default=None,
                        help="a folder where each case's two parts are pickled, and read "
                             "from on a later run (to measure again without cutting)")
    args = parser.parse_args()
    machine = load_machine(MACHINE)
    print(f"{'tool':10s} {'along':5s} {'move mm':>7s} {'tilt':>5s} {'sweeps':>6s} "
          f"{'ref':>6s} {'over nm':>8s} {'over um^3':>10s} {'under nm':>8s} "
          f"{'under um^3':>10s} {'cut s':>6s} {'ref s':>6s}", flush=True)
    for spec in args.tools.split(","):
        tool = tool_from_spec(spec)
        for along in args.along.split(","):
            for move in (float(m) for m in args.moves.split(",")):
                for tilt in (float(t) for t in args.tilts.split(",")):
                    program = parse_program(program_text(along, move, tilt, args.depth_um),
                                            "tilt.nc")
                    kept = None if args.keep is None else args.keep / (
                        f"{spec.replace(':', '_')}-{along}-{move:g}-{tilt:g}-"
                        f"{args.refine}-{args.depth_um:g}.pickle")
                    if kept is not None and kept.exists():
                        part, reference, sweeps, fine_sweeps, seconds, ref_seconds = (
                            pickle.loads(kept.read_bytes()))
                    else:
                        began = time.perf_counter()
                        part, _ = machinesim.cut(program, machine, tool=tool, stock=STOCK)
                        seconds = time.perf_counter() - began
                        _, sweeps = planned_poses(program, machine, tool, 1, 4)
                        fine, fine_sweeps = planned_poses(program, machine, tool,
                                                          args.refine, 4)
                        began = time.perf_counter()
                        reference, _ = remove(stock_from_spec(STOCK), tool, fine,
                                              method="boolean")
                        ref_seconds = time.perf_counter() - began
                        if kept is not None:
                            kept.parent.mkdir(parents=True, exist_ok=True)
                            kept.write_bytes(pickle.dumps((part, reference, sweeps,
                                                           fine_sweeps, seconds,
                                                           ref_seconds)))
                    over_v, over = sliver(reference, part)
                    under_v, under = sliver(part, reference)
                    round_ball = ""
                    if isinstance(tool, BallEndMill):
                        dense, _ = planned_poses(program, machine, tool, DENSE, 4)
                        (out, inner), (ref_out, _) = (
                            past_round_ball(p, tool.radius, dense) for p in (part, reference))
                        round_ball = (f"  round ball: past it {out * 1e9:.3f} nm (reference "
                                      f"{ref_out * 1e9:.3f}), inside {inner * 1e9:.0f} nm")
                    if isinstance(tool, FlatEndMill):
                        dense, _ = planned_poses(program, machine, tool, DENSE // 8, 4)
                        out, ref_out = (past_round_flat(p, tool.radius, tool.height, dense)
                                        for p in (part, reference))
                        round_ball = (f"  round flat: past it {out * 1e9:.3f} nm (reference "
                                      f"{ref_out * 1e9:.3f})")
                    print(f"{spec:10s} {along:5s} {move:7g} {tilt:5g} {sweeps:6d} "
                          f"{fine_sweeps:6d} {over * 1e9:8.3f} {over_v * 1e18:10.4g} "
                          f"{under * 1e9:8.3f} {under_v * 1e18:10.4g} {seconds:6.1f} "
                          f"{ref_seconds:6.1f}{round_ball}", flush=True)


if __name__ == "__main__":
    main()
