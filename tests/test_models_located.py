"""Hostile URDFs are ModelErrors located at their file, line, joint or link: the
HOSTILE_URDFS cases, namespaced extensions that still load, the line of the joint, link or
axis element at fault, more links than a machine has, elements given twice, and joint
line counts not misled by elements beside the joints."""

from __future__ import annotations

import numpy as np
import pytest
from models_helpers import GROOVING, HOSTILE_URDFS, X_LIMIT, _in_joint, _line

from machinesim.exceptions import ModelError
from machinesim.machines import load_machine


@pytest.mark.parametrize("case", sorted(HOSTILE_URDFS))
def test_a_hostile_urdf_is_a_located_model_error(case, tmp_path):
    text, words = HOSTILE_URDFS[case]
    assert text != GROOVING
    path = tmp_path / f"{case}.urdf"
    path.write_bytes(text.encode("utf-8", "surrogateescape"))  # a case's non-UTF-8 bytes too
    with pytest.raises(ModelError) as raised:
        load_machine(path)
    message = str(raised.value)
    assert message.startswith(str(path)), message
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"


def test_namespaced_extensions_urdf_ignores_still_load(tmp_path):
    # a Gazebo extension's prefixed plugin elements (neither reader reads a <gazebo>),
    # xml:lang, and machinesim's own elements load as the plain file does
    text = (GROOVING.replace('<robot ', '<robot xmlns:sensor="urn:gz#sensor" ', 1)
            .replace('<link name="base">', '<gazebo reference="base"><sensor:camera '
                     'sensor:name="c" xmlns="urn:gz"/></gazebo>\n  <link name="base" '
                     'xml:lang="en">', 1))
    path = tmp_path / "extended.urdf"
    path.write_text(text)
    plain = tmp_path / "plain.urdf"
    plain.write_text(GROOVING)
    machine, reference = load_machine(path), load_machine(plain)
    assert machine.axes == reference.axes
    assert np.array_equal(machine.tool_pose(machine.home), reference.tool_pose(reference.home))


# A CAD export's <transmission> names joint X too, and comes before the joints: the line
# is that of the robot's own <joint name="X">
_TRANSMISSION = ('<transmission name="t"><type>SimpleTransmission</type>\n'
                 '<joint name="X"><hardwareInterface>E</hardwareInterface></joint>\n'
                 '</transmission>\n')
LINED = GROOVING.replace('<link name="base">', _TRANSMISSION + '<link name="base">', 1)
_LINED_X_ALONG_Y = HOSTILE_URDFS["x_moves_along_y"][0].replace(
    '<link name="base">', _TRANSMISSION + '<link name="base">', 1)
_LINED_X_TURNED = HOSTILE_URDFS["x_frame_turned_about_x"][0].replace(
    '<link name="base">', _TRANSMISSION + '<link name="base">', 1)


def _in_lined_joint(name: str, old: str, new: str) -> str:
    """LINED with ``old`` replaced by ``new`` inside the robot's joint ``name`` only."""
    start = LINED.index(f'<joint name="{name}" type')
    end = LINED.index("</joint>", start)
    assert old in LINED[start:end], f"{old!r} is not in joint {name}"
    return LINED[:start] + LINED[start:end].replace(old, new, 1) + LINED[end:]


@pytest.mark.parametrize(("case", "text", "needle", "occurrence", "words"), [
    # an element of a joint is named at its own line (it had been its joint's): the <limit>
    # (since 3d65c24 the <axis> and <origin> were, the <limit> not)
    ("limit", _in_lined_joint("X", 'upper="0.25"', 'upper="-0.25"'),
     'upper="-0.25"', 1, "joint 'X': <limit lower=-0.25 upper=-0.25>"),
    ("limit_number", _in_lined_joint("X", 'velocity="0.025"', 'velocity="fast"'),
     'velocity="fast"', 1, "joint 'X' <limit velocity>: 'fast' is not a number"),
    ("limit_effort", _in_lined_joint("X", 'effort="1000.0" ', ''),
     'upper="0.25" velocity="0.025"', 1, "joint 'X': <limit> has no effort=..."),
    ("limit_rate", _in_lined_joint("X", 'velocity="0.025"', 'velocity="25.0"'),
     'velocity="25.0"', 1, "joint 'X': <limit velocity=25.0> (m/s); expected a rapid rate"),
    ("fixed_limit", _in_lined_joint("tool_tip_fixed", 'rpy="0.0 0.0 0.0"/>',
                                    'rpy="0.0 0.0 0.0"/>\n    <limit lower="0" upper="0"/>'),
     '<limit lower="0" upper="0"/>', 1, "joint 'tool_tip_fixed': <limit> has no effort=..."),
    # no <limit>: the joint's line, as before
    ("no_limit", _in_lined_joint("X", X_LIMIT, ""), '<joint name="X"', 2,
     "joint 'X': no <limit lower=... upper=... velocity=...>"),
    ("origin", LINED.replace('xyz="0.0 -0.4 -0.25"', 'xyz="0.0 -0.4 nan"', 1),
     'xyz="0.0 -0.4 nan"', 1, "joint 'Z' <origin> xyz: 'nan'"),
    ("origin_rpy", LINED.replace('xyz="0.0 -0.4 -0.25" rpy="0.0 0.0 0.0"',
                                 'xyz="0.0 -0.4 -0.25" rpy="0.0 0.0"', 1),
     'rpy="0.0 0.0"/>', 1, "joint 'Z' <origin>: rpy='0.0 0.0'; expected three numbers"),
    ("origin_far", LINED.replace('xyz="0.0 -0.4 -0.25"', 'xyz="0.0 -400.0 -0.25"', 1),
     'xyz="0.0 -400.0 -0.25"', 1, "joint 'Z' <origin xyz='0.0 -400.0 -0.25'> (m)"),
    ("fixed_origin", LINED.replace('<origin xyz="0.0 0.0 0.005"', '<origin xyz="0.0 0.0 x"',
                                   1),
     '<origin xyz="0.0 0.0 x"', 1, "joint 'workpiece_fixed' <origin> xyz: 'x' is not"),
    # a link's: its line and link (it had been 'FILE: an <origin>', with neither)
    ("visual_origin", LINED.replace('<visual><origin xyz="0.0 0.0 -0.03"',
                                    '<visual>\n      <origin xyz="0.0 0.0 nan"', 1),
     '<origin xyz="0.0 0.0 nan"', 1, "link 'y_carriage' <visual> <origin> xyz: 'nan'"),
    ("axis_numbers", LINED.replace('<axis xyz="1.0 0.0 0.0"/>', '<axis xyz="1.0 0.0"/>', 1),
     '<axis xyz="1.0 0.0"/>', 1, "joint 'X' <axis>: xyz='1.0 0.0'; expected three numbers"),
    ("axis_tilted", LINED.replace('<axis xyz="1.0 0.0 0.0"/>', '<axis xyz="1.0 0.1 0.0"/>',
                                  1),
     '<axis xyz="1.0 0.1 0.0"/>', 1, "joint 'X': axis [1.0, 0.1, 0.0] must be a unit"),
    ("axis_along", LINED.replace('<axis xyz="0.0 0.0 1.0"/>', '<axis xyz="1.0 0.0 0.0"/>', 1),
     '<axis xyz="1.0 0.0 0.0"/>', 2, "joint 'Z': <axis xyz=\"1.0 0.0 0.0\"> moves along X"),
    ("axis_sign", LINED.replace('<axis xyz="0.0 -1.0 0.0"/>', '<axis xyz="0.0 1.0 0.0"/>', 1),
     '<axis xyz="0.0 1.0 0.0"/>', 1, "joint 'Y': a workpiece-side axis must point -Y"),
    ("duplicate_link", LINED.replace('<link name="workpiece">',
                                     '<link name="table"/>\n<link name="workpiece">', 1),
     '<link name="table"', 2, "link 'table' is defined twice"),
    ("resolution", LINED.replace('joint="C" resolution="1.7453292519943297e-07"',
                                 'joint="C" resolution="0.1"', 1),
     '<machinesim:axis joint="C"', 1, "<machinesim:axis joint='C'> resolution 0.1 (rad)"),
    # found on the Pinocchio model at zero: the joint named by its axis letter
    ("zero_pose", _LINED_X_ALONG_Y, '<joint name="X"', 2,
     "joint 'X': +1 m of X moves the tool relative to the workpiece by (0, 1, 0) m"),
    ("joint_frame", _LINED_X_TURNED, '<joint name="X"', 2,
     "joint 'X': its frame is turned 90 deg relative to the workpiece"),
])
def test_a_refusal_names_the_line_of_the_joint_link_or_axis_element(case, text, needle,
                                                                    occurrence, words,
                                                                    tmp_path):
    # ElementTree keeps no lines: a refusal named the joint alone, which a CAD export of
    # hundreds of elements (and a <transmission> naming the same joint) leaves to search
    assert text != LINED
    path = tmp_path / f"{case}.urdf"
    path.write_text(text)
    with pytest.raises(ModelError) as raised:
        load_machine(path)
    assert str(raised.value).startswith(
        f"{path}, line {_line(text, needle, occurrence)}: {words}"), str(raised.value)


def test_a_urdf_of_more_links_than_a_machine_has_is_refused_before_pinocchio_reads_it(
        tmp_path):
    """Pinocchio's URDF reader takes a time growing with the square of the links: 144,000
    fixed links hung from the base (15 MB, under the size cap) ran over 10 minutes. Past
    MAX_LINKS the file is refused at once; at it, it loads."""
    from machinesim.urdf import MAX_LINKS

    def with_links(count: int) -> str:
        extra = count - GROOVING.count("<link ")
        return GROOVING.replace("</robot>", "".join(
            f'<link name="e{i}"/><joint name="f{i}" type="fixed"><parent link="base"/>'
            f'<child link="e{i}"/></joint>\n' for i in range(extra)) + "</robot>")

    at_cap, over = tmp_path / "at_cap.urdf", tmp_path / "over.urdf"
    at_cap.write_text(with_links(MAX_LINKS))
    over.write_text(with_links(MAX_LINKS + 1))
    assert load_machine(at_cap).axes == ("X", "Y", "Z", "C")
    with pytest.raises(ModelError) as raised:
        load_machine(over)
    assert str(raised.value) == (f"{over}: 2001 links; a machine has tens (a CAD export of "
                                 "every part a few hundred): expected at most 2000")


# URDF allows one of each in a joint, a link's <inertial> and a visual's or collision's
# <origin>, <geometry> (of one shape) and <material>; the parser under Pinocchio reads the
# first and dropped the others without a word, so these loaded with the first.
_X_AXIS = '<axis xyz="1.0 0.0 0.0"/>'
_X_ORIGIN = '<origin xyz="0.0 0.4 0.55" rpy="0.0 0.0 0.0"/>'
_BASE_VISUAL = ('<visual><origin xyz="0.0 0.0 -0.075" rpy="0.0 0.0 0.0"/><geometry>'
                '<box size="1.2 1.2 0.15"/></geometry><material name="bed"/></visual>')
_INERTIAL = ('<inertial><origin xyz="0 0 0"/><mass value="1"/>'
             '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>')


@pytest.mark.parametrize(("case", "text", "needle", "words"), [
    # the second <axis> turns X about Y: the file loaded as a plain X along +X
    ("two_axes", _in_joint("X", _X_AXIS, _X_AXIS + '\n    <axis xyz="0.0 1.0 0.0"/>'),
     '<joint name="X"', "joint 'X': 2 <axis> elements (lines 60, 61); URDF allows one"),
    ("two_origins", _in_joint("X", _X_ORIGIN,
                              _X_ORIGIN + '\n    <origin xyz="0.0 0.4 0.65" rpy="0.0 0.0 0.0"/>'),
     '<joint name="X"', "joint 'X': 2 <origin> elements (lines 59, 60); URDF allows one"),
    ("two_limits", _in_joint("X", X_LIMIT, X_LIMIT + X_LIMIT.replace("0.25", "0.3")),
     '<joint name="X"', "joint 'X': 2 <limit> elements (lines 61, 61); URDF allows one"),
    ("two_parents", _in_joint("X", '<parent link="base"/>',
                              '<parent link="base"/><parent link="y_carriage"/>'),
     '<joint name="X"', "joint 'X': 2 <parent> elements (lines 58, 58); URDF allows one"),
    ("two_inertials", GROOVING.replace(_BASE_VISUAL, _BASE_VISUAL + _INERTIAL * 2, 1),
     '<link name="base"', "link 'base': 2 <inertial> elements (lines 12, 12); URDF allows one"),
    ("inertial_two_masses", GROOVING.replace(
        _BASE_VISUAL, _BASE_VISUAL + _INERTIAL.replace("<mass", '<mass value="2"/><mass'), 1),
     '<link name="base"', "link 'base' <inertial> (its 1st): 2 <mass> elements (lines 12, 12)"),
    ("visual_two_origins", GROOVING.replace(
        _BASE_VISUAL, _BASE_VISUAL + _BASE_VISUAL.replace("<geometry>", '<origin/><geometry>'),
        1), '<link name="base"', "link 'base' <visual> (its 2nd): 2 <origin> elements "
     "(lines 12, 12)"),
    ("collision_two_shapes", GROOVING.replace(
        _BASE_VISUAL, _BASE_VISUAL + '<collision><geometry><box size="1 1 1"/>'
        '<sphere radius="1"/></geometry></collision>', 1),
     '<link name="base"', "link 'base' <collision> (its 1st): <geometry> holds 2 shapes "
     "(<box>, <sphere>); URDF allows one"),
])
def test_an_element_urdf_allows_once_given_twice_is_refused_naming_it(case, text, needle,
                                                                      words, tmp_path):
    path = tmp_path / f"{case}.urdf"
    path.write_text(text)
    with pytest.raises(ModelError) as raised:
        load_machine(path)
    assert str(raised.value).startswith(f"{path}, line {_line(text, needle)}: {words}"), \
        str(raised.value)


@pytest.mark.parametrize("case", ["inertials", "visual_origins", "collision_geometries"])
def test_an_element_given_twice_in_a_link_is_named_by_its_own_lines(case, tmp_path):
    # a duplicate inside a link had named only the link's line ("line 33: link
    # 'tool_mount': 2 <inertial> elements"), where the joint check names each element's
    # own line. In a link past the <transmission> and the other links' visuals, which the
    # count of lines goes by, on lines of their own
    inertial = '<inertial><mass value="1"/></inertial>'
    visual = '<visual><geometry><box size="1 1 1"/></geometry></visual>'
    added = {
        "inertials": f"\n    {inertial}\n    {visual}\n    {inertial}",
        "visual_origins": f"\n    {visual}\n    <visual>\n      <origin/>\n      "
                          "<geometry><box size=\"1 1 1\"/></geometry>\n      <origin/>\n"
                          "    </visual>",
        "collision_geometries": "\n    <collision>\n      <geometry><box size=\"1 1 1\"/>"
                                "</geometry>\n      <geometry><sphere radius=\"1\"/>"
                                "</geometry>\n    </collision>",
    }[case]
    text = LINED.replace('<link name="tool_mount">', '<link name="tool_mount">' + added, 1)
    path = tmp_path / f"{case}.urdf"
    path.write_text(text)
    with pytest.raises(ModelError) as raised:
        load_machine(path)
    link = _line(text, '<link name="tool_mount"')
    # the lines of the two, counted from the link's in the text added above
    what, first, second = {
        "inertials": ("link 'tool_mount': 2 <inertial>", link + 1, link + 3),
        "visual_origins": ("link 'tool_mount' <visual> (its 2nd): 2 <origin>", link + 3,
                           link + 5),
        "collision_geometries": ("link 'tool_mount' <collision> (its 1st): 2 <geometry>",
                                 link + 2, link + 3),
    }[case]
    assert str(raised.value).startswith(
        f"{path}, line {link}: {what} elements (lines {first}, {second}); URDF allows one"), \
        str(raised.value)


def test_a_joint_line_count_is_not_misled_by_elements_beside_the_joints(tmp_path):
    # the lines of a joint's children are counted joint by joint: a <transmission> (whose
    # <joint> holds children of its own) before the joints and a link's children between
    # them do not shift them
    text = LINED.replace(_X_AXIS, _X_AXIS + '\n    <axis xyz="0.0 1.0 0.0"/>', 1)
    path = tmp_path / "lined.urdf"
    path.write_text(text)
    with pytest.raises(ModelError) as raised:
        load_machine(path)
    first, joint = _line(text, _X_AXIS), _line(text, '<joint name="X"', 2)
    assert str(raised.value).startswith(
        f"{path}, line {joint}: joint 'X': 2 <axis> elements "
        f"(lines {first}, {first + 1})"), str(raised.value)
