"""Hostile machine files that the structural checks let through, as a user writes them: each
loads as the machine it describes, or is refused naming where."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from machinesim.errors import ErrorModel
from machinesim.machines import load_machine, models_dir

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
