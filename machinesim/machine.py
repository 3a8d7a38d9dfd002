"""A machine: its axes, its Pinocchio model with error joints, and where the tool edge is on
it with errors (`Machine`). Which machines there are, and loading one by name or path
(`load_machine`), is `machinesim.machines`.
"""

from __future__ import annotations

import functools
import hashlib
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from machinesim import inverse, tolerances
from machinesim._keywords import keywords_checked
from machinesim.errors.turns import each_turn
from machinesim.exceptions import (
    ErrorModelError,
    InputError,
    ModelError,
)
from machinesim.kinematics import (
    DOF_OF_LETTER,
    TOOL_PARAMS,
    WORKPIECE_PARAMS,
    Axis,
    Binding,
    Kinematics,
)
from machinesim.urdf import (
    REQUIRED_FRAMES,
    check_joint_frames,
    check_tool_mount,
    check_zero_pose,
    joint_places,
    read_axes,
    read_urdf,
)
from machinesim.urdf_checks import check_table

#: The tool geometry family's parameter (the nose radius error, m): accepted by every machine,
#: moves no frame (a zero column in `Machine.error_jacobian`).
NOSE_RADIUS_PARAM = "tool_geometry.nose_radius"

#: The Machine arrays made read-only (`_read_only`), copies and pickles included.
_READ_ONLY = ("lower", "upper", "resolution", "rapid_rate", "rotary")


def _read_only(values) -> np.ndarray:
    """``values`` as a new array that refuses writes."""
    array = np.array(values)
    array.flags.writeable = False
    return array


class Machine:
    """A machine model: its axes, its Pinocchio model with error joints, and its kinematics.

    Build with `load_machine`. Nothing here holds an error model: every method takes one
    (an `machinesim.errors.ErrorModel`, or None for the nominal machine).
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        lines: dict[str, list[int]] = {}
        root = read_urdf(self.path, lines)
        self.name = root.get("name") or self.path.stem
        self._urdf_root = root
        self._axes = read_axes(root, self.path, lines)
        check_table(root, self.path, self._axes, lines)
        self.axes: tuple[str, ...] = tuple(a.letter for a in self._axes)
        self.kin = Kinematics(root, self._axes, str(self.path))
        missing = [f for f in REQUIRED_FRAMES if f not in self.kin.frame_id]
        if missing:
            raise ModelError(f"{self.path}: missing frame(s) {', '.join(missing)}; every "
                             f"machine needs {', '.join(REQUIRED_FRAMES)}")
        nominal, zero = self.kin.bind(None), np.zeros(len(self._axes))
        places = joint_places(root, self.path, lines)
        check_zero_pose(self.path, self._axes, self.kin.poses(zero[None], nominal)[0],
                        self.kin.axis_jacobian(zero, nominal), places)
        check_tool_mount(root, self.path, self.kin.frame_pose(
            self.kin.full_q(zero, nominal), "tool_tip", relative_to="tool_mount"))
        check_joint_frames(self.path, self._axes,
                           self.kin.axis_frames(self.kin.full_q(zero, nominal)), places)
        # read-only: load_machine hands one cached machine to every caller, so a write
        # (machine.lower[0] = ...) would move the travel of every later load
        self.lower = _read_only([a.lower for a in self._axes])
        self.upper = _read_only([a.upper for a in self._axes])
        self.resolution = _read_only([a.resolution for a in self._axes])
        self.rapid_rate = _read_only([a.velocity for a in self._axes])
        self.rotary = _read_only([a.rotary for a in self._axes])
        self._bindings: dict[int, Binding] = {}

    def __repr__(self) -> str:
        return f"Machine({self.name!r}, axes={''.join(self.axes)})"

    def __getstate__(self) -> dict:
        # the bindings are a cache by id() of the error models bound on this machine (a
        # lab's truth among them, as a procedure's measurements hold the lab's machine):
        # a pickle (a Result saved or sent to a worker) leaves them out, a copy starts empty
        state = self.__dict__.copy()
        state["_bindings"] = {}
        return state

    def __setstate__(self, state: dict) -> None:
        # numpy gives a pickled or copied array back writeable: read-only again
        self.__dict__.update(state)
        for name in _READ_ONLY:
            if name in state:
                self.__dict__[name] = _read_only(state[name])

    @functools.cached_property
    def digest(self) -> str:
        """SHA-256 of the URDF this machine was built from, as it was read: two machines
        with one digest move alike."""
        return hashlib.sha256(ET.tostring(self._urdf_root)).hexdigest()

    # ----------------------------------------------------------------------------- axes

    def axis(self, letter: str) -> Axis:
        """Description of one axis (side, direction, travel, resolution)."""
        for a in self._axes:
            if a.letter == letter:
                return a
        raise InputError(f"axis {letter!r} is not on {self.name}; it has {''.join(self.axes)}")

    @property
    def home(self) -> np.ndarray:
        """Axis values of the machine's home, its reference position (n_axes,), m and rad:
        Z at the top of its travel, every other axis at zero. ``machinesim cut`` starts a
        program there and G28 returns there, as a real machine's reference return lifts the
        tool clear rather than onto the work zero."""
        home = np.zeros(len(self.axes))
        if "Z" in self.axes:
            z = self.axes.index("Z")
            home[z] = self.upper[z]
        return home

    @property
    def frames(self) -> tuple[str, ...]:
        """Named frames of this machine (base, table, workpiece, tool_mount, tool_tip, ...)."""
        return tuple(self.kin.frame_id)

    @property
    def model(self) -> pin.Model:
        """The Pinocchio model with its error joints (all zero on the nominal machine)."""
        return self.kin.model

    @property
    def urdf_xml(self) -> str:
        """URDF text of the error-augmented model (visuals as in the machine's file)."""
        return self.kin.xml

    def format_axis_value(self, index: int, value: float) -> str:
        """An axis value as messages show it: mm to 1 nm, or deg to 0.00001 deg."""
        return _fmt(self._axes[index], value)

    def limit_violations(self, q) -> list[str]:
        """Descriptions of the axis values in ``q`` (n_axes,) or (N, n_axes) out of travel."""
        q2 = np.atleast_2d(self._check_q(q))
        slack = tolerances.LIMIT_SLACK
        found = []
        for i, a in enumerate(self._axes):
            bad = np.flatnonzero((q2[:, i] < a.lower - slack) | (q2[:, i] > a.upper + slack))
            if bad.size:
                v = q2[bad[0], i]
                found.append(f"axis {a.letter} = {_fmt(a, v)} outside its travel "
                             f"{_fmt(a, a.lower)} .. {_fmt(a, a.upper)}"
                             + (f" (and {bad.size - 1} more)" if bad.size > 1 else ""))
        return found

    # ------------------------------------------------------------------------ kinematics

    def binding(self, errors) -> Binding:
        """The error-joint values of ``errors`` on this machine (checked; cached per model).

        ``errors`` is an `ErrorModel`, None (the nominal machine), or what `as_error_model`
        reads (a dict in the TOML layout, a TOML path), as `Lab` and `cut` take them."""
        from machinesim.errors import ErrorModel, as_error_model

        if errors is not None and not isinstance(errors, ErrorModel):
            errors = as_error_model(errors)
        key = id(errors)
        b = self._bindings.get(key)
        if b is None or b.errors is not errors:
            try:
                b = self.kin.bind(errors)
            except ErrorModelError as exc:  # name the model's file first, then the machine
                if errors is None:
                    raise
                raise errors.misfit(exc, self.name) from None
            if len(self._bindings) > 32:
                self._bindings.clear()
            self._bindings[key] = b
        return b

    def check_errors(self, errors) -> None:
        """Raise ErrorModelError when ``errors`` does not fit this machine."""
        self.binding(errors)

    @keywords_checked
    def tool_pose(self, q, errors=None) -> np.ndarray:
        """Pose of ``tool_tip`` in the ``workpiece`` frame.

        Parameters
        ----------
        q : array_like, shape (n_axes,) or (N, n_axes)
            Axis values in `axes` order, m and rad.
        errors : ErrorModel, optional
            Injected errors; None for the nominal machine.

        Returns
        -------
        wMt : ndarray, shape (4, 4) or (N, 4, 4)
        """
        return self.frame_pose("tool_tip", q, errors)

    def tool_poses(self, runs, errors=None) -> list[np.ndarray]:
        """`tool_pose` of each run of axis values, in one batch: the same poses, bit for
        bit, as a call per run gives (each run's rotations evaluated as its own call would,
        `BatchedKinematics.poses`), without a call's cost per run (thousands of short feed
        segments).

        Parameters
        ----------
        runs : sequence of array_like, each shape (N_i, n_axes)
        errors : ErrorModel, optional

        Returns
        -------
        list of ndarray, each shape (N_i, 4, 4)
        """
        qs = [self._check_q(q) for q in runs]
        if any(q.ndim != 2 for q in qs):
            raise InputError(f"{self.name}: expected each run of axis values of shape "
                             f"(N, {len(self.axes)})", key="runs")
        if not qs:
            return []
        sizes = [len(q) for q in qs]
        out = self.kin.poses(np.concatenate(qs), self.binding(errors), "tool_tip", runs=sizes)
        return np.split(out, np.cumsum(sizes)[:-1])

    @keywords_checked
    def frame_pose(self, frame: str, q, errors=None) -> np.ndarray:
        """Pose of any named frame (e.g. ``probe_tip``) in the workpiece frame; see tool_pose."""
        if frame not in self.kin.frame_id:
            raise InputError(f"frame {frame!r} is not on {self.name}; it has "
                             f"{', '.join(self.frames)}")
        q = self._check_q(q)
        out = self.kin.poses(np.atleast_2d(q), self.binding(errors), frame)
        return out[0] if q.ndim == 1 else out

    def pinocchio_pose(self, q, errors=None, frame: str = "tool_tip") -> np.ndarray:
        """The same pose as `frame_pose`, one configuration at a time by Pinocchio's
        forwardKinematics (the reference the batched evaluator is held against; ``q`` of
        shape (n_axes,) or (N, n_axes), as there)."""
        if frame not in self.kin.frame_id:
            raise InputError(f"frame {frame!r} is not on {self.name}; it has "
                             f"{', '.join(self.frames)}")
        q = self._check_q(q)
        binding = self.binding(errors)
        out = np.array([self.kin.frame_pose(self.kin.full_q(qn, binding), frame)
                        for qn in np.atleast_2d(q)])
        return out[0] if q.ndim == 1 else out

    def parameter_names(self, errors=None) -> tuple[str, ...]:
        """Every error parameter name this machine accepts (tables: those in ``errors``, an
        `ErrorModel` or what `binding` takes)."""
        errors = _error_model(errors)
        names = [*TOOL_PARAMS, NOSE_RADIUS_PARAM, *WORKPIECE_PARAMS]
        for a in self._axes:
            names += [f"location.{a.letter}.{s}" for s in a.location_symbols()]
        if errors is not None:
            for letter, symbols in errors.component.items():
                for symbol, comp in symbols.items():
                    names += [f"component.{letter}.{symbol}[{i}]"
                              for i in range(len(comp.values))]
        return tuple(names)

    @keywords_checked
    def error_jacobian(self, q, errors=None, params=None, *, frame: str = "tool_tip",
                       point=None) -> np.ndarray:
        """Derivative of a frame's pose (or of a point fixed in it) w.r.t. named error parameters.

        Parameters
        ----------
        q : array_like, shape (n_axes,) or (N, n_axes)
            Axis values, SI.
        errors : ErrorModel, optional
            The errors at which to differentiate (None: the nominal machine).
        params : sequence of str, optional
            Parameter names (see `parameter_names`); default: every parameter ``errors``
            carries (``errors.parameters()``).
        frame : str
            Any frame of the machine (`frames`), e.g. ``probe_tip``; default the tool edge.
        point : array_like, shape (3,) or (N, 3), optional
            Coordinates (m) of a point fixed in ``frame`` (one for all configurations, or one
            per row of ``q``). The position rows are then those of that point,
            d(x + R p) = v + omega x (R p), with ``R`` the frame's rotation in the workpiece.
            Default: the frame origin.

        Returns
        -------
        J : ndarray, shape (6, k) or (N, 6, k)
            Rows: the position of the point (m) and the frame rotation (rad, axis-angle), both
            in the workpiece frame; columns: per unit (m or rad) of each parameter.

        Notes
        -----
        Evaluated once per distinct row of ``q``, all rows at once by the batched evaluator
        (`Kinematics.error_jacobians`): rows repeated (one pose read along several
        directions, several points of one frame) cost nothing more.
        `pinocchio_error_jacobian` is the same, pose by pose by Pinocchio's joint Jacobians.
        """
        return self._error_jacobian(q, errors, params, frame, point, batched=True)

    def pinocchio_error_jacobian(self, q, errors=None, params=None, *,
                                 frame: str = "tool_tip", point=None) -> np.ndarray:
        """The same Jacobian as `error_jacobian`, one distinct pose at a time by Pinocchio's
        computeJointJacobians (the reference the batched evaluator is held against; some
        0.12 ms a pose on robonano_a0ib where the batched one takes 2-8 us)."""
        return self._error_jacobian(q, errors, params, frame, point, batched=False)

    def _error_jacobian(self, q, errors, params, frame: str, point, batched: bool):
        if frame not in self.kin.frame_id:
            raise InputError(f"frame {frame!r} is not on {self.name}; it has "
                             f"{', '.join(self.frames)}")
        q = self._check_q(q)
        errors = _error_model(errors)
        binding = self.binding(errors)
        if params is None:
            params = tuple(errors.parameters()) if errors is not None else ()
        columns = [self._param_columns(p, errors) for p in params]
        q2 = np.atleast_2d(q)
        lever = None if point is None else self._check_point(point, q2.shape[0], q.ndim == 2)
        # Constant coefficients form one (nv, k) map applied by a matrix product; only the
        # component errors' coefficients vary with q (evaluated for every row at once).
        const = np.zeros((self.kin.model.nv, len(columns)))
        varying = []
        for c, terms in enumerate(columns):
            for v_index, coeff in terms:
                if callable(coeff):
                    varying.append((c, v_index, coeff(q2)))
                else:
                    const[v_index, c] += coeff
        unique, inverse = np.unique(q2, axis=0, return_inverse=True)
        inverse = inverse.ravel()
        # Only the velocity columns the parameters use are kept of each pose's (6, nv)
        # Jacobian: all nv (107 on robonano_a0ib) had taken 5 kB a pose, 0.5 GB for a plan
        # of 100,000 poses and more than the machine has for a few million.
        used = np.union1d(np.flatnonzero(np.any(const != 0.0, axis=1)),
                          [v_index for _, v_index, _ in varying]).astype(int)
        column = {int(v): j for j, v in enumerate(used)}
        if batched:
            jacs, rot = self.kin.error_jacobians(unique, binding, frame, used)
        else:
            jacs = np.empty((unique.shape[0], 6, used.size))
            rot = np.empty((unique.shape[0], 3, 3))
            for n, qn in enumerate(unique):
                full = self.kin.full_q(qn, binding)
                jacs[n] = self.kin.relative_jacobian(full, frame)[:, used]
                if lever is not None:
                    rot[n] = self.kin.frame_pose(full, frame)[:3, :3]
        out = (jacs @ const[used])[inverse]
        for c, v_index, values in varying:
            out[:, :, c] += jacs[inverse, :, column[v_index]] * values[:, None]
        if lever is not None:
            arm = np.einsum("nij,nj->ni", rot[inverse], lever)
            out[:, :3, :] += np.cross(out[:, 3:, :], arm[:, :, None], axis=1)
        return out[0] if q.ndim == 1 else out

    @keywords_checked
    def axis_jacobian(self, q, errors=None) -> np.ndarray:
        """Derivative of the tool pose (6, n_axes) with respect to the axis values."""
        q = self._check_q(q, batch=False)
        return self.kin.axis_jacobian(q, self.binding(errors))

    def _param_columns(self, name: str, errors) -> list:
        """(velocity index, coefficient) terms: d(error joint)/d(parameter)."""
        vi = self.kin.v_index
        if name == NOSE_RADIUS_PARAM:
            return []  # the nose radius moves no frame: a zero column
        if name in TOOL_PARAMS:
            return [(vi[f"tool_{TOOL_PARAMS[name]}"], 1.0)]
        if name in WORKPIECE_PARAMS:
            return [(vi[f"workpiece_{WORKPIECE_PARAMS[name]}"], 1.0)]
        parts = name.split(".")
        if len(parts) == 3 and parts[0] == "location":
            _, letter, symbol = parts
            ax = self.kin.axis(letter, key=name)
            self.kin.check_location_symbol(ax, symbol)
            dof = DOF_OF_LETTER[symbol[1]]
            if dof == ax.own_dof:
                return [(vi[letter], 1.0)]
            return [(vi[f"{letter}__loc_{dof}"], 1.0), (vi[f"{letter}__inv_{dof}"], -1.0)]
        if len(parts) == 3 and parts[0] == "component" and parts[2].endswith("]"):
            _, letter, rest = parts
            symbol, _, index = rest[:-1].partition("[")
            comp = (errors.component.get(letter, {}).get(symbol) if errors is not None
                    else None)
            # ASCII digits: str.isdigit() passes '²', which int() refused (a ValueError)
            if (comp is None or not re.fullmatch("[0-9]+", index)
                    or int(index) >= len(comp.values)):
                raise ErrorModelError(
                    f"no component error {letter}.{symbol} with an entry {index} in the error "
                    "model; a component parameter needs its table or polynomial there",
                    key=name)
            ax = self.kin.axis(letter, key=name)
            comp = each_turn(comp, ax, name)
            i, k = self.axes.index(letter), int(index)
            sign = float(ax.side)
            dof = DOF_OF_LETTER[symbol[1]]

            def coeff(q2, comp=comp, i=i, k=k, sign=sign):
                return sign * comp.basis(q2[:, i])[:, k]

            return [(vi[f"{letter}__comp_{dof}"], coeff)]
        raise ErrorModelError(
            f"unknown error parameter {name!r}; expected tool.x .. tool.rz, workpiece.x .. "
            "workpiece.gamma, location.<axis>.<symbol> or component.<axis>.<symbol>[i]",
            key=name)

    # ------------------------------------------------------------------------------ inverse

    #: Axis values that put the tool edge at a pose on this model (`machinesim.inverse`).
    axis_values = inverse.axis_values

    # ------------------------------------------------------------------------------ input

    def _check_point(self, point, n: int, batch: bool) -> np.ndarray:
        """``point`` as (n, 3) m: one point for every configuration, or one per row."""
        arr = np.asarray(point, dtype=np.float64)
        if arr.shape == (3,):
            arr = np.broadcast_to(arr, (n, 3))
        elif not (batch and arr.shape == (n, 3)):
            want = "(3,)" + (f" or ({n}, 3)" if batch else "")
            raise InputError(f"expected point coordinates (m) of shape {want}, got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise InputError(f"point coordinates contain NaN or inf: {arr.tolist()}")
        return arr

    def _check_q(self, q, batch: bool = True, key: str = "q") -> np.ndarray:
        from machinesim.metrology._arrays import as_floats

        try:  # numbers only: a bool among them ([True, 0, 0, 0]) was read as 1 m or 1 rad
            arr = as_floats(q, key)
        except InputError:
            raise InputError(f"expected axis values as numbers (m, rad) in the order "
                             f"{''.join(self.axes)}, got {type(q).__name__} {q!r:.60}",
                             key=key) from None
        n = len(self.axes)
        ok = (arr.shape == (n,)) or (batch and arr.ndim == 2 and arr.shape[1] == n)
        if not ok:
            want = f"({n},)" + (f" or (N, {n})" if batch else "")
            raise InputError(f"{self.name} has axes {''.join(self.axes)}: expected axis values "
                             f"of shape {want}, got {arr.shape}", key=key)
        if not np.all(np.isfinite(arr)):  # which one: "axis values contain NaN or inf" said not
            rows = np.atleast_2d(arr)
            bad = tuple(np.argwhere(~np.isfinite(rows))[0])
            row = f" in row {bad[0]} of {len(arr)}" if arr.ndim == 2 else ""
            raise InputError(f"axis values contain NaN or inf: {self.axes[bad[1]]} = "
                             f"{float(rows[bad])!r}{row} ({''.join(self.axes)}, m and rad); "
                             "expected finite numbers", key=key)
        return arr




def _fmt(a: Axis, value: float) -> str:
    return f"{np.degrees(value):.5f} deg" if a.rotary else f"{value * 1e3:.6f} mm"


__all__ = ["NOSE_RADIUS_PARAM", "Machine"]


def _error_model(errors):
    """``errors`` as `Machine.binding` reads it (an `ErrorModel`, a dict in the TOML layout, a
    TOML path), None kept: the methods that read its tables too had taken a dict or a path
    as the model itself and failed on it (``'dict' object has no attribute 'component'``)."""
    from machinesim.errors import ErrorModel, as_error_model

    return errors if errors is None or isinstance(errors, ErrorModel) else as_error_model(errors)
