"""Kinematics of a machine with injected errors, through Pinocchio.

The errors enter the Pinocchio model itself as *error joints*: one-degree-of-freedom joints
(translation or rotation along a machine direction) inserted in the chain, whose values are
the injected errors. Their derivatives are therefore Pinocchio's joint Jacobians, and the
nominal machine is the same model with every error joint at zero. The chain of axis ``i``
(its carriage pose relative to its parent body) is

    linear axis:  M_i * E_i * J_i(q) * C_i(q)^s * E_i^-1
    rotary axis:  M_i * E_i * C_i(q)^s * J_i(q) * E_i^-1

with ``M_i`` the URDF joint placement, ``J_i`` the axis motion, ``E_i = T(e) Rx Ry Rz`` the
location errors (ISO 230-7: offsets and tilts of the axis line; conjugating with it moves the
axis line without moving what the axis carries at zero), and ``C_i(q) = T(t) Rx Ry Rz`` the
component (motion) errors at position ``q``. ``s = +1`` on the tool side and ``-1`` on the
workpiece side, so that every error is the displacement of the tool relative to the workpiece,
as an interferometer on the machine reads it, whichever side carries the axis. Linear-axis
component errors act at the moving carriage's joint origin; rotary-axis component errors act in
the non-rotating frame of the axis, as ISO 230-7 defines error motions. The zero offset of a
rotary axis (``EC0C`` on C) adds to the axis value. The tool setting error sits between
``tool_mount`` and ``tool_tip`` at the nominal edge, the workpiece setting error between
``table`` and ``workpiece``, both as ``T(d) Rx Ry Rz``.

Poses are evaluated two ways, which tests hold against each other and against an independent
chain: Pinocchio's ``forwardKinematics`` (one configuration at a time; Jacobians), here, and a
batched evaluator that walks the same Pinocchio model (its joint placements and joint types) over
many configurations at once with numpy, poses, (`Kinematics.pose_jacobians`) axis Jacobians and
(`Kinematics.error_jacobians`) error Jacobians: `machinesim.batched_kinematics`, whose
`BatchedKinematics` `Kinematics` inherits.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from machinesim.batched_kinematics import BatchedKinematics, _slope
from machinesim.errors.turns import each_turn
from machinesim.exceptions import ErrorModelError, ModelError
from machinesim.units import M_PER_MM, RAD_PER_DEG, quotient_text

#: The six error degrees of freedom, in the order of ``T(t) Rx Ry Rz``.
DOFS = ("tx", "ty", "tz", "rx", "ry", "rz")
#: ISO 230 direction letter of an error symbol -> error degree of freedom.
DOF_OF_LETTER = {"X": "tx", "Y": "ty", "Z": "tz", "A": "rx", "B": "ry", "C": "rz"}
LETTER_OF_DOF = {dof: letter for letter, dof in DOF_OF_LETTER.items()}
#: Canonical parameter names of the tool and workpiece setting errors -> degree of freedom.
TOOL_PARAMS = {"tool.x": "tx", "tool.y": "ty", "tool.z": "tz",
               "tool.rx": "rx", "tool.ry": "ry", "tool.rz": "rz"}
WORKPIECE_PARAMS = {"workpiece.x": "tx", "workpiece.y": "ty", "workpiece.z": "tz",
                    "workpiece.alpha": "rx", "workpiece.beta": "ry", "workpiece.gamma": "rz"}
#: Error joints are unbounded in practice; URDF wants a limit, Pinocchio ignores it here.
_ERROR_JOINT_LIMIT = 1.0e3
#: Travel beyond which a rotary axis is a work spindle rather than a positioning axis, rad
#: (16 turns; the shipped lathe's C runs to 1e5 rad, every table and tilt axis to 2 turns).
SPINDLE_TRAVEL_RAD = 100.0


@dataclass(frozen=True)
class Axis:
    """One NC axis of a machine.

    Attributes
    ----------
    letter : str
        NC letter, also the URDF joint name.
    rotary : bool
        True for a rotary axis (value in rad), False for a linear one (m).
    side : int
        +1 when the axis carries the tool, -1 when it carries the workpiece.
    direction : int
        Machine direction of the axis at zero (0, 1, 2 for X, Y, Z).
    lower, upper : float
        Travel, SI.
    velocity : float
        Rapid rate, m/s or rad/s.
    resolution : float
        Smallest command increment, m or rad.
    """

    letter: str
    rotary: bool
    side: int
    direction: int
    lower: float
    upper: float
    velocity: float
    resolution: float

    @property
    def spindle(self) -> bool:
        """True for a work spindle: a rotary axis whose travel runs to hundreds of turns
        (`SPINDLE_TRAVEL_RAD`; a URDF writes a spindle as a revolute joint with wide
        limits)."""
        return self.rotary and self.upper > SPINDLE_TRAVEL_RAD

    @property
    def own_dof(self) -> str:
        """The error degree of freedom along (linear) or about (rotary) the axis itself."""
        return ("rx", "ry", "rz")[self.direction] if self.rotary else DOFS[self.direction]

    def location_symbols(self) -> tuple[str, ...]:
        """Location-error symbols that change this axis' motion (ISO 230-7 / 230-1).

        A linear axis has only its two tilts (squareness, parallelism): shifting a straight
        axis line, or turning it about itself, moves nothing. A rotary axis has the two offsets
        and two tilts of its line, and its angular zero offset; moving the line along itself
        moves nothing.
        """
        own = self.direction
        others = [k for k in range(3) if k != own]
        tilts = tuple(f"E{'ABC'[k]}0{self.letter}" for k in others)
        if not self.rotary:
            return tilts
        offsets = tuple(f"E{'XYZ'[k]}0{self.letter}" for k in others)
        return offsets + tilts + (f"E{'ABC'[own]}0{self.letter}",)

    def component_symbols(self) -> tuple[str, ...]:
        """The six component (motion) error symbols of this axis, e.g. EXX ... ECX."""
        return tuple(f"E{d}{self.letter}" for d in "XYZABC")


# --------------------------------------------------------------------------- URDF augmentation


def _error_chain(parent: str, prefix: str, dofs, origin: ET.Element | None, root: ET.Element):
    """Append one error joint per dof after ``parent``; return the last child link name."""
    for i, dof in enumerate(dofs):
        name = f"{prefix}_{dof}"
        link = f"{name}__link"
        root.append(ET.Element("link", {"name": link}))
        joint = ET.Element("joint", {"name": name,
                                     "type": "revolute" if dof[0] == "r" else "prismatic"})
        ET.SubElement(joint, "parent", {"link": parent})
        ET.SubElement(joint, "child", {"link": link})
        if i == 0 and origin is not None:
            joint.append(origin)
        axis = ["0", "0", "0"]
        axis["xyz".index(dof[1])] = "1"
        ET.SubElement(joint, "axis", {"xyz": " ".join(axis)})
        ET.SubElement(joint, "limit", {"lower": str(-_ERROR_JOINT_LIMIT),
                                       "upper": str(_ERROR_JOINT_LIMIT),
                                       "effort": "0", "velocity": "0"})
        root.append(joint)
        parent = link
    return parent


def _fixed(root: ET.Element, name: str, parent: str, child: str) -> None:
    joint = ET.SubElement(root, "joint", {"name": name, "type": "fixed"})
    ET.SubElement(joint, "parent", {"link": parent})
    ET.SubElement(joint, "child", {"link": child})


def augment_urdf(root: ET.Element, axes: Mapping[str, Axis]) -> str:
    """URDF text of the machine with error joints inserted (see the module docstring).

    Parameters
    ----------
    root : xml.etree.ElementTree.Element
        The parsed nominal URDF (not modified).
    axes : mapping of str to Axis
        The machine's axes by letter.
    """
    # a new <robot> holding the same links and joints: the original's are not modified
    # (joints are removed from and appended to this one only, their <origin>, <axis> and
    # <limit> appended to new joints as they are), and a deep copy of a CAD export's
    # visuals took 1.5 s of the 7 s load of a 14 MB file of 260,000 of them
    root, nominal = ET.Element(root.tag, root.attrib), root
    root.text = nominal.text
    root.extend(nominal)
    for extra in [e for e in root if e.tag not in ("link", "joint", "material")]:
        root.remove(extra)
    for joint in list(root.findall("joint")):
        name = joint.get("name")
        parent = joint.find("parent").get("link")
        child = joint.find("child").get("link")
        origin = joint.find("origin")
        if name in axes:
            ax = axes[name]
            root.remove(joint)
            last = _error_chain(parent, f"{name}__loc", DOFS, origin, root)
            comp = DOFS if ax.side > 0 else DOFS[::-1]

            def move(after: str, ax=ax, joint=joint, name=name) -> str:
                moved = ET.Element("joint", {"name": name, "type": joint.get("type")})
                link = f"{name}__moved"
                root.append(ET.Element("link", {"name": link}))
                ET.SubElement(moved, "parent", {"link": after})
                ET.SubElement(moved, "child", {"link": link})
                moved.append(joint.find("axis"))
                moved.append(joint.find("limit"))
                root.append(moved)
                return link

            if ax.rotary:
                last = _error_chain(last, f"{name}__comp", comp, None, root)
                last = move(last)
            else:
                last = move(last)
                last = _error_chain(last, f"{name}__comp", comp, None, root)
            last = _error_chain(last, f"{name}__inv", DOFS[::-1], None, root)
            _fixed(root, f"{name}__carriage", last, child)
        elif child in ("tool_tip", "workpiece") and joint.get("type") == "fixed":
            root.remove(joint)
            prefix = "tool" if child == "tool_tip" else "workpiece"
            last = _error_chain(parent, prefix, DOFS, origin, root)
            _fixed(root, f"{prefix}__set", last, child)
    return ET.tostring(root, encoding="unicode")


# ------------------------------------------------------------------------------ error binding


@dataclass(frozen=True)
class _Varying:
    """An error joint whose value follows a component error of an axis."""

    q_index: int  # index in the Pinocchio configuration
    axis: int  # index of the axis in the machine's axis order
    component: object  # ComponentError
    sign: float


class Binding:
    """An error model bound to a machine: the values of every error joint.

    Built by `Kinematics.bind`; the errors are checked against the machine there.
    """

    def __init__(self, kin: Kinematics, errors) -> None:
        self.errors = errors
        self.const = np.zeros(kin.model.nq)
        self.axis_offset = np.zeros(len(kin.axes))
        varying: list[_Varying] = []
        if errors is None:
            self.varying = ()
            return
        qi = kin.q_index
        for dof, value in zip(DOFS[:3], errors.tool.offset, strict=True):
            self.const[qi[f"tool_{dof}"]] = value
        for dof, value in zip(DOFS[3:], errors.tool.rotation, strict=True):
            self.const[qi[f"tool_{dof}"]] = value
        wp = errors.workpiece
        for dof, value in zip(DOFS, (*wp.delta, wp.alpha, wp.beta, wp.gamma), strict=True):
            self.const[qi[f"workpiece_{dof}"]] = value
        for letter, symbols in errors.location.items():
            ax = kin.axis(letter, key=f"location.{letter}")
            for symbol, value in symbols.items():
                kin.check_location_symbol(ax, symbol)
                dof = DOF_OF_LETTER[symbol[1]]
                if dof == ax.own_dof:  # a rotary axis' angular zero offset
                    self.axis_offset[kin.axes.index(letter)] += value
                else:
                    self.const[qi[f"{letter}__loc_{dof}"]] += value
                    self.const[qi[f"{letter}__inv_{dof}"]] -= value
        for letter, symbols in errors.component.items():
            ax = kin.axis(letter, key=f"component.{letter}")
            for symbol, comp in symbols.items():
                kin.check_component(ax, symbol, comp)
                dof = DOF_OF_LETTER[symbol[1]]
                varying.append(_Varying(qi[f"{letter}__comp_{dof}"], kin.axes.index(letter),
                                        each_turn(comp, ax, f"component.{letter}.{symbol}",
                                                  kin.source), float(ax.side)))
            # a rotary axis's errors repeat each turn (`each_turn`): its errors are held to
            # the bound over one turn each way
            lower, upper = ((max(ax.lower, -2 * math.pi), min(ax.upper, 2 * math.pi))
                            if ax.rotary else (ax.lower, ax.upper))
            errors.check_travel(letter, lower, upper, source=kin.source)
        self.varying = tuple(varying)


# ---------------------------------------------------------------------------------- kinematics


class Kinematics(BatchedKinematics):
    """The error-augmented Pinocchio model of one machine, and the algorithms on it: one
    configuration at a time here, many at once (`poses`, `pose_jacobians`,
    `error_jacobians`) from `machinesim.batched_kinematics.BatchedKinematics`.

    Parameters
    ----------
    urdf_root : xml.etree.ElementTree.Element
        The nominal URDF.
    axes : tuple of Axis
        The axes in configuration order.
    source : str
        Where the URDF came from, for messages.
    """

    def __init__(self, urdf_root: ET.Element, axes: tuple[Axis, ...], source: str) -> None:
        self.source = source
        self.axes = tuple(a.letter for a in axes)
        self._axis = {a.letter: a for a in axes}
        self.xml = augment_urdf(urdf_root, self._axis)
        try:
            self.model = pin.buildModelFromXML(self.xml)
        except (RuntimeError, ValueError) as exc:
            raise ModelError(f"{source}: Pinocchio cannot build the model: {exc}") from None
        self.data = self.model.createData()
        self.q_index = {self.model.names[j]: self.model.idx_qs[j]
                        for j in range(1, self.model.njoints)}
        self.v_index = {self.model.names[j]: self.model.idx_vs[j]
                        for j in range(1, self.model.njoints)}
        self._v_of_q = {self.model.idx_qs[j]: self.model.idx_vs[j]
                        for j in range(1, self.model.njoints)}
        self.axis_q = np.array([self.q_index[a] for a in self.axes])
        self.axis_v = np.array([self.v_index[a] for a in self.axes])
        # the frames are links (Pinocchio's BODY frames): a joint may bear a link's name (URDF
        # keeps them apart), and looked up by name alone a fixed joint named "table" made
        # Pinocchio's "Several frames match" ValueError, and one named "probe_tip" gave a
        # machine without that link a probe_tip frame at the joint
        self.frame_id = {}
        for name in ("base", "table", "workpiece", "tool_mount", "tool_tip", "probe_tip"):
            if self.model.existFrame(name, pin.FrameType.BODY):
                self.frame_id[name] = self.model.getFrameId(name, pin.FrameType.BODY)
        self._plans: dict[tuple[int, str, frozenset], tuple[object, list]] = {}

    def __getstate__(self) -> dict:
        # Pinocchio's Data is a workspace every algorithm here fills before it reads it, and
        # it pickles to tens of MB (73 MB for grooving_4axis): a copy gets a fresh one. The
        # plans are a cache by id() of the error models bound (a lab's truth among them),
        # ids that mean nothing in another process: a copy starts without
        state = self.__dict__.copy()
        del state["data"], state["_plans"]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self.data = self.model.createData()
        self._plans = {}

    # ---------------------------------------------------------------- checks of error models

    def axis(self, letter: str, key: str) -> Axis:
        """The axis with NC letter ``letter``; ErrorModelError naming ``key`` when absent."""
        if letter not in self._axis:
            raise ErrorModelError(
                f"axis {letter!r} is not on this machine; it has {', '.join(self.axes)}",
                source=self.source, key=key)
        return self._axis[letter]

    def check_location_symbol(self, ax: Axis, symbol: str) -> None:
        allowed = ax.location_symbols()
        if symbol not in allowed:
            raise ErrorModelError(
                f"{symbol} has no effect on {'rotary' if ax.rotary else 'linear'} axis "
                f"{ax.letter}; location errors that do: {', '.join(allowed)}",
                source=self.source, key=f"location.{ax.letter}.{symbol}")

    def check_component(self, ax: Axis, symbol: str, comp) -> None:
        key = f"component.{ax.letter}.{symbol}"
        if symbol not in ax.component_symbols():
            raise ErrorModelError(
                f"{symbol} is not a component error of axis {ax.letter}; expected one of "
                f"{', '.join(ax.component_symbols())}", source=self.source, key=key)
        span = comp.span()
        slack = 1e-12
        if span is not None and (span[0] < ax.lower - slack or span[1] > ax.upper + slack):
            unit, scale = ("deg", 180.0 / np.pi) if ax.rotary else ("mm", 1e3)
            per_unit = RAD_PER_DEG if ax.rotary else M_PER_MM
            ends = [quotient_text(end, per_unit, 6) for end in span]  # 1e306 m: not inf mm
            raise ErrorModelError(
                f"table positions {ends[0]} .. {ends[1]} {unit} lie outside "
                f"the travel of axis {ax.letter}, {ax.lower * scale:g} .. "
                f"{ax.upper * scale:g} {unit}", source=self.source, key=key)

    def bind(self, errors) -> Binding:
        """Check ``errors`` against this machine and compute its error-joint values."""
        return Binding(self, errors)

    # ------------------------------------------------------------------- one configuration

    def full_q(self, q: np.ndarray, binding: Binding) -> np.ndarray:
        """Pinocchio configuration for axis values ``q`` (n_axes,) under ``binding``."""
        full = binding.const.copy()
        full[self.axis_q] = q + binding.axis_offset
        for v in binding.varying:
            full[v.q_index] = v.sign * v.component.evaluate(np.array([q[v.axis]]))[0]
        return full

    def axis_jacobian(self, q: np.ndarray, binding: Binding, frame: str = "tool_tip"):
        """Jacobian (6, n_axes) of ``frame``'s pose in the workpiece frame w.r.t. the axes.

        Besides each axis joint's own column, an axis drives its component errors: their
        error joints add their columns times the slope of the error at ``q``.
        """
        jac = self.relative_jacobian(self.full_q(q, binding), frame)
        out = jac[:, self.axis_v].copy()
        for v in binding.varying:
            slope = float(_slope(v.component, q[v.axis]))
            out[:, v.axis] += jac[:, self._v_of_q[v.q_index]] * (v.sign * slope)
        return out

    def frame_pose(self, full: np.ndarray, frame: str, relative_to: str = "workpiece"):
        """Pose of ``frame`` in ``relative_to`` (4, 4) by Pinocchio's forwardKinematics."""
        pin.framesForwardKinematics(self.model, self.data, full)
        a = self.data.oMf[self.frame_id[relative_to]]
        b = self.data.oMf[self.frame_id[frame]]
        return (a.actInv(b)).homogeneous

    def axis_frames(self, full: np.ndarray) -> dict[str, np.ndarray]:
        """Orientation (3, 3) of each axis joint's frame in the workpiece frame, by letter,
        at the Pinocchio configuration ``full`` (its joint frame before the axis moves)."""
        pin.framesForwardKinematics(self.model, self.data, full)
        w_rot = self.data.oMf[self.frame_id["workpiece"]].rotation
        return {a: w_rot.T @ self.data.oMi[self.model.getJointId(a)].rotation
                for a in self.axes}

    def relative_jacobian(self, full: np.ndarray, frame: str = "tool_tip") -> np.ndarray:
        """Jacobian (6, nv) of ``frame``'s pose in the workpiece frame, expressed there.

        Rows: the velocity of the frame origin, then the angular velocity, both relative to
        the workpiece and in workpiece axes. Pinocchio gives each branch's Jacobian in the
        world; a workpiece-side joint moves the tool relative to the workpiece by minus the
        motion of the workpiece at the tool point.
        """
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, full)
        pin.updateFramePlacements(model, data)
        wid, tid = self.frame_id["workpiece"], self.frame_id[frame]
        jt = pin.getFrameJacobian(model, data, tid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        jw = pin.getFrameJacobian(model, data, wid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        ow, ot = data.oMf[wid], data.oMf[tid]
        lever = ot.translation - ow.translation
        jw_at_tool = jw.copy()
        jw_at_tool[:3] += np.cross(jw[3:].T, lever).T
        rel = jt - jw_at_tool
        wr = ow.rotation.T
        return np.vstack((wr @ rel[:3], wr @ rel[3:]))
