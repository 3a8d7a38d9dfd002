"""Which of many boxes, fixed once, overlap a query box, among the first ``k`` of them: an
XY grid of cells, each listing the boxes that reach it, so that a query reads the few cells
its box covers instead of comparing every box (`machinesim.cutting.rapids`: the rapid check
asked every earlier sweep's box for each rapid, and a program of 20,000 rapids spent minutes
there, growing as the square of the rapids).

The grid only narrows: `BoxGrid.candidates` returns every box before ``k`` that shares a
cell with the query (a superset of those that overlap it), and the caller applies its own
exact comparison, so the answer is the one comparing every box gives.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BoxGrid"]

#: Cells along each of X and Y at most: bounds the grid when a few boxes are small and far
#: apart (the cell is then wider than the typical box).
MAX_CELLS_PER_AXIS = 1024
#: A box reaching more cells than this is kept in one list every query reads (a long move
#: across the part): listed in each cell, it would cost its cell count in memory.
WIDE_CELLS = 16
#: A query covering more cells than this reads every box instead (a rapid across the part:
#: most boxes overlap it anyway).
MAX_QUERY_CELLS = 64


class BoxGrid:
    """Boxes ``low``, ``high`` (n, 3), m, indexed by the XY cells they reach.

    The cell is as wide as the median box along each axis (so a typical box reaches at most
    two cells a side), and no narrower than the boxes' span over `MAX_CELLS_PER_AXIS`.
    """

    def __init__(self, low: np.ndarray, high: np.ndarray) -> None:
        self.n = len(low)
        if not self.n:
            self.origin, self.cell, self.shape = np.zeros(2), np.ones(2), (1, 1)
            self.cells = self.boxes = self.wide = np.zeros(0, dtype=np.int64)
            return
        low2, high2 = np.asarray(low)[:, :2], np.asarray(high)[:, :2]
        self.origin = low2.min(axis=0)
        span = high2.max(axis=0) - self.origin
        cell = np.maximum(np.median(high2 - low2, axis=0), span / MAX_CELLS_PER_AXIS)
        self.cell = np.where(cell > 0.0, cell, 1.0)
        top = np.floor(span / self.cell).astype(np.int64)
        self.shape = (int(top[0]) + 1, int(top[1]) + 1)
        first, last = self._index(low2), self._index(high2)
        count = np.prod(last - first + 1, axis=1)
        wide = count > WIDE_CELLS
        self.wide = np.flatnonzero(wide)
        boxes = np.flatnonzero(~wide)
        count, first, last = count[boxes], first[boxes], last[boxes]
        rows = last[:, 1] - first[:, 1] + 1
        box = np.repeat(np.arange(len(boxes)), count)
        within = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        ix = first[box, 0] + within // rows[box]
        iy = first[box, 1] + within % rows[box]
        cells = ix * self.shape[1] + iy
        order = np.argsort(cells, kind="stable")
        #: the cell of each (cell, box) pair, sorted, and its box (in box order per cell)
        self.cells, self.boxes = cells[order], boxes[box[order]]

    def _index(self, points: np.ndarray) -> np.ndarray:
        """The cell (ix, iy) of each XY point (..., 2), clipped to the grid: monotonic in
        each coordinate, so boxes that overlap share a cell."""
        index = np.floor((points - self.origin) / self.cell)
        return np.clip(index, 0, np.array(self.shape) - 1).astype(np.int64)

    def candidates(self, low: np.ndarray, high: np.ndarray, k: int) -> np.ndarray:
        """Indices, ascending, of boxes before ``k`` that may overlap the box ``low``,
        ``high`` (3,), m: all that do, and maybe others (the caller compares them)."""
        if not self.n or k <= 0:
            return np.zeros(0, dtype=np.int64)
        (x0, y0), (x1, y1) = self._index(np.asarray(low)[:2]), self._index(np.asarray(high)[:2])
        if (x1 - x0 + 1) * (y1 - y0 + 1) > MAX_QUERY_CELLS:
            return np.arange(min(k, self.n))
        wanted = (np.arange(x0, x1 + 1)[:, None] * self.shape[1]
                  + np.arange(y0, y1 + 1)[None, :]).ravel()
        begin = np.searchsorted(self.cells, wanted, side="left")
        end = np.searchsorted(self.cells, wanted, side="right")
        found = [self.boxes[a:b] for a, b in zip(begin.tolist(), end.tolist(), strict=True)
                 if b > a]
        found.append(self.wide)
        out = np.unique(np.concatenate(found))
        return out[:int(np.searchsorted(out, k))]

    def at(self, point: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Boxes before ``k`` listed in the cell of ``point`` (3,), and the wide boxes before
        ``k``, each ascending: every box that holds ``point`` is in one of them."""
        if not self.n or k <= 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        x, y = self._index(np.asarray(point)[:2])
        cell = x * self.shape[1] + y
        begin, end = np.searchsorted(self.cells, [cell, cell + 1], side="left")
        listed = self.boxes[begin:end]
        return (listed[:int(np.searchsorted(listed, k))],
                self.wide[:int(np.searchsorted(self.wide, k))])

