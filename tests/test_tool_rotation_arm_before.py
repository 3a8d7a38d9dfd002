"""Paper 000's uncompensated ("before") pattern where it is no pattern to read: an edge
offset within the capture that lifts the edge off the block at the larger angles, or deepens
the grooves faster than their 20 um pitch holds. The figures are n/a, and the note says why
by the identified arm (`unread_before`), not only what the section's fit found."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim import ErrorModel, Lab, load_machine
from machinesim.exceptions import InputError
from machinesim.experiment import run
from machinesim.identification.tool_rotation_arm import ArmEstimate, arm_radius
from machinesim.metrology import Microscope
from machinesim.procedures.tool_rotation_arm import (
    TOOL,
    ToolRotationArm,
    compensate_program,
    measure_pattern,
)
from machinesim.procedures.tool_rotation_arm_reading import unread_before

UM = 1e-6
MACHINE = load_machine("planer_4axis")
R0 = arm_radius(MACHINE)
PATTERN = ToolRotationArm().pattern


def before_part(rho, e_ys):
    """The uncompensated pattern cut with the edge offset (r - r0, e_ys) = (rho, e_ys),
    touched off at 0 deg exactly."""
    touched = ArmEstimate(r0=R0, r=R0, e_ys=0.0, z_offset=-rho, y_offset=e_ys)
    program = compensate_program(PATTERN.program(R0), MACHINE, touched)
    errors = ErrorModel().with_parameters({"tool.y": e_ys, "tool.z": -rho})
    lab = Lab(MACHINE, errors, noise=False)
    part, _ = lab.cut(program, TOOL, PATTERN.stock)
    return part


def test_grooves_the_edge_stays_above_are_named_with_the_offset():
    """e_ys = +500 um, r - r0 = 55 um: by eq 1 the edge rises 55 (1 - cos t) + 500 sin t off
    0 deg, 8.734 um at 1 deg (a groove 1.266 um deep, below the 2 um an apex must rise) and
    17.46 um at 2 deg (above the block's top: not cut), 174.33 um at 20 deg."""
    rho, e_ys = 55 * UM, 500 * UM
    rise = [rho * (1 - math.cos(math.radians(t))) + e_ys * math.sin(math.radians(t))
            for t in (1, 2, 20)]
    assert 10 * UM - rise[0] == pytest.approx(1.266 * UM, abs=1e-9) and rise[1] > 10 * UM
    why = unread_before(ArmEstimate(r0=R0, r=R0 + rho, e_ys=e_ys), PATTERN)
    assert why.startswith("by the identified arm (r - r0 = 55.00 um, e_ys = 500.00 um) the "
                          f"uncompensated grooves run 10.00 to {(10 * UM - rise[2]) / UM:.2f}")
    assert "the edge stays above the block's top at 2 to 20 deg (not cut)" in why
    assert "the grooves at 1 deg are less than the 2 um deep an apex must rise" in why
    assert "neighbours" not in why  # the 0-1 deg pair is the shallow groove's, said once
    with pytest.raises(InputError, match="Expected 21 groove apexes in the profile, found 1 "):
        measure_pattern(before_part(rho, e_ys), PATTERN, Microscope(noise=False))


def test_grooves_deepening_faster_than_the_pitch_holds_are_named():
    """e_ys = -600 um: the grooves deepen by about 9.6 um a degree near 20 deg while the next
    one's flank towards them rises 20 um x tan 26 deg a pitch. By hand, the 18 and 19 deg
    grooves' surface (the lower of the two V's, read every 1 nm between their apexes) rises
    1.76 um over the shallower apex, under the 2 um the reading needs: it finds 18 apexes."""
    rho, e_ys = 55 * UM, -600 * UM
    t = np.radians([18.0, 19.0])
    depth = 10 * UM - (rho * (1 - np.cos(t)) + e_ys * np.sin(t))
    y = PATTERN.centres[18:20] + rho * np.sin(t) + e_ys * (np.cos(t) - 1)
    s = np.arange(y[0], y[1], 1e-9)
    surface = np.minimum(-depth[0] + np.tan(math.pi / 4 + t[0]) * (s - y[0]),
                         -depth[1] + np.tan(math.pi / 4 - t[1]) * (y[1] - s))
    ridge = surface.max() + depth.min()
    assert ridge == pytest.approx(1.76 * UM, abs=0.005 * UM)
    why = unread_before(ArmEstimate(r0=R0, r=R0 + rho, e_ys=e_ys), PATTERN)
    assert ("first the 18 and 19 deg grooves, "
            f"{depth[0] / UM:.2f} and {depth[1] / UM:.2f} um deep and {(y[1] - y[0]) / UM:.2f} "
            f"um apart: their flanks cross {ridge / UM:.2f} um over the shallower apex") in why
    assert "(2 of 20 pairs)" in why and "not cut" not in why
    with pytest.raises(InputError, match="Expected 21 groove apexes in the profile, found 18 "):
        measure_pattern(before_part(rho, e_ys), PATTERN, Microscope(noise=False))


@pytest.mark.parametrize("rho, e_ys", [(55 * UM, -178 * UM), (0.0, 0.0), (350 * UM, -350 * UM)])
def test_a_readable_before_pattern_has_no_reason(rho, e_ys):
    """The paper's offset, none, and (350, -350) um deepening the grooves to 108.6 um: read, and
    unread_before finds nothing against them (of 828 offsets within 1 and 2.848 mm
    captures, it named a reason for no pattern that was read, and for all but 3 of 463 that
    were not, docs/procedures/tool_rotation_arm.md)."""
    assert unread_before(ArmEstimate(r0=R0, r=R0 + rho, e_ys=e_ys), PATTERN) is None
    reading = measure_pattern(before_part(rho, e_ys), PATTERN, Microscope(noise=False))
    assert len(reading.depth) == 21


def test_the_reason_reaches_the_figures_note():
    """--e-ys-um 500: the figures said only 'key 'count': Expected 21 groove apexes in the
    profile, found 1 (prominence 2e-06 m)'; now also the identified offset and the grooves
    not cut."""
    errors = ErrorModel().with_parameters({"tool.y": 500 * UM, "tool.z": -55 * UM})
    result = run(ToolRotationArm(), Lab(MACHINE, errors, noise=False))
    why = result.evaluation.details["pattern_before"]["why"]
    assert why.startswith("key 'count': Expected 21 groove apexes in the profile, found 1 "
                          "(prominence 2e-06 m) (by the identified arm (r - r0 = 55.00 um, "
                          "e_ys = 500.00 um)")
    assert "the edge stays above the block's top at 2 to 20 deg (not cut)" in why
    for figure in result.figures:
        assert figure.before is None and f"before not measured, the uncompensated pattern: " \
            f"{why}" in figure.note
