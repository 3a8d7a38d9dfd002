"""STS tool paths (machinesim.cam.spiral): paper 004's eqs 3-11 and 18-19, the program."""

import math
import re
import warnings

import numpy as np
import pytest
from scipy.integrate import quad

from machinesim.cam import spiral as sp
from machinesim.exceptions import FileError, InputError, MachineSimWarning
from machinesim.metrology import export_x3p
from machinesim.nc import AXES, format_program, parse_program, read_program, write_program

PAPER = sp.Spiral(sp.PART_RADIUS_M, sp.FEED_M)


def test_eq_3_is_the_arc_length_of_the_spiral_of_eqs_4_to_6():
    assert PAPER.turns == pytest.approx(250.0, rel=1e-15)
    assert PAPER.end_angle == pytest.approx(2 * math.pi * 250, rel=1e-15)
    assert PAPER.radius_at(PAPER.end_angle) == pytest.approx(0.0, abs=1e-18)
    fr = PAPER.feed_per_radian
    for a, b in [(0.0, 0.3), (100.0, 100.05), (1500.0, PAPER.end_angle)]:
        exact, _ = quad(lambda t: math.hypot(PAPER.radius - fr * t, fr), a, b, epsabs=1e-18,
                        epsrel=1e-13, limit=200)
        assert PAPER.arc_length(a) - PAPER.arc_length(b) == pytest.approx(exact, rel=1e-11)
    # Table 4 and Figs. 9-10: 0.5 mm at 2 um/rev is 30 um x 13,090 long
    assert PAPER.length / sp.CAL_STEP_M == pytest.approx(13090.0, abs=0.02)
    # eq 3 inverted, all along
    theta = np.linspace(0.0, PAPER.end_angle, 1001)
    np.testing.assert_allclose(PAPER.angle_at(PAPER.arc_length(theta)), theta, rtol=0,
                               atol=1e-9)  # 1e-9 rad of 1571: 1.4 ulp-scale of S


def test_constant_angle_steps_by_the_same_angle():
    theta = sp.constant_angle(PAPER, sp.CA_STEP_RAD)
    assert theta.size == 45_001  # Table 4: 45,000 steps of 2 deg
    np.testing.assert_allclose(np.diff(theta), sp.CA_STEP_RAD, rtol=1e-11)
    assert theta[0] == 0.0 and theta[-1] == PAPER.end_angle
    # a step that does not divide the spiral: the last one shorter
    odd = sp.constant_angle(PAPER, 0.7)
    assert np.diff(odd)[:-1] == pytest.approx(0.7) and 0.0 < np.diff(odd)[-1] < 0.7


def test_constant_arc_length_steps_by_the_same_arc_length():
    theta = sp.constant_arc_length(PAPER, sp.CAL_STEP_M)
    assert theta.size == 13_092  # 13,090 steps of 30 um and one of 0.44 um to the centre
    arcs = -np.diff(PAPER.arc_length(theta))
    np.testing.assert_allclose(arcs[:-1], sp.CAL_STEP_M, rtol=1e-9)
    assert arcs[-1] == pytest.approx(PAPER.length - 13090 * sp.CAL_STEP_M, rel=1e-6)
    # the angle step grows towards the centre (where CAL is sparse, Fig. 10(e))
    steps = np.diff(theta)
    assert steps[-2] > 100 * steps[0]
    # by count: equal steps from the rim to the centre
    by_count = sp.cutting_angles(PAPER, "CAL", count=1001)
    np.testing.assert_allclose(-np.diff(PAPER.arc_length(by_count)), PAPER.length / 1000,
                               rtol=1e-9)
    np.testing.assert_allclose(np.diff(sp.cutting_angles(PAPER, "CA", count=1001)),
                               PAPER.end_angle / 1000, rtol=1e-11)


def test_cutting_points_carry_the_design_and_its_radial_slope():
    design = sp.sine_grid()
    theta = np.linspace(0.1, 700.0, 500)
    points = sp.cutting_points(design, PAPER, theta)
    np.testing.assert_allclose(points.rho, PAPER.radius_at(theta), rtol=0, atol=0)
    np.testing.assert_allclose(points.z, design(points.x, points.y), rtol=0, atol=0)
    h = 1e-9
    cos, sin = np.cos(theta), np.sin(theta)
    numeric = (design((points.rho + h) * cos, (points.rho + h) * sin)
               - design((points.rho - h) * cos, (points.rho - h) * sin)) / (2 * h)
    np.testing.assert_allclose(points.slope, numeric, rtol=0, atol=1e-9)  # slopes ~3e-3
    # a callable without gradient: central differences
    bare = sp.Design(design.height)
    np.testing.assert_allclose(sp.cutting_points(bare, PAPER, theta).slope, points.slope,
                               rtol=0, atol=1e-9)  # truncation h^2 A k^3 / 6 = 2e-10


def test_nose_compensation_puts_the_nose_centre_on_the_offset_surface():
    # eqs 18-19 on a sphere: the nose centre (tip + R z) must lie at Rs + R from the
    # sphere's centre, on the cutting point's normal
    rs, radius = 4e-3, 1e-3
    design = sp.sphere(rs)
    spiral = sp.Spiral(1e-3, 10e-6)
    points = sp.cutting_points(design, spiral, sp.constant_angle(spiral, 0.05))
    path = sp.tool_path(points, radius)
    centre_rho, centre_z = path.x, path.z + radius
    np.testing.assert_allclose(np.hypot(centre_rho, centre_z + rs), rs + radius, rtol=1e-14)
    # its direction from the sphere's centre is the cutting point's
    np.testing.assert_allclose(np.arctan2(centre_rho, centre_z + rs),
                               np.arctan2(points.rho, points.z + rs), rtol=0, atol=1e-13)
    # where the design is flat, the tip is the cutting point; uncompensated, always
    np.testing.assert_array_equal(sp.tool_path(points).x, points.rho)
    flat = sp.cutting_points(sp.Design(lambda x, y: 0 * x), spiral, [0.0, 1.0])
    np.testing.assert_allclose(sp.tool_path(flat, radius).x, flat.rho, rtol=0, atol=0)
    # the tips as workpiece positions of sts_lathe: (X cos C, X sin C, Z)
    tips = path.tips()
    np.testing.assert_allclose(np.hypot(tips[:, 0], tips[:, 1]), np.abs(path.x), rtol=1e-15)


def test_a_nose_wider_than_a_concave_curvature_is_noted_naming_design_radius_and_place():
    # z = A sin(k x) along x only: at its valleys (sin = -1) the radius of curvature is
    # 1 / (A k^2) (slope 0 there), 5.06606 mm for 50 nm and 100 um; across the part the
    # radial profile at angle theta bends by cos^2(theta) of that, never more. A spiral of
    # 0.75 wavelengths starts (C = 0, on +x) at a valley.
    amplitude, wavelength = 50e-9, 100e-6
    least = 1.0 / (amplitude * (2 * math.pi / wavelength) ** 2)
    assert least == pytest.approx(5.06606e-3, rel=1e-6)
    design = sp.sine_grid(amplitude, wavelength, amplitude_y=0.0)
    spiral = sp.Spiral(0.75 * wavelength, 2e-6)
    points = sp.cutting_points(design, spiral, sp.constant_angle(spiral, 0.05))
    with pytest.warns(MachineSimWarning) as noted:
        gouging = sp.tool_path(points, least * (1 + 1e-4))
    assert len(noted) == 1
    text = str(noted[0].message)
    assert text.startswith(f"design {design.name!r}: its least concave radius of curvature "
                           "in the nose's (radial) plane, 5.06606 mm at the cutting point "
                           "(0.075, 0) mm (C 0 rad), is below the nose radius 5.06657 mm")
    assert "gouging" in text
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        clear = sp.tool_path(points, least * (1 - 1e-4))
        sp.tool_path(points)  # uncompensated: no nose, no note
    # the path is made as before either way (the cut is the physical one)
    phi = np.arctan(points.slope)
    np.testing.assert_allclose(gouging.x, points.rho - least * (1 + 1e-4) * np.sin(phi),
                               rtol=1e-15)
    assert len(clear) == len(gouging) == len(points)
    # a concave sphere: its radius |Rs| everywhere, by a second method (its own radius)
    bowl = sp.cutting_points(sp.sphere(-2e-3), sp.Spiral(1e-4, 5e-6), [0.0, 1.0])
    with pytest.warns(MachineSimWarning,
                      match=r"plane, 2 mm at .* nose radius 2.1 mm \(at 2 of 2 "):
        sp.tool_path(bowl, 2.1e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sp.tool_path(bowl, 1.9e-3)
        sp.tool_path(sp.cutting_points(sp.sphere(2e-3), sp.Spiral(1e-4, 5e-6), [0.0, 1.0]),
                     2.1e-3)  # convex: no limit


@pytest.mark.parametrize(("theta", "message"), [
    # np.array(theta, dtype=float) took the strings as angles and raised numpy's ValueError
    # ('setting an array element with a sequence') on a ragged list
    (["0", "1"], "key 'theta': Expected theta as angles (rad), got ['0', '1']"),
    ([[0.0, 1.0], [2.0]], "key 'theta': Expected theta as angles (rad) in a regular "
                          "(non-ragged) array, got [[0.0, 1.0], [2.0]]"),
])
def test_cutting_points_take_no_text_or_ragged_angles(theta, message):
    spiral = sp.Spiral(0.12e-3, 1e-6)
    with pytest.raises(InputError) as caught:
        sp.cutting_points(sp.sine_grid(), spiral, theta)
    assert str(caught.value) == message
    # numbers as before: rho by eq 4 at 0 and 1 rad
    points = sp.cutting_points(sp.sine_grid(), spiral, (0, np.float32(1.0)))
    assert points.rho.tolist() == [0.12e-3, 0.12e-3 - 1e-6 / (2 * math.pi)]


@pytest.mark.parametrize(("arrays", "message"), [
    # spiral_program raised numpy's 'could not broadcast input array from shape (5,) into
    # shape (4,)' for a short X, an NCProgramError 'move 2 drops axis Z' for a NaN Z, and
    # interpolate 'list' object has no attribute 'size' for lists
    ((np.arange(3.0), np.ones(2), np.zeros(3)), "key 'path': Expected path.c, path.x and "
     "path.z as 1-D arrays of one length, got shapes (3,), (2,), (3,)"),
    ((np.arange(3.0), np.ones(3), np.array([0.0, np.nan, 0.0])),
     "key 'path.z': Expected finite path.z, got a NaN or infinity at index 1"),
    (("abc", [1.0], [2.0]), "key 'path.c': Expected path.c as numbers (rad, m), got 'abc'"),
])
def test_a_tool_path_made_by_hand_is_checked_when_made(arrays, message):
    with pytest.raises(InputError) as caught:
        sp.ToolPath(*arrays)
    assert str(caught.value) == message
    # lists of numbers are taken as the arrays they hold, read-only as tool_path's
    path = sp.ToolPath([0.0, 1.0, 2.0], [1e-3] * 3, [0.0] * 3)
    assert path.x.tolist() == [1e-3] * 3 and not path.x.flags.writeable
    assert len(sp.interpolate(path, "spline", 2)) == 5


def test_cutting_points_copied_or_pickled_keep_their_design_and_its_gouging_note():
    # the points had left their design behind when copied (copy.copy, copy.deepcopy) or
    # pickled, so a copy's tool_path made a gouging path without a word: each of the
    # designs made here now pickles (module-level surfaces), and a copy warns the same
    import copy
    import pickle

    amplitude, wavelength = 50e-9, 100e-6
    least = 1.0 / (amplitude * (2 * math.pi / wavelength) ** 2)  # as the test above
    spiral = sp.Spiral(0.75 * wavelength, 2e-6)
    theta = sp.constant_angle(spiral, 0.05)
    x, y = np.meshgrid(np.linspace(-1e-4, 1e-4, 9), np.linspace(-1e-4, 1e-4, 9))
    bowl_map = sp.design_from_height_map(x[0], y[:, 0], 2e-3 - np.sqrt(4e-6 - x * x - y * y))
    for design, nose in ((sp.sine_grid(amplitude, wavelength, amplitude_y=0.0),
                          least * (1 + 1e-4)), (sp.sphere(-2e-3), 2.1e-3),
                         (sp.tilted_plane(0.01), None), (bowl_map, 2.1e-3)):
        points = sp.cutting_points(design, spiral, theta)
        with warnings.catch_warnings(record=True) as first:
            warnings.simplefilter("always")
            path = sp.tool_path(points, nose or 1e-3)
        assert (len(first) == 1) == (nose is not None), design.name
        for back in (copy.copy(points), copy.deepcopy(points),
                     pickle.loads(pickle.dumps(points))):
            assert back.design is not None and back.design.name == design.name
            for name in ("theta", "rho", "z", "slope"):
                assert np.array_equal(getattr(back, name), getattr(points, name))
            with warnings.catch_warnings(record=True) as again:
                warnings.simplefilter("always")
                np.testing.assert_array_equal(sp.tool_path(back, nose or 1e-3).x, path.x)
            assert [str(w.message) for w in again] == [str(w.message) for w in first]
    # a design of a local function copies (itself), and refuses pickling by its name
    flat = sp.cutting_points(sp.Design(lambda x, y: 0 * x, name="flat"), spiral, theta)
    assert copy.deepcopy(flat).design is flat.design
    with pytest.raises(InputError, match=r"design 'flat' cannot be pickled: its height is "
                       r".*<lambda>, a local function"):
        pickle.dumps(flat)

    # an instance of a class defined in a function, by its class's name (pickle's own
    # AttributeError had named neither the design nor the way out)
    class Flat:
        def __call__(self, x, y):
            return 0 * x

    local = sp.cutting_points(sp.Design(Flat(), name="flat"), spiral, theta)
    assert copy.deepcopy(local).design is local.design
    with pytest.raises(InputError, match=r"design 'flat' cannot be pickled: its height is "
                       r".*<locals>\.Flat, a local function, class or lambda"):
        pickle.dumps(local)


def rotational(coefficients):
    """z = sum c_k rho^k: along the spiral (rho linear in theta) a polynomial in theta."""
    def height(x, y):
        rho = np.hypot(x, y)
        return sum(c * rho ** k for k, c in enumerate(coefficients))

    def gradient(x, y):
        rho = np.hypot(x, y)
        slope = sum(k * c * rho ** (k - 1) for k, c in enumerate(coefficients) if k)
        with np.errstate(invalid="ignore", divide="ignore"):
            return (np.where(rho > 0, slope * x / rho, 0.0),
                    np.where(rho > 0, slope * y / rho, 0.0))

    return sp.Design(height, gradient, "rotational polynomial")


@pytest.mark.parametrize("distribution, step", [("CA", math.radians(3.0)), ("CAL", 40e-6)])
def test_spline_reproduces_a_cubic_along_the_spiral_and_linear_leaves_its_chord(distribution,
                                                                               step):
    # a rotational cubic in rho is a cubic in C along the spiral: the not-a-knot cubic
    # spline through the points is the polynomial itself (eq 11 gives round-off only)
    spiral = sp.Spiral(0.2e-3, 4e-6)
    theta = sp.cutting_angles(spiral, distribution, step=step)
    cubic = rotational([1e-7, 2e-4, -3e3, 4e6])  # 7 um of sag over the 0.2 mm
    spline = sp.program_error(cubic, spiral, theta, method="spline", substeps=7)
    linear = sp.program_error(cubic, spiral, theta, method="linear", substeps=7)
    assert np.abs(spline.dz).max() < 1e-19  # round-off of z ~ 1e-5 m: ~1e-21
    assert linear.pv > 1e4 * np.abs(spline.dz).max()
    # a paraboloid z = c rho^2 is c (r - f_r C)^2: the linear path (eqs 7-8) misses it at
    # mid-step by exactly c f_r^2 dC^2 / 4, the chord of a parabola
    c = 2.0
    paraboloid = rotational([0.0, 0.0, c])
    mid = sp.program_error(paraboloid, spiral, theta, method="linear", substeps=2)
    dz = mid.dz[1::2]
    expected = -c * spiral.feed_per_radian ** 2 * np.diff(theta) ** 2 / 4
    np.testing.assert_allclose(dz, expected, rtol=1e-6, atol=1e-22)


def test_program_error_falls_with_the_number_of_points_and_fig_11_orders():
    design = sp.sine_grid()
    spiral = sp.Spiral(0.2e-3, 2e-6)
    counts = [3_000, 6_000, 12_000, 24_000]
    table = sp.program_error_table(design, spiral, counts, substeps=6,
                                   rho_range=(50e-6, 150e-6))
    assert set(table) == {("CA", "linear"), ("CA", "spline"), ("CAL", "linear"),
                          ("CAL", "spline")}
    for values in table.values():
        assert values.shape == (4,) and (np.diff(values) < 0).all()
    # linear converges as 1/n^2, the spline as 1/n^4 (the paper: spline better with many
    # points)
    ca_linear, ca_spline = table["CA", "linear"], table["CA", "spline"]
    assert ca_linear[-2] / ca_linear[-1] == pytest.approx(4.0, rel=0.1)
    assert ca_spline[-2] / ca_spline[-1] == pytest.approx(16.0, rel=0.25)
    assert ca_spline[-1] < ca_linear[-1]


def test_program_error_of_the_paper_programs():
    # Table 4: before (CAL 30 um, spline) and after (CA 2 deg, spline), Fig. 15(a)
    design = sp.sine_grid()
    region = (200e-6, 300e-6)  # r around 250 um, where the paper measures
    before = sp.program_error(design, PAPER, sp.constant_arc_length(PAPER, sp.CAL_STEP_M),
                              method="spline", rho_range=region)
    after = sp.program_error(design, PAPER, sp.constant_angle(PAPER, sp.CA_STEP_RAD),
                             method="spline")
    assert 5e-9 < before.pv < 10e-9   # the paper: 8 nm
    assert 0.5e-9 < after.pv < 1.5e-9  # the paper: 1 nm (whole part)
    assert before.rho.min() >= region[0] and before.rho.max() <= region[1]


def paper_program(number=4):
    spiral = sp.Spiral(0.05e-3, sp.FEED_M)
    points = sp.cutting_points(sp.sine_grid(), spiral, sp.constant_angle(spiral, 0.0123))
    path = sp.tool_path(points, sp.NOSE_RADIUS_M)
    return path, sp.spiral_program(path, number=number)


def test_program_reads_back_at_the_machine_resolution(tmp_path):
    path, program = paper_program()
    assert len(program) == len(path) + 2
    assert program.kinds[0] == 0 and (program.kinds[1:] == 1).all()
    file = tmp_path / "sts.nc"
    write_program(program, file)
    back = read_program(file)
    x, z, c = (back.targets[:, "XYZABC".index(a)] for a in "XZC")
    np.testing.assert_allclose(x[1:-1], path.x, rtol=0, atol=0.5e-9 + 1e-15)
    np.testing.assert_allclose(z[1:-1], path.z, rtol=0, atol=0.5e-9 + 1e-15)
    np.testing.assert_allclose(np.degrees(c[1:-1]), np.degrees(path.c), rtol=0,
                               atol=0.5e-5 + 1e-9)
    assert z[0] == pytest.approx(path.z[0] + 10e-6, abs=1e-9)
    # F: 20 rpm as 7200 deg/min; the spindle then turns at 20 rpm
    assert "F7200." in file.read_text()
    # written again, the same text
    assert format_program(back) == file.read_text()


def test_large_spindle_angles_keep_their_resolution():
    # C is a spindle: thousands of turns. The writer prints C in deg with 5 decimals; a
    # float64 holds 0.00001 deg exactly enough up to 1e10 deg, so reading back loses
    # nothing but the rounding to 0.00001 deg (plus one ulp of the value in deg)
    path, _ = paper_program()
    start = 5e4  # rad, 8,000 turns: half of sts_lathe's +-1e5 rad travel
    program = sp.spiral_program(path, start_c=start)
    back = parse_program(format_program(program))
    c = back.targets[:, 5]
    worst = np.abs(np.degrees(c[1:-1]) - np.degrees(path.c + start)).max()
    assert worst <= 0.5e-5 + 4 * np.spacing(np.degrees(start + path.c[-1]))
    assert np.degrees(c).max() > 2.8e6


def test_designs_from_height_maps_and_files(tmp_path):
    sine = sp.sine_grid()
    x = np.linspace(-0.3e-3, 0.3e-3, 241)
    y = np.linspace(-0.3e-3, 0.3e-3, 221)
    z = sine(*np.meshgrid(x, y))
    mapped = sp.design_from_height_map(x, y, z)
    rng = np.random.default_rng(2)
    px, py = rng.uniform(-0.29e-3, 0.29e-3, (2, 200))
    # a bicubic spline at 2.5 um spacing on lambda = 100 um: h^4 k^4 A / 384 ~ 2e-14
    np.testing.assert_allclose(mapped(px, py), sine(px, py), rtol=0, atol=1e-12)
    # its slope converges as h^3 A k^4 / 24 ~ 5e-7 (of slopes ~3e-3)
    np.testing.assert_allclose(mapped.slope(px, py), sine.slope(px, py), rtol=0, atol=1e-6)
    with pytest.raises(InputError, match="outside the height map"):
        mapped(np.array([0.31e-3]), np.array([0.0]))
    np.savez(tmp_path / "map.npz", x=x, y=y, z=z)
    export_x3p(tmp_path / "map.x3p", x, y, z)
    for name in ("map.npz", "map.x3p"):
        read = sp.read_design(tmp_path / name)
        np.testing.assert_allclose(read(px, py), mapped(px, py), rtol=0, atol=1e-15)
    with pytest.raises(FileError, match="no such file"):
        sp.read_design(tmp_path / "none.npz")
    (tmp_path / "map.txt").write_text("1 2 3")
    with pytest.raises(InputError, match=r"\.x3p or \.npz"):
        sp.read_design(tmp_path / "map.txt")
    np.savez(tmp_path / "bad.npz", x=x, y=y)
    with pytest.raises(InputError, match="missing array"):
        sp.read_design(tmp_path / "bad.npz")


def test_bad_inputs_are_refused_with_what_was_expected():
    with pytest.raises(InputError, match="feed below the radius"):
        sp.Spiral(1e-6, 2e-6)
    with pytest.raises(InputError, match="distribution 'CA' or 'CAL'"):
        sp.cutting_angles(PAPER, "CS", count=10)
    with pytest.raises(InputError, match="either step or count"):
        sp.cutting_angles(PAPER, "CA")
    with pytest.raises(InputError, match="method 'linear' or 'spline'"):
        sp.interpolate(sp.ToolPath(np.arange(3.0), np.ones(3), np.zeros(3)), "cubic")
    with pytest.raises(InputError, match="not defined at the cutting point"):
        sp.cutting_points(sp.sphere(0.1e-3), PAPER, [0.0, 1.0])
    with pytest.raises(InputError, match="rho_range to meet the spiral"):
        sp.program_error(sp.sine_grid(), PAPER, sp.constant_angle(PAPER, 0.5),
                         rho_range=(1.0, 2.0))


@pytest.mark.parametrize("call, key, value", [
    # sine_grid(True) was a grid of 1 m amplitude ('sine grid A 1e+09 nm'), clearance True
    # lifted the rapid 1 m, spindle_rpm True turned at 1 rpm (F 360 deg/min), plunge True fed
    # at 1 mm/min, start_c True started at 1 rad; the strings were float()ed and taken, and
    # start_c None raised TypeError
    (lambda p: sp.sine_grid(True), "amplitude", "True"),
    (lambda p: sp.sine_grid(50e-9, "1e-4"), "wavelength", "'1e-4'"),
    (lambda p: sp.Spiral(True, 1e-6), "radius", "True"),
    (lambda p: sp.spiral_program(p, clearance=True), "clearance", "True"),
    (lambda p: sp.spiral_program(p, spindle_rpm=True), "spindle_rpm", "True"),
    (lambda p: sp.spiral_program(p, spindle_rpm="20"), "spindle_rpm", "'20'"),
    (lambda p: sp.spiral_program(p, plunge_mm_per_min=np.True_), "plunge_mm_per_min", "np.True_"),
    (lambda p: sp.spiral_program(p, start_c=True), "start_c", "True"),
    (lambda p: sp.spiral_program(p, start_c="5"), "start_c", "'5'"),
    (lambda p: sp.spiral_program(p, start_c=None), "start_c", "None"),
])
def test_the_spiral_cam_takes_no_bool_or_str_for_a_number(call, key, value):
    spiral = sp.Spiral(0.12e-3, 1e-6)
    path = sp.tool_path(sp.cutting_points(sp.sphere(2e-3), spiral,
                                          sp.constant_angle(spiral, 0.5)), 1e-3)
    with pytest.raises(InputError) as caught:
        call(path)
    assert caught.value.key == key
    assert f"Expected {key} as a number" in str(caught.value)
    assert str(caught.value).endswith(f"got {value}")
    # numbers as before: a numpy float is a float, a C start of 1 rad is 1 rad
    program = sp.spiral_program(path, clearance=np.float64(1e-5), start_c=np.float64(1.0))
    assert program.targets[0][AXES.index("C")] == 1.0 + path.c[0]


@pytest.mark.parametrize("call, message", [
    # float() took them: sphere(True) was a 1 m sphere ('sphere R 1000 mm'), '2e-3' a 2 mm
    # one; tilted_plane(True) a slope of 1, '0.1' one of 0.1, None a TypeError
    (lambda: sp.sphere(True), "key 'radius': Expected radius as a number (m), got True"),
    (lambda: sp.sphere("2e-3"), "key 'radius': Expected radius as a number (m), got '2e-3'"),
    (lambda: sp.tilted_plane(True),
     "key 'slope_x': Expected slope_x as a number (m per m), got True"),
    (lambda: sp.tilted_plane(0.0, "0.1"),
     "key 'slope_y': Expected slope_y as a number (m per m), got '0.1'"),
    (lambda: sp.tilted_plane(None),
     "key 'slope_x': Expected slope_x as a number (m per m), got None"),
])
def test_the_test_designs_take_no_bool_or_str_for_a_number(call, message):
    with pytest.raises(InputError) as caught:
        call()
    assert str(caught.value) == message
    # numbers as before: a concave 2 mm sphere 1 mm off its pole, a plane of slope 0.02
    assert sp.sphere(np.float64(-2e-3))(1e-3, 0.0) == 2e-3 - math.sqrt(3e-6)
    assert sp.tilted_plane(0.02)(1e-3, 5e-3) == 0.02 * 1e-3


@pytest.mark.parametrize("call, key, unit", [
    # float(10**400) raised 'OverflowError: int too large to convert to float', a traceback
    # naming no argument, in check_length (every length of the CAM) and spiral's _positive
    (lambda p: sp.sine_grid(10**400), "amplitude", " (m)"),
    (lambda p: sp.Spiral(-10**400, 1e-6), "radius", " (m)"),
    (lambda p: sp.spiral_program(p, clearance=10**400), "clearance", " (m)"),
    (lambda p: sp.spiral_program(p, spindle_rpm=10**400), "spindle_rpm", ""),
    (lambda p: sp.constant_angle(sp.Spiral(0.12e-3, 1e-6), 10**400), "step (rad)", ""),
])
def test_an_int_beyond_float64_is_refused_by_name_not_overflowing(call, key, unit):
    spiral = sp.Spiral(0.12e-3, 1e-6)
    path = sp.tool_path(sp.cutting_points(sp.sphere(2e-3), spiral,
                                          sp.constant_angle(spiral, 0.5)), 1e-3)
    with pytest.raises(InputError) as caught:
        call(path)
    assert str(caught.value) == (f"key '{key}': Expected a finite {key}{unit}, got an int of "
                                 "1329 bits, beyond float64")  # (10**400).bit_length()


def test_a_spindle_faster_than_the_lathes_c_axis_is_refused_naming_the_bound():
    # spindle_rpm 1e300 was taken: F = 360 x 1e300 deg/min, 6e297 m/s of the feed array
    from machinesim.machines import load_machine

    lathe = load_machine("sts_lathe")
    c_rate = lathe.rapid_rate[lathe.axes.index("C")]
    assert c_rate == 150.0  # rad/s, models/sts_lathe.urdf
    assert sp.MAX_SPINDLE_RPM == pytest.approx(c_rate * 60.0 / (2 * math.pi), rel=1e-15)
    spiral = sp.Spiral(0.12e-3, 1e-6)
    path = sp.tool_path(sp.cutting_points(sp.sphere(2e-3), spiral,
                                          sp.constant_angle(spiral, 0.5)), 1e-3)
    for rpm in (1e300, 1433.0):
        with pytest.raises(InputError) as caught:
            sp.spiral_program(path, spindle_rpm=rpm)
        assert caught.value.key == "spindle_rpm"
        assert str(caught.value) == (
            "key 'spindle_rpm': Expected spindle_rpm <= 1432.39 rpm (sts_lathe's C rapid rate, "
            'models/sts_lathe.urdf <limit velocity="150.0"> rad/s; '
            f"machinesim.cam.spiral.MAX_SPINDLE_RPM), got {rpm!r}")
    # at the bound, F = 360 x 1432.39 deg/min (8594 mm/min of C) is taken as before
    program = sp.spiral_program(path, spindle_rpm=sp.MAX_SPINDLE_RPM)
    assert program.feeds[2] == pytest.approx(360.0 * sp.MAX_SPINDLE_RPM * 1e-3 / 60.0,
                                             rel=1e-15)


def test_a_path_of_more_points_than_memory_holds_is_refused_naming_what_gave_it():
    # the paper's spiral turns 250 times, 2 pi 250 = 1570.8 rad: a CA step of 1e-12 rad (a
    # step in another unit) is 1.571e15 points, which asked numpy for 11 PiB; the CAL step of
    # 1e-15 m over the 0.3927 m spiral 3.927e14; 10^9 sub-steps on the 15,709 points of a
    # 0.1 rad CA path 1.571e13 samples, which filled memory for minutes
    def refusal(call):
        with pytest.raises(InputError, match=r"Expected at most 1e\+08 points on the path "
                                             r"\(MAX_PATH_POINTS\)") as error:
            call()
        return str(error.value)

    assert "got 1.571e+15 from step 1e-12 rad over the spiral's 1570.8 rad" in refusal(
        lambda: sp.constant_angle(PAPER, 1e-12))
    assert "got 3.927e+14 from step 1e-15 m over the spiral's 0.3927 m" in refusal(
        lambda: sp.constant_arc_length(PAPER, 1e-15))
    assert "got 1e+13 from count 10000000000000" in refusal(
        lambda: sp.cutting_angles(PAPER, "CA", count=10**13))
    path = sp.tool_path(sp.cutting_points(sp.sine_grid(), PAPER, sp.constant_angle(PAPER, 0.1)))
    assert len(path) == math.ceil(2 * math.pi * 250 / 0.1) + 1 == 15709
    assert "got 1.571e+13 from substeps 1000000000 on 15709 points" in refusal(
        lambda: sp.interpolate(path, "spline", 10**9))


def test_angles_must_increase_within_the_spiral():
    # past the centre rho (eq 4) turns negative: 2 pi 250 + 100 rad gives
    # 0.5 mm - 2 um / (2 pi) x 1670.8 rad = -31.8 um, which was taken as a cutting point
    end = 2 * math.pi * 250
    assert PAPER.radius_at(end + 100) == pytest.approx(-3.1831e-5, rel=1e-4)
    with pytest.raises(InputError, match=r"angles within the spiral, 0 \.\. 1570\.79633 rad .*"
                                         r"got 0 \.\. 1670\.79633 rad"):
        sp.cutting_points(sp.sine_grid(), PAPER, [0.0, 1.0, end + 100])
    with pytest.raises(InputError, match=r"got -100 \.\. 0 rad"):
        sp.cutting_points(sp.sine_grid(), PAPER, [-100.0, 0.0])
    with pytest.raises(InputError, match=r"theta strictly increasing .* got 1\.0 rad at index 2 "
                                         r"after 1\.0"):
        sp.cutting_points(sp.sine_grid(), PAPER, [0.0, 1.0, 1.0, 2.0])
    # X linear in C through C = 2, 1, 0 at the half steps is 20, 15, 10, 5, 0; numpy.interp,
    # which needs increasing C, gave 0, 0, 0, 0, 20 without a word
    backwards = sp.ToolPath(np.array([2.0, 1.0, 0.0]), np.array([20.0, 10.0, 0.0]), np.zeros(3))
    for method in ("linear", "spline"):
        with pytest.raises(InputError, match=r"path\.c strictly increasing .* got 1\.0 rad at "
                                             r"index 1 after 2\.0"):
            sp.interpolate(backwards, method, 2)


def test_spiral_program_takes_c_increasing_as_interpolate_does():
    # the CAM cuts the spiral turning C one way, C = theta increasing (ToolPath); the
    # program of a path turning back was written without a word: a repeated C made a block
    # that turns no C (the lathe leaves it uncut, ending the run there), a C going back was
    # refused only when turned ('turns back between points 1 and 2', naming no block), and
    # servo_path.path_times ran the time backwards, so the loops lagged nothing
    from machinesim.cutting.servo_path import path_times

    backwards = sp.ToolPath(np.array([2.0, 1.0, 0.0]), np.array([20.0, 10.0, 0.0]) * 1e-6,
                            np.zeros(3))
    words = ("Expected path.c strictly increasing (the spindle turning one way), got 1.0 rad "
             "at index 1 after 2.0")
    for call in (sp.spiral_program, sp.interpolate, path_times):
        with pytest.raises(InputError, match=re.escape(words)) as caught:
            call(backwards)
        assert caught.value.key == "path.c"
    still = sp.ToolPath(np.array([0.0, 1.0, 1.0, 2.0]), np.full(4, 1e-4), np.zeros(4))
    with pytest.raises(InputError, match=re.escape("got 1.0 rad at index 2 after 1.0")):
        sp.spiral_program(still)
    # C increasing: the program as before, its C the path's, at 360 x 20 deg/min
    ahead = sp.ToolPath(np.array([0.0, 1.0, 2.0]), np.array([20.0, 10.0, 0.0]) * 1e-6,
                        np.zeros(3))
    program = sp.spiral_program(ahead)
    assert np.array_equal(program.targets[1:-1, AXES.index("C")], [0.0, 1.0, 2.0])
    assert program.feeds[2] == pytest.approx(7200.0 * 1e-3 / 60.0)
    assert np.array_equal(path_times(ahead), np.array([0.0, 1.0, 2.0]) / (40.0 * math.pi / 60.0))
