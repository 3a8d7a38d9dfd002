"""What the test files of paper 000 (tests/test_tool_rotation_arm_*.py) share (not
collected: no test_ prefix): the paper's r and e_ys as an error model, and eq 1's
worst-case gain."""

from __future__ import annotations

import numpy as np

from machinesim import ErrorModel, ToolSetting

MM = 1e-3
PAPER_R, PAPER_E = 120.555 * MM, -0.178 * MM


def errors_for(r, e_ys, r0):
    """The paper's two errors as the tool setting of docs/machines.md (tool_mount axes)."""
    return ErrorModel(tool=ToolSetting([0.0, e_ys, -(r - r0)], [0.0, 0.0, 0.0]))


def worst_gain() -> np.ndarray:
    """Largest change of (offset, r, e_ys) per 1 m of bias in every reading of eq 1's fit."""
    t = np.radians([0, 10, 20, 30, 40])
    design = np.column_stack([np.ones(5), 1 - np.cos(t), np.sin(t)])
    return np.abs(np.linalg.pinv(design)).sum(axis=1)
