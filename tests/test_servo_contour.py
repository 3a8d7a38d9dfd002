"""Servo loops on a contour: consecutive feed moves are one motion, so a circle comes out with
the radius and phase of the loops' frequency response, and unequal loops make it an ellipse."""

import numpy as np
import pytest

from machinesim import load_machine
from machinesim.motion import plan
from machinesim.nc import parse_program
from machinesim.servo import AxisServo, PIDServo

R = 1e-3  # circle radius, m
FREQ_HZ = 1.0  # turns per second
TURNS = 3
SAG = 1e-9  # the arcs' chord tolerance


def _circle_program() -> str:
    # G03 full circles about the origin from (R, 0), at the feed of FREQ_HZ turns per second
    feed_mm_min = 2.0 * np.pi * R * FREQ_HZ * 1e3 * 60.0
    turns = "".join(f"G03 X{R * 1e3:.6f} Y0. I{-R * 1e3:.6f} J0.\n" for _ in range(TURNS))
    return (f"G90 G21 G17\nG00 X{R * 1e3:.6f} Y0. Z0.\nG01 Z0. F{feed_mm_min:.9f}\n"
            f"{turns}G00 Z1.\n")


def _p_loop(kp: float) -> AxisServo:
    # P control of a 1 kg mass on 100 N s/m: T(s) = kp / (s^2 + 100 s + kp)
    return AxisServo(kp=kp, ki=0.0, kd=0.0, mass=1.0, damping=100.0)


def _followed_circle(servo_x: AxisServo, servo_y: AxisServo):
    machine = load_machine("grooving_4axis")  # X Y Z C
    program = parse_program(_circle_program(), chord_tolerance=SAG)
    ideal = plan(program, machine)
    lagged = plan(program, machine, servo=PIDServo((servo_x, servo_y, None, None)))
    feed = np.array([s.kind == "linear" for s in ideal.segments])
    first = int(np.argmax(feed)) + 1  # the circles, after the Z feed
    t = np.concatenate([s.t for s in ideal.segments[first:] if s.kind == "linear"])
    t0 = ideal.segments[first].t[0]
    q = np.concatenate([s.q for s in lagged.segments[first:] if s.kind == "linear"])
    command = np.concatenate([s.q for s in ideal.segments[first:] if s.kind == "linear"])
    last_turn = t - t0 >= (TURNS - 1) / FREQ_HZ  # transients gone: exp(-50 s^-1 * 2 s)
    # the motion's last sample is where the axes settle (it ends in position: a rapid
    # follows), not a point of the steady contour
    assert np.array_equal(q[-1], command[-1])
    last_turn[-1] = False
    # where the command stands, as a phasor: the chords, shorter than their arcs, run a
    # turn 3e-7 s early, so the angle is read from the command, not from the clock
    phasor = (command[last_turn, 0] + 1j * command[last_turn, 1]) / R
    return phasor, q[last_turn, :2]


def _expected(phasor, gx: complex, gy: complex) -> np.ndarray:
    """x = R cos(phi) reaches R Re(Gx e^{j phi}), y = R sin(phi) reaches R Im(Gy e^{j phi})."""
    return R * np.stack([(gx * phasor).real, (gy * phasor).imag], axis=1)


def _response(axis: AxisServo) -> complex:
    """The sampled closed loop's gain at the circle's frequency (its transfer function)."""
    import control

    w = 2.0 * np.pi * FREQ_HZ
    return complex(control.evalfr(axis._loops[0], np.exp(1j * w * axis.sample_time_s)))


def test_equal_loops_turn_a_circle_into_a_circle_of_radius_r_times_gain():
    kp = 1e4
    phasor, q = _followed_circle(_p_loop(kp), _p_loop(kp))
    w = 2.0 * np.pi * FREQ_HZ
    # continuous closed form: |T(jw)| = kp / |kp - w^2 + 100 j w|, 1.002 here: +1.98 um
    gain = kp / abs(kp - w**2 + 100j * w)
    radius = np.hypot(q[:, 0], q[:, 1])
    assert R * (gain - 1.0) == pytest.approx(1.98e-6, rel=0.01)
    assert np.ptp(radius) < 1e-9  # a circle: equal loops leave no ellipse
    assert radius.mean() - R == pytest.approx(R * (gain - 1.0), rel=0.01)
    # pointwise against the sampled loop's own frequency response: x = R Re(G e^{jwt})
    g = _response(_p_loop(kp))
    # to the chords' sag: the command lies up to 1 nm inside the circle between vertices
    assert np.max(np.abs(q - _expected(phasor, g, g))) < SAG


def test_unequal_loops_make_an_ellipse_at_the_loops_responses():
    fast, slow = _p_loop(1e4), _p_loop(2.5e3)
    phasor, q = _followed_circle(fast, slow)
    assert np.max(np.abs(q - _expected(phasor, _response(fast), _response(slow)))) < SAG
    # the lag differs between the axes by about 3 deg: the ellipse is tilted, its axes
    # differ by several um
    radius = np.hypot(q[:, 0], q[:, 1])
    assert np.ptp(radius) > 1e-6


def test_the_cut_report_gives_each_axis_peak_following_error():
    # one G01 line at constant speed under a PD loop on X: the lag at its end is v c / Kp
    import machinesim

    m, c, kp, kd = 4.0, 1e4, 6e7, 2e4
    servo = PIDServo((AxisServo(kp=kp, ki=0.0, kd=kd, mass=m, damping=c, name="X"),
                      None, None, None))
    program = parse_program("G90 G21\nG00 X1. Y5. Z0.1\nG01 Z-0.001 F60.\n"
                            "G01 X9. F600.\nG00 Z1.\n")
    part, report = machinesim.cut(program, "grooving_4axis", "v:90", "block:10x10x2",
                                  servo=servo)
    v = 600.0 / 60.0 * 1e-3  # m/s
    assert report.peak_following_error["X"] == pytest.approx(v * c / kp, rel=1e-3)
    assert report.peak_following_error["Y"] == 0.0
    assert report.to_dict()["peak_following_error_um_or_urad"]["X"] == pytest.approx(
        v * c / kp * 1e6, rel=1e-3)
    _, ideal = machinesim.cut(program, "grooving_4axis", "v:90", "block:10x10x2")
    assert ideal.peak_following_error == {}
