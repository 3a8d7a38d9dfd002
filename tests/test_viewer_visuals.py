"""A machine's STL visuals: drawn from their files, never read by Pinocchio (`machinesim.viewer
.visuals`), with the scene Pinocchio's own reading gives; loading a machine reads none."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import umsgpack

import machinesim.viewer.visuals as visuals
from machinesim import load_machine
from machinesim.exceptions import InputError
from machinesim.viewer import machine_scene
from machinesim.viewer.scene import Scene

#: One triangle, 10 mm on its sides, as an ASCII STL (m).
_ASCII_STL = ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.01 0 0\n"
              "vertex 0 0.01 0\nendloop\nendfacet\nendsolid t\n")
_UUID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


def binary_stl(count: int) -> bytes:
    """A binary STL of ``count`` triangles fanned around the origin (m)."""
    angles = np.linspace(0.0, 2.0 * np.pi, count + 1)
    rim = 0.02 * np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
    records = np.zeros(count, dtype=[("normal", "<f4", 3), ("v", "<f4", (3, 3)),
                                     ("attribute", "<u2")])
    records["normal"] = (0.0, 0.0, 1.0)
    records["v"][:, 1], records["v"][:, 2] = rim[:-1], rim[1:]
    return b"fan".ljust(80) + np.uint32(count).tobytes() + records.tobytes()


def meshed_machine(folder: Path, visuals_xml: dict[str, str]) -> Path:
    """grooving_4axis with ``visuals_xml[link]`` (visual elements) first in those links,
    written as ``folder``/mill/urdf/mill.urdf (a ROS package's layout)."""
    text = Path(load_machine("grooving_4axis").path).read_text()
    for link, xml in visuals_xml.items():
        text = text.replace(f'<link name="{link}">', f'<link name="{link}">{xml}')
    path = folder / "mill" / "urdf" / "mill.urdf"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def mesh_visual(filename: str, extra: str = "") -> str:
    return (f'<visual><origin xyz="0 0 0.01" rpy="0 0 0.3"/><geometry><mesh '
            f'filename="{filename}"{extra}/></geometry><material name="m"><color '
            'rgba="0.2 0.4 0.6 0.5"/></material></visual>')


def commands(scene: Scene) -> list:
    """The scene's meshcat commands, decoded, with each object's random uuid numbered in
    order of appearance (two scenes of one machine differ in those only)."""
    numbered: dict[str, str] = {}

    def plain(value):
        if isinstance(value, dict):
            return {key: plain(item) for key, item in value.items()}
        if isinstance(value, list):
            return [plain(item) for item in value]
        if isinstance(value, str) and _UUID.fullmatch(value):
            return numbered.setdefault(value, f"uuid{len(numbered)}")
        if isinstance(value, umsgpack.Ext):
            return value.type, value.data
        return value

    return [plain(umsgpack.unpackb(data)) for _, _, data in scene.frames]


@pytest.fixture
def stl_files(tmp_path):
    """STL files where a URDF in mill/urdf/ names them in each way Pinocchio resolves."""
    files = {"mill/urdf/meshes/base.stl": binary_stl(7),
             "mill/meshes/carriage.stl": _ASCII_STL,
             "elsewhere/table.STL": binary_stl(3),
             "mill/urdf/both.stl": binary_stl(4),  # also one folder up: this one is found
             "mill/both.stl": binary_stl(5)}
    for name, data in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        if isinstance(data, str):
            (tmp_path / name).write_text(data)
        else:
            (tmp_path / name).write_bytes(data)
    return meshed_machine(tmp_path, {
        "base": mesh_visual("meshes/base.stl"),
        "y_carriage": mesh_visual("package://mill/meshes/carriage.stl", ' scale="2 2 0.5"'),
        "table": mesh_visual(str(tmp_path / "elsewhere/table.STL"), ' scale="0.001 0.001 1"'),
        "x_carriage": mesh_visual(f"file://{tmp_path}/elsewhere/table.STL"),
        "z_carriage": mesh_visual("both.stl")})


def test_stl_visuals_are_drawn_from_their_files_with_the_scene_pinocchio_gives(
        stl_files, monkeypatch):
    # Pinocchio read every STL visual (coal's collision tree of a 500,000-triangle STL: 8.5
    # s) that the visualizer then sent as the file's bytes: now it gets a placeholder and
    # the geometry object the file's path, and the scene is the one Pinocchio's own reading
    # gives (the second method: no suffix deferred), command for command
    machine = load_machine(stl_files)
    monkeypatch.chdir(stl_files.parents[2])
    deferred = visuals.machine_visuals(machine, Scene("x"))
    lazy = commands(machine_scene(machine))
    monkeypatch.setattr(visuals, "DEFERRED_SUFFIXES", ())
    read = visuals.machine_visuals(machine, Scene("x"))
    assert commands(machine_scene(machine)) == lazy
    stl = {g.name: g for g in read.geometryObjects if g.meshPath.lower().endswith(".stl")}
    assert sorted(stl) == ["base_0", "table_0", "x_carriage_0", "y_carriage_0",
                           "z_carriage_0"]
    for g, r in zip(deferred.geometryObjects, read.geometryObjects, strict=True):
        assert (g.name, g.parentJoint, g.placement.homogeneous.tolist()) == \
            (r.name, r.parentJoint, r.placement.homogeneous.tolist())
        if g.name in stl:  # the same file and scale as Pinocchio's, and no triangle read
            assert (g.meshPath, g.meshScale.tolist()) == (r.meshPath, r.meshScale.tolist())
            assert g.geometry.num_tris == 0 < r.geometry.num_tris
    assert stl["z_carriage_0"].meshPath.endswith("mill/urdf/both.stl")
    assert stl["table_0"].meshScale.tolist() == [0.001, 0.001, 1.0]


def test_an_stl_not_found_or_not_an_stl_is_left_out_with_a_warning_and_the_rest_drawn(
        tmp_path):
    # a missing mesh is named when the view needs it (loading the machine reads no mesh);
    # Pinocchio, failing on one file, left every mesh out and named them all
    (tmp_path / "mill/urdf/meshes").mkdir(parents=True)
    (tmp_path / "mill/urdf/meshes/base.stl").write_bytes(binary_stl(5))
    (tmp_path / "mill/urdf/meshes/cut.stl").write_bytes(binary_stl(5)[:-10])  # cut short
    (tmp_path / "mill/urdf/meshes/text.stl").write_text("not a mesh\n")
    path = meshed_machine(tmp_path, {
        "base": mesh_visual("meshes/base.stl"),
        "table": mesh_visual("package://foo/meshes/table.stl"),
        "y_carriage": mesh_visual("meshes/cut.stl") + mesh_visual("meshes/text.stl")})
    scene = machine_scene(load_machine(path))
    assert scene.warnings == [
        f"{path}: mesh files that could not be loaded, drawn without them: y_carriage "
        "(meshes/cut.stl: not an STL: binary, or text starting 'solid'), y_carriage "
        "(meshes/text.stl: not an STL: binary, or text starting 'solid'), table "
        f"(package://foo/meshes/table.stl: not found) (a relative path is looked up in "
        f"{path.parent}, "
        "package://<package>/... there and in the two folders above it; give the file's "
        "path)"]
    drawn = {c["path"]: c for c in commands(scene) if c["type"] == "set_object"}
    base = drawn["/meshcat/machine/visuals/base_0"]["object"]["geometries"][0]
    assert base["data"][1] == binary_stl(5)  # the file itself
    assert "/meshcat/machine/visuals/y_carriage_0" in drawn  # its box, now first
    assert "/meshcat/machine/visuals/table_0" in drawn


def test_loading_a_machine_reads_no_mesh_file(tmp_path):
    # kinematics only (``machinesim cut``): a machine naming mesh files that are not there
    # loads, and its tool poses are those of the machine without them, bit for bit
    path = meshed_machine(tmp_path, {link: mesh_visual(f"meshes/{link}.stl")
                                     for link in ("base", "table", "x_carriage")})
    machine, plain = load_machine(path), load_machine("grooving_4axis")
    q = np.random.default_rng(3).uniform(plain.lower, plain.upper, (50, len(plain.axes)))
    assert np.array_equal(machine.tool_pose(q), plain.tool_pose(q))


def test_a_page_too_long_for_its_stl_visuals_says_so_not_to_show_fewer_triangles(
        tmp_path, monkeypatch):
    # five 100 MB STLs made a 666,681,453-character script, refused as "show fewer triangles
    # (--max-triangles at least 1.2 times lower)", which budgets the part's map, not them
    import machinesim.viewer.scene as scene_module

    (tmp_path / "mill/urdf/meshes").mkdir(parents=True)
    (tmp_path / "mill/urdf/meshes/base.stl").write_bytes(binary_stl(2000))  # 100,084 bytes
    path = meshed_machine(tmp_path, {"base": mesh_visual("meshes/base.stl"),
                                     "table": mesh_visual("meshes/base.stl")})
    scene = machine_scene(load_machine(path))
    assert scene.mesh_file_bytes == 2 * 100_084
    files = 4 * -(-2 * 100_084 // 3)  # as base64: 266,892 characters
    monkeypatch.setattr(scene_module, "SCRIPT_CHARS_MOST", files)
    with pytest.raises(InputError, match=re.escape(
            "it would open blank; the machine's mesh files (STL, OBJ, DAE visuals) alone are "
            "0.2 MB (266,892 characters), which no --max-triangles makes smaller: give it "
            "mesh files of at most 0.2 MB in all (fewer triangles, decimated in a mesh "
            "tool)")):
        scene.to_html()
    monkeypatch.setattr(scene_module, "SCRIPT_CHARS_MOST", 536_870_888)
    text = scene.to_html()
    script = len(text[text.rindex("<script>\n") + len("<script>\n"):text.rindex("</script>")])
    rest = script - files  # the commands but the files: lowering the budget shrinks these
    monkeypatch.setattr(scene_module, "SCRIPT_CHARS_MOST", files + rest // 2)
    with pytest.raises(InputError, match=re.escape(
            f"show fewer triangles (--max-triangles at least {rest / (rest // 2):.2g} times "
            "lower)")):
        scene.to_html()


def test_an_obj_visual_s_file_counts_in_the_page_as_an_stl_s_does(tmp_path, monkeypatch):
    # Pinocchio reads an OBJ, and its visualizer sends the file's text to the page all the
    # same (4/3 of its bytes as base64, as an STL's): it was not counted, so a page too long
    # for OBJ or DAE visuals was told to lower --max-triangles, which cannot shorten it
    (tmp_path / "mill/urdf/meshes").mkdir(parents=True)
    n = 500
    fan = ["o fan", *(f"v {0.02 * np.cos(2 * np.pi * k / n):.6f} "
                      f"{0.02 * np.sin(2 * np.pi * k / n):.6f} 0" for k in range(n)), "v 0 0 0",
           *(f"f {n + 1} {k + 1} {(k + 1) % n + 1}" for k in range(n))]
    obj = tmp_path / "mill/urdf/meshes/base.obj"
    obj.write_text("\n".join(fan) + "\n")
    (tmp_path / "mill/urdf/meshes/table.stl").write_bytes(binary_stl(10))  # 584 bytes
    path = meshed_machine(tmp_path, {"base": mesh_visual("meshes/base.obj"),
                                     "table": mesh_visual("meshes/table.stl")})
    scene = machine_scene(load_machine(path))
    assert scene.warnings == []
    assert scene.mesh_file_bytes == obj.stat().st_size + 584
    assert machine_scene(load_machine("grooving_4axis")).mesh_file_bytes == 0  # boxes only
    import machinesim.viewer.scene as scene_module

    monkeypatch.setattr(scene_module, "SCRIPT_CHARS_MOST", 4 * -(-scene.mesh_file_bytes // 3))
    with pytest.raises(InputError, match=r"the machine's mesh files \(STL, OBJ, DAE visuals\) "
                                         r"alone are .* no --max-triangles makes smaller"):
        scene.to_html()


def test_a_mesh_that_is_there_but_no_file_is_named_so_not_as_not_found(tmp_path):
    # a folder or a FIFO named .stl had been told, as a missing file is, where relative
    # paths are looked up and to give the file's path
    import os

    (tmp_path / "mill/urdf/meshes/folder.stl").mkdir(parents=True)
    os.mkfifo(tmp_path / "mill/urdf/meshes/pipe.stl")
    path = meshed_machine(tmp_path, {"base": mesh_visual("meshes/folder.stl"),
                                     "table": mesh_visual("meshes/pipe.stl")})
    scene = machine_scene(load_machine(path))
    assert scene.warnings == [
        f"{path}: mesh files that could not be loaded, drawn without them: base "
        "(meshes/folder.stl: not a regular file), table (meshes/pipe.stl: not a regular "
        "file)"]


def test_an_obj_with_a_vertex_not_finite_is_left_out_with_a_warning(tmp_path, capfd):
    # Pinocchio read it, and its solver printed "eigen: too many iterations in Jacobi
    # transform." from C++ on stderr, the view going on with exit 0 and no word of the file
    (tmp_path / "mill/urdf/meshes").mkdir(parents=True)
    (tmp_path / "mill/urdf/meshes/bad.obj").write_text(
        "o t\nv 0 0 0\nv 0.01 0 0\nv 0 1 nan\nf 1 2 3\n")
    path = meshed_machine(tmp_path, {"base": mesh_visual("meshes/bad.obj")})
    scene = machine_scene(load_machine(path))
    assert scene.warnings == [f"{path}: mesh files that could not be loaded, drawn without "
                              "them: base (meshes/bad.obj: a vertex that is not a finite "
                              "number)"]
    assert "eigen" not in capfd.readouterr().err
