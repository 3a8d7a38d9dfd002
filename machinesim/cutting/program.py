"""Cut an NC program on a machine with errors: program -> motion -> poses -> material removal."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import manifold3d
import numpy as np

from machinesim import motion
from machinesim.cutting.engine import remove
from machinesim.tolerances import RAPID_CUT_VOLUME_M3, RAPID_EDGE_HALF_THICKNESS_M
from machinesim.tools import tool_from_spec
from machinesim.workpiece import Part, stock_from_spec


@dataclass(frozen=True)
class CutReport:
    """What happened while cutting, for people and for JSON.

    Attributes
    ----------
    removed_volume_m3 : float
    machining_time_s, cutting_time_s : float
        From the feeds (motion's FANUC rule), all moves and feed moves only.
    sweeps : int
        Feed sub-steps swept through the material-removal engine.
    substeps : int
        Sub-steps of all moves, rapids included.
    rapids_that_cut : tuple of int
        Source lines of rapids (G00) whose sweep met material present at that time.
    limit_violations : tuple of str
        Axis values outside their travel.
    sideways_sweeps : int
        Feed sweeps that drag a non-rotational tool sideways (across its cutting edge).
    empty_cut : bool
        True when nothing was removed: a program that misses the stock is flagged, not silent.
    engine : str
        How the material was removed: "relief" (straight grooves across a block, meshed as a
        height field) or "boolean" (sweeps subtracted); both exact (`engine.remove`).
    elapsed_s : float
        Wall time of the simulation.
    notes : tuple of str
    """

    removed_volume_m3: float
    machining_time_s: float
    cutting_time_s: float
    sweeps: int
    substeps: int
    rapids_that_cut: tuple[int, ...]
    limit_violations: tuple[str, ...]
    sideways_sweeps: int
    empty_cut: bool
    engine: str
    elapsed_s: float
    notes: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict:
        """JSON-ready dict, every key with its unit."""
        return {
            "removed_volume_mm3": self.removed_volume_m3 * 1e9,
            "machining_time_s": self.machining_time_s,
            "cutting_time_s": self.cutting_time_s,
            "sweeps": self.sweeps,
            "substeps": self.substeps,
            "rapids_that_cut_lines": list(self.rapids_that_cut),
            "limit_violations": list(self.limit_violations),
            "sideways_sweeps": self.sideways_sweeps,
            "empty_cut": self.empty_cut,
            "engine": self.engine,
            "elapsed_s": self.elapsed_s,
            "notes": list(self.notes),
        }


def cut(program, machine, tool="v:90", stock="block:10x10x2", errors=None, *, roi=None,
        start=None, chord_tolerance: float = motion.CHORD_TOLERANCE_M, servo=None,
        progress=None) -> tuple[Part, CutReport]:
    """Run ``program`` on ``machine`` (with ``errors``) and return the machined part.

    Parameters
    ----------
    program : machinesim.nc.Program
    machine : machinesim.Machine or str
        A machine or a machine name.
    tool : str or tool
        ``"v:90"``, ``"nose:2.0:90"``, ``"ball:2.0"`` (mm, deg) or a tool object.
    stock : str or Part
        ``"block:10x10x2"``, ``"cylinder:5x2"`` (mm), optionally ``@x,y,z``, or a Part.
    errors : ErrorModel, optional
        The machine's injected errors (None: the nominal machine).
    roi : sequence of (xmin, xmax, ymin, ymax), optional
        Windows in the workpiece frame (m): cut only there (see `engine.remove`).
    start : array_like, optional
        Axis values before the first block (default zeros).
    chord_tolerance : float
        Rotary moves are split so the swept chord stays this close to the path (m).
    servo : motion.ServoModel, optional
        Axis follow-up model (default ideal).
    progress : callable(done, total), optional
        Called as the engine works through the sweeps.
    """
    from machinesim.machines import Machine, load_machine

    began = time.perf_counter()
    machine = machine if isinstance(machine, Machine) else load_machine(machine)
    tool = tool_from_spec(tool) if isinstance(tool, str) else tool
    stock = stock_from_spec(stock) if isinstance(stock, str) else stock
    machine.check_errors(errors)
    trajectory = motion.plan(program, machine, errors, start=start,
                             tool_points=tool.vertices(), chord_tolerance=chord_tolerance,
                             servo=servo)
    segments = [s for s in trajectory.segments if s.kind != "dwell"]
    all_q = np.vstack([s.q for s in segments]) if segments else np.zeros((0, len(machine.axes)))
    limits = tuple(machine.limit_violations(all_q)) if len(all_q) else ()
    poses = machine.tool_pose(all_q, errors) if len(all_q) else np.zeros((0, 4, 4))
    paths, kinds, lines, offset = [], [], [], 0
    for s in segments:
        paths.append(poses[offset:offset + len(s.q)])
        kinds.append(s.kind)
        lines.append(s.line)
        offset += len(s.q)
    feed_paths = _join([p for p, k in zip(paths, kinds, strict=True) if k == "linear"])
    part, engine = remove(stock, tool, feed_paths, roi=roi, progress=progress)
    rapids = _rapids_that_cut(stock, tool, paths, kinds, lines)
    report = CutReport(
        removed_volume_m3=float(engine.removed_volume),
        machining_time_s=trajectory.duration,
        cutting_time_s=trajectory.cutting_time,
        sweeps=int(engine.n_sweeps),
        substeps=trajectory.substeps,
        rapids_that_cut=rapids,
        limit_violations=limits,
        sideways_sweeps=len(engine.sideways),
        empty_cut=bool(engine.empty_cut),
        engine=engine.method,
        elapsed_s=time.perf_counter() - began,
        notes=trajectory.notes,
    )
    return part, report


def _join(paths: list[np.ndarray]) -> list[np.ndarray]:
    """Merge feed paths that continue one another (end pose == next start pose)."""
    joined: list[np.ndarray] = []
    for p in paths:
        if joined and np.array_equal(joined[-1][-1], p[0]):
            joined[-1] = np.concatenate([joined[-1], p[1:]])
        else:
            joined.append(p)
    return joined


def _thick(tool) -> np.ndarray:
    points = tool.vertices()
    shift = np.array([RAPID_EDGE_HALF_THICKNESS_M, 0.0, 0.0])
    return np.vstack([points + shift, points - shift])


def _hull(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> manifold3d.Manifold:
    ends = [(m[:3, :3] @ points.T).T + m[:3, 3] for m in (a, b)]
    return manifold3d.Manifold.hull_points(np.vstack(ends))


def _rapids_that_cut(stock: Part, tool, paths, kinds, lines) -> tuple[int, ...]:
    """Lines of rapids whose sweep met material still there when they ran.

    The material at that time is the stock less the feed sweeps before the rapid that
    overlap it: exact, and cheap since only rapids whose sweep meets the stock are examined
    further, against the earlier feed sweeps whose boxes overlap theirs.
    """
    lo, hi = stock.bounds
    points = _thick(tool)
    boxes = None  # (sweep path index, pose index, min corner, max corner) of feed sweeps
    found = []
    for i, (path, kind) in enumerate(zip(paths, kinds, strict=True)):
        if kind != "rapid":
            continue
        world = _corners(points, path)
        low, high = world.min(axis=(0, 1)), world.max(axis=(0, 1))
        if np.any(high < lo) or np.any(low > hi):
            continue
        hit = stock.manifold ^ manifold3d.Manifold.batch_boolean(
            [_hull(points, path[j], path[j + 1]) for j in range(len(path) - 1)],
            manifold3d.OpType.Add)
        if hit.volume() <= RAPID_CUT_VOLUME_M3:
            continue
        if boxes is None:
            boxes = _sweep_boxes(points, paths, kinds)
        owner, pose, b_low, b_high = boxes
        near = np.flatnonzero((owner < i) & np.all(b_high >= low, axis=1)
                              & np.all(b_low <= high, axis=1))
        if near.size:
            earlier = [_hull(points, paths[owner[k]][pose[k]], paths[owner[k]][pose[k] + 1])
                       for k in near]
            hit = hit - manifold3d.Manifold.batch_boolean(earlier, manifold3d.OpType.Add)
        if hit.volume() > RAPID_CUT_VOLUME_M3:
            found.append(lines[i])
    return tuple(found)


def _corners(points: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """Tool points at each pose, (n_poses, n_points, 3)."""
    return np.einsum("nij,kj->nki", poses[:, :3, :3], points) + poses[:, None, :3, 3]


def _sweep_boxes(points, paths, kinds):
    """Boxes of every feed sweep, with the path and pose each starts at."""
    owner, pose, low, high = [], [], [], []
    for i, (path, kind) in enumerate(zip(paths, kinds, strict=True)):
        if kind != "linear" or len(path) < 2:
            continue
        world = _corners(points, path)
        ends_low, ends_high = world.min(axis=1), world.max(axis=1)
        low.append(np.minimum(ends_low[:-1], ends_low[1:]))
        high.append(np.maximum(ends_high[:-1], ends_high[1:]))
        owner.append(np.full(len(path) - 1, i))
        pose.append(np.arange(len(path) - 1))
    if not owner:
        empty = np.zeros((0, 3))
        return np.zeros(0, int), np.zeros(0, int), empty, empty
    return (np.concatenate(owner), np.concatenate(pose), np.vstack(low), np.vstack(high))
