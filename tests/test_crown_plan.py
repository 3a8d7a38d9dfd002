"""The crown's finishing passes and machining time (`machinesim.cam.crown`, paper 002 section
3.2.4): passes clipped to the faces, their time against the whole program's plan, and the
paper's 9.5 h."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim import load_machine, motion
from machinesim.cam import crown as cam
from machinesim.realism import draw_spheres, make_spheres
from machinesim.units import M_PER_MM as MM

MACHINE = load_machine("robonano_a0ib")
#: Paper 002 section 3.2.4: 9.5 h in all, 12 min of it setting.
PAPER_TOTAL_H, PAPER_SETTING_MIN = 9.5, 12.0


def _all_passes(groups):
    return [(g.c, *g.pass_ends(j)) for g in groups for j in range(g.count)]


def test_top_passes_cover_the_octagon_chord_by_chord():
    """Each top pass at row y runs over the chord of the octagon of apothem a + overrun:
    |x| <= min(R, R sqrt 2 - |y|), R = a + overrun; rows at multiples of the pitch."""
    plan = cam.CROWN
    reach = plan.apothem + plan.overrun
    top = [(s, e) for c, s, e in _all_passes(cam.crown_passes(plan, offsets=[0.0]))
           if c == 0.0 and s[2] == e[2] == 0.0]
    ys = np.array([s[1] for s, _ in top])
    want = np.minimum(reach, reach * math.sqrt(2.0) - np.abs(ys))
    np.testing.assert_allclose([e[0] for _, e in top], want, rtol=0, atol=1e-15)
    np.testing.assert_allclose([-s[0] for s, _ in top], want, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.diff(np.sort(ys)), plan.pitch, rtol=1e-12)
    assert ys.max() == pytest.approx(math.floor(reach / plan.pitch) * plan.pitch)
    # summed over the rows the chords make the octagon's area, 8 R^2 tan(22.5 deg), to the
    # rows' discretisation: the last row stops short of y = R by < a pitch, where the chord
    # is the top edge, 2 R tan(22.5 deg): < 2 x 2 R tan(22.5) pitch / area = 0.5 % here
    area = sum(2 * e[0] for _, e in top) * plan.pitch
    assert area == pytest.approx(8 * reach**2 * math.tan(math.pi / 8),
                                 rel=plan.pitch / reach)


def test_side_passes_start_on_the_hip_lines_and_end_above_the_flat():
    """A side pass at v along the edge starts at r = max(top edge, |v| / tan 22.5 deg) on the
    layer's plane and ends 1 um above the flat; every point lies on the face's layer."""
    plan = cam.CROWN
    tan_s = math.tan(plan.slope)
    passes = [(c, s, e) for c, s, e in _all_passes(cam.crown_passes(plan, offsets=[0.0]))
              if c == math.radians(45.0)]
    top_r = plan.apothem - plan.rough_top / tan_s
    foot_r = plan.apothem + (-plan.rough_flat - plan.depth_of_cut) / tan_s
    for _, s, e in passes:
        assert s[0] == pytest.approx(max(top_r, abs(s[1]) / math.tan(math.pi / 8)), abs=1e-15)
        assert e[0] == pytest.approx(foot_r, abs=1e-15)
        for p in (s, e):
            assert p[2] == pytest.approx(-(p[0] - plan.apothem) * tan_s, abs=1e-15)
    assert max(abs(s[1]) for _, s, _ in passes) <= foot_r * math.tan(math.pi / 8)


def test_machining_time_matches_the_plan_of_the_whole_program():
    """Groups planned with one, two (three) passes against the whole program planned at
    once: equal passes exactly, passes whose ends move to 0.05 s in the 9 h (the rapids'
    lengths change non-linearly), checked on every finishing pass of the crown."""
    groups = cam.crown_passes()
    assert any(not g.equal for g in groups) and any(g.equal and g.count > 2 for g in groups)
    whole = motion.plan(cam.passes_program(groups, stagger=False), MACHINE,
                        start=cam.PARK).duration
    assert cam.machining_time(MACHINE, groups) == pytest.approx(whole, abs=0.05)
    equal = [g for g in groups if g.equal][:6]
    whole = motion.plan(cam.passes_program(equal, stagger=False), MACHINE,
                        start=cam.PARK).duration
    assert cam.machining_time(MACHINE, equal) == pytest.approx(whole, rel=1e-9)


def test_the_finishing_time_is_the_papers():
    """Finishing the rough crown (10 layers of 1 um, pitch feed 12.5 um, 20 mm/min) plus the
    paper's 12 min of setting: the paper's 9.5 h (section 3.2.4) within 2 %: the crown's
    size (Fig. 9 is missing) was chosen for it. Second method: every pass is fed along its
    length and down and up by `CLEARANCE` at the feed; the rest (rapids, turns of C) adds
    under 2 %."""
    groups = cam.crown_passes()
    finishing = cam.machining_time(MACHINE, groups)
    total_h = (finishing + cam.SETTING_S) / 3600.0
    assert cam.SETTING_S == PAPER_SETTING_MIN * 60.0
    assert total_h == pytest.approx(PAPER_TOTAL_H, rel=0.02)
    passes = _all_passes(groups)
    fed = sum(np.linalg.norm(e - s) + 2 * cam.CLEARANCE for _, s, e in passes)
    feed = fed / (cam.FEED_MM_PER_MIN * MM / 60.0)
    assert feed < finishing < 1.02 * feed


def test_crown_stock_is_the_blank_with_the_designed_spheres():
    """`crown_stock` is `crown_blank` less the three designed sphere cavities: the volume
    removed is three spherical caps below the flat (the spheres' centres lie in it), i.e.
    three half balls, to the polygon's chord tolerance."""
    blank, stock = cam.crown_blank(), cam.crown_stock()
    r = cam.crown_sphere_design().radius
    assert blank.volume - stock.volume == pytest.approx(3 * 2 / 3 * math.pi * r**3, rel=2e-4)
    design = cam.crown_sphere_design()
    again = make_spheres(blank, design, draw_spheres(design, None))
    assert again.volume == pytest.approx(stock.volume, rel=1e-12)
    assert cam.CROWN.cuboid_half == pytest.approx(cam.CROWN.apothem + 5 * (
        cam.CROWN.height - cam.CROWN.oversize), rel=1e-12)


@pytest.mark.parametrize(("fields", "key"), [
    ({"pitch": 0.0}, "pitch"), ({"pitch": float("nan")}, "pitch"),
    ({"pitch": -12.5e-6}, "pitch"), ({"apothem": -1.5e-3}, "apothem"),
    ({"depth_of_cut": 0.0}, "depth_of_cut"), ({"slope": 0.0}, "slope"),
    ({"slope": math.pi / 2}, "slope"), ({"oversize": math.inf}, "oversize"),
    ({"height": 5e-6}, "height"), ({"overrun": -1e-3}, "overrun"),
    ({"pitch": True}, "pitch"), ({"pitch": 12.5e-12}, "pitch"),
    ({"depth_of_cut": 4e-6}, "depth_of_cut"),
    # too many passes named by the field that asks for them: these were told as the pitch
    ({"slope": 1e-9}, "slope"), ({"overrun": 1.0}, "overrun"), ({"apothem": 10.0}, "apothem"),
    ({"height": 1000.0}, "height"), ({"depth_of_cut": 1e-12}, "depth_of_cut")])
def test_a_crown_plan_out_of_its_bounds_is_refused_naming_the_field(fields, key):
    # CrownPlan took anything: a pitch or depth of cut of 0 was a ZeroDivisionError in
    # crown_passes, a NaN pitch numpy's ValueError, an infinite oversize an OverflowError; a
    # negative pitch or apothem made no pass at all, silently; a pitch in the wrong unit
    # (12.5 pm) asked for ~10^10 passes. 4 um cuts of the 10 um oversize made layers at 4
    # and 0 um (round(2.5) = 2), the first cutting 6 um, not 4
    from machinesim.exceptions import InputError

    with pytest.raises(InputError, match=f"key '{key}'"):
        cam.CrownPlan(**fields)


def test_a_crown_plan_in_its_bounds_makes_its_layers():
    # 12 um in 3 um cuts: four layers at 9, 6, 3 and 0 um over the finished faces (hand)
    plan = cam.CrownPlan(oversize=12e-6, depth_of_cut=3e-6)
    assert plan.layers == 4
    tops = sorted({round(g.start[2] / 1e-6, 9) for g in cam.crown_passes(plan)
                   if g.start[2] == g.end[2]})  # the top face's passes, level
    assert tops == [0.0, 3.0, 6.0, 9.0]
    assert cam.CrownPlan() == cam.CROWN  # the paper's plan is taken as it was


@pytest.mark.parametrize(("fields", "words"), [
    ({"depth": -3e-6}, "key 'depth': Expected depth > 0"),
    ({"depth": 0.0}, "key 'depth': Expected depth > 0"),
    ({"depth": 3e-3}, "key 'depth': Expected depth below the groove block's thickness"),
    ({"depth": True}, "key 'depth': Expected depth as a number"),
    ({"length": -1e-3}, "key 'length': Expected length > 0"),
    ({"length": float("nan")}, "key 'length': Expected length > 0")])
def test_groove_program_refuses_grooves_off_the_block(fields, words):
    # depth -3 um made four 'grooves' 3 um over the block's top, silently (every move's Z
    # > 0), 3 mm cut through the 3 mm block, a negative length ran each groove back along -X
    from machinesim.exceptions import InputError

    with pytest.raises(InputError, match=words):
        cam.groove_program(**fields)
    program = cam.groove_program(depth=5e-6, length=2e-3)
    z = program.targets[:, 2]
    assert np.nanmin(z) == pytest.approx(-5e-6, abs=1e-18)
