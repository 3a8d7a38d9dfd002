"""How much of the stock's bottom face a cut took away: a tool that went through the
bottom of the stock went below it, into what holds it (a table, chuck or fixture, which no
model here has), as a wrong tool length (`G43 H` of another tool) takes it on a machine.

A pocket 3 mm deep in a 2 mm block leaves a ring, one piece, so the pieces check
(`machinesim cut`'s "separate pieces") says nothing; its bottom face has lost the pocket's
area, which this reads from the meshes alone."""

from __future__ import annotations

import numpy as np

#: A face lies in the bottom plane when its vertices are within this share of the part's
#: size of the stock's lowest z (1e-9: 10 pm on a 10 mm block; the boolean engine's new
#: vertices on that plane are off it by round-off, ~1e-19 m) and its normal within 1e-6
#: rad of -z.
PLANE_SHARE = 1e-9
NORMAL_TOLERANCE = 1e-6
#: The least area (m^2) that counts as gone: 1 um^2, a tenth of the 10 um hole of a micro
#: drill, well above the round-off of the faces' areas (~1e-22 m^2 on a 10 mm block).
LEAST_AREA_M2 = 1e-12


def bottom_area(vertices: np.ndarray, triangles: np.ndarray, z: float, size: float) -> float:
    """The area (m^2) of the faces that face down (-z) and lie in the plane ``z``.

    The faces in the plane are picked by their vertices' z first, a byte per vertex and per
    face, and only they are measured: the whole mesh's corners and normals (some 200 bytes
    a face) had held 5.5 times the mesh (400 MB beside a 72 MB mesh of 2 million faces; a
    cut's part may have 40 million) at the end of a cut that fitted."""
    level = np.abs(vertices[:, 2] - z) <= PLANE_SHARE * size  # (n,)
    on_plane = level[triangles[:, 0]]
    on_plane &= level[triangles[:, 1]]
    on_plane &= level[triangles[:, 2]]
    corners = vertices[triangles[on_plane]]                    # (k, 3, 3)
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    doubled = np.linalg.norm(normals, axis=1)
    down = normals[:, 2] <= -(1.0 - NORMAL_TOLERANCE) * doubled
    return float(0.5 * doubled[down].sum())


def bottom_lost(part, material) -> float:
    """The area (m^2) of ``material``'s bottom face (the faces down at its lowest z) that
    ``part``, cut from it, no longer has; 0 when less than `LEAST_AREA_M2` is gone."""
    bounds = material.bounds
    z = float(bounds[0, 2])
    size = float(np.abs(bounds).max()) or 1.0
    lost = bottom_area(*material.mesh(), z, size) - bottom_area(*part.mesh(), z, size)
    return lost if lost >= LEAST_AREA_M2 else 0.0


__all__ = ["LEAST_AREA_M2", "bottom_area", "bottom_lost"]
