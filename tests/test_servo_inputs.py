"""Bad input to the servo loops and the STS designs is refused, naming the value."""

from __future__ import annotations

import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.servo import table6_servo


def test_a_servo_refuses_commands_that_are_not_finite():
    servo = table6_servo("before")
    t = np.linspace(0.0, 0.01, 50)
    q = np.zeros((50, 3))
    assert np.all(servo.follow(t, q) == 0.0)  # at rest it stays at rest
    q[20, 1] = np.nan
    with pytest.raises(InputError, match=r"q at sample 20 holds .*nan.* expected finite"):
        servo.follow(t, q)
    t[3] = np.inf
    with pytest.raises(InputError, match=r"t at sample 3 holds .*inf.*"):
        servo.follow(t, np.zeros((50, 3)))


@pytest.mark.parametrize("wavelength", [1e-300, 1e-10, 0.0, -1e-4])
def test_a_sine_grid_refuses_a_wavelength_below_a_nanometre(wavelength):
    from machinesim.cam.designs import MIN_WAVELENGTH_M, sine_grid

    assert MIN_WAVELENGTH_M == 1e-9
    with pytest.raises(InputError, match="wavelength"):
        sine_grid(wavelength=wavelength)
    with pytest.raises(InputError, match="wavelength_y"):
        sine_grid(wavelength_y=wavelength)
    design = sine_grid(amplitude=50e-9, wavelength=1e-9)  # the shortest taken
    assert design.height(np.array([0.25e-9]), np.array([0.0]))[0] == pytest.approx(100e-9)
