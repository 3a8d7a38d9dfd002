"""Tiling a cell into a grid of tiles, each cut with only the sweeps that reach it, and a
tile's parallel sweeps into runs, each united and subtracted on its own."""

from __future__ import annotations

import math

import numpy as np

from machinesim.tolerances import BOX_CLEARANCE_REL

#: Tiles are made small enough to hold this many sweeps: manifold3d's boolean cost grows
#: faster than the sweep count (measured: 2000 parallel grooves 0.30 s in one piece, 0.21 s
#: in 8 tiles; 500 x 500 crossing grooves 13.9 s in one piece, 11.9 s in 16 tiles).
SWEEPS_PER_TILE = 256
#: Interior tile walls sit this fraction of a tile width before the regular grid lines. Not
#: 0: patterns laid out on round numbers would put groove bottoms and ridges exactly in the
#: walls, coincident geometry that manifold3d must resolve and that stitching then carries
#: (measured on 500 x 500 crossing grooves: 3 % more triangles, same time). An irrational
#: fraction makes such coincidences unlikely.
WALL_OFFSET = (math.sqrt(5.0) - 2.0) / 10.0
#: A union of sweeps holds at most this many pairs that overlap each other. manifold3d's
#: union costs about as much per overlapping pair, so a group of sweeps that all overlap
#: (finishing passes stacked down an inclined face: the tool body of each reaches the
#: passes above it) unites in a time that grows as its size squared, while subtracting
#: costs about the part's size each time. Measured on one crown face, 357 passes each
#: overlapping ~250 others, cut into a 150,000-triangle part: one union 76 s; runs of 8
#: (28 pairs) 9.4 s; of 1, 2, 4, 16, 64: 27, 15, 9.8, 10.5, 21 s; the same part within
#: 6e-18 m. Sweeps side by side (grooves at their own width's pitch) overlap no other, so
#: they stay in one union, as fast as before.
PAIRS_PER_UNION = 28
#: Two sweeps overlap when their boxes do by more than this fraction of the narrower box,
#: along every axis (grooves that only touch are not counted).
OVERLAP_FRACTION = 0.1
#: Most sweeps in one union (bounds the pair bookkeeping, span^2 per run).
MAX_RUN = 1024
#: Most tiles per cell: bounds the member bookkeeping (tiles x sweeps).
MAX_TILES = 4096
#: A doubling of the tile grid must leave at most this fraction of the fullest tile's sweeps.
SPLIT_GAIN = 0.8


def members_in(lower, upper, box, margin: float) -> np.ndarray:
    """Indices of the sweeps whose bounds reach the box (xmin, xmax, ymin, ymax)."""
    return np.flatnonzero(
        (lower[:, 0] <= box[1] + margin) & (upper[:, 0] >= box[0] - margin)
        & (lower[:, 1] <= box[3] + margin) & (upper[:, 1] >= box[2] - margin)
    )


def _walls(low: float, high: float, count: int) -> np.ndarray:
    """Tile boundaries along one axis: the ends and ``count - 1`` offset interior walls."""
    inner = low + (high - low) * (np.arange(1, count) - WALL_OFFSET) / count
    return np.concatenate([[low], inner, [high]])


def _grid_ranges(lower, upper, walls, axis: int, margin: float):
    """First and last tile index along ``axis`` that each sweep's bounds reach."""
    inner = walls[1:-1]
    first = np.searchsorted(inner, lower[:, axis] - margin, side="left")
    last = np.searchsorted(inner, upper[:, axis] + margin, side="right")
    return first, last


def grid_tiles(box, members, lower, upper, margin: float, target: int):
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
        ranges = [_grid_ranges(low, high, _walls(box[2 * a], box[2 * a + 1], counts[a]),
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
    walls = [_walls(box[2 * a], box[2 * a + 1], counts[a]) for a in (0, 1)]
    (x0, x1), (y0, y1) = (_grid_ranges(low, high, walls[a], a, margin) for a in (0, 1))
    tiles = []
    for i in range(counts[0]):
        in_column = (x0 <= i) & (x1 >= i)
        for j in range(counts[1]):
            inside = members[in_column & (y0 <= j) & (y1 >= j)]
            tiles.append(((walls[0][i], walls[0][i + 1], walls[1][j], walls[1][j + 1]), inside))
    return tiles


def tile_box(tile, cell, open_sides: bool, bounds: np.ndarray, scale: float):
    """Box (xmin, xmax, ymin, ymax, zmin, zmax) that cuts a tile out of the stock.

    Its top and bottom, and with ``open_sides`` its sides on the cell boundary, lie
    `BOX_CLEARANCE_REL` * scale beyond the stock: sweeps are clipped at the same height
    margin as the cell's edges, so a box face there would coincide with their top faces and
    edges, geometry manifold3d would have to resolve. Only the interior walls cut the stock.
    """
    clearance = BOX_CLEARANCE_REL * scale
    box = list(tile)
    if open_sides:
        for side in range(4):
            if tile[side] == cell[side]:
                box[side] += clearance if side % 2 else -clearance
    return (*box, bounds[0, 2] - clearance, bounds[1, 2] + clearance)


def overlapping(cells: np.ndarray) -> bool:
    """True when two of the windows (n, 4) overlap with positive area."""
    x = (cells[:, None, 0] < cells[None, :, 1]) & (cells[None, :, 0] < cells[:, None, 1])
    y = (cells[:, None, 2] < cells[None, :, 3]) & (cells[None, :, 2] < cells[:, None, 3])
    both = x & y
    np.fill_diagonal(both, False)
    return bool(both.any())


def union_runs(members: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> list[np.ndarray]:
    """Split sweeps into runs, in their order, each with at most `PAIRS_PER_UNION`
    overlapping pairs (`OVERLAP_FRACTION`) and `MAX_RUN` sweeps: each run is united and
    subtracted on its own.

    Parameters
    ----------
    members : ndarray of int
        Sweep indices, in program order (neighbours in a run are neighbours on the part).
    lower, upper : ndarray, shape (s, 3)
        Bounds of every sweep, m.
    """
    runs, start = [], 0
    while start < len(members):
        span = SWEEPS_PER_TILE  # a tile's sweeps: one block, most often
        while True:
            block = members[start:start + span]
            low, high = lower[block], upper[block]
            overlap = (np.minimum(high[:, None], high[None]) - np.maximum(low[:, None], low[None]))
            extent = high - low
            narrower = np.minimum(extent[:, None], extent[None])
            pairs = np.tril((overlap > OVERLAP_FRACTION * narrower).all(axis=2), k=-1)
            over = np.flatnonzero(np.cumsum(pairs.sum(axis=1)) > PAIRS_PER_UNION)
            if len(over) or len(block) < span or span >= MAX_RUN:
                break
            span *= 2
        end = int(over[0]) if len(over) else len(block)
        runs.append(block[:end])
        start += end
    return runs
