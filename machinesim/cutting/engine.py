"""Exact material removal: stock minus the convex sweeps of a tool along pose sequences.

A sweep is the convex hull of the tool at two consecutive poses of a path (float64,
`manifold3d.Manifold.hull_points`). For a move at fixed orientation this is the exact volume
swept by the tool; a move that rotates must arrive already split into sub-steps whose chord
error is within tolerance (`rotary_substeps`).

Straight grooves right across a block are first offered to `machinesim.cutting.relief`,
which meshes their height field exactly without any boolean; everything else is subtracted
here. Speed comes from never touching the part mesh once per sweep:

1. Tool points for all poses are transformed at once (numpy).
2. Each sweep is clipped, before its hull is built, to the half-space a hair above the top
   of the stock (`CLIP_MARGIN_REL`). The part is unchanged (nothing above the stock is
   material), but tall tool bodies no longer overlap their neighbours, so parallel sweeps
   stay (almost) disjoint and their union is nearly free.
3. Sweeps are grouped by their direction of travel in XY. Parallel sweeps are unioned in
   one `batch_boolean`; groups that cross each other are subtracted one after the other,
   each evaluated before the next, because the union of crossing sweeps costs as much as
   cutting them (and manifold3d, left lazy, would form exactly that union).
4. The region is split into cells (ROI windows, and a grid of tiles inside each): a tile is
   cut with only the sweeps that touch it, which keeps manifold3d's faster-than-linear
   boolean cost down, and the tiles of a cell are joined by `stitch` (a mesh merge along
   the walls, with a boolean union as the fallback), the cells by one union.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import manifold3d
import numpy as np
from manifold3d import OpType

from machinesim.cutting.relief import cut_reliefs
from machinesim.cutting.stitch import exact_box, stitch
from machinesim.cutting.tiling import (
    SWEEPS_PER_TILE,
    grid_tiles,
    members_in,
    overlapping,
    tile_box,
)
from machinesim.exceptions import InputError
from machinesim.tolerances import (
    CLIP_MARGIN_REL,
    EMPTY_REL,
    PLANAR_TRAVEL_REL,
    RIGID_TOL,
    SAME_ORIENTATION,
    SIDEWAYS_REL,
)
from machinesim.tools import arc_segments
from machinesim.workpiece import Part

#: Sweeps travelling within this angle (rad) in XY are cut together as one parallel group.
DIRECTION_BIN_RAD = math.radians(5.0)
#: Rotating sweeps clip only when the all-pairs edge search is small: beyond this many tool
#: vertices their hull is built unclipped (still exact, only slower to union).
PAIR_CLIP_MAX_VERTICES = 64
#: Sweeps whose tool points are processed together: bounds the transient memory (k points
#: per pose, ~100 bytes each) to ~50 MB whatever the path length.
POINTS_PER_CHUNK = 1 << 19


@dataclass(frozen=True)
class EngineReport:
    """What a call to `remove` did.

    Attributes
    ----------
    removed_volume : float
        Volume removed from the stock (clipped to the ROI), m^3.
    n_sweeps : int
        Sweeps in the input (consecutive pose pairs over all paths).
    n_sweeps_cut : int
        Sweeps that reach the stock region and were subtracted.
    n_degenerate : int
        Sweeps with no volume (a zero-thickness profile moved within its own plane or not
        at all); they remove nothing.
    empty_cut : bool
        True when nothing was removed: flagged, never silent.
    sideways : tuple of int
        Indices (over all paths, in order) of sweeps that drag a non-rotational tool
        sideways (`SIDEWAYS_REL`).
    n_cells : int
        Cells (ROI windows times tiles) the region was cut in; 1 per window by relief.
    method : str
        "relief" when the cut was meshed as a height field (straight grooves across a block,
        `machinesim.cutting.relief`), "boolean" when the sweeps were subtracted.
    elapsed_s : float
        Wall time of the call, s.
    """

    removed_volume: float
    n_sweeps: int
    n_sweeps_cut: int
    n_degenerate: int
    empty_cut: bool
    sideways: tuple[int, ...]
    n_cells: int
    method: str
    elapsed_s: float


def rotary_substeps(radius: float, angle: float, chord_tol: float = 1e-9) -> int:
    """Sub-steps that keep a point at ``radius`` from a rotation axis within ``chord_tol``.

    A point turning by ``step`` about an axis at distance r leaves its chord by the sagitta
    r (1 - cos(step / 2)); the count is the fewest equal steps over ``angle`` with a sagitta
    at most ``chord_tol``.

    Parameters
    ----------
    radius : float
        Largest distance of a tool point from the rotation axis, m.
    angle : float
        Rotation of the move, rad.
    chord_tol : float
        Largest chord error, m (default 1 nm, the axis resolution).
    """
    if radius <= 0.0 or angle == 0.0:
        return 1
    return arc_segments(radius, abs(angle), chord_tol)


def _check_paths(paths) -> list[np.ndarray]:
    """Paths as float64 arrays (N_i, 4, 4) of rigid transforms, else InputError naming one."""
    arrays = []
    for index, path in enumerate(paths):
        poses = np.asarray(path, dtype=np.float64)
        if poses.ndim != 3 or poses.shape[1:] != (4, 4):
            raise InputError(
                f"path {index}: expected poses of shape (N, 4, 4), got {poses.shape}",
                key="paths",
            )
        arrays.append(poses)
    if not arrays:
        return arrays
    poses = np.concatenate(arrays)
    rotation = poses[:, :3, :3]
    error = np.abs(np.einsum("nji,njk->nik", rotation, rotation) - np.eye(3)).reshape(-1, 9)
    bottom = np.abs(poses[:, 3] - [0.0, 0.0, 0.0, 1.0])
    bad = ~np.isfinite(poses).reshape(-1, 16).all(axis=1)
    bad |= (error.max(axis=1, initial=0.0) > RIGID_TOL) | (bottom.max(axis=1, initial=0.0) > 0.0)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        path = int(np.searchsorted(np.cumsum([len(a) for a in arrays]), first, side="right"))
        raise InputError(
            f"path {path}: pose {first - sum(len(a) for a in arrays[:path])} is not a rigid "
            f"transform (finite, orthonormal rotation within {RIGID_TOL}, last row 0 0 0 1): "
            f"{poses[first].tolist()}",
            key="paths",
        )
    return arrays


def _check_roi(roi, bounds: np.ndarray) -> list[tuple[float, float, float, float]]:
    windows = np.asarray(roi, dtype=np.float64)
    if windows.ndim != 2 or windows.shape[1] != 4 or not np.all(np.isfinite(windows)):
        raise InputError(
            f"roi: expected windows (xmin, xmax, ymin, ymax) of shape (n, 4), got "
            f"{windows.shape}",
            key="roi",
        )
    if np.any(windows[:, 1] <= windows[:, 0]) or np.any(windows[:, 3] <= windows[:, 2]):
        raise InputError("roi: each window needs xmin < xmax and ymin < ymax", key="roi")
    cells = []
    for xmin, xmax, ymin, ymax in windows:
        box = (max(xmin, bounds[0, 0]), min(xmax, bounds[1, 0]),
               max(ymin, bounds[0, 1]), min(ymax, bounds[1, 1]))
        if box[0] < box[1] and box[2] < box[3]:
            cells.append(box)
    return cells


class _Sweeps:
    """The sweeps of all paths, built chunk by chunk into clipped convex hulls."""

    def __init__(self, tool, paths: list[np.ndarray], clip_z: float) -> None:
        self.rotational = bool(tool.rotational)
        self.vertices = np.asarray(tool.vertices(), dtype=np.float64)
        edges = np.asarray(tool.edges(), dtype=np.int64)
        self.clip_z = clip_z
        self.poses = np.concatenate(paths) if paths else np.zeros((0, 4, 4))
        firsts = np.cumsum([0] + [len(poses) for poses in paths])
        # A sweep joins pose i to pose i + 1 of the same path, never across paths.
        self.pairs = np.concatenate(
            [np.arange(a, b - 1) for a, b in zip(firsts[:-1], firsts[1:], strict=True)]
            + [np.zeros(0, dtype=np.int64)]
        ).astype(np.int64)
        self.count = len(self.pairs)
        k = len(self.vertices)
        # Candidate edges of hull(T0, T1), T1 = points k.. 2k-1: for a translation the edges
        # of T0, of T1 and each vertex's own path; for a rotation any T0-T1 pair as well.
        ends = np.stack([np.arange(k), np.arange(k) + k], axis=1)
        self.translation_segments = np.concatenate([edges, edges + k, ends])
        self.rotation_segments = None
        if k <= PAIR_CLIP_MAX_VERTICES:
            i, j = np.meshgrid(np.arange(k), np.arange(k) + k, indexing="ij")
            self.rotation_segments = np.concatenate(
                [edges, edges + k, np.stack([i.ravel(), j.ravel()], axis=1)]
            )

    def _clip(self, points: np.ndarray, segments):
        """Point sets whose hulls are the sweeps' hulls cut by z <= clip_z, and their bounds.

        ``points`` has shape (s, 2k, 3). Every candidate lies in the hull, and every vertex
        of the clipped hull is a point below the plane or a crossing of a hull edge, so the
        hull of the candidates is exactly the clipped sweep.

        Returns
        -------
        candidates : list of (ndarray, shape (c, 3)) or None
            None where the whole sweep lies above the plane.
        lower, upper : ndarray, shape (s, 3)
            Bounds of each candidate set, m.
        """
        below = points[:, :, 2] <= self.clip_z
        if segments is None:
            kept = [p if b.any() else None for p, b in zip(points, below, strict=True)]
            return kept, points.min(axis=1), points.max(axis=1)
        a, b = points[:, segments[:, 0]], points[:, segments[:, 1]]
        crossing = below[:, segments[:, 0]] != below[:, segments[:, 1]]
        # Segments that do not cross may divide by zero; only crossing ones are read.
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (self.clip_z - a[:, :, 2]) / (b[:, :, 2] - a[:, :, 2])
            cut = a + t[:, :, None] * (b - a)
        cut[:, :, 2] = self.clip_z
        every = np.concatenate([points, cut], axis=1)
        valid = np.concatenate([below, crossing], axis=1)[:, :, None]
        lower = np.where(valid, every, np.inf).min(axis=1)
        upper = np.where(valid, every, -np.inf).max(axis=1)
        out = []
        for sweep, state in enumerate(below.sum(axis=1)):
            if state == below.shape[1]:
                out.append(points[sweep])
            elif state == 0:
                out.append(None)
            else:
                out.append(np.concatenate([points[sweep][below[sweep]],
                                           cut[sweep][crossing[sweep]]]))
        return out, lower, upper

    def hulls(self, keep: Callable[[np.ndarray, np.ndarray], np.ndarray]):
        """Clipped hulls of the sweeps whose point bounds pass ``keep``.

        Returns
        -------
        hulls : list of manifold3d.Manifold
        lower, upper : ndarray, shape (s, 3)
            Bounds of each clipped hull's points, m.
        direction : ndarray, shape (s, 3)
            Displacement of the tool tip over each sweep, m.
        n_degenerate : int
        sideways : list of int
            Sweep indices (over all paths) that drag a non-rotational tool sideways.
        """
        hulls, lower, upper, direction, sideways = [], [], [], [], []
        n_degenerate = 0
        rotation, origin = self.poses[:, :3, :3], self.poses[:, :3, 3]
        k = len(self.vertices)
        nseg = len(self.translation_segments)
        if self.rotation_segments is not None:
            nseg = max(nseg, len(self.rotation_segments))
        step = max(1, POINTS_PER_CHUNK // (2 * k + nseg))
        for begin in range(0, self.count, step):
            first = self.pairs[begin:begin + step]
            r0, r1 = rotation[first], rotation[first + 1]
            move = origin[first + 1] - origin[first]
            if not self.rotational:
                sideways.extend((begin + np.flatnonzero(dragged(r0, move))).tolist())
            p0 = np.einsum("nij,kj->nki", r0, self.vertices) + origin[first][:, None, :]
            p1 = np.einsum("nij,kj->nki", r1, self.vertices) + origin[first + 1][:, None, :]
            points = np.concatenate([p0, p1], axis=1)
            chosen = np.flatnonzero(keep(points.min(axis=1), points.max(axis=1)))
            same = np.abs(r1 - r0).reshape(-1, 9).max(axis=1) <= SAME_ORIENTATION
            for subset, segments in ((chosen[same[chosen]], self.translation_segments),
                                     (chosen[~same[chosen]], self.rotation_segments)):
                kept, low, high = self._clip(points[subset], segments)
                for row, (offset, candidates) in enumerate(zip(subset, kept, strict=True)):
                    if candidates is None:
                        continue
                    hull = manifold3d.Manifold.hull_points(candidates)
                    # Coplanar points give an empty or a flat, zero-volume hull.
                    if hull.is_empty() or not hull.volume() > 0.0:
                        n_degenerate += 1
                        continue
                    hulls.append(hull)
                    lower.append(low[row])
                    upper.append(high[row])
                    direction.append(move[offset])
        shape = (-1, 3)
        return (hulls, np.array(lower).reshape(shape), np.array(upper).reshape(shape),
                np.array(direction).reshape(shape), n_degenerate, sideways)


def dragged(rotation: np.ndarray, move: np.ndarray) -> np.ndarray:
    """Which moves (s, 3) drag a non-rotational tool at ``rotation`` (s, 3, 3) sideways."""
    local = np.einsum("nji,nj->ni", rotation, move)
    length = np.linalg.norm(local, axis=1)
    return (np.abs(local[:, 1]) > SIDEWAYS_REL * length) & (length > 0.0)


def _direction_keys(direction: np.ndarray) -> np.ndarray:
    """Group key per sweep: its XY travel direction modulo pi, in bins; -1 for no XY travel."""
    planar = np.hypot(direction[:, 0], direction[:, 1])
    angle = np.mod(np.arctan2(direction[:, 1], direction[:, 0]), math.pi)
    bins = int(round(math.pi / DIRECTION_BIN_RAD))
    key = np.mod(np.rint(angle / DIRECTION_BIN_RAD).astype(np.int64), bins)
    return np.where(planar > PLANAR_TRAVEL_REL * np.linalg.norm(direction, axis=1), key, -1)


def remove(
    stock: Part,
    tool,
    paths: Sequence,
    *,
    roi=None,
    progress: Callable[[int, int], None] | None = None,
    sweeps_per_tile: int = SWEEPS_PER_TILE,
    method: str = "auto",
) -> tuple[Part, EngineReport]:
    """Cut ``stock`` with ``tool`` moved along ``paths``.

    Parameters
    ----------
    stock : Part
        The stock, workpiece frame, m.
    tool : VTool or RoundNoseTool or BallEndMill
        The tool (machinesim.tools), in its tool_tip frame.
    paths : sequence of array-like, each shape (N_i, 4, 4)
        wMt poses of the tool_tip frame in the workpiece frame (m). Consecutive poses of a
        path form sweeps; nothing joins one path to the next.
    roi : array-like, shape (n, 4), optional
        Windows (xmin, xmax, ymin, ymax), m. Only sweeps touching a window are cut and the
        result is the stock clipped to the windows.
    progress : callable(done, total), optional
        Called as cells are cut, in units of sweep-cell pairs.
    sweeps_per_tile : int
        Cells are split into a grid of tiles until each has at most this many sweeps (or
        splitting stops paying, see `SPLIT_GAIN`); a huge value disables tiling.
    method : {"auto", "boolean"}
        "auto" meshes the cut as a height field when every sweep that reaches the stock is
        a straight groove along X or Y right across a block (or a part cut that way before),
        `machinesim.cutting.relief`, and subtracts sweeps otherwise; "boolean" always
        subtracts. Both are exact; the height field is 10-20 times faster on groove patterns.

    Returns
    -------
    part : Part
        The machined part (clipped to ``roi`` if given).
    report : EngineReport
    """
    start = time.perf_counter()
    paths = _check_paths(paths)
    bounds = stock.bounds
    scale = float(np.abs(bounds).max()) or 1.0
    margin = CLIP_MARGIN_REL * scale
    if roi is None:
        cells = [(bounds[0, 0] - margin, bounds[1, 0] + margin,
                  bounds[0, 1] - margin, bounds[1, 1] + margin)]
    else:
        cells = _check_roi(roi, bounds)
    cell_array = np.array(cells).reshape(-1, 4)
    z_low, z_high = bounds[0, 2] - margin, bounds[1, 2] + margin

    def touches(low: np.ndarray, high: np.ndarray) -> np.ndarray:
        inside = (low[:, 2] <= z_high) & (high[:, 2] >= z_low)
        hit = ((low[:, None, 0] <= cell_array[None, :, 1] + margin)
               & (high[:, None, 0] >= cell_array[None, :, 0] - margin)
               & (low[:, None, 1] <= cell_array[None, :, 3] + margin)
               & (high[:, None, 1] >= cell_array[None, :, 2] - margin))
        return inside & hit.any(axis=1)

    sweeps = _Sweeps(tool, paths, z_high)
    if method not in ("auto", "boolean"):
        raise InputError(f"method must be 'auto' or 'boolean', got {method!r}", key="method")
    if method == "auto" and sweeps.count:
        relief = cut_reliefs(stock, sweeps.vertices, sweeps.poses, sweeps.pairs,
                             None if roi is None else cells)
        if relief is not None:
            if progress is not None:
                progress(0, relief.n_sweeps_cut)
                progress(relief.n_sweeps_cut, relief.n_sweeps_cut)
            sideways = []
            if not sweeps.rotational:
                first = sweeps.pairs
                move = sweeps.poses[first + 1, :3, 3] - sweeps.poses[first, :3, 3]
                sideways = np.flatnonzero(dragged(sweeps.poses[first, :3, :3], move)).tolist()
            report = EngineReport(
                removed_volume=relief.removed_volume,
                n_sweeps=sweeps.count,
                n_sweeps_cut=relief.n_sweeps_cut,
                n_degenerate=relief.n_degenerate,
                empty_cut=not relief.removed_volume > EMPTY_REL * relief.stock_volume,
                sideways=tuple(sideways),
                n_cells=len(relief.part.reliefs),
                method="relief",
                elapsed_s=time.perf_counter() - start,
            )
            return relief.part, report
    hulls, lower, upper, direction, n_degenerate, sideways = sweeps.hulls(touches)
    keys = _direction_keys(direction)

    plan = [(cell, grid_tiles(cell, members_in(lower, upper, cell, margin), lower, upper, margin,
                          sweeps_per_tile)) for cell in cells]
    total = int(sum(len(members) for _, tiles in plan for _, members in tiles))
    done = 0
    if progress is not None:
        progress(done, total)

    base = stock.manifold
    stock_pieces, cell_parts = [], []
    for cell, tiles in plan:
        pieces = []
        for (xmin, xmax, ymin, ymax), members in tiles:
            if roi is None and len(tiles) == 1:
                piece = base
            else:
                piece = base ^ exact_box(*tile_box((xmin, xmax, ymin, ymax), cell, roi is None,
                                                    bounds, scale))
            stock_pieces.append(piece)
            for key in np.unique(keys[members]):
                group = [hulls[i] for i in members[keys[members] == key]]
                piece = piece - manifold3d.Manifold.batch_boolean(group, OpType.Add)
                # Evaluate now: manifold3d is lazy and would flatten A - B - C into
                # A - (B + C), the union of crossing groups this loop exists to avoid.
                piece.num_tri()
            pieces.append(piece)
            done += len(members)
            if progress is not None:
                progress(done, total)
        joined = None
        if len(pieces) > 1:
            joined = stitch(pieces, [box for box, _ in tiles], cell, scale)
        cell_parts.append(joined if joined is not None
                          else manifold3d.Manifold.batch_boolean(pieces, OpType.Add))
    result = (manifold3d.Manifold.batch_boolean(cell_parts, OpType.Add) if cell_parts
              else manifold3d.Manifold())
    if overlapping(cell_array):
        stock_volume = manifold3d.Manifold.batch_boolean(stock_pieces, OpType.Add).volume()
    else:
        stock_volume = sum(piece.volume() for piece in stock_pieces)
    removed = stock_volume - result.volume()
    report = EngineReport(
        removed_volume=removed,
        n_sweeps=sweeps.count,
        n_sweeps_cut=len(hulls),
        n_degenerate=n_degenerate,
        empty_cut=not removed > EMPTY_REL * stock_volume,
        sideways=tuple(int(i) for i in sideways),
        n_cells=sum(len(tiles) for _, tiles in plan),
        method="boolean",
        elapsed_s=time.perf_counter() - start,
    )
    return Part(result), report
