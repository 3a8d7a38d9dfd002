"""Virtual instruments against closed forms: probe contacts on a block, a cut groove's depth,
an injected error table read back, a squareness seen on the diagonal; seeded noise statistics."""

import math

import numpy as np
import pytest
from metrology_helpers import above

import machinesim
from machinesim.cutting import cut
from machinesim.errors import ComponentError, ErrorModel, ToolSetting, WorkpieceSetting
from machinesim.exceptions import AxisLimitError, InputError
from machinesim.metrology import (
    LaserInterferometer,
    Microscope,
    Readout,
    RTest,
    TouchProbe,
    WhiteLightInterferometer,
    squareness_from_diagonal,
)
from machinesim.nc import ProgramBuilder
from machinesim.tolerances import PROBE_CHORD_M as CHORD_M
from machinesim.workpiece import block

MM, UM, NM = 1e-3, 1e-6, 1e-9
R = 0.25 * MM
#: Axis values are rounded to 1 nm; an exact contact on the 1 nm grid reads back to round-off
#: of ~1e-3 m values (~1e-19 m): 0.1 nm (the brief) is far above that, far below 1 nm.
EXACT_M = 1e-10
#: Heights and interferometer readings: float64 round-off of mm-scale (heights) or 0.1 m-scale
#: (carriage positions) values is ~1e-17 m; 1e-15 m fails on any real error.
ROUND_OFF_M = 1e-15
#: Standard normal quantile for "within 4 sigma of the estimator": a seeded test never
#: flakes, and a wrong model (a sigma off by 10 % at N = 2000) fails it.
K = 4.0
N = 2000



@pytest.fixture(scope="module")
def grooving():
    return machinesim.load_machine("grooving_4axis")



def assert_noise_model(readings, truth, readout):
    """Mean and standard deviation within K standard errors of the model's (Sheppard) std."""
    readings = np.asarray(readings)
    n = readings.size
    std = readout.std
    assert abs(readings.mean() - truth) <= K * std / math.sqrt(n)
    assert abs(readings.std(ddof=1) - std) <= K * std / math.sqrt(2 * (n - 1))


# ------------------------------------------------------------------------------ touch probe


def test_touch_on_a_flat_block_reads_the_exact_axis_values(a0ib, flat):
    probe = TouchProbe(a0ib, None, flat, noise=False)
    q = probe.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM), "-Z", 2 * MM)
    # ball centre R above the top face: Z = R - 1 mm (the probe's 1 mm above the edge)
    np.testing.assert_allclose(q, above(a0ib, 2.5 * MM, 1.5 * MM, R), rtol=0, atol=EXACT_M)
    side = probe.touch(above(a0ib, -1 * MM, 1.5 * MM, -0.5 * MM), [1.0, 0, 0, 0, 0], 2 * MM)
    np.testing.assert_allclose(side, above(a0ib, -R, 1.5 * MM, -0.5 * MM), rtol=0, atol=EXACT_M)
    assert probe.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM), "+Z", 2 * MM) is None
    np.testing.assert_allclose(probe.nominal_centres(q), [2.5 * MM, 1.5 * MM, R], atol=EXACT_M)


def test_a_workpiece_offset_moves_the_readings_by_the_offset(a0ib, flat):
    delta = np.array([3.2, -1.1, -1.7]) * UM
    # A tool setting error moves the tool, not the probe beside it: it must not show.
    errors = ErrorModel(tool=ToolSetting([5 * UM, 0.0, 2 * UM], [0.0, 1e-4, 0.0]),
                        workpiece=WorkpieceSetting(delta))
    probe = TouchProbe(a0ib, errors, flat, noise=False)
    top = probe.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM), "-Z", 2 * MM)
    side = probe.touch(above(a0ib, -1 * MM, 1.5 * MM, -0.5 * MM), "+X", 2 * MM)
    face = probe.touch(above(a0ib, 2.5 * MM, -1 * MM, -0.5 * MM), "+Y", 2 * MM)
    assert top[2] == pytest.approx(R - 1 * MM + delta[2], abs=EXACT_M)
    assert side[0] == pytest.approx(-R + delta[0], abs=EXACT_M)
    assert face[1] == pytest.approx(-R - 40 * MM + delta[1], abs=EXACT_M)


def test_a_curved_axis_motion_is_followed_along_its_true_path(a0ib, flat):
    """EZZ = c1 z + c2 z^2 makes the ball run along Z at a varying rate: the contact solves
    Z + EZZ(Z) = R - 1 mm (Z on the tool side: the error adds to the tool's motion)."""
    c1, c2 = 1e-3, 0.5
    errors = ErrorModel(component={"Z": {"EZZ": ComponentError("poly", None, [0.0, c1, c2])}})
    probe = TouchProbe(a0ib, errors, flat, noise=False, resolution=0.0)
    q = probe.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM), "-Z", 2 * MM)
    a, b, c = c2, 1.0 + c1, 1 * MM - R
    z = (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)
    # the path is replaced by chords within CHORD_M; the contact can be off by that much
    # (over the ~1:1 slope of the Z travel), 2x for a kink anywhere in a piece
    assert q[2] == pytest.approx(z, abs=2 * CHORD_M)
    assert abs(q[2] - (R - 1 * MM)) > 1e-7  # the error is really there: ~0.3 um


def test_touch_noise_has_the_stated_mean_and_spread(a0ib, flat):
    probe = TouchProbe(a0ib, None, flat, rng=np.random.default_rng(0))
    start = above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM)
    z = [probe.touch(start, "-Z", 2 * MM)[2] for _ in range(N)]
    assert_noise_model(z, R - 1 * MM, probe.readout)
    assert probe.readout.std == pytest.approx(20 * NM, rel=1e-3)  # the stated default


def test_scan_deflections_follow_the_surface_and_its_edge(a0ib, flat):
    """Across the edge at x = 5 mm the ball rests on the edge line: centre height
    sqrt(R^2 - (x - 5 mm)^2); beyond x = 5 mm + R it hangs free (NaN)."""
    x = np.array([1.0, 4.9, 5.1, 5.2, 5.3]) * MM
    free = 0.1 * MM  # free ball centre height: below every resting height, within the stroke
    path = np.array([above(a0ib, xi, 1.5 * MM, free) for xi in x])
    scan = TouchProbe(a0ib, None, flat, noise=False, resolution=0.0).scan(path)
    rest = np.array([R, R, math.sqrt(R**2 - (0.1 * MM) ** 2),
                     math.sqrt(R**2 - (0.2 * MM) ** 2), np.nan])
    np.testing.assert_allclose(scan.deflection, rest - free, rtol=0, atol=ROUND_OFF_M)
    np.testing.assert_allclose(scan.contact_q[:4, 2], rest[:4] - 1 * MM, rtol=0,
                               atol=ROUND_OFF_M)
    assert np.isnan(scan.contact_q[4]).all() and not scan.q.flags.writeable


def test_scan_noise_has_the_stated_mean_and_spread(a0ib, flat):
    probe = TouchProbe(a0ib, None, flat, sigma=50 * NM, rng=7)
    path = np.tile(above(a0ib, 2.5 * MM, 1.5 * MM, R - 1 * UM), (N, 1))
    assert_noise_model(probe.scan(path).deflection, 1 * UM, probe.readout)


def test_probe_refuses_bad_set_ups(a0ib, grooving, flat):
    with pytest.raises(InputError, match="probe_tip"):
        TouchProbe(grooving, None, flat)
    probe = TouchProbe(a0ib, None, flat)
    with pytest.raises(InputError, match="start clear of the part"):
        probe.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 0.1 * MM), "-Z", 1 * MM)
    for z in (-0.3 * MM, -0.6 * MM):  # the top face 0.55 and 0.85 mm above the free ball
        with pytest.raises(InputError, match=r"over-travel"):
            probe.scan([above(a0ib, 1 * MM, 1.5 * MM, 1 * MM),
                        above(a0ib, 2.5 * MM, 1.5 * MM, z)], stroke=0.5 * MM)
    with pytest.raises(InputError, match="direction like '-Z'"):
        probe.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM), "-A", 1 * MM)
    with pytest.raises(InputError, match=r"shape \(5,\)"):
        probe.touch([0.0, 0.0, 0.0], "-Z", 1 * MM)
    with pytest.raises(AxisLimitError, match="axis X"):
        probe.touch(above(a0ib, 200 * MM, 1.5 * MM, 1 * MM), "-Z", 1 * MM)
    # 5 mm given in m: the search had run 5 m down, past Z's -30 mm, and returned None
    with pytest.raises(AxisLimitError, match=r"robonano_a0ib: a search of max_travel 5 along "
                                             r"-Z from q_start ends at axis Z = -5000\.0+ mm "
                                             r"outside its travel -30\.0+ mm \.\. 100\.0+ mm; "
                                             r"expected it within the travel \(max_travel is "
                                             r"in m"):
        probe.touch(above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM), "-Z", 5)
    # to the end of the travel is searched: 30 mm down from Z = 0 meets the block's top
    top = TouchProbe(a0ib, None, flat, noise=False).touch(
        above(a0ib, 2.5 * MM, 1.5 * MM, 1 * MM), "-Z", 30 * MM)
    np.testing.assert_allclose(top, above(a0ib, 2.5 * MM, 1.5 * MM, R), rtol=0, atol=EXACT_M)
    with pytest.raises(InputError, match="sigma >= 0"):
        TouchProbe(a0ib, None, flat, sigma=-1e-9)
    with pytest.raises(InputError, match="rng"):
        TouchProbe(a0ib, None, flat, rng="seed")


# ------------------------------------------------------------------------ optical profilers


@pytest.fixture(scope="module")
def grooved(grooving):
    """One 90-degree V groove 3 um deep along X at y = 1 mm (paper 002's microgrooves)."""
    b = ProgramBuilder(1).rapid(X=-0.5 * MM, Y=1 * MM, Z=0.1 * MM).rapid(Z=-3 * UM)
    program = b.linear(X=5.5 * MM, feed_mm_per_min=500.0).rapid(Z=0.1 * MM).build()
    part, _ = cut(program, grooving, tool="v:90", stock="block:5x3x1")
    return part


@pytest.mark.parametrize("instrument", [Microscope, WhiteLightInterferometer])
def test_optical_instruments_read_the_cut_groove_depth(grooved, instrument):
    reader = instrument(noise=False)
    # 0.1 um spacing from y = 0.99 mm puts sample 100 on the groove's apex line y = 1 mm
    p = reader.profile(grooved, (2.5 * MM, 0.99 * MM), (2.5 * MM, 1.01 * MM), 0.1 * UM)
    reference = np.concatenate([p.z[:50], p.z[-50:]]).mean()  # flat top either side
    # 0.01 nm (the brief): the depth is a 1 nm (and 0.1 nm) multiple, so rounding keeps it
    assert reference - p.z.min() == pytest.approx(3 * UM, abs=1e-11)
    assert np.argmin(p.z) == 100
    np.testing.assert_allclose(p.xy[100], [2.5 * MM, 1 * MM], rtol=0, atol=ROUND_OFF_M)
    hm = reader.height_map(grooved, 2.4 * MM, 2.6 * MM, 0.99 * MM, 1.01 * MM, 0.1 * UM)
    assert hm.z.shape == (201, 2001) and hm.y[100] == pytest.approx(1 * MM, abs=ROUND_OFF_M)
    np.testing.assert_allclose(hm.z[100], -3 * UM, rtol=0, atol=1e-11)


def test_optical_reading_rounds_to_the_resolution_and_keeps_nan():
    raised = block(5 * MM, 3 * MM, 1 * MM, origin=(0.0, 0.0, 0.4 * NM))
    start, end = (4.9 * MM, 1 * MM), (5.1 * MM, 1 * MM)
    micro = Microscope(noise=False).profile(raised, start, end, 10 * UM)
    wli = WhiteLightInterferometer(noise=False).profile(raised, start, end, 10 * UM)
    assert micro.s.size == 21
    # sample 10 lies on the block's edge to round-off: left out
    np.testing.assert_array_equal(micro.z[:10], 0.0)  # 0.4 nm rounds to 0 on a 1 nm grid
    np.testing.assert_allclose(wli.z[:10], 0.4 * NM, rtol=0, atol=ROUND_OFF_M)
    noisy = Microscope(rng=1).profile(raised, start, end, 10 * UM)
    for z in (micro.z, wli.z, noisy.z):  # beyond x = 5 mm there is no surface
        assert np.isnan(z[11:]).all() and np.isfinite(z[:10]).all()


@pytest.mark.parametrize("instrument, sigma", [(Microscope, 12 * NM),
                                               (WhiteLightInterferometer, 0.5 * NM)])
def test_optical_noise_has_the_stated_mean_and_spread(flat, instrument, sigma):
    reader = instrument(rng=np.random.default_rng(3))
    assert reader.readout.sigma == pytest.approx(sigma, rel=1e-12)
    hm = reader.height_map(flat, 1 * MM, 1 * MM + 49 * UM, 1 * MM, 1 * MM + 39 * UM, 1 * UM)
    assert hm.z.size == N
    assert_noise_model(hm.z, 0.0, reader.readout)


# ---------------------------------------------------------------------- laser interferometer

TABLE_X = np.linspace(-200, 200, 9) * MM
TABLE_E = np.array([0, 120, -35, 40, 80, -10, 5, 60, -25]) * NM


def test_interferometer_reads_back_an_injected_positioning_table(grooving):
    errors = ErrorModel(
        component={"X": {"EXX": ComponentError("table", TABLE_X, TABLE_E)}},
        # the laser rides on the table: the part's setting on the chuck must not show
        workpiece=WorkpieceSetting([1 * MM, -2 * MM, 0.0], alpha=0.01, beta=-0.02, gamma=0.03))
    laser = LaserInterferometer(grooving, errors, noise=False)
    reading = laser.positioning("X", TABLE_X)
    # zeroed at the first position, where the table reads 0; the values are 1 nm multiples
    np.testing.assert_allclose(reading.deviation, TABLE_E, rtol=0, atol=ROUND_OFF_M)
    between = laser.positioning("X", [-175 * MM, 25 * MM], reference=-200 * MM)
    np.testing.assert_allclose(between.deviation, [60 * NM, 35 * NM], rtol=0, atol=ROUND_OFF_M)
    assert not reading.deviation.flags.writeable


def test_interferometer_straightness_and_its_reference_lines(grooving):
    errors = ErrorModel(component={"X": {"EYX": ComponentError("table", TABLE_X, TABLE_E)}})
    laser = LaserInterferometer(grooving, errors, noise=False, resolution=0.0)
    raw = laser.straightness("X", TABLE_X, "Y", reference="none").deviation
    np.testing.assert_allclose(raw, TABLE_E, rtol=0, atol=ROUND_OFF_M)
    line = np.polyval(np.polyfit(TABLE_X, TABLE_E, 1), TABLE_X)
    fitted = laser.straightness("X", TABLE_X, "Y").deviation
    np.testing.assert_allclose(fitted, TABLE_E - line, rtol=0, atol=ROUND_OFF_M)
    ends = laser.straightness("X", TABLE_X, "Y", reference="end_points").deviation
    chord = TABLE_E[0] + (TABLE_E[-1] - TABLE_E[0]) * (TABLE_X - TABLE_X[0]) / 0.4
    np.testing.assert_allclose(ends, TABLE_E - chord, rtol=0, atol=ROUND_OFF_M)
    flat_z = laser.straightness("X", TABLE_X, "Z", reference="none").deviation
    np.testing.assert_allclose(flat_z, 0.0, rtol=0, atol=ROUND_OFF_M)
    # a run there and back has no end-point line (its slope was 0 / 0: every deviation
    # NaN, with noise on +-inf between NaN ends, under a RuntimeWarning only); the
    # least-squares line reads it
    there_and_back = np.r_[TABLE_X, TABLE_X[-2::-1]]
    with pytest.raises(InputError, match="positions.*end-point reference"):
        laser.straightness("X", there_and_back, "Y", reference="end_points")
    both = laser.straightness("X", there_and_back, "Y").deviation
    line = np.polyval(np.polyfit(there_and_back, np.r_[TABLE_E, TABLE_E[-2::-1]], 1),
                      there_and_back)
    np.testing.assert_allclose(both, np.r_[TABLE_E, TABLE_E[-2::-1]] - line, rtol=0,
                               atol=ROUND_OFF_M)


def test_interferometer_straightness_with_its_arguments_swapped_is_refused_in_words(grooving):
    # straightness("X", "Y", positions), the direction before the positions (a new-user
    # pass): the array reached `direction not in ("X", "Y", "Z")` and numpy raised "The
    # truth value of an array with more than one element is ambiguous", a traceback
    laser = LaserInterferometer(grooving, None, noise=False)
    with pytest.raises(InputError, match=r"key 'direction'.*got a ndarray.*"
                                         r"straightness\('X', positions, 'Y'\)"):
        laser.straightness("X", "Y", TABLE_X)
    with pytest.raises(InputError, match="key 'direction'.*got 'W'"):
        laser.straightness("X", TABLE_X, "W")


@pytest.mark.parametrize("corner, opposite", [((-200 * MM, -150 * MM), (200 * MM, 150 * MM)),
                                              ((200 * MM, -150 * MM), (-200 * MM, 150 * MM))])
def test_iso_230_6_diagonal_sees_the_squareness_in_closed_form(grooving, corner, opposite):
    """EC0Y = e runs Y along (-sin e, cos e): commanding (x, y) from the corner moves the tool
    (x - y sin e, y cos e); the laser reads its projection on the nominal diagonal."""
    e = 20e-6
    laser = LaserInterferometer(grooving, ErrorModel(location={"Y": {"EC0Y": e}}), noise=False,
                                resolution=0.0)
    a, b = np.subtract(opposite, corner)
    d = math.hypot(a, b)
    s = np.linspace(0.0, d, 11)
    reading = laser.diagonal(s, corner, opposite)
    x, y = s * a / d, s * b / d
    expected = ((x - y * math.sin(e)) * a + y * math.cos(e) * b) / d - s
    np.testing.assert_allclose(reading.deviation, expected, rtol=0, atol=ROUND_OFF_M)
    # first order: -a b e / d at the far corner (4.8 um here); second order ~e^2 d ~ 1e-10 m
    assert reading.deviation[-1] == pytest.approx(-a * b * e / d, abs=1e-9)
    # paper 003 eq 2 inverted; the projection differs from the length at second order: e^2
    assert squareness_from_diagonal(d + reading.deviation[-1], a, b) == pytest.approx(
        e, rel=1e-4)


def test_interferometer_noise_has_the_stated_mean_and_spread(grooving):
    laser = LaserInterferometer(grooving, None, rng=np.random.default_rng(11))
    # targets off the 1 nm grid: the display's rounding adds its resolution^2 / 12
    x = np.linspace(-100 * MM, 100 * MM, N) + 0.3 * NM
    reading = laser.positioning("X", x, reference=0.0)
    assert_noise_model(reading.deviation, 0.0, laser.readout)


def test_interferometer_refuses_bad_tests(grooving):
    laser = LaserInterferometer(grooving)
    with pytest.raises(InputError, match="rotary axis C"):
        laser.positioning("C", [0.0, 0.1])
    with pytest.raises(InputError, match="across axis X"):
        laser.straightness("X", [0.0, 0.1], "X")
    with pytest.raises(InputError, match="reference in"):
        laser.straightness("X", [0.0, 0.1], "Y", reference="best")
    with pytest.raises(AxisLimitError, match="axis X"):
        laser.positioning("X", [0.0, 0.3])
    with pytest.raises(InputError, match="along the diagonal"):
        laser.diagonal([0.0, 1.0], (0.0, 0.0), (0.1, 0.1))
    with pytest.raises(InputError, match="possible for spans"):
        squareness_from_diagonal(1.0, 0.3, 0.4)


def test_readout_is_seeded_and_rounds():
    readout = Readout(sigma=2 * NM, resolution=1 * NM)
    first = readout.read(np.zeros(5), np.random.default_rng(5))
    again = readout.read(np.zeros(5), np.random.default_rng(5))
    np.testing.assert_array_equal(first, again)
    np.testing.assert_allclose(first / NM, np.round(first / NM), rtol=0, atol=1e-9)
    assert Readout.of(2 * NM, 0.0, noise=False).read([1.25 * NM, np.nan], None)[0] == 1.25 * NM


@pytest.mark.parametrize("zero, factor", [("nominal", 1.0), ("first", math.sqrt(2.0))])
def test_r_test_readings_spread_as_their_stated_sigma(a0ib, zero, factor):
    # A zeroed reading is the difference of two displays, n_i - n_0: its spread over draws
    # is sqrt(2) x 50 nm = 70.7 nm, where 50 nm was stated. Monte Carlo over 4000 reads of
    # two poses (the second's three sensors: 12000 independent draws of the error).
    r_test = RTest(a0ib, rng=np.random.default_rng(5), resolution=0.0, zero=zero)
    q = np.array([[0.01, 0.005, 0.002, 0.1, 0.2], [0.012, 0.004, 0.003, 0.15, 0.3]])
    exact = RTest(a0ib, noise=False, resolution=0.0, zero=zero).read(q).displacement[1]
    readings = [r_test.read(q) for _ in range(4000)]
    errors = np.array([r.displacement[1] for r in readings]) - exact
    # the sample std of 12000 normal draws is within 5 x 1 / sqrt(2 x 12000) = 3.2 % of the
    # true one (a miss by chance ~6e-7); the old stated 50 nm is 29 % below 70.7 nm
    assert np.std(errors) == pytest.approx(readings[0].sigma, rel=0.032)
    assert {r.sigma for r in readings} == {factor * 50e-9}


@pytest.mark.parametrize("instrument", [Microscope, WhiteLightInterferometer])
def test_a_reading_off_the_part_in_mm_for_m_is_refused_saying_the_unit_and_the_part(
        instrument):
    # a line across a 10 mm block written in mm: (1, 5) to (9, 5) read 26.7 million NaN
    # samples in 9 s, and fit_v_groove then said 'Expected at least 5 finite samples, got 0'
    part = block(10 * MM, 10 * MM, 2 * MM)
    reader = instrument(noise=False)
    spans = ("the part spans x 0 .. 10 mm, y 0 .. 10 mm (in m: x 0 .. 0.01, y 0 .. 0.01). "
             "Expected ")
    with pytest.raises(InputError) as raised:
        reader.profile(part, (1, 5), (9, 5), spacing=1 * UM)
    assert str(raised.value) == (
        f"key 'start': {instrument.__name__}: the profile from (1, 5) to (9, 5) m (8 m long, "
        f"8e+06 samples at 1e-06 m) misses the part: every sample would read NaN (no "
        f"surface); {spans}start and end in m (SI: 5 mm is 0.005)")
    # x in mm, y in m: 10 mm of the 12 m line over the block, 0.0833 % (10 / 12000)
    with pytest.raises(InputError, match=r"\(-1, 0\.005\) to \(11, 0\.005\) m \(12 m long, "
                       r"1\.2e\+07 samples at 1e-06 m\) lies over the part for 0\.08% of it: "
                       r"the rest would read NaN; the part spans x 0 \.\. 10 mm"):
        reader.profile(part, (-1, 5 * MM), (11, 5 * MM), spacing=1 * UM)
    with pytest.raises(InputError, match=r"the map over x 1 \.\. 9 m, y 1 \.\. 9 m \(8 m x 8 m, "
                       r"6\.4e\+09 samples at 0\.0001 m\) misses the part.*Expected x0, x1, "
                       r"y0, y1 in m"):
        reader.height_map(part, 1, 9, 1, 9, spacing=0.1 * MM)
    # at the bound: a line of which 1/1000 lies over the block is read (10 mm of 9.99 m),
    # and so is a map 10 times the block's size each way around it (1 % of its area)
    line = reader.profile(part, (0.0, 5 * MM), (9.99, 5 * MM), spacing=1 * MM)
    assert np.isfinite(line.z).sum() == 11  # x = 0, 1, ..., 10 mm: on the block
    area = reader.height_map(part, -44.5 * MM, 54.5 * MM, -44.5 * MM, 54.5 * MM,
                             spacing=1 * MM)
    assert np.isfinite(area.z).sum() == 10 * 10  # x and y = 0.5, 1.5, ..., 9.5 mm


def test_an_instrument_marks_the_samples_off_the_part_missing_and_refuses_a_trace_on_none():
    # A profile half off a 2 x 2 x 1 mm block (x, y 0 .. 2 mm, top 1 mm) keeps the 10
    # samples over it at the top's height and marks the 11 off it missing; a map likewise,
    # and a plane fitted to it is the top exactly (the missing samples left out, not NaN).
    import manifold3d

    from machinesim.metrology import fit_plane, height_map_points
    from machinesim.metrology.imperfections import Spot
    from machinesim.workpiece import Part

    mm = 1e-3
    part = Part(manifold3d.Manifold.cube([2 * mm, 2 * mm, 1 * mm]))
    microscope = Microscope(noise=False)
    read = microscope.profile(part, (-1.05 * mm, 1 * mm), (0.95 * mm, 1 * mm), 0.1 * mm)
    assert read.missing.tolist() == [True] * 11 + [False] * 10
    np.testing.assert_allclose(read.z[~read.missing], 1 * mm, rtol=0, atol=1e-15)
    area = microscope.height_map(part, -0.95 * mm, 0.95 * mm, 0.05 * mm, 0.95 * mm, 0.1 * mm)
    assert area.missing[:, area.x < 0].all() and not area.missing[:, area.x > 0].any()
    top = fit_plane(height_map_points(area.x, area.y, area.z))
    np.testing.assert_allclose(top.normal, [0.0, 0.0, 1.0], atol=1e-12)
    assert top.point[2] == pytest.approx(1 * mm, abs=1e-15)
    # a trace within the part's extent over a gap between two blocks reads nothing: refused,
    # the spot's path (read through line_heights / spot_heights) as the exact one
    two = Part(manifold3d.Manifold.cube([1 * mm, 2 * mm, 1 * mm])
               + manifold3d.Manifold.cube([1 * mm, 2 * mm, 1 * mm]).translate((2 * mm, 0, 0)))
    for instrument in (microscope, Microscope(noise=False, spot=Spot(0.3e-6))):
        with pytest.raises(InputError, match=r"the profile from \(0.0015, 0\) to \(0.0015, "
                                             r"0.002\) m reads no surface: all 21 of its "
                                             r"samples lie off the part"):
            instrument.profile(two, (1.5 * mm, 0.0), (1.5 * mm, 2 * mm), 0.1 * mm)
        with pytest.raises(InputError, match=r"reads no surface: all 100 of its samples"):
            instrument.height_map(two, 1.05 * mm, 1.95 * mm, 0.05 * mm, 0.95 * mm, 0.1 * mm)


def test_a_profile_and_a_height_map_say_what_they_are_with_units():
    """Their repr had been the dataclass dump, numpy's elided arrays of bare SI
    (Profile(s=array([0.0000e+00, 3.0000e-07, ...]), z=array([ 5.0e-09, ...]), ...)):
    neither the count, the line in mm nor the heights' range in a unit. Hand values: a
    line of 1 mm at 0.3 um spacing holds 3334 samples, half of it (1667) off a 10 mm
    block's edge; 4 x 2 um read at 0.5 um spacing is 9 x 5; noise off, the top reads 0."""
    part = block(10 * MM, 10 * MM, 2 * MM)
    profile = Microscope(noise=False).profile(part, (5 * MM, 9.5 * MM), (5 * MM, 10.5 * MM))
    assert repr(profile) == ("Profile(3334 samples from (5, 9.5) mm to (5, 10.5) mm, "
                             "1667 missing, z 0 .. 0 um)")
    heights = WhiteLightInterferometer(noise=False).height_map(part, 1 * MM, 1.004 * MM,
                                                                2 * MM, 2.002 * MM)
    assert repr(heights) == ("HeightMap(5 x 9 samples over x 1 .. 1.004 mm, "
                             "y 2 .. 2.002 mm, 0 missing, z 0 .. 0 um)")
