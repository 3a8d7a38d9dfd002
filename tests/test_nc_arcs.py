"""Arcs whose end is nearly their start: read as written, with a warning naming each.

`G02 X5.0005 Y5. I2.` from X5 Y5 had been read as an arc 0.5 um long, silently, where the
program most likely meant a full circle (end = start) and its end carries a rounding: the
end lies within the radius tolerance (3 um; 7.5 um under G20) that a post's rounding leaves
on an arc. No FANUC rule for such an end was found, so the reader warns
(`machinesim.nc.arcs.near_circle_warning`) and reads the arc as written.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from machinesim.exceptions import MachineSimWarning
from machinesim.nc import parse_program

START = "G90 G21 G17\nG00 X5. Y5. Z0\n"
MM = 1e-3


def _read(text: str, **options):
    """The program and the MachineSimWarnings reading it raised."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        program = parse_program(text, "prog.nc", **options)
    return program, [str(w.message) for w in caught if issubclass(w.category,
                                                                  MachineSimWarning)]


@pytest.mark.parametrize(("block", "length_um", "sweep_deg"), [
    # the end on the start's ray from the centre (7, 5), 0.5 um nearer: no turn at all, the
    # radius going from 2 to 1.9995 mm, a path of 0.5 um
    ("G02 X5.0005 Y5. I2.", 0.5, 0.0),
    # 0.5 um along the circle, clockwise: atan(0.0005 / 2) = 0.01432 deg, 2 mm x that angle
    # = 0.5 um
    ("G02 X5. Y5.0005 I2.", 0.5, 0.0143),
])
def test_an_arc_ending_within_the_tolerance_of_its_start_warns_and_reads_as_written(
        block, length_um, sweep_deg):
    for fast in (True, False):
        program, found = _read(START + f"N10 {block} F100.\nM30\n", fast=fast)
        assert found == [
            "prog.nc: 1 arc with I J K whose end is within 3 um of its start but not on it "
            "(within the rounding a post leaves on an arc's radius), read as written, a short "
            f"arc, where a full circle was most likely meant: G02 at line 3: {length_um:g} um "
            f"long ({sweep_deg:g} deg), its end 0.5 um from its start. For a full circle "
            "write the end as the start (or leave out its axis words)"]
        # as written: the end reached, along a path as long as the message says
        end = [float(w[1:]) * MM for w in block.split()[1:3]]
        assert program.targets[-1, :2].tolist() == end
        path = np.diff(program.targets[:, :2], axis=0)
        assert np.hypot(path[:, 0], path[:, 1]).sum() == pytest.approx(length_um * 1e-6,
                                                                       rel=1e-3)


@pytest.mark.parametrize("block", [
    "G02 X5. Y5. I2.",        # end = start: a full circle
    "G02 I2.",                # no axis words: end = start
    "G02 X5. Y4.9995 I2.",    # the end on the other side: read as 359.99 deg, near the circle
    "G02 X5. Y5.004 I2.",     # 4 um from the start: beyond the tolerance, an arc meant short
    "G02 X5. Y5.0005 R2.",    # R gives the short arc explicitly (an end = start is refused)
    "G02 X9. Y5. I2.",        # an ordinary half circle
])
def test_arcs_meant_as_written_read_without_a_warning(block):
    program, found = _read(START + f"{block} F100.\nM30\n")
    assert found == []
    if "Y4.9995" in block:  # the whole circle, 2 pi x 2 mm, but the 0.5 um it leaves out
        path = np.diff(program.targets[:, :2], axis=0)
        # (the chords, within 1 nm of the arc, are shorter than it by far less than 0.5 um)
        assert np.hypot(path[:, 0], path[:, 1]).sum() == pytest.approx(
            4 * math.pi * MM - 0.5e-6, rel=1e-6)


def test_under_g20_the_inch_tolerance_holds():
    # X5.0002 inch is 5.08 um from the start: within the 7.5 um of an inch program
    _, found = _read("G90 G20 G17\nG00 X5. Y5. Z0\nG03 X5.0002 Y5. I0.1 F10.\nM30\n")
    assert len(found) == 1
    assert "within 7.5 um of its start" in found[0]
    assert "G03 at line 3: 5.08 um long (0 deg), its end 5.08 um from its start" in found[0]


def test_many_such_arcs_make_one_warning_listing_the_first_and_counting_the_rest():
    # seven in the main program, one in a subprogram run three times (one line: listed once)
    arcs = "".join("G02 X5.0005 Y5. I2.\nG00 X5. Y5.\n" for _ in range(7))
    text = (START + "F100.\n" + arcs + "M98 P100 L3\nM30\n"
            "O100\nG00 X5. Y5.\nG02 X5.0005 Y5. I2.\nM99\n")
    _, found = _read(text)
    assert len(found) == 1
    assert found[0].startswith("prog.nc: 8 arcs with I J K whose end is within 3 um")
    listed = [f"G02 at line {4 + 2 * k}: 0.5 um long" for k in range(5)]
    assert all(item in found[0] for item in listed)
    assert "line 14:" not in found[0] and "; and 3 more. For a full circle" in found[0]
