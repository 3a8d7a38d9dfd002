"""Exact height-field cutting of straight grooves that run right across a block.

A tool translated in a straight line, from wholly before the block to wholly beyond it in
XY, removes over the block an extrusion of one profile: the lower boundary of the tool's
shadow on the plane across its travel, projected along the travel
(`machinesim.cutting.profiles.lower_hull`). Grooves that share a direction d in XY and a
slope a along it (dz/dt, t = d . (x, y); 0 when cut level, non-zero on a tilted table) form
a family; across them, at s = n . (x, y) with n = (-d_y, d_x), they leave the lower
envelope F(s) of their profiles, and the family's surface is F(s) + a t. With two families
in any two directions the top of the cut block is

    z = min(top, F_1(s_1) + a_1 t_1, F_2(s_2) + a_2 t_2),

piecewise linear on the affine grid of the two envelopes' breakpoints and meshed exactly,
cell by cell, with the cells on the block's sides clipped to it
(`machinesim.cutting.relief_mesh`): no boolean is needed. This is the configuration of ruled
groove patterns (parallel V grooves, crossing grooves that leave pyramids, both slanted by a
machine's squareness or a C rotation), where the boolean engine spends about 5 us per output
triangle and this mesher well under 1 us.

A cut qualifies when the stock is an axis-aligned box or a part this module made, every
sweep that can reach the stock is such a full-span straight groove whose profile rises above
the top at both ends and stays above the bottom, and the grooves, with those the part was
cut with before, run in at most two directions (`MAX_FAMILIES`) at least `MIN_FAMILY_SINE`
apart, all grooves of one direction at one slope (within `STRAIGHT_REL`). Anything else
returns None and the caller uses the boolean engine. A relief keeps its envelopes with the
part (`Part.reliefs`), so a second program of grooves on the same part is cut the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.cutting.profiles import clip_to_top, envelope, lower_hull, segments_of
from machinesim.cutting.relief_mesh import (
    Family,
    Relief,
    across,
    along,
    direction,
    domain,
    grid_families,
    mesh_relief,
    relief_part,
    span,
)
from machinesim.exceptions import InputError
from machinesim.tolerances import SAME_ORIENTATION, STRAIGHT_REL
from machinesim.workpiece import Part

#: Most distinct tool orientations the relief path profiles; more means a rotary program,
#: which is never a set of straight grooves.
MAX_ORIENTATIONS = 64
#: Most groove directions one relief holds: the mesher grids two families.
MAX_FAMILIES = 2
#: Two families must cross at a sine at least this (about 5.7 deg): nearer parallel, the
#: grid's cells turn into long slivers and most of its bounding grid lies off the block.
MIN_FAMILY_SINE = 0.1
#: Most grid cells in one cut: about 2 triangles and 120 bytes of mesh each, so 2e7 cells
#: make a ~2.4 GB part. Larger parts are refused with advice, not left to exhaust memory
#: (the boolean engine could not cut them either).
MAX_CELLS = 20_000_000


def _flat(x0, x1, y0, y1, bottom, top) -> Relief:
    return Relief(x0, x1, y0, y1, bottom, top, ())


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


def unit_direction(move_xy: np.ndarray) -> np.ndarray:
    """Unit direction of a travel in XY, snapped to an axis within `STRAIGHT_REL`.

    The snap keeps grooves along X or Y exact (s is then y or -x, no rounding), and moves
    them by at most the straightness tolerance the sweeps already pass.
    """
    d = move_xy / np.hypot(move_xy[0], move_xy[1])
    if abs(d[1]) <= STRAIGHT_REL:
        return np.array([1.0, 0.0])
    if abs(d[0]) <= STRAIGHT_REL:
        return np.array([0.0, 1.0])
    return d


def _normal(direction: np.ndarray) -> np.ndarray:
    return np.array([-direction[1], direction[0]])


def _same_direction(normal: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Rows of ``d`` (unit, (k, 2)) parallel to the family of ``normal`` within tolerance."""
    return np.abs(d @ normal) <= STRAIGHT_REL


@dataclass(frozen=True)
class ReliefCut:
    """What `cut_reliefs` did: the part, and the counts for the engine's report.

    ``swept_volume`` (m^3) is the most the grooves could remove: each profile's area below
    the top times the length of the block along the groove (its chord for a groove along
    an axis, the block's extent along it otherwise); the empty-cut rule is relative to it.
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


def _extent(low: np.ndarray, high: np.ndarray, d: np.ndarray, pick) -> np.ndarray:
    """Largest (``pick`` np.maximum) or least (np.minimum) d . p over boxes [low, high] in XY.

    A zero component of d adds nothing (no 0 * inf from a box that is empty there).
    """
    total = np.zeros(len(low))
    for k in (0, 1):
        if d[k] != 0.0:
            total += pick(low[:, k] * d[k], high[:, k] * d[k])
    return total


def _orientations(flat: np.ndarray, used: np.ndarray):
    """Distinct rotations (rows of 9) among poses ``used``, and each pose's index into them.

    Poses not in ``used`` get -1. (None, None) when there are more than `MAX_ORIENTATIONS`.
    """
    which = np.full(len(flat), -1, dtype=np.int64)
    rows = flat[used]
    if np.all(rows == rows[:1]):  # one orientation, the usual case: no row sort
        unique, inverse = rows[:1], np.zeros(len(rows), dtype=np.int64)
    else:
        unique, inverse = np.unique(rows, axis=0, return_inverse=True)
    if len(unique) > MAX_ORIENTATIONS:
        return None, None
    which[used] = inverse.reshape(-1)
    return unique, which


def _raised_top(normal, slope: float, box, top: float) -> float:
    """The level a family's envelope is built under: ``top`` for a level family; for a
    sloped one high enough that no slope term over ``box`` brings it down to ``top`` (the
    mesher then cuts the surface at the real top)."""
    if slope == 0.0:
        return top
    t0, t1 = span(direction(normal), *box)
    return top + 2.0 * abs(slope) * max(abs(t0), abs(t1), abs(top))


def _rebuilt(old: Relief, box, normals, segments, slopes) -> Relief:
    """Relief over ``box`` (within ``old``) with the old envelopes and new profile segments.

    ``normals`` and ``slopes`` are the families'; ``segments[k]`` lists (u0, z0, u1, z1)
    pieces of new profiles across family k, heights at t = 0. An old family's normal is one
    of ``normals``, at the same slope.
    """
    families = []
    for k, normal in enumerate(normals):
        pieces = list(segments[k])
        for family in old.families:
            if np.array_equal(family.normal, normal):
                pieces.append(segments_of(family.u, family.z))
        if not pieces:
            continue
        u0, z0, u1, z1 = (np.concatenate([np.ravel(p[i]) for p in pieces]) for i in range(4))
        lo, hi = domain(normal, *box)
        raised = _raised_top(normal, slopes[k], box, old.top)
        u, z = envelope(u0, z0, u1, z1, lo, hi, raised)
        if np.any(z < raised):
            families.append(Family(normal, u, z, slopes[k]))
    return Relief(*box, old.bottom, old.top, tuple(families))


def _lowest_slope_term(family: Family, box) -> float:
    """Least of slope * t over the rectangle (0 for a level family), m."""
    t0, t1 = span(direction(family.normal), *box)
    return min(family.slope * t0, family.slope * t1)


def _family_slopes(normals, chosen, member, move, olds) -> list[float] | None:
    """Each family's slope along its direction (dz/dt): its old envelope's, or else its
    first new groove's; a groove within `STRAIGHT_REL` of level counts as level (0). None
    when a groove's slope differs from it by more than `STRAIGHT_REL`: grooves of one
    direction at several slopes are not one extrusion."""
    slopes = []
    for k, normal in enumerate(normals):
        d = direction(normal)
        known = [float(f.slope) for old in olds for f in old.families
                 if np.array_equal(f.normal, normal)]
        mine = chosen[member == k]
        travel = move[mine, :2] @ d
        rise = move[mine, 2] / travel
        rise[np.abs(move[mine, 2]) <= STRAIGHT_REL * np.abs(travel)] = 0.0
        every = np.concatenate([known, rise])
        if not len(every):
            slopes.append(0.0)
            continue
        if np.any(np.abs(every - every[0]) > STRAIGHT_REL):
            return None
        slopes.append(float(every[0]))
    return slopes


def _ends_in_stock(vertices: np.ndarray, poses: np.ndarray, pairs: np.ndarray,
                   rects) -> bool:
    """Whether a sweep starts or ends with the tool in a rectangle's stock: its lowest
    vertex strictly within the rectangle and below its top. Such a sweep (a plunge, a pass
    that stops in the material, a raster's short sloped lines) reaches the stock and cannot
    run right across it, so the span check would refuse the cut; found here first, it is
    refused before the reaching bounds (`pose_bounds`), which took 2.8 s of a 3,844-line
    ball raster only to be refused."""
    tip = vertices[np.argmin(vertices[:, 2])]
    ends = np.unique(np.concatenate([pairs, pairs + 1]))
    points = np.einsum("nij,j->ni", poses[ends, :3, :3], tip) + poses[ends, :3, 3]
    x, y, z = points.T
    return any(bool(np.any((x > x0) & (x < x1) & (y > y0) & (y < y1) & (z < old.top)))
               for old, (x0, x1, y0, y1) in rects)


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
    if not _separated(boxes) or _ends_in_stock(vertices, poses, pairs, rects):
        return None
    rotation, origin = poses[:, :3, :3], poses[:, :3, 3]
    flat = np.ascontiguousarray(rotation.reshape(-1, 9))
    a, b = pairs, pairs + 1
    if pose_bounds is None:
        unique, which = _orientations(flat, np.arange(len(flat)))
        if unique is None:
            return None
        turned = np.einsum("rij,kj->rki", unique.reshape(-1, 3, 3), vertices)
        low = turned.min(axis=1)[which] + origin
        high = turned.max(axis=1)[which] + origin
    else:
        low, high = pose_bounds()
    sweep_low, sweep_high = np.minimum(low[a], low[b]), np.maximum(high[a], high[b])
    tops = np.array([old.top for old, _ in rects])
    # Poses where no part of the tool is below the stock's top.
    above = ~np.isfinite(low[:, 2]) | (low[:, 2] >= tops.max())
    if pose_bounds is not None:
        # A sloped sweep with one end wholly above the stock cuts on the way there, where
        # neither end's reaching part is: it takes the whole tool's bounds at that end.
        # (Ends that both reach bound the way between; a plunge reaches deepest at its end.)
        travels = (origin[a, 0] != origin[b, 0]) | (origin[a, 1] != origin[b, 1])
        for end, other in ((a, b), (b, a)):
            lost = np.flatnonzero(travels & ~np.isfinite(low[end, 2])
                                  & np.isfinite(low[other, 2]))
            if len(lost):
                body = (np.einsum("nij,kj->nki", rotation[end[lost]], vertices)
                        + origin[end[lost], None])
                sweep_low[lost] = np.minimum(sweep_low[lost], body.min(axis=1))
                sweep_high[lost] = np.maximum(sweep_high[lost], body.max(axis=1))
    touch = ((sweep_low[:, None, 2] < tops[None, :])
             & (sweep_low[:, None, 0] <= boxes[None, :, 1])
             & (sweep_high[:, None, 0] >= boxes[None, :, 0])
             & (sweep_low[:, None, 1] <= boxes[None, :, 3])
             & (sweep_high[:, None, 1] >= boxes[None, :, 2]))
    relevant = touch.any(axis=1)
    if not relevant.any():
        return None
    if pose_bounds is not None:
        # Only the orientations of sweeps that reach the block are profiled: a C turn
        # between groove sets, clear of the block, does not count.
        unique, which = _orientations(flat, np.unique(np.concatenate([a[relevant],
                                                                      b[relevant]])))
        if unique is None:
            return None
        turned = np.einsum("rij,kj->rki", unique.reshape(-1, 3, 3), vertices)
    same = np.abs(flat[b] - flat[a]).max(axis=1) <= SAME_ORIENTATION
    move = origin[b] - origin[a]
    planar = np.hypot(move[:, 0], move[:, 1])
    straight = same & (planar > 0.0)
    if np.any(relevant & ~straight):
        return None
    chosen = np.flatnonzero(relevant)
    travel_xy = move[chosen, :2] / planar[chosen, None]
    # Families: the part's own directions first (their normals are kept as they are, so a
    # second program extends the same envelopes), then each new direction.
    normals: list[np.ndarray] = []
    for old, _ in rects:
        for family in old.families:
            if not any(np.array_equal(family.normal, n) for n in normals):
                normals.append(family.normal)
    member = np.full(len(chosen), -1)
    for k, normal in enumerate(normals):
        member[(member < 0) & _same_direction(normal, travel_xy)] = k
    while np.any(member < 0) and len(normals) <= MAX_FAMILIES:
        first = int(np.flatnonzero(member < 0)[0])
        normals.append(_normal(unit_direction(move[chosen[first], :2])))
        member[(member < 0) & _same_direction(normals[-1], travel_xy)] = len(normals) - 1
    if len(normals) > MAX_FAMILIES:
        return None
    if len(normals) == 2 and abs(normals[0][0] * normals[1][1]
                                 - normals[0][1] * normals[1][0]) < MIN_FAMILY_SINE:
        return None
    slopes = _family_slopes(normals, chosen, member, move, [old for old, _ in rects])
    if slopes is None:
        return None
    segments: list[list[list]] = [[[] for _ in normals] for _ in rects]
    n_cut = n_degenerate = 0
    swept = 0.0
    for k, normal in enumerate(normals):
        mine = chosen[member == k]
        if not len(mine):
            continue
        d = direction(normal)  # along the grooves
        slope = slopes[k]
        forward = move[mine, :2] @ d > 0.0
        # Full span: the tool is wholly before the rectangle at the start of the move and
        # wholly beyond it at the end, along d (its bounding box's extent along d), or, for
        # a sloped groove, wholly above the stock there: the line goes on rising beyond
        # that end, so the groove leaves through the top as the extrusion does.
        start, end = np.where(forward, a[mine], b[mine]), np.where(forward, b[mine], a[mine])
        before = _extent(low[start], high[start], d, np.maximum)
        beyond = _extent(low[end], high[end], d, np.minimum)
        for r, (_, box) in enumerate(rects):
            t0, t1 = span(d, *box)
            spans = (((before <= t0) | above[start]) & ((beyond >= t1) | above[end]))
            if np.any(touch[mine, r] & ~spans):
                return None
        for key in np.unique(which[a[mine]]):
            group = mine[which[a[mine]] == key]
            shape = turned[key]
            # The shadow projected along the travel: a vertex at t_v along d, z_v, meets
            # the plane t = 0 at z_v - slope t_v.
            hull = lower_hull(across(normal, shape[:, 0], shape[:, 1]),
                              shape[:, 2] - slope * along(normal, shape[:, 0], shape[:, 1]))
            if len(hull) < 2:
                n_degenerate += len(group)  # every chosen sweep reaches a rectangle
                continue
            for r, (old, box) in enumerate(rects):
                reach = group[touch[group, r]]
                if not len(reach):
                    continue
                t0, t1 = span(d, *box)
                # the groove at t = 0 (its profile's height there), and at its lowest over
                # the rectangle
                dz = origin[a[reach], 2] - slope * along(normal, origin[a[reach], 0],
                                                         origin[a[reach], 1])
                if min(hull[0, 1], hull[-1, 1]) + dz.min() + min(slope * t0, slope * t1) \
                        < old.top:
                    return None  # a profile end below the top: the groove has a wall there
                du = across(normal, origin[a[reach], 0], origin[a[reach], 1])[:, None]
                dz = dz[:, None]
                piece = (hull[:-1, 0] + du, hull[:-1, 1] + dz, hull[1:, 0] + du,
                         hull[1:, 1] + dz)
                segments[r][k].append(piece)
                middle = slope * (t0 + t1) / 2.0  # the profile's height change at mid-span
                u0, z0, u1, z1 = clip_to_top(*(np.ravel(p) for p in piece), old.top - middle)
                swept += (t1 - t0) * float(np.sum((u1 - u0)
                                                  * (old.top - middle - (z0 + z1) / 2.0)))
            n_cut += len(group)
    new = []
    for r, (old, box) in enumerate(rects):
        relief = _rebuilt(old, box, normals, segments[r], slopes)
        if any(f.z.min() + _lowest_slope_term(f, box) <= old.bottom for f in relief.families):
            return None  # cut through the bottom: the walls would not close
        new.append(relief)
    cells = 0
    for relief in new:
        first, second = grid_families(relief)
        cells += (len(first.u) - 1) * (len(second.u) - 1)
    if cells > MAX_CELLS:
        raise InputError(
            f"the cut part would have about {2 * cells:,} triangles ({cells * 120 / 1e9:.1f} GB), "
            f"over the {2 * MAX_CELLS:,} this engine builds in one piece; cut it where it will "
            "be measured with roi=[(xmin, xmax, ymin, ymax), ...] (m) or --roi (mm)",
            key="roi")
    part, cut_after = relief_part(tuple(new))
    before = tuple(_rebuilt(old, box, normals, [[] for _ in normals], slopes)
                   for old, box in rects)
    uncut = all(not r.families for r in before)
    cut_before = 0.0 if uncut else relief_part(before)[1]
    stock_volume = sum((r.x1 - r.x0) * (r.y1 - r.y0) * (r.top - r.bottom) for r in before)
    stock_volume -= cut_before
    return ReliefCut(part, cut_after - cut_before, stock_volume, n_cut, n_degenerate, swept,
                     np.flatnonzero(relevant))


__all__ = ["MAX_FAMILIES", "Family", "Relief", "ReliefCut", "cut_reliefs", "envelope",
           "lower_hull", "mesh_relief", "relief_part", "stock_reliefs", "unit_direction"]
