"""URDF machine files: read one, check its tree, and find its axes.

Everything a machinesim URDF must satisfy is checked here, before Pinocchio sees the file,
so that a bad file is a located `ModelError` (file, joint or link, value, what was
expected), never a hang or a traceback: the XML must parse; links and joints must form one
tree (no cycle, no dangling or duplicate name, one root); every axis joint is named by its
NC letter, has a unit machine direction pointing as ISO 841 asks, finite origins, a
``<limit>`` with lower < upper and a velocity > 0, and a ``<machinesim:axis>`` resolution.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from machinesim.exceptions import ModelError
from machinesim.kinematics import DOFS, Axis

__all__ = ["AXIS_ORDER", "REQUIRED_FRAMES", "check_tree", "read_axes", "read_urdf"]

#: NC letters in the order machinesim puts them in a configuration vector.
AXIS_ORDER = "XYZABC"
#: Frames every machine has.
REQUIRED_FRAMES = ("base", "table", "workpiece", "tool_mount", "tool_tip")
_NS = "{https://machinesim.invalid/urdf}"


def read_urdf(path: Path) -> ET.Element:
    """The checked XML root of the URDF file ``path`` (`check_tree`)."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ModelError(f"{path}: not readable XML ({exc})") from None
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the URDF file ({exc.strerror})") from None
    except RecursionError:
        raise ModelError(f"{path}: XML nested too deeply to be a URDF") from None
    check_tree(root, path)
    return root


def read_axes(root: ET.Element, path: Path) -> tuple[Axis, ...]:
    """Axes of a machinesim URDF, in AXIS_ORDER, with side, direction and resolution.

    ``root`` has passed `check_tree`: a tree of uniquely named links and joints with finite
    origins.
    """
    resolution = _resolutions(root, path)
    links_parent = {j.find("child").get("link"): j for j in root.findall("joint")}

    def ancestors(link: str) -> set[str]:
        names = set()
        while link in links_parent:
            joint = links_parent[link]
            names.add(joint.get("name"))
            link = joint.find("parent").get("link")
        return names

    tool_side, wp_side = ancestors("tool_tip"), ancestors("workpiece")
    axes = []
    for joint in root.findall("joint"):
        kind = joint.get("type")
        if kind == "fixed":
            continue
        name = joint.get("name")
        where = f"{path}: joint {name!r}"
        if kind not in ("prismatic", "revolute"):
            raise ModelError(f"{where}: type {kind!r}; machine axes are prismatic or revolute "
                             "(a spindle is a revolute joint with wide limits)")
        if name not in AXIS_ORDER or len(name) != 1:
            raise ModelError(f"{where}: axis joints are named by their NC letter, one of "
                             f"{', '.join(AXIS_ORDER)}")
        element = joint.find("axis")
        if element is None:
            raise ModelError(f"{where}: no <axis xyz=...>; a machine axis states its direction")
        axis = _vector(element, "xyz", f"{where} <axis>")
        k = int(np.argmax(np.abs(axis)))
        if np.count_nonzero(axis) != 1 or abs(abs(axis[k]) - 1.0) > 0:
            raise ModelError(f"{where}: axis {axis.tolist()} must be a unit machine direction")
        side = 1 if name in tool_side else -1 if name in wp_side else 0
        if side == 0:
            raise ModelError(f"{where}: moves neither the tool_tip nor the workpiece")
        expected_sign = 1.0 if side > 0 else -1.0
        if np.sign(axis[k]) != expected_sign:
            raise ModelError(
                f"{where}: a {'tool' if side > 0 else 'workpiece'}-side axis must point "
                f"{'+' if side > 0 else '-'}{'XYZ'[k]} so that positive commands move the tool "
                "positively relative to the workpiece (ISO 841)")
        if name not in resolution:
            raise ModelError(f"{where}: no <machinesim:axis joint=\"{name}\" resolution=...> "
                             "element")
        lower, upper, velocity = _limits(joint, where, kind == "revolute")
        axes.append(Axis(
            letter=name, rotary=kind == "revolute", side=side, direction=k,
            lower=lower, upper=upper, velocity=velocity, resolution=resolution[name]))
    return tuple(sorted(axes, key=lambda a: AXIS_ORDER.index(a.letter)))


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
    lower, upper, velocity = values["lower"], values["upper"], values["velocity"]
    if not lower < upper:
        raise ModelError(f"{where}: <limit lower={lower!r} upper={upper!r}> ({unit}); "
                         "expected lower < upper (swapped or empty travel)")
    if not velocity > 0.0:
        raise ModelError(f"{where}: <limit velocity={velocity!r}> ({unit}/s); expected a rapid "
                         "rate > 0")
    return lower, upper, velocity


def _resolutions(root: ET.Element, path: Path) -> dict[str, float]:
    """Command resolution (m or rad) of each axis, from the machinesim:axis elements."""
    found: dict[str, float] = {}
    for element in root.iter(f"{_NS}axis"):
        joint = element.get("joint")
        where = f"{path}: <machinesim:axis joint={joint!r}>"
        if not joint:
            raise ModelError(f"{path}: a <machinesim:axis> has no joint=...")
        if joint in found:
            raise ModelError(f"{where}: given twice; one resolution per axis")
        text = element.get("resolution")
        if text is None:
            raise ModelError(f"{where}: no resolution=... (m or rad)")
        value = _number(text, f"{where} resolution")
        if not value > 0.0:
            raise ModelError(f"{where}: resolution {value!r}; expected > 0 (m or rad)")
        found[joint] = value
    return found


def _number(text: str, where: str) -> float:
    """A finite float from URDF attribute text, or ModelError naming ``where`` and the text."""
    try:
        value = float(text)
    except ValueError:
        raise ModelError(f"{where}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise ModelError(f"{where}: {text!r}; expected a finite number")
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


def check_tree(root: ET.Element, path) -> None:
    """Check a URDF's structure before anything walks it.

    Checked: the ``<robot>`` root; every link and joint named, and uniquely; every joint's
    parent and child links exist; each link the child of at most one joint; no cycle (found
    before any walk, so a cyclic file cannot hang the loader); one root link; the frames
    every machine needs (`REQUIRED_FRAMES`), the tool edge and the workpiece on fixed joints;
    no name taken by machinesim's error joints; every ``<origin>`` finite.

    Raises
    ------
    ModelError
        Naming ``path``, the joint or link, and the value.
    """
    if root.tag != "robot":
        raise ModelError(f"{path}: root element <{root.tag}>; expected <robot>")
    links: set[str] = set()
    for link in root.findall("link"):
        name = link.get("name")
        if not name:
            raise ModelError(f"{path}: a <link> has no name=...")
        if name in links:
            raise ModelError(f"{path}: link {name!r} is defined twice; link names are unique")
        _check_reserved(name, "link", path)
        links.add(name)
    joints: dict[str, ET.Element] = {}
    parent_joint: dict[str, str] = {}  # child link -> the joint that carries it
    parent_link: dict[str, str] = {}  # joint -> its parent link
    for joint in root.findall("joint"):
        name = joint.get("name")
        if not name:
            raise ModelError(f"{path}: a <joint> has no name=...")
        if name in joints:
            raise ModelError(f"{path}: joint {name!r} is defined twice; joint names are unique")
        _check_reserved(name, "joint", path)
        joints[name] = joint
        where = f"{path}: joint {name!r}"
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
            _vector(origin, "xyz", f"{where} <origin>", "0 0 0")
            _vector(origin, "rpy", f"{where} <origin>", "0 0 0")
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
