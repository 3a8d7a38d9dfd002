"""The tool table: tool lengths (G43/G44 H words), radii (D words) and shapes by tool number.

A TOML file with one table per tool, units in the keys::

    [tool.1]
    length_mm = 2.5       # tool length, read by H1 under G43/G44 and carried by T1 in the cut
    radius_mm = 0.5       # tool radius, the D1 register (only listed: G41/G42 are refused)
    shape = "ball:0.5"    # optional: the tool's solid, a `tool_specs.tool_from_spec` spec
    name = "R0.5 ball end mill"   # optional

    [tool.2]
    length_um = 48012.5   # any length unit machinesim reads: m, mm, um, nm

H and D numbers are the tool numbers (``H1`` reads ``[tool.1]``), as CAM posts write them;
``H0`` and ``D0`` are zero by definition. A tool may give only a length or only a radius.

A length is measured from the machine model's ``tool_tip`` (where the tool the model carries
has its edge) along the tool's axis: the tool in the spindle after a change (`ToolChange`)
has its edge that far beyond ``tool_tip``, and ``G43 H<n>`` lifts Z by the same amount, so
a tool whose H matches its T cuts at the programmed point.
"""

from __future__ import annotations

import math
import os
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from machinesim._io import check_readable_file
from machinesim.arrays import beyond_float64
from machinesim.exceptions import InputError, NCProgramError
from machinesim.nc.program import FrozenMapping
from machinesim.tool_specs import tool_from_spec
from machinesim.units import LENGTH

#: Largest tool number read: 8 digits, as FANUC's T words (H and D registers are fewer).
MAX_TOOL_NUMBER = 99999999
_TOOL_NUMBER = re.compile(r"[0-9]+")


@dataclass(frozen=True)
class Tool:
    """One tool's offsets, SI.

    Attributes
    ----------
    length_m : float or None
        Tool length offset, m (None: not given).
    radius_m : float or None
        Tool radius, m (None: not given).
    name : str
    shape : str or None
        The tool's solid as a `machinesim.tool_specs.tool_from_spec` spec (None: the cut's own
        tool, ``--tool`` on the command line).
    """

    length_m: float | None = None
    radius_m: float | None = None
    name: str = ""
    shape: str | None = None


@dataclass(frozen=True)
class ToolChange:
    """A tool put in the spindle: from move ``move`` on, tool ``number`` cuts.

    ``length_m`` (the table's length, 0 when it gives none) places the tool's edge that far
    beyond the model's ``tool_tip`` along the tool axis; ``shape`` (None: the cut's own tool)
    is its solid; ``radius_m`` the table's radius (None: not given), checked against the
    cut's own tool when there is no shape. Read by `machinesim.nc.read_program` from T
    words: at each M06 the last T selected, or, in a program without M06, each T itself.
    """

    move: int
    number: int
    line: int
    length_m: float = 0.0
    shape: str | None = None
    radius_m: float | None = None


@dataclass(frozen=True)
class ToolTable:
    """Tools by number, read from TOML (`from_toml`) or a dict (`from_dict`)."""

    tools: Mapping[int, Tool]
    source: str = "<tools>"

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> ToolTable:
        """Read a tool table file (layout in the module docstring)."""
        from machinesim.errors.toml import read_toml_lines

        path = check_readable_file(path, "tool table")
        data, lines = read_toml_lines(path, NCProgramError)
        return cls.from_dict(data, source=str(path), lines=lines)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str = "<tools>",
                  lines: Mapping[str, int] | None = None) -> ToolTable:
        """A tool table from ``{"tool": {"1": {"length_mm": 50.0}, ...}}``; ``lines``, the
        line of each key path in ``source`` (`machinesim.errors.toml.key_lines`), puts the
        line in a refusal's message."""
        lines = lines or {}
        if not isinstance(data, Mapping) or set(data) - {"tool"}:
            extra = sorted(set(data) - {"tool"}) if isinstance(data, Mapping) else data
            first = extra[0] if isinstance(data, Mapping) else None
            raise NCProgramError(f"a tool table has only [tool.<number>] tables, got {extra!r}",
                                 **_where(source, "tool", lines, first))
        tables = data.get("tool", {})
        if not isinstance(tables, Mapping):
            raise NCProgramError("'tool' must be tables [tool.<number>]",
                                 **_where(source, "tool", lines))
        tools = []
        for name, entry in tables.items():
            key = f"tool.{name}"
            text = str(name)
            # ASCII digits, as a T, H or D word is written: str.isdigit() also passed '²',
            # which int() refused with an internal ValueError, and '١' or '１', read as 1
            if not _TOOL_NUMBER.fullmatch(text) or int(text) > MAX_TOOL_NUMBER:
                raise NCProgramError(f"tool number must be an unsigned integer up to "
                                     f"{MAX_TOOL_NUMBER}, got {text!r}",
                                     **_where(source, key, lines))
            if not isinstance(entry, Mapping):
                raise NCProgramError(f"[{key}] must be a table, got {entry!r}",
                                     **_where(source, key, lines))
            tools.append((int(text), _tool(entry, source, key, lines)))
        numbers = [n for n, _ in tools]
        if len(set(numbers)) != len(numbers):
            number = next(n for n in numbers if numbers.count(n) > 1)
            both = [f"tool.{name}" for name in tables if int(str(name)) == number]
            raise NCProgramError(f"tool {number} is given twice, as [{both[0]}] and "
                                 f"[{both[1]}]; expected each tool number once",
                                 **_where(source, "tool", lines, both[1]))
        return cls(FrozenMapping(sorted(tools)), source)

    def length(self, number: int) -> float:
        """Length offset of tool ``number``, m (0 for H0)."""
        return self._value(number, "length")

    def radius(self, number: int) -> float:
        """Radius of tool ``number``, m (0 for D0)."""
        return self._value(number, "radius")

    def change(self, move: int, number: int, line: int) -> ToolChange:
        """The `ToolChange` that puts tool ``number`` in the spindle at move ``move``."""
        tool = self.tools.get(number)
        if tool is None:
            return ToolChange(move, number, line)
        return ToolChange(move, number, line, tool.length_m or 0.0, tool.shape, tool.radius_m)

    def _value(self, number: int, what: str) -> float:
        if number == 0:
            return 0.0
        tool = self.tools.get(number)
        value = None if tool is None else getattr(tool, f"{what}_m")
        if value is None:
            have = " ".join(str(n) for n in self.tools) or "none"
            raise KeyError(f"the tool table {self.source} has no {what} for tool {number} "
                           f"(tools: {have})")
        return value


def _where(source: str, key: str, lines: Mapping[str, int],
           at: str | None = None) -> dict[str, Any]:
    """The ``source``, ``line`` and ``key`` of a refusal of ``key``, its line that of the key
    path ``at`` (default ``key``) when ``lines`` has it."""
    return {"source": source, "line": lines.get(key if at is None else at), "key": key}


def _tool(entry: Mapping[str, Any], source: str, key: str,
          lines: Mapping[str, int]) -> Tool:
    values: dict[str, float] = {}
    name, shape = "", None
    for field, value in entry.items():
        where = _where(source, f"{key}.{field}", lines)
        if field == "name":
            if not isinstance(value, str):
                raise NCProgramError(f"name must be a string, got {value!r}", **where)
            name = value
            continue
        if field == "shape":
            shape = _shape(value, where)
            continue
        what, _, unit = field.rpartition("_")
        if what not in ("length", "radius"):
            raise NCProgramError(f"unknown key {field!r}; a tool has length_<unit>, "
                                 "radius_<unit>, shape and name", **where)
        if unit not in LENGTH:
            raise NCProgramError(f"unknown length unit {unit!r} in {field!r}; expected one "
                                 f"of {', '.join(LENGTH)}", **where)
        if what in values:
            raise NCProgramError(f"{what} is given twice", **where)
        if (huge := beyond_float64(value)) is not None:  # math.isfinite overflowed on it
            raise NCProgramError(f"{field} must be a finite number, got {huge}", **where)
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(
                value):
            raise NCProgramError(f"{field} must be a finite number, got {value!r}", **where)
        si = float(value) * LENGTH[unit]
        if what == "radius" and si < 0.0:
            raise NCProgramError(f"{field} must be >= 0, got {value!r}", **where)
        if abs(si) > 10.0:
            raise NCProgramError(f"{field} = {value!r} is beyond 10 m; expected a tool "
                                 "offset", **where)
        values[what] = si
    return Tool(values.get("length"), values.get("radius"), name, shape)


def _shape(value: Any, where: Mapping[str, Any]) -> str:
    """A tool table's ``shape``, checked by building the tool it names."""
    if not isinstance(value, str):
        raise NCProgramError(f"shape must be a tool spec string such as \"ball:0.5\", got "
                             f"{value!r}", **where)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            tool_from_spec(value)
        except InputError as error:
            raise NCProgramError(str(error.args[0] if error.args else error), **where) from None
    # a warning on the spec (`flat:500`, a radius perhaps in um) named the spec alone, not
    # the table or line it came from: said again with them
    for warning in said:  # located as a refusal of the same key is
        warnings.warn(str(NCProgramError(str(warning.message), **where)), warning.category,
                      stacklevel=2)
    return value


def table_tool(shape: str):
    """The tool a table's ``shape`` names (`tool_from_spec`), built again where a cut changes
    to it: its warnings, said at the table's line when it was read (`_shape`), not again
    without it."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tool_from_spec(shape)


def tool_table(tools: Any) -> ToolTable | None:
    """``tools`` as a ToolTable: None, a ToolTable, a path to TOML, or a dict."""
    if tools is None or isinstance(tools, ToolTable):
        return tools
    if isinstance(tools, str | os.PathLike):
        return ToolTable.from_toml(tools)
    if isinstance(tools, Mapping):
        return ToolTable.from_dict(tools)
    raise NCProgramError(f"tools must be a tool table path, a dict or a ToolTable, got "
                         f"{type(tools).__name__}", key="tools")
