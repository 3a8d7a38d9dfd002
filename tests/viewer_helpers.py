"""What several of the viewer's test files share (not collected: no test_ prefix): a
small display budget, a grooves program and its errors, a tilted block, a PLY file's
bytes, `machinesim view` through its parser and its machine scene recorded, not drawn."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

from machinesim import ErrorModel, ToolSetting
from machinesim.nc import ProgramBuilder
from machinesim.viewer.cli import add_view_parser, run_view
from machinesim.viewer.scene import Scene
from machinesim.workpiece import Part

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


def ply_bytes(vertices, triangles, kind="double") -> bytes:
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
              f"property {kind} x\nproperty {kind} y\nproperty {kind} z\n"
              f"element face {len(triangles)}\nproperty list uchar int vertex_indices\n"
              "end_header\n").encode("ascii")
    faces = np.zeros(len(triangles), dtype=[("n", "u1"), ("i", "<i4", 3)])
    faces["n"], faces["i"] = 3, triangles
    dtype = {"double": "<f8", "float": "<f4"}[kind]
    return header + np.asarray(vertices, dtype=dtype).tobytes() + faces.tobytes()


def run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="machinesim")
    add_view_parser(parser.add_subparsers(dest="command", required=True))
    return run_view(parser.parse_args(["view", *argv]))


@pytest.fixture
def captured(monkeypatch):
    import machinesim.viewer.machine as viewer_machine

    seen = {}

    def capture(machine, program, **kwargs):
        seen.update(program=program, **kwargs)
        return Scene("captured")

    monkeypatch.setattr(viewer_machine, "machine_scene", capture)
    return seen
