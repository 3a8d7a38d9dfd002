"""Sheets of stock thinner than an atom, left between sweeps whose faces coincide.

Where two sweeps' faces coincide in exact arithmetic (a plunge and the pass after it along
the tool's flank, two grooves that meet end to end), the kinematics' round-off can set them
a fraction of a picometre apart. The boolean then keeps the stock between them: a sheet
1e-13 m thick standing on the cut surface, which a height map reads as a wall
(docs/cutting.md). No material is that thin, and no NC program (1 nm resolution) asks for
it, so the engine takes such sheets away (`remove_sheets`, `trim_sheets`).

A sheet is a pair of faces of the part with opposite outward normals, parallel, whose
planes are less than `SHEET_M` apart with the material between them, which overlap, and
with nothing on either side (`find_sheets`). The sheets' faces on one side fall into
patches (edge-connected, each on one plane); each patch is cut away with a prism, the
patch moved `PRISM_DEPTH` along its normal both ways, walled on its edges. Where a face
reaches past its sheet onto full material, the prism notches it by at most `PRISM_DEPTH`
(2 pm), five hundred times below the 1 nm the machines resolve. A prism's walls can leave
new sheets where they meet the part's faces; the search runs again, `PASSES` times in all.
A part with more than `MOST_REMOVED` patches is left as it is, the sheets counted: each
prism is a boolean on the whole part.
"""

from __future__ import annotations

from dataclasses import dataclass

import manifold3d
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from machinesim.cutting.flat_pieces import flat_pieces
from machinesim.cutting.sweeps import manifold_from
from machinesim.tolerances import SHEET_M

__all__ = ["SheetReport", "find_sheets", "remove_sheets", "trim_sheets"]

#: Two unit normals are opposite when they differ by at most this (after one is negated):
#: 1e-9 rad, far above the round-off of a face normal (1e-16 relative to its edges) and far
#: below any real angle between two faces of a part.
NORMAL_TOL = 1e-9
#: How far (m) beyond a sheet's faces a point must lie outside the part: ten picometres,
#: clear of the faces' round-off and of the sheet itself.
OUTSIDE_STEP = 10 * SHEET_M
#: The most patches of sheets' faces cut away from one part. Each prism is its own boolean
#: on the whole part (0.05 s on 60,000 triangles); a part with more is returned as it is,
#: the sheets counted (`SheetReport.removed` False, and the cut's notes say so).
MOST_REMOVED = 256
#: How far (m) a patch is moved along its normal both ways to make its prism: past the
#: sheet's far face (under `SHEET_M` away) with a picometre to spare.
PRISM_DEPTH = 2 * SHEET_M
#: Two faces of a sheet sharing an edge join one patch when their normals agree within this
#: (rad): a patch is then flat, and its prism, moved along the patch's mean normal, stands
#: PRISM_DEPTH times the cosine of a face's tilt (1 - 5e-9 at 0.1 mrad) off each face.
PATCH_NORMAL_TOL = 1e-6
#: Searches for sheets, and prisms cut, at most: the first for the cut's own sheets, the
#: others for those the prisms' walls leave against the part's faces.
PASSES = 3


@dataclass(frozen=True)
class SheetReport:
    """Sheets found on a part and cut away.

    Attributes
    ----------
    count : int
        Pairs of faces found bounding a sheet, and the free-standing sheets (``pieces``).
    thickness_max : float
        The thickest of them, m (below `SHEET_M`); 0 when none.
    area : float
        Summed area of the sheets' faces on one side, m^2 (an upper bound of the sheets'
        area: a triangle may reach past its sheet).
    volume : float
        Volume cut away with them, m^3 (the sheets and their slabs' picometre notches).
    removed : bool
        False when sheets are left on the part (``left``), and said.
    left : int
        Sheets still on the part returned: all of them when their faces made more than
        `MOST_REMOVED` patches, else those the last of `PASSES` searches found.
    pieces : int
        Free-standing sheets among ``count``: separate pieces of the part thinner than
        `SHEET_M` on average (`flat_pieces`), removed whole.
    """

    count: int = 0
    thickness_max: float = 0.0
    area: float = 0.0
    volume: float = 0.0
    removed: bool = True
    left: int = 0
    pieces: int = 0


#: +u faces paired with the -u faces at a time in `find_sheets`: the k-d query's pairs are
#: kept only when close, so a part of millions of faces stays within memory (4 million
#: triangles of a pocket cut through bending axes asked for more than 24 GB at once).
FACING_CHUNK = 1_000_000


def _facing(points, plus, minus, u, offset, thickness):
    """Pairs (i +u, j -u) of faces parallel within `NORMAL_TOL` whose planes lie less than
    ``thickness`` apart, and the gaps: by a k-d query on (u, scaled offset), `FACING_CHUNK`
    +u faces at a time."""
    tree = cKDTree(points[minus])
    found = []
    for start in range(0, len(plus), FACING_CHUNK):
        chunk = plus[start:start + FACING_CHUNK]
        near = cKDTree(points[chunk]).sparse_distance_matrix(tree, 2.0 * NORMAL_TOL,
                                                             output_type="ndarray")
        i, j = chunk[near["i"]], minus[near["j"]]
        gap = offset[i] - offset[j]
        close = (np.abs(u[i] - u[j]).max(axis=1) <= NORMAL_TOL) & (np.abs(gap) < thickness)
        found.append((i[close], j[close], gap[close]))
    if len(found) == 1:
        return found[0]
    return tuple(np.concatenate(parts) for parts in zip(*found, strict=True))


def find_sheets(vertices, triangles, thickness: float = SHEET_M) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of triangles bounding a sheet of material thinner than ``thickness`` (m) with
    nothing on either side of it.

    Candidates are pairs of faces with opposite outward normals, parallel within
    `NORMAL_TOL`, whose planes are less than ``thickness`` apart with the +u face ahead
    (the material between them) and whose triangles overlap in their plane by more than
    ``thickness`` (separating axes). Two kinds of candidates are not sheets and are left:

    - a skin over a crack: a face lies just behind the sheet's back face (or ahead of its
      front face), facing it, within ``thickness``; what a height map sees is the same;
    - a face with material just behind it: the point ``OUTSIDE_STEP`` in front of the
      pair's common part, or behind it, is inside the solid: a short segment through
      the pair meets other faces than its two.

    Parameters
    ----------
    vertices : array_like, shape (n, 3)
    triangles : array_like, shape (m, 3)
        A closed, outward-oriented mesh.
    thickness : float

    Returns
    -------
    pairs : ndarray of int, shape (k, 2)
        (triangle facing +u, triangle facing -u) for a common direction u.
    gaps : ndarray, shape (k,)
        Their planes' distance (m), 0 <= gap < ``thickness``.
    """
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    empty = np.zeros((0, 2), dtype=np.int64), np.zeros(0)
    if len(t) < 2:
        return empty
    corners = v[t]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(cross, axis=1)
    keep = np.flatnonzero(length > 0.0)
    normal = cross[keep] / length[keep, None]
    # one direction u per family of parallel faces: the normal with its largest component
    # made positive; side says which way the face looks along u
    big = np.abs(normal).argmax(axis=1)
    side = np.sign(normal[np.arange(len(keep)), big])
    u = normal * side[:, None]
    kept = corners[keep]
    offset = np.einsum("ij,ij->i", u, kept.mean(axis=1))
    # a 4-d point per face, its offset scaled so that `thickness` counts as NORMAL_TOL
    points = np.column_stack([u, offset * (NORMAL_TOL / thickness)])
    wide = _wide(kept, length[keep], thickness)
    plus, minus = np.flatnonzero((side > 0) & wide), np.flatnonzero((side < 0) & wide)
    if not (plus.size and minus.size):
        return empty
    # material lies behind each face: between the planes when the +u face is ahead
    i, j, gap = _facing(points, plus, minus, u, offset, thickness)
    low, high = corners.min(axis=1), corners.max(axis=1)
    kept_low, kept_high = low[keep], high[keep]
    boxed = np.all((kept_low[i] <= kept_high[j] + thickness)
                   & (kept_low[j] <= kept_high[i] + thickness), axis=1)
    i, j, gap = i[boxed], j[boxed], gap[boxed]
    flat_i, flat_j = _in_plane(kept[i], u[i]), _in_plane(kept[j], u[i])
    common = _overlapping(flat_i, flat_j, thickness)
    i, j, gap, flat_i, flat_j = i[common], j[common], gap[common], flat_i[common], flat_j[common]
    crack = gap < 0.0
    skin = np.isin(j, j[crack]) | np.isin(i, i[crack])
    candidates = np.flatnonzero(~crack & ~skin)
    found = []
    boxes = _Boxes(low, high) if candidates.size else None
    for k in candidates:
        q2 = _clipped(flat_i[k], flat_j[k]).mean(axis=0)
        basis = _basis(u[i[k]])
        middle = 0.5 * (offset[i[k]] + offset[j[k]])
        q = q2[0] * basis[0] + q2[1] * basis[1] + middle * u[i[k]]
        step = (OUTSIDE_STEP + 0.5 * gap[k]) * u[i[k]]
        # a segment through the sheet's common part that meets its two faces and nothing
        # else: empty on both sides (the winding number is 0 or 1 on a closed mesh, so it
        # cannot be 1 before the back face and 2 between the faces)
        if _crossings(q - step, q + step, corners, boxes) == 2:
            found.append(k)
    found = np.array(found, dtype=np.int64)
    if not found.size:
        return empty
    return np.column_stack([keep[i[found]], keep[j[found]]]), gap[found]


def _wide(corners: np.ndarray, doubled_area: np.ndarray, thickness: float) -> np.ndarray:
    """Whether each triangle (k, 3, 3), of twice the area ``doubled_area`` (k,), is wider
    than ``thickness`` across every edge: its smallest altitude, twice its area over its
    longest edge, is more. One that is not cannot overlap another by more than ``thickness``
    across that edge (`_overlapping`), however it is paired, so it bounds no sheet and is
    left out before the pairing: the booleans leave such slivers (a slot plunged 1 um at a
    time: 522 of 1e-29 m^2 facing down in a floor of 123,091 facing up, 64 million pairs
    and 35 s, where 0.3 s without them)."""
    edges = np.stack([corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 1],
                      corners[:, 0] - corners[:, 2]], axis=1)
    return doubled_area > thickness * np.linalg.norm(edges, axis=2).max(axis=1)


def _basis(u: np.ndarray) -> np.ndarray:
    """Two unit vectors (2, 3) spanning the plane normal to the unit ``u`` (..., 3)."""
    u = np.asarray(u, dtype=np.float64)
    ref = np.where(np.abs(u[..., :1]) < 0.9, np.array([1.0, 0.0, 0.0]),
                   np.array([0.0, 1.0, 0.0]))
    e1 = np.cross(u, ref)
    e1 = e1 / np.linalg.norm(e1, axis=-1, keepdims=True)
    return np.stack([e1, np.cross(u, e1)], axis=-2)


def _in_plane(triangles: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Triangles (k, 3, 3) in the coordinates (k, 3, 2) of the planes normal to u (k, 3)."""
    return np.einsum("kij,klj->kil", triangles, _basis(u))


def _overlapping(a: np.ndarray, b: np.ndarray, margin: float) -> np.ndarray:
    """Whether flat triangles a, b (k, 3, 2) overlap by more than ``margin`` across each of
    their six edges (the separating axes of two convex polygons)."""
    result = np.ones(len(a), dtype=bool)
    for tri in (a, b):
        for n in range(3):
            edge = tri[:, (n + 1) % 3] - tri[:, n]
            axis = np.column_stack([-edge[:, 1], edge[:, 0]])
            axis = axis / np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-300)
            pa = np.einsum("kij,kj->ki", a, axis)
            pb = np.einsum("kij,kj->ki", b, axis)
            result &= (np.minimum(pa.max(axis=1), pb.max(axis=1))
                       - np.maximum(pa.min(axis=1), pb.min(axis=1))) > margin
    return result


def _clipped(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The overlap (k, 2) of flat triangles a and b (3, 2): a clipped by each edge of b."""
    orientation = np.sign(_cross2(b[1] - b[0], b[2] - b[0]))
    polygon = list(a)
    for n in range(3):
        p0, p1 = b[n], b[(n + 1) % 3]

        def inside(p, p0=p0, p1=p1):
            return orientation * _cross2(p1 - p0, p - p0) >= 0.0

        out = []
        for m, current in enumerate(polygon):
            previous = polygon[m - 1]
            if inside(current) != inside(previous):
                d0 = _cross2(p1 - p0, previous - p0)
                d1 = _cross2(p1 - p0, current - p0)
                out.append(previous + (current - previous) * d0 / (d0 - d1))
            if inside(current):
                out.append(current)
        polygon = out
        if not polygon:
            return np.asarray(a)  # touching within round-off: any point of a will do
    return np.array(polygon)


def _cross2(a: np.ndarray, b: np.ndarray) -> float:
    """z component of the cross product of two plane vectors."""
    return float(a[0] * b[1] - a[1] * b[0])


class _Boxes:
    """Axis-aligned boxes (low, high: (m, 3)) of triangles, each axis's bounds contiguous."""

    def __init__(self, low: np.ndarray, high: np.ndarray) -> None:
        self.low = [np.ascontiguousarray(low[:, n]) for n in range(3)]
        self.high = [np.ascontiguousarray(high[:, n]) for n in range(3)]

    def touching(self, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """Indices of the boxes that touch the box low..high."""
        near = np.flatnonzero((self.low[0] <= high[0]) & (self.high[0] >= low[0]))
        for n in (1, 2):
            near = near[(self.low[n][near] <= high[n]) & (self.high[n][near] >= low[n])]
        return near


def _crossings(start: np.ndarray, end: np.ndarray, corners: np.ndarray,
               boxes: _Boxes) -> int:
    """How many triangles (corners (m, 3, 3)) the segment start-end meets (Moller and
    Trumbore's test on those whose box it touches)."""
    near = boxes.touching(np.minimum(start, end), np.maximum(start, end))
    tri = corners[near]
    direction = end - start
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = det != 0.0
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    r = start - tri[:, 0]
    a = np.einsum("ij,ij->i", r, p) * inv
    q = np.cross(r, e1)
    b = (q @ direction) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    return int(np.count_nonzero(ok & (a >= 0.0) & (b >= 0.0) & (a + b <= 1.0)
                                & (t >= 0.0) & (t <= 1.0)))


def remove_sheets(solid: manifold3d.Manifold,
                  thickness: float = SHEET_M) -> tuple[manifold3d.Manifold, SheetReport]:
    """``solid`` without its sheets thinner than ``thickness`` (m), and what was found.

    A solid with no sheet comes back as it is (the same object). Each patch's prism is
    subtracted on its own: prisms on crossing planes may overlap, and a union of
    overlapping slabs (this module's first removal, a slab per pair of triangles) cost
    manifold3d ten times their subtractions. Measured on paper 002's crown after
    compensation: 3,369 sheets in 100 patches, cut away in 7.9 s with the three searches;
    the slabs, united in rounds of disjoint boxes, needed 1,069 rounds and grew the part
    from 58,000 to 660,000 triangles in the first 40.
    """
    solid, flat = flat_pieces(solid, thickness)  # the same solid when it has none
    pieces = dict(count=len(flat), area=sum((a for a, _, _ in flat), 0.0),
                  thickness_max=max((t for _, t, _ in flat), default=0.0),
                  volume=sum((v for _, _, v in flat), 0.0), pieces=len(flat))
    vertices, triangles = _arrays(solid)
    pairs, gaps = find_sheets(vertices, triangles, thickness)
    if not len(pairs):
        return solid, SheetReport(**pieces)
    corners = vertices[triangles]
    front = corners[pairs[:, 0]]
    area = 0.5 * float(np.linalg.norm(np.cross(front[:, 1] - front[:, 0],
                                               front[:, 2] - front[:, 0]), axis=1).sum())
    found = dict(count=len(pairs) + pieces["count"], area=area + pieces["area"],
                 thickness_max=max(float(gaps.max()), pieces["thickness_max"]),
                 pieces=len(flat))
    run_id = manifold3d.Manifold.reserve_ids(1)  # the notches are no sweep's faces
    trimmed, left = solid, 0
    for n in range(PASSES + 1):
        if n:  # what the prisms left
            vertices, triangles = _arrays(trimmed)
            pairs = find_sheets(vertices, triangles, thickness)[0]
            if not len(pairs) or n == PASSES:
                left = len(pairs)
                break
        patches = _patches(vertices, triangles, np.unique(pairs[:, 0]))
        if len(patches) > MOST_REMOVED:
            left = len(pairs)
            break
        for patch in patches:
            for prism in _prisms(vertices, triangles[patch], run_id):
                trimmed = trimmed - prism
                trimmed.num_tri()  # evaluate now: left lazy, manifold3d would unite them
    # a sheet is 1e-20 m^3 or so: the difference of the two volumes is exact enough
    removed = solid.volume() - trimmed.volume() if trimmed is not solid else 0.0
    removed += pieces["volume"]
    return trimmed, SheetReport(**found, volume=removed, removed=left == 0, left=left)


def _arrays(solid: manifold3d.Manifold) -> tuple[np.ndarray, np.ndarray]:
    mesh = solid.to_mesh64()
    return np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts)


def _patches(vertices: np.ndarray, triangles: np.ndarray,
             faces: np.ndarray) -> list[np.ndarray]:
    """``faces`` (triangle indices) grouped into patches: joined where two share an edge and
    their normals agree within `PATCH_NORMAL_TOL`."""
    tri = triangles[faces].astype(np.int64)
    corners = vertices[tri]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(tri)), 3)
    key = edges[:, 0] * (int(tri.max()) + 1) + edges[:, 1]
    order = np.argsort(key, kind="stable")
    shared = np.flatnonzero(key[order][1:] == key[order][:-1])
    a, b = owner[order][shared], owner[order][shared + 1]
    flat = np.linalg.norm(normals[a] - normals[b], axis=1) <= PATCH_NORMAL_TOL
    a, b = a[flat], b[flat]
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(len(tri), len(tri)))
    count, label = connected_components(graph, directed=False)
    return [faces[label == k] for k in range(count)]


def _prisms(vertices: np.ndarray, patch: np.ndarray, run_id: int) -> list:
    """The prism of a patch of triangles (k, 3): the patch moved `PRISM_DEPTH` along its
    mean normal and against it, walled along its boundary edges; a patch whose prism is no
    closed manifold (faces meeting at a corner only) gives one prism per triangle."""
    corners = vertices[patch]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]).sum(axis=0)
    normal /= np.linalg.norm(normal)
    used, local = np.unique(patch, return_inverse=True)
    local = local.reshape(-1, 3)
    n = len(used)
    points = np.concatenate([vertices[used] + PRISM_DEPTH * normal,
                             vertices[used] - PRISM_DEPTH * normal])
    directed = np.concatenate([local[:, [0, 1]], local[:, [1, 2]], local[:, [2, 0]]])
    boundary = directed[~np.isin(directed[:, 0] * n + directed[:, 1],
                                 directed[:, 1] * n + directed[:, 0])]
    i, j = boundary[:, 0], boundary[:, 1]
    # an edge i -> j (the patch on its left, seen from the normal) walls the prism outwards
    walls = np.concatenate([np.stack([i, i + n, j + n], axis=1), np.stack([i, j + n, j], axis=1)])
    prism = manifold_from(points, np.concatenate([local, local[:, ::-1] + n, walls]), run_id)
    if prism is not None:
        return [prism]
    if len(patch) == 1:
        return []
    return [p for k in range(len(patch)) for p in _prisms(vertices, patch[k:k + 1], run_id)]


def trim_sheets(part):
    """A finished `Part` without its sheets (`remove_sheets`), what was found, and a note for
    the cut's report when they were too many to remove (else None)."""
    from machinesim.workpiece import Part

    solid = part.manifold
    trimmed, report = remove_sheets(solid)
    note = None
    if not report.removed:
        note = (f"{report.left} sheets of stock under {SHEET_M:g} m thick left between "
                f"sweeps whose faces coincide (of {report.count} found; more than "
                f"{MOST_REMOVED} patches to cut away, or left after {PASSES} passes): a "
                "height read on one reads its top edge, not the cut surface")
    return (part if trimmed is solid else Part(trimmed)), report, note
