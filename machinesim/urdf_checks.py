"""What a machinesim URDF's axes and nominal machine must satisfy, and where a file that
does not is refused.

The checks a machine file passes as it loads (`machinesim.urdf`, `machinesim.machines`),
so that a bad file is a located `ModelError` (file, line, joint or link, value, what was
expected), never a hang or a traceback: `_limits`, an axis's travel and a plausible rapid
rate (rotary limits that read as degrees load with a warning); `check_table`, the table on
the workpiece's side, moved by its linear axes and by no axis of the tool's; and, once
Pinocchio has the model, `check_zero_pose`, the nominal machine at zero against the
conventions of docs/machines.md (the edge at the workpiece origin, each axis moving the tool
along or about its direction), `check_joint_frames`, each axis joint's frame parallel to the
machine axes, and `check_tool_mount`, tool_tip rigidly on tool_mount and parallel to it, the
frame the tool setting error is given in. An axis joint's name, type and direction are
checked as `machinesim.urdf.read_axes` reads them. The file's structure (`check_tree`), its
size and link-count limits and the readers of URDF numbers are
`machinesim.urdf_structure`'s, importable from here as well.
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET

import numpy as np

from machinesim.exceptions import MachineSimWarning, ModelError
from machinesim.kinematics import SPINDLE_TRAVEL_RAD, Axis
from machinesim.urdf_reading import _at, _number, _vector
from machinesim.urdf_structure import (
    MAX_DEPTH,  # noqa: F401 (importable from here, as before the split)
    MAX_LINKS,  # noqa: F401 (importable from here, as before the split)
    MAX_PLACEMENT_M,  # noqa: F401 (importable from here, as before the split)
    MAX_URDF_BYTES,  # noqa: F401 (importable from here, as before the split)
    REQUIRED_FRAMES,
    check_tree,
)

__all__ = ["REQUIRED_FRAMES", "check_joint_frames", "check_table", "check_tool_mount",
           "check_tree", "check_zero_pose"]

_NS = "{https://machinesim.invalid/urdf}"
#: How far the nominal machine at zero may be from the conventions (docs/machines.md): the
#: tool edge at the workpiece origin (m), its frame and each axis's direction parallel to
#: the workpiece's axes (rad, and the unit axis vectors' components). Round-off of the
#: origins' sums is ~1e-16.
ZERO_POSE_TOL = 1e-9
#: Plausible travel limits and rapid rates: beyond them a value was written in the wrong
#: unit (100 for 100 mm reads as 100 m) or is not a machine's. Rotary axes may be spindles,
#: whose travel is many turns.
MAX_TRAVEL_M = 10.0
#: The coarsest command resolution a machine axis plausibly has (0.1 mm, 0.01 rad).
COARSEST_RESOLUTION_M = 1e-4
COARSEST_RESOLUTION_RAD = 1e-2
#: The finest command resolution machinesim takes (1 pm, 1e-12 rad): a thousandth of the
#: shipped 1 nm, finer than any machine's scale. The encoders round each reading to it, and
#: a resolution of 5e-324 (or 1e-310) loaded and read 0.1 m as inf (0.1 / 5e-324 overflows).
FINEST_RESOLUTION_M = 1e-12
FINEST_RESOLUTION_RAD = 1e-12
MAX_TRAVEL_RAD = 1e9
#: The fastest machine tools rapid at 2-3 m/s; 10 m/s refuses a rate written in mm/s (a
#: ROBOnano's 25 mm/s as 25 loaded, its rapids 1000 times too fast).
RAPID_RATE_M_PER_S = (1e-6, 10.0)
RAPID_RATE_RAD_PER_S = (1e-6, 1e5)
#: Rotary limits that may be degrees (`_degree_warning`): beyond one turn (0.1 % over, for a
#: 2 pi written rounded, 6.2832), where a tilt or table axis written in degrees lands (B
#: -100 .. 100 deg loads as +-16 turns), and within the travel that, read as degrees, is
#: still no spindle's (beyond it both readings are a spindle).
DEGREE_LIKE_RAD = (2.0 * math.pi * 1.001, math.degrees(SPINDLE_TRAVEL_RAD))
#: A linear travel this long or longer loads with a warning (`_millimetre_warning`): a machine
#: written in millimetres whose every length is under `MAX_TRAVEL_M` (a 5 mm stage, written
#: 5) passes every check, scaled 1000 times as a whole, its zero pose and directions intact.
#: No check on the file's own numbers tells it from a machine that large (a uniform scale
#: keeps every ratio), so the longest travel is the evidence: the shipped machines travel
#: 0.5 m at most, the parts' unit-slip note starts at the same 1 m (`part.UNIT_SLIP_SIZE_M`).
MM_LIKE_TRAVEL_M = 1.0


def check_zero_pose(path, axes: tuple[Axis, ...], wMt: np.ndarray,
                    jacobian: np.ndarray, places: dict[str, str] | None = None) -> None:
    """Check the nominal machine at zero axis values against the conventions.

    ``wMt`` (4, 4) is the tool_tip's pose in the workpiece frame at zero, ``jacobian``
    (6, n_axes) its derivative (linear rows, then angular, in workpiece axes). The edge
    must sit at the workpiece origin with tool_tip parallel to workpiece; +1 of a linear
    axis must move the tool +1 along its letter relative to the workpiece (ISO 841), and a
    rotary axis turn it about the direction its ``<axis>`` names. A joint origin's ``rpy``
    that turns an axis, or a placement that leaves the edge off the origin, loads as a
    different machine (X moving along Y, Y mirrored, a part cut shifted), so it is refused.
    """
    offset, turned = wMt[:3, 3], _angle(wMt[:3, :3])
    if np.abs(offset).max() > ZERO_POSE_TOL or turned > ZERO_POSE_TOL:
        raise ModelError(
            f"{path}: at zero axis values the tool_tip sits at "
            f"({_fmt(offset * 1e3, 1e-9)}) mm in the workpiece frame, "
            f"turned {math.degrees(turned):.6g} deg; expected the tool edge at the workpiece "
            "origin and tool_tip parallel to workpiece (docs/machines.md, Conventions): "
            "check the origins (xyz in m, rpy in rad) from workpiece and tool_tip down to "
            "their common link")
    for column, axis in zip(jacobian.T, axes, strict=True):
        unit = np.eye(3)[axis.direction]
        moved, turns = column[:3], column[3:]
        if axis.rotary:
            if np.abs(turns - unit).max() <= ZERO_POSE_TOL:
                continue
            got = (f"+1 rad of {axis.letter} turns the tool relative to the workpiece about "
                   f"({_fmt(turns)})")
            wanted = f"about +{'XYZ'[axis.direction]}"
        else:
            if np.abs(moved - unit).max() <= ZERO_POSE_TOL and np.abs(turns).max() <= \
                    ZERO_POSE_TOL:
                continue
            got = (f"+1 m of {axis.letter} moves the tool relative to the workpiece by "
                   f"({_fmt(moved)}) m" + (f" and turns it by ({_fmt(turns)}) rad"
                                          if np.abs(turns).max() > ZERO_POSE_TOL else ""))
            wanted = f"+1 m along {axis.letter}"
        raise ModelError(
            f"{(places or {}).get(axis.letter, path)}: joint {axis.letter!r}: {got}; expected "
            f"{wanted} (ISO 841, with joint "
            "frames parallel to the machine axes at zero: check the rpy of this joint's "
            "origin and of the joints above it, docs/machines.md, Conventions)")


def check_tool_mount(root: ET.Element, path, mMt: np.ndarray) -> None:
    """Check that ``tool_tip`` sits rigidly on ``tool_mount`` and parallel to it.

    The tool setting error (``[tool]``, ``lab.adjust_tool``) is given in the tool_mount
    frame and enters the chain just above tool_tip, in tool_tip's axes: the two coincide
    only when no axis joint lies between the frames and tool_tip is not turned relative to
    tool_mount. ``mMt`` (4, 4) is tool_tip's nominal pose in tool_mount at zero axis values.
    A frame turned otherwise (a CAD export's spindle frame with Z along the spindle) would
    apply an offset along tool_mount Y along another direction, without a word.
    """
    between = sorted(_axes_above(root, "tool_tip") ^ _axes_above(root, "tool_mount"))
    if between:
        raise ModelError(f"{path}: axis joint(s) {', '.join(between)} move tool_tip and not "
                         "tool_mount, or tool_mount and not tool_tip; expected tool_tip held "
                         "rigidly by tool_mount (fixed joints between them: the tool setting "
                         "error is given in the tool_mount frame)")
    turned = _angle(mMt[:3, :3])
    if turned > ZERO_POSE_TOL:
        raise ModelError(f"{path}: tool_tip is turned {math.degrees(turned):.6g} deg relative "
                         "to tool_mount; expected them parallel (docs/machines.md, "
                         "Conventions), since the tool setting error is given in the "
                         "tool_mount frame: check the rpy of the origins between them")


def check_table(root: ET.Element, path, axes: tuple[Axis, ...],
                lines: dict[str, list[int]] | None = None) -> None:
    """Check that ``table`` moves with the workpiece: on its side, under its linear axes.

    The laser interferometer reads the tool's motion relative to the table, in the table's
    axes (`machinesim.metrology.LaserInterferometer`), as its optics ride on the table. A
    ``table`` moved by an axis that does not move the workpiece (on the tool's chain: the
    names of ``table`` and ``tool_mount`` swapped), or left behind by a linear axis that
    does (on the bed under a moving workpiece), loaded without a word, and a positioning
    test of X read its 10 mm stroke as a 10 mm error. Every linear axis moving the
    workpiece must move the table, and every axis moving the table must move the
    workpiece; a rotary table may turn the table or turn above it. ``root`` has passed
    `check_tree` and ``axes`` are its axis joints (`machinesim.urdf.read_axes`); ``lines``
    (`machinesim.urdf.read_urdf`) puts the line of ``<link name="table">`` in a message.

    Raises
    ------
    ModelError
        Naming ``path``, the line of the table link, and the axes at fault.
    """
    on_table, on_workpiece = _axes_above(root, "table"), _axes_above(root, "workpiece")
    index = [link.get("name") for link in root.findall("link")].index("table")
    where = f"{_at(path, lines, 'link', index)}: link 'table'"
    expected = ("expected the table on the workpiece's side, carried by every linear axis "
                "that moves the workpiece and by no axis that does not (a rotary table may "
                "turn it or turn above it; docs/machines.md, Conventions): the laser "
                "interferometer reads the tool's motion relative to the table")
    moving = [a.letter for a in axes if a.letter in on_table - on_workpiece]
    if moving:
        raise ModelError(f"{where} is moved by axis joint(s) {', '.join(moving)}, which do "
                         f"not move the workpiece; {expected}")
    behind = [a.letter for a in axes
              if not a.rotary and a.letter in on_workpiece - on_table]
    if behind:
        raise ModelError(f"{where} is not moved by linear axis joint(s) {', '.join(behind)}, "
                         f"which move the workpiece; {expected}")


def _axes_above(root: ET.Element, link: str) -> set[str]:
    """The names of the axis (not fixed) joints on the chain from the root link to ``link``."""
    parent_of = {j.find("child").get("link"): j for j in root.findall("joint")}
    names = set()
    while link in parent_of:
        joint = parent_of[link]
        if joint.get("type") != "fixed":
            names.add(joint.get("name"))
        link = joint.find("parent").get("link")
    return names


def check_joint_frames(path, axes: tuple[Axis, ...], rotations: dict[str, np.ndarray],
                       places: dict[str, str] | None = None) -> None:
    """Check that every axis joint's frame is parallel to the workpiece frame at zero.

    ``rotations`` maps each axis letter to its joint frame's orientation (3, 3) in the
    workpiece frame on the nominal machine at zero axis values. An axis's errors (``EYX``,
    ``EC0X``, ...) are given along the machine axes and enter the chain in its joint frame
    (`machinesim.kinematics`). A frame turned about the axis's own direction, the turn
    undone by the joint below, moves the tool as designed, so `check_zero_pose` passes it;
    but X's straightness in Y then moved the tool along Z, and its squareness to Y tilted
    it toward Z, without a word.
    """
    for axis in axes:
        turned = _angle(rotations[axis.letter])
        if turned > ZERO_POSE_TOL:
            raise ModelError(
                f"{(places or {}).get(axis.letter, path)}: joint {axis.letter!r}: its frame "
                "is turned "
                f"{math.degrees(turned):.6g} deg relative to the workpiece at zero axis "
                f"values; expected it parallel to the machine axes (docs/machines.md, "
                f"Conventions), since the errors of {axis.letter} "
                f"({', '.join(axis.component_symbols()[:3])}, ...) are given along them and "
                "enter in its frame: check the rpy of this joint's origin and of the joints "
                "above it")


def _turned_frame_hint(joint: ET.Element) -> str:
    """For a joint whose origin turns its frame (a CAD export's): that ``<axis>`` is read in
    the turned frame, which machinesim asks to be parallel to the machine axes."""
    origin = joint.find("origin")
    rpy = origin.get("rpy") if origin is not None else None
    if rpy is None or not np.any(_vector(origin, "rpy", "")):
        return ""
    return (f" (<axis> is read in the joint's frame, which its <origin rpy=\"{rpy}\"> turns: "
            "write rpy=\"0 0 0\" on an axis joint and its <axis> along the machine axes, "
            "docs/machines.md)")


def _angle(rotation: np.ndarray) -> float:
    """The angle (rad) of a rotation matrix, accurate for small angles too."""
    return float(np.arctan2(np.linalg.norm(rotation - rotation.T) / math.sqrt(8.0),
                            (np.trace(rotation) - 1.0) / 2.0))


def _fmt(vector: np.ndarray, below: float = 1e-12) -> str:
    """Components to 6 digits, round-off (below ``below``) shown as 0."""
    return ", ".join(f"{0.0 if abs(v) < below else v:.6g}" for v in vector)


def _namespace_hint(root: ET.Element, name: str) -> str:
    """Where an axis element for joint ``name`` is in another XML namespace: which one, and
    the one machinesim reads."""
    for element in root.iter():
        tag = element.tag if isinstance(element.tag, str) else ""
        if tag.rpartition("}")[2] == "axis" and element.get("joint") == name:
            found = tag.rpartition("}")[0].lstrip("{") or "no namespace"
            return (f" (an <axis joint={name!r}> is there, in {found}; declare "
                    f"xmlns:machinesim=\"{_NS.strip('{}')}\" on <robot>)")
    return ""


def _limits(joint: ET.Element, where: str, rotary: bool) -> tuple[float, float, float]:
    """Travel and rapid rate of an axis joint (SI), each present, finite and in order."""
    limit = joint.find("limit")
    unit = "rad" if rotary else "m"
    if limit is None:
        raise ModelError(f"{where}: no <limit lower=... upper=... velocity=...>; an axis "
                         f"needs its travel ({unit}) and rapid rate ({unit}/s)")
    values = {}
    for attribute in ("lower", "upper", "velocity"):
        text = limit.get(attribute)
        if text is None:
            raise ModelError(f"{where}: <limit> has no {attribute}=...; an axis needs its "
                             f"travel ({unit}) and rapid rate ({unit}/s)")
        values[attribute] = _number(text, f"{where} <limit {attribute}>")
    # URDF requires effort on every <limit> (machinesim does not use it): without it the
    # URDF parser under Pinocchio refuses the whole file without naming the joint
    if limit.get("effort") is None:
        raise ModelError(f"{where}: <limit> has no effort=...; URDF requires it on every "
                         "<limit> (any number >= 0: machinesim does not use it)")
    effort = _number(limit.get("effort"), f"{where} <limit effort>")
    if effort < 0.0:  # Pinocchio: "Some components of min_effort are greater than max_effort"
        raise ModelError(f"{where}: <limit effort={effort!r}>; expected a number >= 0 "
                         "(machinesim does not use it, but Pinocchio refuses a negative one)")
    lower, upper, velocity = values["lower"], values["upper"], values["velocity"]
    if not lower < upper:
        raise ModelError(f"{where}: <limit lower={lower!r} upper={upper!r}> ({unit}); "
                         "expected lower < upper (swapped or empty travel)")
    if not velocity > 0.0:
        raise ModelError(f"{where}: <limit velocity={velocity!r}> ({unit}/s); expected a rapid "
                         "rate > 0")
    most = MAX_TRAVEL_RAD if rotary else MAX_TRAVEL_M
    if max(abs(lower), abs(upper)) > most:
        raise ModelError(f"{where}: <limit lower={lower!r} upper={upper!r}> ({unit}); expected "
                         f"a travel within +-{most:g} {unit} (URDF lengths are metres: "
                         "100 mm is 0.1)")
    slowest, fastest = RAPID_RATE_RAD_PER_S if rotary else RAPID_RATE_M_PER_S
    if not slowest <= velocity <= fastest:
        raise ModelError(f"{where}: <limit velocity={velocity!r}> ({unit}/s); expected a rapid "
                         f"rate of {slowest:g} .. {fastest:g} {unit}/s")
    if rotary:
        _degree_warning(where, lower, upper)
    return lower, upper, velocity


def _millimetre_warning(where: str, letter: str, lower: float, upper: float) -> None:
    """Warn (`MachineSimWarning`) of a longest linear travel of `MM_LIKE_TRAVEL_M` or more
    (``where``, the <limit>'s place, and ``letter``, its axis): perhaps a machine written in
    millimetres. A warning, not a refusal: a machine of a metre's travel is a machine too."""
    travel = upper - lower
    if not travel >= MM_LIKE_TRAVEL_M:
        return
    warnings.warn(
        f"{where}: <limit lower={lower!r} upper={upper!r}> gives {letter} a travel of "
        f"{travel:g} m, the longest of the machine's linear axes (the shipped machines travel "
        "0.5 m at most). URDF lengths are metres: a machine written in millimetres loads 1000 "
        "times too large, its origins and rapid rates with it, and a program in mm never "
        f"leaves its travel. If these are millimetres, write every length in m ({upper:g} mm "
        f"is {upper / 1e3:g}) and velocities in m/s", MachineSimWarning, stacklevel=2)


def _degree_warning(where: str, lower: float, upper: float) -> None:
    """Warn (`MachineSimWarning`) of rotary limits that read as degrees (`DEGREE_LIKE_RAD`).

    Loaded as radians, B -100 .. 100 deg is +-16 turns, so its travel check never fires, and
    C -360 .. 360 deg runs past `SPINDLE_TRAVEL_RAD`, a work spindle, so a program that
    turns C while it feeds is refused. A warning, not a refusal: a table of several turns
    (+-4 pi) is a machine too.
    """
    most = max(abs(lower), abs(upper))
    if not DEGREE_LIKE_RAD[0] < most <= DEGREE_LIKE_RAD[1]:
        return
    spindle = (f", past {SPINDLE_TRAVEL_RAD:g} rad: a work spindle, which a program may not "
               "turn while it feeds" if upper > SPINDLE_TRAVEL_RAD else "")
    warnings.warn(
        f"{where}: <limit lower={lower!r} upper={upper!r}> is read in rad, as URDF limits "
        f"are: {lower / (2 * math.pi):.3g} .. {upper / (2 * math.pi):.3g} turns{spindle}. If "
        f"these are degrees, write lower=\"{math.radians(lower)!r}\" "
        f"upper=\"{math.radians(upper)!r}\" ({lower:g} .. {upper:g} deg), and the velocity "
        "in rad/s; an axis that turns without end is written with wide limits (sts_lathe's C: "
        "-1e5 .. 1e5 rad)", MachineSimWarning, stacklevel=2)
