"""Hostile machine files that the structural checks let through, as a user writes them: each
loads as the machine it describes, or is refused naming where."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError, ModelError
from machinesim.machines import load_machine, models_dir
from machinesim.metrology.instruments import Readout

MILL3 = models_dir() / "examples" / "mill3.urdf"
#: Errors that move the tool and the workpiece through every frame of the chain.
ERRORS = {"tool": {"offset_um": [1.0, 2.0, 3.0], "rotation_urad": [0.0, 0.0, 100.0]},
          "workpiece": {"delta_um": [5.0, 0.0, 0.0], "gamma_urad": 50.0},
          "location": {"X": {"EB0X_urad": 20.0}}}


def _mill3(tmp_path: Path, name: str, old: str, new: str) -> Path:
    text = MILL3.read_text()
    assert old in text
    path = tmp_path / f"{name}.urdf"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize("joint, name", [
    ("table_fixed", "table"), ("tool_mount_fixed", "tool_mount"),
    ("tool_mount_fixed", "base"), ("tool_mount_fixed", "workpiece"),
    ("tool_mount_fixed", "probe_tip")])
def test_a_joint_named_as_a_frame_loads_as_the_machine_with_its_links_frames(joint, name,
                                                                            tmp_path):
    # URDF keeps link and joint names apart: a fixed joint may bear a link's name. The
    # machine's frames are its links; looked up by name alone, a joint named "table" was
    # Pinocchio's ValueError "Several frames match the filter" (an unexpected error, exit 1
    # on the command line), and one named "probe_tip" gave mill3, which has no probe, a
    # probe_tip frame at that joint
    path = _mill3(tmp_path, name, f'<joint name="{joint}"', f'<joint name="{name}"')
    machine, shipped = load_machine(path), load_machine(MILL3)
    assert machine.frames == shipped.frames == ("base", "table", "workpiece", "tool_mount",
                                                "tool_tip")
    errors = ErrorModel.from_dict(ERRORS, "errors")
    q = np.array([0.01, 0.02, 0.03])
    for frame in machine.frames:
        np.testing.assert_array_equal(machine.frame_pose(frame, q, errors),
                                      shipped.frame_pose(frame, q, errors))


@pytest.mark.parametrize("resolution", ["5e-324", "1e-310", "9e-13"])
def test_a_resolution_finer_than_a_picometre_is_refused_naming_its_line(resolution, tmp_path):
    # 5e-324 (a denormal) loaded, and the encoders, which round each reading to the
    # resolution, read Z = 0.1 m as inf (0.1 / 5e-324 overflows; 1e-310 likewise)
    path = _mill3(tmp_path, "fine", '<machinesim:axis joint="Z" resolution="1e-9"/>',
                  f'<machinesim:axis joint="Z" resolution="{resolution}"/>')
    with pytest.raises(ModelError) as info:
        load_machine(path)
    assert str(info.value) == (
        f"{path.resolve()}, line 49: <machinesim:axis joint='Z'> resolution "
        f"{float(resolution)!r} (m); expected at least 1e-12 m (1 pm: finer than any "
        "machine's scale; SI: 1 nm is 1e-9)")


def test_a_picometre_resolution_loads_and_its_encoders_read_to_it(tmp_path):
    path = _mill3(tmp_path, "pm", '<machinesim:axis joint="Z" resolution="1e-9"/>',
                  '<machinesim:axis joint="Z" resolution="1e-12"/>')
    machine = load_machine(path)
    assert machine.resolution.tolist() == [1e-9, 1e-9, 1e-12]
    readout = Readout.of(0.0, float(machine.resolution[2]), False, limit=None)
    # 0.1 m + 0.4 pm reads 0.1 m, 0.1 m + 0.6 pm reads 0.1 m + 1 pm: rounded to the step
    read = readout.read(np.array([0.1 + 0.4e-12, 0.1 + 0.6e-12]), np.random.default_rng(0))
    assert np.abs(read - np.array([0.1, 0.1 + 1e-12])).max() < 3e-17  # 2 ulps of 0.1


def test_an_include_is_refused_as_not_urdf(tmp_path):
    # the URDF parser drops <include>, and the links and joints of its file with it: it
    # loaded without a word where the machine needed none of them, and otherwise as
    # "child link ... does not exist", neither saying why
    path = _mill3(tmp_path, "include", '<link name="base"/>',
                  '<include filename="parts.urdf"/><link name="base"/>')
    with pytest.raises(ModelError) as info:
        load_machine(path)
    assert str(info.value) == (
        f"{path.resolve()}: <include filename='parts.urdf'> is not URDF: its parser drops it, "
        "and the links and joints of that file with it (they loaded missing, or without a "
        "word); write them into this file, or, for a xacro file's <xacro:include>, expand it "
        "first (xacro include.urdf > machine.urdf) and load the URDF")


@pytest.mark.parametrize("data, said", [(b"", "0 bytes"), (b"\n  \r\n", "5 bytes, all blank")])
def test_an_empty_urdf_says_it_is_empty(data, said, tmp_path):
    # was expat's "not readable XML (no element found: line 1, column 0)"
    path = tmp_path / "empty.urdf"
    path.write_bytes(data)
    with pytest.raises(ModelError) as info:
        load_machine(path)
    assert str(info.value) == (f"{path.resolve()}: the file is empty ({said}); expected a URDF, "
                               "<robot name=...> holding the machine's links and joints")


def test_axis_values_with_nan_or_inf_name_the_axis_and_row():
    # "axis values contain NaN or inf", naming neither the axis nor the row of many
    machine = load_machine("grooving_4axis")
    with pytest.raises(InputError) as info:
        machine.tool_pose([0.0, np.nan, 0.0, 0.0])
    assert info.value.key == "q"
    assert str(info.value) == ("key 'q': axis values contain NaN or inf: Y = nan (XYZC, m and "
                               "rad); expected finite numbers")
    with pytest.raises(InputError, match=r"C = inf in row 1 of 2 \(XYZC, m and rad\)"):
        machine.limit_violations([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, np.inf]])


def test_axis_values_that_are_bools_are_refused():
    # tool_pose([True, 0, 0, 0]) read True as X = 1 m: numbers only (as_floats), through
    # each method that takes axis values (Machine._check_q)
    machine = load_machine("grooving_4axis")
    said = "key 'q': expected axis values as numbers (m, rad) in the order XYZC, got "
    for q in ([True, 0, 0, 0], (0.0, np.bool_(False), 0.0, 0.0),
              np.array([True, False, False, False]), [10**400, 0, 0, 0]):
        with pytest.raises(InputError) as info:
            machine.tool_pose(q)
        assert str(info.value).startswith(said) and info.value.key == "q"
    with pytest.raises(InputError, match="expected axis values as numbers"):
        machine.limit_violations([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, True]])
    with pytest.raises(InputError, match="expected axis values as numbers"):
        machine.frame_pose("tool_tip", [0, 0, 0, False])
    # numbers of any kind are taken as before: X = 1 m as an int, a float, a numpy int
    for q in ([1, 0, 0, 0], [1.0, 0.0, 0.0, 0.0], np.array([1, 0, 0, 0])):
        assert np.array_equal(machine.tool_pose(q), machine.tool_pose([1.0, 0.0, 0.0, 0.0]))



@pytest.mark.parametrize("upper, resolution, said", [
    ("1e-10", "1e-9", "upper=1e-10> (m) spans 1e-10 m, less than one step of the axis' "
                      "resolution 1e-09 m"),
    ("5e-5", "1e-4", "upper=5e-05> (m) spans 5e-05 m, less than one step of the axis' "
                     "resolution 0.0001 m")])
def test_a_travel_shorter_than_one_resolution_step_is_refused_at_its_limit(
        upper, resolution, said, tmp_path):
    # Z travel 0 .. 0.1 nm on a 1 nm scale loaded, and no command moves it a step: a target
    # rounds to 0 or to 1 nm, beyond its travel. Refused at the <limit>'s line (37), naming
    # the span, the resolution and the resolution's line (49)
    text = MILL3.read_text().replace('lower="-0.05" upper="0.1"', f'lower="0" upper="{upper}"')
    text = text.replace('<machinesim:axis joint="Z" resolution="1e-9"/>',
                        f'<machinesim:axis joint="Z" resolution="{resolution}"/>')
    path = tmp_path / "short.urdf"
    path.write_text(text)
    with pytest.raises(ModelError) as info:
        load_machine(path)
    assert str(info.value) == (
        f"{path.resolve()}, line 37: joint 'Z': <limit lower=0.0 {said} "
        f"({path.resolve()}, line 49): no command moves it; expected a travel of at least one "
        "step (lengths in m, angles in rad)")


def test_a_travel_of_exactly_one_step_loads(tmp_path):
    path = _mill3(tmp_path, "one", 'lower="-0.05" upper="0.1"', 'lower="0" upper="1e-9"')
    machine = load_machine(path)
    assert machine.upper[2] - machine.lower[2] == machine.resolution[2] == 1e-9


def _scaled_mill3(tmp_path: Path, name: str, k: float) -> Path:
    """mill3 with every origin, limit and velocity times ``k``: a machine of the same shape."""
    import re

    def times(match):
        return f'{match.group(1)}="{float(match.group(2)) * k:g}"'

    text = re.sub(r'(lower|upper|velocity)="([-0-9.e]+)"', times, MILL3.read_text())
    text = re.sub(r'<origin xyz="([^"]+)"', lambda m: '<origin xyz="' + " ".join(
        f"{float(v) * k:g}" for v in m.group(1).split()) + '"', text)
    path = tmp_path / f"{name}.urdf"
    path.write_text(text)
    return path


def test_a_machine_written_in_millimetres_loads_with_a_warning(tmp_path):
    # a 7.5 x 5 x 3.75 mm stage written in mm, every number under 10 (X -3.75 .. 3.75,
    # origins up to 7.5, velocities 0.625): it passed every check (travel within 10 m, the
    # zero pose and directions kept by a uniform scale) and loaded 1000 times too large, X
    # travelling 7.5 m. Its longest travel, beyond 1 m, is now a warning at X's <limit>
    # (line 23); the same stage in m loads without one, as the shipped machines do
    import warnings

    from machinesim.exceptions import MachineSimWarning

    path = _scaled_mill3(tmp_path, "mm", 1e3 / 40)
    with pytest.warns(MachineSimWarning) as caught:
        machine = load_machine(path)
    assert machine.upper.tolist() == [3.75, 2.5, 2.5]
    [message] = [str(w.message) for w in caught]
    assert message == (
        f"{path.resolve()}, line 23: joint 'X': <limit lower=-3.75 upper=3.75> gives X a "
        "travel of 7.5 m, the longest of the machine's linear axes (the shipped machines "
        "travel 0.5 m at most). URDF lengths are metres: a machine written in millimetres "
        "loads 1000 times too large, its origins and rapid rates with it, and a program in mm "
        "never leaves its travel. If these are millimetres, write every length in m (3.75 mm "
        "is 0.00375) and velocities in m/s")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        small = load_machine(_scaled_mill3(tmp_path, "m", 1 / 40))  # the stage in m
        assert small.upper.tolist() == [0.00375, 0.0025, 0.0025]
        for name in ("grooving_4axis", "planer_4axis", "robonano_a0ib", "robonano_ui",
                     "sts_lathe"):
            load_machine(models_dir() / f"{name}.urdf")
