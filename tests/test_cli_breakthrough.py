"""`machinesim cut` says when the cut went through the stock's bottom face: the tool went
below the stock, into what holds it. A pocket deeper than the block (a wrong G43 H) leaves a
ring, one piece, which the pieces check passes; it had exited 0 without a word."""

from __future__ import annotations

import json
import math

import pytest

from machinesim.cli import main
from machinesim.cutting.breakthrough import bottom_area, bottom_lost
from machinesim.workpiece import Part, stock_from_spec

#: A Fusion-style square pocket: a 2 mm flat end mill round the square x, y in 4..6 mm
#: leaves a pocket x, y in 3..7 mm with corners of R1: 16 - (4 - pi) mm^2.
POCKET = ("G90 G94 G17 G21\nT1 M6\nG0 X5. Y5.\nG43 Z15. H1\nG0 Z5.\nG1 Z{depth} F200.\n"
          "X6. F400.\nY6.\nX4.\nY4.\nX6.\nY5.\nX5.\nG0 Z15.\nM30\n")
POCKET_MM2 = 16.0 - (4.0 - math.pi)


def run(argv, capsys) -> tuple[int, str, str]:
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def cut(tmp_path, capsys, depth: str, length_mm: float, *extra) -> tuple[int, str, dict]:
    program = tmp_path / "pocket.nc"
    program.write_text(POCKET.format(depth=depth))
    tools = tmp_path / "tools.toml"
    tools.write_text(f'[tool.1]\nlength_mm = {length_mm}\nshape = "flat:1.0"\n')
    report = tmp_path / "pocket.json"
    code, _, err = run(["cut", program, "--machine", "robonano_a0ib", "--tool", "flat:1.0",
                        "--stock", "block:10x10x2", "--tools", tools, "--quiet", "--out",
                        tmp_path / "pocket.ply", "--report", report, *extra], capsys)
    return code, err, (json.loads(report.read_text()) if code == 0 else {})


def test_a_pocket_through_the_bottom_is_warned_about_and_reported(tmp_path, capsys):
    code, err, report = cut(tmp_path, capsys, "-3.", 0.0)
    assert code == 0, err
    assert report["part_pieces_count"] == 1  # a ring: the pieces check says nothing
    # the pocket's area, less what the end mill's facets leave in its corners (< 0.1 %)
    assert report["bottom_cut_through_mm2"] == pytest.approx(POCKET_MM2, rel=1e-3)
    assert ("warning: the cut went through the bottom of the stock (z = -2 mm; 15.1" in err
            and "into what holds it" in err), err
    assert report["removed_volume_mm3"] == pytest.approx(2.0 * POCKET_MM2, rel=1e-3)


def test_a_pocket_within_the_block_is_not(tmp_path, capsys):
    code, err, report = cut(tmp_path, capsys, "-1.999", 0.0)
    assert code == 0, err
    assert report["bottom_cut_through_mm2"] == 0.0
    assert "bottom of the stock" not in err, err
    assert report["removed_volume_mm3"] == pytest.approx(1.999 * POCKET_MM2, rel=1e-3)


def test_a_window_judges_the_bottom_within_it(tmp_path, capsys):
    # the window x 0..5 mm holds the pocket's left half
    code, err, report = cut(tmp_path, capsys, "-3.", 0.0, "--roi", "0,5,0,10")
    assert code == 0, err
    assert report["bottom_cut_through_mm2"] == pytest.approx(POCKET_MM2 / 2, rel=1e-3)


def test_bottom_area_of_stocks_is_their_footprint():
    for spec, area_mm2 in [("block:10x10x2", 100.0), ("block:3x4x1@1,2,5", 12.0),
                           ("cylinder:5x2", 25.0 * math.pi)]:
        stock = stock_from_spec(spec)
        z = stock.bounds[0, 2]
        assert bottom_area(*stock.mesh(), z, 0.01) * 1e6 == pytest.approx(area_mm2, rel=1e-6)
        assert bottom_lost(stock, stock) == 0.0
    # a 1 mm square hole through a 10 x 10 x 2 mm block: 1 mm^2 gone
    block = stock_from_spec("block:10x10x2")
    hole = stock_from_spec("block:1x1x4@4,4,1")
    holed = Part(block.manifold - hole.manifold)
    assert bottom_lost(holed, block) * 1e6 == pytest.approx(1.0, rel=1e-12)


def test_the_viewer_says_so_from_the_report(tmp_path, capsys):
    code, err, report = cut(tmp_path, capsys, "-3.", 0.0)
    assert code == 0, err
    code, _, err = run(["view", tmp_path / "pocket.ply", "--report", tmp_path / "pocket.json",
                        "--html", tmp_path / "pocket.html"], capsys)
    assert code == 0, err
    assert ("warning: the report says the cut went through the bottom of the stock (15.1"
            in err), err
    # a pocket within the block: no such line
    code, err, report = cut(tmp_path, capsys, "-1.", 0.0)
    code, _, err = run(["view", tmp_path / "pocket.ply", "--report", tmp_path / "pocket.json",
                        "--html", tmp_path / "pocket.html"], capsys)
    assert code == 0 and "bottom of the stock" not in err, err


def test_bottom_area_holds_little_beside_the_mesh():
    # a cut's part may have 40 million faces: measuring its bottom had held the whole mesh's
    # corners and normals, 5.5 times the mesh (this one's 14 MB: 80 MB), at the end of a cut
    import tracemalloc

    import numpy as np

    rng = np.random.default_rng(7)
    n, m = 200_000, 400_000
    vertices = rng.random((n, 3)) * 0.01
    vertices[:1000, 2] = -0.002                      # 1000 vertices in the bottom plane
    triangles = rng.integers(0, n, (m, 3))
    triangles[:5000] = rng.integers(0, 1000, (5000, 3))  # faces among them, up and down
    # the same area measured over every face (the formula of the docstring, face by face)
    corners = vertices[triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    doubled = np.linalg.norm(normals, axis=1)
    flat = np.all(corners[:, :, 2] == -0.002, axis=1)
    expected = float(0.5 * doubled[flat & (normals[:, 2] <= -(1 - 1e-6) * doubled)].sum())
    del corners, normals, doubled, flat
    assert expected > 0.0
    tracemalloc.start()
    try:
        area = bottom_area(vertices, triangles, -0.002, 0.01)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert area == expected  # the same faces summed in the same order: bit-identical
    assert peak < vertices.nbytes + triangles.nbytes, peak  # had been 5.5 times the mesh


def test_a_pocket_to_the_bottom_exactly_is_not_said_below_it(tmp_path, capsys):
    # the tool's end at z = -2 mm, the block's bottom: the part is the same ring (the end
    # mill's floor takes the bottom face away), but the tool went no lower than the stock,
    # as a through cut meant to the stock's thickness does; the warning had said 'the tool
    # went below the stock' and named only a mistake
    code, err, report = cut(tmp_path, capsys, "-2.", 0.0)
    assert code == 0, err
    assert report["bottom_cut_through_mm2"] == pytest.approx(POCKET_MM2, rel=1e-3)
    warning = next(line for line in err.splitlines() if "bottom of the stock" in line)
    assert "went below the stock" not in warning, warning
    assert "reached the stock's bottom face or went below it" in warning, warning
    assert "a through cut that is meant needs the stock on a sacrificial plate" in warning
