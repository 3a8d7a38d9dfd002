"""What a machinesim URDF must satisfy, and where a file that does not is refused.

The checks a machine file passes as it loads (`machinesim.urdf`, `machinesim.machines`),
so that a bad file is a located `ModelError` (file, line, joint or link, value, what was
expected), never a hang or a traceback: `check_tree`, the structure (one tree of uniquely
named links and joints, no cycle, one root, the frames every machine has, finite origins
within a machine's size, no xacro, URDF's shapes) and the size and link-count limits;
`_limits`, an axis's travel and a plausible rapid rate (rotary limits that read as degrees
load with a warning); `check_table`, the table on the workpiece's side, moved by its
linear axes and by no axis of the tool's; and, once Pinocchio has the model,
`check_zero_pose`, the nominal machine at zero against the conventions of docs/machines.md
(the edge at the workpiece origin, each axis moving the tool along or about its
direction), `check_joint_frames`, each axis joint's frame parallel to the machine axes, and
`check_tool_mount`, tool_tip rigidly on tool_mount and parallel to it, the frame the tool
setting error is given in. Also the readers of URDF numbers (`_number`, `_vector`) that
refuse what the URDF parser under Pinocchio would. An axis joint's name, type and
direction are checked as `machinesim.urdf.read_axes` reads them.
"""

from __future__ import annotations

import math
import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from machinesim.exceptions import MachineSimWarning, ModelError
from machinesim.kinematics import DOFS, SPINDLE_TRAVEL_RAD, Axis

__all__ = ["REQUIRED_FRAMES", "check_joint_frames", "check_table", "check_tool_mount",
           "check_tree", "check_zero_pose"]

#: Frames every machine has.
REQUIRED_FRAMES = ("base", "table", "workpiece", "tool_mount", "tool_tip")
_NS = "{https://machinesim.invalid/urdf}"
#: How far the nominal machine at zero may be from the conventions (docs/machines.md): the
#: tool edge at the workpiece origin (m), its frame and each axis's direction parallel to
#: the workpiece's axes (rad, and the unit axis vectors' components). Round-off of the
#: origins' sums is ~1e-16.
ZERO_POSE_TOL = 1e-9
#: Elements nested deeper than this are not a URDF (one is 5-6 deep).
MAX_DEPTH = 64
#: Bytes beyond which a file is not a machine's URDF (one is a few kB, a CAD export with
#: hundreds of links a few hundred kB; meshes are files of their own). A 200 MB file of
#: links took 3.6 GB within two minutes and was still growing.
MAX_URDF_BYTES = 16 * 2**20
#: Links beyond which a file is not a machine's (one has tens, a CAD export of every part a
#: few hundred): Pinocchio's URDF reader takes a time growing with the square of their
#: number (20,000 links: 16 s; 144,000, a 15 MB file: over 10 minutes).
MAX_LINKS = 2000
#: Plausible travel limits and rapid rates: beyond them a value was written in the wrong
#: unit (100 for 100 mm reads as 100 m) or is not a machine's. Rotary axes may be spindles,
#: whose travel is many turns.
MAX_TRAVEL_M = 10.0
#: How far (m, each coordinate) a joint may sit from its parent link: a machine's parts lie
#: within metres of each other, and a file whose origins are written in mm (its limits in m)
#: loads with every Abbe offset a thousand times too long.
MAX_PLACEMENT_M = 10.0
#: The coarsest command resolution a machine axis plausibly has (0.1 mm, 0.01 rad).
COARSEST_RESOLUTION_M = 1e-4
COARSEST_RESOLUTION_RAD = 1e-2
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
#: A number as the URDF parser under Pinocchio (urdfdom, a C++ stream) reads one: ASCII
#: digits, a point, an exponent, blanks before it only. Python's float() reads more
#: ("1_000", Arabic-Indic digits, a trailing blank), which the parser then refused without
#: naming the joint.
_URDF_NUMBER = re.compile(r"\s*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def _at(path, lines: dict[str, list[int]] | None, tag: str, index: int) -> str:
    """``path`` and the line of the ``index``-th ``tag`` element when known."""
    found = (lines or {}).get(tag, ())
    return f"{path}, line {found[index]}" if index < len(found) else f"{path}"


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
                         "<limit> (any number: machinesim does not use it)")
    _number(limit.get("effort"), f"{where} <limit effort>")
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


def _number(text: str, where: str) -> float:
    """A finite float from URDF attribute text, or ModelError naming ``where`` and the text."""
    try:
        value = float(text)
    except ValueError:
        raise ModelError(f"{where}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise ModelError(f"{where}: {text!r}; expected a finite number")
    if not _URDF_NUMBER.fullmatch(text):
        raise ModelError(f"{where}: {text!r} is not a number as a URDF parser reads one "
                         "(ASCII digits, '.', an exponent; no '_', no blank after it)")
    return value


def _vector(element: ET.Element, attribute: str, where: str,
            default: str | None = None) -> np.ndarray:
    """Three finite floats from a URDF attribute (``xyz``, ``rpy``)."""
    text = element.get(attribute, default)
    if text is None:
        raise ModelError(f"{where}: no {attribute}=...; expected three numbers")
    fields = text.split()
    if len(fields) != 3:
        raise ModelError(f"{where}: {attribute}={text!r}; expected three numbers")
    return np.array([_number(f, f"{where} {attribute}") for f in fields])


def check_tree(root: ET.Element, path, lines: dict[str, list[int]] | None = None) -> None:
    """Check a URDF's structure before anything walks it.

    Checked: the ``<robot>`` root; every link and joint named, and uniquely; every joint's
    parent and child links exist; each link the child of at most one joint; no cycle (found
    before any walk, so a cyclic file cannot hang the loader); no element given twice where
    URDF allows one (a joint's ``<axis>``, ``<origin>``, ``<limit>`` ..., a link's
    ``<inertial>``, a visual's ``<origin>``, ``<geometry>`` and its shape, ...: the parser
    reads the first); one root link; the frames
    every machine needs (`REQUIRED_FRAMES`), the tool edge and the workpiece on fixed joints;
    no name taken by machinesim's error joints; every ``<origin>`` finite; every visual and
    collision shape a box, cylinder, sphere or mesh with positive sizes.

    Raises
    ------
    ModelError
        Naming ``path``, the line of the joint or link when ``lines`` (`read_urdf`) has
        it, the joint or link, and the value.
    """
    if root.tag != "robot":
        raise ModelError(f"{path}: root element <{root.tag}>; expected <robot>")
    if not root.get("name"):
        raise ModelError(f"{path}: <robot> has no name=...; URDF requires one")
    _check_not_xacro(root, path)
    count = len(root.findall("link"))
    if count > MAX_LINKS:
        raise ModelError(f"{path}: {count} links; a machine has tens (a CAD export of every "
                         f"part a few hundred): expected at most {MAX_LINKS}")
    links: set[str] = set()
    in_link = (lines or {}).get("in_link", ())
    inside = 0  # the links' children and grandchildren before this link's, for their lines
    for index, link in enumerate(root.findall("link")):
        name = link.get("name")
        at = _at(path, lines, "link", index)
        if not name:
            raise ModelError(f"{at}: a <link> has no name=...")
        if name in links:
            raise ModelError(f"{at}: link {name!r} is defined twice; link names are unique")
        _check_reserved(name, "link", at)
        count = len(link) + sum(len(child) for child in link)
        _check_link_once(link, f"{at}: link {name!r}", in_link[inside:inside + count])
        inside += count
        links.add(name)
    joints: dict[str, ET.Element] = {}
    parent_joint: dict[str, str] = {}  # child link -> the joint that carries it
    parent_link: dict[str, str] = {}  # joint -> its parent link
    in_joint = (lines or {}).get("in_joint", [])
    children = 0  # the joints' children before this joint's, for their lines
    for index, joint in enumerate(root.findall("joint")):
        name = joint.get("name")
        at = _at(path, lines, "joint", index)
        if not name:
            raise ModelError(f"{at}: a <joint> has no name=...")
        if name in joints:
            raise ModelError(f"{at}: joint {name!r} is defined twice; joint names are unique")
        _check_reserved(name, "joint", at)
        joints[name] = joint
        where = f"{at}: joint {name!r}"
        _check_once(joint, _ONCE_IN_JOINT, where, in_joint[children:children + len(joint)])
        children += len(joint)
        ends = {}
        for end in ("parent", "child"):
            element = joint.find(end)
            link = None if element is None else element.get("link")
            if not link:
                raise ModelError(f"{where}: no <{end} link=...>")
            if link not in links:
                raise ModelError(f"{where}: {end} link {link!r} does not exist; expected one of "
                                 f"the file's links ({_some(links)})")
            ends[end] = link
        child = ends["child"]
        if child in parent_joint:
            raise ModelError(f"{where}: link {child!r} is already the child of joint "
                             f"{parent_joint[child]!r}; in a URDF tree each link has one parent")
        parent_joint[child] = name
        parent_link[name] = ends["parent"]
        origin = joint.find("origin")
        if origin is not None:
            xyz = _vector(origin, "xyz", f"{where} <origin>", "0 0 0")
            _vector(origin, "rpy", f"{where} <origin>", "0 0 0")
            if np.abs(xyz).max() > MAX_PLACEMENT_M:
                raise ModelError(f"{where} <origin xyz={origin.get('xyz')!r}> (m); expected "
                                 f"each coordinate within +-{MAX_PLACEMENT_M:g} m of the parent "
                                 "link (URDF lengths are metres: 100 mm is 0.1)")
        limit = joint.find("limit")
        if limit is not None and joint.get("type") == "fixed":  # axes: `_limits`
            for attribute in ("effort", "velocity"):
                text = limit.get(attribute)
                if text is None:
                    raise ModelError(f"{where}: <limit> has no {attribute}=...; URDF requires "
                                     "effort and velocity on every <limit> (a fixed joint "
                                     "needs no <limit>)")
                _number(text, f"{where} <limit {attribute}>")
    _check_acyclic(links, parent_joint, parent_link, path)
    roots = sorted(link for link in links if link not in parent_joint)
    if len(roots) != 1:
        raise ModelError(f"{path}: {len(roots)} root links ({_some(roots)}); a URDF is one tree "
                         "with one root link")
    missing = [f for f in REQUIRED_FRAMES if f not in links]
    if missing:
        raise ModelError(f"{path}: missing frame(s) {', '.join(missing)}; every machine needs "
                         f"{', '.join(REQUIRED_FRAMES)}")
    for frame in ("tool_tip", "workpiece"):
        joint = joints.get(parent_joint.get(frame, ""))
        if joint is None or joint.get("type") != "fixed":
            raise ModelError(f"{path}: link {frame!r} must hang on a fixed joint (its setting "
                             "error is inserted there)")
    checked = {id(j.find("origin")) for j in joints.values()}
    for element in root.iter("origin"):
        if id(element) in checked:
            continue
        _vector(element, "xyz", f"{path}: an <origin>", "0 0 0")
        _vector(element, "rpy", f"{path}: an <origin>", "0 0 0")
    for link in root.findall("link"):
        for kind in ("visual", "collision"):
            for element in link.findall(f"{kind}/geometry/*"):
                _check_shape(element, f"{path}: link {link.get('name')!r} <{kind}>")


def _check_not_xacro(root: ET.Element, path) -> None:
    """Refuse a xacro file (macros, properties, ``${...}``) given for its URDF: its links
    made by a macro were missing ("child link 'x_carriage' does not exist") and its
    expressions were not numbers, neither of which said to expand it."""
    expand = f"expand it first (xacro {Path(str(path)).name} > machine.urdf) and load the URDF"
    for element in root.iter():
        tag = element.tag if isinstance(element.tag, str) else ""
        namespace, _, local = tag.rpartition("}")
        if namespace.rstrip("/").endswith("xacro"):
            raise ModelError(f"{path}: <xacro:{local}> is xacro, not URDF: {expand}")
        for attribute, value in element.attrib.items():
            if "${" in value or "$(" in value:
                raise ModelError(f"{path}: <{local} {attribute}={value!r}> is a xacro "
                                 f"expression, not a value: {expand}")


#: The elements URDF allows once in a joint, a link, a link's visual or collision and its
#: inertial: the URDF parser under Pinocchio reads the first and drops the others without a
#: word, so a joint with two <axis> or <origin> (a CAD export's, or an edit written beside
#: the old line) loaded with the first.
_ONCE_IN_JOINT = ("parent", "child", "origin", "axis", "limit", "calibration", "dynamics",
                  "mimic", "safety_controller")
_ONCE_IN_LINK = ("inertial",)
_ONCE_IN_SHAPE = ("origin", "geometry", "material")
_ONCE_IN_INERTIAL = ("origin", "mass", "inertia")


def _check_once(element: ET.Element, tags: tuple[str, ...], where: str,
                lines: list[int] = ()) -> None:
    """Refuse a second ``<tag>`` of ``tags`` among the children of ``element``, naming
    the lines of them all when ``lines`` (one per child, in order) has them."""
    if len(element) < 2:
        return
    seen = [child.tag for child in element]
    for tag in tags:
        if seen.count(tag) > 1:
            on = ""
            if len(lines) == len(seen):
                at = [str(line) for line, t in zip(lines, seen, strict=True) if t == tag]
                on = f" (lines {', '.join(at)})"
            raise ModelError(f"{where}: {seen.count(tag)} <{tag}> elements{on}; URDF allows "
                             f"one, and its parser reads the first and drops the others "
                             f"without a word: keep the one meant")


def _check_link_once(link: ET.Element, where: str, lines=()) -> None:
    """`_check_once` for a link, its visuals and collisions (and their geometry, which holds
    one shape) and its inertial, each named by its place among its kind in the link, with
    the lines of the elements given twice when ``lines`` has them (the link's children and
    grandchildren in the order of the file, `read_urdf`'s ``"in_link"``). The message is
    put together only for a refusal: a CAD export has 100,000s of visuals."""
    starts, end = [], 0  # where each child's line stands in ``lines``, its children after it
    for child in link:
        starts.append(end)
        end += 1 + len(child)
    known = len(lines) == end
    twice = known and any(sum(child.tag == tag for child in link) > 1 for tag in _ONCE_IN_LINK)
    _check_once(link, _ONCE_IN_LINK, where, [lines[k] for k in starts] if twice else ())
    count = {"visual": 0, "collision": 0, "inertial": 0}
    for place, child in enumerate(link):
        kind = child.tag
        if kind not in count:
            continue
        count[kind] += 1
        tags = [part.tag for part in child]
        twice = len(set(tags)) != len(tags)
        shapes = [part for part in child if part.tag == "geometry" and len(part) > 1]
        if not (twice or shapes):
            continue
        inner = f"{where} <{kind}> (its {_ordinal(count[kind])})"
        first = starts[place] + 1
        _check_once(child, _ONCE_IN_INERTIAL if kind == "inertial" else _ONCE_IN_SHAPE, inner,
                    lines[first:first + len(child)] if known else ())
        if shapes and kind != "inertial":
            listed = ", ".join(f"<{shape.tag}>" for shape in shapes[0])
            raise ModelError(f"{inner}: <geometry> holds {len(shapes[0])} shapes ({listed}); "
                             "URDF allows one, and its parser reads the first and drops the "
                             f"others without a word: one shape per <{kind}>")


def _ordinal(n: int) -> str:
    return f"{n}{'th' if 10 <= n % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(n % 10, 'th')}"


#: The sizes (m) of URDF's shapes: attribute -> how many numbers.
_SHAPE_SIZES = {"box": {"size": 3}, "cylinder": {"radius": 1, "length": 1},
                "sphere": {"radius": 1}, "mesh": {}}


def _check_shape(element: ET.Element, where: str) -> None:
    """A visual or collision shape with its sizes positive and finite (a mesh with a file
    name), so that a bad one is a located ModelError rather than a C++ message of the URDF
    parser on stderr and a link drawn without it."""
    if element.tag not in _SHAPE_SIZES:
        raise ModelError(f"{where}: <{element.tag}>; expected a box, cylinder, sphere or mesh")
    if element.tag == "mesh" and not element.get("filename"):
        raise ModelError(f"{where}: a <mesh> has no filename=...")
    for attribute, count in _SHAPE_SIZES[element.tag].items():
        text = element.get(attribute)
        fields = [] if text is None else text.split()
        values = [_number(f, f"{where} <{element.tag} {attribute}>") for f in fields]
        if len(values) != count or not all(v > 0.0 for v in values):
            raise ModelError(f"{where}: <{element.tag} {attribute}={text!r}>; expected "
                             f"{'one length' if count == 1 else f'{count} lengths'} > 0 (m)")


def _check_acyclic(links, parent_joint, parent_link, path) -> None:
    """ModelError naming the joints of a cycle, found by walking up from every link once."""
    done: set[str] = set()
    for start in sorted(links):
        trail: list[str] = []
        on_trail: set[str] = set()
        link = start
        while link in parent_joint and link not in done:
            if link in on_trail:
                cycle = trail[trail.index(link):]
                names = " -> ".join(repr(parent_joint[c]) for c in cycle)
                raise ModelError(f"{path}: joints {names} form a cycle (link {link!r} is its own "
                                 "ancestor); a URDF is a tree")
            trail.append(link)
            on_trail.add(link)
            link = parent_link[parent_joint[link]]
        done.update(trail)


#: Suffixes of the error joints machinesim inserts (`kinematics.augment_urdf`).
_RESERVED = {f"{prefix}_{dof}" for prefix in ("tool", "workpiece") for dof in DOFS}


def _check_reserved(name: str, kind: str, path) -> None:
    if "__" in name or name in _RESERVED:
        raise ModelError(f"{path}: {kind} name {name!r} is reserved for machinesim's error "
                         "joints (names with '__', tool_tx .. workpiece_rz); rename it")


def _some(names, count: int = 8) -> str:
    names = sorted(names)
    shown = ", ".join(repr(n) for n in names[:count])
    return shown + (f", ... ({len(names)} in all)" if len(names) > count else "")
