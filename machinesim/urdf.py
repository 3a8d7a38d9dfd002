"""URDF machine files: read one, locate its elements, and find its axes.

`read_urdf` reads the file (at most `MAX_URDF_BYTES`, nested at most `MAX_DEPTH` deep, in
UTF-8 or the encoding it declares), keeps the line of each element a message may name, and
has `check_tree` check its structure before anything walks it; `read_axes` reads its axis
joints, each named by its NC letter (X Y Z prismatic, A B C revolute), carrying the tool or
the workpiece, with a unit machine direction pointing as ISO 841 asks, a ``<limit>`` and a
``<machinesim:axis>`` resolution. The file's structure and its size limits are checked in
`machinesim.urdf_structure`; what the axes must satisfy, and the checks of the nominal
machine once Pinocchio has the model (`check_zero_pose`, `check_joint_frames`,
`check_tool_mount`), are in `machinesim.urdf_checks`; they and their limits are importable
from here as well.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from array import array
from pathlib import Path
from xml.parsers import expat

import numpy as np

from machinesim.exceptions import ModelError
from machinesim.kinematics import Axis
from machinesim.urdf_checks import (
    _NS,
    COARSEST_RESOLUTION_M,
    COARSEST_RESOLUTION_RAD,
    DEGREE_LIKE_RAD,
    FINEST_RESOLUTION_M,
    FINEST_RESOLUTION_RAD,
    MAX_TRAVEL_M,
    MAX_TRAVEL_RAD,
    RAPID_RATE_M_PER_S,
    RAPID_RATE_RAD_PER_S,
    ZERO_POSE_TOL,
    _limits,
    _millimetre_warning,
    _namespace_hint,
    _turned_frame_hint,
    check_joint_frames,
    check_tool_mount,
    check_zero_pose,
)
from machinesim.urdf_reading import _at, _number, _vector
from machinesim.urdf_structure import (
    MAX_DEPTH,
    MAX_LINKS,
    MAX_PLACEMENT_M,
    MAX_URDF_BYTES,
    REQUIRED_FRAMES,
    _in_joint_at,
    check_tree,
)

# The checks and limits of `machinesim.urdf_checks` and `machinesim.urdf_structure` are
# importable from here, where they were defined until those modules were split off.
__all__ = ["AXIS_ORDER", "COARSEST_RESOLUTION_M", "COARSEST_RESOLUTION_RAD", "DEGREE_LIKE_RAD",
           "FINEST_RESOLUTION_M", "FINEST_RESOLUTION_RAD", "MAX_DEPTH", "MAX_LINKS",
           "MAX_PLACEMENT_M", "MAX_TRAVEL_M", "MAX_TRAVEL_RAD",
           "MAX_URDF_BYTES", "RAPID_RATE_M_PER_S", "RAPID_RATE_RAD_PER_S", "REQUIRED_FRAMES",
           "ZERO_POSE_TOL", "check_joint_frames", "check_tool_mount", "check_tree",
           "check_zero_pose", "joint_places", "read_axes", "read_urdf"]

#: NC letters in the order machinesim puts them in a configuration vector.
AXIS_ORDER = "XYZABC"
#: The joint types URDF has (lower case, as its parser reads them).
_URDF_JOINT_TYPES = ("fixed", "prismatic", "revolute", "continuous", "floating", "planar")


def read_urdf(path: Path, lines: dict[str, list[int]] | None = None) -> ET.Element:
    """The checked XML root of the URDF file ``path`` (`check_tree`).

    ``lines``, a dict, is filled with the line of each element a message may name
    (`_element_lines`), for `read_axes`.
    """
    try:
        with open(path, "rb") as file:
            data = file.read(MAX_URDF_BYTES + 1)
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the URDF file ({exc.strerror})") from None
    if not data.strip():  # expat: "not readable XML (no element found: line 1, column 0)"
        raise ModelError(f"{path}: the file is empty ({len(data)} bytes"
                         f"{', all blank' if data else ''}); expected a URDF, <robot name=...> "
                         "holding the machine's links and joints")
    if len(data) > MAX_URDF_BYTES:
        raise ModelError(f"{path}: larger than {MAX_URDF_BYTES // 2**20} MB; a machine's URDF "
                         "is a few kB (meshes are files of their own): expected at most "
                         f"{MAX_URDF_BYTES // 2**20} MB")
    try:
        # parsed from one buffer: expat, fed a file in 64 kB pieces, scans a token that
        # spans them again with each piece (a 200 MB comment took 9 minutes)
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        hint = ""
        if "unbound prefix" in str(exc):  # machinesim:axis and the like without xmlns
            hint = (f"; a prefixed tag such as <machinesim:axis> needs its namespace declared "
                    f"on <robot>: xmlns:machinesim=\"{_NS.strip('{}')}\"")
        elif "invalid token" in str(exc):
            hint = _encoding_hint(data)
        raise ModelError(f"{path}: not readable XML ({exc}){hint}") from None
    except RecursionError:
        raise ModelError(f"{path}: XML nested too deeply to be a URDF") from None
    except (LookupError, ValueError) as exc:
        # expat's: an encoding Python does not know (LookupError), or one of several bytes a
        # character it cannot read (ValueError: "multi-byte encodings are not supported",
        # a Japanese CAD tool's Shift_JIS); both ended the command as an internal error
        declared = re.search(rb"""^\s*<\?xml[^>]*encoding\s*=\s*["']([^"']*)""", data)
        name = declared[1].decode("ascii", "replace") if declared else "?"
        raise ModelError(f"{path}: its XML declaration gives encoding=\"{name}\", which the "
                         f"XML reader cannot read ({exc}); expected UTF-8, UTF-16 or a "
                         "single-byte encoding such as ISO-8859-1: save the file as UTF-8 "
                         "(and write encoding=\"UTF-8\", or no encoding)") from None
    depth = _depth(root)
    if depth > MAX_DEPTH:
        raise ModelError(f"{path}: XML nested {depth} elements deep; a URDF is at most a few "
                         f"(robot, link, visual, geometry, ...), expected at most {MAX_DEPTH}")
    found = _element_lines(data)
    if lines is not None:
        lines.update(found)
    if root.tag == "robot" and not found["xacro"]:  # else check_tree says what the file is
        _check_namespaces(path, found["foreign"])
    check_tree(root, path, found)
    return root


#: The namespaces of xml:lang, xml:space and xsi:schemaLocation, attributes no URDF reader
#: reads, which pass as machinesim's own elements do (and xacro's, which `check_tree`
#: refuses saying to expand the file).
_PASSING = ("http://www.w3.org/XML/1998/namespace", "http://www.w3.org/2001/XMLSchema-instance")


def _check_namespaces(path: Path, foreign: list[tuple[int, str, str, str]]) -> None:
    """Refuse the first element or attribute (outside a ``<gazebo>`` extension) in an XML
    namespace other than machinesim's: an ``<origin xmlns="...">`` (a default namespace on
    it or above it) is ``origin`` to urdfdom, which matches names as written, but this
    reader found no ``origin`` and dropped it, so a joint's placement loaded as zero
    without a word; a prefixed ``<ros:origin>`` both drop."""
    if not foreign:
        return
    line, kind, written, namespace = foreign[0]
    local = written.rpartition(":")[2]
    where = f"{path}, line {line}: {kind} {written!r}" if kind == "attribute" else \
        f"{path}, line {line}: <{written}>"
    if written.startswith("machinesim:"):
        hint = (f"machinesim's elements are in {_NS.strip('{}')!r}: declare "
                f"xmlns:machinesim=\"{_NS.strip('{}')}\" on <robot>")
    elif ":" not in written:
        hint = (f"a default xmlns=\"{namespace}\" on it or above it puts it there; URDF's "
                f"parser reads it as <{local}>, this reader would drop it: remove the "
                "xmlns=... attribute (URDF's elements are in no namespace)")
    else:
        hint = (f"neither URDF's parser nor this reader reads it (both drop it): remove it, "
                f"or write it as {local!r} in no namespace")
    raise ModelError(f"{where} is in the XML namespace {namespace!r}, which this reader does "
                     f"not read as URDF; {hint}")


def _encoding_hint(data: bytes) -> str:
    """Why expat found an invalid token, when the file is not the UTF-8 it reads a file
    without an encoding declaration as (a CAD tool's comment in Latin-1 or Shift-JIS: "1 µm"
    was "not well-formed (invalid token): line 1, column 28")."""
    if data.startswith((b"\xff\xfe", b"\xfe\xff")) or re.match(rb"\s*<\?xml[^>]*encoding", data):
        return ""
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1)
        return (f"; the file is not UTF-8 (byte 0x{data[exc.start]:02x} at line {line}, column "
                f"{column}) and declares no encoding: save it as UTF-8, or declare its "
                "encoding, e.g. <?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>")
    return ""


def _element_lines(data: bytes) -> dict[str, list[int] | array]:
    """The line of each ``<link>``, ``<joint>`` and ``<material>`` under ``<robot>``, of each
    element in a joint (key ``"in_joint"``, the joints' children one after the other), of
    each child and grandchild of a link (key ``"in_link"``, in the order of the file: a
    visual, then its origin, geometry ...) and of each ``<machinesim:axis>``, in the order of
    the file, by tag: ``findall`` gives the same elements in the same order, and ElementTree
    keeps no lines. ``data`` has parsed. The links' lines are 4 bytes each (an ``array``): a
    CAD export has 100,000s of visuals. Key ``"foreign"``: the first element or attribute below
    ``<robot>`` and outside a ``<gazebo>`` in a namespace neither machinesim's nor xacro's
    nor `_PASSING`, as (line, "element" or "attribute", its name as written, its namespace), for
    `_check_namespaces`; ``"xacro"``: whether the file has xacro's elements or attributes."""
    parser = expat.ParserCreate(namespace_separator="}")
    parser.namespace_prefixes = True  # "uri}local}prefix": tells <p:origin> from xmlns="uri"
    found: dict = {"link": [], "joint": [], "material": [], "in_joint": [], "axis": [],
                   "in_link": array("I"), "foreign": [], "xacro": False}
    depth = 0
    in_joint = in_link = False
    gazebo = 0  # the depth of the <gazebo> extension being read, 0 outside one

    def foreign(name: str, kind: str) -> None:
        namespace, _, local = name.partition("}")
        local, _, prefix = local.partition("}")
        if namespace.rstrip("/").endswith("xacro"):
            found["xacro"] = True
        elif namespace not in (_NS[1:-1], *_PASSING) and not gazebo and not found["foreign"]:
            written = f"{prefix}:{local}" if prefix else local
            found["foreign"].append((parser.CurrentLineNumber, kind, written, namespace))

    def start(tag, attributes):
        nonlocal depth, in_joint, in_link, gazebo
        depth += 1
        if depth == 2 and tag == "gazebo":
            gazebo = depth
        if depth > 1 and "}" in tag:
            foreign(tag, "element")
        for name in attributes:
            if "}" in name:
                foreign(name, "attribute")
        tag = tag.rpartition("}")[0] if tag.count("}") == 2 else tag  # the prefix dropped
        if depth == 2:
            in_joint, in_link = tag == "joint", tag == "link"
            if tag in ("link", "joint", "material"):
                found[tag].append(parser.CurrentLineNumber)
        elif depth == 3 and in_joint:
            found["in_joint"].append(parser.CurrentLineNumber)
        elif depth in (3, 4) and in_link:
            found["in_link"].append(parser.CurrentLineNumber)
        if tag == f"{_NS[1:]}axis":
            found["axis"].append(parser.CurrentLineNumber)

    def end(tag):
        nonlocal depth, gazebo
        if depth == gazebo:
            gazebo = 0
        depth -= 1

    parser.StartElementHandler, parser.EndElementHandler = start, end
    parser.Parse(data, True)
    return found


def _depth(root: ET.Element) -> int:
    """How many elements deep the tree under ``root`` goes (iteratively: a file nested
    100,000 deep overflows Python's stack in anything recursive, `ET.tostring` included).
    Level by level: a tuple per element on a stack took 1.3 s of the 7 s load of a 14 MB
    file of 260,000 visuals, this 0.2 s."""
    depth, level = 0, [root]
    while level:
        depth += 1
        level = [child for element in level for child in element]
    return depth


def read_axes(root: ET.Element, path: Path,
              lines: dict[str, list[int]] | None = None) -> tuple[Axis, ...]:
    """Axes of a machinesim URDF, in AXIS_ORDER, with side, direction and resolution.

    ``root`` has passed `check_tree`: a tree of uniquely named links and joints with finite
    origins. ``lines`` (`read_urdf`) puts the line of a joint in a message.
    """
    resolution, resolution_at = _resolutions(root, path, lines)
    links_parent = {j.find("child").get("link"): j for j in root.findall("joint")}

    def ancestors(link: str) -> set[str]:
        names = set()
        while link in links_parent:
            joint = links_parent[link]
            names.add(joint.get("name"))
            link = joint.find("parent").get("link")
        return names

    tool_side, wp_side = ancestors("tool_tip"), ancestors("workpiece")
    element_at = _in_joint_at(root, path, lines)
    axes = []
    limits_at = {}  # each axis joint's <limit> place, for a warning after the loop
    for index, joint in enumerate(root.findall("joint")):
        kind = joint.get("type")
        if kind == "fixed":
            continue
        name = joint.get("name")
        where = f"{_at(path, lines, 'joint', index)}: joint {name!r}"
        if kind not in _URDF_JOINT_TYPES:  # a typo or none: the joint may be meant fixed
            raise ModelError(f"{where}: type {kind!r} is not a URDF joint type; expected "
                             "fixed, or prismatic or revolute for a machine axis")
        if kind not in ("prismatic", "revolute"):
            raise ModelError(f"{where}: type {kind!r}; machine axes are prismatic or revolute "
                             "(a spindle is a revolute joint with wide limits)")
        if name not in AXIS_ORDER or len(name) != 1:
            raise ModelError(f"{where}: axis joints are named by their NC letter, one of "
                             f"{', '.join(AXIS_ORDER)}")
        if joint.find("mimic") is not None:
            raise ModelError(f"{where}: has a <mimic>; machinesim moves each axis by its own "
                             "NC letter (a gantry's second drive is one axis joint)")
        if (kind == "prismatic") != (name in "XYZ"):
            raise ModelError(f"{where}: type {kind!r}; X, Y and Z are linear axes (prismatic "
                             "joints), A, B and C rotary ones (revolute joints)")
        element = joint.find("axis")
        if element is None:
            raise ModelError(f"{where}: no <axis xyz=...>; a machine axis states its direction")
        joint_at = _at(path, lines, "joint", index)
        at_axis = f"{element_at.get(id(element), joint_at)}: joint {name!r}"  # its own line
        axis = _vector(element, "xyz", f"{at_axis} <axis>")
        k = int(np.argmax(np.abs(axis)))
        if np.count_nonzero(axis) != 1 or abs(abs(axis[k]) - 1.0) > 0:
            raise ModelError(f"{at_axis}: axis {axis.tolist()} must be a unit machine direction: "
                             "one of 1 0 0, 0 1 0, 0 0 1, either sign, each other number "
                             "exactly 0 (an axis tilted off them is not modelled; CAD "
                             "round-off such as 6.1e-17 is written 0)")
        if kind == "prismatic" and "XYZ"[k] != name:
            raise ModelError(f"{at_axis}: <axis xyz=\"{element.get('xyz')}\"> moves along "
                             f"{'XYZ'[k]}; the {name} axis moves along {name}"
                             f"{_turned_frame_hint(joint)}")
        if name in tool_side and name in wp_side:
            raise ModelError(f"{where}: carries both the tool_tip and the workpiece, so it "
                             "moves neither relative to the other; an axis joint is on one "
                             "side only")
        side = 1 if name in tool_side else -1 if name in wp_side else 0
        if side == 0:
            raise ModelError(f"{where}: moves neither the tool_tip nor the workpiece")
        expected_sign = 1.0 if side > 0 else -1.0
        if np.sign(axis[k]) != expected_sign:
            raise ModelError(
                f"{at_axis}: a {'tool' if side > 0 else 'workpiece'}-side axis must point "
                f"{'+' if side > 0 else '-'}{'XYZ'[k]} so that positive commands move the tool "
                f"positively relative to the workpiece (ISO 841){_turned_frame_hint(joint)}")
        if name not in resolution:
            raise ModelError(f"{where}: no <machinesim:axis joint=\"{name}\" resolution=...> "
                             f"element{_namespace_hint(root, name)}")
        coarsest = COARSEST_RESOLUTION_RAD if kind == "revolute" else COARSEST_RESOLUTION_M
        if resolution[name] > coarsest:
            unit = "rad" if kind == "revolute" else "m"
            raise ModelError(f"{resolution_at[name]}: <machinesim:axis joint={name!r}> resolution "
                             f"{resolution[name]!r} ({unit}); expected at most {coarsest:g} "
                             f"{unit} (SI: 1 nm is 1e-9)")
        finest = FINEST_RESOLUTION_RAD if kind == "revolute" else FINEST_RESOLUTION_M
        if resolution[name] < finest:
            unit = "rad" if kind == "revolute" else "m"
            raise ModelError(f"{resolution_at[name]}: <machinesim:axis joint={name!r}> resolution "
                             f"{resolution[name]!r} ({unit}); expected at least {finest:g} "
                             f"{unit} (1 pm: finer than any machine's scale; SI: 1 nm is 1e-9)")
        # a bad <limit> at its own line; no <limit> at the joint's
        at_limit = f"{element_at.get(id(joint.find('limit')), joint_at)}: joint {name!r}"
        lower, upper, velocity = _limits(joint, at_limit, kind == "revolute")
        limits_at[name] = at_limit
        if upper - lower < resolution[name]:  # no command moves it: travel or step mistyped
            unit = "rad" if kind == "revolute" else "m"
            raise ModelError(f"{at_limit}: <limit lower={lower!r} upper={upper!r}> ({unit}) "
                             f"spans {upper - lower:g} {unit}, less than one step of the "
                             f"axis' resolution {resolution[name]!r} {unit} "
                             f"({resolution_at[name]}): no command moves it; expected a "
                             "travel of at least one step (lengths in m, angles in rad)")
        axes.append(Axis(
            letter=name, rotary=kind == "revolute", side=side, direction=k,
            lower=lower, upper=upper, velocity=velocity, resolution=resolution[name]))
    linear = [(a.upper - a.lower, a) for a in axes if not a.rotary]
    if linear:  # a machine written in mm, every number under 10, passes every check above
        longest = max(linear, key=lambda pair: pair[0])[1]
        _millimetre_warning(limits_at[longest.letter], longest.letter, longest.lower,
                            longest.upper)
    if not axes:  # Pinocchio's model then has no axis to index: an IndexError at load
        raise ModelError(f"{path}: no axis joint; expected at least one, named by its NC "
                         "letter: X, Y, Z (prismatic) or A, B, C (revolute)")
    stray = sorted(set(resolution) - {a.letter for a in axes})
    if stray:
        raise ModelError(f"{path}: <machinesim:axis joint={stray[0]!r}> names no axis joint; "
                         f"the axis joints are {', '.join(sorted(a.letter for a in axes))}")
    return tuple(sorted(axes, key=lambda a: AXIS_ORDER.index(a.letter)))


def joint_places(root: ET.Element, path, lines: dict[str, list[int]] | None) -> dict[str, str]:
    """Each joint's place for a message, by name: the file and the joint's line (`read_urdf`
    fills ``lines``)."""
    return {joint.get("name"): _at(path, lines, "joint", index)
            for index, joint in enumerate(root.findall("joint"))}


def _resolutions(root: ET.Element, path: Path, lines: dict[str, list[int]] | None = None
                 ) -> tuple[dict[str, float], dict[str, str]]:
    """Command resolution (m or rad) of each axis, from the machinesim:axis elements, and
    where each is written (the file and its line) for a message."""
    found: dict[str, float] = {}
    written: dict[str, str] = {}
    for index, element in enumerate(root.iter(f"{_NS}axis")):
        joint = element.get("joint")
        at = _at(path, lines, "axis", index)
        where = f"{at}: <machinesim:axis joint={joint!r}>"
        if not joint:
            raise ModelError(f"{at}: a <machinesim:axis> has no joint=...")
        if joint in found:
            raise ModelError(f"{where}: given twice; one resolution per axis")
        text = element.get("resolution")
        if text is None:
            raise ModelError(f"{where}: no resolution=... (m or rad)")
        value = _number(text, f"{where} resolution")
        if not value > 0.0:
            raise ModelError(f"{where}: resolution {value!r}; expected > 0 (m or rad)")
        found[joint] = value
        written[joint] = at
    return found, written
