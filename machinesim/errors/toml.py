"""Error models read from and written to TOML or its dict (the layout: `machinesim.errors`).

`ErrorModel.from_dict`, `to_dict`, `from_toml` and `to_toml` call these functions.
"""

from __future__ import annotations

import math
import os
import re
import stat
import tomllib
from collections.abc import Mapping
from decimal import Decimal
from fractions import Fraction
from typing import Any

import numpy as np
import tomli_w

from machinesim._io import not_a_regular_file, write_atomic
from machinesim.errors._checks import (
    AXES,
    LINEAR_AXES,
    _check_axis,
    _check_increasing,
    _check_size,
    _check_symbol,
    _check_unit,
    _describe,
    _fail,
    _limit,
    _number,
    _numbers,
    _quantity,
)
from machinesim.errors.families import (
    _WORKPIECE_ANGLES,
    ComponentError,
    ToolGeometry,
    ToolSetting,
    WorkpieceSetting,
    check_poly_size,
)
from machinesim.errors.model import ErrorModel
from machinesim.errors.unit_slips import (  # noqa: F401  (importable from here, as before)
    LARGEST_LIKELY_ERROR_M,
    LARGEST_LIKELY_ERROR_RAD,
    SHORTEST_TABLE_SHARE,
    SMALLEST_WRITTEN_ERROR_SI,
    below_any_machine,
    beyond_any_machine,
    short_tables,
)
from machinesim.exceptions import ErrorModelError
from machinesim.units import ANGLE, FACTORS, LENGTH

_SECTIONS = ("tool", "tool_geometry", "workpiece", "location", "component")
#: Bytes beyond which a TOML file is not an error model, tool table or servo file (`_read_toml`):
#: tomllib and the key scan read 1 MB in some 1.2 s and 10 MB of memory, so a 20 MB file of
#: one table took 25 s and 210 MB before anything was checked, a 200 MB one minutes and GBs.
MAX_TOML_BYTES = 4 * 2**20
_TOML_POSITION_RE = re.compile(r"\s*\(at line (\d+), column (\d+)\)")
_READABLE_UNITS = {"length": "um", "angle": "urad", "linear": "mm", "rotary": "deg"}
_SI_UNITS = {"length": "m", "angle": "rad", "linear": "m", "rotary": "rad"}
_HEADER = (
    "# machinesim error model. Lengths in um, angles in urad, positions of linear axes in mm,\n"
    "# of rotary axes in deg; <SYM>_poly_<value>_<position> = c_k in value/position**k.\n\n"
)


def _poly_factors(value_factor: float, position_factor: float, count: int) -> np.ndarray:
    """SI per file unit of each coefficient c_k: the value factor over position factor**k.

    Reading multiplies by these and writing divides by the very same numbers, so a round
    trip through a file costs two roundings per coefficient.
    """
    return value_factor / np.power(position_factor, np.arange(count, dtype=np.float64))


def _exact_si(coefficient: float, value_factor: float, position_factor: float, k: int) -> float:
    """``coefficient`` (file units) times ``value_factor / position_factor**k`` in SI, taken
    exactly and rounded once: inf beyond float64 (then refused), 0.0 below it.

    The exact power is taken only where the product may be a float64: a polynomial of
    10,000 zero coefficients in um/mm**k (a 20 kB file) took a minute to read, its powers
    of 1e-3 growing to numbers of millions of digits, and one of 300,000 never ended. Its
    binary exponent (`math.frexp`) tells the others apart at once."""
    if coefficient == 0.0:
        return 0.0
    exponent = (math.frexp(coefficient)[1] + math.frexp(value_factor)[1]
                - k * (math.frexp(position_factor)[1] - 1))  # within k + 2 of its own
    if exponent - k - 2 > 1024:  # at least 2**1025: beyond float64
        return math.copysign(math.inf, coefficient)
    if exponent + k + 2 < -1075:  # below half the smallest subnormal: rounds to 0
        return math.copysign(0.0, coefficient)
    try:
        exact = Fraction(coefficient) * Fraction(value_factor) / Fraction(position_factor) ** k
        return float(exact)
    except OverflowError:
        return math.copysign(math.inf, coefficient)


def _utf16_text(data: bytes) -> bool:
    """True when ``data`` reads as UTF-16 text (printable, tabs and line ends): a file with
    zero bytes that does not (a PNG, an .npz given for the TOML) is binary, not UTF-16."""
    try:
        text = data.decode("utf-16")
    except UnicodeDecodeError:
        return False
    return all(c.isprintable() or c in "\t\r\n" for c in text)


def read_toml(path: str | os.PathLike, error: type = ErrorModelError) -> dict[str, Any]:
    """The tables of the TOML file `path`; errors (an ``error``, default `ErrorModelError`)
    name the file, and the line and column (`_read_toml`)."""
    return _read_toml(path, error)[1]


def read_toml_lines(path: str | os.PathLike, error: type = ErrorModelError
                    ) -> tuple[dict[str, Any], dict[str, int]]:
    """The tables of the TOML file `path`, as `read_toml`, and the line of each key path
    (`key_lines`), for the messages of what the tables hold."""
    text, data = _read_toml(path, error)
    return data, key_lines(text)


def _read_toml(path: str | os.PathLike, error: type) -> tuple[str, dict[str, Any]]:
    """The text of the TOML file `path` and its tables; errors (an ``error``) name the file,
    and the line and column.

    A UTF-8 byte order mark at the start (which some Windows editors write, and TOML does
    not allow) is dropped, as most tools do: lines and columns count from after it. A path
    that is not a regular file (a named pipe, ``/dev/zero``) is refused before it is read.
    """
    source = str(path)
    text = None
    try:
        mode = os.stat(path).st_mode
        if stat.S_ISDIR(mode):
            # said as the command line's own checks say it (the reading's "cannot read the
            # file: Is a directory" had reached a scenario's --errors)
            raise error("is a folder; expected a TOML file", source=source)
        if not stat.S_ISREG(mode):
            # a FIFO with no writer blocks for ever, /dev/zero fills the memory: refuse before
            # reading
            raise error(f"{not_a_regular_file(path)}; expected a TOML file", source=source)
        with open(path, "rb") as file:
            data = file.read(MAX_TOML_BYTES + 1)
        if len(data) > MAX_TOML_BYTES:
            raise error(f"larger than {MAX_TOML_BYTES // 2**20} MB; an error model, tool table "
                        "or servo file is a few kB (an error table of 10,000 positions some "
                        f"0.2 MB): expected at most {MAX_TOML_BYTES // 2**20} MB",
                        source=source)
        text = data.decode("utf-8-sig")
        data = tomllib.loads(text)
    except OSError as exc:
        raise error(f"cannot read the file: {exc.strerror or exc}", source=source) from None
    except UnicodeDecodeError as exc:  # the line and column of the byte, as an editor shows
        before = exc.object[:exc.start]  # valid UTF-8, after any byte order mark
        line = before.count(b"\n") + 1
        column = len(before[before.rfind(b"\n") + 1:].decode("utf-8")) + 1
        if b"\x00" not in exc.object:  # UTF-16 of ASCII has one in every other byte
            why = ("a Latin-1 or Windows-1252 character such as a micro or degree sign, saved "
                   "in that encoding")
        elif _utf16_text(exc.object):
            why = "UTF-16, as Windows Notepad's 'Unicode' saves it"
        else:
            why = "binary data, not a text file"
        raise error(f"not UTF-8 text (byte 0x{exc.object[exc.start]:02x}, {exc.reason}: {why});"
                    " expected UTF-8 TOML: save the file as UTF-8", source=source, line=line,
                    column=column) from None
    except tomllib.TOMLDecodeError as exc:
        position = _TOML_POSITION_RE.search(str(exc))
        line, column = (int(position[1]), int(position[2])) if position else (None, None)
        if position is None and "end of document" in str(exc):
            # an array, table or string left open runs to the last line (where to look)
            lines = text.splitlines() or [""]
            line, column = len(lines), len(lines[-1]) + 1
        message = f"not valid TOML: {_TOML_POSITION_RE.sub('', str(exc))}"
        raise error(message, source=source, line=line, column=column) from None
    except RecursionError:  # tomllib recurses once per nesting level of arrays and tables
        raise error("arrays or tables nested too deeply to read (hundreds of levels); "
                    "expected numbers or arrays of numbers", source=source) from None
    return text, data


_BARE_KEY_RE = re.compile(r"[A-Za-z0-9_-]+")


class _KeyLines:
    """The line of each key of a TOML text that `tomllib` has read (so valid TOML): a small
    scan of the text, as tomllib gives no positions. ``lines`` maps each key path, its
    parts joined by '.' as `model_from_dict` names them (``location.C.EX0C_um``), to the
    line it is written on: a table's header (``[location.C]``), a key's own line, a dotted
    key's (``C.EX0C_um = 2`` under ``[location]`` gives ``location.C`` and
    ``location.C.EX0C_um``), a key in an inline table; an array spanning lines is the line
    of its key. A table defined twice over (a header after a dotted key) keeps its first
    line."""

    def __init__(self, text: str) -> None:
        self.text, self.i, self.line = text, 0, 1
        self.lines: dict[str, int] = {}
        prefix: list[str] = []
        while self._space(newlines=True) < len(text):
            if text[self.i] == "[":
                brackets = 2 if text.startswith("[[", self.i) else 1
                line = self.line
                self._step(brackets)
                prefix = self._key()
                self._space()
                self._step(brackets)
                self._note(prefix, line)
            else:
                self._pair(prefix)

    def _step(self, count: int = 1) -> None:
        self.line += self.text.count("\n", self.i, self.i + count)
        self.i += count

    def _space(self, newlines: bool = False) -> int:
        """Skip blanks and comments (and line ends, with ``newlines``); the index reached."""
        text = self.text
        while self.i < len(text):
            c = text[self.i]
            if c == "#":
                end = text.find("\n", self.i)
                self.i = len(text) if end < 0 else end
            elif c in " \t" or (newlines and c in "\r\n"):
                self._step()
            else:
                break
        return self.i

    def _note(self, path: list[str], line: int) -> None:
        for k in range(1, len(path) + 1):
            self.lines.setdefault(".".join(path[:k]), line)

    def _key(self) -> list[str]:
        """A dotted key's parts, quoted parts unquoted."""
        parts = []
        while True:
            self._space()
            c = self.text[self.i]
            if c in "\"'":
                start = self.i
                self._string()
                parts.append(tomllib.loads(f"k = {self.text[start:self.i]}")["k"])
            else:
                bare = _BARE_KEY_RE.match(self.text, self.i)
                parts.append(bare[0])
                self.i = bare.end()
            self._space()
            if self.i >= len(self.text) or self.text[self.i] != ".":
                return parts
            self._step()

    def _pair(self, prefix: list[str] | None) -> None:
        """``key = value``; its keys noted under ``prefix`` (None: in an array, not noted)."""
        line = self.line
        path = None if prefix is None else prefix + self._key()
        if path is None:
            self._key()
        else:
            self._note(path, line)
        self._space()
        self._step()  # '='
        self._space()
        self._value(path)

    def _value(self, path: list[str] | None) -> None:
        text, c = self.text, self.text[self.i]
        if c in "\"'":
            self._string()
        elif c == "[":  # an array: its elements (and their inline tables) have no key paths
            self._step()
            while self._space(newlines=True) < len(text) and text[self.i] != "]":
                self._value(None)
                if self._space(newlines=True) < len(text) and text[self.i] == ",":
                    self._step()
            self._step()
        elif c == "{":
            self._step()
            while self._space(newlines=True) < len(text) and text[self.i] != "}":
                self._pair(path)
                if self._space(newlines=True) < len(text) and text[self.i] == ",":
                    self._step()
            self._step()
        else:  # a number, a date, true or false: up to what ends it
            while self.i < len(text) and text[self.i] not in ",]}#\r\n":
                self.i += 1

    def _string(self) -> None:
        """Past a string, basic or literal, of one line or many."""
        text = self.text
        quote = text[self.i]
        if text.startswith(quote * 3, self.i):
            end = self.i + 3
            while True:
                if quote == '"' and text[end] == "\\":
                    end += 2
                elif text.startswith(quote * 3, end):
                    end += 3
                    while end < len(text) and text[end] == quote:  # up to 2 quotes inside
                        end += 1
                    break
                else:
                    end += 1
        else:
            end = self.i + 1
            while text[end] != quote:
                end += 2 if quote == '"' and text[end] == "\\" else 1
            end += 1
        self._step(end - self.i)


def key_lines(text: str) -> dict[str, int]:
    """The line of each key path of the TOML ``text`` (valid TOML: read by tomllib first);
    see `_KeyLines`. A scan that loses its way gives no lines rather than a traceback: the
    messages then name the file and key alone, as before."""
    try:
        return _KeyLines(text).lines
    except (IndexError, TypeError, ValueError, RecursionError):  # arrays nested too deeply
        return {}


def write_toml(data: Mapping[str, Any], path: str | os.PathLike) -> None:
    """Write `data` (``to_dict(readable=True)``) under the units header, whole or not at all."""
    text = _HEADER + tomli_w.dumps(data)
    write_atomic(path, text)


def dict_from_model(model: ErrorModel, readable: bool) -> dict[str, Any]:
    """The TOML structure of `model`, in m and rad, or in the units of `to_toml` if `readable`."""
    units = _READABLE_UNITS if readable else _SI_UNITS
    length, angle = units["length"], units["angle"]
    wp = model.workpiece
    out: dict[str, Any] = {
        "tool": {
            f"offset_{length}": (model.tool.offset / LENGTH[length]).tolist(),
            f"rotation_{angle}": (model.tool.rotation / ANGLE[angle]).tolist(),
        },
        "workpiece": {
            f"delta_{length}": (wp.delta / LENGTH[length]).tolist(),
            **{f"{n}_{angle}": getattr(wp, n) / ANGLE[angle] for n in _WORKPIECE_ANGLES},
        },
    }
    if model.tool_geometry.nose_radius != 0.0:
        out["tool_geometry"] = {
            f"nose_radius_{length}": model.tool_geometry.nose_radius / LENGTH[length]}
    if model.location:
        out["location"] = {
            axis: {
                f"{s}_{units[_quantity(s[1])]}": v / FACTORS[units[_quantity(s[1])]]
                for s, v in table.items()
            }
            for axis, table in model.location.items()
        }
    if model.component:
        out["component"] = {
            axis: _component_section(axis, table, units)
            for axis, table in model.component.items()
        }
    return out


def _component_section(axis: str, table: Mapping[str, ComponentError], units: dict) -> dict:
    position_unit = units["linear" if axis in LINEAR_AXES else "rotary"]
    position_factor = FACTORS[position_unit]
    out: dict[str, Any] = {}
    grids = [e.positions for e in table.values() if e.kind == "table"]
    if grids:
        out[f"position_{position_unit}"] = (grids[0] / position_factor).tolist()
    for symbol, error in table.items():
        value_unit = units[_quantity(symbol[1])]
        if error.kind == "table":
            out[f"{symbol}_{value_unit}"] = (error.values / FACTORS[value_unit]).tolist()
        else:
            factors = _poly_factors(FACTORS[value_unit], position_factor, error.values.size)
            out[f"{symbol}_poly_{value_unit}_{position_unit}"] = (error.values / factors).tolist()
    return out


def _position_kind(axis: str) -> str:
    """'linear' or 'rotary': the kind of the positions of `axis` (units of `_SI_UNITS`)."""
    return "linear" if axis in LINEAR_AXES else "rotary"


def _table(value: Any, source: str, key: str | None) -> Mapping:
    if not isinstance(value, Mapping):
        raise _fail(f"expected a table, got {_describe(value)}", source, key)
    return value


def model_from_dict(data: Any, source: str, lines: Mapping[str, int] | None = None
                    ) -> ErrorModel:
    """The model of `data` (the TOML structure), remembering `source` and each key and value
    as written there (`ErrorModel.source`, `ErrorModel.written`) for later messages.

    ``lines`` (`key_lines` of the file read) gives the line of each key path: a refusal of
    a key of the file names its line too (``F.toml, line 3, key 'tool.offset_um': ...``),
    as the model's later messages do (`ErrorModel.lines`).
    """
    lines = {} if lines is None else dict(lines)
    try:
        return _model_from_dict(data, source, lines)
    except ErrorModelError as exc:
        line = lines.get(exc.key) if exc.source == source and exc.line is None else None
        if line is None:
            raise
        raise ErrorModelError(exc.message, source=exc.source, line=line, column=exc.column,
                              key=exc.key) from None


def _model_from_dict(data: Any, source: str, lines: dict[str, int]) -> ErrorModel:
    for section in _table(data, source, None):
        if section not in _SECTIONS:
            hint = ""
            if isinstance(section, str) and section.split(".")[0] in _SECTIONS:
                hint = ("; a parameter name (SI values by name, as Estimate.as_dict and "
                        "Machine.parameter_names give them) goes through "
                        "ErrorModel().with_parameters({name: value})")
            elif isinstance(section, str) and section in AXES:  # a servo file given for it
                hint = (f"; [{section}] alone is a servo loop's table (--servo); an axis's "
                        f"errors go in [location.{section}] and [component.{section}]")
            raise _fail(f"unknown section; expected one of {', '.join(_SECTIONS)}{hint}",
                        source, section)
    tool_spec = {"offset": ("length", 3), "rotation": ("angle", 3)}
    workpiece_spec = {"delta": ("length", 3)} | {a: ("angle", None) for a in _WORKPIECE_ANGLES}
    written: dict[str, tuple[str, Any]] = {}
    tool = _parse_fields(data.get("tool", {}), "tool", tool_spec, source, written)
    workpiece = _parse_fields(data.get("workpiece", {}), "workpiece", workpiece_spec, source,
                              written)
    geometry = _parse_fields(data.get("tool_geometry", {}), "tool_geometry",
                             {"nose_radius": ("length", None)}, source, written)
    location = {
        axis: _parse_location(axis, table, source, written)
        for axis, table in _table(data.get("location", {}), source, "location").items()
    }
    component = {
        axis: _parse_component(axis, table, source, written)
        for axis, table in _table(data.get("component", {}), source, "component").items()
    }
    return ErrorModel(ToolSetting(**tool), WorkpieceSetting(**workpiece), location, component,
                      ToolGeometry(**geometry), source=source, written=written, lines=lines)


def _split_key(key: Any, expected: str, source: str, path: str) -> list[str]:
    if not isinstance(key, str) or not key:
        raise _fail(f"unknown key; expected {expected}", source, path)
    return key.split("_")


def _parse_fields(section: Any, name: str, spec: dict, source: str,
                  written: dict) -> dict[str, Any]:
    """The fields of [tool], [tool_geometry] or [workpiece]: `spec` maps a field to (quantity,
    size or None); `written` gets ``<section>.<field>`` -> (key path, value) as written."""
    expected = ", ".join(f"{field_}_<{q} unit>" for field_, (q, _) in spec.items())
    out: dict[str, Any] = {}
    for key, value in _table(section, source, name).items():
        path = f"{name}.{key}"
        parts = _split_key(key, expected, source, path)
        if key not in spec:  # field names may hold '_' (nose_radius): the unit is the last part
            parts = key.rsplit("_", 1)
        if parts[0] not in spec or len(parts) > 2:
            hint = ""
            if name == "tool" and isinstance(value, Mapping) and key.isdigit():
                hint = (f" ([tool.{key}] is a tool table's, given with --tools; an error "
                        "file's [tool] is the tool setting error)")
            raise _fail(f"unknown key; expected {expected}{hint}", source, path)
        quantity, size = spec[parts[0]]
        if len(parts) == 1:
            message = f"key has no unit suffix; expected {parts[0]}_<{quantity} unit>"
            raise _fail(message, source, path)
        factor = _check_unit(parts[1], quantity, source, path)
        if parts[0] in out:
            raise _fail(f"{parts[0]} is given twice (with two units)", source, path)
        in_file = (_number(value, source, path) if size is None
                   else _numbers(value, source, path, size))
        out[parts[0]] = in_file * factor
        _check_size(out[parts[0]], quantity, parts[1], factor, source, path)
        written[f"{name}.{parts[0]}"] = (path, in_file)
    return out


def _check_apart(positions: np.ndarray, in_file: np.ndarray, source: str, key: str,
                 unit: str) -> None:
    """Refuse positions that increase as written (``in_file``, in ``unit``) but not once in
    SI (``positions``): the product underflows (``position_mm = [0.0, 5e-324]`` is [0, 0] m),
    and the table's own check then named neither the file nor the key (``key 'positions':
    ... got 0.0 then 0.0 m or rad``)."""
    if not np.any(equal := positions[1:] <= positions[:-1]):  # compared: no overflow
        return
    i = int(np.argmax(equal))
    si = "m" if unit in LENGTH else "rad"
    raise _fail(f"positions {in_file[i].item()!r} and {in_file[i + 1].item()!r} {unit} "
                f"(indices {i}, {i + 1}) are both {positions[i].item()!r} {si} once in {si} "
                f"(float64); expected positions strictly increasing in {si} too", source, key)


def _symbol_unit(key: Any, axis: str, location: bool, source: str, path: str):
    """(symbol, rest of the key split at '_') of a [location.*] or [component.*] key."""
    zero = "0" if location else ""
    parts = _split_key(key, f"E<d>{zero}{axis}_<unit>", source, path)
    _check_symbol(parts[0], axis, location, source, path)
    if len(parts) == 1:
        message = f"key has no unit suffix; expected {parts[0]}_<{_quantity(parts[0][1])} unit>"
        raise _fail(message, source, path)
    return parts[0], parts[1:]


def _parse_location(axis: Any, table: Any, source: str, written: dict) -> dict[str, float]:
    path = f"location.{axis}"
    _check_axis(axis, source, path)
    out: dict[str, float] = {}
    for key, value in _table(table, source, path).items():
        symbol, units = _symbol_unit(key, axis, True, source, f"{path}.{key}")
        if len(units) != 1:
            raise _fail(f"expected the key {symbol}_<unit>", source, f"{path}.{key}")
        factor = _check_unit(units[0], _quantity(symbol[1]), source, f"{path}.{key}")
        if symbol in out:
            raise _fail(f"{symbol} is given twice", source, f"{path}.{key}")
        in_file = _number(value, source, f"{path}.{key}")
        out[symbol] = in_file * factor
        _check_size(out[symbol], _quantity(symbol[1]), units[0], factor, source,
                    f"{path}.{key}")
        written[f"{path}.{symbol}"] = (f"{path}.{key}", in_file)
    return out


def _parse_component(axis: Any, table: Any, source: str,
                     written: dict) -> dict[str, ComponentError]:
    path = f"component.{axis}"
    _check_axis(axis, source, path)
    axis_quantity = _quantity(axis)
    positions = position_key = None
    out: dict[str, ComponentError | None] = {}
    tables = {}  # symbol -> (key path, file value, SI values): built once positions are known
    for key, value in _table(table, source, path).items():
        key_path = f"{path}.{key}"
        if key == "position" or (isinstance(key, str) and key.startswith("position_")):
            if key.count("_") != 1:
                raise _fail(f"expected the key position_<{axis_quantity} unit>", source, key_path)
            factor = _check_unit(key.split("_")[1], axis_quantity, source, key_path)
            if positions is not None:
                raise _fail(f"positions are given twice (and as {position_key})", source, key_path)
            in_file = _numbers(value, source, key_path)
            _check_increasing(in_file, source, key_path, key.split("_")[1])
            positions, position_key = in_file * factor, key
            _check_apart(positions, in_file, source, key_path, key.split("_")[1])
            written[f"{path}.position"] = (key_path, in_file)
            continue
        symbol, units = _symbol_unit(key, axis, False, source, key_path)
        if symbol in out:
            raise _fail(f"{symbol} is given twice", source, key_path)
        quantity = _quantity(symbol[1])
        if units[0] == "poly":
            if len(units) != 3:
                form = f"{symbol}_poly_<{quantity} unit>_<{axis_quantity} unit>"
                raise _fail(f"expected a polynomial key {form}", source, key_path)
            value_factor = _check_unit(units[1], quantity, source, key_path)
            position_factor = _check_unit(units[2], axis_quantity, source, key_path)
            coefficients = _numbers(value, source, key_path)
            check_poly_size(coefficients.size, source, key_path)
            with np.errstate(over="ignore", divide="ignore", under="ignore", invalid="ignore"):
                factors = _poly_factors(value_factor, position_factor, coefficients.size)
                si = coefficients * factors
            # where a factor alone leaves float64 (1e-6 / (1e-9)**35 for um/nm**35 is 1e309),
            # the product is taken exactly: a zero coefficient there read 0 * inf = nan and
            # was refused as 'beyond float64', with numpy's RuntimeWarnings on stderr
            for k in np.flatnonzero(~(np.abs(factors) >= np.finfo(np.float64).tiny)
                                    | ~np.isfinite(factors)):
                si[k] = _exact_si(coefficients[k], value_factor, position_factor, int(k))
            if not np.all(np.isfinite(si)):
                k = int(np.argmin(np.isfinite(si)))
                si_unit = f"{_SI_UNITS[quantity]}/{_SI_UNITS[_position_kind(axis)]}**{k}"
                largest = _limit(quantity, units[1], value_factor)  # in the unit written
                factor = (f"{factors[k]:g}" if np.isfinite(factors[k]) else re.sub(  # as :g
                    r"\.?0+(?=e)", "", format(Decimal(value_factor)
                                              / Decimal(position_factor) ** k, ".6g")))
                raise _fail(f"coefficient c_{k} = {coefficients[k]:g} {units[1]}/{units[2]}**{k}"
                            f" is {factor} times as large in {si_unit}, beyond float64; "
                            f"expected a {quantity} error of at most {largest} over the travel",
                            source, key_path)
            out[symbol] = ComponentError("poly", None, si)
            written[f"{path}.{symbol}"] = (key_path, coefficients)
            continue
        if len(units) != 1:
            raise _fail(f"expected the key {symbol}_<{quantity} unit>", source, key_path)
        factor = _check_unit(units[0], quantity, source, key_path)
        out[symbol] = None
        in_file = _numbers(value, source, key_path)
        tables[symbol] = (key_path, value, in_file * factor)
        _check_size(tables[symbol][2], quantity, units[0], factor, source, key_path)
        written[f"{path}.{symbol}"] = (key_path, in_file)
    for symbol, (key_path, raw, values) in tables.items():
        if positions is None:
            message = f"a table needs positions: no position_<unit> key in [{path}]"
            raise _fail(message, source, key_path)
        if values.size != positions.size:
            message = f"the table has {values.size} values, {_describe(raw)}, but {position_key} "
            raise _fail(f"{message}has {positions.size} positions", source, key_path)
        out[symbol] = ComponentError("table", positions, values)
    if positions is not None and not tables:
        raise _fail(f"{position_key} is given but no table uses it; expected an error table "
                    f"beside it (e.g. EX{axis}_um = [...], one value per position)",
                    source, f"{path}.{position_key}")
    return out
