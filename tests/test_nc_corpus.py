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
