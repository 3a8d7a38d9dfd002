"""Inverse kinematics: the axis values that put a machine's tool edge at a requested pose
(`Machine.axis_values`), by Newton steps on its kinematic chain: the edge position first,
the orientation (the whole of it, or the tool's axis alone) in the null space of the
position task, and what the axes cannot produce reported, not hidden.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim import tolerances
from machinesim.exceptions import AxisLimitError, InputError, UnreachableError
from machinesim.rotations import not_rigid, rotation_log
from machinesim.tolerances import IK_SINGULAR, IK_WEAK_TURN

#: Poses solved together by `axis_values` (its working arrays, ~1 kB a pose, stay small for
#: programs of a million blocks).
IK_BATCH = 8192


@dataclass(frozen=True)
class AxisSolution:
    """Axis values that put the tool edge at a requested pose, and what they could not match.

    Attributes
    ----------
    q : ndarray, shape (n_axes,) or (N, n_axes)
        Axis values, SI, in `Machine.axes` order.
    position_residual : ndarray, shape (3,) or (N, 3)
        Requested minus reached edge position, workpiece frame, m.
    rotation_residual : ndarray, shape (3,) or (N, 3)
        Rotation (axis times angle, workpiece frame, rad) from the reached to the requested
        tool orientation: the part of the orientation the machine's axes cannot produce.
    unmatched : str
        Empty when the whole pose was matched, else what was not.
    """

    q: np.ndarray
    position_residual: np.ndarray
    rotation_residual: np.ndarray
    unmatched: str


def axis_values(machine, wMt, errors=None, q_start=None, check_limits: bool = True,
                max_iterations: int = 50, orientation: str = "whole") -> AxisSolution:
    """Axis values that put the tool edge at the pose ``wMt`` on ``machine``.

    The edge position is matched exactly (to `tolerances.IK_POSITION_M`); the orientation
    as far as the axes can produce it, without giving up position (a second task in the
    null space of the position task). What cannot be matched is reported in the result.
    A pose whose orientation task drove Newton off a position the axes reach is solved
    again from its start for the position alone (`_position_first`).

    Parameters
    ----------
    wMt : array_like, shape (4, 4) or (N, 4, 4)
        Requested pose of ``tool_tip`` in ``workpiece``, m.
    errors : ErrorModel, optional
        The model to solve on: None for the nominal machine, or the identified errors
        (model-based compensation).
    q_start : array_like, shape (n_axes,) or (N, n_axes), optional
        Where the search starts (default zeros; for a batch, each solution starts from the
        previous one, pose by pose). Choose it near the wanted branch where several
        exist. Given, the poses are independent and solved all at once (pose ``n`` from
        row ``min(n, len(q_start) - 1)``), some fifty times quicker per pose.
    check_limits : bool
        Raise AxisLimitError when a solution lies outside the travel.
    orientation : {"whole", "tool_axis"}
        ``"whole"``: the tool's whole orientation, in least squares. ``"tool_axis"``:
        only the direction of its Z axis (a rotating tool, or CL data of position and
        tool axis), its roll free; a pose left unmatched is tried again from the start
        with each rotary axis also turned by 90, 180 and 270 deg (from A = 0 on an A-C
        trunnion, C cannot tilt the tool: a tilt the other way needs C turned first),
        keeping the solution that matches best, within the travel first, then nearest
        the start. ``rotation_residual`` is then the tool axis's misalignment.

    Raises
    ------
    UnreachableError
        When no axis values reach the position.
    AxisLimitError
        When the solution lies outside the travel (``check_limits``).
    """
    target = np.asarray(wMt, dtype=np.float64)
    if target.shape[-2:] != (4, 4) or target.ndim not in (2, 3):
        raise InputError(f"expected a pose of shape (4, 4) or (N, 4, 4), got {target.shape}")
    if not np.all(np.isfinite(target)):
        raise InputError("the requested pose has NaN or inf entries")
    batch = target.ndim == 3
    targets = target if batch else target[None]
    bad = not_rigid(targets, tolerances.RIGID_TOL)
    if bad.any():
        n = int(np.flatnonzero(bad)[0])
        raise InputError(
            f"{machine.name}: the requested pose {n} is not a rigid motion (expected an "
            f"orthonormal rotation within {tolerances.RIGID_TOL:g}, no mirror, last row "
            f"0 0 0 1), got {np.round(targets[n], 12).tolist()}", key="wMt")
    if orientation not in ("whole", "tool_axis"):
        raise InputError(f"orientation={orientation!r}: expected 'whole' or 'tool_axis'",
                         key="orientation")
    axis_only = orientation == "tool_axis"
    n_axes = len(machine.axes)
    starts = None if q_start is None else np.atleast_2d(machine._check_q(q_start))
    binding = machine.binding(errors)
    if starts is None:  # each pose from the solution before it
        qs = np.empty((len(targets), n_axes))
        prev = np.zeros((1, n_axes))
        for n, t in enumerate(targets):
            start = prev
            prev = _solve(machine, t[None], binding, start, max_iterations, axis_only)
            if axis_only:
                prev = _turned_starts(machine, t[None], binding, prev, prev, max_iterations)
            qs[n] = prev = _position_first(machine, t[None], binding, prev, start,
                                           max_iterations)
    else:  # independent poses: all at once
        rows = np.minimum(np.arange(len(targets)), len(starts) - 1)
        qs = np.concatenate([
            _solve(machine, targets[k:k + IK_BATCH], binding, starts[rows[k:k + IK_BATCH]],
                        max_iterations, axis_only) for k in range(0, len(targets), IK_BATCH)])
        if axis_only:
            qs = _turned_starts(machine, targets, binding, qs, starts[rows], max_iterations)
        qs = _position_first(machine, targets, binding, qs, starts[rows], max_iterations)
    pres, rres = _residuals(machine, targets, binding, qs, axis_only)
    miss = np.linalg.norm(pres, axis=1)
    if np.any(miss > tolerances.UNREACHABLE_M):
        n = int(np.argmax(miss > tolerances.UNREACHABLE_M))
        raise UnreachableError(
            f"{machine.name}: no axis values reach the edge position "
            f"{np.round(targets[n, :3, 3] * 1e3, 6).tolist()} mm (pose {n}); the best miss "
            f"is {miss[n] * 1e9:.3g} nm")
    turned = np.linalg.norm(rres, axis=1) > tolerances.IK_ANGLE_RAD * 1e3
    unmatched = _describe_rotations(machine, rres[turned])
    if check_limits:
        bad = machine.limit_violations(qs)
        if bad:
            raise AxisLimitError(f"{machine.name}: the requested pose needs " + "; ".join(bad))
    if not batch:
        return AxisSolution(qs[0], pres[0], rres[0], unmatched)
    return AxisSolution(qs, pres, rres, unmatched)

def _residuals(machine, targets, binding, q, axis_only: bool = False
               ) -> tuple[np.ndarray, np.ndarray]:
    """Position (N, 3, m) and rotation (N, 3, rad) left between the poses ``targets``
    and those the axis values ``q`` reach (of the tool's Z axis alone: ``axis_only``)."""
    pose = machine.kin.poses(q, binding)
    return (targets[:, :3, 3] - pose[:, :3, 3],
            _turn_between(pose[:, :3, 2], targets[:, :3, 2]) if axis_only else
            rotation_log(targets[:, :3, :3] @ np.swapaxes(pose[:, :3, :3], 1, 2)))

def _turned_starts(machine, targets, binding, qs, starts, max_iterations) -> np.ndarray:
    """``qs`` (N, n_axes), with each pose whose tool axis is left unmatched solved again
    from its start with the rotary axes turned by multiples of 90 deg; the best match
    kept: the tool axis nearest, within the travel first, then nearest the start."""
    rotary = np.flatnonzero(machine.rotary)
    rres = _residuals(machine, targets, binding, qs, True)[1]
    left = np.flatnonzero(np.linalg.norm(rres, axis=1) > tolerances.IK_ANGLE_RAD * 1e3)
    if not len(rotary) or not len(left):
        return qs
    qs = qs.copy()
    turns = np.array(np.meshgrid(*[np.arange(4)] * len(rotary))).reshape(len(rotary), -1).T
    for n in left:
        tries = np.repeat(starts[n][None], len(turns), axis=0)
        tries[:, rotary] += turns * (np.pi / 2)
        found = _solve(machine, np.repeat(targets[n][None], len(turns), axis=0), binding,
                            tries, max_iterations, True)
        found = np.vstack([qs[n][None], found])
        p, r = _residuals(machine, np.repeat(targets[n][None], len(found), axis=0), binding,
                               found, True)
        miss = np.where(np.linalg.norm(p, axis=1) <= tolerances.UNREACHABLE_M,
                        np.linalg.norm(r, axis=1), np.inf)
        if not np.isfinite(miss.min()):
            continue
        matched = miss <= miss.min() + tolerances.IK_ANGLE_RAD * 1e3
        inside = np.array([not machine.limit_violations(q[None]) for q in found])
        pick = matched & inside if np.any(matched & inside) else matched
        distance = np.linalg.norm(found - starts[n], axis=1)
        qs[n] = found[np.flatnonzero(pick)[np.argmin(distance[pick])]]
    return qs

def _position_first(machine, targets, binding, qs, starts, max_iterations) -> np.ndarray:
    """``qs`` (N, n_axes), with each pose whose position misses by more than
    `tolerances.UNREACHABLE_M` solved again from its start (``starts``, (N, n_axes)) for the
    position alone, where that reaches it: the orientation task can drive Newton off a
    position the axes reach (grooving_4axis, its tool axis tilted 7 mrad by errors and only
    C to turn, matching the tool axis alone: C jumped by pi each step and X, Y doubled, a
    "best miss" of 2e7 m), and the position comes first. The orientation is then left
    unmatched and reported."""
    miss = np.linalg.norm(_residuals(machine, targets, binding, qs)[0], axis=1)
    off = np.flatnonzero(miss > tolerances.UNREACHABLE_M)
    if not len(off):
        return qs
    found = _solve(machine, targets[off], binding, starts[off], max_iterations, orient=False)
    reached = np.linalg.norm(_residuals(machine, targets[off], binding, found)[0],
                             axis=1) <= tolerances.UNREACHABLE_M
    qs = qs.copy()
    qs[off[reached]] = found[reached]
    return qs


def _solve(machine, targets, binding, q, max_iterations, axis_only: bool = False,
           orient: bool = True) -> np.ndarray:
    """Newton steps from ``q`` (N, n_axes) towards ``targets`` (N, 4, 4), all at once:
    position first, orientation in the null space of the position task (of the tool's
    Z axis alone, its roll free: ``axis_only``; none: ``orient=False``). A pose stops when
    its position misses by less than `tolerances.IK_POSITION_M` and its last step was
    below `tolerances.IK_ANGLE_RAD`."""
    q = np.array(q, dtype=np.float64)
    eye = np.eye(q.shape[1])
    active = np.arange(len(q))
    kin = machine.kin
    for _ in range(max_iterations):
        if len(active) == 1:  # Pinocchio's own evaluation is quicker for one pose
            full = kin.full_q(q[active[0]], binding)
            pose = kin.frame_pose(full, "tool_tip")[None]
            jac = kin.axis_jacobian(q[active[0]], binding)[None]
        else:
            pose, jac = kin.pose_jacobians(q[active], binding)
        dp = targets[active, :3, 3] - pose[:, :3, 3]
        jp, jr = jac[:, :3], jac[:, 3:]
        if axis_only:  # turns about the tool's own axis neither help nor count
            z = pose[:, :3, 2]
            dr = _turn_between(z, targets[active, :3, 2])
            jr = jr - np.einsum("ni,nj,nja->nia", z, z, jr)
        else:
            dr = rotation_log(targets[active, :3, :3] @ np.swapaxes(pose[:, :3, :3], 1, 2))
        jp_pinv = _pinv(jp)
        step = np.einsum("nap,np->na", jp_pinv, dp)
        if orient:
            null = eye - jp_pinv @ jp
            rest = dr - np.einsum("nra,na->nr", jr, step)
            # matching the whole orientation, a direction that turns the tool by less than
            # IK_WEAK_TURN per unit of axis motion is left unmatched (reported), not chased
            # by turns beyond all proportion (A against C near B = 0 on robonano_ui)
            weak = IK_SINGULAR if axis_only else IK_WEAK_TURN
            step += np.einsum("nar,nr->na", _pinv(jr @ null, weak), rest)
        q[active] += step
        done = ((np.linalg.norm(dp, axis=1) < tolerances.IK_POSITION_M)
                & (np.linalg.norm(step, axis=1) < tolerances.IK_ANGLE_RAD))
        active = active[~done]
        if not len(active):
            break
    return q

def _describe_rotations(machine, residuals: np.ndarray) -> str:
    """What orientation the axes left unmatched (rad residuals, (n, 3)): one sentence
    per set of directions, with the largest angle and how many poses ("" for none)."""
    found: dict[str, list] = {}
    for dr in residuals:
        about = "/".join("XYZ"[k] for k in range(3)
                         if abs(dr[k]) > tolerances.IK_ANGLE_RAD * 1e3)
        largest, count = found.get(about, (0.0, 0))
        found[about] = (max(largest, float(np.max(np.abs(dr)))), count + 1)
    return "; ".join(
        f"{machine.name} ({''.join(machine.axes)}) cannot turn the tool about {about} "
        f"{'here' if count == 1 else f'at {count} poses'}: orientation left unmatched by "
        f"up to {np.degrees(largest):.6g} deg"
        for about, (largest, count) in sorted(found.items()))


def _turn_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotations (N, 3; axis times angle, rad) that turn the unit vectors ``a`` (N, 3)
    onto ``b`` by the shortest way (about ``a x b``; opposite vectors about an axis normal
    to ``a``)."""
    cross = np.cross(a, b)
    sine = np.linalg.norm(cross, axis=1)
    angle = np.arctan2(sine, np.einsum("ni,ni->n", a, b))
    axis = np.zeros_like(cross)
    turned = sine > 0.0
    axis[turned] = cross[turned] / sine[turned, None]
    opposite = ~turned & (angle > np.pi / 2)
    if np.any(opposite):  # any axis normal to a will do
        helper = np.where(np.abs(a[opposite, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        normal = np.cross(a[opposite], helper)
        axis[opposite] = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    return axis * angle[:, None]


def _pinv(a: np.ndarray, cut: float = IK_SINGULAR) -> np.ndarray:
    """Pseudo-inverses of matrices (..., m, n) with the absolute singular-value cut-off
    ``cut`` (default `IK_SINGULAR`)."""
    u, s, vt = np.linalg.svd(a, full_matrices=False)
    inv = np.divide(1.0, s, out=np.zeros_like(s), where=s > cut)
    return (np.swapaxes(vt, -1, -2) * inv[..., None, :]) @ np.swapaxes(u, -1, -2)


__all__ = ["IK_BATCH", "AxisSolution", "axis_values"]
