"""A lab refuses servo loops that do not fit its machine's axes, when they are given."""

from __future__ import annotations

import numpy as np
import pytest

import machinesim
from machinesim.nc import ProgramBuilder
from machinesim.servo import AxisServo, PIDServo, servo_from_toml, table6_servo

MASS, DAMPING, KP, KD = 12.0, 1600.0, 1.2e6, 3700.0  # a 12 kg slide, about 50 Hz


def _loop(name="axis", ki=7.2e7):
    return AxisServo(kp=KP, ki=ki, kd=KD, mass=MASS, damping=DAMPING, name=name)


def test_wrong_column_count_is_refused_naming_the_machines_axes():
    with pytest.raises(machinesim.InputError) as caught:
        machinesim.Lab("robonano_a0ib", servo=table6_servo("before"))
    message = str(caught.value)
    assert caught.value.key == "servo"
    for part in ("PIDServo with 3 axis columns", "robonano_a0ib", "5 axes are X, Y, Z, B, C",
                 "table6_servo(\"before\", axis_order=('X', 'Y', 'Z', 'B', 'C'))",
                 "PIDServo((x, y, z, b, c))"):
        assert part in message, (part, message)


def test_tune_servo_is_checked_as_the_constructor():
    lab = machinesim.Lab("sts_lathe", noise=False)
    with pytest.raises(machinesim.InputError, match=r"sts_lathe, whose 3 axes are X, Z, C"):
        lab.tune_servo(table6_servo("before", axis_order=("x", "y", "z", "c")))
    assert lab.reveal_servo() is None  # the refused loops were not set


def test_a_servo_handed_to_cut_is_checked():
    lab = machinesim.Lab("grooving_4axis", noise=False)
    with pytest.raises(machinesim.InputError, match=r"grooving_4axis, whose 4 axes"):
        lab.cut(ProgramBuilder(1).linear(X=1e-3, feed_mm_per_min=100).build(),
                servo=PIDServo((_loop("X"), None, None)))


@pytest.mark.parametrize("name", ["Z", "z"])
def test_a_misnamed_column_is_refused(name):
    with pytest.raises(machinesim.InputError) as caught:
        machinesim.Lab("grooving_4axis", servo=PIDServo((_loop("X"), _loop(name), None, None)))
    message = str(caught.value)
    for part in ("column 2 is grooving_4axis's Y axis", "(axes X, Y, Z, C)",
                 f"named {name!r}", "put it in column 3 (Z)"):
        assert part in message, (part, message)


def test_a_name_for_an_axis_the_machine_lacks_is_refused():
    with pytest.raises(machinesim.InputError, match=r"grooving_4axis has no B axis"):
        machinesim.Lab("grooving_4axis", servo=PIDServo((None, None, None, _loop("B"))))


def test_fitting_servos_are_accepted():
    assert machinesim.load_machine("sts_lathe").axes == ("X", "Z", "C")
    for servo in (table6_servo("before"), table6_servo("after", axis_order=("X", "Z", "C"))):
        lab = machinesim.Lab("sts_lathe", servo=servo)
        assert lab.reveal_servo() is servo
    robonano = machinesim.load_machine("robonano_a0ib")
    machinesim.Lab(robonano, servo=table6_servo("before", axis_order=robonano.axes))
    mill = PIDServo((_loop("x"), _loop("Y"), None, None))
    machinesim.Lab("grooving_4axis", servo=mill).tune_servo(mill)
    # names that are not an axis letter are not checked; neither is a servo without axes
    machinesim.Lab("grooving_4axis", servo=PIDServo((_loop(), _loop("slide 2"), None, None)))

    class Lagless:
        def follow(self, t, q):
            return q

    machinesim.Lab("grooving_4axis", servo=Lagless())


def _ramp_error(ki):
    """Following error (m) at the end of a 1 s line, X 3 mm/s and Y 4 mm/s."""
    lab = machinesim.Lab("grooving_4axis", noise=False,
                         servo=PIDServo((_loop("X", ki), _loop("Y", ki), None, None)))
    program = ProgramBuilder(1).linear(X=3e-3, Y=4e-3, feed_mm_per_min=300).build()
    reading = lab.encoders().record(program)
    assert reading.axes == ("X", "Y", "Z", "C")
    assert reading.t[-1] == pytest.approx(1.0)
    # the loops' own error, before the encoders round it to 1 nm
    raw = lab.reveal_servo().following_error(reading.t, reading.commanded)[-1]
    return reading.following_error[-1], reading.peak("X"), raw


def test_a_pid_loop_leaves_no_steady_ramp_error():
    error, peak, raw = _ramp_error(7.2e7)
    assert np.all(np.abs(error) < 1e-9), error
    assert np.all(np.abs(raw) < 1e-12), raw
    assert peak < 1e-9


def test_a_pd_loop_lags_a_ramp_by_v_c_over_kp():
    error, peak, raw = _ramp_error(0.0)
    np.testing.assert_allclose(raw[:2], np.array([3e-3, 4e-3]) * DAMPING / KP, rtol=1e-6)
    # v c / Kp, read to the encoders' 1 nm: 4.000 um on X, 5.333 um on Y
    np.testing.assert_allclose(error[:2], np.array([3e-3, 4e-3]) * DAMPING / KP, atol=1e-9)
    assert error[2:].tolist() == [0.0, 0.0]
    assert peak == pytest.approx(3e-3 * DAMPING / KP, abs=1e-9)


def test_cut_and_turn_called_directly_check_the_servo_as_a_lab_does(tmp_path):
    # machinesim.cut and lathe.turn took any servo: a 3-column PIDServo on the 4-axis mill
    # failed inside the loop with "needs t (N,) and q (N, 3), got (2,) and (2, 4)", and a Z
    # loop in the lathe's X column was turned with, silently
    from machinesim.cutting.lathe import turn

    line = ProgramBuilder(1).rapid(X=1e-3, Y=1e-3, Z=1e-3).linear(
        X=3e-3, feed_mm_per_min=100).build()
    with pytest.raises(machinesim.InputError, match=r"grooving_4axis, whose 4 axes are X, Y, Z, C"):
        machinesim.cut(line, "grooving_4axis", servo=table6_servo("before"))
    face = tmp_path / "face.nc"
    face.write_text("G90 G21\nG00 X0.5 Z0.1 C0\nG01 Z-0.005 F10\nG01 X0 C3600 F7200\nG00 Z1\n")
    with pytest.raises(machinesim.InputError, match=r"sts_lathe, whose 3 axes are X, Z, C"):
        turn(face, "sts_lathe", "nose:0.5:90", servo=table6_servo("before", axis_order="xyzc"))
    z_loop = table6_servo("before").axes[1]
    with pytest.raises(machinesim.InputError, match=r"column 1 is sts_lathe's X axis"):
        turn(face, "sts_lathe", "nose:0.5:90", servo=PIDServo((z_loop, None, None)))


def test_a_servo_file_path_handed_to_a_lab_names_the_reader(tmp_path):
    with pytest.raises(machinesim.InputError, match=r"got str: a servo file is read with "
                       r"machinesim\.servo\.servo_from_toml\(path, machine\)"):
        machinesim.Lab("sts_lathe", servo=str(tmp_path / "servo.toml"))


@pytest.mark.parametrize("column", [1, "x", table6_servo("before")])
def test_a_column_that_is_no_axis_loop_is_refused_when_the_servo_is_made(column):
    # PIDServo((1, None, None, None)) was made; its repr and its first cut raised
    # AttributeError "'int' object has no attribute 'summary'" (or 'reach'), naming no column
    with pytest.raises(machinesim.InputError) as caught:
        PIDServo((None, column, None, None))
    assert str(caught.value).startswith(
        f"key 'axes': column 2: expected an AxisServo or None (the axis follows exactly), "
        f"got {type(column).__name__} ")
    with pytest.raises(machinesim.InputError, match=r"key 'axes': Expected the axis columns "
                                                    r"as a tuple.*got AxisServo"):
        PIDServo(_loop())
    listed = PIDServo([_loop("X"), None, None, None])  # a list is taken, kept as a tuple
    assert isinstance(listed.axes, tuple) and listed.axes[0].name == "X"


def test_a_servo_file_is_read_for_a_machine_given_by_name(tmp_path):
    # servo_from_toml(path, "grooving_4axis") raised AttributeError "'str' object has no
    # attribute 'axes'", where Lab, cut and the instruments take a shipped machine's name
    path = tmp_path / "servo.toml"
    path.write_text("[Y]\nkp_N_per_m = 1.2e6\nki_N_per_m_s = 0.0\nkd_N_s_per_m = 3700.0\n"
                    "mass_kg = 12.0\ndamping_N_s_per_m = 1600.0\n")
    by_name = servo_from_toml(path, "grooving_4axis")
    assert by_name == servo_from_toml(path, machinesim.load_machine("grooving_4axis"))
    assert [a is None for a in by_name.axes] == [True, False, True, True]
    assert by_name.axes[1].kp == 1.2e6 and by_name.axes[1].mass == 12.0
