"""Exact mesh of a block whose top is the lower envelope of straight grooves in XY.

Grooves that share a direction d in XY form a family. Across them the coordinate is
s = n . (x, y), n = (-d_y, d_x), and the family leaves the envelope F(s), piecewise linear
(`machinesim.cutting.profiles`). The cut top of the block is

    z = min(top, F_1(s_1) + a_1 t_1, F_2(s_2) + a_2 t_2),

with t = d . (x, y) along each family and a its grooves' common slope along it (0 for
grooves cut level; a tilted table, for instance, slopes them). Level families' envelopes
already hold the top. The breakpoints of F_1 are lines s_1 = u_i across the
block, those of F_2 lines s_2 = v_j; they cut the plane into the parallelograms of an affine
grid, and inside each F_1 and F_2 are both linear, so the top there is one plane or two
planes that meet on the straight line F_1 = F_2 (the slope terms are linear everywhere, so
this holds for sloped families too). Each cell is meshed exactly as that one or two convex
polygons, in vectorised numpy, in (s_1, s_2) coordinates mapped back to XY by the inverse of
the 2 x 2 matrix of normals (exact when the families run along X and Y). A sloped family's
envelope is built under a raised top that its slope term cannot bring below the real one,
and the meshed surface is then cut at z = top (`_clip_at_top`): every triangle the level
z = top crosses is split on that line, and what lies above it is laid on the top.

The block is an axis-aligned rectangle R in XY. Cells wholly inside R are meshed directly.
Cells that cross or touch its sides are clipped to it (Sutherland-Hodgman, vectorised over
the cells), each new vertex named by the segment it splits and the side that splits it, so
the two cells sharing a segment make the same vertex and the mesh is closed by index. The
top is then closed with vertical walls under the edges on R's sides and a flat bottom. A
single family is meshed with a flat second family along the block's axis most across it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.cutting.clip import clip_polygons, pack
from machinesim.tolerances import HEIGHT_TIE_REL
from machinesim.workpiece import Part

#: Cells meshed per block: bounds the transient index arrays to ~100 MB.
CELLS_PER_BLOCK = 1 << 18
#: A slanted family's envelope reaches this fraction of its range beyond the block (`domain`).
DOMAIN_MARGIN_REL = 1e-6
#: Unit normals of the block's axes, for the flat family that pads a single one.
AXIS_NORMALS = ((0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 0.0))


@dataclass(frozen=True)
class Family:
    """Straight grooves sharing one direction in XY, and the envelope they leave.

    Attributes
    ----------
    normal : ndarray, shape (2,)
        Unit normal n = (-d_y, d_x) of the grooves' direction d; s = n . (x, y) (m) is the
        coordinate across them.
    u, z : ndarray
        Breakpoints of the envelope, strictly increasing s over the block's range of s
        (`domain`), and the envelope there (m).
    slope : float
        The grooves' common slope along d (dz/dt, t = d . (x, y)): the family's surface is
        z(s) + slope * t. 0 for grooves cut level.
    """

    normal: np.ndarray
    u: np.ndarray
    z: np.ndarray
    slope: float = 0.0


@dataclass(frozen=True)
class Relief:
    """A block over [x0, x1] x [y0, y1] x [bottom, ...] whose top is min over its families.

    Attributes
    ----------
    x0, x1, y0, y1, bottom, top : float
        The rectangle, the bottom face and the uncut top (m).
    families : tuple of Family
        At most two; none for an uncut block.
    """

    x0: float
    x1: float
    y0: float
    y1: float
    bottom: float
    top: float
    families: tuple[Family, ...] = ()


def across(normal, x, y):
    """s = n . (x, y), one formula everywhere (exactly y or -x for the axis normals)."""
    return normal[0] * x + normal[1] * y


def direction(normal) -> np.ndarray:
    """The grooves' direction d = (n_y, -n_x) of a family with unit normal n."""
    return np.array([normal[1], -normal[0]])


def along(normal, x, y):
    """t = d . (x, y) along a family, d = `direction` (n)."""
    return normal[1] * x - normal[0] * y


def span(normal, x0: float, x1: float, y0: float, y1: float) -> tuple[float, float]:
    """Range of s = n . (x, y) over the rectangle (m)."""
    s = across(normal, np.array([x0, x1, x0, x1]), np.array([y0, y0, y1, y1]))
    return float(s.min()), float(s.max())


def domain(normal, x0: float, x1: float, y0: float, y1: float) -> tuple[float, float]:
    """Range of s a family's envelope covers: the rectangle's, widened for a slanted family.

    A family along X or Y has its first and last grid lines on the rectangle's sides. A
    slanted one would have them touch the rectangle at a corner, where clipping would leave
    edges of zero length; widened by `DOMAIN_MARGIN_REL` of the range they miss it.
    """
    lo, hi = span(normal, x0, x1, y0, y1)
    if normal[0] == 0.0 or normal[1] == 0.0:
        return lo, hi
    margin = DOMAIN_MARGIN_REL * (hi - lo)
    return lo - margin, hi + margin


def _det(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def grid_families(relief: Relief) -> tuple[Family, Family]:
    """The two families the grid is built on, padded with flat ones, det(n_1, n_2) > 0."""
    families = list(relief.families)
    box = (relief.x0, relief.x1, relief.y0, relief.y1)

    def flat(normal) -> Family:
        normal = np.array(normal, dtype=np.float64)
        return Family(normal, np.array(span(normal, *box)), np.array([relief.top] * 2))

    if not families:
        families = [flat(AXIS_NORMALS[0]), flat(AXIS_NORMALS[1])]
    elif len(families) == 1:
        n = families[0].normal
        families.append(flat(max(AXIS_NORMALS, key=lambda m: _det(n, m))))
    if len(families) != 2:
        raise ValueError(f"the mesher takes at most two groove families, got {len(families)}")
    first, second = families
    if _det(first.normal, second.normal) < 0.0:
        first, second = second, first
    return first, second


def _ring(corner_id, h_id, v_id, sign, i, j):
    """Vertex ids and signs of cells (i, j): corners and edge crossings, counter-clockwise.

    ``i`` and ``j`` are index arrays that broadcast together; the result has a last axis
    of 8 slots: corner (i, j), crossing on the s_1 edge at v_j, corner (i+1, j), crossing on
    the s_2 edge at u_{i+1}, corner (i+1, j+1), crossing at v_{j+1}, corner (i, j+1),
    crossing at u_i. Crossing slots hold -1 where F_1 = F_2 does not cross the edge.
    """
    ids = np.stack([corner_id[i, j], h_id[i, j], corner_id[i + 1, j], v_id[i + 1, j],
                    corner_id[i + 1, j + 1], h_id[i, j + 1], corner_id[i, j + 1], v_id[i, j]],
                   axis=-1)
    s = [sign[i, j], sign[i + 1, j], sign[i + 1, j + 1], sign[i, j + 1]]
    zero = np.zeros_like(s[0])
    signs = np.stack([s[0], zero, s[1], zero, s[2], zero, s[3], zero], axis=-1)
    return ids.reshape(-1, 8), signs.reshape(-1, 8)


def _halves(ids, signs, with_slots: bool = False):
    """The one or two polygons of each cell: where F_2 <= F_1 and where F_2 >= F_1.

    Yields (fan, count, slots): vertex ids packed to the front of each row, in ring order,
    how many (0 for no polygon), and the ring slot each came from. Points on F_1 = F_2
    belong to both sides; a cell with F_1 = F_2 throughout is emitted once.
    """
    valid = ids >= 0
    corner_signs = signs[:, 0::2]
    any_neg = (corner_signs < 0).any(axis=1)
    any_pos = (corner_signs > 0).any(axis=1)
    for mask, emit in ((valid & (signs <= 0), any_neg | ~any_pos),
                       (valid & (signs >= 0), any_pos)):
        mask &= emit[:, None]
        count = mask.sum(axis=1)
        mask &= (count >= 3)[:, None]
        count = np.where(count >= 3, count, 0)
        fan, _ = pack(ids, mask, count)
        slots = (pack(np.broadcast_to(np.arange(8), ids.shape), mask, count)[0]
                 if with_slots else None)
        yield fan, count, slots


def _fan(fan, count):
    """Triangles (v0, vk, vk+1) of convex polygons packed as by `_pack`."""
    triangles = []
    for k in range(1, fan.shape[1] - 1):
        sel = np.flatnonzero(count >= k + 2)
        if not len(sel):
            break
        triangles.append(np.stack([fan[sel, 0], fan[sel, k], fan[sel, k + 1]], axis=1))
    return triangles


def _moment(vertices, triangles, top: float) -> float:
    """Integral of (top - z) over the triangles' projection on XY (m^3), signed by area."""
    p0, p1, p2 = (vertices[triangles[:, m]] for m in range(3))
    area2 = ((p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1])
             - (p2[:, 0] - p0[:, 0]) * (p1[:, 1] - p0[:, 1]))
    depth = top - (p0[:, 2] + p1[:, 2] + p2[:, 2]) / 3.0
    return float(np.dot(area2, depth)) / 2.0


def _corner_moment(points, p: int, q: int, r: int, top: float) -> np.ndarray:
    """Twice `_moment` of triangles (p, q, r) of grid corners, cell by cell (no gathers).

    ``points`` holds the x, y and z of the cells' four corners, each (c0, c1, c2, c3).
    """
    (x, y, z) = points
    area2 = ((x[q] - x[p]) * (y[r] - y[p]) - (x[r] - x[p]) * (y[q] - y[p]))
    return area2 * (top - (z[p] + z[q] + z[r]) / 3.0)


def _clip_at_top(vertices, triangles, n_top: int, top: float, cut_volume: float):
    """The mesh with its top surface (vertices ``[0, n_top)``) cut at z = ``top``.

    The surface is linear on each triangle, so min(top, z) is linear on each side of the
    line where a triangle crosses z = top: every edge of two top vertices strictly either
    side of the level gets one new vertex there (shared by the triangles on that edge), each
    crossed triangle is split on the line (one crossed edge: 2 triangles, a wall under a
    rim edge; two: 3), and every top vertex above the level is laid on it. Only triangles
    with a vertex above the level change. Returns the vertices, the triangles and
    ``cut_volume`` (the integral of top - z over the uncut top) made the cut top's, by the
    `_moment` of the changed triangles before and after.
    """
    z = vertices[:, 2]
    changed = np.flatnonzero((z[triangles] > top).any(axis=1))
    kept = np.delete(triangles, changed, axis=0)
    triangles = triangles[changed]
    before = _moment(vertices, triangles, top)
    a, b = triangles, triangles[:, [1, 2, 0]]              # edge k runs from a[k] to b[k]
    crossed = (a < n_top) & (b < n_top) & ((z[a] > top) & (z[b] < top)
                                           | (z[a] < top) & (z[b] > top))
    lo, hi = np.minimum(a, b)[crossed], np.maximum(a, b)[crossed]
    keys, inverse = np.unique(lo * len(vertices) + hi, return_inverse=True)
    lo, hi = keys // len(vertices), keys % len(vertices)
    t = (top - z[lo]) / (z[hi] - z[lo])
    made = vertices[lo] + t[:, None] * (vertices[hi] - vertices[lo])
    made[:, 2] = top
    mid = np.full(triangles.shape, -1, dtype=np.int64)
    mid[crossed] = len(vertices) + inverse.reshape(-1)
    count = crossed.sum(axis=1)
    pieces = [triangles[count == 0]]
    # One crossed edge, turned to be edge 0 (v0 -> v1, point m): (v0, m, v2), (m, v1, v2).
    one = np.flatnonzero(count == 1)
    turn = (np.argmax(crossed[one], axis=1)[:, None] + np.arange(3)[None, :]) % 3
    v = np.take_along_axis(triangles[one], turn, axis=1)
    m = np.take_along_axis(mid[one], turn, axis=1)[:, 0]
    pieces += [np.stack([v[:, 0], m, v[:, 2]], axis=1), np.stack([m, v[:, 1], v[:, 2]], axis=1)]
    # Two, turned so that edge 1 (v1 -> v2) is the one not crossed, points m0 on edge 0 and
    # m2 on edge 2: (v0, m0, m2) on one side of the line, (m0, v1, v2), (m0, v2, m2) on the other.
    two = np.flatnonzero(count == 2)
    turn = ((np.argmin(crossed[two], axis=1) - 1)[:, None] % 3 + np.arange(3)[None, :]) % 3
    v = np.take_along_axis(triangles[two], turn, axis=1)
    m = np.take_along_axis(mid[two], turn, axis=1)
    pieces += [np.stack([v[:, 0], m[:, 0], m[:, 2]], axis=1),
               np.stack([m[:, 0], v[:, 1], v[:, 2]], axis=1),
               np.stack([m[:, 0], v[:, 2], m[:, 2]], axis=1)]
    vertices = np.concatenate([vertices, made])
    vertices[:n_top, 2] = np.minimum(vertices[:n_top, 2], top)
    pieces = np.concatenate(pieces)
    # Walls and the bottom have no area in XY: their moments are 0 before and after.
    cut_volume += _moment(vertices, pieces, top) - before
    return vertices, np.concatenate([kept, pieces]), cut_volume


def mesh_relief(relief: Relief, first_vertex: int = 0):
    """Closed, outward-oriented triangle mesh of a relief.

    Returns
    -------
    vertices : ndarray, shape (n, 3), float64 (m)
    triangles : ndarray, shape (m, 3), int64, indices offset by ``first_vertex``
    volume : float
        Enclosed volume (m^3).
    cut_volume : float
        Volume below ``top`` not in the relief (m^3): the integral of top - z over the top
        triangles, exact for a piecewise linear top, and free of the cancellation a
        difference of two whole volumes would suffer.
    """
    box = (relief.x0, relief.x1, relief.y0, relief.y1)
    first, second = grid_families(relief)
    n1, u, f = first.normal, first.u, first.z
    n2, v, g = second.normal, second.u, second.z
    det = _det(n1, n2)

    def to_xy(s1, s2):
        return (n2[1] * s1 - n1[1] * s2) / det, (n1[0] * s2 - n2[0] * s1) / det

    nu, nv = len(u), len(v)
    scale = max(abs(relief.x0), abs(relief.x1), abs(relief.y0), abs(relief.y1),
                abs(relief.top), abs(relief.bottom))
    cx, cy = to_xy(u[:, None], v[None, :])
    # Each family's height at the grid's corners: its envelope plus its slope term (which
    # adds exactly 0.0 for a level family, so F is then f itself on every row).
    F = f[:, None] + first.slope * along(n1, cx, cy)
    G = g[None, :] + second.slope * along(n2, cx, cy)
    d = G - F
    sign = (np.sign(d) * (np.abs(d) > HEIGHT_TIE_REL * scale)).astype(np.int8)
    cz = np.minimum(G, F)
    corners = np.stack([cx.ravel(), cy.ravel(), cz.ravel()], axis=1)
    corner_id = np.arange(nu * nv, dtype=np.int64).reshape(nu, nv)
    # Crossings of F_1 = F_2 on the edges along s_1 (between (i, j) and (i + 1, j)), where
    # both are linear (for a level second family G is constant there: t and z as by hand) ...
    hi, hj = np.nonzero(sign[:-1, :].astype(np.int16) * sign[1:, :] < 0)
    dg = G[hi + 1, hj] - G[hi, hj]
    t = (G[hi, hj] - F[hi, hj]) / ((F[hi + 1, hj] - F[hi, hj]) - dg)
    h_points = np.stack([*to_xy(u[hi] + t * (u[hi + 1] - u[hi]), v[hj]), G[hi, hj] + t * dg],
                        axis=1)
    h_id = np.full((nu - 1, nv), -1, dtype=np.int64)
    h_id[hi, hj] = nu * nv + np.arange(len(hi))
    # ... and along s_2 (between (i, j) and (i, j + 1)).
    vi, vj = np.nonzero(sign[:, :-1].astype(np.int16) * sign[:, 1:] < 0)
    df = F[vi, vj + 1] - F[vi, vj]
    t = (F[vi, vj] - G[vi, vj]) / ((G[vi, vj + 1] - G[vi, vj]) - df)
    v_points = np.stack([*to_xy(u[vi], v[vj] + t * (v[vj + 1] - v[vj])), F[vi, vj] + t * df],
                        axis=1)
    v_id = np.full((nu, nv - 1), -1, dtype=np.int64)
    v_id[vi, vj] = nu * nv + len(hi) + np.arange(len(vi))
    top_vertices = np.concatenate([corners, h_points, v_points])

    # Cells strictly inside the rectangle are meshed as they are; cells that reach its
    # sides are clipped; cells wholly outside (slanted families only) are dropped.
    inside = (cx > box[0]) & (cx < box[1]) & (cy > box[2]) & (cy < box[3])
    interior = inside[:-1, :-1] & inside[1:, :-1] & inside[1:, 1:] & inside[:-1, 1:]
    quad_x = np.stack([cx[:-1, :-1], cx[1:, :-1], cx[1:, 1:], cx[:-1, 1:]])
    quad_y = np.stack([cy[:-1, :-1], cy[1:, :-1], cy[1:, 1:], cy[:-1, 1:]])
    outside = ((quad_x.max(axis=0) <= box[0]) | (quad_x.min(axis=0) >= box[1])
               | (quad_y.max(axis=0) <= box[2]) | (quad_y.min(axis=0) >= box[3]))
    del quad_x, quad_y

    triangles = []
    cut_volume = 0.0
    rows = max(1, CELLS_PER_BLOCK // max(nv - 1, 1))
    for i0 in range(0, nu - 1, rows):
        i1 = min(nu - 1, i0 + rows)
        keep = interior[i0:i1]
        if not keep.any():
            continue
        # Most cells have no crossing on their edges: one plane, or two that meet on a
        # diagonal through two corners where F_1 = F_2 (pyramid edges): two triangles.
        crossed = ((h_id[i0:i1, :-1] >= 0) | (v_id[i0 + 1:i1 + 1] >= 0)
                   | (h_id[i0:i1, 1:] >= 0) | (v_id[i0:i1] >= 0))
        c, sg = corner_id[i0:i1 + 1], sign[i0:i1 + 1]
        quad = (c[:-1, :-1], c[1:, :-1], c[1:, 1:], c[:-1, 1:])
        s4 = (sg[:-1, :-1], sg[1:, :-1], sg[1:, 1:], sg[:-1, 1:])
        mixed = ((s4[0] > 0) | (s4[1] > 0) | (s4[2] > 0) | (s4[3] > 0)) & (
            (s4[0] < 0) | (s4[1] < 0) | (s4[2] < 0) | (s4[3] < 0))
        simple = keep & ~crossed
        other_diagonal = simple & mixed & (s4[1] == 0) & (s4[3] == 0)
        points = [(g[i0:i1, :-1], g[i0 + 1:i1 + 1, :-1], g[i0 + 1:i1 + 1, 1:], g[i0:i1, 1:])
                  for g in (cx, cy, cz)]
        for mask, (p, q, r, w) in ((simple & ~other_diagonal, (0, 1, 2, 3)),
                                   (other_diagonal, (1, 2, 3, 0))):
            if not mask.any():
                continue
            moment = (_corner_moment(points, p, q, r, relief.top)
                      + _corner_moment(points, p, r, w, relief.top))
            cut_volume += float(moment[mask].sum()) / 2.0
            corner = [quad[k][mask] for k in (p, q, r, w)]
            triangles += [np.stack(corner[:3], axis=1),
                          np.stack([corner[0], corner[2], corner[3]], axis=1)]
        ri, rj = np.nonzero(keep & crossed)
        if not len(ri):
            continue
        ids, signs = _ring(corner_id, h_id, v_id, sign, ri + i0, rj)
        for fan, count, _ in _halves(ids, signs):
            for tri in _fan(fan, count):
                cut_volume += _moment(top_vertices, tri, relief.top)
                triangles.append(tri)

    bi, bj = np.nonzero(~interior & ~outside)
    ids, signs = _ring(corner_id, h_id, v_id, sign, bi, bj)
    # An edge on the grid's first or last line lies on the rectangle's side: the block
    # lies between those lines and meets them only on its sides (along a whole side, or
    # at a corner, where clipping can leave an edge of zero length there).
    border = np.stack([bj == 0, bi + 1 == nu - 1, bj + 2 == nv, bi == 0], axis=1)
    halves = list(_halves(ids, signs, with_slots=True))
    width = max(h[0].shape[1] for h in halves)
    fan = np.zeros((2 * len(bi), width), dtype=np.int64)
    slots = np.zeros((2 * len(bi), width), dtype=np.int64)
    for h, (part_fan, _, part_slots) in enumerate(halves):
        fan[h * len(bi):(h + 1) * len(bi), :part_fan.shape[1]] = part_fan
        slots[h * len(bi):(h + 1) * len(bi), :part_fan.shape[1]] = part_slots
    count = np.concatenate([halves[0][1], halves[1][1]])
    cell = np.concatenate([np.arange(len(bi))] * 2)
    column = np.arange(width)
    following = np.where(column[None, :] + 1 < count[:, None], column[None, :] + 1, 0)
    here, there = slots, np.take_along_axis(slots, following, axis=1)
    flags = np.zeros(fan.shape, dtype=bool)
    for side in range(4):
        # Slots 2 side, 2 side + 1 and 2 side + 2 (mod 8) lie on that side of the cell.
        on_side_k = ((here - 2 * side) % 8 <= 2) & ((there - 2 * side) % 8 <= 2)
        flags |= on_side_k & border[cell, side][:, None]
    # Cells with every corner in the rectangle (or on its sides) need no clipping.
    within = ((cx >= box[0]) & (cx <= box[1]) & (cy >= box[2]) & (cy <= box[3]))
    within = within[bi, bj] & within[bi + 1, bj] & within[bi + 1, bj + 1] & within[bi, bj + 1]
    clip = (count > 0) & ~within[cell]
    keep = (count > 0) & within[cell]
    kept = (fan[keep], count[keep], flags[keep])
    fan, count, flags = fan[clip], count[clip], flags[clip]
    if len(count):
        # Clip in a local numbering of the few vertices involved: ids stay small.
        local, fan = np.unique(fan, return_inverse=True)
        fan = fan.reshape(len(count), -1)
        fan, count, flags, made = clip_polygons(fan, count, flags, top_vertices[local], box)
        fan = np.concatenate([local, len(top_vertices) + np.arange(len(made))])[fan]
        top_vertices = np.concatenate([top_vertices, made])
    width = max(fan.shape[1], kept[0].shape[1])
    fan = np.concatenate([np.pad(fan, ((0, 0), (0, width - fan.shape[1]))),
                          np.pad(kept[0], ((0, 0), (0, width - kept[0].shape[1])))])
    flags = np.concatenate([np.pad(flags, ((0, 0), (0, width - flags.shape[1]))),
                            np.pad(kept[2], ((0, 0), (0, width - kept[2].shape[1])))])
    count = np.concatenate([count, kept[1]])
    for tri in _fan(fan, count):
        cut_volume += _moment(top_vertices, tri, relief.top)
        triangles.append(tri)

    # Walls under the edges on the rectangle's sides (counter-clockwise seen from above),
    # and the bottom as a fan about the rectangle's centre.
    slot = np.arange(fan.shape[1])
    following = np.where(slot[None, :] + 1 < count[:, None], slot[None, :] + 1, 0)
    on_side = flags & (slot[None, :] < count[:, None])
    start = fan[on_side]
    end = np.take_along_axis(fan, following, axis=1)[on_side]
    rim = np.unique(np.concatenate([start, end]))
    base = len(top_vertices)
    under = top_vertices[rim].copy()
    under[:, 2] = relief.bottom
    centre = np.array([[(relief.x0 + relief.x1) / 2.0, (relief.y0 + relief.y1) / 2.0,
                        relief.bottom]])
    a_low = base + np.searchsorted(rim, start)
    b_low = base + np.searchsorted(rim, end)
    centre_id = np.full(len(start), base + len(rim))
    triangles += [np.stack([start, a_low, b_low], axis=1), np.stack([start, b_low, end], axis=1),
                  np.stack([centre_id, b_low, a_low], axis=1)]
    vertices = np.concatenate([top_vertices, under, centre])
    triangles = np.concatenate(triangles)
    if first.slope != 0.0 or second.slope != 0.0:
        vertices, triangles, cut_volume = _clip_at_top(vertices, triangles, base, relief.top,
                                                       cut_volume)
    used = np.zeros(len(vertices), dtype=bool)
    used[triangles.ravel()] = True
    if not used.all():
        remap = np.cumsum(used) - 1
        triangles = remap[triangles]
        vertices = vertices[used]
    area = (relief.x1 - relief.x0) * (relief.y1 - relief.y0)
    volume = area * (relief.top - relief.bottom) - cut_volume
    return vertices, triangles + first_vertex, volume, cut_volume


def relief_part(reliefs: tuple[Relief, ...]) -> tuple[Part, float]:
    """The part made of disjoint reliefs, meshed, and its cut volume (m^3, `mesh_relief`)."""
    vertices, triangles, offset, volume, cut_volume = [], [], 0, 0.0, 0.0
    for relief in reliefs:
        v, t, enclosed, cut = mesh_relief(relief, offset)
        vertices.append(v)
        triangles.append(t)
        offset += len(v)
        volume += enclosed
        cut_volume += cut
    part = Part._closed(np.concatenate(vertices), np.concatenate(triangles), reliefs, volume)
    return part, cut_volume


__all__ = ["AXIS_NORMALS", "CELLS_PER_BLOCK", "DOMAIN_MARGIN_REL", "Family", "Relief", "across",
           "along", "direction", "domain", "grid_families", "mesh_relief", "relief_part", "span"]
