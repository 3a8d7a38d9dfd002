"""A V tool tilting while it moves cuts within the chord tolerance of its true sweep: the
profile's edges get the sub-steps of `machinesim.motion.faces.edge_substeps`."""

import functools
import math

import numpy as np
from tilted_cuts import sliver

import machinesim
from machinesim import motion
from machinesim.cutting.engine import remove
from machinesim.nc import parse_program
from machinesim.tool_specs import tool_from_spec
from machinesim.workpiece import stock_from_spec

TOL = 1e-9  # the V's default chord
STOCK = "block:10x10x2"  # its top at z = 0
# on robonano_a0ib (B about the Y line through the edge point), 50 um deep, the last 2 deg
# of benchmarks/tilt_with_move.py's swing to B10 over about as many sub-steps a micron
TILT = "G21 G90\nG00 X4. Y5. Z1. B8.\nG01 Z-0.05 F10.\nX4.02 B10. F100.\nM30\n"
START = [4e-3, 5e-3, 1e-3, math.radians(8.0), 0.0]


def _v_profile(tool):
    """The V's edges, below the stock's top (z = 0)."""
    from machinesim.motion.faces import ProfileEdges  # here: the first test runs without it

    return ProfileEdges(np.asarray(tool.vertices())[tool.edges()], 0.0)


def test_tilting_flank_stays_within_the_chord_of_a_finer_cut():
    """The default cut against the same trajectory planned at a 64 times finer chord (the
    vertices' rule, second order: 8 times the sub-steps, so 1/8 of the first-order waist),
    measured on the default's faces (`tilted_cuts.sliver`). The vertices' rule alone cut
    it in 41 sweeps, 1.16 nm past it (the hull of a sub-step's two poses across the tilted
    flank, the waist of `edge_substeps`); the edges' rule in 54, 0.87 nm past it."""
    machine = machinesim.load_machine("robonano_a0ib")
    part, report = machinesim.cut(parse_program(TILT, "tilt.nc"), machine, tool="v:90",
                                  stock=STOCK, start=START)
    _, over = sliver(_fine_reference(), part)
    assert 0.0 < over <= TOL, over


@functools.cache
def _fine_reference():
    """The tilting move cut along its trajectory planned at a 64 times finer chord (8 times
    the sub-steps of the vertices' rule), the engine given those poses."""
    machine = machinesim.load_machine("robonano_a0ib")
    tool = tool_from_spec("v:90")
    fine = motion.plan(parse_program(TILT, "tilt.nc"), machine, tool_points=tool.vertices(),
                       chord_tolerance=TOL / 64, start=START)
    reference, _ = remove(stock_from_spec(STOCK), tool, [machine.tool_pose(fine.q)])
    return reference


def test_cut_turned_holds_a_tilting_flank_as_cut_does():
    """`cut_turned` plans as `cut` does: the same tilting move (C stays 0, one group) within
    the chord of the finer cut. Planned without the profile's edges it cut 41 sweeps,
    1.16 nm past it, where `cut` cut 54."""
    from machinesim.cutting import cut_turned

    part, report = cut_turned(parse_program(TILT, "tilt.nc"), "robonano_a0ib", tool="v:90",
                              stock=STOCK, start=START)
    _, over = sliver(_fine_reference(), part)
    assert 0.0 < over <= TOL, (over, report.sweeps)


def test_the_viewers_finished_part_holds_a_tilting_flank_as_cut_does(monkeypatch):
    """The viewer's last stage (the part it colours by its deviation from `cut`'s) is planned
    as `cut` plans: within the chord of the finer cut, and the nominal machine's part the
    same as `cut`'s to the booleans' round-off. Planned without the profile's edges its last
    stage lay 1.16 nm past the finer cut, and off `cut`'s own by the sub-steps it lacked."""
    from machinesim.viewer import machine as viewer_machine

    drawn = {}

    def keep(scene, path, surface, nominal=None, *args, **kwargs):
        drawn[path] = (surface, nominal)
        return add_part(scene, path, surface, nominal, *args, **kwargs)

    add_part = viewer_machine.add_part
    monkeypatch.setattr(viewer_machine, "add_part", keep)
    viewer_machine.machine_scene("robonano_a0ib", parse_program(TILT, "tilt.nc"),
                                 tool="v:90", stock=STOCK, start=START, max_stages=1,
                                 max_triangles=2000)
    part, nominal = drawn["inspection/part"]
    _, over = sliver(_fine_reference(), part)
    assert 0.0 < over <= TOL, over
    for one, other in ((part, nominal), (nominal, part)):
        volume, _ = sliver(one, other)
        assert volume < 1e-24, volume  # 1e-6 um^3


def test_untilted_moves_and_a_tilt_alone_keep_their_substeps():
    """A move that turns no rotary axis keeps the vertices' count to the bit; a B swing
    about the edge point alone keeps each edge in one plane (its corners at both poses
    coplanar: no waist) and adds no sub-step either."""
    machine = machinesim.load_machine("robonano_a0ib")
    tool = tool_from_spec("v:90")
    profile = _v_profile(tool)
    for text in ("G21 G90\nG00 X4. Y5. Z1. B10.\nG01 Z-0.05 F10.\nX4.1 Y5.05 F100.\nM30\n",
                 "G21 G90\nG00 X4. Y5. Z1.\nG01 Z-0.05 F10.\nB10. F100.\nM30\n"):
        program = parse_program(text, "move.nc")
        plain = motion.plan(program, machine, tool_points=tool.vertices(),
                            chord_tolerance=TOL)
        ruled = motion.plan(program, machine, tool_points=tool.vertices(),
                            chord_tolerance=TOL, profile=profile)
        assert np.array_equal(plain.q, ruled.q)


def test_waist_of_one_substep_by_hand():
    """One sub-step of the swing's end, B10 - d to B10 while X moves t, the flank 50 um deep
    (L = 50 um sqrt(2) below the top, at 45 deg to the B axis): to first order the waist
    |D . n| / 4 = h' d sin(B) / (4 sqrt(1 + cos(B)^2)) when the move dominates the edge's
    own turn (h' = 50 um / cos(B), the flank's reach below the top along the axis), so the
    count the rule gives one such move is that waist over the tolerance, times 1.01 (a
    tolerance of 1e-15 m, for a count of some 16,000 to resolve it by)."""
    machine = machinesim.load_machine("robonano_a0ib")
    tool = tool_from_spec("v:90")
    b, d, t = math.radians(10.0), 1e-5, 1e-5  # 10 um of X to 0.57 mdeg: the move dominates
    start = np.array([[4e-3, 5e-3, -50e-6, b - d, 0.0]])
    delta = np.array([[t, 0.0, 0.0, d, 0.0]])
    found = motion.faces.edge_substeps(machine, None, start, delta, np.array([1]),
                                       _v_profile(tool), 1e-15)
    reach = 50e-6 / math.cos(b)
    waist = reach * d * math.sin(b) / (4.0 * math.sqrt(1.0 + math.cos(b) ** 2))
    assert abs(found[0] / (waist / 1e-15 * 1.01) - 1.0) < 1e-3, (found, waist)


def test_a_long_move_is_read_a_block_at_a_time_with_the_same_count(monkeypatch):
    """A move of more samples than a block holds is read in pieces: it was taken whole,
    each sample costing 24 bytes per edge in a dozen arrays (three turns of C under
    nose:1.0:90, 559 edges, 23,504 samples: 5 GB). Here blocks of 120 (poses of 120 samples,
    or 40 samples of the V's 3 edges) against a swing of 150 sub-steps (B8 to B18 over
    0.1 mm of X, raised to 496): no call poses more than 120 samples or reads more than
    120 edge-samples, and the count is the one read whole (the default block, which holds
    the move), to the bit."""
    from machinesim.motion import faces

    machine = machinesim.load_machine("robonano_a0ib")
    profile = _v_profile(tool_from_spec("v:90"))
    start = np.array([[4e-3, 5e-3, -50e-6, math.radians(8.0), 0.0],
                      [4e-3, 5e-3, -50e-6, math.radians(9.0), 0.1]])
    delta = np.array([[1e-4, 0.0, 0.0, math.radians(10.0), 0.0],
                      [1e-5, 0.0, 0.0, math.radians(-1.0), 0.3]])
    steps = np.array([150, 7])
    whole = faces.edge_substeps(machine, None, start, delta, steps, profile, TOL)
    posed, read = [], []
    pose, waist = type(machine).tool_pose, faces._largest_waist

    def counted(self, q, errors=None):
        posed.append(len(q))
        return pose(self, q, errors)

    def counted_waist(poses, first, edges, top):
        read.append(len(poses) * len(edges))
        return waist(poses, first, edges, top)

    monkeypatch.setattr(type(machine), "tool_pose", counted)
    monkeypatch.setattr(faces, "_largest_waist", counted_waist)
    monkeypatch.setattr(faces, "_SAMPLES_PER_BLOCK", 120)
    blocks = faces.edge_substeps(machine, None, start, delta, steps, profile, TOL)
    assert max(posed) <= 120, posed  # the old code: 159 at once
    assert sum(posed) > 159  # each piece's end read again as the next one's start
    assert max(read) <= 120, read  # the old code: 477 at once
    np.testing.assert_array_equal(blocks, whole)
    assert whole[0] > steps[0]  # the swing is raised: the pieces' waists are read
