"""Exact height-field cutting of straight grooves that run right across a block.

A tool translated along the block's X axis, from wholly before the block to wholly beyond
it, removes over the block an extrusion of one profile: the lower boundary of the tool's
shadow on the Y-Z plane, which for a convex tool is the lower convex hull of its vertices
projected along X. All such grooves together leave the lower envelope F(y) of their
profiles; grooves along Y leave G(x); and the top of the cut block is

    z = min(top, F(y), G(x)).

F and G are piecewise linear. Between consecutive breakpoints of both, F is linear in y and
G in x, so each grid cell is one plane, or two planes that meet on the straight line
F(y) = G(x). The surface is therefore meshed exactly, cell by cell, in vectorised numpy, and
closed with vertical walls and a flat bottom: no boolean is needed. This is the
configuration of ruled groove patterns (parallel V grooves, crossing grooves that leave
pyramids), where the boolean engine spends about 5 us per output triangle and this mesher
well under 1 us.

A cut qualifies when the stock is an axis-aligned box or a part this module made, and every
sweep that can reach the stock is such a full-span straight groove whose profile rises
above the top at both ends and stays above the bottom. Anything else returns None and the
caller uses the boolean engine. A relief keeps F and G with the part (`Part.reliefs`), so a
second program of grooves on the same part is cut the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.tolerances import HEIGHT_TIE_REL, SAME_ORIENTATION, STRAIGHT_REL
from machinesim.workpiece import Part

#: Most distinct tool orientations the relief path profiles; more means a rotary program,
#: which is never a set of straight grooves.
MAX_ORIENTATIONS = 64
#: Cells meshed per block: bounds the transient index arrays to ~100 MB.
CELLS_PER_BLOCK = 1 << 18
#: Most grid cells in one cut: about 2 triangles and 120 bytes of mesh each, so 2e7 cells
#: make a ~2.4 GB part. Larger parts are refused with advice, not left to exhaust memory
#: (the boolean engine could not cut them either).
MAX_CELLS = 20_000_000


@dataclass(frozen=True)
class Relief:
    """A block over [x0, x1] x [y0, y1] x [bottom, ...] whose top is z = min(F(y), G(x)).

    Attributes
    ----------
    x0, x1, y0, y1, bottom, top : float
        The rectangle, the bottom face and the uncut top (m).
    gx, gz : ndarray
        Breakpoints of G(x): strictly increasing x from x0 to x1, and G there (m).
    fy, fz : ndarray
        Breakpoints of F(y), likewise from y0 to y1 (m).
    """

    x0: float
    x1: float
    y0: float
    y1: float
    bottom: float
    top: float
    gx: np.ndarray
    gz: np.ndarray
    fy: np.ndarray
    fz: np.ndarray


def _flat(x0, x1, y0, y1, bottom, top) -> Relief:
    return Relief(x0, x1, y0, y1, bottom, top, np.array([x0, x1]), np.array([top, top]),
                  np.array([y0, y1]), np.array([top, top]))


def stock_reliefs(stock: Part) -> tuple[Relief, ...] | None:
    """The stock as reliefs: its own, or one flat relief when it is an axis-aligned box."""
    if stock.reliefs is not None:
        return stock.reliefs
    manifold = stock.manifold
    if manifold.num_vert() != 8 or manifold.num_tri() != 12:
        return None
    (x0, y0, z0), (x1, y1, z1) = stock.bounds
    box = (x1 - x0) * (y1 - y0) * (z1 - z0)
    if not abs(manifold.volume() - box) <= 1e-12 * box:
        return None  # eight corners but turned: not a box in this frame
    return (_flat(x0, x1, y0, y1, z0, z1),)


def lower_hull(u: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Lower convex hull of points (u, z), shape (h, 2), by increasing u (monotone chain).

    Points on a vertical end edge reduce to the lowest one; collinear points are dropped.
    """
    order = np.lexsort((z, u))
    hull: list[tuple[float, float]] = []
    for k in order:
        p = (float(u[k]), float(z[k]))
        if hull and hull[-1][0] == p[0]:
            continue  # same u, higher (sorted by z): not on the lower hull
        while len(hull) >= 2:
            (ax, az), (bx, bz) = hull[-2], hull[-1]
            if (bx - ax) * (p[1] - az) - (bz - az) * (p[0] - ax) <= 0.0:
                hull.pop()
            else:
                break
        hull.append(p)
    return np.array(hull, dtype=np.float64).reshape(-1, 2)


def _clip_to_top(u0, z0, u1, z1, top):
    """Segments cut to their part at or below ``top`` (those wholly at or above it dropped)."""
    keep = (z0 < top) | (z1 < top)
    u0, z0, u1, z1 = u0[keep], z0[keep], u1[keep], z1[keep]
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = u0 + (top - z0) / (z1 - z0) * (u1 - u0)
    high0, high1 = z0 > top, z1 > top
    u0, z0 = np.where(high0, cross, u0), np.where(high0, top, z0)
    u1, z1 = np.where(high1, cross, u1), np.where(high1, top, z1)
    return u0, z0, u1, z1


def envelope(u0, z0, u1, z1, lo: float, hi: float, top: float):
    """Lower envelope of segments and the line z = top over [lo, hi], exactly.

    The segments must form chains that start and end at or above ``top`` (groove profiles,
    or an earlier envelope): their minimum is then continuous, and every corner of it is a
    segment end or the crossing of two segments within one interval between ends.

    Parameters
    ----------
    u0, z0, u1, z1 : ndarray
        Segments from (u0, z0) to (u1, z1), u0 < u1 (m).
    lo, hi : float
        The domain (m).
    top : float
        The uncut height (m).

    Returns
    -------
    u, z : ndarray
        Breakpoints, strictly increasing u from lo to hi, and the envelope there; a point
        is kept only where the envelope changes line.
    """
    u0, z0, u1, z1 = (np.asarray(a, dtype=np.float64) for a in (u0, z0, u1, z1))
    u0, z0, u1, z1 = _clip_to_top(u0, z0, u1, z1, top)
    keep = (u1 > lo) & (u0 < hi) & (u1 > u0)
    u0, z0, u1, z1 = u0[keep], z0[keep], u1[keep], z1[keep]
    slope = (z1 - z0) / (u1 - u0)
    ends = np.concatenate([u0, u1])
    xs = np.unique(np.concatenate([[lo, hi], ends[(ends > lo) & (ends < hi)]]))
    n = len(xs) - 1
    if len(u0) == 0:
        return np.array([lo, hi]), np.array([top, top])
    first = np.clip(np.searchsorted(xs, u0, side="right") - 1, 0, n - 1)
    last = np.clip(np.searchsorted(xs, u1, side="left"), 1, n)
    count = last - first
    segment = np.repeat(np.arange(len(u0)), count)
    offsets = np.cumsum(count) - count
    interval = first[segment] + np.arange(len(segment)) - offsets[segment]
    order = np.argsort(interval, kind="stable")
    interval, segment = interval[order], segment[order]
    per = np.bincount(interval, minlength=n)
    slot = np.arange(len(interval)) - (np.cumsum(per) - per)[interval]
    width = int(per.max()) + 1
    # Column `width - 1` stays -1: the top, last so that a segment at the top wins ties.
    table = np.full((n, width), -1, dtype=np.int64)
    table[interval, slot] = segment

    def values(at: np.ndarray, rows: np.ndarray) -> np.ndarray:
        ids = table[rows]
        valid = ids >= 0
        safe = np.where(valid, ids, 0)
        line = z0[safe] + slope[safe] * (at[:, None] - u0[safe])
        line = np.where(valid, line, np.inf)
        line[:, -1] = top
        return line

    rows = np.arange(n)
    va, vb = values(xs[:-1], rows), values(xs[1:], rows)
    found = [xs]
    p, q = np.triu_indices(width, k=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        da, db = va[:, p] - va[:, q], vb[:, p] - vb[:, q]
        crossing = ((da < 0.0) & (db > 0.0)) | ((da > 0.0) & (db < 0.0))
        where = np.nonzero(crossing)
        a, b = xs[:-1][where[0]], xs[1:][where[0]]
        found.append(a + (b - a) * (da[where] / (da[where] - db[where])))
    points = np.unique(np.concatenate(found))
    points = points[(points >= lo) & (points <= hi)]
    home = np.clip(np.searchsorted(xs, points, side="right") - 1, 0, n - 1)
    z = values(points, home).min(axis=1)
    middle = (points[:-1] + points[1:]) / 2.0
    in_mid = np.clip(np.searchsorted(xs, middle, side="right") - 1, 0, n - 1)
    column = values(middle, in_mid).argmin(axis=1)
    line = table[in_mid, column]
    keep = np.ones(len(points), dtype=bool)
    keep[1:-1] = line[:-1] != line[1:]
    return points[keep], z[keep]


def _segments_of(relief_u: np.ndarray, relief_z: np.ndarray):
    return relief_u[:-1], relief_z[:-1], relief_u[1:], relief_z[1:]


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
    xs, big_g = relief.gx, relief.gz
    ys, big_f = relief.fy, relief.fz
    nx, ny = len(xs), len(ys)
    scale = max(abs(relief.x0), abs(relief.x1), abs(relief.y0), abs(relief.y1),
                abs(relief.top), abs(relief.bottom))
    d = big_f[None, :] - big_g[:, None]
    sign = (np.sign(d) * (np.abs(d) > HEIGHT_TIE_REL * scale)).astype(np.int8)
    corner_z = np.minimum(big_f[None, :], big_g[:, None])
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    corners = np.stack([gx.ravel(), gy.ravel(), corner_z.ravel()], axis=1)
    corner_id = np.arange(nx * ny, dtype=np.int64).reshape(nx, ny)
    # Crossings of F(y) = G(x) on the edges along X (between (i, j) and (i + 1, j)) ...
    h_mask = sign[:-1, :].astype(np.int16) * sign[1:, :] < 0
    hi_, hj = np.nonzero(h_mask)
    t = (big_f[hj] - big_g[hi_]) / (big_g[hi_ + 1] - big_g[hi_])
    h_points = np.stack([xs[hi_] + t * (xs[hi_ + 1] - xs[hi_]), ys[hj], big_f[hj]], axis=1)
    h_id = np.full((nx - 1, ny), -1, dtype=np.int64)
    h_id[hi_, hj] = nx * ny + np.arange(len(hi_))
    # ... and along Y (between (i, j) and (i, j + 1)).
    v_mask = sign[:, :-1].astype(np.int16) * sign[:, 1:] < 0
    vi, vj = np.nonzero(v_mask)
    t = (big_g[vi] - big_f[vj]) / (big_f[vj + 1] - big_f[vj])
    v_points = np.stack([xs[vi], ys[vj] + t * (ys[vj + 1] - ys[vj]), big_g[vi]], axis=1)
    v_id = np.full((nx, ny - 1), -1, dtype=np.int64)
    v_id[vi, vj] = nx * ny + len(hi_) + np.arange(len(vi))
    top_vertices = np.concatenate([corners, h_points, v_points])

    triangles = []
    cut_volume = 0.0
    rows = max(1, CELLS_PER_BLOCK // max(ny - 1, 1))
    for i0 in range(0, nx - 1, rows):
        i1 = min(nx - 1, i0 + rows)
        c = corner_id[i0:i1 + 1]
        s = sign[i0:i1 + 1]
        # The cell's corners and edge crossings, counter-clockwise seen from above.
        ids = np.stack([c[:-1, :-1], h_id[i0:i1, :-1], c[1:, :-1], v_id[i0 + 1:i1 + 1],
                        c[1:, 1:], h_id[i0:i1, 1:], c[:-1, 1:], v_id[i0:i1]],
                       axis=-1).reshape(-1, 8)
        zero = np.zeros_like(s[:-1, :-1])
        signs = np.stack([s[:-1, :-1], zero, s[1:, :-1], zero, s[1:, 1:], zero, s[:-1, 1:],
                          zero], axis=-1).reshape(-1, 8)
        valid = ids >= 0
        corner_signs = signs[:, 0::2]
        any_neg = (corner_signs < 0).any(axis=1)
        any_pos = (corner_signs > 0).any(axis=1)
        # Where F < G the surface is z = F(y), where F > G it is G(x): one polygon each side
        # of the line F = G (points on it belong to both); a cell with F = G throughout
        # is emitted once.
        for mask, emit in ((valid & (signs <= 0), any_neg | ~any_pos),
                           (valid & (signs >= 0), any_pos)):
            mask &= emit[:, None]
            count = mask.sum(axis=1)
            mask &= (count >= 3)[:, None]
            # Pack each polygon's vertices to the front of its row, in order (no sort).
            row, slot = np.nonzero(mask)
            rank = np.arange(len(row)) - (np.cumsum(count) - count)[row]
            fan = np.zeros((len(ids), 8), dtype=np.int64)
            fan[row, rank] = ids[row, slot]
            for k in range(1, 7):
                sel = np.flatnonzero(count >= k + 2)
                if not len(sel):
                    break
                tri = np.stack([fan[sel, 0], fan[sel, k], fan[sel, k + 1]], axis=1)
                p0, p1, p2 = (top_vertices[tri[:, m]] for m in range(3))
                area2 = ((p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1])
                         - (p2[:, 0] - p0[:, 0]) * (p1[:, 1] - p0[:, 1]))
                depth = relief.top - (p0[:, 2] + p1[:, 2] + p2[:, 2]) / 3.0
                cut_volume += float(np.dot(area2, depth)) / 2.0
                triangles.append(tri)

    # The perimeter, counter-clockwise seen from above, then walls down to the bottom.
    last_i, last_j = nx - 1, ny - 1
    runs = [
        (corner_id[:-1, 0], h_id[:, 0]),
        (corner_id[last_i, :-1], v_id[last_i, :]),
        (corner_id[:0:-1, last_j], h_id[::-1, last_j]),
        (corner_id[0, :0:-1], v_id[0, ::-1]),
    ]
    loop = np.concatenate([np.stack([a, b], axis=1).ravel() for a, b in runs])
    loop = loop[loop >= 0]
    count = len(loop)
    base = len(top_vertices)
    under = top_vertices[loop].copy()
    under[:, 2] = relief.bottom
    centre = np.array([[(relief.x0 + relief.x1) / 2.0, (relief.y0 + relief.y1) / 2.0,
                        relief.bottom]])
    q = base + np.arange(count)
    q_next = np.roll(q, -1)
    p_next = np.roll(loop, -1)
    centre_id = np.full(count, base + count)
    triangles += [np.stack([loop, q, q_next], axis=1), np.stack([loop, q_next, p_next], axis=1),
                  np.stack([centre_id, q_next, q], axis=1)]
    vertices = np.concatenate([top_vertices, under, centre])
    area = (relief.x1 - relief.x0) * (relief.y1 - relief.y0)
    volume = area * (relief.top - relief.bottom) - cut_volume
    return vertices, np.concatenate(triangles) + first_vertex, volume, cut_volume


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


@dataclass(frozen=True)
class ReliefCut:
    """What `cut_reliefs` did: the part, and the counts for the engine's report.

    ``swept_volume`` (m^3) is the most the grooves could remove: each profile's area below
    the top times the groove's length over the block; the empty-cut rule is relative to it.
    ``reached`` (int array) indexes the sweeps that reach the block.
    """

    part: Part
    removed_volume: float
    stock_volume: float
    n_sweeps_cut: int
    n_degenerate: int
    swept_volume: float = 0.0
    reached: np.ndarray = None


def _separated(rects: np.ndarray) -> bool:
    """True when no two rectangles (xmin, xmax, ymin, ymax) touch or overlap."""
    x = (rects[:, None, 0] <= rects[None, :, 1]) & (rects[None, :, 0] <= rects[:, None, 1])
    y = (rects[:, None, 2] <= rects[None, :, 3]) & (rects[None, :, 2] <= rects[:, None, 3])
    both = x & y
    np.fill_diagonal(both, False)
    return not both.any()


def cut_reliefs(stock: Part, vertices: np.ndarray, poses: np.ndarray, pairs: np.ndarray,
                windows=None, pose_bounds=None) -> ReliefCut | None:
    """Cut ``stock`` by height field, or None when the cut does not qualify.

    Parameters
    ----------
    stock : Part
    vertices : ndarray, shape (k, 3)
        Tool vertices in its tool_tip frame (m).
    poses : ndarray, shape (N, 4, 4)
        All poses of all paths.
    pairs : ndarray, shape (s,)
        Sweep i joins pose pairs[i] to pose pairs[i] + 1.
    windows : list of (xmin, xmax, ymin, ymax), optional
        Region of interest (m), already clipped to the stock.
    pose_bounds : callable() -> (ndarray, ndarray), each shape (N, 3), optional
        Bounds of the part of the tool that can reach the stock (below a plane just above
        it) at each pose, m; default the whole tool's. A tall tool's body beside a window
        or above the block then neither touches it nor stops a groove from spanning it.
        Called only once the stock qualifies.
    """
    reliefs = stock_reliefs(stock)
    if reliefs is None:
        return None
    rects = []
    for old in reliefs:
        for w in windows if windows is not None else [(old.x0, old.x1, old.y0, old.y1)]:
            box = (max(w[0], old.x0), min(w[1], old.x1), max(w[2], old.y0), min(w[3], old.y1))
            if box[0] < box[1] and box[2] < box[3]:
                rects.append((old, box))
    if not rects:
        return None
    boxes = np.array([box for _, box in rects])
    if not _separated(boxes):
        return None
    rotation, origin = poses[:, :3, :3], poses[:, :3, 3]
    flat = np.ascontiguousarray(rotation.reshape(-1, 9))
    if np.all(flat == flat[:1]):  # one orientation, the usual case: no row sort
        unique, which = flat[:1], np.zeros(len(flat), dtype=np.int64)
    else:
        unique, which = np.unique(flat, axis=0, return_inverse=True)
        which = which.reshape(-1)
    if len(unique) > MAX_ORIENTATIONS:
        return None
    turned = np.einsum("rij,kj->rki", unique.reshape(-1, 3, 3), vertices)
    if pose_bounds is None:
        low = turned.min(axis=1)[which] + origin
        high = turned.max(axis=1)[which] + origin
    else:
        low, high = pose_bounds()
    a, b = pairs, pairs + 1
    sweep_low, sweep_high = np.minimum(low[a], low[b]), np.maximum(high[a], high[b])
    tops = np.array([old.top for old, _ in rects])
    touch = ((sweep_low[:, None, 2] < tops[None, :])
             & (sweep_low[:, None, 0] <= boxes[None, :, 1])
             & (sweep_high[:, None, 0] >= boxes[None, :, 0])
             & (sweep_low[:, None, 1] <= boxes[None, :, 3])
             & (sweep_high[:, None, 1] >= boxes[None, :, 2]))
    relevant = touch.any(axis=1)
    if not relevant.any():
        return None
    same = np.abs(flat[b] - flat[a]).max(axis=1) <= SAME_ORIENTATION
    move = origin[b] - origin[a]
    along = []
    for axis in (0, 1):
        other = (1 - axis, 2)
        length = np.abs(move[:, axis])
        along.append(same & (length > 0.0)
                     & (np.abs(move[:, other[0]]) <= STRAIGHT_REL * length)
                     & (np.abs(move[:, other[1]]) <= STRAIGHT_REL * length))
    if np.any(relevant & ~(along[0] | along[1])):
        return None
    profiles: dict[tuple[int, int], np.ndarray] = {}
    segments: list[dict[int, list]] = [{0: [], 1: []} for _ in rects]
    n_cut = n_degenerate = 0
    swept = 0.0
    for axis in (0, 1):
        across = 1 - axis
        chosen = np.flatnonzero(relevant & along[axis])
        if not len(chosen):
            continue
        forward = move[chosen, axis] > 0.0
        # Full span: the tool is wholly before the rectangle at the start of the move and
        # wholly beyond it at the end.
        before = np.where(forward, high[a[chosen], axis], high[b[chosen], axis])
        beyond = np.where(forward, low[b[chosen], axis], low[a[chosen], axis])
        for r, (_, box) in enumerate(rects):
            spans = (before <= box[2 * axis]) & (beyond >= box[2 * axis + 1])
            if np.any(touch[chosen, r] & ~spans):
                return None
        for key in np.unique(which[a[chosen]]):
            group = chosen[which[a[chosen]] == key]
            if (key, axis) not in profiles:
                shape = turned[key]
                profiles[(key, axis)] = lower_hull(shape[:, across], shape[:, 2])
            hull = profiles[(key, axis)]
            if len(hull) < 2:
                n_degenerate += len(group)  # every chosen sweep reaches a rectangle
                continue
            for r, (old, _) in enumerate(rects):
                mine = group[touch[group, r]]
                if not len(mine):
                    continue
                if min(hull[0, 1], hull[-1, 1]) + origin[a[mine], 2].min() < old.top:
                    return None  # a profile end below the top: the groove has a wall there
                du = origin[a[mine], across][:, None]
                dz = origin[a[mine], 2][:, None]
                piece = (hull[:-1, 0] + du, hull[:-1, 1] + dz, hull[1:, 0] + du,
                         hull[1:, 1] + dz)
                segments[r][across].append(piece)
                u0, z0, u1, z1 = _clip_to_top(*(np.ravel(p) for p in piece), old.top)
                span = rects[r][1][2 * axis + 1] - rects[r][1][2 * axis]
                swept += span * float(np.sum((u1 - u0) * (old.top - (z0 + z1) / 2.0)))
            n_cut += len(group)
    new = []
    for r, (old, box) in enumerate(rects):
        parts = {}
        for across, (u_old, z_old) in ((0, (old.gx, old.gz)), (1, (old.fy, old.fz))):
            pieces = [_segments_of(u_old, z_old)] + segments[r][across]
            u0, z0, u1, z1 = (np.concatenate([np.ravel(p[i]) for p in pieces])
                              for i in range(4))
            lo, hi = box[2 * across], box[2 * across + 1]
            parts[across] = envelope(u0, z0, u1, z1, lo, hi, old.top)
        (gx, gz), (fy, fz) = parts[0], parts[1]
        if min(gz.min(), fz.min()) <= old.bottom:
            return None  # cut through the bottom: the walls would not close
        new.append(Relief(box[0], box[1], box[2], box[3], old.bottom, old.top, gx, gz, fy, fz))
    cells = sum((len(r.gx) - 1) * (len(r.fy) - 1) for r in new)
    if cells > MAX_CELLS:
        raise InputError(
            f"the cut part would have about {2 * cells:,} triangles ({cells * 120 / 1e9:.1f} GB), "
            f"over the {2 * MAX_CELLS:,} this engine builds in one piece; cut it where it will "
            "be measured with roi=[(xmin, xmax, ymin, ymax), ...] (m) or --roi (mm)",
            key="roi")
    part, cut_after = relief_part(tuple(new))
    before = tuple(Relief(box[0], box[1], box[2], box[3], old.bottom, old.top,
                          *envelope(*_segments_of(old.gx, old.gz), box[0], box[1], old.top),
                          *envelope(*_segments_of(old.fy, old.fz), box[2], box[3], old.top))
                   for old, box in rects)
    uncut = all(np.all(r.gz == r.top) and np.all(r.fz == r.top) for r in before)
    cut_before = 0.0 if uncut else relief_part(before)[1]
    stock_volume = sum((r.x1 - r.x0) * (r.y1 - r.y0) * (r.top - r.bottom) for r in before)
    stock_volume -= cut_before
    return ReliefCut(part, cut_after - cut_before, stock_volume, n_cut, n_degenerate, swept,
                     np.flatnonzero(relevant))


__all__ = ["Relief", "ReliefCut", "cut_reliefs", "envelope", "lower_hull", "mesh_relief",
           "relief_part", "stock_reliefs"]
