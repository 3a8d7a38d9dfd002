"""What the URDF models' test files (tests/test_models_*.py) share (not collected: no test_
prefix): the models folder, grooving_4axis.urdf's text and edits of it, the HOSTILE_URDFS
cases (the located test takes each; the line test edits two), and a text's line of a
needle."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"


GROOVING = (MODELS / "grooving_4axis.urdf").read_text()
X_LIMIT = '<limit lower="-0.25" upper="0.25" effort="1000.0" velocity="0.025"/>'


def _in_joint(name: str, old: str, new: str) -> str:
    """grooving_4axis.urdf with ``old`` replaced by ``new`` inside joint ``name`` only."""
    start = GROOVING.index(f'<joint name="{name}"')
    end = GROOVING.index("</joint>", start)
    body = GROOVING[start:end]
    assert old in body, f"{old!r} is not in joint {name} of grooving_4axis.urdf"
    return GROOVING[:start] + body.replace(old, new, 1) + GROOVING[end:]


# Each case: the hostile file (a text edit of a shipped model) and words the message must
# hold: what is wrong, where (joint or link) and the value.
HOSTILE_URDFS = {
    "cycle": (_in_joint("Y", '<parent link="base"/>', '<parent link="c_table"/>'),
              ["joints 'C' -> 'Y' form a cycle", "'c_table'"]),
    "self_loop": (_in_joint("Z", '<parent link="x_carriage"/>', '<parent link="z_carriage"/>'),
                  ["joints 'Z' form a cycle", "'z_carriage'"]),
    "dangling_parent": (_in_joint("Z", '<parent link="x_carriage"/>',
                                  '<parent link="x_carriag"/>'),
                        ["joint 'Z'", "parent link 'x_carriag' does not exist"]),
    "dangling_child": (_in_joint("X", '<child link="x_carriage"/>', '<child link="nowhere"/>'),
                       ["joint 'X'", "child link 'nowhere' does not exist"]),
    "duplicate_joint": (_in_joint("Z", '<joint name="Z"', '<joint name="X"'),
                        ["joint 'X' is defined twice"]),
    "duplicate_link": (GROOVING.replace('<link name="tool_tip">',
                                        '<link name="tool_tip"/><link name="tool_tip">'),
                       ["link 'tool_tip' is defined twice"]),
    "two_parents": (_in_joint("Z", '<child link="z_carriage"/>', '<child link="x_carriage"/>'),
                    ["joint 'Z'", "'x_carriage' is already the child of joint 'X'"]),
    "two_roots": (GROOVING.replace('<link name="base">', '<link name="stray"/><link name="base">'),
                  ["2 root links", "'stray'"]),
    "missing_limit": (_in_joint("X", X_LIMIT, ""), ["joint 'X'", "no <limit"]),
    "missing_lower": (_in_joint("X", ' lower="-0.25"', ""), ["joint 'X'", "no lower="]),
    "missing_upper": (_in_joint("X", ' upper="0.25"', ""), ["joint 'X'", "no upper="]),
    "missing_velocity": (_in_joint("X", ' velocity="0.025"', ""), ["joint 'X'", "no velocity="]),
    # a ROS or CAD export may leave effort out; the URDF parser then refused the file with
    # "The XML stream does not contain a valid URDF model", naming neither joint nor key
    "missing_effort": (_in_joint("X", ' effort="1000.0"', ""), ["joint 'X'", "no effort="]),
    "effort_not_a_number": (_in_joint("X", 'effort="1000.0"', 'effort="1kN"'),
                            ["joint 'X'", "effort", "'1kN' is not a number"]),
    "swapped_limits": (_in_joint("X", 'lower="-0.25" upper="0.25"', 'lower="0.25" upper="-0.25"'),
                       ["joint 'X'", "lower=0.25 upper=-0.25", "expected lower < upper"]),
    "empty_travel": (_in_joint("Z", 'lower="-0.05" upper="0.1"', 'lower="0.1" upper="0.1"'),
                     ["joint 'Z'", "lower=0.1 upper=0.1", "expected lower < upper"]),
    "velocity_zero": (_in_joint("X", 'velocity="0.025"', 'velocity="0"'),
                      ["joint 'X'", "velocity=0.0", "rapid rate > 0"]),
    "velocity_negative": (_in_joint("C", 'velocity="2.0"', 'velocity="-2"'),
                          ["joint 'C'", "velocity=-2.0", "rapid rate > 0"]),
    "velocity_nan": (_in_joint("X", 'velocity="0.025"', 'velocity="nan"'),
                     ["joint 'X'", "velocity", "'nan'", "finite"]),
    # Python's float() reads these; the URDF parser under Pinocchio refused the file with
    # "does not contain a valid URDF model", naming neither joint nor value
    "limit_with_underscore": (_in_joint("X", 'upper="0.25"', 'upper="0_25"'),
                              ["joint 'X'", "upper", "'0_25' is not a number as a URDF "
                               "parser reads one"]),
    "limit_trailing_blank": (_in_joint("X", 'upper="0.25"', 'upper="0.25 "'),
                             ["joint 'X'", "'0.25 ' is not a number as a URDF parser"]),
    "origin_arabic_indic_digit": (_in_joint("X", 'xyz="0.0 0.4 0.55"', 'xyz="0.0 \u0660.4 0.55"'),
                                  ["joint 'X'", "<origin> xyz", "'\u0660.4' is not a number "
                                   "as a URDF parser"]),
    # the URDF parser reads a <limit> on a fixed joint too, and refused the file without
    # naming it; and it requires the robot's name
    "fixed_joint_limit_without_effort": (
        _in_joint("tool_tip_fixed", '<origin xyz="0.0 0.0 -0.02" rpy="0.0 0.0 0.0"/>',
                  '<origin xyz="0.0 0.0 -0.02" rpy="0.0 0.0 0.0"/><limit lower="0" upper="0"/>'),
        ["joint 'tool_tip_fixed'", "<limit> has no effort="]),
    "robot_without_name": (GROOVING.replace('<robot name="grooving_4axis"', "<robot"),
                           ["<robot> has no name="]),
    "limit_not_a_number": (_in_joint("X", 'upper="0.25"', 'upper="0.25mm"'),
                           ["joint 'X'", "upper", "'0.25mm' is not a number"]),
    "axis_nan": (_in_joint("X", '<axis xyz="1.0 0.0 0.0"/>', '<axis xyz="nan 0.0 0.0"/>'),
                 ["joint 'X'", "<axis> xyz", "'nan'", "finite"]),
    "axis_inf": (_in_joint("Y", '<axis xyz="0.0 -1.0 0.0"/>', '<axis xyz="0.0 -inf 0.0"/>'),
                 ["joint 'Y'", "<axis> xyz", "'-inf'", "finite"]),
    # a CAD export writes cos(90 deg) as 6.123e-17: the message said "must be a unit machine
    # direction" of a vector whose length is 1, without saying which directions those are
    "axis_cad_round_off": (_in_joint("C", '<axis xyz="0.0 0.0 -1.0"/>',
                                     '<axis xyz="6.123233995736766e-17 0.0 -1.0"/>'),
                           ["joint 'C'", "axis [6.123233995736766e-17, 0.0, -1.0]",
                            "one of 1 0 0, 0 1 0, 0 0 1, either sign"]),
    "axis_missing": (_in_joint("X", '<axis xyz="1.0 0.0 0.0"/>', ""), ["joint 'X'", "no <axis"]),
    "axis_two_numbers": (_in_joint("X", '<axis xyz="1.0 0.0 0.0"/>', '<axis xyz="1.0 0.0"/>'),
                         ["joint 'X'", "xyz='1.0 0.0'", "three numbers"]),
    "origin_nan": (_in_joint("X", 'xyz="0.0 0.4 0.55"', 'xyz="0.0 NaN 0.55"'),
                   ["joint 'X'", "<origin> xyz", "'NaN'", "finite"]),
    "origin_rpy_inf": (_in_joint("C", 'rpy="0.0 0.0 0.0"', 'rpy="0.0 inf 0.0"'),
                       ["joint 'C'", "<origin> rpy", "'inf'", "finite"]),
    "resolution_zero": (GROOVING.replace('joint="X" resolution="1e-09"',
                                         'joint="X" resolution="0"'),
                        ["joint='X'", "resolution 0.0", "> 0"]),
    "resolution_in_um": (GROOVING.replace('joint="X" resolution="1e-09"',
                                          'joint="X" resolution="1"'),
                         ["joint='X'", "resolution 1.0 (m)", "expected at most 0.0001 m"]),
    "resolution_missing": (GROOVING.replace('joint="X" resolution="1e-09"', 'joint="X"'),
                           ["joint='X'", "no resolution="]),
    "no_tool_tip": (GROOVING.replace('<link name="tool_tip">', '<link name="tool_tap">')
                    .replace('<child link="tool_tip"/>', '<child link="tool_tap"/>'),
                    ["missing frame(s) tool_tip"]),
    "reserved_name": (_in_joint("Z", '<joint name="Z"', '<joint name="tool_tx"'),
                      ["joint name 'tool_tx' is reserved"]),
    "not_a_robot": (GROOVING.replace("<robot ", "<robut ").replace("</robot>", "</robut>"),
                    ["root element <robut>", "expected <robot>"]),
    # a default namespace (xacro's xacro:targetNamespace writes one): refused as root
    # element <{http://www.ros.org}robot>; expected <robot>, saying neither what nor how
    "default_namespace": (GROOVING.replace("<robot ", '<robot xmlns="http://www.ros.org" ', 1),
                          ["root element <robot> in the XML namespace 'http://www.ros.org' (a "
                           'default xmlns="http://www.ros.org" on it); expected <robot> in no '
                           "namespace, as URDF's elements are: remove the xmlns=... attribute "
                           "from <robot>"]),
    "truncated": (GROOVING[:len(GROOVING) // 2], ["not readable XML"]),
    # a CAD tool's comment in Latin-1 (line 4, after the file's 3 header lines) with no
    # encoding declared: expat, reading UTF-8, said "not well-formed (invalid token)" at a
    # column, not why
    "latin1_undeclared": (GROOVING.replace('<robot name=', '<!-- 1 \u00b5m -->\n<robot name=', 1)
                          .encode("latin-1").decode("utf-8", "surrogateescape"),
                          ["not readable XML (not well-formed (invalid token)",
                           "the file is not UTF-8 (byte 0xb5 at line 4, column 7) and "
                           "declares no encoding: save it as UTF-8, or declare its encoding"]),
    # a xacro file given for its URDF: a link made by a macro was "child link ... does not
    # exist", a ${...} "not a number"; neither said to expand it
    "xacro_macro": (GROOVING.replace(
        '<robot name="grooving_4axis"',
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="grooving_4axis"', 1)
        .replace('<link name="base">', '<xacro:property name="h" value="0.1"/><link name="base">'),
                    ["<xacro:property> is xacro, not URDF: expand it first (xacro "
                     "xacro_macro.urdf > machine.urdf)"]),
    "xacro_expression": (_in_joint("X", 'xyz="0.0 0.4 0.55"', 'xyz="0.0 0.4 ${h}"'),
                         ["<origin xyz='0.0 0.4 ${h}'> is a xacro expression, not a value: "
                          "expand it first"]),
    "namespace_missing": (GROOVING.replace(' xmlns:machinesim="https://machinesim.invalid/urdf"',
                                           ""),
                          ["not readable XML (unbound prefix", "namespace declared on "
                           '<robot>: xmlns:machinesim="https://machinesim.invalid/urdf"']),
    # machines that load as another machine unless the conventions are checked at zero
    "x_along_y": (_in_joint("X", '<axis xyz="1.0 0.0 0.0"/>', '<axis xyz="0.0 1.0 0.0"/>'),
                  ["joint 'X'", '<axis xyz="0.0 1.0 0.0"> moves along Y',
                   "the X axis moves along X"]),
    # a CAD export's joint frame turned so that its Z is the motion: the message said "moves
    # along Z; the X axis moves along X", and <axis xyz="1 0 0"> then moved X along Z
    "x_cad_frame": (_in_joint("X", 'rpy="0.0 0.0 0.0"', 'rpy="0.0 1.5707963267948966 0.0"')
                    .replace('<axis xyz="1.0 0.0 0.0"/>', '<axis xyz="0.0 0.0 -1.0"/>', 1),
                    ["joint 'X'", '<axis xyz="0.0 0.0 -1.0"> moves along Z',
                     "which its <origin rpy=\"0.0 1.5707963267948966 0.0\"> turns: write "
                     'rpy="0 0 0" on an axis joint']),
    "x_mimics_y": (_in_joint("X", '<axis xyz="1.0 0.0 0.0"/>',
                             '<axis xyz="1.0 0.0 0.0"/><mimic joint="Y"/>'),
                   ["joint 'X'", "has a <mimic>", "by its own NC letter"]),
    # a fixed joint's type mistyped or left out was taken for an axis: "machine axes are
    # prismatic or revolute" of a joint meant to be fixed
    "fixed_type_typo": (_in_joint("table_fixed", 'type="fixed"', 'type="fixd"'),
                        ["joint 'table_fixed': type 'fixd' is not a URDF joint type",
                         "expected fixed, or prismatic or revolute for a machine axis"]),
    "type_missing": (_in_joint("table_fixed", ' type="fixed"', ""),
                     ["joint 'table_fixed': type None is not a URDF joint type"]),
    "continuous_x": (_in_joint("X", 'type="prismatic"', 'type="continuous"'),
                     ["joint 'X': type 'continuous'; machine axes are prismatic or revolute"]),
    # every joint fixed: the load ended in an IndexError inside the kinematics
    "no_axis": (GROOVING.replace('type="prismatic"', 'type="fixed"')
                .replace('type="revolute"', 'type="fixed"')
                .replace(' xmlns:machinesim="https://machinesim.invalid/urdf"', "")
                .split("  <machinesim:axis")[0] + "</robot>\n",
                ["no axis joint; expected at least one", "X, Y, Z (prismatic) or A, B, C"]),
    "x_revolute": (_in_joint("X", 'type="prismatic"', 'type="revolute"'),
                   ["joint 'X'", "type 'revolute'", "X, Y and Z are linear axes"]),
    "c_prismatic": (_in_joint("C", 'type="revolute"', 'type="prismatic"'),
                    ["joint 'C'", "type 'prismatic'", "A, B and C rotary ones"]),
    "x_frame_turned": (_in_joint("X", 'rpy="0.0 0.0 0.0"', 'rpy="0.0 0.0 1.5707963267948966"'),
                       ["at zero axis values the tool_tip sits at", "turned 90 deg",
                        "expected the tool edge at the workpiece origin"]),
    # X's frame turned a quarter and Z's turned back, Z placed where it was: the tool sits
    # as designed, but X moves it along +Y
    "x_moves_along_y": (
        _in_joint("X", 'rpy="0.0 0.0 0.0"', 'rpy="0.0 0.0 1.5707963267948966"').replace(
            '<origin xyz="0.0 -0.4 -0.25" rpy="0.0 0.0 0.0"/>',
            '<origin xyz="-0.4 0.0 -0.25" rpy="0.0 0.0 -1.5707963267948966"/>'),
        ["joint 'X'", "+1 m of X moves the tool relative to the workpiece by (0, 1, 0) m",
         "expected +1 m along X"]),
    # a spindle frame turned a quarter about Z and the tip turned back: the tool sits as
    # designed, but a tool setting error along tool_mount Y entered along its X
    # X's frame turned a quarter about X itself and Z's turned back: X and Z move the tool as
    # designed, but X's errors entered in the turned frame (its straightness in Y moved the
    # tool along Z)
    "x_frame_turned_about_x": (
        _in_joint("X", 'rpy="0.0 0.0 0.0"', 'rpy="1.5707963267948966 0.0 0.0"').replace(
            '<origin xyz="0.0 -0.4 -0.25" rpy="0.0 0.0 0.0"/>',
            '<origin xyz="0.0 -0.25 0.4" rpy="-1.5707963267948966 0.0 0.0"/>'),
        ["joint 'X': its frame is turned 90 deg relative to the workpiece",
         "expected it parallel to the machine axes", "errors of X (EXX, EYX, EZX, ...)"]),
    "tool_mount_turned": (
        _in_joint("tool_mount_fixed", 'rpy="0.0 0.0 0.0"', 'rpy="0.0 0.0 1.5707963267948966"')
        .replace('<origin xyz="0.0 0.0 -0.02" rpy="0.0 0.0 0.0"/>',
                 '<origin xyz="0.0 0.0 -0.02" rpy="0.0 0.0 -1.5707963267948966"/>'),
        ["tool_tip is turned 90 deg relative to tool_mount", "expected them parallel"]),
    # tool_mount hung from the base, where no axis moves it: X and Z move the tip alone
    "tool_mount_on_the_base": (
        _in_joint("tool_mount_fixed", '<parent link="z_carriage"/>', '<parent link="base"/>')
        .replace('<joint name="tool_tip_fixed" type="fixed">\n    <parent link="tool_mount"/>',
                 '<joint name="tool_tip_fixed" type="fixed">\n    <parent link="z_carriage"/>')
        .replace('<origin xyz="0.0 0.0 -0.02" rpy="0.0 0.0 0.0"/>',
                 '<origin xyz="0.0 0.0 -0.1" rpy="0.0 0.0 0.0"/>'),
        ["axis joint(s) X, Z move tool_tip and not tool_mount"]),
    "tip_off_origin": (GROOVING.replace('<origin xyz="0.0 0.0 -0.02" rpy="0.0 0.0 0.0"/>',
                                        '<origin xyz="0.003 0.0 -0.02" rpy="0.0 0.0 0.0"/>'),
                       ["the tool_tip sits at (3, 0, 0) mm", "turned 0 deg"]),
    "y_carries_both": (_in_joint("X", '<parent link="base"/>', '<parent link="y_carriage"/>'),
                       ["joint 'Y'", "carries both the tool_tip and the workpiece"]),
    "travel_in_mm": (_in_joint("X", 'lower="-0.25" upper="0.25"', 'lower="-250" upper="250"'),
                     ["joint 'X'", "lower=-250.0 upper=250.0", "within +-10 m",
                      "100 mm is 0.1"]),
    # every origin in mm, the limits in m: the tool still sat at the origin at zero and the
    # file loaded, but every Abbe offset was 1000 times too long (X's pitch of 10 urad moved
    # mill3's tool 250 um instead of 0.25 um)
    "origins_in_mm": (re.sub(r'<origin xyz="([^"]*)"', lambda m: '<origin xyz="{}"'.format(
                          " ".join(f"{1e3 * float(v):g}" for v in m[1].split())), GROOVING),
                      ["joint 'Y' <origin xyz='0 0 80'> (m)", "each coordinate within +-10 m",
                       "100 mm is 0.1"]),
    "rapid_rate_tiny": (_in_joint("X", 'velocity="0.025"', 'velocity="1e-300"'),
                        ["joint 'X'", "velocity=1e-300", "rate of 1e-06 .. 10 m/s"]),
    # 25 mm/s written as 25 loaded, and the report's machining time took rapids as 25 m/s
    "rapid_rate_in_mm_per_s": (_in_joint("X", 'velocity="0.025"', 'velocity="25"'),
                               ["joint 'X'", "<limit velocity=25.0> (m/s)",
                                "expected a rapid rate of 1e-06 .. 10 m/s"]),
    "stray_resolution": (GROOVING.replace('<machinesim:axis joint="Y"',
                                          '<machinesim:axis joint="Q" resolution="1e-09"/>'
                                          '<machinesim:axis joint="Y"'),
                         ["<machinesim:axis joint='Q'> names no axis joint"]),
    "other_namespace": (GROOVING.replace('xmlns:machinesim="https://machinesim.invalid/urdf"',
                                         'xmlns:machinesim="http://example.com/ms"'),
                        ["<machinesim:axis> is in the XML namespace 'http://example.com/ms'",
                         'declare xmlns:machinesim="https://machinesim.invalid/urdf"']),
    # urdfdom reads <origin xmlns="..."> as the joint's origin (it matches names as
    # written); this reader found no <origin>: a base set 0.5 m up on a floor link loaded
    # without a word at the floor, and Y's 80 mm above the base was refused as a zero pose
    # 80 mm off
    "default_namespace_floor_origin": (GROOVING.replace(
        '  <link name="base">',
        '  <link name="floor"/>\n  <joint name="mount" type="fixed"><parent link="floor"/>'
        '<child link="base"/><origin xmlns="http://www.ros.org" xyz="0 0 0.5"/></joint>\n'
        '  <link name="base">', 1),
                                       [", line 12: <origin> is in the XML namespace "
                                        "'http://www.ros.org'", "reads it as <origin>"]),
    "default_namespace_origin": (GROOVING.replace('<origin xyz="0.0 0.0 0.08"',
                                                  '<origin xmlns="http://www.ros.org" '
                                                  'xyz="0.0 0.0 0.08"', 1),
                                 [", line 39: <origin> is in the XML namespace "
                                  "'http://www.ros.org'", "reads it as <origin>",
                                  "remove the xmlns=... attribute"]),
    "default_namespace_joint": (GROOVING.replace('<joint name="Y" type="prismatic">',
                                                 '<joint xmlns="urn:x" name="Y" '
                                                 'type="prismatic">', 1),
                                [", line 37: <joint> is in the XML namespace 'urn:x'"]),
    "prefixed_limit": (GROOVING.replace('<robot ', '<robot xmlns:ros="urn:ros" ', 1)
                       .replace('<axis xyz="0.0 -1.0 0.0"/>',
                                '<axis xyz="0.0 -1.0 0.0"/><ros:limit lower="0"/>', 1),
                       [", line 40: <ros:limit> is in the XML namespace 'urn:ros'",
                        "both drop it", "write it as 'limit' in no namespace"]),
    "prefixed_attribute": (GROOVING.replace('<robot ', '<robot xmlns:ros="urn:ros" ', 1)
                           .replace('<origin xyz="0.0 0.0 0.08"',
                                    '<origin ros:xyz="0.0 0.0 0.08"', 1),
                           [", line 39: attribute 'ros:xyz' is in the XML namespace "
                            "'urn:ros'"]),
    "visual_box_not_a_number": (GROOVING.replace('<box size="1.2 1.2 0.15"/>',
                                                 '<box size="a 1.2 0.15"/>'),
                                [", line 12: link 'base' <visual> <box size>",
                                 "'a' is not a number"]),
    "visual_box_two_sizes": (GROOVING.replace('<box size="1.2 1.2 0.15"/>',
                                              '<box size="1.2 0.15"/>'),
                             [", line 12: link 'base' <visual>", "<box size='1.2 0.15'>",
                              "expected 3 lengths > 0 (m)"]),
    "visual_cylinder_negative": (GROOVING.replace('<cylinder radius="0.0015"',
                                                  '<cylinder radius="-0.0015"'),
                                 [", line 35: link 'tool_tip' <visual>",
                                  "<cylinder radius='-0.0015'>", "expected one length > 0 (m)"]),
    # the URDF parser dropped the visual of a scale it could not read (a C++ message on
    # stderr), and read 'nan' as 1 1 1: the machine loaded and was drawn without that mesh
    "mesh_scale_two_numbers": (GROOVING.replace('<box size="1.2 1.2 0.15"/>',
                                                '<mesh filename="base.stl" scale="1e-3 1e-3"/>'),
                               ["link 'base' <visual>", "<mesh scale='1e-3 1e-3'>",
                                "expected three numbers", "0.001 0.001 0.001 for a mesh in mm"]),
    "mesh_scale_not_finite": (GROOVING.replace('<box size="1.2 1.2 0.15"/>',
                                               '<mesh filename="base.stl" scale="nan 1 1"/>'),
                              ["link 'base' <visual> <mesh scale>", "'nan'; expected a finite"]),
    "mesh_scale_commas": (GROOVING.replace('<box size="1.2 1.2 0.15"/>',
                                           '<mesh filename="base.stl" scale="1,1,1"/>'),
                          ["link 'base' <visual> <mesh scale>", "'1,1,1' is not a number"]),
    # a shape's message named no line (every other refusal of a link's element did): it now
    # names its <geometry>'s, here on the line after the visual's
    "collision_box_own_line": (GROOVING.replace(
        '<material name="bed"/></visual>',
        '<material name="bed"/></visual>\n    <collision>\n      <geometry>\n'
        '        <box size="1.2 -1.2 0.15"/>\n      </geometry>\n    </collision>', 1),
                               [", line 14: link 'base' <collision>: <box size='1.2 -1.2 0.15'>",
                                "expected 3 lengths > 0 (m)"]),
    # the URDF parser dropped a visual or collision without a shape, and a visual whose
    # material had no name, saying so on stderr only ("Could not parse visual element for
    # Link [base]"): the machine loaded, drawn without it
    "visual_without_geometry": (GROOVING.replace('<geometry><box size="1.2 1.2 0.15"/></geometry>',
                                                 '', 1),
                                [", line 12: link 'base' <visual>: has no <geometry>",
                                 "a box, cylinder, sphere or mesh"]),
    "visual_empty_geometry": (GROOVING.replace('<box size="1.2 1.2 0.15"/>', '', 1),
                              [", line 12: link 'base' <visual>: has an empty <geometry>"]),
    "collision_without_geometry": (GROOVING.replace(
        '<material name="bed"/></visual>',
        '<material name="bed"/></visual>\n    <collision>\n    </collision>', 1),
                                   [", line 13: link 'base' <collision>: has no <geometry>"]),
    "material_without_name": (GROOVING.replace('<material name="bed"/>', '<material/>', 1),
                              [", line 12: link 'base' <visual>: a <material> has no name"]),
    # an <inertial> the parser cannot read was dropped with a C++ message on stderr only
    "inertial_without_mass": (GROOVING.replace(
        '<material name="bed"/></visual>',
        '<material name="bed"/></visual>\n    <inertial><inertia ixx="1" ixy="0" ixz="0" '
        'iyy="1" iyz="0" izz="1"/></inertial>', 1),
                              [", line 13: link 'base' <inertial>: no <mass value=...> (kg)"]),
    "inertial_mass_not_a_number": (GROOVING.replace(
        '<material name="bed"/></visual>',
        '<material name="bed"/></visual>\n    <inertial><mass value="1 kg"/><inertia ixx="1" '
        'ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>', 1),
                                   [", line 13: link 'base' <inertial> <mass value>",
                                    "'1 kg' is not a number"]),
    "inertia_missing_ixy": (GROOVING.replace(
        '<material name="bed"/></visual>',
        '<material name="bed"/></visual>\n    <inertial><mass value="1"/><inertia ixx="1" '
        'iyy="1" izz="1"/></inertial>', 1),
                            [", line 13: link 'base' <inertial>: <inertia> has no ixy=..."]),
    "visual_unknown_shape": (GROOVING.replace('<box size="1.2 1.2 0.15"/>',
                                              '<cone size="1.2 1.2 0.15"/>'),
                             ["link 'base' <visual>", "<cone>",
                              "expected a box, cylinder, sphere or mesh"]),
    # entity expansion: a billion laughs (1e9 "lol"s from 1 kB) in the robot's name, and a
    # file's contents pulled in by an external entity; expat refuses both before it expands
    "billion_laughs": (GROOVING.replace(
        '<robot name="grooving_4axis"',
        '<!DOCTYPE robot [<!ENTITY l0 "lol">' + "".join(
            f'<!ENTITY l{i} "{f"&l{i - 1};" * 10}">' for i in range(1, 10))
        + ']>\n<robot name="&l9;"', 1),
                       ["not readable XML (limit on input amplification factor"]),
    "external_entity": (GROOVING.replace(
        '<robot name="grooving_4axis"',
        '<!DOCTYPE robot [<!ENTITY e SYSTEM "file:///etc/hostname">]>\n<robot name="&e;"', 1),
                        ["not readable XML (reference to external entity in attribute"]),
    # what the URDF parser reads of a joint beside its origin, axis and limit, and <robot
    # version>: it refused a bad one with lines of C++ on stderr and "The XML stream does not
    # contain a valid URDF model", naming neither the joint nor the value
    "fixed_joint_dynamics_nan": (_in_joint("table_fixed", "<origin", '<dynamics damping="nan"/>'
                                           "<origin"),
                                 [", line 51: joint 'table_fixed' <dynamics damping>: 'nan'"]),
    "fixed_joint_dynamics_empty": (_in_joint("table_fixed", "<origin", "<dynamics/><origin"),
                                   ["joint 'table_fixed': <dynamics> has neither damping"]),
    "fixed_joint_limit_lower_nan": (_in_joint("table_fixed", "<origin", '<limit lower="nan" '
                                              'effort="1" velocity="1"/><origin'),
                                    ["joint 'table_fixed' <limit lower>: 'nan'; expected a "
                                     "finite number"]),
    "fixed_joint_safety_without_k_velocity": (
        _in_joint("table_fixed", "<origin", '<safety_controller soft_lower_limit="0"/><origin'),
        ["joint 'table_fixed': <safety_controller> has no k_velocity=..."]),
    "fixed_joint_calibration_not_a_number": (
        _in_joint("table_fixed", "<origin", '<calibration rising="1 mm"/><origin'),
        ["joint 'table_fixed' <calibration rising>: '1 mm' is not a number"]),
    "fixed_joint_mimic_without_joint": (_in_joint("table_fixed", "<origin", "<mimic/><origin"),
                                        ["joint 'table_fixed': <mimic> has no joint=..."]),
    "robot_version_2": (GROOVING.replace('<robot name="grooving_4axis"',
                                         '<robot name="grooving_4axis" version="2.0"', 1),
                        ["<robot version='2.0'>; expected a URDF version", "1.0, 1.1, 1.2"]),
    # Pinocchio refused it in one line that named neither the joint nor the value
    "effort_negative": (_in_joint("X", 'effort="1000.0"', 'effort="-1"'),
                        [", line 61: joint 'X': <limit effort=-1.0>; expected a number >= 0"]),
    # a no-break space (a word processor's, a web page's) between numbers or before one:
    # str.split() and float() took it for a blank, the URDF parser does not, and refused the
    # file in lines of C++ on stderr, then "The XML stream does not contain a valid URDF
    # model", naming neither the joint nor the value
    "origin_no_break_space": (_in_joint("X", 'xyz="0.0 0.4 0.55"', 'xyz="0.0\u00a00.4 0.55"'),
                              [", line 59: joint 'X' <origin>: xyz='0.0\\xa00.4 0.55'; expected "
                               "three numbers (U+00A0 NO-BREAK SPACE separates no numbers"]),
    "axis_em_space": (_in_joint("X", '<axis xyz="1.0 0.0 0.0"/>', '<axis xyz="1.0\u20030.0 0.0"/>'),
                      [", line 60: joint 'X' <axis>: xyz='1.0\\u20030.0 0.0'", "U+2003 EM SPACE"]),
    "limit_no_break_space": (_in_joint("X", 'lower="-0.25"', 'lower="\u00a0-0.25"'),
                             [", line 61: joint 'X' <limit lower>: '\\xa0-0.25' is not a number "
                              "as a URDF parser reads one"]),
    "box_size_line_end": (GROOVING.replace('<box size="1.2 1.2 0.15"/>',
                                           '<box size="1.2 1.2&#13;0.15"/>'),
                          ["link 'base' <visual> <box size>: '1.2\\r0.15' is not a number"]),
    # the URDF parser refused a name given twice, in C++ on stderr and a line naming no
    # material, and dropped one without a name, saying so on stderr only
    "material_defined_twice": (GROOVING.replace(
        '<link name="base">', '<material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>'
        '\n  <material name="grey"><color rgba="0.6 0.6 0.6 1"/></material>\n  <link name="base">',
        1), [", line 12: <material name='grey'> is defined twice under <robot> (first at line "
             "11)"]),
    "material_without_name_under_robot": (GROOVING.replace(
        '<link name="base">', '<material><color rgba="0.5 0.5 0.5 1"/></material>'
        '<link name="base">', 1), [", line 11: a <material> under <robot> has no name=..."]),
    # expat reads no multi-byte encoding but UTF-8 and UTF-16, and no encoding Python does
    # not know: its ValueError and LookupError ended the command as internal errors
    "encoding_shift_jis": (GROOVING.replace('<?xml version="1.0"?>',
                                            '<?xml version="1.0" encoding="Shift_JIS"?>', 1),
                           ["its XML declaration gives encoding=\"Shift_JIS\", which the XML "
                            "reader cannot read (multi-byte encodings are not supported)",
                            "save the file as UTF-8"]),
    "encoding_unknown": (GROOVING.replace('<?xml version="1.0"?>',
                                          "<?xml version='1.0' encoding='UTF8X'?>", 1),
                         ["gives encoding=\"UTF8X\"", "(unknown encoding: UTF8X)"]),
    # a colour the URDF parser cannot read it dropped with a C++ message on stderr only; one
    # of three numbers (no alpha) it took as black without a word
    "material_color_three_numbers": (GROOVING.replace('rgba="0.35 0.37 0.40 1"',
                                                      'rgba="0.35 0.37 0.40"', 1),
                                     [", line 5: <material name='bed'>: <color rgba='0.35 0.37 "
                                      "0.40'>; expected four numbers from 0 to 1"]),
    "visual_color_beyond_one": (GROOVING.replace(
        '<material name="bed"/></visual>',
        '<material name="bed"><color rgba="0.35 0.37 1.5 1"/></material></visual>', 1),
                                [", line 12: link 'base' <visual> <material name='bed'>: <color "
                                 "rgba='0.35 0.37 1.5 1'>; expected four numbers from 0 to 1"]),
    "material_color_without_rgba": (GROOVING.replace('<color rgba="0.35 0.37 0.40 1"/>',
                                                     '<color/>', 1),
                                    [", line 5: <material name='bed'> has a <color> without "
                                     "rgba=..."]),
    "nested_deep": (GROOVING.replace('<link name="base">', '<link name="base">'
                                     + "<a>" * 100_000 + "</a>" * 100_000),
                    ["XML nested 100002 elements deep", "expected at most 64"]),
}


def _line(text: str, needle: str, occurrence: int = 1) -> int:
    """The line on which the ``occurrence``-th ``needle`` of ``text`` starts."""
    at = -1
    for _ in range(occurrence):
        at = text.index(needle, at + 1)
    return text.count("\n", 0, at) + 1
