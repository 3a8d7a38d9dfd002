"""Where a machine's tool points are, for many axis vectors at once: `ToolPaths`.

The chord rule (`machinesim.motion.chords`) evaluates the path of every tool point at the
samples of many moves in one batch. `ToolPaths` walks the machine's kinematic plan (its
`Kinematics` plan from the tool tip and from the workpiece, with the machine's errors
bound) with the operations of the batched evaluator of `machinesim.batched_kinematics`, in
the same order, so each position is the same float64 number as `Machine.tool_pose` gives;
constants are folded (a product with an exact 0 or 1, a sum with an exact 0 are skipped),
which can only change the sign of a zero. It also lists what of the bound error model bends
or steps the path: the tables' corners, the whole-turn tables that wrap, the axes with
polynomial errors and their degrees.
"""

from __future__ import annotations

import numpy as np

from machinesim.batched_kinematics import _grouped_cos_sin

__all__ = ["ToolPaths"]


# ------------------------------------------------------------------- folded arithmetic
# A value is a Python float (the same for every row) or an ndarray (one per row).


def _mul(a, b):
    if type(a) is float:
        a, b = b, a
    if type(b) is float:
        if type(a) is float:
            return a * b
        if b == 0.0:
            return 0.0
        if b == 1.0:
            return a
    return a * b


def _add(a, b):
    if type(a) is float and type(b) is float:
        return a + b
    if type(a) is float and a == 0.0:
        return b
    if type(b) is float and b == 0.0:
        return a
    return a + b


def _sub(a, b):
    if type(a) is float and type(b) is float:
        return a - b
    if type(b) is float and b == 0.0:
        return a
    if type(a) is float and a == 0.0:
        return -b
    return a - b


def _dot(terms):
    """Sum of products in order (numpy's einsum order), exact zero terms skipped."""
    total = None
    for a, b in terms:
        p = _mul(a, b)
        if type(p) is float and p == 0.0:
            continue
        total = p if total is None else _add(total, p)
    return 0.0 if total is None else total


class ToolPaths:
    """Positions of tool points in the workpiece frame for many axis vectors at once.

    Parameters
    ----------
    machine : machinesim.Machine
    errors : ErrorModel or None
    points : ndarray, shape (k, 3)
        Points in the tool_tip frame, m; the first is the edge (origin).
    """

    def __init__(self, machine, errors, points: np.ndarray) -> None:
        binding = machine.binding(errors)
        kin = machine.kin
        self._tool_ops = kin._plan("tool_tip", binding)
        self._wp_ops = kin._plan("workpiece", binding)
        self.points = points
        self.k = len(points)
        self._edge_only = self.k == 1 and not np.any(points)
        # (axis, breakpoints, period) of every error table: the path has a corner where an
        # axis crosses one, which the sub-step midpoints may miss; a rotary axis's table of a
        # whole turn repeats each turn (`machinesim.errors.turns.each_turn`), and so do its
        # breakpoints, its ends among them (period None: the table's own only)
        self.corners = tuple(
            (var.axis, np.asarray(var.component.positions, dtype=np.float64),
             getattr(var.component, "period", None))
            for var in binding.varying
            if getattr(var.component, "kind", None) == "table"
            and (len(var.component.positions) > 2
                 or getattr(var.component, "period", None) is not None))
        # (axis, position, side, period, name) where a table of a whole turn whose values a
        # turn apart differ wraps: the path steps there, and a whole number of turns beyond
        # (side -1: below the table's first position, +1: above its last; `steps.wrap_steps`)
        self.wraps = tuple(
            (var.axis, float(at), side, var.component.period, _name(binding, var))
            for var in binding.varying
            if getattr(var.component, "period", None) is not None
            for at, side in _unclosed(var.component))
        # axes whose errors vary along them as no table does (a polynomial): one chord's
        # midpoint may miss such a path's bow (`_bowed`); a table's corners are checked
        self.smooth_axes = np.array(sorted(
            {var.axis for var in binding.varying
             if getattr(var.component, "kind", None) != "table"}), dtype=np.int64)
        # the highest degree of a polynomial error along each axis (0: none): a path bent by
        # one of degree 3 or more is checked between its midpoints too (`bows.bowed_steps`)
        self.degrees = np.zeros(len(machine.axes), dtype=np.int64)
        for var in binding.varying:
            if getattr(var.component, "kind", None) == "poly":
                degree = len(np.polynomial.polynomial.polytrim(var.component.values)) - 1
                self.degrees[var.axis] = max(int(self.degrees[var.axis]), degree)
        # (axis, table, name) of every error table, to name one where the path steps
        self.tables = tuple(
            (var.axis, var.component, _name(binding, var)) for var in binding.varying
            if getattr(var.component, "kind", None) == "table")

    def positions(self, q: list[np.ndarray], groups, keep_angles: bool = False):
        """x, y, z of every point at every row (each (N,) or (N, k)).

        ``q``: one (N,) array of values per axis. ``groups``: the groups of rows that
        `Machine.tool_pose` would have been given in one call (one block) each, an int
        ``g`` (consecutive groups of ``g`` rows) or (starts, sizes); they decide the
        series/cos choice of rotations. With ``keep_angles``, a fourth item lists the angle
        (N,) of every rotation evaluated.
        """
        n = len(q[0])
        angles = [] if keep_angles else None
        rt, pt = self._run(self._tool_ops, q, groups, angles)
        rw, pw = self._run(self._wp_ops, q, groups, angles)
        d = [_sub(pt[k], pw[k]) for k in range(3)]
        pos = [_dot((rw[k][i], d[k]) for k in range(3)) for i in range(3)]
        if self._edge_only:
            return [np.full(n, p) if type(p) is float else p for p in pos] + [angles]
        out = np.zeros((n, 4, 4))
        for i in range(3):
            for j in range(3):
                out[:, i, j] = _dot((rw[k][i], rt[k][j]) for k in range(3))
            out[:, i, 3] = pos[i]
        p = out[:, :3, :3] @ self.points.T + out[:, :3, 3:4]
        return [p[:, 0, :], p[:, 1, :], p[:, 2, :], angles]

    @staticmethod
    def _run(ops, q, groups, angles):
        """`Kinematics._run` on folded values: rot[i][j] and pos[i] of the plan's frame."""
        rot = pos = None
        for op in ops:
            if op[0] == "C":
                c_rot, c_pos = op[1], op[2]
                if rot is None:
                    rot = [[float(c_rot[i, j]) for j in range(3)] for i in range(3)]
                    pos = [float(c_pos[i]) for i in range(3)]
                    continue
                terms = [k for k in range(3) if c_pos[k]]
                for i in range(3):
                    total = 0.0
                    for k in terms:
                        total = _add(total, _mul(rot[i][k], float(c_pos[k])))
                    pos[i] = _add(pos[i], total)
                if not np.array_equal(c_rot, np.eye(3)):
                    new = [[0.0] * 3 for _ in range(3)]
                    for j in range(3):
                        ks = [k for k in range(3) if c_rot[k, j]]
                        for i in range(3):
                            total = 0.0
                            for k in ks:
                                total = _add(total, _mul(rot[i][k], float(c_rot[k, j])))
                            new[i][j] = total
                    rot = new
                continue
            _, kind, k, source = op
            if source[0] == "axis":
                _, i, offset, sign = source
                value = sign * (q[i] + offset) if offset else sign * q[i]
            else:
                _, var, sign = source
                value = (sign * var.sign) * var.component.evaluate(q[var.axis])
            if kind == "P":
                for i in range(3):
                    pos[i] = _add(pos[i], _mul(rot[i][k], value))
                continue
            i1, i2 = (k + 1) % 3, (k + 2) % 3
            if angles is not None:
                angles.append(value)
            c, s = _grouped_cos_sin(value, groups)
            for i in range(3):
                col1, col2 = rot[i][i1], rot[i][i2]
                rot[i][i1] = _add(_mul(col1, c), _mul(col2, s))
                rot[i][i2] = _sub(_mul(col2, c), _mul(col1, s))
        return rot, pos


def _unclosed(component) -> list[tuple[float, int]]:
    """The ends of a table of a whole turn (or more) whose value differs from the table's a
    turn inside, with the side beyond them where the repeated table is read (-1 below the
    first position, +1 above the last): where it steps."""
    first, last = component.positions[0], component.positions[-1]
    inside = component.component.evaluate(np.array([first + component.period,
                                                    last - component.period]))
    return [(at, side) for at, side, value, there in (
        (first, -1, component.values[0], inside[0]), (last, 1, component.values[-1], inside[1]))
        if value != there]


def _name(binding, var) -> str:
    """The error model's name of a bound component error (``component.C.ECC``)."""
    bound = getattr(var.component, "component", var.component)  # a turn's table: its own
    for letter, symbols in binding.errors.component.items():
        for symbol, component in symbols.items():
            if component is bound:
                return f"component.{letter}.{symbol}"
    return "a table"
