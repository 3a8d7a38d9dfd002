"""What a machinesim URDF must be as a file: one tree of URDF elements, checked before
anything walks it.

`check_tree` checks the structure (`machinesim.urdf.read_urdf` calls it): one tree of
uniquely named links and joints, no cycle, one root, the frames every machine has
(`REQUIRED_FRAMES`), finite origins within a machine's size (`MAX_PLACEMENT_M`), no xacro,
no element given twice where URDF allows one, URDF's shapes, no name of machinesim's error
joints; with the file's size, depth and link-count limits (`MAX_URDF_BYTES`, `MAX_DEPTH`,
`MAX_LINKS`). The readers of URDF numbers that refuse what the URDF parser under Pinocchio
would, and `_at`, which puts an element's line in a message, are
`machinesim.urdf_reading`'s; the optional elements' checks `machinesim.urdf_elements`'.
A bad file is a located `ModelError` (file, line, joint or link, value, what was expected),
never a hang or a traceback. What the machine's axes and its nominal kinematics must
satisfy is `machinesim.urdf_checks`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from machinesim.exceptions import ModelError
from machinesim.kinematics import DOFS
from machinesim.urdf_elements import (
    _check_joint_numbers,
    _check_materials,
    _check_rgba,
    _check_version,
    _rgba_read,
)
from machinesim.urdf_reading import _at, _fields, _number, _vector

__all__ = ["MAX_DEPTH", "MAX_LINKS", "MAX_PLACEMENT_M", "MAX_URDF_BYTES", "REQUIRED_FRAMES",
           "check_tree"]

#: Frames every machine has.
REQUIRED_FRAMES = ("base", "table", "workpiece", "tool_mount", "tool_tip")
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
#: How far (m, each coordinate) a joint may sit from its parent link: a machine's parts lie
#: within metres of each other, and a file whose origins are written in mm (its limits in m)
#: loads with every Abbe offset a thousand times too long.
MAX_PLACEMENT_M = 10.0


def _in_joint_at(root: ET.Element, path, lines: dict[str, list[int]] | None
                 ) -> dict[int, str]:
    """``path`` and the line of each element in a joint (its ``<origin>``, ``<axis>`` ...),
    by ``id`` of the element, when ``lines`` (`read_urdf`'s ``"in_joint"``) has them all:
    a bad ``<axis>`` or ``<origin>`` is named at its own line, not its joint's."""
    found = (lines or {}).get("in_joint", ())
    children = [child for joint in root.findall("joint") for child in joint]
    if len(children) != len(found):
        return {}
    return {id(child): f"{path}, line {line}"
            for child, line in zip(children, found, strict=True)}


def _link_origin_at(root: ET.Element, path, lines: dict[str, list[int]] | None,
                    origin: ET.Element) -> str:
    """Where ``origin`` (not a joint's) is, for a message: ``path``, its line and its link
    (a visual's, a collision's or the inertial's origin) when `read_urdf`'s ``"in_link"``
    has its line; else ``path`` alone (an origin outside the links)."""
    found = _in_link_at(root, path, lines, origin)
    if found is None:
        return f"{path}: an <origin>"
    at, link, child = found
    inside = "" if origin is child else f" <{child.tag}>"
    return f"{at}: link {link.get('name')!r}{inside} <origin>"


def _in_link_at(root: ET.Element, path, lines: dict[str, list[int]] | None,
                wanted: ET.Element) -> tuple[str, ET.Element, ET.Element] | None:
    """``path`` with the line of ``wanted``, a child or grandchild of a link, when
    `read_urdf`'s ``"in_link"`` has it (else ``path`` alone), its link and the link's child
    that holds it; None when no link holds it."""
    found = (lines or {}).get("in_link", ())
    count = 0
    for link in root.findall("link"):
        for child in link:
            for element in (child, *child):
                if element is wanted:
                    at = f"{path}, line {found[count]}" if count < len(found) else f"{path}"
                    return at, link, child
                count += 1
    return None


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
    collision with a shape in its ``<geometry>``, a box, cylinder, sphere or mesh with
    positive sizes, and a visual's ``<material>`` named; every ``<inertial>`` with its mass
    and inertia.

    Raises
    ------
    ModelError
        Naming ``path``, the line of the joint or link when ``lines`` (`read_urdf`) has
        it, the joint or link, and the value.
    """
    if root.tag != "robot":
        namespace, _, local = root.tag.rpartition("}")
        if local == "robot" and namespace:
            # a default xmlns="..." on <robot> (xacro writes one for xacro:targetNamespace)
            # puts every element in that namespace: urdfdom, which matches names as
            # written, ignores it; this reader finds none of <robot>'s links and joints
            raise ModelError(f"{path}: root element <robot> in the XML namespace "
                             f"{namespace.lstrip('{')!r} (a default "
                             f"xmlns=\"{namespace.lstrip('{')}\" on it); expected <robot> "
                             "in no namespace, as URDF's elements are: remove the xmlns=... "
                             "attribute from <robot> (a prefixed xmlns:name=... stays)")
        raise ModelError(f"{path}: root element <{root.tag}>; expected <robot>")
    if not root.get("name"):
        raise ModelError(f"{path}: <robot> has no name=...; URDF requires one")
    _check_version(root, path)
    _check_not_xacro(root, path)
    count = len(root.findall("link"))
    if count > MAX_LINKS:
        raise ModelError(f"{path}: {count} links; a machine has tens (a CAD export of every "
                         f"part a few hundred): expected at most {MAX_LINKS}")
    links: set[str] = set()
    in_link = (lines or {}).get("in_link", ())
    inside = 0  # the links' children and grandchildren before this link's, for their lines
    for index, link in enumerate(root.findall("link")):
        at = _at(path, lines, "link", index)
        name = _unique_name(link, "link", at, links)
        count = len(link) + sum(len(child) for child in link)
        _check_link_once(link, f"{at}: link {name!r}", in_link[inside:inside + count])
        inside += count
        links.add(name)
    joints: dict[str, ET.Element] = {}
    parent_joint: dict[str, str] = {}  # child link -> the joint that carries it
    parent_link: dict[str, str] = {}  # joint -> its parent link
    in_joint = (lines or {}).get("in_joint", [])
    children = 0  # the joints' children before this joint's, for their lines
    element_at = _in_joint_at(root, path, lines)
    for index, joint in enumerate(root.findall("joint")):
        at = _at(path, lines, "joint", index)
        name = _unique_name(joint, "joint", at, joints)
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
            named = f"{element_at.get(id(origin), at)}: joint {name!r}"
            xyz = _vector(origin, "xyz", f"{named} <origin>", "0 0 0")
            _vector(origin, "rpy", f"{named} <origin>", "0 0 0")
            if np.abs(xyz).max() > MAX_PLACEMENT_M:
                raise ModelError(f"{named} <origin xyz={origin.get('xyz')!r}> (m); expected "
                                 f"each coordinate within +-{MAX_PLACEMENT_M:g} m of the parent "
                                 "link (URDF lengths are metres: 100 mm is 0.1)")
        limit = joint.find("limit")
        if limit is not None and joint.get("type") == "fixed":  # axes: `_limits`
            named = f"{element_at.get(id(limit), at)}: joint {name!r}"  # its own line
            for attribute in ("effort", "velocity"):
                text = limit.get(attribute)
                if text is None:
                    raise ModelError(f"{named}: <limit> has no {attribute}=...; URDF requires "
                                     "effort and velocity on every <limit> (a fixed joint "
                                     "needs no <limit>)")
                _number(text, f"{named} <limit {attribute}>")
            for attribute in ("lower", "upper"):
                if limit.get(attribute) is not None:
                    _number(limit.get(attribute), f"{named} <limit {attribute}>")
        _check_joint_numbers(joint, name, element_at, at)
    _check_materials(root, path, lines)
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
        try:
            _vector(element, "xyz", f"{path}: an <origin>", "0 0 0")
            _vector(element, "rpy", f"{path}: an <origin>", "0 0 0")
        except ModelError:  # refused again naming its line and link, looked up only now
            where = _link_origin_at(root, path, lines, element)
            _vector(element, "xyz", where, "0 0 0")
            _vector(element, "rpy", where, "0 0 0")
            raise
    for link in root.findall("link"):
        for kind in ("visual", "collision"):
            for part in link.findall(kind):
                _check_shaped(root, path, lines, link, kind, part)
            for geometry in link.findall(f"{kind}/geometry"):
                for element in geometry:
                    try:
                        _check_shape(element, f"{path}: link {link.get('name')!r} <{kind}>")
                    except ModelError:  # refused again at its <geometry>'s line, found now
                        at = _in_link_at(root, path, lines, geometry)[0]
                        _check_shape(element, f"{at}: link {link.get('name')!r} <{kind}>")
                        raise
        for inertial in link.findall("inertial"):
            _check_inertial(root, path, lines, link, inertial)


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
    include = root.find("include")  # SDF's, or xacro's written without its prefix
    if include is not None:
        raise ModelError(f"{path}: <include filename={include.get('filename')!r}> is not URDF: "
                         "its parser drops it, and the links and joints of that file with it "
                         "(they loaded missing, or without a word); write them into this "
                         f"file, or, for a xacro file's <xacro:include>, {expand}")


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


def _check_shaped(root: ET.Element, path, lines, link: ET.Element, kind: str,
                  part: ET.Element) -> None:
    """A link's ``<visual>`` or ``<collision>`` (``kind``, ``part``) with a shape in its
    ``<geometry>``, and a visual's ``<material>`` with a ``name`` attribute: the URDF parser
    under Pinocchio drops such a part otherwise, saying so on stderr only ("Could not parse
    visual element for Link [table]"), and the machine loaded with the link drawn without
    it. An empty name (``name=""``) it reads, visual kept, so that is no refusal. Named at
    the part's line (`_in_link_at`)."""
    geometry = part.find("geometry")
    material = part.find("material") if kind == "visual" else None
    color = None if material is None else material.find("color")
    rgba = None if color is None else color.get("rgba")
    if geometry is not None and len(geometry) and (material is None or (
            material.get("name") is not None and (rgba is None or _rgba_read(rgba)))):
        return
    found = _in_link_at(root, path, lines, part)
    where = f"{found[0] if found else path}: link {link.get('name')!r} <{kind}>"
    if geometry is None or not len(geometry):
        what = "has no <geometry>" if geometry is None else "has an empty <geometry>"
        raise ModelError(f"{where}: {what}; expected one shape in it (a box, cylinder, "
                         f"sphere or mesh): the URDF parser drops a {kind} without one")
    if material.get("name") is None:
        raise ModelError(f"{where}: a <material> has no name=...; URDF requires one (the "
                         "parser drops the visual without it): name it, e.g. <material "
                         "name=\"grey\">")
    _check_rgba(rgba, f"{where} <material name={material.get('name')!r}>")


#: The attributes of an ``<inertia>``, each a number the URDF parser requires.
_INERTIA = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def _check_inertial(root: ET.Element, path, lines, link: ET.Element,
                    inertial: ET.Element) -> None:
    """A link's ``<inertial>`` with a ``<mass value>`` and an ``<inertia>`` of its six
    numbers: the URDF parser under Pinocchio drops an inertial without them, saying so on
    stderr only ("Inertial: mass element must have value attribute", "Could not parse
    inertial element for Link [table]"), and the machine loaded. machinesim uses no mass,
    but a URDF check refuses the file. Named at the inertial's line (`_in_link_at`)."""
    mass, inertia = inertial.find("mass"), inertial.find("inertia")
    if (mass is not None and mass.get("value") is not None and inertia is not None
            and all(inertia.get(name) is not None for name in _INERTIA)):
        try:  # numbers, finite, as the parser reads them (refused again where found)
            _number(mass.get("value"), "")
            for name in _INERTIA:
                _number(inertia.get(name), "")
            return
        except ModelError:
            pass
    found = _in_link_at(root, path, lines, inertial)
    where = f"{found[0] if found else path}: link {link.get('name')!r} <inertial>"
    if mass is None or mass.get("value") is None:
        raise ModelError(f"{where}: no <mass value=...> (kg); URDF requires one in an "
                         "<inertial>, whose parser drops it otherwise: give it, or leave "
                         "the <inertial> out (machinesim uses no mass)")
    _number(mass.get("value"), f"{where} <mass value>")
    if inertia is None:
        raise ModelError(f"{where}: no <inertia ixx=... izz=...> (kg m^2); URDF requires one "
                         "in an <inertial>: give it, or leave the <inertial> out")
    for name in _INERTIA:
        text = inertia.get(name)
        if text is None:
            raise ModelError(f"{where}: <inertia> has no {name}=...; expected "
                             f"{', '.join(_INERTIA)} (kg m^2)")
        _number(text, f"{where} <inertia {name}>")


def _check_shape(element: ET.Element, where: str) -> None:
    """A visual or collision shape with its sizes positive and finite (a mesh with a file
    name, and a scale of three numbers if it has one), so that a bad one is a located
    ModelError rather than a C++ message of the URDF parser on stderr and a link drawn
    without it."""
    if element.tag not in _SHAPE_SIZES:
        raise ModelError(f"{where}: <{element.tag}>; expected a box, cylinder, sphere or mesh")
    if element.tag == "mesh" and not element.get("filename"):
        raise ModelError(f"{where}: a <mesh> has no filename=...")
    if element.tag == "mesh" and element.get("scale") is not None:
        # the URDF parser drops the whole visual of a scale it cannot read, saying so on
        # stderr only (or takes 1 1 1), so a mesh in mm scaled "0.001 0.001" was not drawn
        text = element.get("scale")
        fields = _fields(text)
        for field in fields:
            _number(field, f"{where} <mesh scale>")
        if len(fields) != 3:
            raise ModelError(f"{where}: <mesh scale={text!r}>; expected three numbers, the "
                             "factor along each axis of the file's coordinates (0.001 0.001 "
                             "0.001 for a mesh in mm)")
    for attribute, count in _SHAPE_SIZES[element.tag].items():
        text = element.get(attribute)
        fields = [] if text is None else _fields(text)
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


def _unique_name(element: ET.Element, kind: str, at: str, seen) -> str:
    """The name of a <link> or <joint> (``kind``) at ``at``: refused when it has none, when
    ``seen`` (the names before it) holds it, or when it is reserved (`_check_reserved`)."""
    name = element.get("name")
    if not name:
        raise ModelError(f"{at}: a <{kind}> has no name=...")
    if name in seen:
        raise ModelError(f"{at}: {kind} {name!r} is defined twice; {kind} names are unique")
    _check_reserved(name, kind, at)
    return name


def _check_reserved(name: str, kind: str, path) -> None:
    if "__" in name or name in _RESERVED:
        raise ModelError(f"{path}: {kind} name {name!r} is reserved for machinesim's error "
                         "joints (names with '__', tool_tx .. workpiece_rz); rename it")


def _some(names, count: int = 8) -> str:
    names = sorted(names)
    shown = ", ".join(repr(n) for n in names[:count])
    return shown + (f", ... ({len(names)} in all)" if len(names) > count else "")
