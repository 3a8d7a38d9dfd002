"""The viewer's meshes without a browser: `read_ply` gives back the exact float64 mesh,
reads the forms other tools write and refuses what it cannot read, naming the file and
what it found; `decimate` meets its budget and keeps the shape."""

from __future__ import annotations

import manifold3d
import numpy as np
import pytest
from viewer_helpers import BUDGET, ply_bytes

from machinesim.exceptions import InputError
from machinesim.viewer import decimate, part_scene, read_ply
from machinesim.viewer.meshes import ply_single_precision, triangle_normals
from machinesim.workpiece import mesh_volume, stock_from_spec

MM = 1e-3


def test_read_ply_gives_back_the_exact_float64_mesh(tmp_path):
    part = stock_from_spec("cylinder:1.234567x0.5@0.1,0.2,0.3")
    part.export_ply(tmp_path / "part.ply")
    vertices, triangles = read_ply(tmp_path / "part.ply")
    expected_v, expected_t = part.mesh()
    assert vertices.dtype == np.float64
    assert np.array_equal(vertices, expected_v)  # bit for bit
    assert np.array_equal(triangles, expected_t)


def test_read_ply_reads_the_forms_other_tools_write(tmp_path):
    # ASCII, big-endian, a CRLF header and faces with a colour and flags were each refused
    # ("expected 'format binary_little_endian 1.0'", "expected faces with one list property")
    part = stock_from_spec("cylinder:1.234567x0.5@0.1,0.2,0.3")
    expected_v, expected_t = part.mesh()
    head = (f"element vertex {len(expected_v)}\nproperty double x\nproperty double y\n"
            f"property double z\nelement face {len(expected_t)}\n")
    text = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in expected_v.tolist())
    text += "".join(f"3 {a} {b} {c}\n" for a, b, c in expected_t.tolist())
    (tmp_path / "ascii.ply").write_text(
        "ply\nformat ascii 1.0\ncomment by hand\n" + head
        + "property list uchar int vertex_indices\nend_header\n" + text)
    faces = np.zeros(len(expected_t), dtype=[("flags", ">i4"), ("n", "u1"), ("i", ">i4", 3),
                                             ("rgb", "u1", 3)])
    faces["flags"], faces["n"], faces["i"], faces["rgb"] = 7, 3, expected_t, (200, 10, 10)
    (tmp_path / "big.ply").write_bytes(
        ("ply\r\nformat binary_big_endian 1.0\r\n" + head.replace("\n", "\r\n")
         + "property int flags\r\nproperty list uchar int vertex_indices\r\n"
         "property uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\n"
         "end_header\r\n").encode() + expected_v.astype(">f8").tobytes() + faces.tobytes())
    for name in ("ascii.ply", "big.ply"):
        vertices, triangles = read_ply(tmp_path / name)
        assert np.array_equal(vertices, expected_v), name  # bit for bit
        assert np.array_equal(triangles, expected_t), name
    # trimesh's ASCII export (8 decimals of metres, from float32): within its 1e-8 m
    trimesh = pytest.importorskip("trimesh")
    (tmp_path / "trimesh.ply").write_bytes(trimesh.exchange.ply.export_ply(
        trimesh.Trimesh(expected_v, expected_t, process=False), encoding="ascii"))
    vertices, triangles = read_ply(tmp_path / "trimesh.ply")
    assert np.abs(vertices - expected_v).max() < 1e-8
    assert np.array_equal(triangles, expected_t)
    assert ply_single_precision(tmp_path / "trimesh.ply")
    assert not ply_single_precision(tmp_path / "big.ply")
    # its text, not float32's 0.23 nm at 1.2 mm, is what rounded it (5 nm)
    assert part_scene(tmp_path / "trimesh.ply", max_triangles=BUDGET).warnings == [
        "the part (trimesh.ply) stores its vertices as text: each as precise as it was printed "
        "(eight decimals of a metre round by up to 5 nm), so its heights are exact for the "
        "mesh as printed only; machinesim cut --out part.ply writes float64"]
    assert part_scene(tmp_path / "big.ply", max_triangles=BUDGET).warnings == []


@pytest.mark.parametrize("path", [None, b"part.ply", 5])
def test_read_ply_refuses_what_is_no_file_name_as_load_result_does(path):
    # it gave the path to Path(): 'TypeError: expected str, bytes or os.PathLike object, not
    # NoneType', where load_result and the writers refuse it by _io.check_path
    with pytest.raises(InputError) as info:
        read_ply(path)
    assert info.value.key == "path"
    assert str(info.value) == ("key 'path': reading the PLY part: expected a file name (str or "
                               f"pathlib.Path), got {type(path).__name__}")


def test_read_ply_refuses_what_it_cannot_read(tmp_path):
    ascii_ply = tmp_path / "ascii.ply"
    ascii_ply.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                         "property double y\nproperty double z\nelement face 2\n"
                         "property list uchar int vertex_indices\nend_header\n"
                         "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n4 0 1 2 0\n")
    with pytest.raises(InputError, match="ascii.ply: face 1 has 4 vertices: only triangle"):
        read_ply(ascii_ply)
    ascii_ply.write_text(ascii_ply.read_text().replace("4 0 1 2 0\n", "3 0 1\n"))
    with pytest.raises(InputError, match="ends after 16 numbers, where its 2 'face' elements "
                                         "need 8 from number 9: truncated"):
        read_ply(ascii_ply)
    ascii_ply.write_text(ascii_ply.read_text().replace("0 1 0\n", "0 one 0\n"))
    with pytest.raises(InputError, match="'vertex' elements hold a word that is not a number"):
        read_ply(ascii_ply)
    ascii_ply.write_text("ply\nformat ascii 1.0\nelement vertex 1\n"
                         "property list uchar double xyz\nend_header\n3 0 0 0\n")
    with pytest.raises(InputError, match="element 'vertex' has list properties; only 'face'"):
        read_ply(ascii_ply)
    other = tmp_path / "other.ply"
    other.write_text("ply\nformat binary_middle_endian 1.0\nend_header\n")
    with pytest.raises(InputError, match="'format binary_middle_endian 1.0': expected"):
        read_ply(other)
    quad = tmp_path / "quad.ply"
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\n"
              b"property double y\nproperty double z\nelement face 1\n"
              b"property list uchar int vertex_indices\nend_header\n")
    body = np.zeros((4, 3)).tobytes() + bytes([4]) + np.arange(4, dtype="<i4").tobytes()
    quad.write_bytes(header + body)
    with pytest.raises(InputError, match="only triangle faces"):
        read_ply(quad)
    with pytest.raises(InputError, match="cannot read"):
        read_ply(tmp_path / "missing.ply")


def test_read_ply_says_an_empty_file_or_a_folder_is_one(tmp_path):
    # both were named for what they lack ('not a PLY file: expected 'ply' and 'end_header'
    # lines'; 'cannot read the PLY file (Is a directory)', a folder named *.ply in a report
    # folder)
    for data, size in ((b"", "0 bytes"), (b"\n \n", "3 bytes, all white space")):
        (tmp_path / "empty.ply").write_bytes(data)
        with pytest.raises(InputError) as caught:
            read_ply(tmp_path / "empty.ply")
        assert str(caught.value) == (f"{tmp_path / 'empty.ply'}: the file is empty ({size}); "
                                     "expected a PLY part (a 'ply' line, its header and its "
                                     "elements)")
    (tmp_path / "folder.ply").mkdir()
    with pytest.raises(InputError) as caught:
        read_ply(tmp_path / "folder.ply")
    assert str(caught.value) == f"{tmp_path / 'folder.ply'}: is a folder; expected a PLY part file"


def test_read_ply_refuses_a_pipe_or_a_device_named_as_a_part(tmp_path):
    # a report folder's *.ply that is a named pipe blocked `machinesim view DIR` for ever
    # (its read waits for a writer), one linking to /dev/zero read until memory ran out;
    # /dev/null read as an empty file
    import os
    import threading

    (tmp_path / "null.ply").symlink_to("/dev/null")
    with pytest.raises(InputError, match=r"links to /dev/null, a character device, .*"
                                         r"expected a PLY part file"):
        read_ply(tmp_path / "null.ply")
    os.mkfifo(tmp_path / "pipe.ply")
    refused = []

    def read():
        try:
            read_ply(tmp_path / "pipe.ply")
        except InputError as error:
            refused.append(str(error))

    reader = threading.Thread(target=read, daemon=True)  # on the old code: blocked for ever
    reader.start()
    reader.join(timeout=20.0)
    assert not reader.is_alive() and len(refused) == 1
    assert "is a named pipe (FIFO), not a regular file; expected a PLY part file" in refused[0]


def test_read_ply_names_the_file_of_a_truncated_malformed_or_non_finite_part(tmp_path):
    # parts from elsewhere: each was a ValueError traceback ("buffer is smaller than requested
    # size", "invalid literal for int()") or read on to a misleading later error (NaN bounds)
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    data = (tmp_path / "part.ply").read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    vertices, triangles = read_ply(tmp_path / "part.ply")
    cases = {
        # 8 vertices of 24 bytes, then 12 faces of 13 bytes: 7 bytes short of the last face
        "truncated.ply": (data[:-7], rf"the file ends at byte {len(data) - 7}, where its 12 "
                                     rf"'face' elements need bytes {end + 8 * 24} \.\. "
                                     rf"{end + 8 * 24 + 12 * 13}"),
        "short_vertices.ply": (data[:end + 100], "the file ends .* its 8 'vertex' elements"),
        "bad_count.ply": (data.replace(b"element vertex 8", b"element vertex eight"),
                          "malformed element line 'element vertex eight'"),
        "no_faces.ply": (data[:end].replace(b"element face 12", b"element face 0")
                         + data[end:end + 8 * 24], r"no faces \(8 vertices\)"),
    }
    nan = vertices.copy()
    nan[3, 1] = np.nan
    cases["nan.ply"] = (data[:end] + nan.astype("<f8").tobytes() + data[end + 8 * 24:],
                        r"vertex 3 is \[.*nan.*\] \(1 of 8 not finite\)")
    for name, (content, message) in cases.items():
        (tmp_path / name).write_bytes(content)
        with pytest.raises(InputError, match=f"{name}: {message}"):
            read_ply(tmp_path / name)


def test_read_ply_refuses_a_closed_part_inside_out_and_reads_an_open_surface(tmp_path):
    # wound clockwise seen from outside, a 2 mm block's map showed its bottom as its top:
    # "height z" -2000 um everywhere, P-V 0, with exit 0
    vertices, triangles = stock_from_spec("block:1x1x2").mesh()
    (tmp_path / "inside_out.ply").write_bytes(ply_bytes(vertices, triangles[:, ::-1]))
    with pytest.raises(InputError, match=r"inside_out.ply: the part is inside out: it "
                                         r"encloses -2 mm\^3"):
        read_ply(tmp_path / "inside_out.ply")
    # an open mesh has no inside: its top alone (here reversed too) is read as it is
    up = triangle_normals(vertices, triangles)[:, 2] > 0.0
    (tmp_path / "open.ply").write_bytes(ply_bytes(vertices, triangles[up][:, ::-1]))
    assert len(read_ply(tmp_path / "open.ply")[1]) == 2
    assert mesh_volume(vertices, triangles) == pytest.approx(2e-9, rel=1e-12)
    assert mesh_volume(vertices, triangles[:, ::-1]) == pytest.approx(-2e-9, rel=1e-12)


def _searched_closed_and_oriented(triangles) -> bool:
    """The edge check as first written (539f4c0): each reversed edge searched among the
    sorted edges, the second method `closed_and_oriented`'s two sorts must agree with."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    count = int(triangles.max()) + 1
    key = np.sort(edges[:, 0] * count + edges[:, 1])
    if np.any(key[1:] == key[:-1]):
        return False
    back = edges[:, 1] * count + edges[:, 0]
    return bool(np.all(key[np.minimum(np.searchsorted(key, back), len(key) - 1)] == back))


def _row_volume(vertices, triangles) -> float:
    """`mesh_volume` as first written: bounds and centring along the (n, 3) rows."""
    centre = (vertices.min(axis=0) + vertices.max(axis=0)) / 2.0
    x, y, z = np.ascontiguousarray((vertices - centre).T)
    total = 0.0
    for start in range(0, len(triangles), 65536):
        a, b, c = triangles[start:start + 65536].T
        total += float(np.sum(x[a] * (y[b] * z[c] - z[b] * y[c])
                              + y[a] * (z[b] * x[c] - x[b] * z[c])
                              + z[a] * (x[b] * y[c] - y[b] * x[c])))
    return total / 6.0


def test_the_inside_out_checks_verdicts_are_the_searched_ones_and_known_by_hand(tmp_path):
    # read_ply's inside-out check was made cheaper (bounds along columns, two sorts for the
    # edges): the same volumes to the bit and the same verdicts as the first code
    from machinesim.viewer.meshes import closed_and_oriented

    vertices, triangles = stock_from_spec("block:1x1x2").mesh()
    n = len(vertices)
    flipped = triangles.copy()
    flipped[0] = flipped[0][::-1]
    big, small = stock_from_spec("block:4x4x4").mesh(), stock_from_spec("block:1x1x1@1,1,-1").mesh()
    two = np.vstack([big[0], small[0]])
    ball = manifold3d.Manifold.sphere(3 * MM, 480).translate((1e3, -2e3, 5e2)).to_mesh64()
    ball_v, ball_t = np.asarray(ball.vert_properties), np.asarray(ball.tri_verts, np.int64)
    cases = {  # triangles, whether closed and consistently wound, by construction
        "block": (vertices, triangles, True), "reversed": (vertices, triangles[:, ::-1], True),
        "one face flipped": (vertices, flipped, False), "open": (vertices, triangles[1:], False),
        "a face twice": (vertices, np.vstack([triangles, triangles[:1]]), False),
        "two blocks": (two, np.vstack([big[1], small[1][:, ::-1] + len(big[0])]), True),
        "far ball": (ball_v, ball_t, True), "far ball reversed": (ball_v, ball_t[:, ::-1], True)}
    assert n == 8 and len(ball_t) > 100_000  # more than one of mesh_volume's chunks
    for name, (v, t, closed) in cases.items():
        assert closed_and_oriented(t) == _searched_closed_and_oriented(t) == closed, name
        assert mesh_volume(v, t) == _row_volume(v, t), name  # bit for bit
    # the verdict: the whole volume's sign; a 4 mm cube holding a 1 mm cube wound inside
    # out (a cavity) encloses 63 mm^3 and is read, reversed it is -63 mm^3 and refused
    two_t = cases["two blocks"][1]
    (tmp_path / "cavity.ply").write_bytes(ply_bytes(two, two_t))
    assert mesh_volume(*read_ply(tmp_path / "cavity.ply")) == pytest.approx(63e-9, rel=1e-12)
    (tmp_path / "cavity_out.ply").write_bytes(ply_bytes(two, two_t[:, ::-1]))
    with pytest.raises(InputError, match=r"inside out: it encloses -63 mm\^3"):
        read_ply(tmp_path / "cavity_out.ply")


def test_decimate_meets_the_budget_and_keeps_the_shape():
    radius = 5 * MM
    mesh = manifold3d.Manifold.sphere(radius, 600).to_mesh64()
    vertices, triangles = np.asarray(mesh.vert_properties), np.asarray(mesh.tri_verts)
    assert len(triangles) > 100_000
    out_v, out_t = decimate(vertices, triangles, 20_000)
    assert 5_000 < len(out_t) <= 20_000  # thinned to the budget, not far below it
    # cluster means of points on the sphere stay within a cell of it: cells of ~0.1 mm here
    r = np.linalg.norm(out_v, axis=1)
    assert np.all(r <= radius * (1 + 1e-12)) and np.all(r > radius - 0.2 * MM)
    assert out_t.min() == 0 and out_t.max() == len(out_v) - 1  # every vertex used
    same_v, same_t = decimate(vertices, triangles, len(triangles))
    assert np.array_equal(same_v, vertices) and np.array_equal(same_t, triangles)
    with pytest.raises(InputError, match="max_triangles"):
        decimate(vertices, triangles, 0)


def test_read_ply_names_the_face_whose_index_is_outside_the_vertices(tmp_path):
    # it said "face indices outside [0, 3)": neither which face nor the index that was
    # wrong, in a file of a million faces
    bad = tmp_path / "bad.ply"
    faces = np.array([[0, 1, 2], [0, 2, 1], [0, 7, 1]])
    bad.write_bytes(ply_bytes(np.eye(3), faces))
    with pytest.raises(InputError) as caught:
        read_ply(bad)
    assert str(caught.value) == (f"{bad}: face 2 is [0, 7, 1] (1 of 9 indices outside): expected "
                                 "vertex indices 0 .. 2 (the file has 3 vertices)")


def test_read_ply_refuses_elements_the_header_does_not_count(tmp_path):
    # a header whose face count is too small (a writer that did not update it) was read
    # without a word: the faces after the count were dropped and the part drawn without them
    ascii_ply = tmp_path / "ascii.ply"
    ascii_ply.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                         "property double y\nproperty double z\nelement face 1\n"
                         "property list uchar int vertex_indices\nend_header\n"
                         "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n \n")
    with pytest.raises(InputError) as caught:
        read_ply(ascii_ply)
    assert str(caught.value) == (f"{ascii_ply}: the file goes on for 4 numbers after its "
                                 "elements end at number 13: expected as many elements as "
                                 "the header counts (3 vertex, 1 face)")
    binary = tmp_path / "binary.ply"
    data = ply_bytes(np.eye(3), np.array([[0, 1, 2], [0, 2, 1]]))
    binary.write_bytes(data.replace(b"element face 2", b"element face 1"))
    end = data.index(b"end_header\n") + len(b"end_header\n") + 3 * 24 + 13
    with pytest.raises(InputError) as caught:
        read_ply(binary)
    assert str(caught.value) == (f"{binary}: the file goes on for 13 bytes after its "
                                 f"elements end at byte {end}: expected as many elements as "
                                 "the header counts (3 vertex, 1 face)")
    # a line end some writers leave after the binary data is no element: read as without it
    trailing = tmp_path / "trailing.ply"
    trailing.write_bytes(data + b"\r\n")
    for got, want in zip(read_ply(trailing), read_ply_bytes(tmp_path, data), strict=True):
        np.testing.assert_array_equal(got, want)


def read_ply_bytes(folder, data: bytes):
    """`read_ply` of a file holding ``data``."""
    path = folder / "as_written.ply"
    path.write_bytes(data)
    return read_ply(path)


def test_a_float32_part_with_a_long_header_is_still_warned_about(tmp_path):
    # only the first 64 KiB were read for the header: 3000 comments pushed the element lines
    # past them and the float32 rounding went without its warning
    part = tmp_path / "long.ply"
    data = ply_bytes(np.array([[0.0, 0.0, 0.0], [1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0]]),
                     np.array([[0, 1, 2]]), kind="float")
    comments = ("comment " + "x" * 30 + "\n") * 3000
    at = data.index(b"element vertex")
    part.write_bytes(data[:at] + comments.encode("ascii") + data[at:])
    assert ply_single_precision(part)


def test_read_ply_names_an_ascii_face_index_past_any_integer_as_written(tmp_path):
    # 1e30 was cast to int64's -9223372036854775808 and named so; 2.5 and nan were
    # "a face's vertex index is not a whole number", naming no face
    header = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
              "property double z\nelement face 2\nproperty list uchar int vertex_indices\n"
              "end_header\n0 0 0\n0.001 0 0\n0 0.001 0\n3 0 1 2\n")
    for index, shown in (("1e30", "1e+30"), ("inf", "inf"), ("2.5", "2.5"), ("nan", "nan")):
        part = tmp_path / "part.ply"
        part.write_text(f"{header}3 0 1 {index}\n")
        with pytest.raises(InputError) as caught:
            read_ply(part)
        assert str(caught.value) == (f"{part}: face 1 is [0, 1, {shown}]: expected "
                                     "whole-number vertex indices")
