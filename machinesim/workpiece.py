"""Stock and machined parts: immutable float64 manifold3d solids in the workpiece frame."""

from __future__ import annotations

from dataclasses import dataclass

import manifold3d
import numpy as np


@dataclass(frozen=True)
class Part:
    """A solid in its workpiece frame (metres), exact float64 mesh behind a manifold3d value.

    Attributes
    ----------
    manifold : manifold3d.Manifold
        The solid. Never mutated: every operation returns a new `Part`.
    """

    manifold: manifold3d.Manifold

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertices, shape (n, 3) float64 in m, and triangles, shape (m, 3) int64."""
        mesh = self.manifold.to_mesh64()
        vertices = np.ascontiguousarray(mesh.vert_properties[:, :3], dtype=np.float64)
        triangles = np.ascontiguousarray(mesh.tri_verts, dtype=np.int64)
        return vertices, triangles

    @property
    def volume(self) -> float:
        """Volume in m^3."""
        return float(self.manifold.volume())
