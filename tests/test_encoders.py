"""The lab's axis encoders: the follow-up error its hidden servo loops leave, as a control
records it, against the final-value theorem."""

import numpy as np
import pytest

import machinesim
from machinesim.cutting import cut
from machinesim.exceptions import InputError
from machinesim.nc import parse_program
from machinesim.servo import AxisServo, PIDServo

#: A PD loop on X (mass 4 kg, guide damping 1e4 N s/m, kd adding 2e3): the velocity
#: constant is kp / c = 60 /s, the slow closed-loop pole kp / (c + kd) = 50 /s.
M, C, KP, KD = 4.0, 1e4, 6e5, 2e3
V = 1e-3  # m/s: G01 at F60 mm/min
RAMP = parse_program("G90 G21 G94\nG01 X1. F60.\nM30")


def lab_with_pd_x(**options) -> machinesim.Lab:
    servo = PIDServo((AxisServo(kp=KP, ki=0.0, kd=KD, mass=M, damping=C), None, None))
    return machinesim.Lab("sts_lathe", servo=servo, **options)


def test_a_ramp_lags_by_the_final_value_theorem():
    # L(s) = (kd s + kp) / (s (m s + c)): e_ss = v c / kp = 16.67 um; after 1 s (50 time
    # constants of the slow pole) the transient is gone; the encoder rounds to the axis'
    # resolution.
    lab = lab_with_pd_x(noise=False)
    reading = lab.encoders().record(RAMP)
    resolution = lab.machine.resolution[0]
    assert reading.following_error[-1, 0] == pytest.approx(V * C / KP,
                                                           abs=resolution / 2 + 1e-15)
    assert reading.peak("Z") == 0.0 and reading.peak("C") == 0.0  # ideal axes
    np.testing.assert_array_equal(reading.commanded[[0, -1], 0], [0.0, 1e-3])


def test_encoder_noise_is_the_stated_fraction_of_the_resolution():
    # Ideal axes on 1 um steps, exact multiples of the resolution q: a reading is the noise
    # (sigma = 0.3 q) rounded to whole steps, k q with probability
    # Phi((k + 1/2) q / sigma) - Phi((k - 1/2) q / sigma); its standard deviation follows.
    from scipy.stats import norm

    lab = machinesim.Lab("sts_lathe", seed=3)
    program = parse_program("G90 G21 G94\n" + "".join(
        f"G01 X{0.001 * k:.3f} F60.\n" for k in range(1, 2001)) + "M30")
    encoders = lab.encoders()
    reading = encoders.record(program)
    readout = encoders.readouts[0]
    error = reading.following_error[:, 0]
    k = np.arange(-5, 6)
    z = readout.resolution / readout.sigma
    p = norm.cdf((k + 0.5) * z) - norm.cdf((k - 0.5) * z)
    expected = readout.resolution * np.sqrt(np.sum(p * k**2))
    assert readout.sigma == pytest.approx(0.3 * lab.machine.resolution[0], rel=1e-12)
    assert np.std(error) == pytest.approx(expected, rel=0.1)  # 4000 samples: ~3 %


def test_the_lab_cuts_through_its_own_servo_and_hides_it():
    lab = lab_with_pd_x(noise=False)
    # a step: X lags into the corner at X0 and carries the lag down the next feed move
    program = parse_program("G90 G21 G94\nG00 X-0.5 Z0.1\nG01 Z-0.01 F60.\nX0.\nZ-0.02\n"
                            "X0.5\nG00 Z0.1\nM30")
    stock = "cylinder:2x1"
    _, by_lab = lab.cut(program, "ball:0.5", stock)
    _, given = cut(program, "sts_lathe", "ball:0.5", stock, servo=lab.reveal_servo())
    _, ideal = cut(program, "sts_lathe", "ball:0.5", stock)
    assert by_lab.removed_volume_m3 == given.removed_volume_m3
    assert by_lab.removed_volume_m3 != ideal.removed_volume_m3  # the lag rounds the step
    encoders = lab.encoders()
    assert not any(name in ("servo", "_servo") for name in vars(encoders))
    with pytest.raises(InputError, match="follow"):
        machinesim.Lab("sts_lathe", servo=object())


def test_a_trace_at_the_loop_period_follows_the_continuous_ramp_response():
    # P loop on a 1 kg mass, 100 N s/m, Kp 1e4 N/m: a ramp from rest leaves the error
    # E(s) = v (s + 100) / (s (s^2 + 100 s + 1e4)), settling to v c / Kp = 100 um at 10 mm/s
    from scipy.signal import lsim

    loop = AxisServo(kp=1e4, ki=0.0, kd=0.0, mass=1.0, damping=100.0, name="X")
    lab = machinesim.Lab("grooving_4axis", noise=False,
                         servo=PIDServo((loop, None, None, None)))
    program = parse_program("G90 G21\nG01 X5. F600.\n")  # 0.5 s at 10 mm/s
    assert len(lab.encoders().record(program).t) == 2  # by default the move's ends
    trace = lab.encoders().record(program, period_s=1e-3)
    assert np.allclose(np.diff(trace.t), 1e-3)
    v = 10e-3
    # E(s) = G(s) / s, G = v (s + 100) / (s^2 + 100 s + 1e4): G's response to a unit step
    _, expected, _ = lsim(([v, 100.0 * v], [1.0, 100.0, 1e4]), np.ones_like(trace.t), trace.t)
    error = trace.following_error[:, 0]
    assert error[-1] == pytest.approx(v * 100.0 / 1e4, rel=1e-3)
    # the sampled loop (10 kHz, zero-order hold) against the continuous one, and the 1 nm
    # resolution of the readout
    assert np.max(np.abs(error - expected)) < 0.01 * v * 100.0 / 1e4
    with pytest.raises(InputError, match="period_s"):
        lab.encoders().record(program, period_s=0.0)


def test_a_period_is_a_number_of_seconds_not_a_bool_and_numpy_scalars_are_taken():
    # period_s=True was taken as 1 s (the 0.5 s move then read at its two ends only), and
    # np.float32(1e-3), np.int64(1) were refused as "Expected period_s > 0, got 0.001"
    lab = machinesim.Lab("grooving_4axis", noise=False)
    program = parse_program("G90 G21\nG01 X5. F600.\n")  # 0.5 s at 10 mm/s
    for flag in (True, np.True_):
        with pytest.raises(InputError, match="period_s as a number"):
            lab.encoders().record(program, period_s=flag)
    # every ms of the 0.5 s: 499 inner samples and the move's two ends
    assert len(lab.encoders().record(program, period_s=np.float64(1e-3)).t) == 501
    assert len(lab.encoders().record(program, period_s=np.float32(0.25)).t) == 3
    assert len(lab.encoders().record(program, period_s=np.int64(1)).t) == 2


def test_a_sigma_given_as_text_is_refused_naming_what_arrived():
    # lab.encoders(sigma="1") said "Expected one sigma per axis (5), got ()": numpy had
    # read the text as the number 1; ["1e-9"] * 5 was read as numbers
    import machinesim
    from machinesim.exceptions import InputError

    lab = machinesim.Lab("robonano_a0ib", noise=False)
    for sigma in ("1", ["1e-9"] * 5, [True] * 5):
        with pytest.raises(InputError, match=r"Expected sigma as one noise std per axis "
                                             r"\(m or rad\), got ") as info:
            lab.encoders(sigma=sigma)
        assert info.value.key == "sigma"
    assert lab.encoders(sigma=[1e-9] * 5).readouts[0].sigma == 0.0  # noise off: sigma unused


def test_a_recorded_path_past_an_axis_travel_is_refused_as_the_cut_refuses_it():
    # sts_lathe's X travels -100 .. 100 mm: G01 X150. leaves it at line 3 (N30); the
    # recording took it silently (3 samples), where Lab.cut refuses the same path
    from machinesim.exceptions import AxisLimitError

    lab = machinesim.Lab("sts_lathe", noise=False)
    program = parse_program("G90 G21 G94\nN20 G01 X10. F600.\nN30 G01 X150.\nM30",
                            source="far.nc")
    with pytest.raises(AxisLimitError, match=r"far\.nc: axis X = 150\.000000 mm at line 3 "
                                             r"\(N30\) outside its travel -100\.000000 mm "
                                             r"\.\. 100\.000000 mm; nothing was recorded"):
        lab.encoders().record(program)
    with pytest.raises(AxisLimitError, match=r"axis X = 150\.000000 mm at line 3 \(N30\)"):
        lab.cut(program, "ball:1")
    reading = lab.encoders().record(program, allow_overtravel=True)
    assert reading.commanded[-1, 0] == pytest.approx(0.150, abs=1e-15)
    with pytest.raises(InputError, match="allow_overtravel"):
        lab.encoders().record(program, allow_overtravel="no")
    # the turning recording as Lab.turn: C turns while X runs out to 120 mm at line 3
    spiral = parse_program("G01 X0 Z0 C0 F100.\nG01 X50. C360.\nG01 X120. C720.\n")
    with pytest.raises(AxisLimitError, match=r"axis X = 120\.000000 mm at line 3 outside "
                                             r"its travel -100\.000000 mm \.\. 100\.000000 mm; "
                                             r"nothing was recorded"):
        lab.encoders().record_turning(spiral)
    with pytest.raises(AxisLimitError, match=r"axis X = 120\.000000 mm at line 3 "):
        lab.turn(spiral)
    assert lab.encoders().record_turning(spiral, allow_overtravel=True).commanded.shape == (
        9, 3)


def test_an_encoder_reading_and_the_encoders_say_what_they_are_with_units():
    """The reading's repr had been the dataclass dump of bare SI arrays (t, commanded,
    position), the lag nowhere; the encoders' a list of resolutions of m and rad mixed,
    [1e-09, 1e-09, 1e-09, 1.7453292519943297e-07]. Now the samples, the time span and each
    axis' peak lag in um or urad; each resolution with its unit. Hand value (docs/lab.md): a
    PD loop of Kp 1.2e6 N/m on a guide of 1600 N s/m lags v c / Kp, X at 3 mm/s 4 um."""
    from machinesim.nc import ProgramBuilder

    slide = AxisServo(kp=1.2e6, ki=0.0, kd=3700.0, mass=12.0, damping=1600.0, name="X")
    lab = machinesim.Lab("grooving_4axis", noise=False, servo=PIDServo((slide, None, None,
                                                                         None)))
    program = ProgramBuilder(1).linear(X=3e-3, feed_mm_per_min=180).build()  # 3 mm/s
    encoders = lab.encoders()
    assert repr(encoders) == ("Encoders(grooving_4axis, resolution X 1e-09 m, Y 1e-09 m, "
                              f"Z 1e-09 m, C {np.radians(1e-5):.6g} rad)")
    assert repr(encoders.record(program)) == (
        "EncoderReading(2 samples of XYZC over 0 .. 1 s; peak following error X "
        f"{3e-3 * 1600 / 1.2e6 * 1e6:.6g} um, Y 0 um, Z 0 um, C 0 urad)")
