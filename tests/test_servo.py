"""The sampled PID + feed-forward servo against closed forms of continuous linear systems."""

import re

import numpy as np
import pytest

from machinesim.exceptions import InputError, MachineSimError
from machinesim.servo import AxisServo, PIDServo, ServoDivergenceError, table6_servo


def test_step_of_p_loop_matches_second_order_response():
    # P control on m s^2 + c s: T(s) = kp / (m s^2 + c s + kp), a pure second-order system.
    m, c, kp = 2.0, 80.0, 2.0e4
    wn = np.sqrt(kp / m)
    zeta = c / (2.0 * np.sqrt(kp * m))
    wd = wn * np.sqrt(1.0 - zeta**2)
    ts = 1e-5
    axis = AxisServo(kp=kp, ki=0.0, kd=0.0, mass=m, damping=c, sample_time_s=ts)
    t = ts * np.arange(20001)
    r = np.ones_like(t)
    r[0] = 0.0  # at rest on 0, step to 1 at the first period
    y = axis.respond(t, r)
    tt = t - ts
    expected = 1.0 - np.exp(-zeta * wn * tt) * (np.cos(wd * tt)
                                                + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * tt))
    expected[0] = 0.0
    # the zero-order hold delays by half a period: error of order wn * ts
    assert np.max(np.abs(y - expected)) < 2e-3
    assert y.max() - 1.0 == pytest.approx(np.exp(-np.pi * zeta / np.sqrt(1 - zeta**2)),
                                          abs=2e-3)


def _ramp_error(axis: AxisServo, v: float, duration: float) -> float:
    t = np.linspace(0.0, duration, 2001)
    q = (v * t)[:, None]
    return float(PIDServo((axis,)).following_error(t, q)[-1, 0])


def test_ramp_error_of_pd_loop_is_final_value_theorem():
    # L(s) = (kd s + kp) / (s (m s + c)): velocity constant Kv = kp / c, e_ss = v / Kv.
    m, c, kp, kd, v = 4.0, 1e4, 6e7, 2e4, 1e-3
    axis = AxisServo(kp=kp, ki=0.0, kd=kd, mass=m, damping=c)
    assert _ramp_error(axis, v, 0.2) == pytest.approx(v * c / kp, rel=1e-3)


def test_ramp_error_vanishes_with_integral_action():
    # the integrator makes the loop type 2: zero steady-state error for a ramp
    m, c, kp, kd, ki, v = 4.0, 1e4, 6e7, 2e4, 1e9, 1e-3
    axis = AxisServo(kp=kp, ki=ki, kd=kd, mass=m, damping=c)
    assert abs(_ramp_error(axis, v, 0.5)) < 1e-3 * v * c / kp


@pytest.mark.parametrize("factor, stable", [(0.8, True), (1.25, False)])
def test_instability_matches_routh_criterion(factor, stable):
    # m s^3 + kd s^2 + kp s + ki (c = 0) is stable iff kd kp > m ki (Routh-Hurwitz).
    m, kp, kd = 1.0, 1e4, 100.0
    ki = factor * kd * kp / m
    if stable:
        axis = AxisServo(kp=kp, ki=ki, kd=kd, mass=m, sample_time_s=1e-6)
        assert axis.pole_radius < 1.0
    else:
        with pytest.raises(ServoDivergenceError) as info:
            AxisServo(kp=kp, ki=ki, kd=kd, mass=m, sample_time_s=1e-6, name="x")
        assert isinstance(info.value, MachineSimError)
        assert "axis x is unstable" in str(info.value)


def test_a_pole_far_outside_the_unit_circle_is_written_in_six_digits():
    # Kd = 1e200 put |z| = 4.1e194 in the message as its 195 digits and 9 decimals
    with pytest.raises(ServoDivergenceError) as info:
        AxisServo(kp=1.2e6, ki=0.0, kd=1e200, mass=12.0, damping=1600.0)
    assert re.search(r"largest closed-loop pole \|z\| = \d\.\d{5}e\+\d+ > 1\)", str(info.value))
    assert len(str(info.value)) < 250, str(info.value)


def test_a_loop_unstable_in_continuous_time_says_what_to_change():
    # m s^3 + (c + Kd) s^2 + Kp s + Ki is stable iff (c + Kd) Kp > m Ki (Routh-Hurwitz); where
    # it is not, "lower the gains" (all of them) does not settle it
    def refusal(**gains):
        with pytest.raises(ServoDivergenceError) as info:
            AxisServo(mass=4.0, name="x", **{"damping": 1600.0, **gains})
        return str(info.value)

    # Table 6 "before" X with Ki 100 times: (1600 + 900) 6e4 = 1.5e8 <= 4 x 7e8 = 2.8e9, and
    # Ki below 1.5e8 / 4 = 3.75e7 settles it
    message = refusal(kp=6e4, ki=7e8, kd=900.0)
    assert re.search(r"\(damping \+ Kd\) Kp = 1\.5e\+08 <= mass Ki = 2\.8e\+09: unstable in "
                     r"continuous time.*raise Kp, Kd or the damping, or lower Ki below \(c \+ "
                     r"Kd\) Kp / m = 3\.75e\+07", message)
    assert "lower the gains" not in message
    for factor, stable in ((0.9, True), (1.1, False)):
        assert (AxisServo(kp=6e4, ki=factor * 3.75e7, kd=900.0, mass=4.0, damping=1600.0)
                .pole_radius < 1.0) if stable else refusal(kp=6e4, ki=factor * 3.75e7, kd=900.0)
    # Kp = 0 with integral action: no s term, unstable for any Ki > 0
    message = refusal(kp=0.0, ki=7e6, kd=900.0)
    assert "Kp = 0 <= mass Ki = 2.8e+07" in message and "lower Ki" not in message
    # a P loop on an undamped mass: m s^2 + Kp oscillates at any Kp
    assert "nothing damps it (damping = Kd = 0)" in refusal(kp=6e4, ki=0.0, kd=0.0, damping=0.0)
    # Kd alone: the position is not fed back (a pole at z = 1 it blamed on "an integral gain
    # too small to act against Kp" with Ki = 0)
    message = refusal(kp=0.0, ki=0.0, kd=900.0)
    assert "no position feedback (Kp = Ki = 0)" in message and "integral gain" not in message
    # stable in continuous time, unstable sampled at 10 kHz: lowering the gains does help
    assert refusal(kp=6e9, ki=7e6, kd=900.0).endswith("the axis would oscillate; lower the gains")


def test_a_motion_longer_than_the_followed_periods_is_refused_before_it_is_simulated():
    axis = AxisServo(kp=1e4, ki=0.0, kd=0.0, mass=1.0, damping=100.0, name="x")
    # 1e6 s at 1e-4 s: 1e10 periods, ten times the most (MAX_FOLLOW_PERIODS, 27.8 h at 10 kHz)
    with pytest.raises(InputError, match=r"axis x: a motion of 1e\+06 s is 1e\+10 loop periods "
                                         r"of 0\.0001 s, more than the 1e\+09 one motion is "
                                         r"followed for \(27\.8 h"):
        axis.reach(np.array([0.0, 1e6]), np.array([0.0, 1e-3]))


def test_table6_after_follows_better_than_before():
    # the paper's tuning (Table 6) reduces the follow-up error on a servo sine
    t = np.linspace(0.0, 0.2, 2001)
    q = np.stack([1e-4 * np.sin(2 * np.pi * 5 * t)] * 2 + [np.sin(2 * np.pi * 5 * t)], axis=1)
    before = np.abs(table6_servo("before").following_error(t, q)[1000:]).max(axis=0)
    after = np.abs(table6_servo("after").following_error(t, q)[1000:]).max(axis=0)
    assert np.all(after < before)


def test_bad_input_is_named():
    with pytest.raises(InputError, match="kp"):
        AxisServo(kp=-1.0, ki=0.0, kd=0.0, mass=1.0)
    with pytest.raises(InputError, match="mass"):
        AxisServo(kp=1.0, ki=0.0, kd=0.0, mass=0.0)
    with pytest.raises(InputError, match="preset"):
        table6_servo("middle")
    with pytest.raises(InputError, match="needs t"):
        PIDServo((None,)).follow(np.zeros(3), np.zeros((3, 2)))
    # a feed-forward fraction past twice the inertial force (1e9 was taken without a word)
    assert AxisServo(kp=1.0, ki=0.0, kd=1.0, mass=1.0, acc_ff=2.0).acc_ff == 2.0
    with pytest.raises(InputError, match="acc_ff of axis z is the fraction of the inertial "
                                         r"force fed forward, 0 \(none\) to 1 \(all\), at "
                                         "most 2; got 1000000000.0"):
        AxisServo(kp=1.0, ki=0.0, kd=1.0, mass=1.0, acc_ff=1e9, name="z")


def test_plan_keeps_a_move_s_lag_and_ends_it_in_position():
    # a G01 move is a ramp from rest: with a PD loop on X the lag at its end is v c / kp;
    # then the axes settle onto its end (the program ends), where the part is cut to
    from machinesim import load_machine
    from machinesim.motion import plan
    from machinesim.nc import parse_program

    machine = load_machine("sts_lathe")
    program = parse_program("G90 G21\nG01 X1.0 Z-0.5 F100\n")
    m, c, kp, kd = 4.0, 1e4, 6e7, 2e4
    servo = PIDServo((AxisServo(kp=kp, ki=0.0, kd=kd, mass=m, damping=c, name="x"), None,
                      None))
    ideal = plan(program, machine)
    lagged = plan(program, machine, servo=servo)
    v_x = (ideal.q[-1, 0] - ideal.q[0, 0]) / (ideal.t[-1] - ideal.t[0])
    assert lagged.peak_lag[0] == pytest.approx(v_x * c / kp, rel=1e-3)
    assert lagged.peak_lag[1:].tolist() == [0.0, 0.0]
    assert ideal.peak_lag is None
    np.testing.assert_array_equal(lagged.q, ideal.q)


def test_fast_filter_equals_forced_response():
    # second method: python-control's own simulation of the same closed loop
    import control

    from machinesim.servo import table6_axis
    axis = table6_axis("after", "z")
    reference, feed, _ = axis._loops
    t = axis.sample_time_s * np.arange(3000)
    r = 1e-5 * np.sin(2 * np.pi * 7 * t) + 2e-6 * t
    a = np.gradient(np.gradient(r, axis.sample_time_s), axis.sample_time_s)
    expected = (r[0] + control.forced_response(reference, T=t, U=r - r[0]).outputs
                + control.forced_response(feed, T=t, U=a).outputs)
    np.testing.assert_allclose(axis.respond(t, r), expected, rtol=0, atol=1e-15)


def test_p_loop_has_the_poles_of_its_continuous_loop_and_the_ramp_error_v_c_over_kp():
    # m s^2 + c s + kp = s^2 + 100 s + 2000: poles -27.64 and -72.36 1/s, so the sampled
    # loop's largest |z| is about exp(-27.64 Ts) (the hold shifts it by 0.2 %). Discretising
    # the bare gain once left a (z - 1) / (z - 1) pair: the loop was refused as on the unit
    # circle, or drifted.
    axis = AxisServo(kp=2e3, ki=0.0, kd=0.0, mass=1.0, damping=100.0)
    slowest = -50.0 + np.sqrt(50.0**2 - 2e3)
    assert np.log(axis.pole_radius) / axis.sample_time_s == pytest.approx(slowest, rel=5e-3)
    stiff = AxisServo(kp=2e5, ki=0.0, kd=0.0, mass=10.0, damping=2000.0)
    assert _ramp_error(stiff, 1e-3, 2.0) == pytest.approx(1e-3 * 2000.0 / 2e5, rel=1e-6)


def test_a_long_motion_is_followed_in_pieces_equal_to_one_piece(monkeypatch):
    # the loops' state carries across pieces: the same numbers bit for bit, feed-forward on
    from machinesim import servo as servo_module
    from machinesim.servo import table6_axis

    axis = table6_axis("before", "z")  # acceleration feed-forward and its low-pass
    assert axis.acc_ff > 0.0
    t = np.sort(np.random.default_rng(3).uniform(0.0, 0.25, 300))
    t[0] = 0.0
    q = (1e-5 * np.sin(2 * np.pi * 9 * t) + 3e-6 * t)[:, None]
    whole = PIDServo((axis,)).follow(t, q)
    monkeypatch.setattr(servo_module, "FOLLOW_CHUNK", 7)
    np.testing.assert_array_equal(PIDServo((axis,)).follow(t, q), whole)


def test_a_gain_given_as_text_is_named():
    with pytest.raises(InputError, match="mass .*must be a number.*'4'"):
        AxisServo(kp=1.0, ki=0.0, kd=0.0, mass="4")


@pytest.mark.filterwarnings("error::RuntimeWarning")  # numpy's overflow, not one line
def test_values_no_machine_axis_has_are_refused_not_turned_into_a_silent_loop():
    # a 1e30 kg mass underflows the loop's coefficients; a 1e-12 s period left no poles
    with pytest.raises(InputError, match="badly conditioned"):
        AxisServo(kp=1e6, ki=0.0, kd=1e3, mass=1e30, damping=100.0)
    # a damping of 1e300 or a mass of 1e-300 overflows them to inf: numpy's LinAlgError
    # ("Array must not contain infs or NaNs"; scipy's ValueError for a Kd of 1e300 on a
    # 1e-300 kg mass) ended `cut --servo` with status 1
    for kp, kd, mass, damping in ((1.2e6, 3700.0, 12.0, 1e300), (1.2e6, 3700.0, 1e-300, 1600.0),
                                  (0.0, 1e300, 1e-300, 0.0)):
        with pytest.raises(InputError, match="badly conditioned"):
            AxisServo(kp=kp, ki=0.0, kd=kd, mass=mass, damping=damping)
    with pytest.raises(InputError, match="period .* 1e-07 .. 0.1 s"):
        AxisServo(kp=1e6, ki=1e7, kd=1e3, mass=10.0, damping=100.0, sample_time_s=1e-12)


def test_a_servo_model_returning_nan_is_named_by_the_planner():
    from machinesim import load_machine
    from machinesim.motion import plan
    from machinesim.nc import parse_program

    class Broken:
        def follow(self, t, q):
            out = q.copy()
            out[-1, 0] = np.nan
            return out

    program = parse_program("G90 G21\nG01 X1.0 Z-0.5 F100\nG01 X2.0\n")
    with pytest.raises(InputError, match=r"servo.follow returned .*not finite.*Broken"):
        plan(program, load_machine("sts_lathe"), servo=Broken())


def test_an_axis_and_a_servo_say_what_they_are_with_units():
    """Their repr had been the dataclass dump of bare SI ('AxisServo(kp=1200000.0, ki=0.0,
    kd=3700.0, mass=12.0, damping=1600.0, acc_ff=0.0, bandwidth_hz=inf, sample_time_s=
    0.0001, name='X')'). Hand values: docs/lab.md's slide; Table 6 "after" c reads Kp 100
    per mrad as 1e5 N m/rad, inertia 0.3 kg m^2; its z feeds forward ACCFF 0.001 x 1000 = 1
    of the inertial force through System BW 16 Hz; 1e-4 s is 0.1 ms."""
    slide = AxisServo(kp=1.2e6, ki=0.0, kd=3700.0, mass=12.0, damping=1600.0, name="X")
    assert repr(slide) == ("AxisServo(X: Kp 1.2e+06 N/m, Ki 0 N/(m s), Kd 3700 N s/m, mass "
                           "12 kg, damping 1600 N s/m; no feed-forward; loop 0.1 ms)")
    unnamed = AxisServo(kp=1e4, ki=0.0, kd=0.0, mass=1.0, damping=100.0, sample_time_s=1e-3)
    assert repr(unnamed) == ("AxisServo(axis: SI, per m or rad: Kp 10000, Ki 0, Kd 0, mass 1, "
                             "damping 100; no feed-forward; loop 1 ms)")
    assert repr(PIDServo((slide, None))) == f"PIDServo({slide.summary()} | column 2 exact)"
    after = repr(table6_servo("after", ("z", "y", "c")))
    assert after == (
        "PIDServo(z: Kp 180000 N/m, Ki 1e+07 N/(m s), Kd 1500 N s/m, mass 4.8 kg, damping "
        "1600 N s/m; feed-forward 1 x the inertial force through 16 Hz; loop 0.1 ms | column 2 "
        "exact | c: Kp 100000 N m/rad, Ki 1e+07 N m/(rad s), Kd 1500 N m s/rad, mass 0.3 kg "
        "m^2, damping 50 N m s/rad; no feed-forward; loop 0.1 ms)")
