"""Exact material removal: stock minus the convex sweeps of a tool along pose sequences.

A sweep is the convex hull of the tool at two consecutive poses of a path (float64,
`manifold3d.Manifold.hull_points`). For a move at fixed orientation this is the exact volume
swept by the tool; a move that rotates must arrive already split into sub-steps whose chord
error is within tolerance (`rotary_substeps`).

Speed comes from never touching the part mesh once per sweep:

1. Tool points for all poses are transformed at once (numpy).
2. Each sweep is clipped, before its hull is built, to the half-space a hair above the top
   of the stock (`CLIP_MARGIN_REL`). The part is unchanged (nothing above the stock is
   material), but tall tool bodies no longer overlap their neighbours, so parallel sweeps
   stay (almost) disjoint and their union is nearly free.
3. Sweeps are grouped by their direction of travel in XY. Parallel sweeps are unioned in
   one `batch_boolean`; groups that cross each other are subtracted one after the other,
   because the union of crossing sweeps costs as much as cutting them.
4. The region is split into cells (ROI windows, and tiles inside them): each cell is cut
   with only the sweeps that touch it, so no boolean handles a polygon with thousands of
   notches, and cells are joined by one union at the end.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import manifold3d
import numpy as np
from manifold3d import OpType

from machinesim.cutting.stitch import exact_box, stitch
from machinesim.exceptions import InputError
from machinesim.workpiece import Part

#: Sweeps are clipped at z = stock top + CLIP_MARGIN_REL * (largest stock coordinate). The
#: margin is 10^6 times manifold3d's own tolerance (1e-12 relative), so the clip plane never
#: merges with the top face, and small enough (10 nm on a 10 mm part) that the slivers by
#: which neighbouring clipped grooves still overlap are tiny.
CLIP_MARGIN_REL = 1e-6
#: Two poses have the same orientation when their rotation matrices differ by at most this:
#: then the sweep is a translation and its hull edges are known, so clipping needs no pair
#: search. 1e-12 is the kinematic agreement of two float64 chains (tolerances.POSE_M / 1 m).
SAME_ORIENTATION = 1e-12
#: A non-rotational tool is dragged sideways when its move direction, in the tool frame, has
#: a Y component above this fraction of the move: 1 urad, i.e. the groove widens by more than
#: 1 nm per mm of travel, far above float64 round-off of a kinematic chain (~1e-15).
SIDEWAYS_REL = 1e-6
#: Sweeps travelling within this angle (rad) in XY are cut together as one parallel group.
DIRECTION_BIN_RAD = math.radians(5.0)
#: Rotating sweeps clip only when the all-pairs edge search is small: beyond this many tool
#: vertices their hull is built unclipped (still exact, only slower to union).
PAIR_CLIP_MAX_VERTICES = 64
#: Sweeps whose tool points are processed together: bounds the transient memory (k points
#: per pose, ~100 bytes each) to ~50 MB whatever the path length.
POINTS_PER_CHUNK = 1 << 19
#: A cut is empty when it removes at most this fraction of the stock volume: the round-off of
#: a float64 volume sum over ~10^6 triangles is ~1e-13 relative. A real cut smaller than
#: this (a 1 nm scratch on a 0.1 l block) is reported empty too.
EMPTY_REL = 1e-12
#: Tiles are made small enough to hold this many sweeps: manifold3d's boolean cost grows faster than
#: the sweep count (measured: 2000 grooves cost 1.6x more in one piece than in 8 tiles).
SWEEPS_PER_TILE = 256
#: Interior tile walls sit this fraction of a tile width before the regular grid lines, in
#: X and in Y. Not 0: patterns laid out on round numbers put grooves and ridges exactly on
#: regular grid lines, and a wall through a feature line makes manifold3d resolve coincident
#: geometry. Not equal: on a square cell, equal X and Y walls meet on the diagonal, where the
#: X and Y grooves of a symmetric crossing pattern cross a tile corner at the same height
#: (measured: one such tile 30x slower than its neighbours). Irrational values make such
#: coincidences unlikely.
WALL_OFFSET = ((math.sqrt(5.0) - 2.0) / 10.0, (math.sqrt(2.0) - 1.3) / 10.0)
#: Most tiles per cell: bounds the member bookkeeping (tiles x sweeps).
MAX_TILES = 4096
#: A doubling of the tile grid must leave at most this fraction of the fullest tile's sweeps.
SPLIT_GAIN = 0.8


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
        Cells (ROI windows times tiles) the region was cut in.
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
    if chord_tol >= radius:
        return max(1, math.ceil(abs(angle) / math.pi))
    step = 2.0 * math.acos(1.0 - chord_tol / radius)
    return max(1, math.ceil(abs(angle) / step - 1e-12))


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
    bad |= (error.max(axis=1, initial=0.0) > 1e-9) | (bottom.max(axis=1, initial=0.0) > 0.0)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        path = int(np.searchsorted(np.cumsum([len(a) for a in arrays]), first, side="right"))
        raise InputError(
            f"path {path}: pose {first - sum(len(a) for a in arrays[:path])} is not a rigid "
            f"transform (finite, orthonormal rotation within 1e-9, last row 0 0 0 1): "
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

    def _clip(self, points: np.ndarray, segments) -> list[np.ndarray | None]:
        """Point sets whose hulls are the sweeps' hulls cut by z <= clip_z (None: all above).

        ``points`` has shape (s, 2k, 3). Every candidate lies in the hull, and every vertex
        of the clipped hull is a point below the plane or a crossing of a hull edge, so the
        hull of the candidates is exactly the clipped sweep.
        """
        below = points[:, :, 2] <= self.clip_z
        if segments is None:
            return [p if b.any() else None for p, b in zip(points, below, strict=True)]
        a, b = points[:, segments[:, 0]], points[:, segments[:, 1]]
        crossing = below[:, segments[:, 0]] != below[:, segments[:, 1]]
        # Segments that do not cross may divide by zero; only crossing ones are read.
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (self.clip_z - a[:, :, 2]) / (b[:, :, 2] - a[:, :, 2])
            cut = a + t[:, :, None] * (b - a)
        cut[:, :, 2] = self.clip_z
        out = []
        for sweep in range(len(points)):
            keep = below[sweep]
            if keep.all():
                out.append(points[sweep])
            elif not keep.any():
                out.append(None)
            else:
                out.append(np.concatenate([points[sweep][keep], cut[sweep][crossing[sweep]]]))
        return out

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
                local = np.einsum("nji,nj->ni", r0, move)
                length = np.linalg.norm(local, axis=1)
                lateral = (np.abs(local[:, 1]) > SIDEWAYS_REL * length) & (length > 0.0)
                sideways.extend((begin + np.flatnonzero(lateral)).tolist())
            p0 = np.einsum("nij,kj->nki", r0, self.vertices) + origin[first][:, None, :]
            p1 = np.einsum("nij,kj->nki", r1, self.vertices) + origin[first + 1][:, None, :]
            points = np.concatenate([p0, p1], axis=1)
            chosen = np.flatnonzero(keep(points.min(axis=1), points.max(axis=1)))
            same = np.abs(r1 - r0).reshape(-1, 9).max(axis=1) <= SAME_ORIENTATION
            for subset, segments in ((chosen[same[chosen]], self.translation_segments),
                                     (chosen[~same[chosen]], self.rotation_segments)):
                for offset, candidates in zip(
                    subset, self._clip(points[subset], segments), strict=True
                ):
                    if candidates is None:
                        continue
                    hull = manifold3d.Manifold.hull_points(candidates)
                    # Coplanar points give an empty or a flat, zero-volume hull.
                    if hull.is_empty() or not hull.volume() > 0.0:
                        n_degenerate += 1
                        continue
                    hulls.append(hull)
                    lower.append(candidates.min(axis=0))
                    upper.append(candidates.max(axis=0))
                    direction.append(move[offset])
        shape = (-1, 3)
        return (hulls, np.array(lower).reshape(shape), np.array(upper).reshape(shape),
                np.array(direction).reshape(shape), n_degenerate, sideways)


def _direction_keys(direction: np.ndarray) -> np.ndarray:
    """Group key per sweep: its XY travel direction modulo pi, in bins; -1 for no XY travel."""
    planar = np.hypot(direction[:, 0], direction[:, 1])
    angle = np.mod(np.arctan2(direction[:, 1], direction[:, 0]), math.pi)
    bins = int(round(math.pi / DIRECTION_BIN_RAD))
    key = np.mod(np.rint(angle / DIRECTION_BIN_RAD).astype(np.int64), bins)
    return np.where(planar > 1e-3 * np.linalg.norm(direction, axis=1), key, -1)


def _members(lower, upper, box, margin: float) -> np.ndarray:
    """Indices of the sweeps whose bounds reach the box (xmin, xmax, ymin, ymax)."""
    return np.flatnonzero(
        (lower[:, 0] <= box[1] + margin) & (upper[:, 0] >= box[0] - margin)
        & (lower[:, 1] <= box[3] + margin) & (upper[:, 1] >= box[2] - margin)
    )


def _walls(low: float, high: float, count: int, axis: int) -> np.ndarray:
    """Tile boundaries along one axis: the ends and ``count - 1`` offset interior walls."""
    inner = low + (high - low) * (np.arange(1, count) - WALL_OFFSET[axis]) / count
    return np.concatenate([[low], inner, [high]])


def _grid_ranges(lower, upper, walls, axis: int, margin: float):
    """First and last tile index along ``axis`` that each sweep's bounds reach."""
    inner = walls[1:-1]
    first = np.searchsorted(inner, lower[:, axis] - margin, side="left")
    last = np.searchsorted(inner, upper[:, axis] + margin, side="right")
    return first, last


def _tiles(box, members, lower, upper, margin: float, target: int):
    """Split a cell (xmin, xmax, ymin, ymax) into a grid of tiles with few sweeps each.

    The grid doubles along X or Y, whichever leaves the fullest tile emptier, until every
    tile has at most ``target`` sweeps, or a doubling would keep more than `SPLIT_GAIN` of
    the fullest tile's sweeps (sweeps that span the cell gain nothing from more tiles, and
    every tile adds wall geometry). A grid, not a k-d split: a wall must be shared whole by
    the two tiles beside it for `stitch` to join them.

    Returns
    -------
    list of (box, members)
    """
    low, high = lower[members], upper[members]

    def fullest(counts) -> int:
        grid = np.zeros((counts[0] + 1, counts[1] + 1), dtype=np.int64)
        ranges = [_grid_ranges(low, high, _walls(box[2 * a], box[2 * a + 1], counts[a], a),
                               a, margin) for a in (0, 1)]
        (x0, x1), (y0, y1) = ranges
        for dx, dy, sign in ((x0, y0, 1), (x1 + 1, y0, -1), (x0, y1 + 1, -1),
                             (x1 + 1, y1 + 1, 1)):
            np.add.at(grid, (dx, dy), sign)
        return int(grid.cumsum(0).cumsum(1).max(initial=0))

    counts, worst = [1, 1], len(members)
    while worst > target and counts[0] * counts[1] < MAX_TILES:
        options = [(fullest(c), c) for c in ([2 * counts[0], counts[1]],
                                              [counts[0], 2 * counts[1]])]
        best, choice = min(options, key=lambda option: option[0])
        if best > SPLIT_GAIN * worst:
            break
        worst, counts = best, choice
    walls = [_walls(box[2 * a], box[2 * a + 1], counts[a], a) for a in (0, 1)]
    (x0, x1), (y0, y1) = (_grid_ranges(low, high, walls[a], a, margin) for a in (0, 1))
    tiles = []
    for i in range(counts[0]):
        in_column = (x0 <= i) & (x1 >= i)
        for j in range(counts[1]):
            inside = members[in_column & (y0 <= j) & (y1 >= j)]
            tiles.append(((walls[0][i], walls[0][i + 1], walls[1][j], walls[1][j + 1]), inside))
    return tiles


def _overlapping(cells: np.ndarray) -> bool:
    """True when two of the windows (n, 4) overlap with positive area."""
    x = (cells[:, None, 0] < cells[None, :, 1]) & (cells[None, :, 0] < cells[:, None, 1])
    y = (cells[:, None, 2] < cells[None, :, 3]) & (cells[None, :, 2] < cells[:, None, 3])
    both = x & y
    np.fill_diagonal(both, False)
    return bool(both.any())


def remove(
    stock: Part,
    tool,
    paths: Sequence,
    *,
    roi=None,
    progress: Callable[[int, int], None] | None = None,
    sweeps_per_tile: int = SWEEPS_PER_TILE,
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
    hulls, lower, upper, direction, n_degenerate, sideways = sweeps.hulls(touches)
    keys = _direction_keys(direction)

    plan = [(cell, _tiles(cell, _members(lower, upper, cell, margin), lower, upper, margin,
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
                piece = base ^ exact_box(xmin, xmax, ymin, ymax, z_low - margin, z_high)
            stock_pieces.append(piece)
            for key in np.unique(keys[members]):
                group = [hulls[i] for i in members[keys[members] == key]]
                piece = piece - manifold3d.Manifold.batch_boolean(group, OpType.Add)
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
    if _overlapping(cell_array):
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
        elapsed_s=time.perf_counter() - start,
    )
    return Part(result), report
