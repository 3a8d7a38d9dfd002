"""The corpus programs that cut, cut on small stock: removed volumes against shapes worked
out by hand from the program text (tests/nc_corpus/)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from machinesim.cutting import cut
from machinesim.nc import read_program
from machinesim.tools import BallEndMill, VTool

CORPUS = Path(__file__).parent / "nc_corpus"
MM = 1e-3
#: Removed volumes are integrated exactly (docs/cutting.md); float64 round-off over a few
#: thousand faces stays far below this.
VOLUME_REL = 1e-9


def test_subprogram_grooves_remove_four_v_prisms():
    # O3002 called four times: G91 Z-1.01 from Z1 (0.01 mm below the top), a feed 10 mm
    # along X, out, back and 2 mm over in Y. The V edge is a zero-thickness profile in the
    # tool's Y-Z plane, so the plunge removes nothing and each feed leaves a prism of the
    # 90-deg V's section d^2 (half-width d at the top: d * d) over 10 mm.
    program = read_program(CORPUS / "subprogram.nc")
    _, report = cut(program, "grooving_4axis", tool=VTool(math.pi / 2),
                    stock="block:12x8x1@-1,-1,0")
    depth, length = 0.01 * MM, 10 * MM
    assert report.removed_volume_m3 == pytest.approx(4 * depth**2 * length, rel=VOLUME_REL)
    assert report.rapids_that_cut == () and report.holder_contact == ()


def _ball_hole(tool: BallEndMill, depth: float) -> float:
    """Volume a ball polyhedron leaves plunged straight down to ``depth`` > its radius: the
    hemisphere as frusta of regular pyramids between its rings (`BallEndMill.rings`) and a
    prism of the equator polygon over depth - R."""
    rings, segments = tool.rings
    theta = np.linspace(0.0, math.pi / 2, rings + 1)
    r, z = tool.radius * np.sin(theta), tool.radius * (1 - np.cos(theta))
    area = segments / 2 * r**2 * math.sin(2 * math.pi / segments)
    hemisphere = np.sum(np.diff(z) / 3 * (area[1:] + area[:-1] + np.sqrt(area[1:] * area[:-1])))
    return float(hemisphere + area[-1] * (depth - tool.radius))


def test_drilling_cycles_leave_four_ball_holes():
    # G81 at (5, 5) and (10, 5) to Z-2, G82 at (5, 10) to Z-1.5, G83 pecks at (10, 10) to
    # Z-3 (every peck re-enters the hole it made: the union is one plunge to Z-3). The holes
    # are 5 mm apart, R 0.5 mm: disjoint. Between holes the tool rapids at Z10 or the R
    # level (Z0.5 and Z1), above the top.
    tool = BallEndMill(0.5 * MM, chord_tol=5e-6)
    program = read_program(CORPUS / "drilling.nc")
    _, report = cut(program, "grooving_4axis", tool=tool, stock="block:15x15x4")
    expected = sum(_ball_hole(tool, d * MM) for d in (2.0, 2.0, 1.5, 3.0))
    assert report.removed_volume_m3 == pytest.approx(expected, rel=VOLUME_REL)
    assert report.rapids_that_cut == ()
    # the polyhedron lies within its chord tolerance inside the true ball
    true = sum(2 / 3 * math.pi * tool.radius**3 + math.pi * tool.radius**2
               * (d * MM - tool.radius) for d in (2.0, 2.0, 1.5, 3.0))
    assert true * (1 - 1e-2) < expected <= true
