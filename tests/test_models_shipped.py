"""The shipped URDF models: urdfdom's check_urdf and Pinocchio (with visuals and frames) take
each, the probe and the tool mount where the papers put them, the files are what
models/build_models.py writes, a plain wheel install ships them, the hand-written example
machine cuts as the shipped one, and a loaded machine's arrays are read-only."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from models_helpers import MODELS, ROOT

from machinesim.machines import list_machines, load_machine, models_dir


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
