"""How the URDF parser under Pinocchio (urdfdom, C++ streams) reads a URDF's numbers, and
where an element stands in the file: the readers that refuse what that parser would, named
at the element's line, before it reads the file.

`_number` reads one number (ASCII digits, a point, an exponent: `_URDF_NUMBER`), `_fields`
splits an attribute of several at spaces only, `_vector` reads three, and `_at` puts an
element's line in a message (`machinesim.urdf_structure`, `machinesim.urdf_elements`).
"""

from __future__ import annotations

import math
import re
import unicodedata
import xml.etree.ElementTree as ET

import numpy as np

from machinesim.exceptions import ModelError

#: A number as the URDF parser under Pinocchio (urdfdom, a C++ stream) reads one: ASCII
#: digits, a point, an exponent, ASCII blanks before it only. Python's float() reads more
#: ("1_000", Arabic-Indic digits, a trailing blank, a no-break space before it), which the
#: parser then refused without naming the joint.
_URDF_NUMBER = re.compile(r"[ \t\n\r]*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def _at(path, lines: dict[str, list[int]] | None, tag: str, index: int) -> str:
    """``path`` and the line of the ``index``-th ``tag`` element when known."""
    found = (lines or {}).get(tag, ())
    return f"{path}, line {found[index]}" if index < len(found) else f"{path}"


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


def _fields(text: str) -> list[str]:
    """The numbers of a URDF attribute of several (``xyz``, a box's ``size``, a mesh's
    ``scale``) as the URDF parser splits them: at spaces only. ``str.split()`` splits at any
    Unicode blank too, so ``xyz="0\u00a00 0.05"`` (a no-break space, as a word processor or
    web page writes one) read as three numbers here, and the parser refused the file with
    lines of C++ on stderr and a message that named neither the joint nor the value."""
    return [field for field in text.split(" ") if field]


def _blank_hint(text: str) -> str:
    """For attribute text holding a blank that is not a space (a no-break space, a tab or
    line end written as a character reference): which, since ``repr`` shows it as a code."""
    odd = sorted({c for c in text if c.isspace() and c != " "})
    if not odd:
        return ""
    named = ", ".join(f"U+{ord(c):04X} {unicodedata.name(c, 'a control character')}"
                      for c in odd)
    return f" ({named} separates no numbers for the URDF parser: write plain spaces)"


def _vector(element: ET.Element, attribute: str, where: str,
            default: str | None = None) -> np.ndarray:
    """Three finite floats from a URDF attribute (``xyz``, ``rpy``), split as the URDF
    parser splits them (`_fields`)."""
    text = element.get(attribute, default)
    if text is None:
        raise ModelError(f"{where}: no {attribute}=...; expected three numbers")
    fields = _fields(text)
    if len(fields) != 3:
        raise ModelError(f"{where}: {attribute}={text!r}; expected three numbers"
                         f"{_blank_hint(text)}")
    return np.array([_number(f, f"{where} {attribute}") for f in fields])
