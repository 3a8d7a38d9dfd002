"""A flat end mill's end face, tilted by a rotary move, cuts within the chord tolerance of its
true sweep (`machinesim.motion.faces`)."""

import math

import numpy as np

import machinesim
from machinesim import motion
from machinesim.metrology import height_map
from machinesim.nc import parse_program

DEPTH = 50e-6
SWING_DEG = 1.0
TOL = 1e-6  # a coarse chord, so that the test is quick: the rule is the same at 100 nm

# B turns about the Y line through the edge (robonano_a0ib), the face's centre: the face
# swings from -1 deg to +1 deg about its own diameter along Y, 50 um deep
SWING = f"""G21 G90
G00 X5. Y5. Z1.
B-{SWING_DEG}
G01 Z-0.05 F10.
B{SWING_DEG} F100.
G00 Z1.
M30
"""


def test_swung_face_keeps_its_depth_on_the_turning_line():
    part, _ = machinesim.cut(parse_program(SWING, "swing.nc"), "robonano_a0ib",
                             tool="flat:0.5", stock="block:10x10x2", chord_tolerance=TOL)
    x = np.array([4.9e-3, 5e-3, 5.1e-3])
    heights = height_map(part, x, np.array([4.9e-3, 5e-3, 5.1e-3]))
    # on the B line every pose's face stands at -50 um; 0.1 mm off it the face's lowest
    # point is 0.1 mm tan(1 deg) lower, at the end poses (by hand, Pythagoras)
    lowest = -DEPTH - np.abs(x - 5e-3) * math.tan(math.radians(SWING_DEG))
    below = lowest - heights  # how far the cut went under the true sweep, per column
    # the hull of two poses of a face tilted by d cuts a d / 2 under it (a = 0.5 mm): the
    # old rule, by the vertices' chords alone, took 2 sub-steps of 1 deg (4.4 um under)
    assert np.all(below <= TOL + 1e-12), below
    assert np.all(below >= -1e-12), below  # and never shallower than the face's own depth


def test_turning_about_the_tool_axis_adds_no_substep():
    """A C turn under an upright end mill spins its face in its own plane: no tilt."""
    program = parse_program("G21 G90\nG00 X3. Y0. Z1.\nG01 Z-0.05 F10.\nC90. F100.\nM30\n",
                            "spin.nc")
    machine = machinesim.load_machine("robonano_a0ib")
    tool = machinesim.tools.FlatEndMill(0.5e-3)
    plain = motion.plan(program, machine, tool_points=tool.vertices(),
                        chord_tolerance=1e-7)
    faced = motion.plan(program, machine, tool_points=tool.vertices(),
                        chord_tolerance=1e-7, face_radius=0.5e-3)
    assert plain.substeps > 0
    assert faced.substeps == plain.substeps


def test_tilting_move_gets_the_face_rule_count():
    """A B swing of 2 deg under a 0.5 mm face at 100 nm: each sub-step tilts at most
    2 tol / a = 4e-4 rad, so at least 0.0349 / 4e-4 = 88 sub-steps (the vertices' chords
    alone asked for 4)."""
    program = parse_program("G21 G90\nG00 B-1.\nG01 B1. F100.\nM30\n", "tilt.nc")
    machine = machinesim.load_machine("robonano_a0ib")
    tool = machinesim.tools.FlatEndMill(0.5e-3)
    plain = motion.plan(program, machine, tool_points=tool.vertices(), chord_tolerance=1e-7)
    faced = motion.plan(program, machine, tool_points=tool.vertices(), chord_tolerance=1e-7,
                        face_radius=0.5e-3)
    need = math.ceil(math.radians(2.0) / (2e-7 / 0.5e-3))
    assert plain.segment(1).q.shape[0] - 1 < need
    steps = faced.segment(1).q.shape[0] - 1
    assert need <= steps <= math.ceil(need * 1.02)


def test_the_viewer_stages_cut_the_swung_face_as_cut_does(monkeypatch):
    """The viewer's stages plan the program themselves: their last part, coloured against
    cut()'s, keeps the face's depth on the B line too (old: 4.27 um under it)."""
    import machinesim.viewer.machine as viewer

    kept = []
    stages = viewer._stages

    def keep(*args, **kwargs):
        out = stages(*args, **kwargs)
        kept.append(out[1][-1])
        return out

    monkeypatch.setattr(viewer, "_stages", keep)
    viewer.machine_scene("robonano_a0ib", parse_program(SWING, "swing.nc"), tool="flat:0.5",
                         stock="block:10x10x2", chord_tolerance=TOL)
    height = height_map(kept[0], np.array([5e-3]), np.array([5e-3]))[0, 0]
    assert -DEPTH - TOL - 1e-12 <= height <= -DEPTH + 1e-12, height + DEPTH
