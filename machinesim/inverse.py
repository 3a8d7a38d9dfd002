"""Inverse kinematics: the axis values that put a machine's tool edge at a requested pose
(`Machine.axis_values`), by Newton steps on its kinematic chain: the edge position first,
the orientation (the whole of it, or the tool's axis alone) in the null space of the
position task, and what the axes cannot produce reported, not hidden.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from machinesim import tolerances
from machinesim._keywords import keywords_checked
from machinesim.exceptions import AxisLimitError, InputError, UnreachableError
from machinesim.rotations import not_rigid, rotation_log
from machinesim.tolerances import IK_SINGULAR, IK_WEAK_TURN

#: Poses solved together by `axis_values` (its working arrays, ~1 kB a pose, stay small for
#: programs of a million blocks).
IK_BATCH = 8192
#: Random poses within the travel on which `turn_rank` counts the directions the axes turn
#: the tool in; a singular pose is a set of measure zero, so one would do; the most of 16.
GENERIC_POSES = 16
#: Turn (rad) of the rotary axes, times 1, 2, 3 ... in axis order, from a singular pose to
#: one near it where the axes turn the tool in as many directions as at a generic pose
#: (`_singular_parts`): the lost direction then has a singular value of this order, far
#: above round-off, while the directions kept move by as little.
NEAR_TURN = 1e-3


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
    singular_residual : ndarray, shape (3,) or (N, 3)
        The part of ``rotation_residual`` left at a singularity of the axes (rad, workpiece
        frame): what they turn the tool by at the poses around (as many directions as at a
        generic pose, `turn_rank`) but not at this one, e.g. A and C one axis at B = 0 on
        robonano_ui. Zero where the pose is not singular: what is left there the machine's
        structure can never match (a tilt on four axes, a roll on five).
    """

    q: np.ndarray
    position_residual: np.ndarray
    rotation_residual: np.ndarray
    unmatched: str
    singular_residual: np.ndarray


@keywords_checked
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

    ``machine`` is a `machinesim.machines.Machine` or the name of a shipped one (anything
    else an InputError, as ``check_limits`` not True or False).

    Raises
    ------
    UnreachableError
        When no axis values reach the position.
    AxisLimitError
        When the solution lies outside the travel (``check_limits``).
    """
    # (imported here: metrology's instruments import the machines, which import this)
    from machinesim.metrology._arrays import as_flag, as_floats
    from machinesim.metrology.instruments import as_machine

    machine = as_machine(machine)
    check_limits = as_flag(check_limits, "check_limits")
    # numbers only: a complex pose had lost its imaginary part with a ComplexWarning, and a
    # pose of texts ("1", "0", ...) was read as numbers
    target = as_floats(wMt, "wMt", "a pose (4 x 4, m)")
    if target.shape[-2:] != (4, 4) or target.ndim not in (2, 3):
        raise InputError(f"expected a pose of shape (4, 4) or (N, 4, 4), got {target.shape}",
                         key="wMt")
    if not np.all(np.isfinite(target)):
        n = int(np.flatnonzero(~np.isfinite(target.reshape(-1, 16)).all(axis=1))[0])
        raise InputError(f"{machine.name}: the requested pose {n} has NaN or inf entries, "
                         f"{np.reshape(target, (-1, 4, 4))[n].tolist()}; expected finite "
                         "numbers (m)", key="wMt")
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
    starts = (None if q_start is None
              else np.atleast_2d(machine._check_q(q_start, key="q_start")))
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
    singular = _singular_parts(machine, binding, qs, rres, turned, axis_only)
    unmatched = _describe_rotations(machine, (rres - singular)[turned], singular[turned])
    if check_limits:
        bad = machine.limit_violations(qs)
        if bad:
            raise AxisLimitError(f"{machine.name}: the requested pose needs " + "; ".join(bad))
    if not batch:
        return AxisSolution(qs[0], pres[0], rres[0], unmatched, singular[0])
    return AxisSolution(qs, pres, rres, unmatched, singular)

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

def turn_rank(machine, axis_only: bool = False) -> int:
    """How many independent directions ``machine``'s axes turn the tool in with its edge
    held (the whole orientation; the tool's axis alone: ``axis_only``) at a generic pose.

    The rank of the rotation Jacobian in the null space of the position task, as
    `axis_values` steps in it (singular values above `IK_WEAK_TURN`, `IK_SINGULAR` for the
    tool axis), the most over `GENERIC_POSES` random poses within the travel (nominal
    machine: errors of micrometres and microradians move no rank). 1 on grooving_4axis (C)
    and planer_4axis (A), 2 on robonano_a0ib (B and C, always square), 3 on robonano_ui
    (A, B, C; 2 at B = 0, where A and C are one axis), 0 on sts_lathe (C is needed for the
    position). A pose with fewer is singular.

    ``machine``: a `machinesim.machines.Machine` or the name of a shipped one (anything
    else an InputError, as ``axis_only`` not True or False).
    """
    # (imported here: metrology's instruments import the machines, which import this)
    from machinesim.metrology._arrays import as_flag
    from machinesim.metrology.instruments import as_machine

    return _turn_rank(as_machine(machine), as_flag(axis_only, "axis_only"))


@functools.lru_cache(maxsize=32)
def _turn_rank(machine, axis_only: bool) -> int:
    rng = np.random.default_rng(0)
    lower = np.maximum(machine.lower, -2 * np.pi)
    upper = np.minimum(machine.upper, 2 * np.pi)
    q = rng.uniform(lower, upper, size=(GENERIC_POSES, len(machine.axes)))
    return int(np.max(_turn_count(_turns(machine, machine.binding(None), q, axis_only),
                                  axis_only)))


def _turns(machine, binding, q, axis_only: bool) -> np.ndarray:
    """The rotation Jacobians (N, 3, n_axes; workpiece frame) in the null space of the
    position task at the axis values ``q`` (N, n_axes): how the axes turn the tool per unit
    of motion with the edge held, as `_solve` steps (across the tool's axis alone:
    ``axis_only``)."""
    pose, jac = machine.kin.pose_jacobians(q, binding)
    jp, jr = jac[:, :3], jac[:, 3:]
    if axis_only:
        z = pose[:, :3, 2]
        jr = jr - np.einsum("ni,nj,nja->nia", z, z, jr)
    return jr @ (np.eye(q.shape[1]) - _pinv(jp) @ jp)


def _turn_count(turns: np.ndarray, axis_only: bool) -> np.ndarray:
    """How many directions (N,) the ``turns`` (`_turns`) turn the tool in by more than the
    cut `_solve` drops below (`IK_WEAK_TURN`; `IK_SINGULAR` for the tool's axis)."""
    strength = np.linalg.svd(turns, compute_uv=False)
    return np.sum(strength > (IK_SINGULAR if axis_only else IK_WEAK_TURN), axis=1)


def _singular_parts(machine, binding, qs, rres, turned, axis_only: bool) -> np.ndarray:
    """The part (N, 3, rad) of each unmatched orientation ``rres`` left by a singularity.

    A pose ``qs`` is singular where its axes turn the tool in fewer directions (singular
    values above the cut `_solve` drops below) than at a generic pose (`turn_rank`). What
    the poses around it turn the tool in is, in the limit, the span of the `turn_rank`
    strongest directions at a pose a little way off (`NEAR_TURN` on each rotary axis);
    the residual's projection on that span is what a generic pose would have matched
    (all of it where the axes turn the tool every way, robonano_ui's A B C), the rest what
    no pose matches. Zero at the poses that are not singular, and at every pose of a
    machine whose turns never lose a direction (grooving_4axis: C turns about Z at every
    pose, and a tilt is left by its structure, not reported as a singularity)."""
    parts = np.zeros_like(rres)
    generic = turn_rank(machine, axis_only)
    left = np.flatnonzero(turned)
    if not generic or not len(left):
        return parts
    left = left[_turn_count(_turns(machine, binding, qs[left], axis_only), axis_only)
                < generic]
    if not len(left):
        return parts
    if generic == (2 if axis_only else 3):  # the poses around turn the tool every way
        parts[left] = rres[left]
        return parts
    near = qs[left] + machine.rotary * np.cumsum(machine.rotary) * NEAR_TURN
    span = np.linalg.svd(_turns(machine, binding, near, axis_only))[0][:, :, :generic]
    parts[left] = np.einsum("nig,njg,nj->ni", span, span, rres[left])
    return parts


def _describe_rotations(machine, structural: np.ndarray, singular: np.ndarray) -> str:
    """What orientation the axes left unmatched (rad residuals, (n, 3), split into what
    their structure never matches and what they leave at a singularity): one sentence per
    set of directions and kind, with the largest angle and how many poses ("" for none)."""
    found: dict[tuple[str, bool], tuple[float, int]] = {}
    for at_singularity, residuals in ((False, structural), (True, singular)):
        for dr in residuals[np.linalg.norm(residuals, axis=1)
                            > tolerances.IK_ANGLE_RAD * 1e3]:
            about = "/".join("XYZ"[k] for k in range(3)
                             if abs(dr[k]) > tolerances.IK_ANGLE_RAD * 1e3)
            largest, count = found.get((about, at_singularity), (0.0, 0))
            found[about, at_singularity] = (max(largest, float(np.max(np.abs(dr)))),
                                            count + 1)
    return "; ".join(
        f"{machine.name} ({''.join(machine.axes)}) cannot turn the tool about {about} "
        f"{'here' if count == 1 else f'at {count} poses'}"
        f"{', at a singularity of its axes (the poses around can)' if at_singularity else ''}"
        f": orientation left unmatched by up to {np.degrees(largest):.6g} deg"
        for (about, at_singularity), (largest, count) in sorted(found.items()))


def singular_note(machine, singular, name) -> str:
    """What a singularity of the axes left unmatched matching the whole orientation (as
    `machinesim.compensation.model_based` does), as one sentence ("" for nothing).

    Parameters
    ----------
    machine : Machine
    singular : array_like, shape (N, 3)
        `AxisSolution.singular_residual` of N poses, rad.
    name : callable
        ``name(row) -> str``: what pose ``row`` is, e.g. ``"line 12"`` of a program.

    Returns
    -------
    str
        Where the poses are (the first ten names, each once: the chords of an arc are
        poses of one line), the largest turn left (urad), where, and about which direction
        (a unit vector in the workpiece frame); empty when no pose is singular.
    """
    singular = np.atleast_2d(singular)
    size = np.linalg.norm(singular, axis=1)
    rows = np.flatnonzero(size > tolerances.IK_ANGLE_RAD * 1e3)
    if not len(rows):
        return ""
    worst = int(rows[np.argmax(size[rows])])
    direction = ", ".join(f"{v:+.4f}" for v in np.round(singular[worst] / size[worst], 4)
                          + 0.0)  # no -0.0000
    names: dict[str, None] = {}
    for r in rows.tolist():
        names.setdefault(name(int(r)))
        if len(names) > 10:
            break
    listed = ", ".join(list(names)[:10]) + (" ..." if len(names) > 10 else "")
    return (f"{machine.name} ({''.join(machine.axes)}) stands at a singularity of its axes at "
            f"{len(rows)} of {len(singular)} pose(s) ({listed}): there they turn the tool "
            f"about a direction by less than {tolerances.IK_WEAK_TURN:g} rad per unit of "
            f"axis motion, which they turn it about at the poses around, and the tool "
            f"orientation is left unmatched by up to {size[worst] * 1e6:.4g} urad "
            f"({name(worst)}) about ({direction}) in the workpiece frame. A pose off the "
            f"singularity is matched")


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


__all__ = ["IK_BATCH", "AxisSolution", "axis_values", "singular_note", "turn_rank"]
