"""Tools swung about a Y line, cut by the engine given their poses, and the distance from a
point to the cut's surface: shared by tests/test_cutting_tilted_*.py and
benchmarks/tilted_*.py. Not part of the package."""

from __future__ import annotations

import math

import numpy as np

from machinesim.cutting.engine import remove
from machinesim.workpiece import block


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
