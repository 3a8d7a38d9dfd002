"""The viewer's scenes without a browser: staged cuts (block by block, ending with the part
`cut` cuts in one go) and the machine scene (every visual, the tool moved as the
kinematics say, its notes, the meshes it cannot load)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import umsgpack
from scipy.spatial.transform import Rotation
from viewer_helpers import BUDGET, ERRORS, STOCK, grooves

from machinesim import ErrorModel, load_machine
from machinesim.cutting import cut
from machinesim.exceptions import InputError
from machinesim.metrology import height_map
from machinesim.motion import plan
from machinesim.nc import ProgramBuilder
from machinesim.tool_specs import tool_from_spec
from machinesim.viewer import cut_by_block, machine_scene
from machinesim.viewer.scene import Scene
from machinesim.workpiece import stock_from_spec

UM, MM = 1e-6, 1e-3


def decoded(scene: Scene) -> list[dict]:
    return [umsgpack.unpackb(data) for _, _, data in scene.frames]


def floats(ext) -> np.ndarray:
    return np.frombuffer(ext.data, dtype=np.float32)


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
                              "them: base (package://foo/meshes/base.stl: not found) (a "
                              f"relative path is looked up in {tmp_path}, package://<package>/"
                              "... there and in the two folders above it; give the file's "
                              "path)"]
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
    # the rotary axes' travel as `machinesim machines` gives it (they read "B rotary")
    assert scene.notes[0] == ("travel: X -140..140 mm, Y -75..75 mm, Z -30..100 mm, "
                              "B -100..100 deg, C -360..360 deg")
    assert machine_scene("sts_lathe").notes[0] == ("travel: X -100..100 mm, Z -50..100 mm, "
                                                   "C spindle")
    with pytest.raises(InputError, match="duration_s and max_stages must be positive"):
        machine_scene("grooving_4axis", grooves(), stock=STOCK, duration_s=0.0)
