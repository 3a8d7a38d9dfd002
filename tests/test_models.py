"""The URDF models: standard URDF check, Pinocchio with visuals, generator, packaging."""

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

from machinesim.exceptions import ModelError
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
