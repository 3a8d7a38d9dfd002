"""The predicted form error's "tool" share (`sts_prediction.predict`, summary.json's
``predicted_tool_pv_nm``, Fig. 16's tool bar) derived by hand for a tool set off the spindle
axis by dx on paper 004's sine grid (eqs 2 and 12)."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

import machinesim.cam.spiral as sp
from machinesim.exceptions import InputError
from machinesim.machines import load_machine
from machinesim.metrology.encoders import EncoderReading
from machinesim.procedures.sts_plans import MEASURE_LINE
from machinesim.procedures.sts_prediction import predict

A, WAVELENGTH, NOSE = 50e-9, 100e-6, 1e-3


def test_the_tool_share_of_a_radial_offset_is_the_tilt_free_pv_of_the_shifted_grid():
    # Along theta = 0 the grid of eq 2 is z = A sin(k rho) + A; a tip dx off the axis cuts
    # the design's profile at rho - dx (eq 12's exact form), leaving
    #   z(rho - dx) - z(rho) = B cos(k rho + psi0),  B = 2 A sin(-k dx / 2), psi0 = -k dx / 2.
    # The profile is fitted over piston and tilt across MEASURE_LINE, r 150 .. 350 um: two
    # whole wavelengths about c = 250 um, over which the cosine's mean is 0 but its
    # first moment is not: with u = rho - c, L = 200 um, psi = k c + psi0,
    #   int u cos(k u + psi) du = -sin(psi) int u sin(k u) du = sin(psi) L / k  (k L / 2 = 2 pi)
    # over int u^2 du = L^3 / 12, so the tilt is 12 B sin(psi) / (k L^2). Its P-V, read on a
    # dense u, is the figure; the predicted share fits the 401 samples of the line instead.
    dx = -3.5e-6  # Table 5 "before"
    k = 2.0 * math.pi / WAVELENGTH
    b = 2.0 * A * math.sin(-k * dx / 2.0)
    (start, _), (end, _), _ = MEASURE_LINE
    length, centre = end - start, (start + end) / 2.0
    psi = k * centre - k * dx / 2.0
    u = np.linspace(-length / 2.0, length / 2.0, 2_000_001)
    by_hand = np.ptp(b * np.cos(k * u + psi) - 12.0 * b * math.sin(psi) * u / (k * length ** 2))
    assert by_hand == pytest.approx(22.733e-9, rel=1e-4, abs=0.0)  # not 2 B = 21.95 nm: the tilt
    # eq 12's first order, -dx tan(phi), has the amplitude |dx| A k for B
    assert abs(dx) * A * k == pytest.approx(b, rel=3e-3, abs=0.0)

    # the share as the procedure predicts it: the known tool (dx alone, no nose radius left
    # uncompensated), a program over the line, followed exactly
    spiral = sp.Spiral(0.4e-3, 2e-6)
    path = sp.tool_path(sp.cutting_points(sp.sine_grid(), spiral,
                                          sp.constant_angle(spiral, 0.05)), NOSE)
    machine = load_machine("sts_lathe")
    q = np.zeros((len(path.c), len(machine.axes)))
    for axis, values in (("X", path.x), ("Z", path.z), ("C", path.c)):
        q[:, machine.axes.index(axis)] = values
    recording = EncoderReading(tuple(machine.axes), np.arange(len(q), dtype=float), q, q,
                               machine=machine.name)
    known = SimpleNamespace(dx=dx, dy=0.0, d_radius=0.0)
    prediction = predict(machine, sp.sine_grid(), recording, known, NOSE, NOSE)
    # 401 samples of the line for the dense u: 0.03 % apart
    assert prediction.tool == pytest.approx(by_hand, rel=1e-3, abs=0.0)
    assert prediction.servo == 0.0  # followed exactly


@pytest.mark.parametrize("taken_on", [("robonano_a0ib", "XYZBC"), ("other_lathe", "XZC")])
def test_a_recording_of_another_machine_is_refused(taken_on):
    # a recording's columns are its machine's axes: another machine's, even with the same
    # letters, would be read as this lathe's X, Z and C
    name, axes = taken_on
    machine = load_machine("sts_lathe")
    q = np.zeros((3, len(axes)))
    recording = EncoderReading(tuple(axes), np.arange(3.0), q, q, machine=name)
    known = SimpleNamespace(dx=0.0, dy=0.0, d_radius=0.0)
    with pytest.raises(InputError, match=f"recording is of {name} .*not of sts_lathe"):
        predict(machine, sp.sine_grid(), recording, known, NOSE, NOSE)
