"""The volume a cut removes, integrated over the cut's own faces (divergence theorem).

`removed_volume` sums, over the faces a cut made and the parts of the stock's faces it took
away, the integral of (z - z0) n_z dA (`_face_moments`), so the result keeps the cut's own
float64 precision instead of the difference of two large volumes. Split out of
`machinesim.cutting.engine`, which cuts each tile and calls it (and still exports its names).
"""

from __future__ import annotations

import manifold3d
import numpy as np

#: A face's integral changes by a cut only when the change exceeds this fraction of the
#: magnitude of its terms: an untouched face split by tile walls sums to itself within
#: ~1e-15 (float64 summation over its pieces). A real cut below it on a face that is not
#: the top (e.g. grazing a block's bottom) moves the volume by less than this fraction of
#: that face's integral, and is dropped as round-off.
FACE_ROUND_REL = 1e-12
#: Key of a (run id, face id) pair, run * FACE_KEY + face: face ids stay below 2^31.
FACE_KEY = 1 << 31


def _face_moments(solid: manifold3d.Manifold, z0: float):
    """Each triangle's integral of (z - z0) n_z dA, with its origin (run id, face id).

    By the divergence theorem (field (0, 0, z - z0), divergence 1) these sum to the solid's
    volume. For a flat triangle the integral is its signed area projected on XY times its
    centroid's height above z0; both use coordinate differences, so a small feature far from
    the origin keeps its own relative precision.
    """
    mesh = solid.to_mesh64()
    vertices = np.asarray(mesh.vert_properties)[:, :3]
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64)
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    area = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                  - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1]))
    moment = area * ((a[:, 2] + b[:, 2] + c[:, 2]) / 3.0 - z0)
    runs = np.asarray(mesh.run_original_id, dtype=np.int64)
    run_index = np.asarray(mesh.run_index, dtype=np.int64)
    run = np.repeat(runs, np.diff(run_index[:len(runs) + 1]) // 3)
    face = np.asarray(mesh.face_id, dtype=np.int64)
    if len(face) != len(triangles):
        face = np.arange(len(triangles), dtype=np.int64)
    return run, face, moment


def removed_volume(before: manifold3d.Manifold, after: manifold3d.Manifold, cut_id: int,
                   z0: float) -> float:
    """Volume of ``before`` not in ``after`` (m^3), integrated over the region removed.

    The region's boundary is the cut surface (faces of ``after`` that came from the sweeps,
    ``cut_id``) and the parts of ``before``'s faces that the sweeps took away. With the field
    (0, 0, z - z0), z0 the stock top, the top face and every vertical face contribute
    nothing; each other face of ``before`` contributes the difference of its integral before
    and after, kept only where it exceeds `FACE_ROUND_REL` of the face's own terms (an
    untouched face, split by tile walls, agrees with itself to round-off). So the removed
    volume is a sum over the cut, free of the cancellation of two whole volumes: a 10 nm
    groove on a 100 mm block comes out to its own float64 precision.
    """
    run_b, face_b, moment_b = _face_moments(before, z0)
    run_a, face_a, moment_a = _face_moments(after, z0)
    cut = run_a == cut_id
    removed = -float(np.sum(moment_a[cut]))
    keys = np.concatenate([run_b * FACE_KEY + face_b, run_a[~cut] * FACE_KEY + face_a[~cut]])
    moments = np.concatenate([moment_b, -moment_a[~cut]])
    _, group = np.unique(keys, return_inverse=True)
    change = np.bincount(group, weights=moments)
    size = np.bincount(group, weights=np.abs(moments))
    return removed + float(np.sum(change[np.abs(change) > FACE_ROUND_REL * size]))
