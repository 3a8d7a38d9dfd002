"""The viewer in a real browser: headless Chromium (Debian package ``chromium``) draws the
exported page and a live session; the pixels must show the machine, the part and the colour
map. Without Chromium these tests skip, saying so, except under ``CI=true`` (.ci/run installs
Chromium and sets it), where they fail."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
from urllib.parse import urlparse

import numpy as np
import pytest
from PIL import Image

from machinesim import ErrorModel, ToolSetting, load_machine
from machinesim.exceptions import MachineSimError
from machinesim.motion import plan
from machinesim.nc import ProgramBuilder
from machinesim.viewer import Browser, machine_scene, part_scene, report_scene, serve, write_html
from machinesim.viewer.browser import INSTALL_HINT, find_chromium
from machinesim.viewer.scene import OVERLAY_WIDTH_PX
from machinesim.workpiece import Part, block

UM, MM = 1e-6, 1e-3
WIDTH, HEIGHT = 1000, 700
#: Display budget: enough for the colour map to show, small enough for a quick page.
BUDGET = 20_000
ERRORS = ErrorModel(tool=ToolSetting([0.0, 4 * UM, 0.0], [0.0, 0.0, 0.0]))
STOCK = "block:1x0.8x0.5"
#: Hue ranges (degrees) of the colour-map ends (ColorBrewer PRGn: purple 283-292, green
#: 115-138), of the rotary tables' orange (35) and of the part's copper (31), widened for
#: shading; a pixel counts when it is also saturated (S > 0.3) and not dark (V > 0.15).
PURPLE, GREEN, ORANGE = (265.0, 315.0), (100.0, 160.0), (20.0, 45.0)


def running_in_ci() -> bool:
    """True when the CI environment variable says so (CI=true, as CI services set it)."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


@pytest.fixture(scope="module")
def browser():
    try:
        find_chromium()
    except MachineSimError as error:
        if running_in_ci():
            pytest.fail(f"CI=true and headless Chromium is missing, so the browser tests "
                        f"cannot run: {error}")
        pytest.skip(f"headless Chromium not found, browser tests skipped (with CI=true they "
                    f"fail); install it: {INSTALL_HINT}")
    with Browser(WIDTH, HEIGHT) as b:
        yield b


def grooves(n=4, pitch=150 * UM, depth=20 * UM, y0=0.2 * MM, length=1 * MM):
    b = ProgramBuilder(1)
    for i in range(n):
        b.rapid(X=-0.2 * MM, Y=y0 + i * pitch, Z=0.1 * MM).rapid(Z=-depth)
        b.linear(X=length + 0.2 * MM, feed_mm_per_min=500.0).rapid(Z=0.1 * MM)
    return b.build()


def tilted_block(slope: float, length=2 * MM, width=1 * MM, height=0.5 * MM) -> Part:
    """Block [0, L] x [0, W] x [-H, top] whose top is z = slope * (x - L/2)."""
    top = (-slope * length / 2, slope * length / 2)
    vertices = [(x, y, z) for z in ("bottom", "top") for y in (0.0, width)
                for x in (0.0, length)]
    vertices = [(x, y, -height if z == "bottom" else top[int(x > 0)]) for x, y, z in vertices]
    faces = [(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
             (1, 3, 7), (1, 7, 5), (3, 2, 6), (3, 6, 7), (2, 0, 4), (2, 4, 6)]
    return Part.from_mesh(vertices, faces)


def hue_counts(png: bytes, region: str) -> dict[str, int]:
    """Saturated pixels per hue range, in the 3D view right of the overlay or in the overlay."""
    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64) / 255.0
    rgb = rgb[:, OVERLAY_WIDTH_PX + 20:] if region == "view" else rgb[:, :OVERLAY_WIDTH_PX]
    hi, lo = rgb.max(axis=2), rgb.min(axis=2)
    chroma = hi - lo
    saturation = np.divide(chroma, hi, out=np.zeros_like(hi), where=hi > 0)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    safe = np.where(chroma > 0, chroma, 1.0)
    hue = np.where(hi == r, ((g - b) / safe) % 6, np.where(hi == g, (b - r) / safe + 2,
                                                            (r - g) / safe + 4)) * 60.0
    vivid = (saturation > 0.3) & (hi > 0.15) & (chroma > 0)
    return {name: int(np.count_nonzero(vivid & (hue >= a) & (hue <= b)))
            for name, (a, b) in (("purple", PURPLE), ("green", GREEN), ("orange", ORANGE))}


def test_the_exported_machine_page_draws_machine_part_and_colour_map(browser, tmp_path):
    machine = load_machine("grooving_4axis")
    scene = machine_scene(machine, grooves(), tool="v:150", stock=STOCK, errors=ERRORS,
                          max_triangles=BUDGET)
    page = write_html(scene, tmp_path / "machine.html")
    browser.requests.clear()
    browser.open(page.as_uri())
    png = browser.screenshot()
    (tmp_path / "machine.png").write_bytes(png)
    view = hue_counts(png, "view")
    # the orange C table (and the copper part) cover thousands of pixels; the enlarged part
    # beside the machine shows both ends of the deviation scale (the flanks of grooves
    # shifted by 4 um: one flank above nominal, the other below)
    assert view["orange"] > 5000, view
    assert view["purple"] > 300 and view["green"] > 300, view
    legend = hue_counts(png, "overlay")
    assert legend["purple"] > 300 and legend["green"] > 300, legend  # the colour bar
    # nothing but the file itself and inline data was fetched: no server, no network
    assert browser.requests and all(u.startswith(("file:", "data:")) for u in browser.requests)

    # the animation in the browser puts the tool where the kinematics say at the end
    end = browser.evaluate("(() => { const a = viewer.animator; a.pause(); "
                           "a.seek(a.duration); return a.duration; })()")
    position = browser.evaluate(
        "(() => { const w = viewer.scene_tree.find(['meshcat', 'workpiece']).object;"
        " const t = viewer.scene_tree.find(['meshcat', 'tool']).object;"
        " w.updateMatrixWorld(true); t.updateMatrixWorld(true);"
        " const m = w.matrixWorld.clone().invert().multiply(t.matrixWorld);"
        " return [m.elements[12], m.elements[13], m.elements[14]]; })()")
    q_end = plan(grooves(), machine, ERRORS).segments[-1].q[-1]
    assert end > 0
    visible = ("[0, 1, 2, 3, 4].map(k => viewer.scene_tree.find("
               "['meshcat', 'workpiece', 'stages', String(k)]).object.visible)")
    assert browser.evaluate(visible) == [False, False, False, False, True]  # finished
    browser.evaluate("viewer.animator.seek(0)")
    assert browser.evaluate(visible) == [True, False, False, False, False]  # the stock
    # three.js matrices are float32: 1e-9 m on a 1 m scene
    np.testing.assert_allclose(position, machine.tool_pose(q_end, ERRORS)[:3, 3], rtol=0,
                               atol=1e-6)


def test_the_exported_part_page_draws_both_ends_of_the_deviation_scale(browser, tmp_path):
    scene = part_scene(tilted_block(1e-4), nominal=block(2 * MM, 1 * MM, 0.5 * MM),
                       max_triangles=BUDGET)
    page = write_html(scene, tmp_path / "part.html")
    browser.open(page.as_uri())
    png = browser.screenshot()
    view = hue_counts(png, "view")
    # the top is tilted +-100 nm along x: a purple end, a green end (measured ~5000 and
    # ~16000 px: the purple end is the far one), copper sides
    assert view["purple"] > 2000 and view["green"] > 2000, view
    assert view["orange"] > 2000, view
    flat = write_html(part_scene(block(2 * MM, 1 * MM, 0.5 * MM), nominal=block(
        2 * MM, 1 * MM, 0.5 * MM), max_triangles=BUDGET), tmp_path / "flat.html")
    browser.open(flat.as_uri())
    flat_view = hue_counts(browser.screenshot(), "view")
    # no deviation: the map is the scale's neutral middle, neither purple nor green
    assert flat_view["purple"] < 100 and flat_view["green"] < 100, flat_view


#: The overlay's boxes: the column, then each legend panel, (left, top, right, bottom) CSS px.
BOXES = ("JSON.stringify(['#machinesim-overlay', '.ms-legend'].flatMap(q => "
         "[...document.querySelectorAll(q)]).map(e => { const r = e.getBoundingClientRect(); "
         "return [r.left, r.top, r.right, r.bottom]; }))")


def test_every_legend_of_a_report_folder_is_reached_in_an_800_px_window(browser, tmp_path):
    # Seven plates of a paper 001 report folder made seven legends, 1,860 px of them: in an
    # 800 x 600 window the first showed and the rest ran off it, out of reach (the overlay
    # hid its overflow and took no mouse event). Now it is a column within the window that
    # the wheel over it scrolls. (`browser` only skips, or fails under CI, without Chromium.)
    folder = tmp_path / "report"
    folder.mkdir()
    block(2 * MM, 1 * MM, 0.5 * MM).export_ply(folder / "nominal.ply")
    for k in range(4):
        tilted_block((k + 1) * 1e-4).export_ply(folder / f"plate_{k}.ply")
    (folder / "summary.json").write_text(json.dumps({f"figure_{k}_um": 1.5 * k
                                                     for k in range(12)}))
    page = write_html(report_scene(folder, BUDGET), tmp_path / "report.html")
    width, height = 800, 600
    with Browser(width, height) as small:
        small.open(page.as_uri())
        column, *legends = json.loads(small.evaluate(BOXES))
        assert len(legends) == 4
        assert legends[-1][3] > height  # taller than the window: the case in question
        for left, _, right, _ in (column, *legends):
            assert 0 <= left and right <= min(width, 8 + OVERLAY_WIDTH_PX), (column, legends)
        assert 0 <= column[1] and column[3] <= height, column
        for _ in range(8):  # 3,200 px of wheel over the overlay: past its whole height
            small.wheel(150, 300, 400)
        small.wait_for("(() => { const r = [...document.querySelectorAll('.ms-legend')]"
                       ".pop().getBoundingClientRect(); return r.bottom <= innerHeight; })()",
                       timeout=10)
        column, *legends = json.loads(small.evaluate(BOXES))
    left, top, right, bottom = legends[-1]
    assert 0 <= left and right <= width and 0 <= top and bottom <= height, legends


def test_a_report_folders_figures_table_fits_the_overlay_column(browser, tmp_path):
    # the figures of a report folder, a table of name, before, after and unit: within the
    # overlay's column (OVERLAY_WIDTH_PX) beside the 3D view, a long name wrapped, not cut
    # off or spilling over the view; each row holds the four cells as written
    folder = tmp_path / "report"
    folder.mkdir()
    tilted_block(1e-4).export_ply(folder / "part.ply")
    figures = [{"name": f"edge_distance_planes_L{k}_L{k + 4}", "unit": "um",
                "before": 149.8046875 - k, "after": -0.27398563029207984 * k,
                "paper_before": None, "paper_after": None} for k in range(1, 5)]
    (folder / "summary.json").write_text(json.dumps({"figures": figures}))
    page = write_html(report_scene(folder, BUDGET), tmp_path / "report.html")
    browser.open(page.as_uri())
    overlay, table = json.loads(browser.evaluate(
        "JSON.stringify(['#machinesim-overlay', '.ms-table'].map(q => { const r = "
        "document.querySelector(q).getBoundingClientRect(); return [r.left, r.right]; }))"))
    assert overlay[1] <= 8 + OVERLAY_WIDTH_PX and overlay[0] <= table[0] < table[1] <= overlay[1]
    rows = json.loads(browser.evaluate(
        "JSON.stringify([...document.querySelectorAll('.ms-table tr')].map(r => "
        "[...r.cells].map(c => c.textContent)))"))
    assert rows[0] == ["figure", "before", "after", "unit"]
    assert rows[1] == ["edge_distance_planes_L1_L5", "148.8", "-0.274", "um"]
    assert rows[4] == ["edge_distance_planes_L4_L8", "145.8", "-1.096", "um"]


def test_a_live_session_is_drawn_from_127_0_0_1_only(browser):
    scene = part_scene(tilted_block(1e-4), nominal=block(2 * MM, 1 * MM, 0.5 * MM),
                       max_triangles=BUDGET)
    with serve(scene) as live:
        browser.requests.clear()
        browser.open(live.url)
        browser.wait_for(f"viewer.num_messages_received >= {live.messages}")
        png = browser.screenshot()
    view = hue_counts(png, "view")
    assert view["purple"] > 2000 and view["green"] > 2000, view
    assert hue_counts(png, "overlay")["green"] > 300  # the legend, served by the live page
    # page, script and websocket from 127.0.0.1:PORT; inline data: images aside
    hosts = {urlparse(u).netloc for u in browser.requests if urlparse(u).scheme != "data"}
    assert hosts == {urlparse(live.url).netloc}


def test_the_request_log_sees_a_page_reaching_for_a_server(browser, tmp_path):
    """The check above can fail: a page that fetches anything shows up in the log."""
    page = tmp_path / "fetch.html"
    page.write_text('<script>fetch("http://127.0.0.1:9/x").catch(() => 0);</script>')
    browser.requests.clear()
    browser.open(page.as_uri())
    browser.evaluate("new Promise(done => setTimeout(() => done(true), 200))")
    assert "http://127.0.0.1:9/x" in browser.requests


def test_view_in_live_mode_prints_its_url_and_stops_on_ctrl_c(browser, tmp_path,
                                                              as_in_a_terminal):
    tilted_block(1e-4).export_ply(tmp_path / "part.ply")
    script = ("import argparse, sys\n"
              "from machinesim.viewer.cli import add_view_parser, run_view\n"
              "parser = argparse.ArgumentParser()\n"
              "add_view_parser(parser.add_subparsers(dest='command'))\n"
              "sys.exit(run_view(parser.parse_args(sys.argv[1:])))\n")
    process = subprocess.Popen(
        [sys.executable, "-c", script, "view", str(tmp_path / "part.ply"),
         "--max-triangles", str(BUDGET), "--screenshot", str(tmp_path / "live.png")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **as_in_a_terminal)
    try:
        line = process.stdout.readline()
        assert line.startswith("machinesim viewer at http://127.0.0.1:"), line
        url = line.split()[3]
        second = process.stdout.readline()
        if not second.startswith("wrote"):  # the --screenshot PNG; say why it is missing
            process.kill()
            pytest.fail(f"no screenshot line ({second!r}); stderr: "
                        f"{process.communicate(timeout=20)[1]}")
        view = hue_counts((tmp_path / "live.png").read_bytes(), "view")
        assert view["orange"] > 2000, view  # the part's sides: height map is one colour
        browser.open(url)
        assert browser.evaluate("document.title") == "part part.ply"
        os.kill(process.pid, signal.SIGINT)
        # interrupted: 130 (it had been 0), saying the screenshot was written before
        _, err = process.communicate(timeout=20)
        assert process.returncode == 130
        assert err.endswith(f"machinesim: interrupted; the viewer stopped, its screenshot "
                            f"{tmp_path / 'live.png'} written before\n"), err
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
