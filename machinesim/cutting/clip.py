"""Convex polygons clipped to an axis-aligned rectangle, vectorised, closed by index.

Polygons are rows of vertex ids packed to the front (`pack`) with their counts. Clipping
(Sutherland-Hodgman, one side of the rectangle at a time, all polygons at once) names each
vertex it makes by the segment it splits and the side that splits it, so two polygons that
share a segment split it at the same vertex id: a mesh closed by index stays closed. Used by
`machinesim.cutting.relief_mesh` for the grid cells on a block's sides.
"""

from __future__ import annotations

import numpy as np


def pack(ids, mask, count):
    """Rows of ``ids`` where ``mask``, packed to the front in order (no sort)."""
    row, slot = np.nonzero(mask)
    rank = np.arange(len(row)) - (np.cumsum(count) - count)[row]
    fan = np.zeros((len(ids), max(int(count.max(initial=0)), 1)), dtype=np.int64)
    fan[row, rank] = ids[row, slot]
    return fan, count


def _distance(side: int, x, y, box):
    """Signed distance inside the side ``side`` (0: x >= x0, 1: y >= y0, 2: x <= x1, 3: y <= y1)."""
    x0, x1, y0, y1 = box
    return (x - x0, y - y0, x1 - x, y1 - y)[side]


def clip_polygons(fan, count, flags, vertices, box):
    """Convex polygons clipped to the rectangle ``box`` (x0, x1, y0, y1).

    Parameters
    ----------
    fan, count : ndarray
        Polygons as packed vertex ids (counter-clockwise) and their vertex counts.
    flags : ndarray of bool, like ``fan``
        Edges (from slot k to the next) known to lie on the rectangle's sides.
    vertices : ndarray, shape (n, 3)
        The vertices the ids refer to (m).

    Returns
    -------
    fan, count, flags : ndarray
        The clipped polygons (ids may refer to new vertices); ``flags[r, k]`` is True when
        the edge from slot k to the next lies on a side of the rectangle.
    new_vertices : ndarray, shape (k, 3)
        Vertices made by clipping, ids n, n + 1, ...: each is named by the segment it
        splits (its two end vertices) and the side, so polygons that share a segment split
        it at the same vertex. It lies exactly on its side; x, y and z are interpolated
        along the segment from its lower-id end, where z is linear (a polygon is planar).
    """
    table = [vertices]
    total = len(vertices)

    def coords(ids):
        if len(table) > 1:
            table[:] = [np.concatenate(table)]
        return table[0][ids]

    for side in range(4):
        width = fan.shape[1]
        slot = np.arange(width)
        valid = slot[None, :] < count[:, None]
        following = np.where(slot[None, :] + 1 < count[:, None], slot[None, :] + 1, 0)
        p_ids, q_ids = fan, np.take_along_axis(fan, following, axis=1)
        p, q = coords(p_ids), coords(q_ids)
        d_p = _distance(side, p[..., 0], p[..., 1], box)
        d_q = _distance(side, q[..., 0], q[..., 1], box)
        p_emit = valid & (d_p >= 0.0)
        p_flag = np.where(d_q >= 0.0, flags | ((d_p == 0.0) & (d_q == 0.0)), flags | (d_p == 0.0))
        cross = valid & (((d_p > 0.0) & (d_q < 0.0)) | ((d_p < 0.0) & (d_q > 0.0)))
        i_flag = np.where(d_p > 0.0, True, flags)
        new_ids = np.zeros_like(fan)
        row, col = np.nonzero(cross)
        if len(row):
            a = np.minimum(p_ids[row, col], q_ids[row, col])
            b = np.maximum(p_ids[row, col], q_ids[row, col])
            unique, inverse = np.unique(a * total + b, return_inverse=True)
            end_a, end_b = coords(unique // total), coords(unique % total)
            d_a = _distance(side, end_a[:, 0], end_a[:, 1], box)
            d_b = _distance(side, end_b[:, 0], end_b[:, 1], box)
            t = d_a / (d_a - d_b)
            made = end_a + t[:, None] * (end_b - end_a)
            made[:, side % 2] = box[(0, 2, 1, 3)[side]]  # exactly on the side
            new_ids[row, col] = total + inverse.reshape(-1)
            table.append(made)
            total += len(unique)
        out_ids = np.stack([p_ids, new_ids], axis=-1).reshape(len(fan), -1)
        out_mask = np.stack([p_emit, cross], axis=-1).reshape(len(fan), -1)
        out_flag = np.stack([p_flag, i_flag], axis=-1).reshape(len(fan), -1)
        count = out_mask.sum(axis=1)
        fan, _ = pack(out_ids, out_mask, count)
        flags, _ = pack(out_flag, out_mask, count)
        flags = flags.astype(bool)
    count = np.where(count >= 3, count, 0)
    made = np.concatenate(table)[len(vertices):]
    return fan, count, flags, made


__all__ = ["clip_polygons", "pack"]
