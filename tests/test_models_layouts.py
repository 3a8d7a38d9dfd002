"""Machine layouts a URDF may describe: table and tool mount on the links their axes move,
a table off the workpiece's side refused, a gantry's or rotary table's bed, a visual's
unnamed material, rotary limits that read as degrees, a C centre line off the workpiece
origin, and an axis frame turned about its own direction."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from models_helpers import GROOVING, ROOT, _in_joint, _line

from machinesim.exceptions import MachineSimWarning, ModelError
from machinesim.machines import load_machine


def test_table_and_tool_mount_may_be_the_links_their_axes_move(tmp_path):
    # docs/machines.md said all four frames hang on fixed joints; only workpiece and
    # tool_tip must (their setting errors are inserted there). mill3 with X's child the table
    # and Z's the tool_mount moves as mill3 with both on fixed joints of zero origin: the
    # same poses under errors of every family (a second chain, compared to the last bit)
    from machinesim.sampling import random_axis_values, random_errors

    text = (ROOT / "models" / "examples" / "mill3.urdf").read_text()
    moves = {'xyz="0 0 0.05"': 'xyz="0 0 0.07"', 'xyz="0 0 0.02"': 'xyz="0 0 0"',
             'xyz="0 0 0.3"': 'xyz="0 0 0.195"', 'xyz="0 0 -0.105"': 'xyz="0 0 0"'}
    for old, new in moves.items():
        assert text.count(old) == 1
        text = text.replace(old, new)
    fixed = tmp_path / "fixed.urdf"
    fixed.write_text(text)
    for carriage, frame in (("x_carriage", "table"), ("z_carriage", "tool_mount")):
        start = text.index(f'<joint name="{frame}_fixed"')
        text = (text[:start] + text[text.index("</joint>", start) + len("</joint>"):]) \
            .replace(f'<link name="{carriage}"/>', "") \
            .replace(f'<child link="{carriage}"/>', f'<child link="{frame}"/>')
    moved = tmp_path / "moved.urdf"
    moved.write_text(text)
    a, b = load_machine(fixed), load_machine(moved)
    assert "carriage" not in text.replace('"y_carriage"', "")
    rng = np.random.default_rng(0)
    errors = random_errors(a, rng)
    for q in random_axis_values(a, rng, 20):
        for frame in ("tool_tip", "table", "tool_mount"):
            np.testing.assert_array_equal(b.frame_pose(frame, q, errors),
                                          a.frame_pose(frame, q, errors))


MILL3 = (ROOT / "models" / "examples" / "mill3.urdf").read_text()
_MILL3_TABLE = ('  <joint name="table_fixed" type="fixed">\n'
                '    <parent link="x_carriage"/><child link="table"/>\n'
                '    <origin xyz="0 0 0.02" rpy="0 0 0"/>\n'
                '  </joint>\n'
                '  <joint name="workpiece_fixed" type="fixed">\n'
                '    <parent link="table"/><child link="workpiece"/>\n'
                '    <origin xyz="0 0 0.005" rpy="0 0 0"/>\n'
                '  </joint>\n')


def _mill3_table_on(parent: str, z: str) -> str:
    """mill3 with the workpiece on the X carriage and the table a fixed child of ``parent``
    at ``z`` (m) above it."""
    assert MILL3.count(_MILL3_TABLE) == 1
    return MILL3.replace(_MILL3_TABLE, _MILL3_TABLE.replace(
        '<parent link="x_carriage"/><child link="table"/>',
        f'<parent link="{parent}"/><child link="table"/>').replace(
        'xyz="0 0 0.02"', f'xyz="0 0 {z}"').replace(
        '<parent link="table"/><child link="workpiece"/>',
        '<parent link="x_carriage"/><child link="workpiece"/>').replace(
        'xyz="0 0 0.005"', 'xyz="0 0 0.025"'))


@pytest.mark.parametrize(("case", "text", "words"), [
    # the names of table and tool_mount swapped: the table is the Z carriage's
    ("swapped", MILL3.replace('"table"', '"t"').replace('"tool_mount"', '"table"')
     .replace('"t"', '"tool_mount"'),
     "link 'table' is moved by axis joint(s) Z, which do not move the workpiece; expected "
     "the table on the workpiece's side"),
    ("on_the_tool_side", _mill3_table_on("z_carriage", "-0.1"),
     "link 'table' is moved by axis joint(s) Z, which do not move the workpiece"),
    # on the bed, under the workpiece that Y and X move
    ("on_the_bed", _mill3_table_on("base", "0.1"),
     "link 'table' is not moved by linear axis joint(s) X, Y, which move the workpiece"),
])
def test_a_table_off_the_workpiece_side_is_refused_naming_its_line(case, text, words,
                                                                    tmp_path):
    # The last two loaded without a word, the tool where mill3 puts it, and the laser
    # interferometer, which reads the tool's motion relative to the table, read X's 10 mm
    # stroke as a -10 mm error (0 on mill3); the first was refused as tool_tip not held by
    # tool_mount, naming neither the table nor a line
    path = tmp_path / f"{case}.urdf"
    path.write_text(text)
    with pytest.raises(ModelError) as raised:
        load_machine(path)
    line = _line(text, '<link name="table"')
    assert str(raised.value).startswith(f"{path}, line {line}: {words}"), str(raised.value)


def test_a_visual_whose_material_has_an_empty_name_loads_with_its_visual(tmp_path):
    # the URDF parser drops a visual whose <material> has no name attribute (refused), but
    # reads name="" and keeps the visual: 8 visuals as the shipped file (had been refused)
    import pinocchio as pin

    text = GROOVING.replace('<material name="bed"/>', '<material name=""/>', 1)
    path = tmp_path / "empty_material_name.urdf"
    path.write_text(text)
    machine = load_machine(path)
    visuals = [pin.buildGeomFromUrdfString(machine.model, urdf, pin.GeometryType.VISUAL)
               for urdf in (text, GROOVING)]
    assert [len(v.geometryObjects) for v in visuals] == [8, 8]


def test_a_table_on_the_bed_of_a_gantry_or_under_its_rotary_table_loads(tmp_path):
    # The check refuses a table that does not move with the workpiece, not a table on the
    # stem of a machine whose axes all move the tool: there the laser interferometer reads
    # X's stroke exactly (the nominal machine, no noise), as on mill3
    from machinesim.metrology import LaserInterferometer

    gantry = MILL3.replace(_MILL3_TABLE, (
        '  <joint name="table_fixed" type="fixed">\n'
        '    <parent link="base"/><child link="table"/>\n'
        '    <origin xyz="0 0 0.17" rpy="0 0 0"/>\n  </joint>\n'
        + _MILL3_TABLE[_MILL3_TABLE.index('  <joint name="workpiece_fixed"'):]))
    for old, new in (('<parent link="base"/><child link="y_carriage"/>',
                      '<parent link="table"/><child link="y_carriage"/>'),
                     ('xyz="0 0 0.1"', 'xyz="0 0 0"'),
                     ('<axis xyz="0 -1 0"/>', '<axis xyz="0 1 0"/>'),  # now on the tool side
                     ('xyz="0 0 0.05"', 'xyz="0 0 0"'),
                     ('<axis xyz="-1 0 0"/>', '<axis xyz="1 0 0"/>'),
                     ('<parent link="base"/><child link="z_carriage"/>',
                      '<parent link="x_carriage"/><child link="z_carriage"/>'),
                     ('xyz="0 0 0.3"', 'xyz="0 0 0.13"')):
        assert gantry.count(old) == 1, old
        gantry = gantry.replace(old, new)
    path = tmp_path / "gantry.urdf"
    path.write_text(gantry)
    stroke = np.array([0.0, 0.01, 0.02])
    for machine in (load_machine(path), load_machine(ROOT / "models/examples/mill3.urdf")):
        reading = LaserInterferometer(machine, noise=False).positioning("X", stroke)
        np.testing.assert_allclose(reading.deviation, 0.0, rtol=0, atol=1e-15)
    # grooving_4axis with its C table turning above the table rather than turning it: the
    # same tool poses (the C axis line is the same vertical)
    under = GROOVING
    for old, new in (('<parent link="y_carriage"/><child link="c_table"/>',
                      '<parent link="table"/><child link="c_table"/>'),
                     ('<parent link="c_table"/><child link="table"/>',
                      '<parent link="y_carriage"/><child link="table"/>'),
                     ('<parent link="table"/><child link="workpiece"/>',
                      '<parent link="c_table"/><child link="workpiece"/>')):
        assert under.count(old) == 1, old
        under = under.replace(old, new)
    path = tmp_path / "c_above_table.urdf"
    path.write_text(under)
    machine, shipped = load_machine(path), load_machine("grooving_4axis")
    q = np.random.default_rng(0).uniform(shipped.lower, shipped.upper, (5, 4))
    np.testing.assert_allclose(machine.tool_pose(q), shipped.tool_pose(q), rtol=0, atol=1e-15)


C_LIMIT = 'lower="-6.283185307179586" upper="6.283185307179586"'


def _c_limits(tmp_path, lower: str, upper: str) -> Path:
    path = tmp_path / f"c_{lower}_{upper}.urdf"
    path.write_text(_in_joint("C", C_LIMIT, f'lower="{lower}" upper="{upper}"'))
    return path


def test_rotary_limits_that_read_as_degrees_warn_naming_the_joint(tmp_path):
    # written in degrees, C -100 .. 100 loaded as +-16 turns (its travel check never fired)
    # and C -360 .. 360 as a work spindle (past 100 rad), so a program turning C while it
    # fed was refused; both loaded without a word
    # the <limit>'s own line (it had been its joint's)
    line = GROOVING[:GROOVING.index('<limit', GROOVING.index('<joint name="C"'))].count("\n") + 1
    advice = ("and the velocity in rad/s; an axis that turns without end is written with wide "
              "limits (sts_lathe's C: -1e5 .. 1e5 rad)")
    for degrees, turns, spindle in ((100, 15.9, ""), (360, 57.3, (
            ", past 100 rad: a work spindle, which a program may not turn while it feeds"))):
        path = _c_limits(tmp_path, f"-{degrees}", f"{degrees}")
        with pytest.warns(MachineSimWarning) as caught:
            machine = load_machine(path)
        rad = degrees * np.pi / 180.0  # what the user meant, by hand
        assert [str(w.message) for w in caught] == [
            f"{path}, line {line}: joint 'C': <limit lower={-float(degrees)!r} "
            f"upper={float(degrees)!r}> is read in rad, as URDF limits are: -{turns} .. "
            f"{turns} turns{spindle}. If these are degrees, write lower=\"{-rad!r}\" "
            f"upper=\"{rad!r}\" (-{degrees} .. {degrees} deg), {advice}"]
        assert machine.axis("C").upper == degrees  # loaded as written: a warning, not a refusal
        assert machine.axis("C").spindle == bool(spindle)


def test_rotary_limits_of_a_turn_a_tilt_or_a_spindle_load_without_a_warning(tmp_path):
    # one turn (as the shipped tables, or 2 pi rounded up), a tilt, a spindle of 1e5 rad; and
    # 1e4 rad, which read as degrees is a spindle too (past 100 rad)
    paths = [_c_limits(tmp_path, lower, upper) for lower, upper in (
        ("-6.2832", "6.2832"), ("-0.7853981633974483", "1.5"), ("-1e5", "1e5"),
        ("-1e4", "1e4"))]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for path in paths:
            load_machine(path)
    # a table of two turns each side is a machine too: it loads, with the warning
    with pytest.warns(MachineSimWarning, match=r"-2 .. 2 turns"):
        machine = load_machine(_c_limits(tmp_path, "-12.566370614359172", "12.566370614359172"))
    assert machine.axis("C").upper == 4 * np.pi


def test_a_c_centre_line_off_the_workpiece_origin_moves_as_written(tmp_path):
    # docs/machines.md, Conventions: not checked on a machine of one's own. The workpiece
    # origin W = (10, 0) mm from the C line, X's origin with it (the edge at W at zero). C
    # turns the table by -C about +Z (ISO 841), so the edge at (10 + X, Y) from the line is
    # at Rz(C) (10 + X, Y) - W in the workpiece frame: (-10, 10) mm at C = 90 deg, X = Y = 0;
    # (1, 0) mm needs (-Y - 10, 10 + X) = (1, 0): X = -10 mm, Y = -11 mm
    text = _in_joint("X", '<origin xyz="0.0 0.4 0.55"', '<origin xyz="0.01 0.4 0.55"')
    old = '<child link="workpiece"/>\n    <origin xyz="0.0 0.0 0.005"'
    assert text.count(old) == 1
    path = tmp_path / "off_centre.urdf"
    path.write_text(text.replace(old, old.replace("0.0 0.0 0.005", "0.01 0.0 0.005")))
    machine = load_machine(path)
    turned = np.array([0.0, 0.0, 0.0, np.pi / 2])
    pose = machine.tool_pose(turned)
    np.testing.assert_allclose(pose[:3, 3], [-0.010, 0.010, 0.0], rtol=0, atol=1e-15)
    pose[:3, 3] = [0.001, 0.0, 0.0]
    solution = machine.axis_values(pose)
    # Newton steps to round-off (1e-17 m measured): 1e-15 m is a millionth of the 1 nm step
    np.testing.assert_allclose(solution.q, [-0.010, -0.011, 0.0, np.pi / 2], rtol=0,
                               atol=1e-15)


def test_an_axis_frame_turned_about_its_own_direction_is_refused_a_turned_machine_is_not(
        tmp_path):
    """An axis's errors enter in its joint frame. C's frame turned 30 deg about Z, the table
    turned back: C turns about Z as before and the edge sits at the origin, but EX0C (C's
    line off in X) moved it 30 deg off X. The whole machine turned under a root link (a CAD
    export's Y-up world) keeps every frame parallel to the workpiece: it loads, and X's
    straightness in Y moves the tool along the workpiece's Y by the table's value."""
    from machinesim.errors import ErrorModel

    turned = tmp_path / "c_turned.urdf"
    turned.write_text(
        _in_joint("C", 'rpy="0.0 0.0 0.0"', 'rpy="0.0 0.0 0.5235987755982988"').replace(
            '<origin xyz="0.0 0.0 0.055" rpy="0.0 0.0 0.0"/>',
            '<origin xyz="0.0 0.0 0.055" rpy="0.0 0.0 -0.5235987755982988"/>'))
    with pytest.raises(ModelError) as raised:
        load_machine(turned)
    assert str(raised.value).startswith(  # grooving_4axis.urdf: joint C opens line 43
        f"{turned}, line 43: joint 'C': its frame is turned 30 deg relative to the workpiece")
    root = tmp_path / "y_up_world.urdf"
    root.write_text(GROOVING.replace(
        '<link name="base">',
        '<link name="world"/><joint name="to_z_up" type="fixed"><parent link="world"/>'
        '<child link="base"/><origin xyz="0.0 0.0 0.0" rpy="1.5707963267948966 0.0 0.0"/>'
        '</joint><link name="base">'))
    machine = load_machine(root)
    errors = ErrorModel.from_dict({"component": {"X": {"position_mm": [-250.0, 0.0, 250.0],
                                                       "EYX_um": [-2.0, 0.0, 2.0]}}})
    q = np.array([0.125, 0.0, 0.0, 0.0])  # X Y Z C: EYX = 1 um at X = 125 mm
    moved = machine.tool_pose(q, errors)[:3, 3] - machine.tool_pose(q)[:3, 3]
    np.testing.assert_allclose(moved, [0.0, 1e-6, 0.0], rtol=0, atol=1e-15)
