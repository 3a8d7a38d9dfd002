"""The part does not depend on how sweeps are batched (issue 12, found porting paper 002).

Subtraction commutes: removing sweeps all at once, one by one or in reverse order must give
the same solid. It did not: near-flat sweeps (a plunge or a retract of a zero-thickness
profile, a few urad off its plane because the program compensates a workpiece setting
error) went through manifold3d's QuickHull, which drops points within ~1e-7 of the extent
of a plane, and the wrong solids left 11 of 12 robot landings up to 3e4 um^3 apart and a
groove 11.5 nm shallower. Sweeps are now built from the tool's faces (`cutting.sweeps`).
"""

import math

import numpy as np
import pytest

from machinesim.cutting import remove
from machinesim.metrology import height_map
from machinesim.tools import RoundNoseTool, VTool
from machinesim.workpiece import block

UM, MM = 1e-6, 1e-3
#: Batch and one by one agree to manifold3d's round-off, far below anything measurable, but
#: not bit for bit: a boolean evaluated in another order rounds its new vertices (~1e-19 m
#: at mm scale) differently, and the sub-nm slivers of the plunges and retracts, which
#: share faces with the grooves, are resolved by symbolic perturbation in either order.
#: Measured: ~3e-10 of the groove volume on the synthetic cross (the old engine: 5e-2),
#: at most 7e-9 on paper 002's 24 groove programs (the old engine: 1e-2); heights to
#: well under 0.1 nm.
ORDER_REL = 1e-8
PAPER_ORDER_REL = 1e-7
HEIGHT_M = 1e-10


def pose(position, rotation):
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = position
    return matrix


def rot_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def cross_of_grooves(depth=3 * UM, length=1 * MM, drift=6e-11, turn=0.003):
    """Paper 002's groove pattern: four grooves from the workpiece origin, along +X, +Y, -X,
    -Y (turned by ``turn`` rad), each plunged at the centre from 60 um above the top and
    retracted at its end, the plunges and retracts off the vertical by ``drift`` m in X and
    Y as a compensated program makes them. Returns one path per move."""
    paths = []
    centre = np.zeros(3)
    for k in range(4):
        rotation = rot_z(turn + k * math.pi / 2)
        along = rotation[:, 0]
        bottom = centre + [0.0, 0.0, -depth]
        end = bottom + length * along
        above = np.array([drift, -0.7 * drift, 60 * UM + depth])
        # the retract drifts the other way: the two drifts swapped, the lift kept in Z (it
        # had been np.roll(above, 1), which put the 63 um lift in X: the +X groove ran on
        # 63 um, 1.6 % more volume, hidden by approx's default abs of 1e-12 m^3)
        paths.append(np.array([pose(bottom + above, rotation), pose(bottom, rotation)]))
        paths.append(np.array([pose(bottom, rotation), pose(end, rotation)]))
        paths.append(np.array([pose(end, rotation), pose(end + above[[1, 0, 2]], rotation)]))
    return paths


def one_by_one(stock, tool, paths):
    part = stock
    for path in paths:
        part, _ = remove(part, tool, [path])
    return part


@pytest.mark.parametrize("tool", [VTool(math.pi / 2), RoundNoseTool(2 * MM, math.pi / 2)],
                         ids=["v90", "nose2"])
def test_batch_one_by_one_and_reverse_order_cut_the_same_part(tool):
    stock = block(3 * MM, 3 * MM, 1 * MM, origin=(-1.5 * MM, -1.5 * MM, 0.0))
    paths = cross_of_grooves()
    batch, report = remove(stock, tool, paths)
    forward = one_by_one(stock, tool, paths)
    backward = one_by_one(stock, tool, paths[::-1])
    removed = stock.volume - batch.volume
    assert report.removed_volume == pytest.approx(removed, rel=1e-9, abs=0.0)
    for part in (forward, backward):
        assert abs(part.volume - batch.volume) <= ORDER_REL * removed
    # The groove bottoms, read along each groove, agree.
    for part in (forward, backward):
        for x, y in ((0.5 * MM, 0.0), (0.0, 0.5 * MM), (-0.5 * MM, 0.0), (0.0, -0.5 * MM)):
            a = height_map(batch, np.array([x]), np.array([y]))[0, 0]
            b = height_map(part, np.array([x]), np.array([y]))[0, 0]
            assert abs(a - b) <= HEIGHT_M


def test_the_cross_of_v_grooves_has_its_analytic_volume_however_it_is_batched():
    # Four 90-deg V grooves d deep, L long, from one centre: 4 d^2 L, less the four
    # overlaps of neighbouring arms at the centre, each the region x, y in [0, d] above
    # z = max(x, y) - d: d^3 / 3 (opposite arms meet only in a plane). The sub-nm slivers
    # of the plunges and retracts add at most drift x (their section) ~1e-21 m^3, 1e-7 of it.
    depth, length = 3 * UM, 1 * MM
    expected = 4 * depth**2 * length - 4 * depth**3 / 3
    stock = block(3 * MM, 3 * MM, 1 * MM, origin=(-1.5 * MM, -1.5 * MM, 0.0))
    tool = VTool(math.pi / 2)
    paths = cross_of_grooves(depth, length, turn=0.0)
    batch, report = remove(stock, tool, paths)
    assert report.removed_volume == pytest.approx(expected, rel=1e-6, abs=0.0)
    assert stock.volume - one_by_one(stock, tool, paths).volume == pytest.approx(expected,
                                                                                rel=1e-6, abs=0.0)


def test_paper_002_groove_programs_cut_the_same_part_batched_or_not():
    """The case that exposed the bug: robot landing seed 5, the model-based program, was
    15,400 um^3 apart (of 1.68e6 um^3)."""
    from machinesim import ErrorModel, load_machine, motion
    from machinesim.cam.crown import GROOVE_ROI, GROOVE_STOCK, PARK, groove_program
    from machinesim.cutting import clip_to
    from machinesim.identification.workpiece_setting import Identification
    from machinesim.loading import RobotLoader
    from machinesim.procedures.workpiece_setting import model_based_program
    from machinesim.tool_specs import tool_from_spec
    from machinesim.workpiece import stock_from_spec

    machine, tool = load_machine("robonano_a0ib"), tool_from_spec("nose:2.0:90")
    base = clip_to(stock_from_spec(GROOVE_STOCK), GROOVE_ROI)
    setting = RobotLoader().land(np.random.default_rng(5))
    errors = ErrorModel(workpiece=setting)
    found = Identification(np.zeros((3, 3)), 2e-3, setting, np.zeros(3), np.zeros(2),
                           np.zeros((3, 2)), ())
    program = model_based_program(groove_program(), machine, found)
    plan = motion.plan(program, machine, errors, start=PARK, tool_points=tool.vertices())
    paths = [machine.tool_pose(s.q, errors) for s in plan.segments if s.kind == "linear"]
    batch, report = remove(base, tool, paths)
    forward = one_by_one(base, tool, paths)
    assert abs(batch.volume - forward.volume) <= PAPER_ORDER_REL * report.removed_volume
    x = np.linspace(-1.2 * MM, 1.2 * MM, 25)
    a, b = height_map(batch, x, x), height_map(forward, x, x)
    assert np.nanmax(np.abs(a - b)) <= HEIGHT_M
