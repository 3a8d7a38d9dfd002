"""Paper 002 replay, the crown (`machinesim.cam.crown`): the last layer and all ten cut the
same part, cut_turned against cut, the machining time against the plan, the crown after
compensation within the paper's errors, read pair by pair in one placement."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim import ErrorModel, Lab, WorkpieceSetting, load_machine, motion
from machinesim.cam import crown as cam
from machinesim.cutting import clip_to, cut, cut_turned
from machinesim.identification import workpiece_setting as ws
from machinesim.loading import RobotLoader
from machinesim.metrology import Microscope, TouchProbe, crown_features, height_map
from machinesim.procedures.workpiece_setting import eqs_5_to_7_program, read_spheres

UM, MM, NM = 1e-6, 1e-3, 1e-9
MACHINE = load_machine("robonano_a0ib")


@pytest.fixture(scope="module")
def crown_stock():
    return cam.crown_stock()


def small_crown(offsets, face, rows=(-50 * UM, 50 * UM)):
    """A few passes of one side face (all rows for face None: the top), and its window."""
    groups = cam.crown_passes(offsets=offsets, top_rows=rows, side_rows=rows)
    keep = [g for g in groups if (g.end[2] < g.start[2]) == (face is not None)
            and (face is None or math.isclose(g.c, face * math.pi / 4))]
    return cam.passes_program(keep)


def test_the_last_layer_alone_cuts_the_part_all_ten_layers_cut(crown_stock):
    """Every earlier layer's sweep is the last one's moved out along the face normal: inside
    the stock it lies within the last one's (docs/procedures/workpiece_setting.md). The
    parts agree to boolean round-off: volume 1e-12 relative, heights 1e-12 m."""
    errors = ErrorModel(workpiece=WorkpieceSetting([1 * UM, -2 * UM, 3 * UM], 2e-4, -1e-4, 3e-4))
    middle = cam.CROWN.apothem + 0.5 * cam.CROWN.run  # the middle of the face at C = 0
    box = [(middle - 0.05 * MM, middle + 0.05 * MM, -0.03 * MM, 0.03 * MM)]
    tool = cam.crown_tool()
    parts = [cut_turned(small_crown(offsets, 0), MACHINE, tool, crown_stock, errors, roi=box,
                        start=cam.PARK, allow_holder_contact=True)[0]
             for offsets in (None, [0.0])]
    assert parts[0].volume == pytest.approx(parts[1].volume, rel=1e-12, abs=0.0)
    x, y = middle + np.linspace(-0.04, 0.04, 9) * MM, np.linspace(-0.02, 0.02, 9) * MM
    np.testing.assert_allclose(height_map(parts[0], x, y), height_map(parts[1], x, y),
                               rtol=0, atol=1e-12)


def test_cut_turned_makes_the_part_cutting_cut_makes(crown_stock):
    """cut_turned turns each C group into its own frame for speed; the part must not change:
    volumes to 1e-12 relative, heights to 1e-12 m (boolean and rotation round-off)."""
    errors = ErrorModel(workpiece=WorkpieceSetting([1 * UM, 2 * UM, -1 * UM], 1e-4, 2e-4, 5e-4))
    program = small_crown([0.0], 1, rows=(-25 * UM, 25 * UM))
    middle = cam.CROWN.apothem + 0.5 * cam.CROWN.run  # the middle of the face at 45 deg
    cx, cy = middle * math.cos(math.pi / 4), middle * math.sin(math.pi / 4)
    box = [(cx - 0.05 * MM, cx + 0.05 * MM, cy - 0.05 * MM, cy + 0.05 * MM)]
    tool = cam.crown_tool()
    told = []
    ours, report = cut_turned(program, MACHINE, tool, crown_stock, errors, roi=box,
                              start=cam.PARK, allow_holder_contact=True,
                              progress=lambda *done: told.append(done))
    # progress in feed sweeps: from none to all, one call before the groups and one after each
    total = sum(len(s.q) - 1 for s in motion.plan(program, MACHINE, errors, start=cam.PARK,
                                                  tool_points=tool.vertices()).segments
                if s.kind == "linear")
    assert told[0] == (0, total) and told[-1] == (total, total) and len(told) >= 2
    assert all(a[0] <= b[0] for a, b in zip(told, told[1:], strict=False))
    theirs, _ = cut(program, MACHINE, tool=tool, stock=clip_to(crown_stock, box),
                    errors=errors, roi=box, start=cam.PARK, allow_holder_contact=True)
    assert ours.volume == pytest.approx(theirs.volume, rel=1e-12, abs=0.0)
    assert report.removed_volume_m3 > 0 and report.sweeps == 5
    x, y = cx + np.linspace(-0.04, 0.04, 9) * MM, cy + np.linspace(-0.04, 0.04, 9) * MM
    np.testing.assert_allclose(height_map(ours, x, y), height_map(theirs, x, y), rtol=0,
                               atol=1e-12)
    # the lab cuts by it when asked for turn groups, with its own errors
    lab = Lab(MACHINE, errors, noise=False)
    through_lab, _ = lab.cut(program, tool, crown_stock, roi=box, start=cam.PARK,
                             turn_step=math.pi / 4, allow_holder_contact=True)
    assert through_lab.volume == ours.volume


def test_machining_time_is_the_planned_time_of_the_whole_program():
    """Planning each group with one and two passes gives the plan of the whole program:
    durations add up exactly, to float64 round-off (1e-9 relative)."""
    groups = cam.crown_passes(offsets=[1 * UM, 0.0], top_rows=(-0.1 * MM, 0.1 * MM),
                              side_rows=(-0.05 * MM, 0.05 * MM))
    whole = motion.plan(cam.passes_program(groups, stagger=False), MACHINE,
                        start=cam.PARK).duration
    assert cam.machining_time(MACHINE, groups) == pytest.approx(whole, rel=1e-9)
    # the cuboid takes every side face out to the block's top corner, seen from a 45 deg
    # face at sqrt 2 times its half width, 1 um a layer; the finishing ten layers
    plan = cam.CROWN
    layers = {(g.c, round(g.start[2] + math.tan(plan.slope) * (g.start[0] - plan.apothem), 12))
              for g in cam.crown_passes(cuboid=True) if g.c != 0.0}
    corner = (math.sin(plan.slope) * (math.sqrt(2) * plan.cuboid_half - plan.apothem)
              + math.cos(plan.slope) * plan.rough_top)
    assert len({z for c, z in layers if c == math.radians(45.0)}) == math.floor(
        corner / UM + 1e-9) + 1
    assert len({float(g.start[2]) for g in cam.crown_passes() if g.start[2] == g.end[2]}) == 10


def test_after_compensation_with_probe_noise_the_crown_is_within_the_papers_errors(
        crown_stock):
    """The whole chain on the crown, noise on (probe 20 nm, microscope 12 nm), seeded robot
    placement: Table 3's after-column bounds (edge distances 2 um, inclinations 0.2 deg),
    and the levels the simulation reaches (measured L < 5 nm, S < 3e-4 deg: the sphere
    heights to ~30 nm over the 12 mm between spheres); the bounds are 20x those."""
    rng = np.random.default_rng(4)
    landed = RobotLoader().land(rng)
    errors = ErrorModel(workpiece=landed)
    found = ws.identify(read_spheres(TouchProbe(MACHINE, errors, crown_stock, rng=rng),
                                     cam.crown_spheres()))
    windows, boxes, rows = cam.crown_roi(margin=0.25 * MM, top=0.15 * MM, side=0.1 * MM)
    program = eqs_5_to_7_program(cam.passes_program(
        cam.crown_passes(offsets=[0.0], **rows)), MACHINE, found)
    part, _ = cut_turned(program, MACHINE, cam.crown_tool(), crown_stock, errors, roi=boxes,
                         start=cam.PARK, allow_holder_contact=True)
    features = crown_features(part, Microscope(rng=rng), windows)
    plan = cam.CROWN
    edge = np.abs(features.edge_distances - 2 * plan.apothem)
    tilt = np.abs(np.degrees(features.inclinations - plan.slope))
    assert edge.max() < 2 * UM and tilt.max() < 0.2
    assert edge.max() < 0.1 * UM and tilt.max() < 6e-3


def test_the_crown_is_read_pair_by_pair_in_one_placement_so_registration_cancels(
        crown_stock):
    """The microscope's registration (its origin 5 um off the part's, turned 1 mrad, the
    part tilted 0.2 mrad under it) moves every reading of one placement alike, and each pair
    of opposite faces is read in one placement with the top and the flat: the edge and foot
    distances come out as with no registration, to the shear's second order (L:
    (2 x 1.5 mm x 0.2 mrad)^2 / 2 L ~ 0.1 nm), and so do the inclinations to the shear's
    first order (the tilt is applied as a shear of heights). Reading the faces of a pair in
    placements turned 180 deg apart (as before) put 2 x 5 um into L."""
    from machinesim.metrology.imperfections import Registration

    windows, boxes, rows = cam.crown_roi(margin=0.25 * MM, top=0.15 * MM, side=0.1 * MM)
    program = cam.passes_program(cam.crown_passes(offsets=[0.0], **rows))
    part, _ = cut_turned(program, MACHINE, cam.crown_tool(), crown_stock, None, roi=boxes,
                         start=cam.PARK, allow_holder_contact=True)
    plain = crown_features(part, Microscope(noise=False), windows)
    registered = Registration((5 * UM, -4 * UM, 3 * UM), 1e-3, (2e-4, -1e-4))
    seen = crown_features(part, Microscope(noise=False, registration=registered), windows)
    np.testing.assert_allclose(seen.edge_distances, plain.edge_distances, atol=1e-9)
    np.testing.assert_allclose(seen.foot_distances, plain.foot_distances, atol=1e-9)
    # The tilt is a shear of heights (`Registration`), not a turn: slopes a and 0 sheared by
    # t meet at an angle changed by t (1 / (1 + a^2) - 1) = -0.038 t for a = 0.2.
    t = math.hypot(2e-4, 1e-4)
    np.testing.assert_allclose(seen.inclinations, plain.inclinations, atol=0.04 * t)
    np.testing.assert_allclose(plain.edge_distances, 2 * cam.CROWN.apothem, atol=2e-9)
