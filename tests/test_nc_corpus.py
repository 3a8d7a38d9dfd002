"""The corpus (tests/nc_corpus/): programs written here in the styles issue 12 names, read
and checked against the geometry they were written for (worked out from the text by hand)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from machinesim.nc import AXES, KIND_DWELL, KIND_LINEAR, format_program, parse_program, read_program
from machinesim.nc.cycles import PECK_CLEARANCE_M

CORPUS = Path(__file__).parent / "nc_corpus"
TOOLS = CORPUS / "tools.toml"
MM = 1e-3
#: On the circle: float64 round-off of centre + r (cos, sin) at <= 30 mm is ~1e-17 m.
ON_CIRCLE_M = 1e-12
#: Decimal words in mm times 1e-3: round-off far below this, 10^6 x below 1 nm.
EXACT_M = 1e-15
PROGRAMS = sorted(CORPUS.glob("*.nc"))


def _line_of(path: Path, text: str) -> int:
    """1-based line of the only line of ``path`` that contains ``text``."""
    hits = [n for n, line in enumerate(path.read_text().splitlines(), 1) if text in line]
    assert len(hits) == 1, (text, hits)
    return hits[0]


def _block(program, path: Path, text: str) -> np.ndarray:
    """Targets of the moves of the block containing ``text``, after the position before."""
    rows = np.flatnonzero(program.lines == _line_of(path, text))
    return program.targets[rows[0] - 1:rows[-1] + 1]


def _check_arc(points: np.ndarray, centre, radius_mm: float, sweep_deg: float,
               tolerance: float = 1e-9) -> None:
    centre = np.asarray(centre, dtype=float) * MM
    radius = radius_mm * MM
    offsets = points - centre
    assert np.max(np.abs(np.linalg.norm(offsets, axis=1) - radius)) <= ON_CIRCLE_M
    middle = (points[1:] + points[:-1]) / 2
    assert np.max(radius - np.linalg.norm(middle - centre, axis=1)) <= tolerance
    angle = np.unwrap(np.arctan2(offsets[:, 1], offsets[:, 0]))
    assert math.degrees(angle[-1] - angle[0]) == pytest.approx(sweep_deg, abs=1e-9)


@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: p.name)
def test_corpus_reads_identically_on_both_paths_and_writes_back(path):
    program = read_program(path, tools=TOOLS)
    assert program == read_program(path, tools=TOOLS, fast=False)
    assert program.integer_input == "calculator"
    back = parse_program(format_program(program))
    assert len(back) == len(program)
    assert np.allclose(back.targets, program.targets, rtol=0, atol=0.5e-9, equal_nan=True)


def test_cam_header():
    path = CORPUS / "cam_header.nc"
    program = read_program(path, tools=TOOLS)
    assert program.number == 1001
    states = {word: _line_of(path, text) for word, text in [
        ("G40", "N10 "), ("G80", "N10 "), ("T1", "N30 "), ("T2", "N120 "),
        ("G05.1 Q1", "N130 "), ("G64", "N135 "), ("G05.1 Q0", "N165 ")]}
    assert dict(program.states) == states
    z = {n: program.targets[program.lines == _line_of(path, f"N{n} ")][-1, 2] / MM
         for n in (20, 55, 65, 105, 145, 150, 170)}
    # G28 G91 Z0: machine zero; G43 H01: length 0; G43 H02: 2.5 mm longer tool
    assert z == pytest.approx({20: 0.0, 55: 15.0, 65: -1.0, 105: 0.0, 145: 12.5,
                               150: -0.2 + 2.5, 170: 0.0}, abs=1e-12)
    _check_arc(_block(program, path, "N75 ")[:, :2], (25, 10), 5, 90)
    _check_arc(_block(program, path, "N85 ")[:, :2], (25, 20), 5, 90)
    _check_arc(_block(program, path, "N155 ")[:, :2], (15, 15), 5, -360)
    last = program.targets[-1]
    assert last[:3].tolist() == [0.0, 0.0, 0.0]  # G28 X0 Y0 after G28 Z0
    rows = program.lines == _line_of(path, "N75 ")
    assert set(program.block_numbers[rows]) == {75}
    assert np.all(program.feeds[rows] == pytest.approx(1000 * MM / 60, rel=1e-15))
    t1 = int(np.flatnonzero(program.lines == _line_of(path, "N30 "))[0])
    assert program.kinds[t1] == KIND_DWELL and program.m_codes[t1] == (6,)  # T1 M06


ARCS = [  # (comment text, centre (u, v) mm, radius, sweep deg, plane columns)
    ("XY quarter, counter-clockwise, centre form", (0, 0), 10, 90, ("X", "Y")),
    ("XY quarter, radius form", (0, 0), 10, 90, ("X", "Y")),
    ("XY three quarters, clockwise", (0, 0), 10, -270, ("X", "Y")),
    ("XY full circle with Z", (0, 0), 10, 360, ("X", "Y")),
    ("ZX quarter, clockwise", (0, 0), 5, -90, ("Z", "X")),
    ("YZ quarter, counter-clockwise", (0, 0), 5, 90, ("Y", "Z")),
]


@pytest.mark.parametrize(("comment", "centre", "radius", "sweep", "plane"), ARCS)
def test_arcs_in_the_three_planes(comment, centre, radius, sweep, plane):
    path = CORPUS / "arcs_planes.nc"
    program = read_program(path)
    rows = _block(program, path, comment)
    _check_arc(rows[:, [AXES.index(a) for a in plane]], centre, radius, sweep)


def test_helices_in_the_corpus_advance_with_the_angle():
    path = CORPUS / "arcs_planes.nc"
    program = read_program(path)
    for comment, plane, axis, rise_mm in [("XY full circle with Z", "XY", "Z", -1.0),
                                          ("YZ quarter", "YZ", "X", 2.0)]:
        rows = _block(program, path, comment)
        u, v = (rows[:, AXES.index(a)] for a in plane)
        angle = np.abs(np.unwrap(np.arctan2(v, u)) - math.atan2(v[0], u[0]))
        along = rows[:, AXES.index(axis)] - rows[0, AXES.index(axis)]
        assert np.max(np.abs(along - rise_mm * MM * angle / angle[-1])) <= 1e-16


def test_subprogram_grooves_and_repeats():
    path = CORPUS / "subprogram.nc"
    program = read_program(path)
    cuts = program.targets[program.kinds == KIND_LINEAR]
    grooves = cuts[cuts[:, 0] == 10 * MM]
    assert grooves[:, 1] / MM == pytest.approx([0, 2, 4, 6], abs=1e-12)  # L4: four calls
    assert np.all(np.abs(grooves[:, 2] + 0.01 * MM) <= 1e-15)  # 1.01 down from Z1
    assert program.targets[-1, 1] == pytest.approx(8 * MM, abs=EXACT_M)
    dwells = program.dwells[program.kinds == KIND_DWELL]
    assert dwells.tolist() == [0.1, 0.1]  # P<2><3003>: two calls
    sub_lines = {_line_of(path, "G91 G01 Z-1.01"), _line_of(path, "X10. F200."),
                 _line_of(path, "G00 Z1.01"), _line_of(path, "X-10. Y2.")}
    assert set(program.lines[1:17]) == sub_lines


def test_drilling_depths_dwell_and_pecks():
    path = CORPUS / "drilling.nc"
    program = read_program(path)

    def moves_of(text):
        rows = program.lines == _line_of(path, text)
        return program.kinds[rows], program.targets[rows][:, 2] / MM, program.dwells[rows]

    kinds, z, _ = moves_of("G98 G81")
    assert z.min() == pytest.approx(-2.0) and z[-1] == pytest.approx(10.0)  # initial level
    kinds, z, dwell = moves_of("G99 G82")
    assert z.min() == pytest.approx(-1.5) and z[-1] == pytest.approx(0.5)  # back to R
    assert dwell.max() == 0.25
    kinds, z, _ = moves_of("G98 G83")
    feeds = z[kinds == KIND_LINEAR]
    assert feeds == pytest.approx([-0.2, -1.4, -2.6, -3.0])  # pecks of 1.2 from R1
    rapid_down = z[2:][(kinds[2:] != KIND_LINEAR) & (z[2:] < 1.0)]
    assert rapid_down == pytest.approx([f + PECK_CLEARANCE_M / MM for f in feeds[:-1]])


def test_sts_point_list_follows_its_formula():
    path = CORPUS / "sts_points.nc"
    program = read_program(path)
    first = _line_of(path, "X4.995000")
    rows = (program.lines >= first) & (program.lines < first + 720)
    x, z, c = (program.targets[rows][:, AXES.index(a)] for a in "XZC")
    k = np.arange(1, 721)
    assert np.max(np.abs(x - (5 - 0.005 * k) * MM)) <= 0.5e-9 + EXACT_M
    assert np.max(np.abs(c - np.radians(0.5 * k))) <= np.radians(0.5e-5)
    assert np.max(np.abs(z - 0.001 * np.sin(np.radians(1.5 * k)) * MM)) <= 0.5e-9 + EXACT_M
    assert np.all(program.kinds[rows] == KIND_LINEAR)
    assert np.all(program.feeds[rows] == pytest.approx(10 * MM / 60, rel=1e-15))


# Public programs (tests/nc_corpus/public/): CAM output that nobody here wrote, each with a
# header naming its repository, path, commit and licence. The values below are read off
# the program text by hand (and the CAM's own header: ZMIN).
PUBLIC = CORPUS / "public"
LENGTH_0 = "[tool.1]\nlength_mm = 0.0\nradius_mm = 1.0\n"


@pytest.mark.parametrize("path", sorted(PUBLIC.glob("*.nc")), ids=lambda p: p.name)
def test_public_programs_read_identically_on_both_paths(path, tmp_path):
    table = tmp_path / "tools.toml"
    table.write_text(LENGTH_0)
    program = read_program(path, tools=table)
    assert program == read_program(path, tools=table, fast=False)
    assert dict(program.unit_words) == {"G21": _line_of(path, "G21")}


def test_fusion_contour_without_tool_length_words():
    # Fusion 360 'personal use' post: T1 without M6, G54, G0 X Y then Z10, three passes
    # round a 21.4 mm square (tool centre) at Z -1, -2, -3, back up to Z10
    path = PUBLIC / "led_floor_1024_block_14bit.nc"
    program = read_program(path)
    assert dict(program.states) == {"T1": path.read_text().splitlines().index("T1") + 1}
    moves = program.targets[:, :3] / MM
    assert moves[program.lines == _line_of(path, "G0 X-0.7 Y-0.7")][-1].tolist()[:2] == [-0.7, -0.7]
    assert np.nanmin(moves[:, 2]) == -3.0  # ZMIN=-3 in the CAM's tool line
    assert moves[-1].tolist() == [-0.7, -0.7, 10.0]
    corners = moves[program.kinds == KIND_LINEAR]
    assert sorted({tuple(c[:2]) for c in corners if c[2] == -3.0}) == [
        (-0.7, -0.7), (-0.7, 20.0), (-0.7, 20.7), (20.0, 20.7), (20.7, -0.7), (20.7, 20.7)]


def test_fusion_fanuc_post_with_lead_arcs_in_three_planes(tmp_path):
    # Fusion 360 generic FANUC-style post: G28 G91 Z0, T1 M6, G43 Z25 H1, each pass
    # entered by a G18 quarter arc, turned by G17 arcs and left by a G19 one; tabs at Z0.5
    table = tmp_path / "tools.toml"
    table.write_text(LENGTH_0)
    path = PUBLIC / "led_floor_1003_wall_tester.nc"
    program = read_program(path, tools=table, reference={"Z": 100 * MM})
    assert [(c.number, c.line) for c in program.tool_changes] == [(1, _line_of(path, "N35 T1 M6"))]
    z = program.targets[:, 2] / MM
    assert z[program.lines == _line_of(path, "N25 G28 G91 Z0")][-1] == 100.0  # the reference
    assert z[program.lines == _line_of(path, "N55 G43 Z25 H1")][-1] == 25.0  # H1: length 0
    assert np.min(z) == -1.0  # ZMIN=-1 in the CAM's tool line
    # N75 G18 G2 Z8 I0.2 from (X-1.6, Z8.2): centre (Z8.2, X-1.4) in (Z, X), clockwise
    # about +Y, a quarter down to the cut's level, tangent to the G1 after it
    _check_arc(_block(program, path, "N75 ")[:, [2, 0]], (8.2, -1.4), 0.2, -90)
    # N85 G17 G3 X-1 Y-1 J0.2 from (-1.2, -1.2): centre (-1.2, -1), a counter-clockwise quarter
    _check_arc(_block(program, path, "N85 ")[:, :2], (-1.2, -1.0), 0.2, 90)
    # N165 G19 G2 Y-1.6 Z8.2 K0.2 from (Y-1.4, Z8): centre (Y-1.4, Z8.2) in (Y, Z), up and out
    _check_arc(_block(program, path, "N165 ")[:, [1, 2]], (-1.4, 8.2), 0.2, -90)
    # the lead-in arcs reach the five levels, then the tabs' last pass: Z8 6 4 2 0 -1
    ends = [z[program.lines == _line_of(path, f"N{n} G18 G2")][-1]
            for n in (75, 190, 305, 420, 535)]
    assert ends == [8.0, 6.0, 4.0, 2.0, 0.0]
    tabs = program.targets[program.lines == _line_of(path, "N765 Z0.5")][:, :3] / MM
    assert tabs.tolist() == [[-1.0, 18.0, 0.5]]
    last = program.targets[-1, :3] / MM  # G28 G91 X0 Y0 after G28 G91 Z0: the reference
    assert last.tolist() == [0.0, 0.0, 100.0]


def test_fusion_helical_bore_descends_a_quarter_mm_a_half_turn():
    # Fusion 360 bore: G17 G3 half circles about (30, 0) mm, each 0.25 mm deeper, from
    # X30.3 Y0 at Z0 to Z-12.75 in 51 halves (radius 0.3), then again at radius 0.4
    path = PUBLIC / "led_floor_1105_bore_test.nc"
    program = read_program(path)
    bores = [(_line_of(path, "Z-0.25 I-0.3 J0"), _line_of(path, "Z-12.75 I-0.3"), 0.3),
             (103, 153, 0.4)]  # lines 103-153: the first of the two bores at 0.4
    for first, last, radius in bores:
        rows = np.flatnonzero((program.lines >= first) & (program.lines <= last))
        helix = program.targets[rows[0] - 1:rows[-1] + 1, :3] / MM  # from the move before
        _check_arc(helix[:, :2] * MM, (30, 0), radius, 51 * 180)
        turned = np.unwrap(np.arctan2(helix[:, 1], helix[:, 0] - 30))
        assert helix[0, 2] == 0.0 and helix[-1, 2] == -12.75
        assert np.max(np.abs(helix[:, 2] + 0.25 * (turned - turned[0]) / math.pi)) <= 1e-12
    # ZMIN=-12.8 in the CAM's tool line
    assert np.nanmin(program.targets[:, 2]) / MM == pytest.approx(-12.8, abs=1e-12)
