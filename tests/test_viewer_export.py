"""The viewer's exported pages: self-contained HTML written whole or refused, and the
warnings a part's page carries (millimetres, single precision, no heights)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from viewer_helpers import BUDGET, ply_bytes, tilted_block

from machinesim.exceptions import InputError
from machinesim.viewer import part_scene, read_ply, write_html
from machinesim.viewer.meshes import triangle_normals
from machinesim.viewer.scene import Scene
from machinesim.viewer.views import report_notes
from machinesim.workpiece import block, stock_from_spec

MM = 1e-3


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
