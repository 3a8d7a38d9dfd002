"""Rotation matrices, the one place machinesim builds them from angles (rad).

``rot_x``, ``rot_y``, ``rot_z`` take a scalar (-> (3, 3)) or an array of angles (-> (..., 3, 3));
`rotation_xyz` composes ``Rx(alpha) Ry(beta) Rz(gamma)``, the order of the workpiece setting
error (`machinesim.WorkpieceSetting`, paper 002).

>>> import numpy as np
>>> np.round(rot_z(np.pi / 2) @ [1.0, 0.0, 0.0], 12)
array([0., 1., 0.])
"""

from __future__ import annotations

import numpy as np

__all__ = ["rot_x", "rot_y", "rot_z", "rotation_xyz"]


def _rot(angle, i: int, j: int) -> np.ndarray:
    """Rotation by ``angle`` in the plane of axes i -> j (right-handed about the third)."""
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(a.shape + (3, 3))
    k = 3 - i - j
    out[..., k, k] = 1.0
    out[..., i, i], out[..., i, j], out[..., j, i], out[..., j, j] = c, -s, s, c
    return out


def rot_x(angle) -> np.ndarray:
    """Rotation about X by ``angle`` (rad): shape (3, 3), or (..., 3, 3) for an array."""
    return _rot(angle, 1, 2)


def rot_y(angle) -> np.ndarray:
    """Rotation about Y by ``angle`` (rad): shape (3, 3), or (..., 3, 3) for an array."""
    return _rot(angle, 2, 0)


def rot_z(angle) -> np.ndarray:
    """Rotation about Z by ``angle`` (rad): shape (3, 3), or (..., 3, 3) for an array."""
    return _rot(angle, 0, 1)


def rotation_xyz(alpha, beta, gamma) -> np.ndarray:
    """``Rx(alpha) Ry(beta) Rz(gamma)`` (rad), shape (3, 3) or (..., 3, 3)."""
    return rot_x(alpha) @ rot_y(beta) @ rot_z(gamma)
