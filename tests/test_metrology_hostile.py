"""Hostile input to the metrology API, the lab's instrument methods and the file writer: each
refusal is an `InputError` (a `FileError` for the file system) naming the argument, the value
and what was expected; no bare TypeError, ValueError, numpy error or MemoryError, and no
silently meaningless number. Plus the documented pipeline of a probe scan through
`TouchProbe.nominal_centres`, and the Gaussian spot's reading of a step edge."""

import math
import os

import numpy as np
import pytest
from metrology_helpers import above

import machinesim
from machinesim import _io
from machinesim.exceptions import FileError, InputError
from machinesim.metrology import (
    Line2D,
    Microscope,
    RTest,
    TouchProbe,
    fit_line,
    fit_parallel_edges,
    fit_plane,
    fit_sphere,
    fit_v_groove,
    form_error,
    groove_pitch,
    height_map,
    intersect_lines,
    line_distance,
    plane_angle,
    plane_intersection,
    roughness_sa,
    sphere_centre_from_touch,
    step_positions,
)
from machinesim.metrology.imperfections import Spot
from machinesim.metrology.instruments import OPTICAL_LIMIT
from machinesim.metrology.surface import MAX_SAMPLES

MM, UM, NM = 1e-3, 1e-6, 1e-9
R = 0.25 * MM
#: float64 round-off of mm-scale coordinates (~1e-19 m); 1e-15 m fails on any real error.
ROUND_OFF_M = 1e-15






def groove_profile():
    """A 20 um deep, 40 um wide V groove in the middle of a 100 um profile."""
    s = np.linspace(0.0, 100 * UM, 201)
    return s, -np.maximum(0.0, 20 * UM - np.abs(s - 50 * UM))


def flat_map():
    x = y = np.arange(11) * UM
    return x, y, np.zeros((11, 11))


# --------------------------------------------------------------------- A: bad types in fits


def test_v_groove_threshold_must_be_a_number():
    s, z = groove_profile()
    assert fit_v_groove(s, z, threshold=1 * UM).depth == pytest.approx(20 * UM, abs=1e-12)
    for bad in ("1e-6", [1e-6]):
        with pytest.raises(InputError, match=r"threshold as a number \(m\), got "):
            fit_v_groove(s, z, threshold=bad)


def test_sphere_fits_refuse_text_none_and_arrays():
    points = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]], float)
    with pytest.raises(InputError, match=r"radius as a number \(m\), got '1'"):
        fit_sphere(points, radius="1")
    with pytest.raises(InputError, match=r"z_touch as a number \(m\), got '1'"):
        sphere_centre_from_touch((0, 0), "1", 1.0)
    with pytest.raises(InputError, match=r"z_touch as a number \(m\), got array"):
        sphere_centre_from_touch((0, 0), np.array([1.0, 2.0]), 1.0)
    with pytest.raises(InputError, match=r"radius as a number \(m\), got None"):
        sphere_centre_from_touch((0, 0), 1.0, None)
    with pytest.raises(InputError, match=r"probe_radius as a number \(m\), got '0'"):
        sphere_centre_from_touch((0, 0), 1.0, 1.0, probe_radius="0")
    with pytest.raises(InputError, match=r"xy as two numbers \(m\), got 'ab'"):
        sphere_centre_from_touch("ab", 0, 1)
    with pytest.raises(InputError, match="concave as True or False, got 'no'"):
        sphere_centre_from_touch((0, 0), 1.0, 1.0, concave="no")
    # a numpy scalar is a number: the centre 1 m above a bottom touch at z = 0.5 m
    np.testing.assert_array_equal(
        sphere_centre_from_touch((0, 0), np.float64(0.5), 1.0), [0.0, 0.0, 1.5])


def test_text_in_point_and_centre_arrays_is_refused():
    with pytest.raises(InputError, match=r"centres as numbers \(m\), got \['a', 'b'\]"):
        groove_pitch(["a", "b"])
    with pytest.raises(InputError, match=r"points as numbers \(m\), got 'abc'"):
        fit_line("abc")
    with pytest.raises(InputError, match=r"points as numbers \(m\)"):
        fit_line([["0", "0"], ["1", "1"]])  # numbers spelled as text are not converted


def test_a_bool_among_numbers_is_refused_not_read_as_1_or_0():
    # numpy makes (True, 0) an int array and [0.5, False] a float one: as_floats took them,
    # so Registration(offset=(True, 0, 0)) was a 1 m offset and fit_plane of points with a
    # True read it as 1 m; all-bool arrays were refused already
    from machinesim.metrology._arrays import as_floats
    from machinesim.metrology.imperfections import Registration

    for value in ((True, 0), [[0.5, False]], [np.True_, 2.0], [[0.0, 1.0], (2.0, True)],
                  [np.array([True, False]), [0.5, 2.0]]):
        with pytest.raises(InputError, match="key 'x': Expected x as numbers"):
            as_floats(value, "x")
    with pytest.raises(InputError, match="key 'offset'"):
        Registration(offset=(True, 0, 0))
    points = np.random.default_rng(1).normal(size=(100, 3)).tolist()  # a long list: 0s
    points[7][2] = True  # and 1s looked up
    with pytest.raises(InputError, match="key 'points'"):
        fit_plane(points)
    points[7][2] = 1  # the numbers 1 and 0, ints or floats, are numbers
    assert as_floats(points, "points")[7, 2] == 1.0 and as_floats((1, 0), "x").tolist() == [
        1.0, 0.0]
    assert Registration(offset=(1e-6, 0, 0)).offset.tolist() == [1e-6, 0.0, 0.0]


def test_roughness_cutoff_must_be_a_number_of_at_least_two_spacings():
    x, y, z = flat_map()
    z = z + np.random.default_rng(1).normal(size=z.shape) * NM
    with pytest.raises(InputError, match=r"l_cutoff as a number \(m\), got 'a'"):
        roughness_sa(x, y, z, l_cutoff="a")
    # 1 um spacing: the shortest wavelength the grid holds is 2 um
    with pytest.raises(InputError, match=r"l_cutoff >= 2 sample spacings \(2e-06 m.*got 1e-12"):
        roughness_sa(x, y, z, l_cutoff=1e-12)
    with pytest.raises(InputError, match=r"l_cutoff >= 2 sample spacings"):
        roughness_sa(x, y, z, l_cutoff=1.999 * UM)


def test_levels_must_be_numbers():
    s, z = groove_profile()
    np.testing.assert_allclose(step_positions(s, z, level=-10 * UM), [40 * UM, 60 * UM],
                               rtol=0, atol=1e-18)
    with pytest.raises(InputError, match=r"level as a number \(m\), got 'x'"):
        step_positions(s, z, level="x")
    x, y, zmap = flat_map()
    with pytest.raises(InputError, match=r"level as a number \(m\), got 'a'"):
        fit_parallel_edges(x, y, zmap, level="a")


def test_fits_refuse_what_is_not_their_input_type():
    x, y, z = flat_map()
    with pytest.raises(InputError, match=r"nominal as a function nominal\(X, Y\) -> Z"):
        form_error(x, y, z, 0.0)
    with pytest.raises(InputError, match="first as a PlaneFit"):
        plane_angle("a", "b")
    # once a raw AttributeError ('str' object has no attribute 'normal')
    plane = fit_plane([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    with pytest.raises(InputError, match="first as a plane with a point and a unit normal"):
        plane_intersection("a", plane)
    with pytest.raises(InputError, match="second as a plane with a point and a unit normal"):
        plane_intersection(plane, Line2D(np.zeros(2), np.array([1.0, 0.0]), 0.0))
    # line_distance read .point and .direction unchecked: a raw AttributeError ('str' object
    # has no attribute 'point'), and a Line2D's (2,) arrays a numpy broadcasting error
    edge = plane_intersection(plane, fit_plane([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0],
                                                [0.0, 0.0, 1.0]]))
    with pytest.raises(InputError, match="first as a line with a point and a unit direction"):
        line_distance("a", edge)
    with pytest.raises(InputError, match="second as a line with a point and a unit direction"):
        line_distance(edge, Line2D(np.zeros(2), np.array([1.0, 0.0]), 0.0))
    # the x axis (the two planes' edge) and a parallel line 3 mm off it, 1 m along and 1 m up
    other = type(edge)(np.array([1.0, 3e-3, 1.0]), np.array([-1.0, 0.0, 0.0]))
    assert line_distance(edge, other) == pytest.approx(math.hypot(3e-3, 1.0), rel=1e-15)
    with pytest.raises(InputError, match="first as a Line2D"):
        intersect_lines("a", "b")
    line = fit_line([[0, 0], [1, 0]])
    with pytest.raises(InputError, match="second as a Line2D"):
        intersect_lines(line, "b")
    crossing = intersect_lines(line, Line2D(np.array([2.0, 3.0]), np.array([0.0, 1.0]), 0.0))
    np.testing.assert_array_equal(crossing, [2.0, 0.0])


def test_a_ragged_vertex_list_is_refused():
    vertices = [[0.0, 0.0, 0.0], [1.0, 1.0]]
    with pytest.raises(InputError, match=r"vertices \(n, 3\) and triangles \(m, 3\) as "
                                          r"regular arrays"):
        height_map((vertices, [[0, 1, 2]]), [0.0], [0.0])


# ------------------------------------------------------------------ A: instruments' set-up


def test_rtest_point_must_be_numbers(a0ib):
    with pytest.raises(InputError, match=r"point as 3 coordinates \(m\) of the ball centre, "
                                         r"got 'abc'"):
        RTest(a0ib, point="abc")


def test_an_r_test_ball_given_in_mm_is_refused_naming_it_and_the_machine_reach(a0ib):
    # r_test(point=[0, 0, 25]) (25 mm meant) set the ball 25 m off the tool, and its lever
    # multiplied every angular error into the readings, exit 0. The bound is the diagonal
    # of the machine's linear travel: by hand, sqrt(280**2 + 150**2 + 130**2) = 343.22 mm
    lab = machinesim.Lab("robonano_a0ib", noise=False)
    with pytest.raises(InputError, match=r"ball centre at most 343\.22 mm from tool_tip's "
                                         r"origin \(the diagonal of robonano_a0ib's linear "
                                         r"travel.*got \[0\.0, 0\.0, 25\.0\], 25000 mm "
                                         r"\(25 m\) from it") as info:
        lab.r_test(point=[0, 0, 25])
    assert info.value.key == "point"
    from machinesim.metrology.rtest import ball_reach

    reach = ball_reach(a0ib)
    assert reach == pytest.approx(math.sqrt(0.28**2 + 0.15**2 + 0.13**2), rel=1e-12)
    assert RTest(a0ib, point=[0.0, 0.0, reach]).point[2] == reach  # the bound itself is taken
    with pytest.raises(InputError, match="343.22 mm"):
        RTest(a0ib, point=[0.0, 0.0, reach * (1 + 1e-12)])
    assert lab.r_test(point=[0.0, 0.0, 0.04]).read(np.zeros((1, 5))).point[2] == 0.04


def test_an_r_test_ball_on_a_machine_of_short_linear_travel_is_bounded_by_the_floor(tmp_path):
    # a machine of one linear axis of 10 mm stroke (sts_lathe with X fixed and Z cut to
    # +-5 mm: a rotary table on a short Z) had a reach of 10 mm, its stroke, and refused a
    # ball 40 mm from the nose ('at most 10 mm'), as real as on any machine; with no linear
    # axis the reach was 0. The floor, BALL_REACH_FLOOR = 200 mm, holds there
    import re

    from machinesim.machines import models_dir
    from machinesim.metrology import rtest

    text = (models_dir() / "sts_lathe.urdf").read_text()
    text = re.sub(r'<joint name="X" type="prismatic">(.*?)<axis xyz="-1.0 0.0 0.0"/>\s*'
                  r'<limit[^>]*/>', r'<joint name="x_fixed" type="fixed">\1', text, flags=re.S)
    text = text.replace('<machinesim:axis joint="X" resolution="1e-09"/>', "")
    text = text.replace('<limit lower="-0.05" upper="0.1"', '<limit lower="-0.005" upper="0.005"')
    path = tmp_path / "zc.urdf"
    path.write_text(text)
    machine = machinesim.load_machine(path)
    assert machine.axes == ("Z", "C")
    assert np.linalg.norm(machine.upper[:1] - machine.lower[:1]) == pytest.approx(0.01)
    assert RTest(machine, point=[0.0, 0.0, 0.04]).point[2] == 0.04
    assert rtest.ball_reach(machine) == rtest.BALL_REACH_FLOOR == 0.2
    with pytest.raises(InputError, match=r"at most 200 mm from tool_tip's origin "
                                         r"\(BALL_REACH_FLOOR, sts_lathe's linear travel "
                                         r"being shorter.*got \[0\.0, 0\.0, 25\.0\]"):
        RTest(machine, point=[0, 0, 25])


def test_seed_must_be_non_negative():
    with pytest.raises(InputError, match="a non-negative int seed or None, got -1"):
        Microscope(rng=-1)


def test_probe_takes_a_machine_by_name_and_refuses_other_things(a0ib, flat):
    by_name = TouchProbe("robonano_a0ib", None, flat, noise=False, resolution=0.0)
    assert by_name.machine.name == "robonano_a0ib"
    # the ball (R = 0.25 mm) touches the top face z = 0 with its centre at z = R
    q = by_name.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM), "-Z", 1 * MM)
    np.testing.assert_allclose(q, above(a0ib, 2.5 * MM, 1.5 * MM, R), rtol=0, atol=1e-10)
    with pytest.raises(InputError, match="machine as a Machine or the name of a shipped one"):
        TouchProbe(42, None, flat)
    with pytest.raises(machinesim.exceptions.ModelError, match="unknown machine 'no_such'"):
        TouchProbe("no_such", None, flat)


def test_a_probe_ball_given_in_mm_is_refused_when_the_probe_is_built(a0ib, flat):
    # lab.touch_probe(part, radius=0.25) (R0.25 mm meant) was built, and refused only at its
    # first touch, as a 0.25 m ball overlapping the part
    lab = machinesim.Lab("robonano_a0ib", noise=False)
    for radius, shown in ((0.25, r"250 mm \(0\.25 m\)"), (0.0100001, r"10\.0001 mm")):
        with pytest.raises(InputError, match=r"Expected the ball radius <= 10 mm \(0\.01 m\) "
                                             r"\(BALL_RADIUS_LIMIT: .*unit slip.*\), got "
                                             + shown) as info:
            lab.touch_probe(flat, radius=radius)
        assert info.value.key == "radius"
    assert TouchProbe(a0ib, None, flat, radius=10 * MM).radius == 10 * MM  # the bound is taken
    # a 10 mm ball touches the top face z = 0 with its centre at z = 10 mm, by hand
    probe = TouchProbe(a0ib, None, flat, radius=10 * MM, noise=False, resolution=0.0)
    q = probe.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 11 * MM), "-Z", 2 * MM)
    np.testing.assert_allclose(q, above(a0ib, 2.5 * MM, 1.5 * MM, 10 * MM), rtol=0, atol=1e-10)


def test_a_touch_probe_on_a_machine_without_one_says_what_it_lacks(flat):
    # lab.touch_probe(part) on a new user's trunnion (no probe_tip) said only "Expected a
    # frame of trun5 (...), got 'probe_tip'", an argument the call had not given
    lab = machinesim.Lab("grooving_4axis", noise=False)
    assert "probe_tip" not in lab.machine.frames
    with pytest.raises(InputError, match=r"key 'frame': Expected a frame of grooving_4axis "
                                         r"\(.*\), got 'probe_tip'; a touch probe rides on "
                                         r"'probe_tip', its ball centre, .*add one to its URDF"):
        lab.touch_probe(flat)
    with pytest.raises(InputError, match=r"got 'no_such'$"):
        lab.touch_probe(flat, frame="no_such")


def test_probe_lobing_amplitudes_must_be_a_mapping(a0ib, flat):
    with pytest.raises(InputError, match=r"lobing_amplitudes as a mapping of lobing order to "
                                         r"amplitude \(m\), e.g. \{3: 1e-7\}, or None, got "
                                         r"\[1, 2\]"):
        TouchProbe(a0ib, None, flat, lobing_amplitudes=[1, 2])
    with pytest.raises(InputError, match=r"lobing_amplitudes\[3\] as a number"):
        TouchProbe(a0ib, None, flat, lobing_amplitudes={3: "1e-7"})
    probe = TouchProbe(a0ib, None, flat, lobing_amplitudes={3: 1e-7})
    assert probe.lobing_amplitudes == {3: 1e-7}


@pytest.fixture(scope="module")
def lab():
    return machinesim.Lab("robonano_a0ib")


def test_lab_refuses_options_it_sets_itself(lab, flat):
    with pytest.raises(InputError, match="the lab sets the microscope's rng itself .*seed"):
        lab.microscope(rng=1)
    with pytest.raises(InputError, match="the lab sets the white light interferometer's "
                                         "noise itself"):
        lab.white_light_interferometer(noise=False)
    with pytest.raises(InputError, match="the lab sets the laser interferometer's errors "
                                         "itself"):
        lab.laser_interferometer(errors=None)
    with pytest.raises(InputError, match="the lab sets the r test's machine itself"):
        lab.r_test(machine="robonano_a0ib")
    with pytest.raises(InputError, match="the lab sets the touch probe's rng itself"):
        lab.touch_probe(flat, rng=0)
    with pytest.raises(InputError, match="the lab sets the encoders' noise itself"):
        lab.encoders(noise=False)
    with pytest.raises(InputError, match="the lab sets the encoders' follow itself .*servo"):
        lab.encoders(follow=None)


def test_lab_refuses_options_the_instrument_does_not_take(lab, flat):
    with pytest.raises(InputError, match="Microscope has no option 'bogus'; the microscope "
                                         "takes sigma, resolution, lateral_spacing"):
        lab.microscope(bogus=1)
    with pytest.raises(InputError, match="TouchProbe has no option 'radius_mm'"):
        lab.touch_probe(flat, radius_mm=0.25)
    with pytest.raises(InputError, match="Encoders has no option 'sigmaa'; the encoders "
                                         "takes sigma"):
        lab.encoders(sigmaa=1e-9)
    assert lab.microscope(sigma=5 * NM).readout.sigma == 5 * NM  # an option it takes
    sigma = [1e-9, 2e-9, 3e-9, 4e-9, 5e-9]  # one per axis of the A0IB
    assert [r.sigma for r in lab.encoders(sigma=sigma).readouts] == sigma


# ------------------------------------------------------------------------ A: file writing


def test_a_file_name_too_long_is_a_file_error_naming_the_path(tmp_path):
    path = tmp_path / ("a" * 300)
    with pytest.raises(FileError, match="file name is longer than this file system allows") \
            as caught:
        _io.write_atomic(path, "x")
    assert caught.value.source == str(path)
    assert os.listdir(tmp_path) == []  # no temporary file left behind


def test_only_text_or_bytes_are_written(tmp_path):
    path = tmp_path / "out.txt"
    with pytest.raises(InputError, match="Expected the data to write as str or bytes, got int"):
        _io.write_atomic(path, 3)
    assert not path.exists()
    _io.write_atomic(path, bytearray(b"ok"))
    assert path.read_bytes() == b"ok"


# ---------------------------------------------------------------- B: implausible settings


def test_numbers_spelled_as_text_are_refused(flat):
    with pytest.raises(InputError, match=r"resolution as a number \(m\), got '1'"):
        Microscope(resolution="1")
    with pytest.raises(InputError, match=r"width as a number \(m\), got '1'"):
        Spot(width="1")
    with pytest.raises(InputError, match=r"sigma as a number \(m\), got True"):
        Microscope(sigma=True)
    with pytest.raises(InputError, match=r"spacing as a number \(m\), got '1e-6'"):
        Microscope().profile(flat, (0, 0), (1 * MM, 0), spacing="1e-6")


def test_noise_must_be_a_bool():
    with pytest.raises(InputError, match="noise as True or False, got 'no'"):
        Microscope(noise="no")


@pytest.mark.parametrize("name", ["sigma", "resolution", "lateral_sigma", "stage_sigma"])
def test_optical_settings_are_bounded_by_the_field_of_view(name):
    with pytest.raises(InputError, match=rf"{name} <= 0.001 m \(OPTICAL_LIMIT"):
        Microscope(**{name: 1e300})
    with pytest.raises(InputError, match=rf"{name} <= 0.001 m \(OPTICAL_LIMIT.*got 0.0011"):
        Microscope(**{name: 1.1e-3})
    at_limit = Microscope(**{name: OPTICAL_LIMIT})  # the bound itself is taken
    owner = at_limit.readout if name in ("sigma", "resolution") else at_limit
    assert getattr(owner, name) == 1e-3


@pytest.mark.parametrize("read", ["profile", "height_map"])
def test_a_reading_s_spacing_is_bounded_by_the_field_of_view_as_lateral_spacing_is(flat, read):
    # spacing=0.3 (um meant) per reading had read the 4 mm line across the block as one
    # sample, and a 2 x 2 mm map as one pixel, where lateral_spacing=0.3 was refused
    scope = Microscope(rng=0, noise=False)
    window = {"profile": ((0.5 * MM, 1.5 * MM), (4.5 * MM, 1.5 * MM)),
              "height_map": (1 * MM, 3 * MM, 0.5 * MM, 2.5 * MM)}[read]
    with pytest.raises(InputError, match=r"key 'spacing': Expected spacing <= 0.001 m "
                                         r"\(OPTICAL_LIMIT.*got 0.3$"):
        getattr(scope, read)(flat, *window, spacing=0.3)
    at_limit = getattr(scope, read)(flat, *window, spacing=OPTICAL_LIMIT)
    # 4 mm at 1 mm: 5 samples; 2 x 2 mm at 1 mm: 3 x 3, all on the top face at z = 0
    assert at_limit.z.shape == {"profile": (5,), "height_map": (3, 3)}[read]
    assert np.all(at_limit.z == 0.0)


def test_the_exact_profile_refuses_a_spacing_that_reads_one_sample(flat):
    from machinesim.metrology import profile

    with pytest.raises(InputError, match=r"key 'spacing': Expected a spacing shorter than the "
                                         r"line, got spacing 0.3 m over a 0.004 m line: it "
                                         r"would read one sample"):
        profile(flat, (0.5 * MM, 1.5 * MM), (4.5 * MM, 1.5 * MM), 0.3)
    s, z = profile(flat, (0.5 * MM, 1.5 * MM), (4.5 * MM, 1.5 * MM), 3 * MM)
    assert s.tolist() == [0.0, 3 * MM] and z.tolist() == [0.0, 0.0]


def test_spot_width_is_bounded_by_the_field_of_view():
    with pytest.raises(InputError, match=r"width <= 0.001 m \(OPTICAL_LIMIT.*got 0.002"):
        Spot(width=2e-3)
    assert Spot(width=OPTICAL_LIMIT).width == 1e-3


def test_a_reading_beyond_the_sample_cap_is_refused_before_allocating(flat):
    with pytest.raises(InputError, match=r"at most 1e\+08 samples in one reading "
                                         r"\(MAX_SAMPLES\), got 3e\+10 at spacing 1e-13 "
                                         r"m over a 0.003 m line"):
        Microscope().profile(flat, (0, 0), (3 * MM, 0), spacing=1e-13)
    with pytest.raises(InputError, match=r"got 1e\+12 at spacing 1e-09 m over 0.001 m x "
                                         r"0.001 m"):
        Microscope().height_map(flat, 0, 1 * MM, 0, 1 * MM, spacing=1e-9)
    # through a 5 x 5 spot a profile reads 25 points per sample, all at once
    with pytest.raises(InputError, match=r"got 5e\+06 x 25 spot sub-samples at spacing 2e-10"):
        Microscope(spot=Spot(1 * UM)).profile(flat, (0, 0), (1 * MM, 0), spacing=2e-10)
    # the exact core: 20000 x 6000 given samples
    x, y = np.arange(20000) * 1e-8, np.arange(6000) * 1e-8
    assert x.size * y.size > MAX_SAMPLES
    with pytest.raises(InputError, match=r"got 1.2e\+08 over x 0 .. 0.00019999 m"):
        height_map(flat, x, y)
    # the laser interferometer's tests: 1e7 positions took 3.7 GB, 1e8 ran out of memory
    laser = machinesim.Lab("grooving_4axis", noise=False).laser_interferometer()
    with pytest.raises(InputError, match=r"at most 1,000,000 positions in one test, got "
                                         r"1,000,001"):
        laser.positioning("X", np.linspace(0.0, 0.05, 1_000_001))
    assert laser.positioning("X", np.linspace(0.0, 0.05, 11)).deviation.shape == (11,)


# ---------------------------------------------------- C: scan -> nominal centres with NaN


def test_nominal_centres_of_a_scan_keep_nan_rows_where_the_ball_hung_free(a0ib, flat):
    """Across the edge at x = 5 mm: on the face the ball centre rests at z = R; beyond
    x = 5 mm + R it hangs free, and its row stays NaN."""
    x = np.array([1.0, 4.0, 5.3, 2.0]) * MM
    free = 0.1 * MM
    probe = TouchProbe(a0ib, None, flat, noise=False, resolution=0.0)
    scan = probe.scan(np.array([above(a0ib, xi, 1.5 * MM, free) for xi in x]))
    centres = probe.nominal_centres(scan.contact_q)
    assert centres.shape == (4, 3)
    assert np.isnan(centres[2]).all() and not np.isnan(centres[[0, 1, 3]]).any()
    for i in (0, 1, 3):
        np.testing.assert_array_equal(centres[i], probe.nominal_centres(scan.contact_q[i]))
        np.testing.assert_allclose(centres[i], [x[i], 1.5 * MM, R], rtol=0, atol=ROUND_OFF_M)
    assert np.isnan(probe.nominal_centres([np.nan] * len(a0ib.axes))).all()
    with pytest.raises(InputError, match="finite q or NaN rows, got infinity"):
        probe.nominal_centres([np.inf] * len(a0ib.axes))


# ------------------------------------------------------- D: the Gaussian spot on a step


def test_gaussian_spot_reads_a_step_edge_as_a_staircase():
    """The 5-node Gauss-Hermite weights are 8/15 and (7 +- 2 sqrt 10) / 60; at the edge the
    centre node and the two beyond it read the top (the highest surface wins): 23/30 of the
    step, 4/15 above the 1/2 of a true Gaussian blur (docs/metrology.md)."""
    height, edge = 5 * UM, 10 * UM
    vertices = np.array([[0, -5, 0], [10, -5, 0], [10, 5, 0], [0, 5, 0],
                         [10, -5, 5], [20, -5, 5], [20, 5, 5], [10, 5, 5]], float) * UM
    triangles = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    scope = Microscope(noise=False, resolution=0.0, spot=Spot(1 * UM, "gaussian"))
    read = scope.profile((vertices, triangles), (edge - 2 * UM, 0), (edge + 2 * UM, 0),
                         spacing=1 * UM)
    outer = (7 - 2 * math.sqrt(10)) / 60
    inner = (7 + 2 * math.sqrt(10)) / 60
    # samples at the edge - 2, -1, 0, +1, +2 um; nodes at 0, +-0.576 and +-1.213 um
    expected = np.array([0.0, outer, 23 / 30, 1 - outer, 1.0]) * height
    np.testing.assert_allclose(read.z, expected, rtol=0, atol=1e-12 * height)
    assert 23 / 30 == pytest.approx(8 / 15 + inner + outer, abs=1e-15)


def test_an_r_test_plan_in_degrees_is_told_the_units_and_order_the_axes_take():
    # C given as 90 deg (90 rad, past robonano_a0ib's +-360 deg): the message had named the
    # value and the travel only, where fit's own says "axis values in m and rad"
    from machinesim.exceptions import AxisLimitError

    lab = machinesim.Lab("robonano_a0ib", noise=False)
    q = np.zeros((2, 5))
    q[1, 4] = 90.0
    with pytest.raises(AxisLimitError, match=r"axis C = 5156\.62016 deg outside its travel "
                                             r".*\(axis values in m and rad, in the order "
                                             r"XYZBC: a rotary axis given in degrees is the "
                                             r"usual cause\)"):
        lab.r_test().read(q)


def test_a_noise_or_step_in_the_wrong_unit_is_refused_by_every_instrument():
    # A new user's lab.laser_interferometer(sigma=2) (nm meant) read with 2 m of noise,
    # r_test(sigma=50), touch_probe(part, sigma=20) and encoders(sigma=[1] * 5) alike, exit 0;
    # only the optical instruments had a bound (OPTICAL_LIMIT). And the microscope's
    # lateral_spacing=0.3 (um meant) read a 2 mm profile as one sample.
    import machinesim
    from machinesim.workpiece import stock_from_spec

    lab = machinesim.Lab("robonano_a0ib", noise=False)
    part = stock_from_spec("block:10x10x2")
    made = {"laser_interferometer": lambda **o: lab.laser_interferometer(**o),
            "r_test": lambda **o: lab.r_test(**o),
            "touch_probe": lambda **o: lab.touch_probe(part, **o)}
    for kind, make in made.items():
        for name, value in (("sigma", 2.0), ("resolution", 1.0)):
            with pytest.raises(InputError, match=rf"Expected {name} <= 0.001 m or rad "
                                                 rf"\(READOUT_LIMIT: .*unit slip.*\), got "
                                                 rf"{value}") as info:
                make(**{name: value})
            assert info.value.key == name, kind
        make(sigma=1e-3, resolution=1e-3)  # the bound itself is taken
    with pytest.raises(InputError, match=r"Expected sigma <= 0.001 m or rad"):
        lab.encoders(sigma=[1.0] * 5)
    # an encoder's step is its machine's, which a URDF may set up to 1e-2 rad
    # (urdf_checks.COARSEST_RESOLUTION_RAD): its readout and default noise stay unbounded
    from types import SimpleNamespace

    from machinesim.metrology.encoders import Encoders

    coarse = Encoders(SimpleNamespace(resolution=(1e-9, 8.7e-3), axes=("X", "C")),
                      lambda t, q: q)
    assert [r.resolution for r in coarse.readouts] == [1e-9, 8.7e-3]
    with pytest.raises(InputError, match=r"Expected lateral_spacing <= 0.001 m \(OPTICAL_LIMIT"):
        lab.microscope(lateral_spacing=0.3)
    assert lab.microscope(lateral_spacing=1e-3).lateral_spacing == 1e-3
