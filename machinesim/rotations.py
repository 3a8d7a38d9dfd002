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

__all__ = ["not_rigid", "rot_x", "rot_y", "rot_z", "rotation_log", "rotation_xyz"]


def not_rigid(poses, tolerance: float) -> np.ndarray:
    """Which of the homogeneous transforms ``poses`` (N, 4, 4) are not rigid motions, (N,)
    bool: a non-finite entry, a rotation block off orthonormal by more than ``tolerance`` (a
    scale, a shear), a mirror (determinant -1), or a last row other than 0 0 0 1."""
    poses = np.asarray(poses, dtype=np.float64)
    finite = np.isfinite(poses).reshape(len(poses), 16).all(axis=1)
    rotation = np.where(finite[:, None, None], poses[:, :3, :3], 0.0)
    error = np.abs(np.einsum("nji,njk->nik", rotation, rotation) - np.eye(3))
    bottom = np.abs(np.where(finite[:, None], poses[:, 3], 0.0) - [0.0, 0.0, 0.0, 1.0])
    return (~finite | (error.reshape(len(poses), 9).max(axis=1) > tolerance)
            | (np.linalg.det(rotation) < 0.0) | (bottom.max(axis=1) > 0.0))


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


#: Past this angle (rad) a rotation's axis is taken from Pinocchio's log3, which handles the
#: half turn, instead of from the skew part of the matrix, whose size sin(angle) vanishes.
_NEAR_HALF_TURN = np.pi - 1e-2


def rotation_log(r) -> np.ndarray:
    """Rotation vectors (axis times angle, rad) of rotation matrices: (3, 3) -> (3,), or
    (..., 3, 3) -> (..., 3); Pinocchio's ``log3`` for many at once.

    The angle is ``atan2(sin, cos)`` of the matrix's skew part and trace, exact to round-off
    down to zero angle, where ``arccos`` of the trace would lose half the digits.
    """
    r = np.asarray(r, dtype=np.float64)
    skew = 0.5 * np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0],
                           r[..., 1, 0] - r[..., 0, 1]], axis=-1)
    sine = np.linalg.norm(skew, axis=-1)
    angle = np.arctan2(sine, 0.5 * (np.trace(r, axis1=-2, axis2=-1) - 1.0))
    factor = np.divide(angle, sine, out=np.ones_like(sine), where=sine > 0.0)
    out = skew * factor[..., None]
    wide = angle > _NEAR_HALF_TURN
    if np.any(wide):
        import pinocchio as pin

        flat_r, flat_out = r.reshape(-1, 3, 3), out.reshape(-1, 3)
        for i in np.flatnonzero(wide.reshape(-1)):
            flat_out[i] = pin.log3(flat_r[i])
    return out
