"""The optional elements of a URDF as the URDF parser under Pinocchio reads them: a
joint's ``<dynamics>``, ``<safety_controller>``, ``<calibration>`` and ``<mimic>``, the
``<material>`` colours under ``<robot>`` and in visuals, and ``<robot version>``.

machinesim uses none of them, but that parser refuses the whole file for one it cannot
read, saying which on stderr only, in lines of C++ above one line that names neither the
element nor the file's line, or drops it without a word (a colour drawn black). Each is
refused here at its line (`machinesim.urdf_structure.check_tree` calls these).
"""

from __future__ import annotations

import functools
import re
import xml.etree.ElementTree as ET

from machinesim.exceptions import ModelError
from machinesim.urdf_reading import _URDF_NUMBER, _at, _fields, _number

#: The other elements of a joint the URDF parser under Pinocchio reads, each with its number
#: attributes and the one it requires: it refuses the whole file for one that is missing or
#: not a number (`_number`), saying which on stderr only, in lines of C++ above the one
#: line "The XML stream does not contain a valid URDF model" that named neither the joint
#: nor the file's line (a fixed joint's <dynamics damping="nan">, a <safety_controller>
#: without k_velocity, a <mimic> without joint=...).
_JOINT_NUMBERS = {"dynamics": (("damping", "friction"), None),
                  "safety_controller": (("soft_lower_limit", "soft_upper_limit", "k_position",
                                         "k_velocity"), "k_velocity"),
                  "calibration": (("rising", "falling"), None),
                  "mimic": (("multiplier", "offset"), "joint")}


def _check_joint_numbers(joint: ET.Element, name: str, element_at: dict[int, str],
                         at: str) -> None:
    """A joint's ``<dynamics>``, ``<safety_controller>``, ``<calibration>`` and ``<mimic>``
    as the URDF parser reads them (`_JOINT_NUMBERS`): their number attributes numbers, the
    attribute each requires there, and a ``<dynamics>`` with damping or friction. Named at
    the element's own line (``element_at``, else ``at``, the joint's)."""
    for tag, (numbers, required) in _JOINT_NUMBERS.items():
        element = joint.find(tag)
        if element is None:
            continue
        named = f"{element_at.get(id(element), at)}: joint {name!r}"
        if required is not None and element.get(required) is None:
            raise ModelError(f"{named}: <{tag}> has no {required}=...; URDF requires it (its "
                             f"parser refuses the file without it): give it, or leave the "
                             f"<{tag}> out (machinesim does not use it)")
        for attribute in numbers:
            if element.get(attribute) is not None:
                _number(element.get(attribute), f"{named} <{tag} {attribute}>")
        if tag == "dynamics" and not any(element.get(a) is not None for a in numbers):
            raise ModelError(f"{named}: <dynamics> has neither damping=... nor friction=...; "
                             "URDF requires one (its parser refuses the file otherwise): give "
                             "it, or leave the <dynamics> out (machinesim does not use it)")


def _check_materials(root: ET.Element, path, lines: dict[str, list[int]] | None) -> None:
    """The ``<material>`` elements under ``<robot>`` (the visuals' colours by name), each
    named, and each name once: the URDF parser refuses the whole file for a name given twice
    ("material 'grey' is not unique" in C++ on stderr, then "The XML stream does not contain
    a valid URDF model", naming no material), and drops one without a name with a message
    on stderr only."""
    seen = set()
    for index, material in enumerate(root.findall("material")):
        name, at = material.get("name"), _at(path, lines, "material", index)
        if not name:
            raise ModelError(f"{at}: a <material> under <robot> has no name=...; URDF requires "
                             "one (its parser drops it): name it, as the visuals that use it "
                             "do, e.g. <material name=\"grey\">")
        color = material.find("color")
        if color is not None and color.get("rgba") is None:
            raise ModelError(f"{at}: <material name={name!r}> has a <color> without rgba=...; "
                             "URDF requires it there (its parser drops the material, and the "
                             "visuals that name it are drawn without it)")
        _check_rgba(None if color is None else color.get("rgba"),
                    f"{at}: <material name={name!r}>")
        if name in seen:
            first = _at(path, lines, "material",
                        [m.get("name") for m in root.findall("material")].index(name))
            raise ModelError(f"{at}: <material name={name!r}> is defined twice under <robot> "
                             f"(first at {first.rpartition(', ')[2]}); URDF requires each name "
                             "once (its parser refuses the file): keep the one meant")
        seen.add(name)


#: A ``<robot version>`` as the URDF parser under Pinocchio reads it, "MAJOR.MINOR", and
#: the versions it reads.
_VERSION = re.compile(r"\s*\+?([0-9]+)\.\s*([+-]?[0-9]+)")
_VERSIONS = ((1, 0), (1, 1), (1, 2))


def _check_version(root: ET.Element, path) -> None:
    """Refuse a ``<robot version>`` the URDF parser refuses (``2.0``, ``1``, ``1.0.0``): it
    did so in C++ lines on stderr, and machinesim's one line said only "The XML stream does
    not contain a valid URDF model", naming neither the attribute nor its value."""
    text = root.get("version")
    if text is None:
        return
    match = _VERSION.fullmatch(text)
    if match is None or (int(match[1]), int(match[2])) not in _VERSIONS:
        raise ModelError(f"{path}: <robot version={text!r}>; expected a URDF version the URDF "
                         f"parser reads, {', '.join(f'{a}.{b}' for a, b in _VERSIONS)} "
                         "(or none: 1.0)")


@functools.lru_cache(maxsize=256)  # a CAD export's 100,000s of visuals share a few colours
def _rgba_read(text: str) -> bool:
    """Whether a ``<color rgba>`` reads as the URDF parser reads one: four numbers (split at
    spaces, `_fields`), each from 0 to 1."""
    fields = _fields(text)
    return len(fields) == 4 and all(_URDF_NUMBER.fullmatch(field) and 0.0 <= float(field) <= 1.0
                                    for field in fields)


def _check_rgba(rgba: str | None, where: str) -> None:
    """Refuse a ``<color rgba>`` the URDF parser misreads: one outside 0 .. 1 or not a number
    it drops with a C++ message on stderr only ("Material [grey] has malformed color rgba
    values"), and three numbers (``rgba="0.5 0.5 0.5"``, an alpha left out) or five it
    takes without a word as black, so the machine was drawn in other colours than the
    file's."""
    if rgba is None or _rgba_read(rgba):
        return
    raise ModelError(f"{where}: <color rgba={rgba!r}>; expected four numbers from 0 to 1, "
                     "red, green, blue and alpha (1 opaque), separated by spaces: the URDF "
                     "parser drops or misreads another colour")
