"""What the kinematics test files (tests/test_kinematics_*.py) share (not collected: no
test_ prefix): plain 4x4 translations and rotations, and a pose comparison."""

from __future__ import annotations

import math

import numpy as np


def trans(v) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = v
    return out


def rot(k: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = (k + 1) % 3, (k + 2) % 3
    out = np.eye(4)
    out[i, i], out[i, j], out[j, i], out[j, j] = c, -s, s, c
    return out


def assert_pose_close(a, b, tol=1e-12):
    """Positions within tol m, rotation matrices within tol (rad, to first order)."""
    np.testing.assert_allclose(a[..., :3, 3], b[..., :3, 3], rtol=0, atol=tol)
    np.testing.assert_allclose(a[..., :3, :3], b[..., :3, :3], rtol=0, atol=tol)
