"""A cut part written as PLY and read back is the same solid: tiles stitched without cracks.

The boolean engine cuts a large part in tiles and joins them along their walls
(`machinesim.cutting.stitch`). A pocket cut in levels leaves each tile's floor with vertices
from its own history where old edges met the wall, so the two sides of a wall met in
different vertices (T-junctions), the merge did not close and the tiles were joined by a
boolean union instead. Their walls lie off their planes by round-off (1e-19 .. 1e-18 m), and
that union kept both walls inside the part: a crack of no width. manifold3d, importing such
a part's own mesh again (from its PLY), may fold the crack and change the volume (a round
pocket in levels in four tiles: 3.8 mm^3 of 265 mm^3). The pocket here is small enough to
cut in a second; its crack (16 triangles) does not happen to move the re-imported volume,
so the tests read the crack and the stitch directly.
"""

import math

import manifold3d
import numpy as np
import pytest

from machinesim.cutting import remove
from machinesim.cutting.stitch import snapped_union, split_t_junctions
from machinesim.tools import FlatEndMill
from machinesim.workpiece import block

#: Volumes of the same exact float64 mesh agree to summation round-off (~1e-15 relative).
VOLUME_REL = 1e-12


def _pose(position):
    matrix = np.eye(4)
    matrix[:3, 3] = position
    return matrix


def _round_pocket():
    """Rings of radius 0.6 and 1.2 mm at 0.2 and 0.4 mm deep, flat:0.5, in four tiles."""
    paths = []
    angle = np.linspace(0.0, 2.0 * math.pi, 25)
    for depth in (0.2e-3, 0.4e-3):
        paths.append(np.array([_pose((2e-3 + r * math.cos(a), 2e-3 + r * math.sin(a), -depth))
                               for r in (0.6e-3, 1.2e-3) for a in angle]))
    return paths


@pytest.fixture(scope="module")
def pocket():
    """The pocket cut with the tiles and the stitch's answer recorded."""
    import machinesim.cutting.engine as engine

    calls = []
    original = engine.stitch

    def record(pieces, boxes, outer, scale):
        calls.append((pieces, boxes, outer, scale, original(pieces, boxes, outer, scale)))
        return calls[-1][-1]

    engine.stitch = record
    try:
        part, report = remove(block(4e-3, 4e-3, 1e-3),
                              FlatEndMill(0.5e-3, chord_tol=1e-6, height=5e-3),
                              _round_pocket(), method="boolean", sweeps_per_tile=16,
                              sheets=False)
    finally:
        engine.stitch = original
    return part, report, calls


def _wall_triangles(vertices, triangles, boxes, outer) -> int:
    """Triangles lying in an interior tile wall's plane (a crack's faces)."""
    corners = vertices[triangles]
    count = 0
    for axis in (0, 1):
        walls = {box[2 * axis + 1] for box in boxes} - {outer[2 * axis + 1]}
        for wall in walls:
            count += int(np.all(corners[:, :, axis] == wall, axis=1).sum())
    return count


def _read_ply(data: bytes):
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii")
    n_vertex = int(header.split("element vertex ")[1].split()[0])
    n_face = int(header.split("element face ")[1].split()[0])
    vertices = np.frombuffer(data, "<f8", 3 * n_vertex, end).reshape(-1, 3)
    faces = np.frombuffer(data, [("n", "u1"), ("i", "<i4", 3)], n_face, end + 24 * n_vertex)
    assert np.all(faces["n"] == 3) and len(data) == end + 24 * n_vertex + 13 * n_face
    return vertices, faces["i"].astype(np.int64)


def test_tiles_whose_walls_meet_in_t_junctions_are_stitched(pocket):
    part, report, calls = pocket
    assert report.n_cells == 4 and len(calls) == 1
    pieces, boxes, outer, _, joined = calls[0]
    assert joined is not None  # was None: T-junctions on the floor line of a wall
    assert joined.volume() == pytest.approx(sum(p.volume() for p in pieces), rel=VOLUME_REL)
    vertices, triangles = part.mesh()
    assert _wall_triangles(vertices, triangles, boxes, outer) == 0  # was 16: a crack


def test_a_tiled_part_reads_back_from_its_ply_as_the_same_solid(pocket, tmp_path):
    part, report, _ = pocket
    path = tmp_path / "part.ply"
    part.export_ply(path)
    vertices, triangles = _read_ply(path.read_bytes())
    mine_v, mine_t = part.mesh()
    np.testing.assert_array_equal(vertices, mine_v)  # float64, bit for bit, same order
    np.testing.assert_array_equal(triangles, mine_t)
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, uses = np.unique(edges, axis=0, return_counts=True)
    assert np.all(uses == 2)  # no open, no non-manifold edge
    again = manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=np.array(vertices), tri_verts=triangles.astype(np.uint64)))
    assert again.status() == manifold3d.Error.NoError
    assert again.volume() == pytest.approx(part.volume, rel=VOLUME_REL)
    # and it is the stock less what the engine integrated over the cut faces
    assert part.volume == pytest.approx(4e-3 * 4e-3 * 1e-3 - report.removed_volume,
                                        rel=VOLUME_REL)


def test_the_fallback_union_snaps_the_walls_and_leaves_no_crack(pocket):
    _, _, calls = pocket
    pieces, boxes, outer, scale, _ = calls[0]
    joined = snapped_union(pieces, boxes, outer, scale)
    mesh = joined.to_mesh64()
    vertices = np.asarray(mesh.vert_properties[:, :3])
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64)
    assert _wall_triangles(vertices, triangles, boxes, outer) == 0  # plain union: 16
    assert joined.volume() == pytest.approx(sum(p.volume() for p in pieces), rel=VOLUME_REL)
    again = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=np.array(vertices),
                                                  tri_verts=triangles.astype(np.uint64)))
    assert again.volume() == pytest.approx(joined.volume(), rel=VOLUME_REL)


def test_a_t_junction_is_split_into_a_closed_mesh():
    # A unit cube whose top face carries a vertex (0.5, 0, 1) on its front edge that the front
    # face does not: the front face's top edge is open, as a wall seen from one side only.
    corners = np.array([[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)])
    vertices = np.vstack([corners, [[0.5, 0.0, 1.0]]])
    triangles = np.array([
        [0, 2, 1], [1, 2, 3],                      # bottom
        [4, 8, 6], [8, 5, 6], [5, 7, 6],           # top, its edge 4-5 split at vertex 8
        [0, 1, 4], [1, 5, 4],                      # front (y = 0): edge 5-4 passes vertex 8
        [2, 6, 3], [3, 6, 7],                      # back
        [0, 4, 2], [2, 4, 6],                      # left
        [1, 3, 5], [3, 7, 5],                      # right
    ])
    assert manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=vertices.copy(), tri_verts=triangles.astype(np.uint64))).status() \
        == manifold3d.Error.NotManifold
    split = split_t_junctions(vertices, triangles, 1e-12)
    assert len(split) == len(triangles) + 1
    solid = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=vertices.copy(),
                                                  tri_verts=split.astype(np.uint64)))
    assert solid.status() == manifold3d.Error.NoError
    assert solid.volume() == pytest.approx(1.0, rel=VOLUME_REL)
