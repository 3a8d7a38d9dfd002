"""The URDF models: standard URDF check, Pinocchio with visuals, generator, packaging."""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from machinesim.exceptions import MachineSimWarning, ModelError
from machinesim.machines import list_machines, load_machine, models_dir

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"


def _generator():
    spec = importlib.util.spec_from_file_location("build_models", MODELS / "build_models.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def find_check_urdf() -> str | None:
    """urdfdom's ``check_urdf``: beside the running interpreter first (Pinocchio's ``pin``
    wheel installs it into the environment's bin folder, which is not on PATH when the tests
    run as ``.venv/bin/python -m pytest``), then on PATH (Debian's liburdfdom-tools)."""
    return (shutil.which("check_urdf", path=str(Path(sys.executable).parent))
            or shutil.which("check_urdf"))


@pytest.mark.parametrize("name", list_machines())
def test_check_urdf_accepts_every_model(name):
    check_urdf = find_check_urdf()
    if check_urdf is None:
        pytest.fail(f"check_urdf is missing, neither beside {sys.executable} nor on PATH: "
                    f"it comes with Pinocchio's wheel ('{sys.executable} -m pip install pin', "
                    f"which `make test` does), or install Debian's liburdfdom-tools")
    result = subprocess.run([check_urdf, str(MODELS / f"{name}.urdf")],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Successfully Parsed XML" in result.stdout


@pytest.mark.parametrize("name", list_machines())
def test_every_model_loads_in_pinocchio_with_visuals_and_frames(name):
    machine = load_machine(name)
    visual = pin.buildGeomFromUrdfString(machine.model, machine.urdf_xml,
                                         pin.GeometryType.VISUAL)
    assert visual.ngeoms >= 5
    for frame in ("base", "table", "workpiece", "tool_mount", "tool_tip"):
        assert frame in machine.frames
    assert machine.model.names[1:].tolist().count(machine.axes[0]) == 1
    # resolution as the papers give it: 1 nm and 0.00001 deg
    for letter in machine.axes:
        ax = machine.axis(letter)
        expected = np.radians(1e-5) if ax.rotary else 1e-9
        assert ax.resolution == pytest.approx(expected, rel=1e-12)
        assert ax.lower < 0.0 < ax.upper


def test_robonano_a0ib_has_the_probe_beside_the_tool():
    machine = load_machine("robonano_a0ib")
    pose = machine.frame_pose("probe_tip", np.zeros(5))
    np.testing.assert_allclose(pose[:3, 3], [0.0, 0.040, 0.001], atol=1e-15)


def test_tool_mount_is_parallel_to_the_machine_axes_and_above_the_edge():
    for name in list_machines():
        machine = load_machine(name)
        mount = machine.frame_pose("tool_mount", np.zeros(len(machine.axes)))
        np.testing.assert_allclose(mount, np.eye(4) + np.pad([[0.020]], ((2, 1), (3, 0))),
                                   atol=1e-15)


def test_models_are_what_the_generator_writes():
    texts = _generator().build()
    assert sorted(texts) == sorted(list_machines())
    for name, text in texts.items():
        assert (MODELS / f"{name}.urdf").read_text() == text, (
            f"models/{name}.urdf differs from models/build_models.py: rerun the script")


def test_unknown_machine_and_bad_files_are_refused(tmp_path):
    with pytest.raises(ModelError, match="unknown machine 'robonano'; expected one of"):
        load_machine("robonano")
    with pytest.raises(ModelError, match="no such URDF file"):
        load_machine(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.urdf"
    text = (MODELS / "planer_4axis.urdf").read_text().replace('axis xyz="-1.0 0.0 0.0"',
                                                              'axis xyz="1.0 0.0 0.0"')
    bad.write_text(text)
    with pytest.raises(ModelError, match="workpiece-side axis must point -X"):
        load_machine(bad)


def test_a_folder_or_a_file_not_ending_in_urdf_is_not_an_unknown_machine(tmp_path):
    # 'cut ... --machine DIR' or '--machine mill.xml' (a URDF saved as .xml) said "unknown
    # machine 'DIR'; expected one of ...", as if a shipped machine's name were misspelt
    from machinesim.machines import list_machines

    shipped = ", ".join(list_machines())
    folder = tmp_path / "mill"
    folder.mkdir()
    with pytest.raises(ModelError) as raised:
        load_machine(folder)
    assert str(raised.value) == (f"{folder}: is a folder; expected a machine's name "
                                 f"({shipped}) or the path of a .urdf file")
    xml = tmp_path / "mill.xml"
    xml.write_text(GROOVING)
    with pytest.raises(ModelError) as raised:
        load_machine(xml)
    assert str(raised.value) == (f"{xml}: a file whose name does not end in .urdf; expected "
                                 f"a machine's name ({shipped}) or the path of a .urdf file "
                                 "(a URDF saved under another ending: rename it to .urdf)")
    with pytest.raises(ModelError, match="unknown machine 'mill'"):
        load_machine("mill")  # not there (the folder is in tmp_path, not here)
    # '--machine /dev/null' (or a FIFO) was an "unknown machine '/dev/null'" too
    fifo = tmp_path / "mill.fifo"
    os.mkfifo(fifo)
    for path, kind in (("/dev/null", "a character device"), (fifo, "a named pipe (FIFO)")):
        with pytest.raises(ModelError) as raised:
            load_machine(path)
        assert str(raised.value) == (f"{path}: is {kind}, not a regular file; expected a "
                                     f"machine's name ({shipped}) or the path of a .urdf file")


def test_a_xacro_file_is_refused_with_how_to_expand_it(tmp_path):
    # it was taken for a machine's name: "unknown machine 'mill.urdf.xacro'"
    path = tmp_path / "mill.urdf.xacro"
    path.write_text(GROOVING)
    with pytest.raises(ModelError) as raised:
        load_machine(path)
    assert str(raised.value) == (f"{path}: a xacro file; expand it first (xacro "
                                 "mill.urdf.xacro > mill.urdf) and load the .urdf")


def test_a_machine_or_no_name_is_refused_as_what_it_is():
    # str() of each was taken for a name: "unknown machine "Machine('robonano_a0ib',
    # axes=XYZBC)"" for a machine loaded already, "unknown machine 'None'"
    machine = load_machine("robonano_a0ib")
    with pytest.raises(ModelError) as raised:
        load_machine(machine)
    assert str(raised.value) == ("got a Machine (robonano_a0ib), loaded already: use it as it "
                                 "is; expected a machine's name or the path of a .urdf file")
    shipped = ", ".join(list_machines())
    for given, shown in ((None, "NoneType None"), (7, "int 7"),
                         (b"sts_lathe", "bytes b'sts_lathe'")):
        with pytest.raises(ModelError) as raised:
            load_machine(given)
        assert str(raised.value) == (f"expected a machine's name ({shipped}) or the path of a "
                                     f".urdf file, got {shown}")
    # a name as str or as a Path is the same machine
    assert load_machine(Path("sts_lathe")).name == load_machine("sts_lathe").name == "sts_lathe"


def test_a_plain_wheel_install_ships_the_models(tmp_path):
    """Build the wheel, install it (no deps) into a folder, load a model from there."""
    wheel_dir = tmp_path / "wheel"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                    "-q", "-w", str(wheel_dir), str(ROOT)], check=True)
    wheel = next(wheel_dir.glob("machinesim-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    for name in list_machines():
        assert f"machinesim/models/{name}.urdf" in names
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target",
                    str(target), str(wheel)], check=True)
    code = ("import machinesim, machinesim.machines as m; "
            "print(m.models_dir()); print(machinesim.load_machine('sts_lathe').axes)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={"PYTHONPATH": str(target), "PATH": "/usr/bin"},
                         cwd=tmp_path).stdout.split("\n")
    assert Path(out[0]) == target / "machinesim" / "models"
    assert out[1] == "('X', 'Z', 'C')"
    assert models_dir() == MODELS  # the source tree itself uses models/


# --------------------------------------------------------------------- validation at load

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
    "nested_deep": (GROOVING.replace('<link name="base">', '<link name="base">'
                                     + "<a>" * 100_000 + "</a>" * 100_000),
                    ["XML nested 100002 elements deep", "expected at most 64"]),
}


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


def test_the_hand_written_example_machine_cuts_as_the_shipped_one_and_takes_its_errors():
    # docs/machines.md "Your own machine": the 3-axis example cuts the grooves example as
    # grooving_4axis does (the same 20 um V grooves), and with the workpiece set 5 um high
    # each groove is 25 um deep: a V of 90 deg removes depth^2 per length, (25/20)^2 more
    from machinesim.cutting import cut
    from machinesim.nc import read_program

    examples = ROOT / "models" / "examples"
    program = read_program(examples / "grooves.nc")
    own, shipped = load_machine(examples / "mill3.urdf"), load_machine("grooving_4axis")
    assert own.axes == ("X", "Y", "Z")
    volumes = [cut(program, machine, "v:90", "block:10x10x2", errors=errors,
                   start=machine.home)[1].removed_volume_m3
               for machine, errors in ((shipped, None), (own, None),
                                       (own, examples / "mill3_errors.toml"))]
    # the two kinematic chains round differently: 5e-12 of the volume apart, measured
    assert volumes[1] == pytest.approx(volumes[0], rel=2e-11, abs=0.0)
    assert volumes[2] == pytest.approx(volumes[0] * (25 / 20) ** 2, rel=1e-9, abs=0.0)


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


def test_a_cyclic_urdf_fails_fast_instead_of_hanging(tmp_path):
    """Every link in one ring: no root to start from, and the walk up never ends."""
    links = "".join(f'<link name="l{i}"/>' for i in range(4))
    joints = "".join(f'<joint name="j{i}" type="fixed"><parent link="l{i}"/>'
                     f'<child link="l{(i + 1) % 4}"/></joint>' for i in range(4))
    path = tmp_path / "ring.urdf"
    path.write_text(f'<robot name="ring">{links}{joints}</robot>')
    with pytest.raises(ModelError, match=r"joints 'j\d' -> 'j\d' -> 'j\d' -> 'j\d' form a cycle"):
        load_machine(path)


def test_a_folder_or_an_unreadable_urdf_is_a_model_error_naming_it(tmp_path):
    folder = tmp_path / "machine.urdf"
    folder.mkdir()
    with pytest.raises(ModelError, match="machine.urdf: is a folder; expected a .urdf file"):
        load_machine(folder)
    binary = tmp_path / "binary.urdf"
    binary.write_bytes(bytes(range(256)))
    with pytest.raises(ModelError, match="binary.urdf: not readable XML"):
        load_machine(binary)


def test_a_pipe_or_a_device_given_as_the_urdf_says_what_it_is(tmp_path):
    # both were "no such URDF file", though ls shows them there
    fifo, link = tmp_path / "pipe.urdf", tmp_path / "zero.urdf"
    os.mkfifo(fifo)
    link.symlink_to(os.devnull)
    with pytest.raises(ModelError) as raised:
        load_machine(fifo)
    assert str(raised.value) == (f"{fifo}: is a named pipe (FIFO), not a regular file; "
                                 "expected a .urdf file")
    with pytest.raises(ModelError) as raised:
        load_machine(link)
    assert str(raised.value) == (f"{link}: links to {os.devnull}, a character device, not a "
                                 "regular file; expected a .urdf file")


def test_a_urdf_edited_after_loading_loads_again(tmp_path):
    path = tmp_path / "edited.urdf"
    path.write_text(GROOVING)
    assert load_machine(path).upper[0] == 0.25
    path.write_text(_in_joint("X", 'upper="0.25"', 'upper="0.125"'))
    os.utime(path, ns=(path.stat().st_atime_ns, path.stat().st_mtime_ns + 10**9))
    assert load_machine(path).upper[0] == 0.125


@pytest.mark.parametrize("name", ["lower", "upper", "resolution", "rapid_rate", "rotary"])
def test_a_machine_array_refuses_a_write_and_the_cache_hands_it_unchanged(name):
    """load_machine hands one cached Machine to every caller: a write into its travel,
    resolution or rates had moved them for every later load (writeable arrays)."""
    import copy
    import pickle

    machine = load_machine("grooving_4axis")
    before = getattr(machine, name).copy()
    with pytest.raises(ValueError, match="read-only"):
        getattr(machine, name)[0] = 7
    with pytest.raises(ValueError, match="read-only"):
        getattr(machine, name)[:] += 1
    again = load_machine("grooving_4axis")
    assert again is machine
    np.testing.assert_array_equal(getattr(again, name), before)
    # a copy or a pickle (a Result sent to a worker) keeps them read-only
    for other in (copy.copy(machine), copy.deepcopy(machine),
                  pickle.loads(pickle.dumps(machine))):
        np.testing.assert_array_equal(getattr(other, name), before)
        with pytest.raises(ValueError, match="read-only"):
            getattr(other, name)[0] = 7


def test_a_urdf_past_the_size_cap_is_refused_and_one_at_it_loads(tmp_path):
    """A 200 MB file took 9 minutes to parse (one long comment, which expat scanned again
    with every 64 kB it was fed) or 3.6 GB of memory (links): a file larger than any
    machine's URDF is refused before it is parsed; one of exactly the cap still loads."""
    from machinesim.urdf import MAX_URDF_BYTES

    head, tail = GROOVING.split("<robot", 1)
    pad = MAX_URDF_BYTES - len(GROOVING.encode()) - len("<!---->")
    at_cap = tmp_path / "at_cap.urdf"
    at_cap.write_text(f"{head}<!--{'x' * pad}--><robot{tail}")
    assert at_cap.stat().st_size == MAX_URDF_BYTES == 16 * 2**20
    assert load_machine(at_cap).axes == ("X", "Y", "Z", "C")
    over = tmp_path / "over.urdf"
    over.write_text(f"{head}<!--{'x' * (pad + 1)}--><robot{tail}")
    with pytest.raises(ModelError) as raised:
        load_machine(over)
    assert str(raised.value) == (f"{over}: larger than 16 MB; a machine's URDF is a few kB "
                                 "(meshes are files of their own): expected at most 16 MB")


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


def _line(text: str, needle: str, occurrence: int = 1) -> int:
    """The line on which the ``occurrence``-th ``needle`` of ``text`` starts."""
    at = -1
    for _ in range(occurrence):
        at = text.index(needle, at + 1)
    return text.count("\n", 0, at) + 1


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
