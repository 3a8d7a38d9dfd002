"""Paper 002's crown read as the paper reads it (machinesim.metrology.crown_image).

Known values: the designed crown (edge distance 2 x apothem, faces at atan 0.2); a crown
made with another apothem and slope; the statistics of a height-over-length reading
derived by hand; a profile with a step beyond the face, as the windowed cut leaves.
"""

import math

import numpy as np
import pytest
from scipy.special import ndtr

from machinesim import Lab, load_machine
from machinesim.cam.crown import (
    CROWN,
    CROWN_BASE,
    CROWN_BASE_HEIGHT,
    crown_blank,
    crown_design,
    crown_roi,
)
from machinesim.exceptions import InputError
from machinesim.metrology import Microscope
from machinesim.metrology.crown_image import (
    CLEARANCE_SIGMAS,
    crown_image_reading,
    profile_edges,
    profile_reading,
    spot_clearance,
    turned_placements,
)
from machinesim.realism import OBJECTIVE_10X, Realism
from machinesim.workpiece import Part, block, diamond_crown

UM = 1e-6
WINDOWS = crown_roi(CROWN)[0]
EXACT = Microscope(noise=False, lateral_spacing=OBJECTIVE_10X.pixel)


def test_the_designed_crown_reads_its_design_without_imperfections():
    part = crown_design(CROWN)
    reading = crown_image_reading(part, EXACT, WINDOWS, CROWN)
    np.testing.assert_allclose(reading.edge_distances, 2 * CROWN.apothem, rtol=0, atol=5e-9)
    np.testing.assert_allclose(reading.inclinations, CROWN.slope, rtol=0, atol=1e-6)


def test_a_crown_of_another_size_and_slope_reads_its_own():
    """3 um more apothem and faces at atan 0.205: L and S read those, not the plan's."""
    apothem, slope = CROWN.apothem + 3 * UM, math.atan(0.205)
    part = diamond_crown(0.0, 2 * apothem, CROWN.height - CROWN.oversize, CROWN_BASE,
                         CROWN_BASE_HEIGHT, slope)
    reading = crown_image_reading(part, EXACT, WINDOWS, CROWN)
    np.testing.assert_allclose(reading.edge_distances, 2 * apothem, rtol=0, atol=5e-9)
    np.testing.assert_allclose(reading.inclinations, slope, rtol=0, atol=1e-6)


def test_the_height_over_length_scatter_is_the_height_noise_carried_by_hand():
    """S = atan(h / l): a height error e on each of the two cursors gives
    sd(S) = sqrt(2) sd(e) l / (l^2 + h^2) (h = 60 um, l = 300 um). sd(e): the 10x's height
    noise sigma = 0.179 um (0.0465 deg in S), and the pixel cursor: half the time it sits
    off the face (on the top, or on the flat past the foot), u ~ U(0, p/2) from the corner,
    and reads m u off the face's line (m = tan 11.31 deg, p the 1.32 um pixel), a variance
    of 5 m^2 p^2 / 192 (+2.8 % in sd). 128 readings (16 seeds x 8 faces): their sd within
    25 % of it (the sd of an sd over 128 draws is 6 %; measured +17 %: the corners the
    cursors sit by are themselves read through the noise and the 1 um spot), and the pixel
    cursor reads shallower on average, never steeper beyond the noise (mean below 0, above
    -2 sd / sqrt(128) - 0.03 deg)."""
    part = crown_design(CROWN)
    meshes = turned_placements(part)
    errors = []
    seeds = 16
    for seed in range(seeds):
        scope = Microscope(sigma=OBJECTIVE_10X.sigma, lateral_spacing=OBJECTIVE_10X.pixel,
                           spot=OBJECTIVE_10X.spot, rng=seed)
        reading = crown_image_reading(part, scope, WINDOWS, CROWN, meshes=meshes)
        errors += list(reading.inclinations - CROWN.slope)
    h, run = CROWN.height - CROWN.oversize, CROWN.run
    gain = math.sqrt(2.0) * run / (run**2 + h**2)
    assert math.degrees(gain * OBJECTIVE_10X.sigma) == pytest.approx(0.0465, abs=5e-4)
    m, p = math.tan(CROWN.slope), OBJECTIVE_10X.pixel
    expected = gain * math.sqrt(OBJECTIVE_10X.sigma**2 + 5.0 * (m * p) ** 2 / 192.0)
    assert np.std(errors) == pytest.approx(expected, rel=0.25)
    assert -0.03 - 2 * math.degrees(expected) / math.sqrt(8 * seeds) \
        < math.degrees(np.mean(errors)) < 0.0


def test_the_lab_reads_through_the_10x_objective_with_its_switches():
    machine = load_machine("robonano_a0ib")
    ideal = Lab(machine, realism=Realism.ideal()).microscope(objective=OBJECTIVE_10X)
    assert ideal.spot is None and ideal.readout.sigma == 0.0
    assert ideal.lateral_spacing == OBJECTIVE_10X.pixel
    lab = Lab(machine, realism=Realism.lab()).microscope(objective=OBJECTIVE_10X)
    assert lab.spot == OBJECTIVE_10X.spot and lab.readout.sigma == OBJECTIVE_10X.sigma
    assert lab.stage_sigma == 1e-6


def test_a_face_that_ends_in_a_step_has_its_foot_at_the_step():
    """A top at 60 um, a face at slope 0.2 down to 1 um, then a band standing 10 um above
    the face's line (the rough stock beyond a windowed cut's last pass), then the flat."""
    s = np.arange(0.0, 500e-6, 1e-6)
    top, foot = 100e-6, 395e-6
    z = np.where(s < top, 60e-6, 60e-6 - 0.2 * (s - top))
    band = (s >= foot) & (s < foot + 50e-6)
    z = np.where(band, 60e-6 - 0.2 * (s - top) + 10.2e-6, np.maximum(z, 0.0))
    z = np.where(s >= foot + 50e-6, 0.0, z)
    edges = profile_edges(s, z, pixel=False, band=0.5e-6)
    assert edges.s_top == pytest.approx(top, abs=1e-12)
    assert edges.s_foot == pytest.approx(foot - 1e-6, abs=1e-12)  # the face's last sample
    assert edges.inclination == pytest.approx(math.atan(0.2), abs=1e-12)
    # a face that runs on into the flat: the corner
    smooth = np.maximum(np.where(s < top, 60e-6, 60e-6 - 0.2 * (s - top)), 0.0)
    edges = profile_edges(s, smooth, pixel=False, band=0.5e-6)
    assert edges.s_foot == pytest.approx(top + 300e-6, abs=1e-12)
    assert edges.inclination == pytest.approx(math.atan(0.2), abs=1e-12)


def _blurred(s, base, kinks, steps, sigma):
    """The Gaussian blur (standard deviation ``sigma``) of the profile ``base`` plus slope
    changes ``kinks`` [(at, change)] and steps ``steps`` [(at, height)], in closed form: a
    step h at a reads h Phi(u), a slope change c at a reads c ((s - a) Phi(u) + sigma phi(u)),
    u = (s - a) / sigma; a constant is unchanged. A surface the same along the profile's
    normal reads so through a round Gaussian spot."""
    z = np.full_like(s, base)
    for at, change in kinks:
        u = (s - at) / sigma
        z += change * ((s - at) * ndtr(u) + sigma * np.exp(-0.5 * u * u) / math.sqrt(2 * math.pi))
    for at, height in steps:
        z += height * ndtr((s - at) / sigma)
    return z


def test_a_face_that_steps_away_to_a_wall_has_its_foot_cursor_clear_of_the_walls_blur():
    """Paper 002's face 2 after: a face at slope 0.2 whose passes stop 1.2 um short of a
    9.5 um wall up to the uncut band, read through the 10x's 1 um spot at its 1.32 um pixel,
    the last sample on the face's line 0.5 um before the wall (the wall's blur lifts it
    1.13 um, the ledge 0.14 um: inside the 1.4 um band). The foot cursor goes on the last
    sample `CLEARANCE_SIGMAS` sigmas or more before the wall, and S reads atan 0.2 within
    what the blur can move the two cursors: each slope change c lifts or lowers a sample by
    at most c sigma phi(0), a step h at k sigmas by h Phi(-k)."""
    pixel, spot = OBJECTIVE_10X.pixel, OBJECTIVE_10X.spot
    sigma = spot.width / (2 * math.sqrt(2 * math.log(2)))  # the width is the FWHM
    s = np.arange(400) * pixel
    top, slope, wall, height, band = s[76], 0.2, s[295] + 0.5 * UM, 9.5 * UM, 1.4 * UM
    face_end = wall - 1.2 * UM
    # the face, its ledge, the wall and the uncut band parallel to the face (the rough face)
    kinks = [(top, -slope), (face_end, slope), (wall, -slope)]
    z = _blurred(s, 60 * UM, kinks, [(wall, height)], sigma)
    clearance = spot_clearance(spot)
    assert clearance == pytest.approx(CLEARANCE_SIGMAS * sigma, rel=1e-15)
    assert height * ndtr(-CLEARANCE_SIGMAS) < 1e-3 * height
    old = profile_edges(s, z, pixel=True, band=band)
    assert old.s_foot == s[295]  # the face's last sample: 0.5 um from the wall
    edges = profile_edges(s, z, pixel=True, band=band, clearance=clearance)
    clear = s[s <= wall - CLEARANCE_SIGMAS * sigma]
    assert edges.s_foot == clear[-1] == s[294]
    assert edges.s_top == top
    bound = (3 * slope * sigma / math.sqrt(2 * math.pi) + height * ndtr(-CLEARANCE_SIGMAS)) / (
        edges.s_foot - edges.s_top)
    assert abs(edges.inclination - math.atan(slope)) <= bound
    assert abs(old.inclination - math.atan(slope)) > 10 * bound  # the wall's blur read
    # without a spot (exact heights) the foot is the face's last sample either way
    sharp = _blurred(s, 60 * UM, kinks, [], 1e-12)
    sharp = np.where(s > wall, sharp + height, sharp)
    assert profile_edges(s, sharp, pixel=True, band=band).s_foot == s[295]
    # a face that runs on into the flat keeps its corner, clearance or not
    smooth = _blurred(s, 60 * UM, [(top, -slope), (s[376], slope)], [], sigma)
    for c in (0.0, clearance):
        assert profile_edges(s, smooth, pixel=False, band=band, clearance=c).s_foot \
            == pytest.approx(s[376], abs=1e-9)


def test_a_face_with_no_sample_clear_of_its_wall_says_so_and_a_bad_clearance_is_refused():
    s = np.arange(400) * UM
    z = np.where(s < 100 * UM, 60 * UM, 60 * UM - 0.2 * (s - 100 * UM))
    z = np.where(s >= 395 * UM, z + 10.2 * UM, z)
    why = profile_reading(s, z, pixel=True, band=0.5 * UM, clearance=300 * UM)
    assert isinstance(why, str) and why.startswith("no foot clear of the wall")
    assert "394 um" in why and "300 um" in why
    assert profile_edges(s, z, pixel=True, band=0.5 * UM, clearance=300 * UM) is None
    assert profile_edges(s, z, pixel=True, band=0.5 * UM, clearance=3 * UM).s_foot == s[391]
    for bad in (-1e-6, float("nan"), "1e-6"):
        with pytest.raises(InputError, match="clearance"):
            profile_reading(s, z, pixel=True, band=0.5 * UM, clearance=bad)


def test_a_profile_without_a_level_top_is_unreadable():
    s = np.arange(0.0, 400e-6, 1e-6)
    assert profile_edges(s, 60e-6 - 0.2 * s, pixel=False, band=0.5e-6) is None


def test_uncut_stock_above_the_top_puts_the_edge_where_the_cut_face_crosses_the_top():
    """The face's passes moved out by 130 um (a C centre off by 65 um) on a workpiece set
    34 um high: the top at 60 um, then the rough face standing 44.2 um above the designed
    one from the top's edge until the passes begin, an 18.2 um step down to the cut face,
    which crosses the top's level 130 um out and runs down at slope 0.2. The edge is that
    crossing, not the top's end."""
    s = np.arange(0.0, 700e-6, 1e-6)
    end, shift = 100e-6, 130e-6
    rough = 60e-6 + 44.2e-6 - 0.2 * (s - end)
    cut = 60e-6 - 0.2 * (s - end - shift)
    z = np.where(s < end, 60e-6, np.where(s < end + shift, rough, np.maximum(cut, 0.0)))
    edges = profile_edges(s, z, pixel=False, band=0.5e-6)
    assert edges.s_top == pytest.approx(end + shift, abs=1e-12)
    assert edges.z_top == pytest.approx(60e-6, abs=1e-15)
    assert edges.inclination == pytest.approx(math.atan(0.2), abs=1e-12)
    # the band as the top's pass ends leave it at a diagonal face: rising gently (0.03) for
    # 60 um, then the cut face; the top's line is taken before the rise, not across it
    rise = np.where(s < end, 60e-6, np.minimum(60e-6 + 0.03 * (s - end),
                                               61.8e-6 - 0.2 * (s - end - 60e-6)))
    edges = profile_edges(s, np.maximum(rise, 0.0), pixel=False, band=0.5e-6)
    assert edges.s_top == pytest.approx(end + 60e-6 + 9e-6, abs=1e-12)


def test_a_top_not_level_with_the_flat_is_followed_as_a_line():
    """A crown cut level on a workpiece tilted by 1.93 deg, seen levelled on its flat: the
    top falls outward at tan 1.93 deg (3.4 um over 100 um, more than the band) and the face
    at 11.31 + 1.93 deg. The top edge is the corner of the two, and S is the face's angle,
    not the corner of the top with itself."""
    s = np.arange(0.0, 700e-6, 1e-6)
    top_end = 150e-6
    top = 60e-6 - math.tan(math.radians(1.93)) * s
    face = top[150] - math.tan(math.atan(0.2) + math.radians(1.93)) * (s - top_end)
    z = np.maximum(np.where(s < top_end, top, face), 0.0)
    edges = profile_edges(s, z, pixel=False, band=0.5e-6)
    assert edges.s_top == pytest.approx(top_end, abs=1e-12)
    assert edges.inclination == pytest.approx(math.atan(0.2) + math.radians(1.93), abs=1e-12)


def test_a_gently_sloping_top_is_followed_to_its_edge():
    """A top falling 0.9 um over the first 60 um (less than the 1.4 um band there: the
    tilt of a crown's low side, levelled on the flat) and 3 um by its edge at 200 um: the
    top's line is grown from its start, so the edge is the corner of the top and the face,
    to round-off, and S the face's angle to the flat. Taken as level, the top leaves its
    level by the band at 93 um, where both lines would be fitted on the top."""
    s = np.arange(0.0, 600e-6, 1.3e-6)
    slope, top_end = 0.015, 200e-6
    top = -slope * s
    face = -slope * top_end - 0.2 * (s - top_end)
    z = np.maximum(np.where(s < top_end, top, face), -40e-6)
    edges = profile_edges(s, z, pixel=False, band=1.4e-6)
    assert edges.s_top == pytest.approx(top_end, abs=1e-12)
    assert edges.inclination == pytest.approx(math.atan(0.2), abs=1e-12)
    assert edges.s_foot == pytest.approx(top_end + (40e-6 - slope * top_end) / 0.2, abs=1e-12)


def test_a_long_face_read_through_noise_runs_to_its_foot():
    """A face 300 um long read with the 10x's height noise (0.179 um, band 5 sigma + 0.5
    um): the face's line is refitted on what keeps to it, so the foot is found at the
    foot in every one of 300 draws (within 3 um: the noise on two lines meeting at
    11.3 deg), where a line fitted on the face's first 55 um alone, extrapolated, leaves
    the face by the band early in some."""
    s = np.arange(0.0, 560e-6, 1.318e-6)
    top_end, foot = 100e-6, 400e-6
    clean = np.where(s < top_end, 0.0, -0.2 * (s - top_end))
    clean = np.maximum(clean, -0.2 * (foot - top_end))
    sigma = OBJECTIVE_10X.sigma
    rng = np.random.default_rng(5)
    feet = []
    for _ in range(300):
        edges = profile_edges(s, clean + sigma * rng.standard_normal(len(s)), pixel=False,
                              band=5 * sigma + 0.5e-6)
        feet.append(edges.s_foot)
    assert np.abs(np.array(feet) - foot).max() < 3e-6


def test_a_profile_that_never_falls_from_its_top_says_so():
    """A face not cut: the profile keeps level (0.5 um band) over its 399 um, or stock
    stands 40 um above the top from 100 um on; either way no top edge, and why."""
    s = np.arange(400) * 1e-6
    assert profile_reading(s, np.full_like(s, 60e-6), pixel=False, band=0.5e-6) == (
        "no top edge: the profile does not fall from the top down a face; it keeps within "
        "0.5 um of the top's line over its whole 399 um (the face is not cut there)")
    stock = np.where(s < 99.5e-6, 60e-6, 100e-6)  # the 101st sample on
    assert profile_reading(s, stock, pixel=False, band=0.5e-6) == (
        "no top edge: the profile does not fall from the top down a face; it leaves the "
        "top's line only upward (stock up to 40 um above it from 100 um along the profile "
        "on) and never falls 0.5 um below it in its 399 um (the face is not cut there)")
    assert profile_edges(s, stock, pixel=False, band=0.5e-6) is None


def test_a_face_left_uncut_is_n_a_with_the_reason_and_the_rest_reads_its_design():
    """The designed crown with stock standing 40 um above its top over faces S2 and S6 (C =
    45 and 225 deg) from their top edges out, as a setting far off leaves faces its passes
    miss (paper 002 at --delta-um 300,0,55: S2, S8, L2 and L6, L4 and L8 n/a, no word why).
    S2, S6 and L2 (its edge points: two on S2, one on S6) are NaN, each saying which
    profiles and what they found; every other figure reads its design, nothing else said."""
    stock = block(1e-3, 0.8e-3, 0.54e-3, (CROWN.apothem, -0.4e-3, 40 * UM)).manifold
    part = Part(crown_design(CROWN).manifold + stock.rotate((0.0, 0.0, 45.0))
                + stock.rotate((0.0, 0.0, 225.0)))
    reading = crown_image_reading(part, EXACT, WINDOWS, CROWN)
    assert np.isnan(reading.inclinations[[1, 5]]).all() and np.isnan(reading.edge_distances[1])
    np.testing.assert_allclose(np.delete(reading.inclinations, [1, 5]), CROWN.slope, rtol=0,
                               atol=1e-6)
    np.testing.assert_allclose(np.delete(reading.edge_distances, 1), 2 * CROWN.apothem,
                               rtol=0, atol=5e-9)
    found = ("no top edge: the profile does not fall from the top down a face; it leaves "
             "the top's line only upward (stock up to 40 um above it from 100 um along the "
             "profile on)")  # the image window starts 100 um inside the top edge
    assert set(reading.unread) == {"S2", "S6", "L2_L6"}
    for face in ("S2 (C = 45 deg)", "S6 (C = 225 deg)"):
        assert reading.unread[face[:2]].startswith(
            f"face {face}, the profile across its middle: {found}")
    a = 0.8 * WINDOWS["image"][3] / UM  # the edge's two points, 200 um either side
    profiles = reading.unread["L2_L6"].split("; face ")
    assert len(profiles) == 3
    assert [p.split(": ", 1)[0] for p in profiles] == [
        f"face S2 (C = 45 deg), the profile across it at {-a:+.0f} um along its edge (not "
        "read in 3 of 3 readings)",
        f"S2 (C = 45 deg), the profile across it at {a:+.0f} um along its edge (not read in "
        "3 of 3 readings)",
        "S6 (C = 225 deg), the profile across its middle (not read in 3 of 3 readings)"]
    assert all(p.split(": ", 1)[1].startswith(found) for p in profiles)


def test_a_plane_fitted_where_no_face_is_cut_is_n_a_with_the_reason():
    """The designed crown with stock standing 40 um above its top over face S2 (its window
    all stock: a plane parallel to the flat) and level with the top over the outer half of
    face S4's window (a cut face and a step of stock, fitted at 11.57 deg). The plane fits
    read them as faces and printed nonsense (paper 002 at --delta-um 300,0,55: planes L2 and
    L6 3440 um, feet 10,230,498 um; S2's plane exactly parallel to the top stopped the
    reading). Now S2 (slope 0.00 deg, more than 5 deg off 11.31) and S4 (residual RMS
    some um against a cut face's 0.1 um) are NaN with why, with their pairs' L and feet;
    the other faces read their design, nothing said."""
    from machinesim.metrology import crown_features

    stock = block(1e-3, 0.8e-3, 0.54e-3, (CROWN.apothem, -0.4e-3, 40 * UM)).manifold
    middle = 0.5 * (WINDOWS["side"][0] + WINDOWS["side"][1])
    step = block(1e-3, 0.8e-3, 0.54e-3, (middle, -0.4e-3, 0.0)).manifold
    part = Part(crown_design(CROWN).manifold + stock.rotate((0.0, 0.0, 45.0))
                + step.rotate((0.0, 0.0, 135.0)))
    features = crown_features(part, Microscope(noise=False), WINDOWS, slope=CROWN.slope)
    assert np.isnan(features.inclinations[[1, 3]]).all()
    np.testing.assert_allclose(np.delete(features.inclinations, [1, 3]), CROWN.slope,
                               rtol=0, atol=1e-7)
    for values in (features.edge_distances, features.foot_distances):
        assert np.isnan(values[[1, 3]]).all()
    np.testing.assert_allclose(features.edge_distances[[0, 2]], 2 * CROWN.apothem, rtol=0,
                               atol=1e-10)
    s2 = ("face S2 (C = 45 deg), the plane fitted in its window: fitted slope 0.00 deg, "
          "designed 11.31 (more than 5 deg off): the face is not cut there")
    assert dict(features.unread) == {"S2": s2, "S4": features.unread["S4"], "L2_L6": s2,
                                     "L4_L8": features.unread["S4"]}
    # S4's window: the face falls 30 um (0.2 x 150 um) from the top's level to the window's
    # middle, where the stock stands at the top's level: a step of 30-45 um over half the
    # samples, a residual of a few to ten um, far above the cut faces' (here 0)
    head, rest = features.unread["S4"].split("residual RMS ")
    assert head == "face S4 (C = 135 deg), the plane fitted in its window: "
    assert 3 < float(rest.split(" um")[0]) < 15
    assert rest.endswith("um, a cut face's 0.1 um or less (fitted slope 11.57 deg): the "
                         "window holds uncut stock as well")


def test_a_face_left_rough_is_n_a_in_plane_fits_and_images_with_the_reason():
    """The designed crown with face S6 (C = 225 deg) and the top next to it left as roughed
    (the drawing's rough crown, `crown_blank`: every face 10 um out along its normal): a
    perfect plane at the designed slope, so the slope and residual limits pass it, and its
    profiles run from a top down a face. Paper 002's large setting (--quick --delta-um
    80,-60,20 --rot-deg 0.5,-0.3,2.0) read such faces as cut: planes S6 -0.0032 deg, images
    S5 -0.051, S6 -0.097 deg and L2 82.2 um, no word. Now the plane fit's S6, L2 and foot
    L2 and the images' S6 and L2 are NaN, each saying the face lies 10.000 um out (the
    allowance, exactly); every other figure reads its design, nothing else said."""
    from machinesim.metrology import crown_features

    # r 1.2 .. 2.5 mm out along C = 225 deg (the top window ends at 0.57 mm), 0.9 mm wide
    wedge = block(1.3e-3, 0.9e-3, 1e-3, (1.2e-3, -0.45e-3, 0.5e-3)).manifold
    part = Part(crown_design(CROWN).manifold
                + (crown_blank(CROWN).manifold ^ wedge.rotate((0.0, 0.0, 225.0))))
    out = ("lies 10.000 um out from the design along its normal, the rough face 10 um (a "
           "cut face lies at or inside the design; 0.5 of the allowance out or more is "
           "uncut): the face is not cut there")
    features = crown_features(part, Microscope(noise=False), WINDOWS, plan=CROWN)
    s6 = f"face S6 (C = 225 deg), the plane fitted in its window: the rough face: it {out}"
    assert dict(features.unread) == {"S6": s6, "L2_L6": s6}
    assert np.isnan(features.inclinations[5])
    assert np.isnan(features.edge_distances[1]) and np.isnan(features.foot_distances[1])
    np.testing.assert_allclose(np.delete(features.inclinations, 5), CROWN.slope, rtol=0,
                               atol=1e-7)
    np.testing.assert_allclose(np.delete(features.edge_distances, 1), 2 * CROWN.apothem,
                               rtol=0, atol=1e-10)
    reading = crown_image_reading(part, EXACT, WINDOWS, CROWN)
    assert set(reading.unread) == {"S6", "L2_L6"}
    assert np.isnan(reading.inclinations[5]) and np.isnan(reading.edge_distances[1])
    head, tail = reading.unread["S6"].split(" along the profile, ")
    assert head.startswith("face S6 (C = 225 deg), the profile across its middle: the rough "
                           "face: the face's line, read from the top edge at ")
    assert tail == out
    assert reading.unread["L2_L6"].startswith(
        "face S6 (C = 225 deg), the profile across its middle (not read in 3 of 3 "
        "readings): the rough face: ") and reading.unread["L2_L6"].endswith(out)
    np.testing.assert_allclose(np.delete(reading.inclinations, 5), CROWN.slope, rtol=0,
                               atol=1e-6)
    np.testing.assert_allclose(np.delete(reading.edge_distances, 1), 2 * CROWN.apothem,
                               rtol=0, atol=5e-9)


def test_inscribed_stays_inside_a_square_at_every_turn_and_refuses_another_box():
    """The box turned back lies inside the square at any turn, its corners on the square's
    inscribed circle (by hand: half size h / sqrt(2) turned has corners at radius h). A 4 x 1
    box turned 90 deg would give a box reaching 1.41 along y against 0.5: refused by name."""
    from machinesim.exceptions import InputError
    from machinesim.metrology.crown_image import inscribed

    square = (1.0, 3.0, -2.0, 0.0)
    centre = np.array([2.0, -1.0])
    for turn in np.linspace(0.0, 2 * math.pi, 17):
        x0, x1, y0, y1 = inscribed(square, turn)
        c, s = math.cos(turn), math.sin(turn)
        corners = np.array([[c * x - s * y, s * x + c * y] for x in (x0, x1) for y in (y0, y1)])
        np.testing.assert_allclose(np.hypot(*(corners - centre).T), 1.0, rtol=1e-12)
    with pytest.raises(InputError, match=r"key 'box': expected a square box .* got "
                                         r"\(0, 4, 0, 1\): 4 m by 1 m"):
        inscribed((0.0, 4.0, 0.0, 1.0), math.pi / 2)
    with pytest.raises(InputError, match=r"got \(0, 1, 0, nan\)"):
        inscribed((0.0, 1.0, 0.0, float("nan")), 0.0)
