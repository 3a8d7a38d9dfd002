"""The viewer without a browser: exact maps, decimation, staged cuts, scene contents, export,
the loopback server and the command line (the browser itself: test_viewer_browser.py)."""

from __future__ import annotations

import argparse
import json
import os
import re
import urllib.request
import xml.etree.ElementTree as ET
from pathlib import Path

import manifold3d
import numpy as np
import pytest
import umsgpack
from scipy.spatial.transform import Rotation

from machinesim import ErrorModel, ToolSetting, load_machine
from machinesim.cutting import cut
from machinesim.exceptions import AxisLimitError, InputError, MachineSimError, ModelError
from machinesim.metrology import height_map
from machinesim.motion import plan
from machinesim.nc import ProgramBuilder
from machinesim.tool_specs import tool_from_spec
from machinesim.viewer import (
    cut_by_block,
    decimate,
    machine_scene,
    part_scene,
    read_ply,
    serve,
    surface_map,
    write_html,
)
from machinesim.viewer.cli import add_view_parser, run_view
from machinesim.viewer.maps import (
    DIVERGING,
    NO_DATA,
    SurfaceMap,
    colours,
    legend_for,
    map_mesh,
)
from machinesim.viewer.meshes import ply_single_precision, triangle_normals
from machinesim.viewer.scene import Scene
from machinesim.viewer.views import report_notes
from machinesim.workpiece import Part, block, mesh_volume, stock_from_spec

UM, MM = 1e-6, 1e-3
#: A small display budget keeps these scenes fast; the exactness checks do not depend on it.
BUDGET = 4000


def grooves(n=4, pitch=150 * UM, depth=20 * UM, y0=0.2 * MM, length=1 * MM):
    """Grooves along X across a 1 mm block, entering and leaving outside it."""
    b = ProgramBuilder(1)
    for i in range(n):
        b.rapid(X=-0.2 * MM, Y=y0 + i * pitch, Z=0.1 * MM).rapid(Z=-depth)
        b.linear(X=length + 0.2 * MM, feed_mm_per_min=500.0).rapid(Z=0.1 * MM)
    return b.build()


ERRORS = ErrorModel(tool=ToolSetting([0.0, 4 * UM, -1 * UM], [0.0, 0.0, 0.0]))
STOCK = "block:1x0.8x0.5"


def tilted_block(slope: float, length=2 * MM, width=1 * MM, height=0.5 * MM) -> Part:
    """Block [0, L] x [0, W] x [-H, top] whose top is z = slope * (x - L/2)."""
    x, y = (0.0, length), (0.0, width)
    top = [slope * (xi - length / 2) for xi in x]
    vertices = [(x[i], y[j], z) for z in (-height, None) for j in (0, 1) for i in (0, 1)]
    vertices = [(vx, vy, top[i % 2] if vz is None else vz)
                for i, (vx, vy, vz) in enumerate(vertices)]
    faces = [(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
             (1, 3, 7), (1, 7, 5), (3, 2, 6), (3, 6, 7), (2, 0, 4), (2, 4, 6)]
    return Part.from_mesh(vertices, faces)


def decoded(scene: Scene) -> list[dict]:
    return [umsgpack.unpackb(data) for _, _, data in scene.frames]


def floats(ext) -> np.ndarray:
    return np.frombuffer(ext.data, dtype=np.float32)


# ------------------------------------------------------------------------------- meshes

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


def ply_bytes(vertices, triangles, kind="double") -> bytes:
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
              f"property {kind} x\nproperty {kind} y\nproperty {kind} z\n"
              f"element face {len(triangles)}\nproperty list uchar int vertex_indices\n"
              "end_header\n").encode("ascii")
    faces = np.zeros(len(triangles), dtype=[("n", "u1"), ("i", "<i4", 3)])
    faces["n"], faces["i"] = 3, triangles
    dtype = {"double": "<f8", "float": "<f4"}[kind]
    return header + np.asarray(vertices, dtype=dtype).tobytes() + faces.tobytes()


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


# --------------------------------------------------------------------------------- maps

def test_deviation_map_of_a_tilted_top_is_the_exact_plane_difference():
    slope = 1e-4  # 0.1 um per mm: +-100 nm over the 2 mm block
    smap = surface_map(tilted_block(slope), block(2 * MM, 1 * MM, 0.5 * MM), BUDGET)
    expected = slope * (smap.x - 1 * MM)[None, :] * np.ones((len(smap.y), 1))
    # float64 plane evaluations of ~1e-7 m values: round-off ~1e-22 m, far below 1e-18 m
    np.testing.assert_allclose(smap.values, expected, rtol=0, atol=1e-18)
    assert smap.kind == "deviation"
    assert smap.peak_to_valley == pytest.approx(200e-9, rel=1e-12)
    legend = legend_for(smap)
    assert [label for _, label in legend.ticks] == ["-100 nm", "-50 nm", "+0 nm", "+50 nm",
                                                    "+100 nm"]
    assert legend.notes[0].startswith("P-V 200 nm, RMS")


def test_a_legend_says_its_p_v_is_the_grid_nodes_and_how_far_apart_they_stand():
    # The README's part: four V grooves 20 um deep and 40 um wide across a 10 mm block. On
    # the default 317 x 317 nodes (31.65 um apart) no node lies on an apex, so the legend's
    # P-V read 13.67 um under "exact heights", which a user takes for the part's 20 um.
    program = ProgramBuilder(1)
    for i, y in enumerate((2, 4, 6, 8)):
        program.rapid(X=(-1 if i % 2 == 0 else 11) * MM, Y=y * MM, Z=0.1 * MM)
        program.rapid(Z=-20 * UM).linear(X=(11 if i % 2 == 0 else -1) * MM,
                                         feed_mm_per_min=100.0).rapid(Z=0.1 * MM)
    part, _ = cut(program.build(), "grooving_4axis", tool="v:90", stock="block:10x10x2")
    smap = surface_map(part)
    spacing = 10 * MM / (len(smap.x) - 1)
    assert len(smap.x) == len(smap.y) == 317 and spacing == pytest.approx(31.65 * UM, abs=5e-9)
    # an exact height map of the same part through the apexes reads the full depth
    assert np.nanmin(height_map(part, smap.x, np.array([2 * MM]))) == pytest.approx(-20 * UM,
                                                                                   abs=1e-15)
    assert smap.peak_to_valley == pytest.approx(13.67 * UM, abs=0.01 * UM)
    legend = legend_for(smap)
    assert legend.notes[0] == "P-V 13.67 um"
    assert legend.notes[1] == ("317 x 317 exact heights (metrology.height_map), 31.65 um "
                               "apart: the P-V and RMS of these nodes, which a narrower "
                               "groove or peak can fall between")


def test_a_legend_tick_at_round_off_of_zero_reads_zero():
    # heights from -1 um to 1 um but for 1e-22 m: the middle tick read '+2.118e-13 nm'
    x = y = np.array([0.0, 1e-3])
    heights = np.array([[-999.8e-9, 0.0], [0.0, 999.8e-9 + 2e-22]])
    legend = legend_for(SurfaceMap(x, y, heights, heights, "height"))
    assert [label for _, label in legend.ticks] == ["-999.8 nm", "-499.9 nm", "+0 nm",
                                                    "+499.9 nm", "+999.8 nm"]


def test_a_legends_p_v_and_rms_below_a_picometre_read_zero():
    # a part and its nominal the same but for round-off (2.745e-18 m) read 'P-V 2.745e-09
    # nm': below 1 pm (tolerances.POSE_M, the geometry's resolution) a figure reads 0, and
    # from 1 pm up it is written as before, to 4 digits
    x = y = np.array([0.0, 1e-3])

    def stats(values):
        values = np.asarray(values, dtype=np.float64)
        return legend_for(SurfaceMap(x, y, values, values, "deviation")).notes[0]

    assert stats([[2.745e-18, 0.0], [0.0, 0.0]]) == "P-V 0 nm, RMS 0 nm"
    assert stats([[4e-13, -5e-13], [0.0, 0.0]]) == "P-V 0 nm, RMS 0 nm"  # 0.9 pm P-V
    # 4 pm P-V, RMS sqrt((2^2 + 2^2) / 4) = 1.414 pm
    assert stats([[2e-12, -2e-12], [0.0, 0.0]]) == "P-V 0.004 nm, RMS 0.001414 nm"
    # RMS sqrt(2^2 / 4) = 1 pm exactly: no longer below the cut-off, so written
    assert stats([[2e-12, 0.0], [0.0, 0.0]]) == "P-V 0.002 nm, RMS 0.001 nm"
    assert stats([[100e-9, -100e-9], [0.0, 0.0]]) == "P-V 200 nm, RMS 70.71 nm"
    heights = np.full((2, 2), 0.5e-3)  # a flat top: P-V 0 as before
    assert legend_for(SurfaceMap(x, y, heights, heights, "height")).notes[0] == "P-V 0 nm"


def test_map_mesh_faces_up_covers_the_part_and_leaves_out_cells_off_it():
    smap = surface_map(tilted_block(1e-4), block(2 * MM, 1 * MM, 0.5 * MM), BUDGET)
    vertices, triangles, rgb = map_mesh(smap)
    nx, ny = len(smap.x), len(smap.y)
    assert len(triangles) == 2 * (nx - 1) * (ny - 1) <= BUDGET
    corner = vertices[triangles]
    normal_z = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])[:, 2]
    assert np.all(normal_z > 0)
    # the scale is symmetric and the extremes are at x = 0 and x = L: the end colours
    np.testing.assert_allclose(rgb[0], DIVERGING[0], atol=1e-12)
    np.testing.assert_allclose(rgb[nx - 1], DIVERGING[-1], atol=1e-12)
    round_map = surface_map(stock_from_spec("cylinder:1x0.5"), max_triangles=BUDGET)
    _, round_tri, _ = map_mesh(round_map)
    assert 0 < len(round_tri) < 2 * (len(round_map.x) - 1) * (len(round_map.y) - 1)
    assert np.all(np.isfinite(round_map.heights.ravel()[np.unique(round_tri)]))


def test_colours_interpolate_the_stops_and_mark_missing_values():
    rgb = colours([-2.0, -1.0, 0.0, 0.5, 1.0, 3.0, np.nan], -1.0, 1.0, DIVERGING)
    np.testing.assert_allclose(rgb[0], DIVERGING[0])  # clipped below
    np.testing.assert_allclose(rgb[1], DIVERGING[0])
    np.testing.assert_allclose(rgb[2], DIVERGING[5])  # the middle of 11 stops
    np.testing.assert_allclose(rgb[3], 0.5 * (DIVERGING[7] + DIVERGING[8]))
    np.testing.assert_allclose(rgb[4], DIVERGING[-1])
    np.testing.assert_allclose(rgb[5], DIVERGING[-1])
    np.testing.assert_allclose(rgb[6], NO_DATA)


# ----------------------------------------------------------------------- staged cutting

def test_cutting_block_by_block_ends_with_the_part_cut_in_one_go():
    machine = load_machine("grooving_4axis")
    tool = tool_from_spec("v:150")
    stock = stock_from_spec(STOCK)
    trajectory = plan(grooves(), machine, ERRORS, tool_points=tool.vertices())
    times, parts = cut_by_block(trajectory, machine, tool, stock, ERRORS)
    assert len(parts) == 5 and times[0] == 0.0 and np.all(np.diff(times) > 0)
    assert np.all(np.diff([p.volume for p in parts]) < 0)  # every groove removes material
    whole, _ = cut(grooves(), machine, tool=tool, stock=stock, errors=ERRORS)
    assert parts[-1].volume == pytest.approx(whole.volume, rel=1e-12)
    x, y = np.linspace(0.1 * MM, 0.9 * MM, 9), np.linspace(0.0, 0.8 * MM, 801)
    # the same planes cut in another order: heights agree to float64 round-off (1 pm)
    np.testing.assert_allclose(height_map(parts[-1], x, y), height_map(whole, x, y),
                               rtol=0, atol=1e-12)
    _, grouped = cut_by_block(trajectory, machine, tool, stock, ERRORS, max_stages=2)
    assert len(grouped) == 3
    assert grouped[-1].volume == pytest.approx(whole.volume, rel=1e-12)


def test_the_stages_cut_the_rapids_too_as_cut_does():
    # a rapid through the block, then a groove fed at Y 0.5 mm: the stages had cut the feed
    # alone, so the finished part lacked the rapid's groove, which the map coloured as the
    # machine's error against cut()'s part; rapids alone were 'no material removed'
    machine = load_machine("grooving_4axis")
    tool = tool_from_spec("v:150")
    stock = stock_from_spec(STOCK)
    b = ProgramBuilder(1).rapid(X=-0.2 * MM, Y=0.2 * MM, Z=0.1 * MM).rapid(Z=-20 * UM)
    rapids = b.rapid(X=1.2 * MM).rapid(Z=0.1 * MM).build()
    both = b.rapid(Y=0.5 * MM).rapid(Z=-20 * UM).linear(
        X=-0.2 * MM, feed_mm_per_min=500.0).rapid(Z=0.1 * MM).build()
    for program, stages in ((both, 2), (rapids, 2)):
        trajectory = plan(program, machine, None, tool_points=tool.vertices())
        _, parts = cut_by_block(trajectory, machine, tool, stock)
        whole, _ = cut(program, machine, tool=tool, stock=stock)
        assert len(parts) == stages
        # each groove: a V of 150 deg, 20 um deep, across the 1 mm block
        groove = (20 * UM) ** 2 * np.tan(np.radians(75.0)) * 1 * MM
        removed = stock.volume - parts[-1].volume
        assert removed == pytest.approx(groove * (2 if program is both else 1), rel=1e-9,
                                        abs=0.0)
        assert parts[-1].volume == pytest.approx(whole.volume, rel=1e-12)
    # the view names the stage of rapids alone so, not as groups of feed blocks
    notes = machine_scene(machine, rapids, tool="v:150", stock=STOCK,
                          max_triangles=BUDGET).notes
    assert "part stages: 1 (stock, then after its rapids: it has no feed block)" in notes
    notes = machine_scene(machine, both, tool="v:150", stock=STOCK, max_triangles=BUDGET).notes
    assert "part stages: 1 (stock, then after each feed block)" in notes


# ----------------------------------------------------------------------- machine scene

def test_machine_scene_draws_every_visual_and_moves_the_tool_as_the_kinematics_say():
    machine = load_machine("grooving_4axis")
    scene = machine_scene(machine, grooves(), tool="v:150", stock=STOCK, errors=ERRORS,
                          max_triangles=BUDGET)
    commands = decoded(scene)
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    # every <visual> of every link in the URDF, named as Pinocchio names them: link_k
    visuals = {f"/meshcat/machine/visuals/{link.get('name')}_{k}"
               for link in ET.fromstring(machine.urdf_xml).iter("link")
               for k, _ in enumerate(link.findall("visual"))}
    assert len(visuals) == 8 and visuals <= objects
    assert {"/meshcat/tool", "/meshcat/workpiece/paths/nominal",
            "/meshcat/workpiece/paths/actual", "/meshcat/inspection/part/map"} <= objects
    [animation] = [c for c in commands if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in animation["animations"]}

    def pose_at_end(path):
        tracks = {t["name"]: t["keys"][-1]["value"] for t in clips[path]["tracks"]}
        pose = np.eye(4)
        pose[:3, :3] = Rotation.from_quat(tracks[".quaternion"]).as_matrix()
        pose[:3, 3] = tracks[".position"]
        return pose

    # the program runs from the machine's home, as machinesim cut runs it
    end_q = plan(grooves(), machine, ERRORS, start=machine.home).segments[-1].q[-1]
    wMt = np.linalg.inv(pose_at_end("/meshcat/workpiece")) @ pose_at_end("/meshcat/tool")
    # Pinocchio's forward kinematics vs machinesim's batched chain: tolerances.POSE_M
    np.testing.assert_allclose(wMt, machine.tool_pose(end_q, ERRORS), rtol=0, atol=1e-12)

    stages = {p: c for p, c in clips.items() if "/stages/" in p}
    assert len(stages) == 5
    for t in np.linspace(0.0, max(k["time"] for c in clips.values()
                                  for tr in c["tracks"] for k in tr["keys"]), 97):
        shown = 0
        for clip in stages.values():
            keys = clip["tracks"][0]["keys"]
            shown += [k["value"] for k in keys if k["time"] <= t][-1]
        assert shown == 1  # one stage of the part at any time

    [nominal] = [c for c in commands if c["path"] == "/meshcat/workpiece/paths/nominal"]
    points = floats(nominal["object"]["geometries"][0]["data"]["attributes"]["position"]["array"])
    feed_q = np.vstack([s.q for s in plan(grooves(), machine, ERRORS,
                                          start=machine.home).segments])
    expected = machine.tool_pose(feed_q, None)[:, :3, 3]
    assert expected[0, 2] == pytest.approx(machine.home[2], abs=1e-15)  # from home: Z 100 mm
    # float32 display buffers: a 24-bit mantissa
    np.testing.assert_allclose(points.reshape(-1, 3), expected, rtol=2.0**-24, atol=1e-12)


def test_the_tool_path_note_says_red_is_the_nominal_path_where_no_error_is_given():
    # 'red actual (with errors)' was said of a view given no errors too, where the red path
    # is the cyan one: the note now says what is drawn, checked against the drawn paths
    machine = load_machine("grooving_4axis")
    program = grooves(n=1)

    def view(errors):
        scene = machine_scene(machine, program, tool="v:150", stock=STOCK, errors=errors,
                              max_triangles=BUDGET)
        paths = {c["path"]: floats(c["object"]["geometries"][0]["data"]["attributes"]
                                   ["position"]["array"])
                 for c in decoded(scene) if c["path"].startswith("/meshcat/workpiece/paths/")
                 and c["type"] == "set_object"}
        same = np.array_equal(paths["/meshcat/workpiece/paths/nominal"],
                              paths["/meshcat/workpiece/paths/actual"])
        return [n for n in scene.notes if n.startswith("tool path:")], same

    assert view(None) == (["tool path: cyan nominal; no errors given (--errors), so the red "
                           "actual path is the nominal one, drawn over it"], True)
    assert view(ErrorModel()) == (["tool path: cyan nominal; the errors given are all zero, "
                                   "so the red actual path is the nominal one, drawn over "
                                   "it"], True)
    assert view(ERRORS) == (["tool path: cyan nominal, red actual (with errors)"], False)


def test_a_mesh_the_viewer_cannot_load_is_left_out_with_a_warning(tmp_path):
    # a ROS file's package:// mesh resolves only inside ROS: the machine is drawn without
    # it, and the warning names the link and the file (the view ended in a ValueError)
    text = (Path(load_machine("grooving_4axis").path).read_text()
            .replace('<link name="base">', '<link name="base"><visual><geometry><mesh '
                     'filename="package://foo/meshes/base.stl"/></geometry></visual>'))
    path = tmp_path / "meshed.urdf"
    path.write_text(text)
    scene = machine_scene(load_machine(path))
    assert scene.warnings == [f"{path}: mesh files that could not be loaded, drawn without "
                              "them: base (package://foo/meshes/base.stl) (a relative path is "
                              f"looked up in {tmp_path}, package://<package>/... there and in "
                              "the two folders above it; give the file's path)"]
    objects = {c["path"] for c in decoded(scene) if c["type"] == "set_object"}
    assert "/meshcat/machine/visuals/tool_tip_0" in objects  # the rest is drawn


#: One triangle, 10 mm on its sides, as an ASCII STL (m).
_STL = ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.01 0 0\n"
        "vertex 0 0.01 0\nendloop\nendfacet\nendsolid t\n")


@pytest.mark.parametrize(("filename", "where"), [
    ("meshes/base.stl", "mill/urdf/meshes/base.stl"),
    ("package://mill/meshes/base.stl", "mill/meshes/base.stl")])
def test_a_mesh_beside_the_urdf_is_drawn_wherever_the_view_starts(filename, where, tmp_path,
                                                                  monkeypatch):
    # a CAD export's meshes/base.STL beside its URDF, or a ROS package's mill/urdf/ and
    # mill/meshes/: Pinocchio looked a relative path up in the working folder only, and
    # package:// nowhere, so both were left out with a warning that said to give the path
    (tmp_path / "ws" / where).parent.mkdir(parents=True)
    (tmp_path / "ws" / where).write_text(_STL)
    path = tmp_path / "ws" / "mill" / "urdf" / "mill.urdf"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(Path(load_machine("grooving_4axis").path).read_text().replace(
        '<link name="base">',
        f'<link name="base"><visual><geometry><mesh filename="{filename}"/></geometry></visual>'))
    monkeypatch.chdir(tmp_path)
    scene = machine_scene(load_machine(path))
    assert scene.warnings == []
    (base,) = [c for c in decoded(scene) if c["type"] == "set_object"
               and c["path"] == "/meshcat/machine/visuals/base_0"]
    geometry = base["object"]["geometries"][0]
    assert (geometry["type"], geometry["format"]) == ("_meshfile", "stl")
    assert geometry["data"].data == _STL.encode()  # the file itself, drawn


def test_a_machine_without_visual_bodies_is_framed_on_its_stock_and_its_part_copied():
    # models/examples/mill3.urdf, docs/machines.md's starting machine, has no <visual>: the
    # view framed a point and scaled the finished part's copy to nothing (a tool path and
    # a dot on screen)
    machine = load_machine(Path(__file__).resolve().parents[1] / "models/examples/mill3.urdf")
    scene = machine_scene(machine, grooves(), tool="v:90", stock="block:10x10x2",
                          max_triangles=BUDGET)
    commands = decoded(scene)

    def transform(path):
        [c] = [c for c in commands if c["type"] == "set_transform" and c["path"] == path]
        return np.array(c["matrix"], dtype=np.float64).reshape(4, 4).T

    # the framing scales the drawn box to about one unit: the stock and the copy beside it
    # (at its own size, 10 mm, with a tenth of the box between): 21 mm across
    assert transform("/meshcat")[0, 0] == pytest.approx(1.0 / 0.021, rel=1e-9)
    assert transform("/meshcat/inspection")[0, 0] == pytest.approx(1.0, rel=1e-12)


def test_a_programs_view_tells_each_cut_as_it_goes():
    # a 100,000-line program's view printed nothing for the 10 minutes it ran before it was
    # stopped (it cuts the program about twice): the four grooves are four stages, then
    # the part on the machine without errors, each told once, in order
    told = []
    machine_scene(load_machine("grooving_4axis"), grooves(), tool="v:150", stock=STOCK,
                  errors=ERRORS, max_triangles=BUDGET,
                  progress=lambda done, total: told.append((done, total)))
    assert told == [(1, 5), (2, 5), (3, 5), (4, 5), (5, 5)]


def test_the_view_command_writes_its_cuts_as_lines_after_ten_seconds(capsys):
    from machinesim.viewer.cli import cut_lines

    now = [100.0]
    show = cut_lines(clock=lambda: now[0])
    show(1, 61)  # at once: nothing, as for a quick view
    now[0] = 111.0
    show(12, 61)
    now[0] = 120.0
    show(13, 61)  # within 30 s of the last line: nothing
    now[0] = 125.0
    show(61, 61)  # the end, once a line was written
    assert capsys.readouterr().err.splitlines() == ["  view: 12/61 cuts (19 %), 11 s",
                                                    "  view: 61/61 cuts (100 %), 25 s"]


def test_machine_scene_without_program_and_with_bad_settings():
    scene = machine_scene("robonano_a0ib")
    assert not [c for c in decoded(scene) if c["type"] == "set_animation"]
    assert scene.notes[0].startswith("travel: X -140..140 mm")
    with pytest.raises(InputError, match="duration_s and max_stages must be positive"):
        machine_scene("grooving_4axis", grooves(), stock=STOCK, duration_s=0.0)


# ------------------------------------------------------------------------------ export

def test_exported_html_is_self_contained_and_written_whole(tmp_path, monkeypatch):
    scene = part_scene(tilted_block(1e-4), nominal=block(2 * MM, 1 * MM, 0.5 * MM),
                       max_triangles=BUDGET)
    target = write_html(scene, tmp_path / "part.html")
    text = target.read_text(encoding="utf-8")
    urls = set(re.findall(r"(?:https?|wss?|ftp)://[^\s\"'`)]+", text))
    # XHTML's namespace name inside three.js (never fetched) and meshcat's default server
    # address, used only by viewer.connect(), which the exported page never calls
    assert urls == {"http://www.w3.org/1999/xhtml", "ws://${location.host}"}
    assert "viewer.connect(" not in text
    assert " src=" not in text and "<link" not in text
    assert text.count("MeshCat.Viewer") == 1 and "deviation from nominal" in text

    def broken(self):
        raise RuntimeError("interrupted")

    monkeypatch.setattr(Scene, "to_html", broken)
    with pytest.raises(RuntimeError):
        write_html(scene, target)
    assert target.read_text(encoding="utf-8") == text  # the old file, whole
    assert [p.name for p in tmp_path.iterdir()] == ["part.html"]  # no temp file left


def test_a_page_whose_script_a_browser_cannot_read_is_refused(tmp_path, monkeypatch):
    # --max-triangles 20000000 wrote a 641 MB page whose scene script was longer than V8's
    # longest string ((1 << 29) - 24 UTF-16 units): it opened blank, exit 0
    import machinesim.viewer.scene as scene_module

    assert scene_module.SCRIPT_CHARS_MOST == 536_870_888
    scene = part_scene(tilted_block(1e-4), max_triangles=BUDGET)
    text = scene.to_html()
    script = text[text.rindex("<script>\n") + len("<script>\n"):text.rindex("</script>")]
    monkeypatch.setattr(scene_module, "SCRIPT_CHARS_MOST", len(script))
    assert scene.to_html() == text  # at the limit: written
    monkeypatch.setattr(scene_module, "SCRIPT_CHARS_MOST", len(script) - 1)
    with pytest.raises(InputError, match=f"a script of {len(script):,} characters, beyond the "
                                         f"{len(script) - 1:,} a browser's JavaScript engine"):
        write_html(scene, tmp_path / "part.html")
    assert not (tmp_path / "part.html").exists()


def test_a_part_file_in_millimetres_is_warned_about(tmp_path):
    # a 10 x 10 x 2 mm block written in mm reads as a 10 m block: it was shown so, its map's
    # P-V 1000 times too large, without a word
    vertices, triangles = stock_from_spec("block:10x10x2").mesh()
    (tmp_path / "mm.ply").write_bytes(ply_bytes(vertices * 1e3, triangles))
    (tmp_path / "m.ply").write_bytes(ply_bytes(vertices, triangles))
    scene = part_scene(tmp_path / "mm.ply", max_triangles=BUDGET)
    assert scene.warnings == ["the part measures 10 x 10 x 2 m, larger than any machine's "
                              "travel: PLY coordinates are read as metres; was the file "
                              "written in millimetres?"]
    assert part_scene(tmp_path / "m.ply", max_triangles=BUDGET).warnings == []
    both = part_scene(tmp_path / "m.ply", nominal=tmp_path / "mm.ply", max_triangles=BUDGET)
    assert [line.split(" measures")[0] for line in both.warnings] == ["the nominal part"]


def test_a_map_without_heights_or_deviations_is_warned_about():
    # a nominal in another frame (here 50 mm along x) left every node without a deviation:
    # a grey map, a +-1 nm scale and 'P-V nan um', exit 0, with no word why
    part = stock_from_spec("block:10x10x2")
    scene = part_scene(part, nominal=stock_from_spec("block:10x10x2@50,0,0"),
                       max_triangles=BUDGET)
    assert scene.warnings == ["the nominal part lies under no point of the part's map (x 0 .. "
                              "10 mm, y 0 .. 10 mm): no deviation to show; are both in the "
                              "same workpiece frame?"]
    # an open surface facing down (a scan with its normals down) had an empty map, no word
    vertices, triangles = part.mesh()
    up = triangle_normals(vertices, triangles)[:, 2] > 0.0
    down = part_scene((vertices, triangles[up][:, ::-1]), max_triangles=BUDGET)
    assert down.warnings == ["the part has no face that faces up over its map, so the map is "
                             "empty: heights are read from upward-facing triangles "
                             "(counter-clockwise seen from above); is the surface wound the "
                             "other way?"]
    # overlapping by half, the map shows what it can: no warning
    half = part_scene(part, nominal=stock_from_spec("block:10x10x2@5,0,0"),
                      max_triangles=BUDGET)
    assert half.warnings == []


def test_a_part_file_in_single_precision_is_warned_about(tmp_path):
    # trimesh writes PLY vertices as float32: read widened, the map's legend still said
    # "exact heights" without a word of the rounding (up to half a float32 step: 0.47 nm at
    # 10 mm, np.spacing(np.float32(0.01)) / 2 = 4.66e-10 m)
    vertices, triangles = stock_from_spec("block:10x10x2").mesh()
    (tmp_path / "f32.ply").write_bytes(ply_bytes(vertices, triangles, "float"))
    (tmp_path / "f64.ply").write_bytes(ply_bytes(vertices, triangles))
    widened = read_ply(tmp_path / "f32.ply")[0]
    assert 0.0 < np.abs(widened - vertices).max() <= 4.66e-10
    scene = part_scene(tmp_path / "f32.ply", max_triangles=BUDGET)
    assert scene.warnings == [
        "the part (f32.ply) stores its vertices as float32: each rounded by up to 0.47 nm "
        "(half a float32 step at 10 mm from the origin) before it was read, so its heights "
        "are exact for the rounded mesh only; machinesim cut --out part.ply writes float64"]
    assert part_scene(tmp_path / "f64.ply", max_triangles=BUDGET).warnings == []
    both = part_scene(tmp_path / "f64.ply", nominal=tmp_path / "f32.ply", max_triangles=BUDGET)
    assert [line.split(" (")[0] for line in both.warnings] == ["the nominal part"]


def test_report_notes_flatten_nested_keys():
    lines = report_notes({"volume_mm3": 0.0123456789, "rapid": {"lines": [1, 2]},
                          "big": list(range(10))})
    assert lines == ["volume_mm3: 0.0123457", "rapid.lines: [1, 2]", "big: [10 entries]"]
    many = report_notes({f"k{i}": i for i in range(20)})
    assert len(many) == 15 and many[-1] == "... 6 more entries"


# -------------------------------------------------------------------------------- live

def _listening(pid: int) -> list[tuple[str, int]]:
    """(address, port) of the TCP sockets process ``pid`` listens on (Linux /proc)."""
    inodes = set()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        try:
            link = os.readlink(f"/proc/{pid}/fd/{fd}")
        except OSError:
            continue
        if link.startswith("socket:["):
            inodes.add(link[8:-1])
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "0A" and fields[9] in inodes:  # 0A: LISTEN
                address, port = fields[1].split(":")
                if len(address) == 8:
                    address = ".".join(str(int(address[i:i + 2], 16)) for i in (6, 4, 2, 0))
                found.append((address, int(port, 16)))
    return found


def test_live_server_listens_on_loopback_only_and_serves_the_page():
    scene = part_scene(tilted_block(1e-4), max_triangles=BUDGET)
    with serve(scene) as live:
        sockets = _listening(live.process.pid)
        assert len(sockets) == 2  # the web server and the ZeroMQ socket
        assert {address for address, _ in sockets} == {"127.0.0.1"}
        assert live.url == f"http://127.0.0.1:{sockets[0][1]}/static/" or \
            live.url == f"http://127.0.0.1:{sockets[1][1]}/static/"
        with urllib.request.urlopen(live.url, timeout=10) as response:
            page = response.read().decode("utf-8")
        assert "viewer.connect()" in page and "height z (workpiece frame)" in page
        # background (2), hidden grid and axes, camera (2), root transform, map and body
        assert live.messages == 9
    assert live.process.poll() is not None


def test_a_live_server_that_cannot_start_or_hangs_is_named_not_waited_for(monkeypatch):
    """A port in use: the server's own reason is in the message (it went to /dev/null). A
    server that prints nothing: ended after START_TIMEOUT_S (the command hung on its pipe)."""
    import socket
    import sys

    from machinesim.exceptions import MachineSimError
    from machinesim.viewer import live as live_module

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(MachineSimError, match="ended before giving its address: "
                                                  r"OSError: \[Errno 98\] Address already"):
            live_module.start_server(port)
    with monkeypatch.context() as short:  # the short bound for the one that hangs alone
        short.setattr(live_module, "START_TIMEOUT_S", 0.5)
        short.setattr(live_module, "server_command", lambda port=None: [
            sys.executable, "-c", "import time; time.sleep(30)"])
        with pytest.raises(MachineSimError, match="gave no address within 0.5 s"):
            live_module.start_server()
    # one that raised before it could say 'error=' (an import failed): its stderr's last
    # line is the reason (it had said 'ended before giving its address' alone). It starts
    # slowly, as any does on a loaded machine, under the default bound: it had run under
    # the 0.5 s above, and a start slower than that was told as a hang (the flake)
    monkeypatch.setattr(live_module, "server_command", lambda port=None: [
        sys.executable, "-c", "import sys, time; time.sleep(1.0); "
        "print('warming up', file=sys.stderr); "
        "raise ImportError('no module named meshcat here')"])
    with pytest.raises(MachineSimError, match="ended before giving its address: ImportError: "
                                              "no module named meshcat here; is the port"):
        live_module.start_server()


def test_a_web_port_in_meshcats_zeromq_range_is_left_to_the_web_server():
    """meshcat binds ZeroMQ to the first free port from 6000 before the web server binds:
    asked for that very port (6000 busy, 6001 free), the web server found it taken."""
    import socket

    from machinesim.viewer.live import start_server

    held = socket.socket()
    try:
        try:
            held.bind(("127.0.0.1", 6000))  # busy already is as good
            held.listen()
        except OSError:
            pass
        # the first free port after 6000; another test's server (run side by side) may take
        # it between the probe and the start: a few tries tell that race from the bug, in
        # which this server's own meshcat takes it every time
        for _ in range(3):
            port = 6001
            while True:
                with socket.socket() as probe:
                    try:
                        probe.bind(("127.0.0.1", port))
                        break
                    except OSError:
                        port += 1
            try:
                session = start_server(port)
                break
            except MachineSimError as error:
                refused = error
        else:
            raise refused
        try:
            assert session.url == f"http://127.0.0.1:{port}/static/"
            assert not session.zmq_url.endswith(f":{port}")
        finally:
            session.close()
    finally:
        held.close()


def test_a_scripts_wait_ends_quietly_on_ctrl_c_and_ends_the_server():
    """``live.wait()`` in a script (docs/viewer.md) stopped by Ctrl-C: it returns None
    (it raised KeyboardInterrupt into the script, a traceback) and the server has ended;
    left alone it returns the server's exit code."""
    import signal
    import threading

    scene = part_scene(tilted_block(1e-4), max_triangles=BUDGET)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with serve(scene) as live:
            # Ctrl-C once wait() is waiting on the server (a fixed 0.5 s timer could fire
            # before it, on a loaded machine, into the test itself)
            waiting, process_wait = threading.Event(), live.process.wait

            def wait(timeout=None):
                waiting.set()
                return process_wait(timeout)

            live.process.wait = wait
            timer = threading.Thread(target=lambda: waiting.wait(60) and os.kill(
                os.getpid(), signal.SIGINT))
            timer.start()
            assert live.wait() is None
            assert live.process.poll() is not None
            timer.join()
    finally:
        signal.signal(signal.SIGINT, before)
    with serve(scene) as live:
        live.process.terminate()
        assert live.wait() == -signal.SIGTERM


# --------------------------------------------------------------------------------- cli

def run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="machinesim")
    add_view_parser(parser.add_subparsers(dest="command", required=True))
    return run_view(parser.parse_args(["view", *argv]))


def test_cli_exports_a_machine_a_part_and_a_report_folder(tmp_path, capsys):
    program = tmp_path / "grooves.nc"
    program.write_text("G90 G21\nG00 X-0.2 Y0.4 Z0.1\nG00 Z-0.02\nG01 X1.2 F500\n"
                       "G00 Z0.1\nM30\n")
    assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK,
                "--tool", "v:150", "--max-triangles", str(BUDGET),
                "--html", str(tmp_path / "m.html")]) == 0
    assert "self-contained" in capsys.readouterr().out

    part, report = cut(grooves(), "grooving_4axis", tool="v:150", stock=STOCK, errors=ERRORS)
    nominal, _ = cut(grooves(), "grooving_4axis", tool="v:150", stock=STOCK)
    part.export_ply(tmp_path / "part.ply")
    nominal.export_ply(tmp_path / "nominal.ply")
    (tmp_path / "report.json").write_text(json.dumps(report.to_dict()))
    assert run([str(tmp_path / "part.ply"), "--report", str(tmp_path / "report.json"),
                "--nominal", str(tmp_path / "nominal.ply"), "--max-triangles", str(BUDGET),
                "--html", str(tmp_path / "p.html")]) == 0
    text = (tmp_path / "p.html").read_text(encoding="utf-8")
    assert "removed_volume_mm3" in text and "deviation from nominal" in text

    folder = tmp_path / "report"
    folder.mkdir()
    for name in ("nominal.ply", "part.ply"):
        (folder / name).write_bytes((tmp_path / name).read_bytes())
    (folder / "summary.json").write_text(json.dumps({"pv_nm": 123.0}))
    assert run([str(folder), "--max-triangles", str(BUDGET),
                "--html", str(tmp_path / "r.html")]) == 0
    text = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert "pv_nm: 123" in text and "part.ply: deviation from nominal" in text
    assert "coloured by deviation from nominal.ply" in text


def test_cli_refuses_bad_input_with_a_clear_message(tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InputError, match="no part meshes"):
        run([str(empty), "--html", str(tmp_path / "x.html")])
    with pytest.raises(InputError, match="no such part file"):
        run([str(tmp_path / "missing.ply"), "--html", str(tmp_path / "x.html")])
    with pytest.raises(InputError, match="^--program does not apply to a part; see"):
        run([str(tmp_path / "missing.ply"), "--program", "p.nc"])
    # it read "--report, --nominal do(es) not apply to a machine"
    with pytest.raises(InputError, match="^--report and --nominal do not apply to a machine; "):
        run(["robonano_a0ib", "--report", "r.json", "--nominal", "n.ply"])
    with pytest.raises(InputError, match="^--program, --report and --nominal do not apply to "
                       "a report folder; "):
        run([str(empty), "--program", "p.nc", "--report", "r.json", "--nominal", "n.ply"])
    with pytest.raises(InputError, match="expected a file name ending in .html"):
        run(["robonano_a0ib", "--html", str(tmp_path / "x.png")])
    # headless Chromium shows ERR_UNSAFE_PORT for 6000 (X11) and 6665 (IRC): the server
    # started and the screenshot failed with 'the page raised: Uncaught'
    for port in ("6000", "6665"):
        with pytest.raises(InputError, match=f"--port {port}: browsers refuse to open pages"):
            run(["robonano_a0ib", "--port", port])
    with pytest.raises(ModelError, match="unknown machine 'nosuch'"):
        run(["nosuch", "--html", str(tmp_path / "x.html")])
    with pytest.raises(InputError, match="reads parts as float64 PLY .*not .stl"):
        run([str(tmp_path / "part.stl"), "--html", str(tmp_path / "x.html")])
    # a part saved under another ending was 'unknown machine', as if a name were misspelt
    (tmp_path / "part.dat").write_bytes(stock_from_spec("block:1x1x1").encode("ply"))
    with pytest.raises(InputError, match=r"part.dat: expected a part file ending in \.ply, a "
                                         r"machine's \.urdf or a report folder"):
        run([str(tmp_path / "part.dat"), "--html", str(tmp_path / "x.html")])
    assert not list(tmp_path.glob("*.html"))


def test_view_reads_a_program_as_cut_reads_it_and_refuses_a_second_tool(tmp_path, monkeypatch,
                                                                       capsys):
    import machinesim.viewer.machine as viewer_machine
    from machinesim.nc import read_program

    program = tmp_path / "integers.nc"
    program.write_text("G90 G21\nG00 X-200 Y400 Z100\nG00 Z-20\nG01 X1200 F500\n"
                       "G02 X1400 Y600 R200\nG00 Z100\nM30\n")
    seen = {}

    def capture(machine, program, **kwargs):
        seen.update(program=program, **kwargs)
        return Scene("captured")

    monkeypatch.setattr(viewer_machine, "machine_scene", capture)
    assert run(["grooving_4axis", "--program", str(program), "--integer-input", "increment",
                "--chord-nm", "3", "--stock", STOCK, "--html", str(tmp_path / "m.html")]) == 0
    # increment input: X1200 is 1.2 um; the arc split within the 3 nm asked for
    home = load_machine("grooving_4axis").home
    expected = read_program(program, integer_input="increment", chord_tolerance=3 * 1e-9,
                            reference=dict(zip("XYZC", home, strict=True)))
    assert seen["program"].moves == expected.moves
    assert seen["chord_tolerance"] == 3 * 1e-9
    # with G21 nothing is noted; without it the unit it was read in is (as cut notes it)
    assert "G20" not in capsys.readouterr().err
    program.write_text(program.read_text().replace("G90 G21", "G90"))
    assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK,
                "--html", str(tmp_path / "m.html")]) == 0
    assert ("note: the program selects neither G20 (inch) nor G21 (mm): its lengths were "
            "read in mm" in capsys.readouterr().err)
    assert expected.targets[2, 0] == pytest.approx(1.2e-6, rel=1e-12)

    tools = tmp_path / "tools.toml"
    tools.write_text("[tool.1]\nlength_mm = 2.5\n")
    changed = tmp_path / "changed.nc"
    changed.write_text("G90 G21\nT1 M06\nG00 G43 H1 Z1.\nG01 X0.5 F500\nM30\n")
    with pytest.raises(InputError, match="T1 at line 2 .*length 2.5 mm.*machinesim cut --tools"):
        run(["grooving_4axis", "--program", str(changed), "--tools", str(tools),
             "--html", str(tmp_path / "t.html")])
    with pytest.raises(InputError, match="--integer-input read a program: give one"):
        run(["grooving_4axis", "--integer-input", "increment"])
    with pytest.raises(InputError, match="--chord-nm does not apply to a part"):
        run([str(tmp_path / "missing.ply"), "--chord-nm", "2"])


def test_cli_refuses_a_display_budget_no_page_holds_naming_the_option(tmp_path):
    # --max-triangles 1000000000 ended in the height map's "Expected at most 1e+08 samples in
    # one reading (MAX_SAMPLES) ... take fewer x or y samples", and 10**20 in "out of memory:
    # ... a cut of many sweeps whose faces nearly coincide", neither naming the option
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    most = ((1 << 29) - 24) // 30  # V8's longest string, ~30 characters a triangle
    for budget in (0, most + 1, 10**9, 10**20):
        with pytest.raises(InputError) as info:
            run([str(tmp_path / "part.ply"), "--max-triangles", str(budget),
                 "--html", str(tmp_path / "p.html")])
        assert str(info.value) == (
            f"--max-triangles {budget}: expected a count from 1 to {most:,} (a page holds "
            "about 30 characters a triangle, and a browser's JavaScript engine reads at most "
            "536,870,888: more opens blank)")
    assert not (tmp_path / "p.html").exists()


def test_cli_refuses_tool_stock_and_duration_where_no_program_runs(tmp_path):
    # `view robonano_a0ib --tool v:90 --stock block:1x1x1 --duration 5`, and the same on a
    # part or a report folder, took the three and ignored them: the page showed the machine
    # (or the part) alone and the command exited 0
    page = str(tmp_path / "x.html")
    for given in (["--tool", "v:90"], ["--stock", "block:1x1x1", "--duration", "5"]):
        names, joined = ", ".join(given[::2]), " and ".join(given[::2])
        with pytest.raises(InputError, match=f"^{names} (is|are) for the program the machine "
                                             "runs .*: give one with --program$"):
            run(["robonano_a0ib", *given, "--html", page])
        with pytest.raises(InputError, match=f"^{joined} do(es)? not apply to a part"):
            run([str(tmp_path / "part.ply"), *given, "--html", page])
        with pytest.raises(InputError, match=f"^{joined} do(es)? not apply to a report folder"):
            run([str(tmp_path), *given, "--html", page])
    assert list(tmp_path.iterdir()) == []
    # the machine alone, and with its errors, is shown as before
    errors = Path(__file__).resolve().parents[1] / "models" / "errors" / "example.toml"
    assert run(["robonano_a0ib", "--errors", str(errors), "--html", page]) == 0


def test_a_report_folders_summary_of_another_schema_version_is_refused(tmp_path):
    # report_scene read summary.json's keys as this version's whatever its schema_version
    # (a newer machinesim's report was shown as if of version 1); read_summary refuses it
    from machinesim.report import read_summary
    from machinesim.viewer import report_scene

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    summary = tmp_path / "summary.json"
    for version in (1, None):  # none: written before the field, read as version 1
        summary.write_text(json.dumps({"pv_nm": 123.0} if version is None
                                      else {"schema_version": version, "pv_nm": 123.0}))
        assert "pv_nm: 123" in report_scene(tmp_path, BUDGET).notes
    for version, newer in ((2, True), ("1", False), (True, False)):
        summary.write_text(json.dumps({"schema_version": version, "pv_nm": 123.0}))
        with pytest.raises(InputError) as info:
            report_scene(tmp_path, BUDGET)
        with pytest.raises(InputError) as read:
            read_summary(summary)
        assert info.value.key == read.value.key == "schema_version"
        assert info.value.source == str(summary)
        assert info.value.message == read.value.message  # the same check's words
        assert ("written by a newer machinesim" in info.value.message) is newer


def test_a_report_folder_whose_summary_names_a_missing_nominal_is_warned_about(tmp_path):
    # the parts were coloured by height, as if no nominal had been named, without a word
    from machinesim.viewer import report_scene

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "nom.ply")
    summary = tmp_path / "summary.json"
    (tmp_path / "sub").mkdir()
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "sub" / "nom.ply")
    # a file, but not one of the folder's parts: "sub/nom.ply" and an absolute path were
    # coloured by height without a word
    for named in ("nominal.ply", ["nom.ply"], "sub/nom.ply", str(tmp_path / "sub" / "nom.ply")):
        summary.write_text(json.dumps({"nominal_ply": named}))
        scene = report_scene(tmp_path, BUDGET)
        assert scene.warnings == [f"{summary} names the nominal part {named!r} (nominal_ply), "
                                  "which is not a file in the folder: each part is coloured "
                                  "by its height, not by its deviation"]
        assert [legend.title for legend in scene.legends] == [
            "nom.ply: height z (workpiece frame)", "part.ply: height z (workpiece frame)"]
    summary.write_text(json.dumps({"nominal_ply": "nom.ply"}))
    scene = report_scene(tmp_path, BUDGET)
    assert scene.warnings == []
    assert [legend.title for legend in scene.legends] == [
        "part.ply: deviation from nominal (height, part - nominal)"]
    # the nominal a folder under a part's name: refused as such a part is, where the parts
    # had been coloured by height without a word
    for name in ("nominal_dir.ply", "nominal.ply"):
        (tmp_path / name).mkdir()
        summary.write_text(json.dumps({"nominal_ply": name} if name != "nominal.ply" else {}))
        with pytest.raises(InputError, match=f"{name}: is a folder; expected a PLY part file"):
            report_scene(tmp_path, BUDGET)
        (tmp_path / name).rmdir()


def test_a_report_of_another_part_file_is_warned_about(tmp_path, capsys):
    # a report from another run was shown beside the part without a word
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "nominal.ply")
    report = tmp_path / "report.json"
    report.write_text(json.dumps({"removed_volume_mm3": 0.026, "part_file": "part.ply",
                                  "part_unit": "m"}))
    assert run([str(tmp_path / "nominal.ply"), "--report", str(report),
                "--html", str(tmp_path / "n.html")]) == 0
    err = capsys.readouterr().err
    assert (f"warning: the report {report} describes the part file 'part.ply', not "
            "nominal.ply: its figures may be of another cut") in err
    assert "gives the part in" not in err
    report.write_text(json.dumps({"part_file": "sub/nominal.stl", "part_unit": "mm"}))
    assert run([str(tmp_path / "nominal.ply"), "--report", str(report),
                "--html", str(tmp_path / "n.html")]) == 0
    err = capsys.readouterr().err
    assert "'sub/nominal.stl', not nominal.ply" in err
    assert f"the report {report} gives the part in 'mm'; a PLY part is read in metres" in err
    report.write_text(json.dumps({"part_file": "sub/nominal.ply", "part_unit": "m"}))
    assert run([str(tmp_path / "nominal.ply"), "--report", str(report),
                "--html", str(tmp_path / "n.html")]) == 0
    assert "warning" not in capsys.readouterr().err


def test_a_program_beyond_the_travel_is_refused_naming_the_command_that_cuts_it(tmp_path):
    # view has no --allow-overtravel: the message sent its user to an option it refuses
    program = tmp_path / "far.nc"
    program.write_text("G90 G21\nG00 X0 Y0 Z1.\nG01 Z-0.01 F100.\nG01 X500. F1000.\n"
                       "G00 Z1.\nM30\n")
    parser = add_view_parser(argparse.ArgumentParser().add_subparsers())
    assert "--allow-overtravel" not in parser.format_help()
    with pytest.raises(AxisLimitError, match=r"axis X = 500\.000000 mm at line 4 outside its "
                                             r"travel -140\.000000 mm \.\. 140\.000000 mm.*"
                                             r"machinesim cut --allow-overtravel"):
        run(["robonano_a0ib", "--program", str(program), "--html", str(tmp_path / "f.html")])
    assert not (tmp_path / "f.html").exists()


def test_a_program_that_misses_the_stock_is_warned_on_the_page_and_on_stderr(tmp_path, capsys):
    # the grooves run at Y 0.4 mm: on a block 0.8 mm wide they cut, moved 5 mm aside they miss
    program = tmp_path / "grooves.nc"
    program.write_text("G90 G21\nG00 X-0.2 Y0.4 Z0.1\nG00 Z-0.02\nG01 X1.2 F500\n"
                       "G00 Z0.1\nM30\n")
    for stock, missed in ((STOCK, False), ("block:1x0.8x0.5@5,5,-0.5", True)):
        page = tmp_path / f"{missed}.html"
        assert run(["grooving_4axis", "--program", str(program), "--stock", stock,
                    "--tool", "v:150", "--max-triangles", str(BUDGET), "--html",
                    str(page)]) == 0
        err = capsys.readouterr().err
        assert ("warning: the program removed no material" in err) == missed
        assert ("<b>warning:</b> the program removed no material"
                in page.read_text(encoding="utf-8")) == missed


def test_a_program_without_moves_is_said_to_have_none_not_to_miss_the_stock(tmp_path,
                                                                           capsys):
    # '%', '%' (or a dwell alone) cut nothing; the page sent its user to --stock's placement
    # ("does it reach the stock?"), where machinesim cut says the program has no moves
    for name, text in (("none", "%\n%\n"), ("dwell", "G90 G21\nG04 P500\nM30\n")):
        program, page = tmp_path / f"{name}.nc", tmp_path / f"{name}.html"
        program.write_text(text)
        assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK,
                    "--tool", "v:150", "--max-triangles", str(BUDGET), "--html",
                    str(page)]) == 0
        err = capsys.readouterr().err
        said = "the program has no moves (no G00/G01/G02/G03 block that runs)"
        assert f"warning: {said}" in err and "does it reach" not in err, err
        assert f"<b>warning:</b> {said}" in page.read_text(encoding="utf-8")


def test_a_program_that_takes_the_whole_stock_animates_and_says_nothing_is_left(tmp_path,
                                                                             capsys):
    # a 60 mm face mill 3 mm down across a 10 x 10 x 2 mm block takes all of it (200 mm^3,
    # as machinesim cut measures): the page had ended in "machinesim: error: the part has no
    # vertices" after a RuntimeWarning of NaN bounds; 1 mm down it draws the finished part
    for depth, gone in ((3.0, True), (1.0, False)):
        program, page = tmp_path / f"face{depth:g}.nc", tmp_path / f"face{depth:g}.html"
        program.write_text(f"G90 G21 G17\nG00 X-40. Y5. Z1.\nG01 Z-{depth:g} F200.\n"
                           "X50.\nG00 Z1.\nM30\n")
        assert run(["grooving_4axis", "--program", str(program), "--stock", "block:10x10x2",
                    "--tool", "flat:30:h=20", "--max-triangles", str(BUDGET), "--html",
                    str(page)]) == 0
        err = capsys.readouterr().err
        # cut()'s note (`nothing_left_note`), by its rule and in its words: the viewer had
        # decided for itself, 'the program removed all of it, so no finished part is drawn'
        said = ("nothing of the stock is left: the cut removed all of it (200 mm^3), and the "
                "part has no faces (a tool wider than the part, or a depth below its bottom?); "
                "no finished part is drawn")
        assert (f"warning: {said}" in err) == gone, err
        assert (f"<b>warning:</b> {said}" in page.read_text(encoding="utf-8")) == gone


def test_a_program_view_notes_how_its_text_was_read_as_cut_does(tmp_path, capsys):
    # X-1 Y0.4 Z0.1 without a decimal point read as mm, a file without M30 and text after
    # its closing %: machinesim cut notes each; view noted only a missing G20/G21
    program = tmp_path / "grooves.nc"
    program.write_text("%\nG90 G21\nG00 X-1 Y0.4 Z0.1\nG00 Z-0.02\nG01 X1.2 F500\n"
                       "G00 Z0.1\n%\nG00 X5.\n")
    offset = tmp_path / "g55.nc"  # a work offset the command line is not given
    offset.write_text("G90 G21 G55\nG00 X-0.2 Y0.4 Z0.1\nG01 Z-0.02 F500.\nX1.2\nM30\n")
    assert run(["grooving_4axis", "--program", str(offset), "--stock", STOCK, "--tool",
                "v:150", "--max-triangles", str(BUDGET), "--html",
                str(tmp_path / "o.html")]) == 0
    assert ("note: G55 at line 1 selects a work offset this command is not given: taken as "
            "zero, the same as G54") in capsys.readouterr().err
    assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK, "--tool",
                "v:150", "--max-triangles", str(BUDGET), "--html",
                str(tmp_path / "g.html")]) == 0
    err = capsys.readouterr().err
    assert ("note: numbers without a decimal point (X at line 3) were read in mm and deg "
            "(calculator-type input, the default)") in err, err
    assert "note: the program has no M30 or M02 (its last move is at line 6)" in err, err
    assert "note: the text from line 8 on, after the % that ends the program" in err, err


def test_a_program_view_notes_its_arcs_split_coarser_than_1_nm_as_cut_does(tmp_path, capsys):
    # an arc under a ball end mill is split within 100 nm by default (a tenth of its 1 um
    # facets): machinesim cut notes it, view noted nothing; --chord-nm given, neither does
    program = tmp_path / "arc.nc"
    program.write_text("G90 G21 G17\nG00 X0.2 Y0.4 Z0.1\nG02 X0.6 Y0.4 I0.2 J0. F500.\nM30\n")
    said = ("note: arcs and rotary moves were split into chords within 100 nm, a tenth of the "
            "tool's own facets (--chord-nm sets it; docs/cutting.md)")
    for chord in ((), ("--chord-nm", "100")):
        assert run(["grooving_4axis", "--program", str(program), "--stock", STOCK, "--tool",
                    "ball:0.5", *chord, "--max-triangles", str(BUDGET), "--html",
                    str(tmp_path / "a.html")]) == 0
        err = capsys.readouterr().err
        assert (said in err) == (not chord), err


def test_a_report_folder_not_yet_written_is_no_such_folder(tmp_path):
    # docs/viewer.md's `machinesim view reports/tool_rotation_arm/` before the scenario ran
    # said "unknown machine 'reports/tool_rotation_arm/'", as if a machine name were misspelt
    missing = str(tmp_path / "reports" / "tool_rotation_arm") + "/"
    with pytest.raises(InputError) as caught:
        run([missing, "--html", str(tmp_path / "x.html")])
    assert str(caught.value) == (
        f"{missing}: no such file or folder; expected a machine name (see 'machinesim "
        "machines'), a machine's .urdf, a part .ply or a report folder")
    assert not list(tmp_path.glob("*.html"))


def test_a_part_with_no_extent_in_x_or_y_is_refused_naming_its_file(tmp_path):
    # a PLY whose triangles all stand in the plane y = 0 was refused as "the part has no
    # extent in x or y: bounds [0.0, 0.0] .. [1.0, 0.0] m", naming no file: in a report
    # folder of several parts, which one?
    sliver = tmp_path / "sliver.ply"
    sliver.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                      "property double y\nproperty double z\nelement face 1\n"
                      "property list uchar int vertex_indices\nend_header\n"
                      "0 0 0\n0.001 0 0\n0 0 0.001\n3 0 1 2\n")
    expected = (f"{sliver}: the part spans x 0 .. 1 mm, y 0 .. 0 mm: expected an extent in "
                "both x and y, a top surface to map")
    with pytest.raises(InputError) as caught:
        run([str(sliver), "--html", str(tmp_path / "x.html")])
    assert str(caught.value) == expected
    folder = tmp_path / "report"
    folder.mkdir()
    stock_from_spec("block:1x1x1").export_ply(folder / "a.ply")
    (folder / "sliver.ply").write_bytes(sliver.read_bytes())
    with pytest.raises(InputError) as caught:
        run([str(folder), "--html", str(tmp_path / "x.html")])
    assert str(caught.value) == expected.replace(str(sliver), str(folder / "sliver.ply"))
    assert not list(tmp_path.glob("*.html"))


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


def _unused_port() -> int:
    """A port the system has just given out and taken back: beyond the ports from 7000 that
    other live viewers (a test running beside this one) take first, so that a closed server's
    URL is not answered by another's."""
    import socket

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _stopped_live_view(tmp_path, stop, **popen) -> tuple[int, str, str]:
    """Run a live `machinesim view` of a 1 mm block, ``stop(process)`` it once it gives its
    address, and return its exit status, its stderr and the address (it is killed after
    60 s if it does not end)."""
    import subprocess
    import sys

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    process = subprocess.Popen([sys.executable, "-m", "machinesim.cli", "view",
                                str(tmp_path / "part.ply"), "--port", str(_unused_port())],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env=env, **popen)
    try:
        line = process.stdout.readline()
        assert line.startswith("machinesim viewer at http://127.0.0.1:"), line
        stop(process)
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    return process.returncode, err, line.split()[3]


def test_a_live_viewer_stopped_by_sigterm_exits_143_and_ends_its_server(tmp_path):
    # `kill PID` of a live `machinesim view` exited 0 with no word (LiveSession.wait took
    # SIGTERM for a Ctrl-C), where docs/cli.md gives 143 and 'machinesim: terminated'
    import signal

    status, err, url = _stopped_live_view(tmp_path, lambda p: p.send_signal(signal.SIGTERM))
    assert status == 143
    assert err == "machinesim: terminated; nothing was written\n"
    with pytest.raises(OSError):
        urllib.request.urlopen(url, timeout=5)


@pytest.mark.parametrize("group", [False, True], ids=["viewer", "terminal"])
def test_a_live_viewer_stopped_by_ctrl_c_exits_130_and_ends_its_server(group, tmp_path,
                                                                       as_in_a_terminal):
    # Ctrl-C of a live `machinesim view` exited 0 with no word (LiveSession.wait returned
    # None, and the command went on to 'return 0'), where every command interrupted exits
    # 130 with 'machinesim: interrupted; nothing was written' (docs/cli.md; `machinesim cut`
    # so). SIGINT to the viewer alone, and to its process group as a terminal's Ctrl-C
    # sends it, to the server too
    import signal

    def ctrl_c(process):
        if group:
            os.killpg(process.pid, signal.SIGINT)
        else:
            process.send_signal(signal.SIGINT)

    status, err, url = _stopped_live_view(tmp_path, ctrl_c, start_new_session=group,
                                          **as_in_a_terminal)
    assert status == 130
    assert err == "machinesim: interrupted; nothing was written\n"
    with pytest.raises(OSError):
        urllib.request.urlopen(url, timeout=5)


def test_a_live_viewer_stopped_after_its_screenshot_says_the_screenshot_stays(tmp_path,
                                                                           as_in_a_terminal):
    # with --screenshot written, 'nothing was written' would be false: the line names it.
    # Chromium is stood in for by a _screenshot that writes the file (the browser test
    # runs the real one)
    import signal
    import subprocess
    import sys

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    shot = tmp_path / "live.png"
    script = ("import sys\n"
              "import machinesim.viewer.cli as view\n"
              "def fake(url, ready, path):\n"
              "    path.write_bytes(b'png')\n"
              "view._screenshot = fake\n"
              "from machinesim.cli import main\n"
              "sys.exit(main(sys.argv[1:]))\n")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    process = subprocess.Popen([sys.executable, "-c", script, "view", str(tmp_path / "part.ply"),
                                "--screenshot", str(shot)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env=env,
                               **as_in_a_terminal)
    try:
        assert process.stdout.readline().startswith("machinesim viewer at http://127.0.0.1:")
        assert process.stdout.readline() == f"wrote {shot} (headless Chromium)\n"
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 130
    assert err == (f"machinesim: interrupted; the viewer stopped, its screenshot {shot} "
                   "written before\n")
    assert shot.read_bytes() == b"png"


def test_a_page_written_before_its_screenshot_is_named_when_a_ctrl_c_stops_the_screenshot(
        tmp_path, capsys, monkeypatch):
    """``view --html P --screenshot S`` stopped while Chromium renders S: the page was written
    whole first (its 'wrote' line is on stdout), and the last line names it. It said
    'interrupted; nothing was written' beside the page. Chromium is stood in for by a
    _screenshot that is interrupted."""
    import machinesim.viewer.cli as view
    from machinesim.cli import main

    def interrupted(url, ready, path):
        raise KeyboardInterrupt

    monkeypatch.setattr(view, "_screenshot", interrupted)
    page, shot = tmp_path / "v.html", tmp_path / "v.png"
    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    assert main(["view", str(tmp_path / "part.ply"), "--html", str(page), "--screenshot",
                 str(shot)]) == 130
    out, err = capsys.readouterr()
    assert out.startswith(f"wrote {page} (")
    assert err == (f"machinesim: interrupted; {page} was written whole before it; nothing "
                   "else was written\n")
    assert page.read_text().startswith("<!DOCTYPE html>") and not shot.exists()


#: A stand-in live server: the real one (`machinesim.viewer.server`), which ends by itself half
#: a second after a browser fetched its page, as a crash (exit status 3), as the kernel's
#: out-of-memory killer ends it (SIGKILL), or with a Python error out of its loop (its loop
#: stopped, then an exception raised: exit status 1 and a traceback on stderr), with no
#: Ctrl-C. ``{chat}`` lines of 100 characters go to stderr as the page is served.
STAND_IN_SERVER = ("import os, signal, sys, threading\n"
                   "import tornado.ioloop\n"
                   "import machinesim.viewer.server as server\n"
                   "page = server.LoopbackBridge.page\n"
                   "def served(self):\n"
                   "    loop = tornado.ioloop.IOLoop.current()\n"
                   "    for i in range({chat}):\n"
                   "        print(f'chat {{i:06d}} ' + 'x' * 88, file=sys.stderr)\n"
                   "    threading.Timer(0.5, lambda: {end}).start()\n"
                   "    return page(self)\n"
                   "server.LoopbackBridge.page = served\n"
                   "server.main(sys.argv[1:])\n"
                   "{after}\n")
#: The stand-in's crash: an exception after its loop was stopped.
CRASH = {"end": "loop.add_callback(loop.stop)",
         "after": "raise RuntimeError('the stand-in server crashed')"}


@pytest.mark.parametrize(("end", "said", "shot", "chat", "traceback"), [
    ("os._exit(3)", "exit status 3", False, 0, False),
    ("os.kill(os.getpid(), signal.SIGKILL)", "killed by SIGKILL", False, 0, False),
    ("os.kill(os.getpid(), signal.SIGKILL)", "killed by SIGKILL; its last line on stderr: "
                                             f"chat 000002 {'x' * 88}", False, 3, False),
    ("os._exit(3)", "exit status 3", True, 0, False),
    ("os._exit(3)", "exit status 3", False, 3, False),
    (CRASH, "exit status 1; its last line on stderr: RuntimeError: the stand-in server "
            "crashed", False, 0, False),
    (CRASH, "exit status 1; its last line on stderr: RuntimeError: the stand-in server "
            "crashed", False, 20000, True)],
    ids=["exit", "killed", "killed-chatty", "screenshot", "exit-chatty", "raised",
         "chatty-traceback"])
def test_a_live_viewer_whose_server_ends_by_itself_says_so_and_exits_1(
        end, said, shot, chat, traceback, tmp_path):
    # a server that died while serving (not by Ctrl-C) left `machinesim view` to exit 0
    # without a word, its page gone; now one line with the server's exit code, status 1,
    # naming a --screenshot written before (Chromium stood in for as above). A server that
    # raised (its stderr had gone to /dev/null) said 'exit status 1' alone: the line now
    # ends with its exception. 20000 lines (2 MB, 30 times a pipe's 64 KiB) written to
    # stderr while the page is served stall no server; with MACHINESIM_TRACEBACK=1 the first
    # and last lines of it come first, the traceback whole at their end. Lines
    # without a traceback are no cause, and are not told (meshcat's 'Port: 6002 in use,
    # trying another...' had been, beside a server killed, when tests ran side by side),
    # but for a server killed by a signal, which can leave no traceback: its last line,
    # which had been lost, is told (meshcat's port line never is).
    import contextlib
    import subprocess
    import sys

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    ending = end if isinstance(end, dict) else {"end": end, "after": ""}
    server = STAND_IN_SERVER.format(chat=chat, **ending)
    script = ("import sys\n"
              "import machinesim.viewer.cli as view\n"
              "view._screenshot = lambda url, ready, path: path.write_bytes(b'png')\n"
              "import machinesim.viewer.live as live\n"
              "live.server_command = lambda port=None: [sys.executable, '-u', '-c', "
              f"{server!r}, *([] if port is None else ['--port', str(port)])]\n"
              "from machinesim.cli import main\n"
              "sys.exit(main(sys.argv[1:]))\n")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    env.pop("MACHINESIM_TRACEBACK", None)
    if traceback:
        env["MACHINESIM_TRACEBACK"] = "1"
    png = tmp_path / "live.png"
    process = subprocess.Popen([sys.executable, "-c", script, "view", str(tmp_path / "part.ply"),
                                "--port", str(_unused_port()),
                                *(["--screenshot", str(png)] if shot else [])],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = process.stdout.readline()
        assert line.startswith("machinesim viewer at http://127.0.0.1:"), line
        url = line.split()[3]
        with contextlib.suppress(OSError):  # the page, as a browser fetches it: the end's cue
            urllib.request.urlopen(url, timeout=10).close()
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 1
    kept = f"; its screenshot {png} written before" if shot else ""
    told = (f"machinesim: error: the live viewer server ended without Ctrl-C ({said}); "
            f"{url} no longer answers{kept}\n")
    if not traceback:
        assert err == told
    else:  # the server's own lines first: the chat's start, a gap, its end, the traceback
        from machinesim.viewer.live import STDERR_FIRST_LINES, STDERR_LAST_LINES

        lines = err.splitlines(keepends=True)
        assert lines[-1] == told and len(lines) == STDERR_FIRST_LINES + STDERR_LAST_LINES + 2
        gap = lines[STDERR_FIRST_LINES]  # the lines before it are the chat's (after
        assert re.fullmatch(r"\.\.\. \d+ lines left out \.\.\.\n", gap)  # meshcat's)
        before, after = (int(lines[at].split()[1]) for at in (STDERR_FIRST_LINES - 1,
                                                               STDERR_FIRST_LINES + 1))
        assert int(gap.split()[1]) == after - before - 1
        assert "Traceback (most recent call last):\n" in lines
        start = lines.index("Traceback (most recent call last):\n")
        assert lines[start - 1] == f"chat {chat - 1:06d} " + "x" * 88 + "\n"
        assert lines[-2] == "RuntimeError: the stand-in server crashed\n"
    assert png.exists() == shot


def test_a_port_in_use_is_named(tmp_path):
    # 'machinesim view PART --port 7000' with 7000 taken said "... Address already in use;
    # is the port free? try --port, ...", not naming the port the user had given
    import socket

    held = socket.socket()
    try:
        held.bind(("127.0.0.1", 0))
        held.listen()
        port = held.getsockname()[1]
        stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
        with pytest.raises(MachineSimError) as caught:
            run([str(tmp_path / "part.ply"), "--port", str(port)])
    finally:
        held.close()
    assert str(caught.value) == (
        f"--port {port}: the live viewer server did not start on it (it ended before giving "
        "its address: OSError: [Errno 98] Address already in use); expected a free port: try "
        "another, or --html FILE to export instead")


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


def test_a_report_folders_figures_are_a_table_of_name_before_after_and_unit(tmp_path):
    # the overlay showed a summary's figures as one line of raw dicts ("figures: [{'name':
    # 'depth_error', 'unit': 'um', ...}]"), or "figures: [7 entries]", or (past its first
    # 15 entries) not at all: they are now a table above the notes, to 4 digits, null n/a
    from machinesim.viewer import report_scene
    from machinesim.viewer.scene import overlay_html

    stock_from_spec("block:1x1x1").export_ply(tmp_path / "part.ply")
    figures = [
        {"name": "depth_error", "unit": "um", "before": 1.23456789, "after": -0.0123456,
         "paper_before": 1.2, "paper_after": None, "note": "the groove's depth less design"},
        {"name": "edge_distance_planes_L1_L5", "unit": "deg", "before": None, "after": 2e-5,
         "paper_before": None, "paper_after": None},
    ]
    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"paper": "001", "figures": figures, "seed": 0}))
    scene = report_scene(tmp_path, BUDGET)
    [table] = scene.tables
    assert table.header == ("figure", "before", "after", "unit")
    assert table.rows == (("depth_error", "1.235", "-0.01235", "um"),
                          ("edge_distance_planes_L1_L5", "n/a", "2e-05", "deg"))
    assert scene.notes == ["paper: 001", "seed: 0"]  # the figures are not a note too
    page = overlay_html(scene)
    assert ("<tr><th>figure</th><th>before</th><th>after</th><th>unit</th></tr>\n"
            "<tr><td>depth_<wbr>error</td><td>1.235</td><td>-0.01235</td><td>um</td></tr>"
            in page)
    assert page.index('class="ms-table"') < page.index("<div>paper: 001</div>")
    assert "{'name'" not in page and "figures:" not in page
    # a 'figures' that is no list of named figures stays a note, as any key
    for odd in ([1, 2], {"a": 1.0}, [{"name": "x"}]):
        summary.write_text(json.dumps({"figures": odd}))
        scene = report_scene(tmp_path, BUDGET)
        assert scene.tables == [] and scene.notes[0].startswith("figures"), scene.notes
