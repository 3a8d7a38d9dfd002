"""The batched evaluator of `machinesim.kinematics.Kinematics`: many configurations at once.

It walks the same Pinocchio model as `Kinematics`'s one-configuration algorithms (its joint
placements and joint types) over many configurations at once with numpy: poses
(`Kinematics.poses`), poses with their axis Jacobians (`Kinematics.pose_jacobians`) and error
Jacobians (`Kinematics.error_jacobians`). Tests hold it against Pinocchio's
``forwardKinematics`` and joint Jacobians pose by pose (tests/test_kinematics_jacobians.py).
`Kinematics` has these methods from `BatchedKinematics`, a mixin; `machinesim.motion.chords`
walks the same plans (`BatchedKinematics._plan`) with its own runner.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from machinesim.exceptions import ModelError
from machinesim.tolerances import SERIES_MAX_RAD

if TYPE_CHECKING:
    from machinesim.kinematics import Binding

#: Batch size of the vectorised evaluator: small enough that its working arrays stay in cache.
_BLOCK = 8192
#: Batch size of `Kinematics.error_jacobians`: each pose of a block holds every varying
#: joint's axis and origin and the screws, some 1 kB on robonano_a0ib; 1024 poses keep that
#: near 1 MB, whatever the number of poses (as fast as 8192 within the noise).
_JACOBIAN_BLOCK = 1024


def _unit_axis(joint) -> tuple[str, int, float]:
    """(kind 'P' or 'R', direction index, sign) of a one-dof Pinocchio joint along +-X/Y/Z."""
    name = joint.shortname()
    kind = "R" if name.startswith("JointModelR") else "P"
    if name in ("JointModelPX", "JointModelPY", "JointModelPZ",
                "JointModelRX", "JointModelRY", "JointModelRZ"):
        return kind, "XYZ".index(name[-1]), 1.0
    if name in ("JointModelPrismaticUnaligned", "JointModelRevoluteUnaligned"):
        axis = np.asarray(joint.extract().axis, dtype=float)
        k = int(np.argmax(np.abs(axis)))
        if abs(abs(axis[k]) - 1.0) > 1e-15 or np.count_nonzero(axis) != 1:
            raise ModelError(f"joint axis {axis} is not along a machine direction")
        return kind, k, float(np.sign(axis[k]))
    raise ModelError(f"joint type {name} is not a prismatic or revolute joint")


def _cos_sin(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of an array, by Taylor series when every angle is small.

    Error joints turn by micro- to milliradians; numpy's sin and cos cost several times a
    short polynomial, and dominate the batched evaluator otherwise.
    """
    if x.size and np.max(np.abs(x)) < SERIES_MAX_RAD:
        x2 = x * x
        s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)))
        c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)))
        return c, s
    return np.cos(x), np.sin(x)


def _grouped_cos_sin(value: np.ndarray, groups):
    """`batched_kinematics._cos_sin` applied to each group of rows on its own.

    ``groups``: an int ``g`` (the rows are ``g`` blocks of ``M``, fraction after fraction,
    and each of the ``M`` columns is a group) or (starts, sizes) of consecutive rows.
    """
    low, high = float(value.min()), float(value.max())
    if max(-low, high) < SERIES_MAX_RAD:
        return _cos_sin(value)  # every group in series range
    if low >= SERIES_MAX_RAD or high <= -SERIES_MAX_RAD:
        return np.cos(value), np.sin(value)  # no group in series range
    size = np.abs(value)
    if isinstance(groups, int):
        series = size.reshape(groups, -1).max(axis=0) < SERIES_MAX_RAD
        rows = np.tile(series, groups)
    else:
        starts, sizes = groups
        series = np.maximum.reduceat(size, starts) < SERIES_MAX_RAD
        rows = np.repeat(series, sizes)
    if not series.any():
        return np.cos(value), np.sin(value)
    c, s = np.empty_like(value), np.empty_like(value)
    c[rows], s[rows] = _cos_sin(value[rows])
    others = ~rows
    c[others], s[others] = np.cos(value[others]), np.sin(value[others])
    return c, s


def _relative_pose(rw, pw, rt, pt, out: np.ndarray) -> None:
    """Write into ``out`` (N, 4, 4) the poses of a frame (rotations (3, 3, N), positions
    (3, N) in the world: ``rt``, ``pt``) in the workpiece frame (``rw``, ``pw``)."""
    out[:, :3, :3] = np.einsum("kin,kjn->nij", rw, rt)
    out[:, :3, 3] = np.einsum("kin,kn->ni", rw, pt - pw)


def _slope(component, x):
    """d value / d position of a component error at ``x`` (a position or an array of them;
    right slope at a table breakpoint; zero beyond the ends, where the table is held
    constant; a rotary table of a whole turn, `machinesim.errors.turns.each_turn`, read a
    whole number of turns back into it, as its value is)."""
    x = np.asarray(x, dtype=np.float64)
    into = getattr(component, "into", None)
    if into is not None:  # beyond such a table the slope had been zero, not the turn's
        x, component = into(x), component.component
    if component.kind == "poly":
        return np.polynomial.polynomial.polyval(
            x, np.polynomial.polynomial.polyder(component.values))
    pos, val = component.positions, component.values
    i = np.searchsorted(pos, x, side="right") - 1
    inside = (i >= 0) & (i < len(pos) - 1)
    j = np.clip(i, 0, len(pos) - 2)
    return np.where(inside, (val[j + 1] - val[j]) / (pos[j + 1] - pos[j]), 0.0)


class BatchedKinematics:
    """The many-configurations methods of `Kinematics`, which inherits them.

    They read the host's model and indices, all set by `Kinematics.__init__`: ``model``,
    ``frame_id``, ``axes``, ``axis_q``, ``axis_v``, ``_v_of_q``, and ``_plans``, the cache of
    `_plan` (a dict, left out of a pickle by `Kinematics.__getstate__`).
    """

    def _plan(self, frame: str, binding: Binding, keep: frozenset = frozenset()) -> list:
        """Operations that take the world frame to ``frame``, constants folded.

        Each op is ``("C", R, p)`` (a constant transform) or ``("V", kind, k, source)`` (a
        joint whose value varies across configurations: ``source`` is ``("axis", i, offset,
        sign)`` or ``("comp", varying, sign)``). The error joints whose configuration
        indices are in ``keep`` stay joints of constant value, ``("const", value, sign,
        q_index)``, for `error_jacobians` to read their screws.
        """
        key = (id(binding), frame, keep)
        cached = self._plans.get(key)
        if cached is not None and cached[0] is binding:
            return cached[1]
        model = self.model
        varying = {v.q_index: v for v in binding.varying}
        axis_of_q = {int(qi): i for i, qi in enumerate(self.axis_q)}
        fr = model.frames[self.frame_id[frame]]
        chain = []
        j = fr.parentJoint
        while j > 0:
            chain.append(j)
            j = model.parents[j]
        ops: list = []
        acc = pin.SE3.Identity()

        def flush():
            nonlocal acc
            if not ops or not acc.isIdentity(0.0):
                ops.append(("C", acc.rotation.copy(), acc.translation.copy()))
            acc = pin.SE3.Identity()

        for j in reversed(chain):
            acc = acc * model.jointPlacements[j]
            qi = model.idx_qs[j]
            kind, k, sign = _unit_axis(model.joints[j])
            if qi in axis_of_q:
                i = axis_of_q[qi]
                flush()
                ops.append(("V", kind, k, ("axis", i, binding.axis_offset[i], sign)))
            elif qi in varying:
                flush()
                ops.append(("V", kind, k, ("comp", varying[qi], sign)))
            elif qi in keep:
                flush()
                ops.append(("V", kind, k, ("const", float(binding.const[qi]), sign, qi)))
            else:
                value = sign * binding.const[qi]
                if value != 0.0:
                    motion = np.zeros(3)
                    if kind == "P":
                        motion[k] = value
                        acc = acc * pin.SE3(np.eye(3), motion)
                    else:
                        motion[k] = value
                        acc = acc * pin.SE3(pin.exp3(motion), np.zeros(3))
        acc = acc * fr.placement
        flush()
        if len(self._plans) > 64:
            self._plans.clear()
        self._plans[key] = (binding, ops)
        return ops

    @staticmethod
    def _run(ops: list, q: np.ndarray, joints: list | None = None, groups=None
             ) -> tuple[np.ndarray, np.ndarray]:
        """Batched poses: rotations (3, 3, N) and translations (3, N) of the plan's frame.

        With a list ``joints``, each varying joint on the way appends ``(kind, source, axis,
        origin)``: its kind ("P" or "R"), value source (as in `_plan`), and its axis
        direction (3, N) and origin (3, N) in the world frame. With ``groups`` (starts,
        sizes) of consecutive rows, each group's rotations are evaluated as if it were the
        whole batch (`_grouped_cos_sin`).
        """
        n = q.shape[0]
        rot = None
        pos = None
        for op in ops:
            if op[0] == "C":
                c_rot, c_pos = op[1], op[2]
                if rot is None:
                    rot = np.repeat(c_rot[:, :, None], n, axis=2)
                    pos = np.repeat(c_pos[:, None], n, axis=1)
                else:
                    pos = pos + sum(rot[:, k, :] * c_pos[k] for k in range(3) if c_pos[k])
                    if not np.array_equal(c_rot, np.eye(3)):
                        rot = np.stack([sum(rot[:, k, :] * c_rot[k, j] for k in range(3)
                                            if c_rot[k, j]) for j in range(3)], axis=1)
                continue
            _, kind, k, source = op
            if source[0] == "axis":
                _, i, offset, sign = source
                value = sign * (q[:, i] + offset) if offset else sign * q[:, i]
            elif source[0] == "const":
                value = np.float64(source[2] * source[1])
            else:
                _, var, sign = source
                value = (sign * var.sign) * var.component.evaluate(q[:, var.axis])
            if joints is not None:
                joints.append((kind, source, rot[:, k, :].copy(), pos))
            if kind == "P":
                pos = pos + rot[:, k, :] * value
            else:
                i1, i2 = (k + 1) % 3, (k + 2) % 3
                c, s = _cos_sin(value) if groups is None else _grouped_cos_sin(value, groups)
                col1, col2 = rot[:, i1, :], rot[:, i2, :]
                new1 = col1 * c
                new1 += col2 * s
                new2 = col2 * c
                new2 -= col1 * s
                rot[:, i1, :] = new1
                rot[:, i2, :] = new2
        return rot, pos

    def pose_jacobians(self, q: np.ndarray, binding: Binding, frame: str = "tool_tip"
                       ) -> tuple[np.ndarray, np.ndarray]:
        """Poses (N, 4, 4) of ``frame`` in the workpiece frame and their axis Jacobians
        (N, 6, n_axes), for axis values (N, n_axes): `poses` and `axis_jacobian` at once.

        Each varying joint's column is the screw of its axis: along the axis for a slide,
        axis x (frame origin - axis origin) and the axis for a rotation; a joint on the
        workpiece's branch moves the frame by minus that. An axis sums the columns of its own
        joint and of its component errors' joints, those times the error's slope.
        """
        n, n_axes = q.shape[0], len(self.axes)
        tool_joints: list = []
        wp_joints: list = []
        rt, pt = self._run(self._plan(frame, binding), q, tool_joints)
        rw, pw = self._run(self._plan("workpiece", binding), q, wp_joints)
        poses = np.zeros((n, 4, 4))
        poses[:, 3, 3] = 1.0
        _relative_pose(rw, pw, rt, pt, poses)
        jac = np.zeros((6, n_axes, n))
        for joints, side in ((tool_joints, 1.0), (wp_joints, -1.0)):
            for kind, source, axis, origin in joints:
                if kind == "P":
                    linear, angular = axis, None
                else:
                    linear, angular = np.cross(axis, pt - origin, axis=0), axis
                if source[0] == "axis":
                    _, i, _, sign = source
                    factor = side * sign
                else:
                    _, var, sign = source
                    i = var.axis
                    factor = (side * sign * var.sign) * _slope(var.component, q[:, i])
                jac[:3, i] += linear * factor
                if angular is not None:
                    jac[3:, i] += angular * factor
        # world axes -> workpiece axes
        out = np.empty((n, 6, n_axes))
        out[:, :3] = np.einsum("kin,kan->nia", rw, jac[:3])
        out[:, 3:] = np.einsum("kin,kan->nia", rw, jac[3:])
        return poses, out

    def error_jacobians(self, q: np.ndarray, binding: Binding, frame: str,
                        columns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Columns ``columns`` (velocity indices of one-dof joints) of `relative_jacobian`,
        (N, 6, len(columns)), and the rotation of ``frame`` in the workpiece frame (N, 3, 3),
        for axis values (N, n_axes): every configuration at once.

        As `pose_jacobians` does for the axes: each joint's column is the screw of its axis
        (along it for a slide; axis x (frame origin - axis origin) and the axis for a
        rotation), times its sign, minus that on the workpiece's branch. The error joints of
        ``columns`` stay joints of the plan, at their constant values, instead of folding
        into its constant transforms. A column of a joint on neither branch is zero.
        """
        q_of_v = {int(v): qi for qi, v in self._v_of_q.items()}
        keep = frozenset(q_of_v[int(v)] for v in columns) - set(self.axis_q) \
            - {v.q_index for v in binding.varying}
        where = {int(v): c for c, v in enumerate(columns)}
        tool_ops = self._plan(frame, binding, keep)
        wp_ops = self._plan("workpiece", binding, keep)
        n = q.shape[0]
        jac = np.empty((n, 6, len(columns)))
        rot = np.empty((n, 3, 3))
        for start in range(0, n, _JACOBIAN_BLOCK):
            block = q[start:start + _JACOBIAN_BLOCK]
            tool_joints: list = []
            wp_joints: list = []
            rt, pt = self._run(tool_ops, block, tool_joints)
            rw, pw = self._run(wp_ops, block, wp_joints)
            screws = np.zeros((6, len(columns), block.shape[0]))
            for joints, side in ((tool_joints, 1.0), (wp_joints, -1.0)):
                for kind, source, axis, origin in joints:
                    if source[0] == "axis":
                        v, sign = self.axis_v[source[1]], source[3]
                    elif source[0] == "const":
                        v, sign = self._v_of_q[source[3]], source[2]
                    else:
                        v, sign = self._v_of_q[source[1].q_index], source[2]
                    c = where.get(int(v))
                    if c is None:
                        continue
                    if kind == "P":
                        screws[:3, c] += axis * (side * sign)
                    else:
                        screws[:3, c] += np.cross(axis, pt - origin, axis=0) * (side * sign)
                        screws[3:, c] += axis * (side * sign)
            # world axes -> workpiece axes
            stop = start + block.shape[0]
            jac[start:stop, :3] = np.einsum("kin,kcn->nic", rw, screws[:3])
            jac[start:stop, 3:] = np.einsum("kin,kcn->nic", rw, screws[3:])
            rot[start:stop] = np.einsum("kin,kjn->nij", rw, rt)
        return jac, rot

    def poses(self, q: np.ndarray, binding: Binding, frame: str = "tool_tip",
              runs=None) -> np.ndarray:
        """Poses of ``frame`` in the workpiece frame, (N, 4, 4), for axis values (N, n_axes).

        ``runs``: the row counts of consecutive runs of ``q`` (summing to N), each posed as a
        call of its own would pose it, bit for bit (its blocks of `_BLOCK` rows deciding
        the series or ``cos``/``sin`` of each rotation, `_grouped_cos_sin`), in batches of
        about `_BLOCK` rows: many short runs at the cost of one call.
        """
        tool_ops = self._plan(frame, binding)
        wp_ops = self._plan("workpiece", binding)
        n = q.shape[0]
        out = np.zeros((n, 4, 4))
        out[:, 3, 3] = 1.0
        if runs is None:
            for start in range(0, n, _BLOCK):
                block = q[start:start + _BLOCK]
                rt, pt = self._run(tool_ops, block)
                rw, pw = self._run(wp_ops, block)
                _relative_pose(rw, pw, rt, pt, out[start:start + _BLOCK])
            return out
        # the blocks each run's own call would cut it into, then batches of whole blocks
        sizes = [min(_BLOCK, size - start) for size in runs
                 for start in range(0, int(size), _BLOCK)]
        begin = first = 0
        while begin < len(sizes):
            end, rows = begin, 0
            while end < len(sizes) and (end == begin or rows + sizes[end] <= _BLOCK):
                rows += sizes[end]
                end += 1
            block = q[first:first + rows]
            local = np.array(sizes[begin:end])
            groups = (np.concatenate(([0], np.cumsum(local[:-1]))), local)
            rt, pt = self._run(tool_ops, block, groups=groups)
            rw, pw = self._run(wp_ops, block, groups=groups)
            _relative_pose(rw, pw, rt, pt, out[first:first + rows])
            begin, first = end, first + rows
        return out
