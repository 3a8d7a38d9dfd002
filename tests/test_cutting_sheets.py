"""Sheets thinner than a picometre: found only where nothing lies on either side, cut away."""

import manifold3d
import numpy as np
import pytest

from machinesim.cutting.sheets import find_sheets, remove_sheets
from machinesim.metrology import Microscope
from machinesim.tolerances import SHEET_M
from machinesim.workpiece import Part

MM = 1e-3


def box(low, high):
    """A closed outward mesh (vertices, triangles) of the box low..high (m)."""
    mesh = manifold3d.Manifold.cube((1.0, 1.0, 1.0)).to_mesh64()
    unit = np.asarray(mesh.vert_properties)[:, :3]
    low, high = np.asarray(low, float), np.asarray(high, float)
    return low + unit * (high - low), np.asarray(mesh.tri_verts, dtype=np.int64)


def joined(*meshes):
    vertices, triangles, count = [], [], 0
    for v, t in meshes:
        vertices.append(v)
        triangles.append(t + count)
        count += len(v)
    return np.vstack(vertices), np.vstack(triangles)


def turned(mesh, degrees=(13.0, 27.0, 41.0)):
    """The mesh turned about x, y, z in turn (a sheet off the axes)."""
    from scipy.spatial.transform import Rotation

    v, t = mesh
    return Rotation.from_euler("xyz", degrees, degrees=True).apply(v), t


@pytest.mark.parametrize("thickness", [2.6e-13, 0.9e-12])
@pytest.mark.parametrize("turn", [False, True])
def test_a_free_plate_thinner_than_a_picometre_is_a_sheet_and_a_thicker_one_is_not(
        thickness, turn):
    plate = box((0.0, 0.0, 1 * MM), (1 * MM, 2 * MM, 1 * MM + thickness))
    mesh = turned(plate) if turn else plate
    pairs, gaps = find_sheets(*mesh)
    assert gaps == pytest.approx(thickness, abs=1e-16 * (1 + 1000 * turn))
    # the pairs cover the plate: their top triangles are its whole 1 x 2 mm
    v, t = mesh
    top = v[t[np.unique(pairs[:, 0])]]
    area = 0.5 * np.linalg.norm(np.cross(top[:, 1] - top[:, 0], top[:, 2] - top[:, 0]), axis=1)
    assert area.sum() == pytest.approx(2 * MM * MM, rel=1e-12)
    thick = box((0.0, 0.0, 1 * MM), (1 * MM, 2 * MM, 1 * MM + 3 * SHEET_M))
    assert len(find_sheets(*thick)[0]) == 0


def test_a_skin_over_a_crack_and_a_crack_are_not_sheets():
    # a block with, 0.1 pm above its top, a plate 0.1 pm thick: the plate's faces are 0.1
    # pm apart, but under it the crack and the block, as on a face cut twice: a height map
    # reads the same surface, so it is no sheet to remove
    block = box((0.0, 0.0, 0.0), (1 * MM, 1 * MM, 1 * MM))
    skin = box((0.0, 0.0, 1 * MM + 1e-13), (1 * MM, 1 * MM, 1 * MM + 2e-13))
    assert len(find_sheets(*joined(block, skin))[0]) == 0
    lid = box((0.0, 0.0, 1 * MM + 1e-13), (1 * MM, 1 * MM, 2 * MM))
    assert len(find_sheets(*joined(block, lid))[0]) == 0


def test_a_sheet_standing_on_a_groove_bottom_is_removed_and_nothing_else_moves():
    stock = manifold3d.Manifold.cube((4 * MM, 4 * MM, 1 * MM)).translate((-2 * MM, -2 * MM,
                                                                          -1 * MM))
    gap = 2.6e-13
    first = manifold3d.Manifold.cube((1 * MM, 2 * MM, 0.5 * MM)).translate(
        (-1 * MM, -1 * MM, -0.01 * MM))
    second = manifold3d.Manifold.cube((1 * MM, 2 * MM, 0.5 * MM)).translate(
        (gap, -1 * MM, -0.01 * MM))
    part = stock - first - second
    trimmed, report = remove_sheets(part)
    assert report.count >= 1 and report.thickness_max == pytest.approx(gap, abs=1e-16)
    # what went is the sheet, 10 um x 2 mm x gap, and pm notches of no volume to speak of
    assert part.volume() - trimmed.volume() == pytest.approx(10e-6 * 2 * MM * gap, rel=1e-3,
                                                              abs=0.0)
    again, second_report = remove_sheets(trimmed)
    assert second_report.count == 0 and again is trimmed
    # a profile along y = 0 across the sheet's place, at 0.01 pm, reads the bottom all along
    along = Microscope(noise=False).profile(Part(trimmed), (-2e-12, 0.0), (3e-12, 0.0),
                                            spacing=1e-14)
    assert len(along.z) > 400 and np.nanmax(along.z) <= -0.01 * MM + 2 * SHEET_M
    before = Microscope(noise=False).profile(Part(part), (-2e-12, 0.0), (3e-12, 0.0),
                                             spacing=1e-14)
    assert np.nanmax(before.z) == 0.0  # the sheet's top, at the stock's top


def test_an_ordinary_solid_has_no_sheets_and_comes_back_as_it_is():
    solid = manifold3d.Manifold.cube((1 * MM, 1 * MM, 1 * MM)) - manifold3d.Manifold.sphere(
        0.3 * MM, 64).translate((0.5 * MM, 0.5 * MM, 1 * MM))
    same, report = remove_sheets(solid)
    assert same is solid and report.count == 0 and report.thickness_max == 0.0


def test_forty_sheets_go_in_twenty_patches_and_more_patches_than_the_limit_are_left(
        monkeypatch):
    # 20 free plates 0.26 pm thick, two overlapping pairs each: 40 sheets, one patch of
    # faces per plate; every plate goes (its volume, 20 x 1 mm^2 x 0.26 pm), and with a
    # limit of 19 patches the part comes back as it is and the report says so
    from machinesim.cutting import sheets

    plates = [box((3 * MM * k, 0.0, 0.0), (3 * MM * k + 1 * MM, 1 * MM, 2.6e-13))
              for k in range(20)]
    v, t = joined(*plates)
    solid = manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(v), tri_verts=np.ascontiguousarray(t, np.uint64)))
    assert len(find_sheets(v, t)[0]) == 40
    trimmed, report = remove_sheets(solid)
    assert report.count == 40 and report.removed and report.left == 0
    assert trimmed.is_empty() or trimmed.volume() == pytest.approx(0.0, abs=1e-30)
    assert report.volume == pytest.approx(20 * MM * MM * 2.6e-13, rel=1e-6, abs=0.0)
    monkeypatch.setattr(sheets, "MOST_REMOVED", 19)
    same, report = remove_sheets(solid)
    assert same is solid and report.count == report.left == 40 and not report.removed
    assert report.area == pytest.approx(20 * MM * MM, rel=1e-12)


def test_a_program_cut_looks_for_sheets_once_on_the_finished_part_and_reports_them(
        monkeypatch):
    import machinesim.cutting.program as program_module
    from machinesim.cutting import cut, sheets
    from machinesim.nc import ProgramBuilder

    searched, engine_calls = [], []
    real_remove = program_module.remove

    def remove(*args, **kwargs):
        engine_calls.append(kwargs.get("sheets", True))
        return real_remove(*args, **kwargs)

    def trim(part):
        searched.append(part)
        found = sheets.SheetReport(40, 2e-13, 1e-8, 0.0, removed=False)
        return part, found, "40 sheets left (a note)"

    monkeypatch.setattr(program_module, "remove", remove)
    monkeypatch.setattr(program_module, "trim_sheets", trim)
    # a swing of the planer's arm: a rotary move, cut by the boolean engine
    program = (ProgramBuilder(1).rapid(X=0.5 * MM, Y=0.0, Z=0.1 * MM, A=-0.005)
               .rapid(Z=-5e-6).linear(X=4.5 * MM, A=0.005, feed_mm_per_min=100.0)
               .rapid(Z=0.1 * MM).build())
    part, report = cut(program, "planer_4axis", tool="v:90", stock="block:5x3x1@0,-1.5,0")
    assert engine_calls and not any(engine_calls)  # the engine leaves them to the end
    assert len(searched) == 1 and searched[0] is part
    assert report.thin_sheets == 40 and "40 sheets left (a note)" in report.notes
    assert report.to_dict()["thin_sheets_count"] == 40


@pytest.mark.parametrize(("fold", "patches"), [(0.3, 2), (1e-8, 1)])
def test_faces_join_one_patch_only_on_one_plane(fold, patches):
    # a strip of four triangles folded along x = 1 mm by ``fold`` rad: two planes, two
    # patches (each prism is flat); folded by less than PATCH_NORMAL_TOL, one
    from machinesim.cutting.sheets import PATCH_NORMAL_TOL, _patches

    assert fold > 10 * PATCH_NORMAL_TOL or fold < PATCH_NORMAL_TOL / 10
    x2 = 1 * MM + 1 * MM * np.cos(fold)
    z2 = 1 * MM * np.sin(fold)
    v = np.array([[0, 0, 0], [1 * MM, 0, 0], [1 * MM, 1 * MM, 0], [0, 1 * MM, 0],
                  [x2, 0, z2], [x2, 1 * MM, z2]], dtype=float)
    t = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    found = _patches(v, t, np.arange(4))
    assert len(found) == patches
    assert sorted(np.concatenate(found).tolist()) == [0, 1, 2, 3]


def test_faces_paired_in_chunks_find_the_same_sheets(monkeypatch):
    # the +u faces are paired with the -u faces a chunk at a time on a large part (memory);
    # with chunks of 7 faces the 20 plates' 40 sheets are the same pairs and gaps
    from machinesim.cutting import sheets

    plates = [box((3 * MM * k, 0.0, 0.0), (3 * MM * k + 1 * MM, 1 * MM, 2.6e-13))
              for k in range(20)]
    v, t = joined(*plates)
    whole = find_sheets(v, t)
    monkeypatch.setattr(sheets, "FACING_CHUNK", 7)
    pieces = find_sheets(v, t)
    assert len(whole[0]) == 40
    order_whole, order_pieces = np.lexsort(whole[0].T), np.lexsort(pieces[0].T)
    np.testing.assert_array_equal(whole[0][order_whole], pieces[0][order_pieces])
    np.testing.assert_array_equal(whole[1][order_whole], pieces[1][order_pieces])


@pytest.mark.parametrize("height, wide", [(2e-12, True), (0.5e-12, False)])
def test_a_face_no_wider_than_a_sheet_across_an_edge_is_left_out_of_the_pairing(height,
                                                                                  wide):
    """A right triangle 1 mm long and ``height`` high: its smallest altitude is ``height``
    (twice its area over its longest edge, by hand), against SHEET_M = 1 pm."""
    from machinesim.cutting import sheets

    corners = np.array([[[0.0, 0.0, 0.0], [1 * MM, 0.0, 0.0], [0.0, height, 0.0]]])
    doubled_area = np.array([1 * MM * height])
    assert sheets._wide(corners, doubled_area, SHEET_M).tolist() == [wide]


def test_leaving_slivers_out_finds_the_same_sheets(monkeypatch):
    # twenty plates 0.26 pm thick, each top split by a sliver 1e-14 m wide: the same pairs
    # and gaps as when every face is paired
    from machinesim.cutting import sheets

    plates = []
    for k in range(20):
        v, t = box((3 * MM * k, 0.0, 0.0), (3 * MM * k + 1 * MM, 1 * MM, 2.6e-13))
        sliver = np.array([[3 * MM * k, 0.5 * MM, 2.6e-13], [3 * MM * k + 1 * MM, 0.5 * MM,
                                                              2.6e-13],
                           [3 * MM * k, 0.5 * MM + 1e-14, 2.6e-13]])
        plates.append((np.vstack([v, sliver]), np.vstack([t, [[len(v), len(v) + 2,
                                                                len(v) + 1]]])))
    v, t = joined(*plates)
    left_out = find_sheets(v, t)
    monkeypatch.setattr(sheets, "_wide", lambda corners, area, thickness:
                        np.ones(len(corners), dtype=bool))
    every = find_sheets(v, t)
    assert len(left_out[0]) == 40
    order_a, order_b = np.lexsort(left_out[0].T), np.lexsort(every[0].T)
    np.testing.assert_array_equal(left_out[0][order_a], every[0][order_b])
    np.testing.assert_array_equal(left_out[1][order_a], every[1][order_b])


#: A flat tetrahedron a V tool led in a spiral under servo lag left in its groove, beside the
#: part (grooving_4axis, docs/cli.md's --servo example loops): its four vertices (m) lie in
#: one plane to 1e-18 m, its volume -1.3e-29 m^3.
FLAT_TETRAHEDRON = (np.array([
    [2.9999275531231371e-03, 9.3607091900975940e-06, 0.0],
    [2.9999283746517427e-03, 2.7113786632219548e-07, -1.9999999999964491e-05],
    [2.9999283991575751e-03, 0.0, -1.9728862132534858e-05],
    [2.9999283991575751e-03, 7.4573569651532708e-20, 0.0]]),
    np.array([[1, 2, 0], [1, 3, 2], [1, 0, 3], [2, 3, 0]]))


def _with_flat_tetrahedron(solid):
    """``solid`` and `FLAT_TETRAHEDRON` as one manifold, the tetrahedron a run of its own
    (original id 99, face ids 100-103), the solid's runs and face ids kept."""
    mesh = solid.to_mesh64()
    runs = np.asarray(mesh.run_index, dtype=np.uint64)
    return manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=np.vstack([mesh.vert_properties, FLAT_TETRAHEDRON[0]]),
        tri_verts=np.vstack([mesh.tri_verts, FLAT_TETRAHEDRON[1] + len(mesh.vert_properties)]
                            ).astype(np.uint64),
        run_index=np.r_[runs, runs[-1] + 12].astype(np.uint64),
        run_original_id=np.r_[mesh.run_original_id, 99].astype(np.uint32),
        run_transform=np.concatenate([mesh.run_transform, mesh.run_transform[:1]]),
        face_id=np.r_[mesh.face_id, 100, 101, 102, 103].astype(np.uint64)))


def test_a_flat_piece_beside_the_part_is_a_sheet_removed_whole():
    """The flat tetrahedron's faces face each other within round-off, so the pairing reads
    none as a sheet; it stood beside the part as a 20 um wall, and `machinesim cut` warned
    of a part in separate pieces. Now it goes whole; the part is left to the bit, each face
    with its origin."""
    from machinesim.cutting.flat_pieces import flat_pieces

    block = (manifold3d.Manifold.cube((1 * MM, 1 * MM, 1 * MM))
             - manifold3d.Manifold.cylinder(2 * MM, 0.2 * MM, 0.2 * MM, 32)).translate(
        (1 * MM, 1 * MM, -1 * MM))
    part = _with_flat_tetrahedron(block)
    assert 99 in np.asarray(part.to_mesh64().run_original_id).tolist()
    assert len(part.decompose()) == 2
    vertices, triangles = _arrays_of(part)
    assert len(find_sheets(vertices, triangles)[0]) == 0  # not found as pairs of faces
    trimmed, report = remove_sheets(part)
    assert len(trimmed.decompose()) == 1 and trimmed.volume() == block.volume()
    kept, mesh = trimmed.to_mesh64(), block.to_mesh64()
    assert sorted(map(tuple, np.asarray(kept.vert_properties))) == sorted(
        map(tuple, np.asarray(mesh.vert_properties)))
    assert sorted(np.asarray(kept.face_id).tolist()) == sorted(np.asarray(mesh.face_id).tolist())
    assert _runs_with_faces(kept) == _runs_with_faces(mesh)
    assert report.pieces == 1 and report.count == 1 and report.removed
    assert abs(report.volume) < 1e-28 and report.thickness_max < SHEET_M
    # a plate 3 pm thick beside the block is material: kept, as a piece of the part
    plate = manifold3d.Manifold.cube((1 * MM, 3e-12, 1 * MM)).translate((3 * MM, 0.0, -1 * MM))
    both = block + plate
    assert len(both.decompose()) == 2 and flat_pieces(both) == (both, [])
    # a void's shell is a piece of negative volume, which `Manifold.compose` drops (it would
    # fill the void): a part with one keeps its flat pieces
    void = block - manifold3d.Manifold.cube((0.2 * MM,) * 3).translate((1.5 * MM, 1.5 * MM,
                                                                        -0.6 * MM))
    assert void.volume() < block.volume() and len(void.decompose()) == 2
    with_void = _with_flat_tetrahedron(void)
    assert flat_pieces(with_void) == (with_void, [])
    # a part that is one flat piece is left as it is
    alone = manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=FLAT_TETRAHEDRON[0], tri_verts=FLAT_TETRAHEDRON[1].astype(np.uint64)))
    assert flat_pieces(alone) == (alone, [])


def _arrays_of(solid):
    mesh = solid.to_mesh64()
    return np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts, dtype=np.int64)


def _runs_with_faces(mesh) -> list[int]:
    """The original ids of a mesh's runs that hold a triangle (compose keeps empty ones)."""
    counts = np.diff(np.asarray(mesh.run_index, dtype=np.int64))
    return sorted(np.asarray(mesh.run_original_id)[:len(counts)][counts > 0].tolist())
