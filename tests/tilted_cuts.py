"""Tools swung about a Y line, cut by the engine given their poses, and the distance from a
point to the cut's surface, and the sliver one cut leaves past another: shared by
tests/test_cutting_tilted_*.py and benchmarks/tilted_*.py and tilt_with_move.py. Not part of
the package."""

from __future__ import annotations

import math

import numpy as np

from machinesim.cutting.engine import remove
from machinesim.tolerances import SHEET_M
from machinesim.workpiece import Part, block

#: Distances beyond this (m) are not resolved by `sliver` (reported as at least it).
FARTHEST_M = 2e-6


def turned_about_y(angle: float, pivot: np.ndarray, tip: np.ndarray):
    """The rotation (3, 3) by ``angle`` (rad) about the Y line through ``pivot`` and the
    origin (3,) that carries ``tip`` (the tool's origin at angle 0) so."""
    c, s = math.cos(angle), math.sin(angle)
    rotation = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return rotation, pivot - rotation @ (pivot - tip)


def swing(n: int, tip: np.ndarray, pivot: np.ndarray, half: float) -> np.ndarray:
    """Poses (n + 1, 4, 4) of a tool whose origin stands at ``tip`` at angle 0, turned about
    the Y line through ``pivot`` from -half to +half (rad) in n equal sweeps."""
    poses = np.zeros((n + 1, 4, 4))
    for i, angle in enumerate(np.linspace(-half, half, n + 1)):
        poses[i, :3, :3], poses[i, :3, 3] = turned_about_y(angle, pivot, tip)
        poses[i, 3, 3] = 1.0
    return poses


def swept_cut(tool, poses: np.ndarray):
    """The engine's cut (part, report) of ``tool`` through ``poses`` (one posed sweep set) in
    a 10 x 10 x 2 mm block, its top at z = 0."""
    return remove(block(10e-3, 10e-3, 2e-3), tool, [poses])


def nearest_material(part, origin, angles) -> float:
    """The shortest distance (m) from ``origin`` along horizontal rays at ``angles`` (rad) to
    the part's surface; 0 where the origin lies inside the part (the ray leaves it through
    the block's far wall, more than 1 mm away) or on its surface."""
    vertices, triangles = part.mesh()
    tri = vertices[np.asarray(triangles, dtype=np.int64)] - origin
    low, high = tri[:, :, 2].min(axis=1), tri[:, :, 2].max(axis=1)
    a, b, c = (tri[(low <= 0.0) & (high >= 0.0), i] for i in range(3))
    e1, e2 = b - a, c - a
    best = math.inf
    for angle in angles:
        d = np.array([math.cos(angle), math.sin(angle), 0.0])
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.einsum("ij,ij->i", -a, p) / det
            q = np.cross(-a, e1)
            v = (q @ d) / det
            t = np.einsum("ij,ij->i", e2, q) / det
            hit = (det != 0.0) & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t >= 0.0)
        first = float(t[hit].min()) if hit.any() else math.inf
        best = min(best, 0.0 if first > 1e-3 else first)
    return best


def _closest_distance(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distance (m) from each point (n, 3) to the nearest of triangles (m, 3, 3), exact
    (Ericson's closest point on a triangle), n x m at once."""
    p = points[:, None, :]
    a, b, c = tri[None, :, 0], tri[None, :, 1], tri[None, :, 2]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = vb / denom
        w = vc / denom
        closest = a + ab * v[..., None] + ac * w[..., None]
        # edges and vertices
        t_ab = d1 / (d1 - d3)
        e_ab = a + ab * t_ab[..., None]
        t_ac = d2 / (d2 - d6)
        e_ac = a + ac * t_ac[..., None]
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        e_bc = b + (c - b) * t_bc[..., None]
    regions = [
        ((d1 <= 0) & (d2 <= 0), np.broadcast_to(a, closest.shape)),
        ((d3 >= 0) & (d4 <= d3), np.broadcast_to(b, closest.shape)),
        ((d6 >= 0) & (d5 <= d6), np.broadcast_to(c, closest.shape)),
        ((vc <= 0) & (d1 >= 0) & (d3 <= 0), e_ab),
        ((vb <= 0) & (d2 >= 0) & (d6 <= 0), e_ac),
        ((va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0), e_bc),
    ]
    done = np.zeros(closest.shape[:2], dtype=bool)
    out = closest.copy()
    for mask, value in regions:
        pick = mask & ~done
        out[pick] = value[pick]
        done |= mask
    return np.sqrt(((out - p) ** 2).sum(-1)).min(axis=1)


def _farthest(points: np.ndarray, tri: np.ndarray) -> float:
    """The largest distance (m, at most `FARTHEST_M`) from ``points`` to the nearest of
    ``tri``, in blocks of nearby points."""
    if not len(points) or not len(tri):
        return 0.0
    low, high = tri.min(axis=1), tri.max(axis=1)
    # nearby points together: 5 um slabs across X, along Y in each
    order = np.lexsort((points[:, 2], points[:, 1], np.floor(points[:, 0] / 5e-6)))
    best = 0.0
    for group in np.array_split(order, max(1, len(order) // 64)):
        chunk = points[group]
        lo, hi = chunk.min(axis=0) - FARTHEST_M, chunk.max(axis=0) + FARTHEST_M
        near = np.flatnonzero(np.all((high >= lo) & (low <= hi), axis=1))
        if not len(near):
            best = FARTHEST_M
            continue
        d = np.full(len(chunk), np.inf)
        for start in range(0, len(near), 4096):
            d = np.minimum(d, _closest_distance(chunk, tri[near[start:start + 4096]]))
        best = max(best, float(min(d.max(), FARTHEST_M)))
    return best


def sliver(kept: Part, cut: Part) -> tuple[float, float]:
    """Volume (m^3) and largest thickness (m) of the material ``kept`` holds and ``cut`` has
    not: how far ``cut``'s surface there (its vertices and face centres in that region) lies
    past ``kept``'s. A fin that ``kept`` leaves standing (a sheet of some 0.1 nm between two
    of its sweeps, microns tall) is not counted: ``cut``'s surface at its foot lies on
    ``kept``'s beside it."""
    a = kept.manifold.as_original()
    b = cut.manifold.as_original()
    left = a - b
    volume = float(left.volume())
    vertices, triangles = kept.mesh()
    surface = vertices[np.asarray(triangles, dtype=np.int64)]
    thick = 0.0
    for piece in left.decompose():
        # a sheet thinner on average than SHEET_M is the booleans' round-off (two faces
        # that coincide), not a cut
        if 2.0 * piece.volume() <= SHEET_M * piece.surface_area():
            continue
        mesh = piece.to_mesh64()
        corners = np.asarray(mesh.vert_properties)[:, :3]
        faces = np.asarray(mesh.tri_verts, dtype=np.int64)
        ids = np.asarray(mesh.run_original_id)
        index = np.asarray(mesh.run_index, dtype=np.int64)
        run = np.repeat(np.arange(len(ids)), np.diff(index) // 3)
        own = faces[ids[run] == b.original_id()]
        points = np.concatenate([corners[np.unique(own)], corners[own].mean(axis=1)])
        thick = max(thick, _farthest(points, surface))
    return volume, thick
