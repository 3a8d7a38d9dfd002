"""The injected errors of a machine, as immutable values, read from and written to TOML.

Four families, machine-independent (the kinematics decides which symbols an axis can carry):

- tool setting error (`ToolSetting`), in the ``tool_mount`` frame;
- workpiece setting error (`WorkpieceSetting`, paper 002);
- location errors of an axis, position independent, ISO 230-1/-7 symbols ``E<d>0<axis>``
  (``EX0C``, ``EB0C``, squareness ``EC0Y``);
- component errors of an axis, position dependent, symbols ``E<d><axis>`` (``EXX``, ``EYX``,
  ``ECC``), each a table or a polynomial of the axis position (`ComponentError`).

In a symbol, ``d`` in X Y Z is a translation along that machine direction (a length), ``d`` in
A B C a rotation about X Y Z (an angle). SI inside (m, rad); units appear only in TOML keys.

TOML layout (every key carries its unit: m mm um nm, rad mrad urad deg arcsec)::

    [tool]           # offset_<length unit> = [x, y, z], rotation_<angle unit> = [a, b, c]
    [workpiece]      # delta_<length unit> = [x, y, z], alpha_/beta_/gamma_<angle unit> = v
    [location.C]     # <SYM>_<unit> = value, e.g. EX0C_um = 2.0
    [component.X]    # position_<unit> = [...], shared by the tables of the axis;
                     # <SYM>_<unit> = [...] a table, values at those positions;
                     # <SYM>_poly_<valueunit>_<positionunit> = [c0, c1, ...] a polynomial,
                     # value = sum c_k (x / positionunit)**k in valueunit

`ErrorModel.to_toml` writes lengths in um, angles in urad, positions of linear axes in mm and
of rotary axes in deg (polynomials in um or urad per mm**k or deg**k).
`ErrorModel.to_dict` gives the same structure in m and rad, so that it round trips exactly.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
import tomli_w

from machinesim.exceptions import ErrorModelError
from machinesim.units import ANGLE, FACTORS, LENGTH

#: Axis letters, in the canonical order of sections and symbols.
AXES = "XYZABC"
#: Linear axes (positions and translation symbols in lengths); the others are rotary.
LINEAR_AXES = "XYZ"

_SECTIONS = ("tool", "workpiece", "location", "component")
_WORKPIECE_ANGLES = ("alpha", "beta", "gamma")
_SYMBOL_RE = re.compile(r"E(.)(0?)(.)")
_PARAMETER_RE = re.compile(
    r"tool\.(?P<tool>x|y|z|rx|ry|rz)|workpiece\.(?P<workpiece>x|y|z|alpha|beta|gamma)"
    r"|location\.(?P<laxis>\w)\.(?P<lsym>\w+)|component\.(?P<caxis>\w)\.(?P<csym>\w+)\[(?P<k>\d+)\]"
)
_PARAMETER_FORMS = (
    "tool.<x|y|z|rx|ry|rz>, workpiece.<x|y|z|alpha|beta|gamma>, location.<axis>.<SYM> or "
    "component.<axis>.<SYM>[k]"
)
_TOML_POSITION_RE = re.compile(r"\s*\(at line (\d+), column (\d+)\)")
_READABLE_UNITS = {"length": "um", "angle": "urad", "linear": "mm", "rotary": "deg"}
_SI_UNITS = {"length": "m", "angle": "rad", "linear": "m", "rotary": "rad"}
_HEADER = (
    "# machinesim error model. Lengths in um, angles in urad, positions of linear axes in mm,\n"
    "# of rotary axes in deg; <SYM>_poly_<value>_<position> = c_k in value/position**k.\n\n"
)


def _fail(message: str, source: str | None, key: str | None) -> ErrorModelError:
    return ErrorModelError(message, source=source, key=key)


def _describe(value: Any) -> str:
    text = repr(value.tolist() if isinstance(value, np.ndarray) else value)
    return f"{text if len(text) <= 80 else text[:77] + '...'} ({type(value).__name__})"


def _number(value: Any, source: str | None, key: str | None) -> float:
    """A finite float from an int or float (bools and strings refused)."""
    if isinstance(value, bool | np.bool_) or not isinstance(
        value, int | float | np.integer | np.floating
    ):
        raise _fail(f"expected a number, got {_describe(value)}", source, key)
    if not math.isfinite(number := float(value)):
        raise _fail(f"expected a finite number, got {number}", source, key)
    return number


def _numbers(value: Any, source: str | None, key: str | None, size: int | None = None):
    """A read-only float64 copy of a 1-D list of finite numbers (non-empty, or `size` long)."""
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "iuf":
        array = value.astype(np.float64)
        if not np.all(np.isfinite(array)):
            bad = array[~np.isfinite(array)][0]
            raise _fail(f"expected finite numbers, got {bad} in {_describe(value)}", source, key)
    elif isinstance(value, list | tuple):
        array = np.array([_number(item, source, key) for item in value], dtype=np.float64)
    else:
        raise _fail(f"expected a list of numbers, got {_describe(value)}", source, key)
    if size is not None and array.size != size:
        message = f"expected {size} values, got {array.size}: {_describe(value)}"
        raise _fail(message, source, key)
    if array.size == 0:
        raise _fail("expected at least one value, got an empty list", source, key)
    array.flags.writeable = False
    return array


def _check_increasing(positions: np.ndarray, source: str | None, key: str | None) -> None:
    if np.any(not_up := np.diff(positions) <= 0.0):
        i = int(np.argmax(not_up))
        raise _fail(
            f"positions must be strictly increasing, got {positions[i].item()!r} then "
            f"{positions[i + 1].item()!r} (indices {i}, {i + 1}) in {positions.tolist()!r}",
            source,
            key,
        )


def _quantity(letter: str) -> str:
    """'length' for X Y Z (translation, linear axis), 'angle' for A B C (rotation, rotary)."""
    return "length" if letter in LINEAR_AXES else "angle"


def _check_unit(unit: str, quantity: str, source: str | None, key: str) -> float:
    """The factor to SI of `unit`, which must be a `quantity` ('length' or 'angle') unit."""
    units = LENGTH if quantity == "length" else ANGLE
    if unit in units:
        return units[unit]
    expected = f"expected {'a length' if quantity == 'length' else 'an angle'} unit "
    expected += f"({', '.join(units)})"
    if unit in FACTORS:
        other = "an angle" if quantity == "length" else "a length"
        raise _fail(f"{expected}, got {unit!r}, {other} unit", source, key)
    raise _fail(f"unit {unit!r} is not recognised; {expected}", source, key)


def _check_axis(axis: Any, source: str | None, key: str) -> None:
    if axis not in tuple(AXES):
        raise _fail(f"axis letter {axis!r} is not one of {', '.join(AXES)}", source, key)


def _check_symbol(symbol: str, axis: str, location: bool, source: str | None, key: str):
    """Refuse `symbol` unless it is an ISO 230 location (E<d>0<axis>) or component symbol."""
    kind, form = ("location", f"E<d>0{axis}") if location else ("component", f"E<d>{axis}")
    match = _SYMBOL_RE.fullmatch(symbol)
    if match is None or match[1] not in AXES or match[3] not in AXES:
        message = f"{symbol!r} is not an ISO 230 {kind} error symbol; expected {form}"
        raise _fail(f"{message} with d one of {', '.join(AXES)}", source, key)
    if bool(match[2]) != location:
        other = "a component (position-dependent)" if location else "a location (constant)"
        raise _fail(f"{symbol!r} is {other} symbol; [{kind}.{axis}] takes {form}", source, key)
    if match[3] != axis:
        raise _fail(f"symbol {symbol!r} is of axis {match[3]}, not [{kind}.{axis}]", source, key)


def _poly_factors(value_factor: float, position_factor: float, count: int) -> np.ndarray:
    """SI per file unit of each coefficient c_k: the value factor over position factor**k.

    Reading multiplies by these and writing divides by the very same numbers, so a round
    trip through a file costs two roundings per coefficient.
    """
    return value_factor / np.power(position_factor, np.arange(count, dtype=np.float64))


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {key: _plain(item) for key, item in value.items()}
    return value


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and np.array_equal(a, b)
    return a == b


class _Value:
    """Exact equality and pickling through the constructor (which freezes the copies)."""

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))

    __hash__ = None

    def __reduce__(self):
        return type(self), tuple(_plain(getattr(self, f.name)) for f in fields(self))


@dataclass(frozen=True, eq=False)
class ToolSetting(_Value):
    """Tool setting error, in the ``tool_mount`` frame.

    Attributes
    ----------
    offset : ndarray, shape (3,), m
        Offset of the tool edge along tool_mount X, Y, Z.
    rotation : ndarray, shape (3,), rad
        Rotations about tool_mount X, Y, Z, applied in that order: R = Rx(a) Ry(b) Rz(c).
    """

    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        object.__setattr__(self, "offset", _numbers(self.offset, None, "offset", 3))
        object.__setattr__(self, "rotation", _numbers(self.rotation, None, "rotation", 3))


@dataclass(frozen=True, eq=False)
class WorkpieceSetting(_Value):
    """Workpiece setting error (paper 002).

    The actual workpiece frame in the ideal one is Trans(delta) Rx(alpha) Ry(beta) Rz(gamma).

    Attributes
    ----------
    delta : ndarray, shape (3,), m
        Position error of the workpiece frame.
    alpha, beta, gamma : float, rad
        Rotations about X, Y, Z.
    """

    delta: np.ndarray = field(default_factory=lambda: np.zeros(3))
    alpha: float = 0.0
    beta: float = 0.0
    gamma: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "delta", _numbers(self.delta, None, "delta", 3))
        for name in _WORKPIECE_ANGLES:
            object.__setattr__(self, name, _number(getattr(self, name), None, name))


@dataclass(frozen=True, eq=False)
class ComponentError(_Value):
    """One position-dependent error (one symbol on one axis): a table or a polynomial.

    Attributes
    ----------
    kind : {"table", "poly"}
        ``"table"``: linear interpolation of `values` at `positions`, constant (the first or
        last value) beyond the first and last position. ``"poly"``: sum c_k x**k.
    positions : ndarray, shape (n,), m or rad, or None
        Axis positions of a table, strictly increasing (m for linear axes, rad for rotary);
        None for a polynomial.
    values : ndarray, shape (n,)
        Table values in SI (m or rad), or polynomial coefficients c_0..c_n in SI per SI**k.
    """

    kind: Literal["table", "poly"]
    positions: np.ndarray | None
    values: np.ndarray

    def __post_init__(self) -> None:
        values = _numbers(self.values, None, "values")
        positions = self.positions
        if self.kind == "table":
            if positions is None:
                raise _fail("a table needs positions, got None", None, "positions")
            positions = _numbers(positions, None, "positions")
            _check_increasing(positions, None, "positions")
            if positions.size != values.size:
                message = f"got {values.size} values for {positions.size} positions"
                raise _fail(f"a table needs one value per position, {message}", None, "values")
        elif self.kind != "poly":
            raise _fail(f"expected 'table' or 'poly', got {_describe(self.kind)}", None, "kind")
        elif positions is not None:
            message = f"a polynomial has no positions, got {_describe(positions)}"
            raise _fail(message, None, "positions")
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "values", values)

    def evaluate(self, x) -> np.ndarray:
        """The error at axis positions `x`.

        Parameters
        ----------
        x : array-like, shape (N,), m or rad
            Axis positions.

        Returns
        -------
        ndarray, shape (N,), m or rad
            Error values; a table is constant beyond its first and last positions.
        """
        x = np.asarray(x, dtype=np.float64)
        if self.kind == "table":
            return np.interp(x, self.positions, self.values)
        return np.polynomial.polynomial.polyval(x, self.values)

    def basis(self, x) -> np.ndarray:
        """The linear map from `values` to `evaluate(x)`, i.e. d evaluate(x) / d values.

        ``evaluate(x) == basis(x) @ values`` up to float64 round-off (the same interpolation
        weights or powers, summed in another order).

        Parameters
        ----------
        x : array-like, shape (N,), m or rad
            Axis positions.

        Returns
        -------
        ndarray, shape (N, len(values))
            Interpolation weights for a table (two non-zero per row; a single 1 beyond the
            ends), powers x**k for a polynomial.
        """
        x = np.asarray(x, dtype=np.float64)
        n = self.values.size
        if self.kind == "poly":
            return np.polynomial.polynomial.polyvander(x.ravel(), n - 1).reshape(x.shape + (n,))
        weights = np.zeros(x.shape + (n,))
        if n == 1:
            weights[...] = 1.0
            return weights
        p = self.positions
        clamped = np.clip(x, p[0], p[-1])
        left = np.clip(np.searchsorted(p, clamped, side="right") - 1, 0, n - 2)[..., None]
        t = ((clamped - p[left[..., 0]]) / (p[left[..., 0] + 1] - p[left[..., 0]]))[..., None]
        np.put_along_axis(weights, left, 1.0 - t, axis=-1)
        np.put_along_axis(weights, left + 1, t, axis=-1)
        return weights

    def span(self) -> tuple[float, float] | None:
        """(first, last) position of a table in m or rad; None for a polynomial."""
        if self.positions is None:
            return None
        return float(self.positions[0]), float(self.positions[-1])


def _freeze(errors: Any, name: str, check) -> MappingProxyType:
    """Validate {axis: {symbol: value}} and freeze it, axes and symbols in X Y Z A B C order."""
    if not isinstance(errors, Mapping):
        raise _fail(f"expected a mapping, got {_describe(errors)}", None, name)
    out = {}
    for axis in sorted(errors, key=lambda a: AXES.find(a) if isinstance(a, str) else -1):
        _check_axis(axis, None, f"{name}.{axis}")
        table = errors[axis]
        if not isinstance(table, Mapping):
            raise _fail(f"expected a mapping, got {_describe(table)}", None, f"{name}.{axis}")
        for symbol in table:
            _check_symbol(symbol, axis, name == "location", None, f"{name}.{axis}.{symbol}")
        if table:
            symbols = sorted(table, key=lambda s: AXES.index(s[1]))
            out[axis] = MappingProxyType(
                {s: check(table[s], f"{name}.{axis}.{s}") for s in symbols}
            )
    return MappingProxyType(out)


def _check_component(axes: Mapping[str, Mapping[str, Any]]) -> None:
    for axis, table in axes.items():
        grids = {}
        for symbol, error in table.items():
            if not isinstance(error, ComponentError):
                message = f"expected a ComponentError, got {_describe(error)}"
                raise _fail(message, None, f"component.{axis}.{symbol}")
            if error.kind == "table":
                grids[symbol] = error.positions
        # The TOML format has one position list per axis: keep every model writable.
        first = next(iter(grids.values()), None)
        for symbol, grid in grids.items():
            if not np.array_equal(grid, first):
                message = f"the tables of axis {axis} must share their positions, got "
                message += f"{grid.tolist()!r}, not {first.tolist()!r}"
                raise _fail(message, None, f"component.{axis}.{symbol}")


@dataclass(frozen=True, eq=False)
class ErrorModel(_Value):
    """All injected errors of a machine; ``ErrorModel()`` has none.

    Attributes
    ----------
    tool : ToolSetting
    workpiece : WorkpieceSetting
    location : Mapping[str, Mapping[str, float]]
        Per axis letter, location error symbol -> value (m or rad), e.g.
        ``{"C": {"EX0C": 2e-6}}``. Read-only; axes and symbols in X Y Z A B C order.
    component : Mapping[str, Mapping[str, ComponentError]]
        Per axis letter, component error symbol -> error, e.g. ``{"X": {"EXX": ...}}``.
        Read-only; the tables of one axis share their positions (one list per axis in TOML).
    """

    tool: ToolSetting = field(default_factory=ToolSetting)
    workpiece: WorkpieceSetting = field(default_factory=WorkpieceSetting)
    location: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    component: Mapping[str, Mapping[str, ComponentError]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name, kind in (("tool", ToolSetting), ("workpiece", WorkpieceSetting)):
            if not isinstance(getattr(self, name), kind):
                message = f"expected a {kind.__name__}, got {_describe(getattr(self, name))}"
                raise _fail(message, None, name)
        location = _freeze(self.location, "location", lambda v, key: _number(v, None, key))
        component = _freeze(self.component, "component", lambda v, key: v)
        _check_component(component)
        object.__setattr__(self, "location", location)
        object.__setattr__(self, "component", component)

    @property
    def is_zero(self) -> bool:
        """True when every parameter is zero: the model injects no error."""
        return all(value == 0.0 for value in self.parameters().values())

    def parameters(self) -> dict[str, float]:
        """Every parameter, by canonical name, in SI (m or rad).

        Order: ``tool.x .y .z .rx .ry .rz``, ``workpiece.x .y .z .alpha .beta .gamma``,
        ``location.<axis>.<SYM>``, ``component.<axis>.<SYM>[k]`` (table value or polynomial
        coefficient k), axes and symbols in X Y Z A B C order.
        """
        tool = np.concatenate([self.tool.offset, self.tool.rotation]).tolist()
        names = ("tool.x", "tool.y", "tool.z", "tool.rx", "tool.ry", "tool.rz")
        out = dict(zip(names, tool, strict=True))
        wp = self.workpiece
        out |= {f"workpiece.{n}": v for n, v in zip("xyz", wp.delta.tolist(), strict=True)}
        out |= {"workpiece.alpha": wp.alpha, "workpiece.beta": wp.beta, "workpiece.gamma": wp.gamma}
        for axis, table in self.location.items():
            out |= {f"location.{axis}.{symbol}": value for symbol, value in table.items()}
        for axis, table in self.component.items():
            for symbol, error in table.items():
                for k, value in enumerate(error.values.tolist()):
                    out[f"component.{axis}.{symbol}[{k}]"] = value
        return out

    def with_parameters(self, mapping: Mapping[str, float]) -> ErrorModel:
        """A copy with the named parameters replaced (names as in `parameters`, SI values).

        A location error not yet in the model is added (any valid symbol of a valid axis);
        a component parameter must exist. Any other name raises `ErrorModelError`.
        """
        offset, rotation = self.tool.offset.copy(), self.tool.rotation.copy()
        delta = self.workpiece.delta.copy()
        angles = {name: getattr(self.workpiece, name) for name in _WORKPIECE_ANGLES}
        location = _plain(self.location)
        values = {(axis, symbol): error.values.copy()
                  for axis, table in self.component.items() for symbol, error in table.items()}
        for name, raw in mapping.items():
            match = _PARAMETER_RE.fullmatch(name) if isinstance(name, str) else None
            if match is None:
                raise _fail(f"unknown parameter name; expected {_PARAMETER_FORMS}", None, name)
            value = _number(raw, None, name)
            if match["tool"]:
                target = rotation if match["tool"].startswith("r") else offset
                target["xyz".index(match["tool"][-1])] = value
            elif match["workpiece"] in ("x", "y", "z"):
                delta["xyz".index(match["workpiece"])] = value
            elif match["workpiece"]:
                angles[match["workpiece"]] = value
            elif match["laxis"]:
                _check_axis(match["laxis"], None, name)
                _check_symbol(match["lsym"], match["laxis"], True, None, name)
                location.setdefault(match["laxis"], {})[match["lsym"]] = value
            else:
                coefficients, k = values.get((match["caxis"], match["csym"])), int(match["k"])
                if coefficients is None:
                    raise _fail("unknown parameter: the model has no such error", None, name)
                if k >= coefficients.size:
                    message = f"unknown parameter: index {k}, but the error has "
                    raise _fail(f"{message}{coefficients.size} values", None, name)
                coefficients[k] = value
        component = {
            axis: {s: ComponentError(e.kind, e.positions, values[axis, s]) for s, e in t.items()}
            for axis, t in self.component.items()
        }
        tool, workpiece = ToolSetting(offset, rotation), WorkpieceSetting(delta, **angles)
        return ErrorModel(tool, workpiece, location, component)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], source: str = "<dict>") -> ErrorModel:
        """Read the TOML structure (module docstring); errors name `source`, the key, the value.

        Parameters
        ----------
        d : Mapping
            Sections ``tool``, ``workpiece``, ``location``, ``component``, all optional.
            Numbers may be ints or floats; lists may be lists, tuples or 1-D arrays.
        source : str
            Where `d` came from, for error messages.
        """
        return _parse(d, source)

    def to_dict(self, *, readable: bool = False) -> dict[str, Any]:
        """The TOML structure of this model.

        With ``readable=False`` (default) every key is in m or rad and
        ``from_dict(to_dict())`` reproduces the model exactly; with ``readable=True`` the
        units are those of `to_toml` (um, urad, mm, deg).
        """
        units = _READABLE_UNITS if readable else _SI_UNITS
        length, angle = units["length"], units["angle"]
        wp = self.workpiece
        out: dict[str, Any] = {
            "tool": {
                f"offset_{length}": (self.tool.offset / LENGTH[length]).tolist(),
                f"rotation_{angle}": (self.tool.rotation / ANGLE[angle]).tolist(),
            },
            "workpiece": {
                f"delta_{length}": (wp.delta / LENGTH[length]).tolist(),
                **{f"{n}_{angle}": getattr(wp, n) / ANGLE[angle] for n in _WORKPIECE_ANGLES},
            },
        }
        if self.location:
            out["location"] = {
                axis: {
                    f"{s}_{units[_quantity(s[1])]}": v / FACTORS[units[_quantity(s[1])]]
                    for s, v in table.items()
                }
                for axis, table in self.location.items()
            }
        if self.component:
            out["component"] = {
                axis: _component_section(axis, table, units)
                for axis, table in self.component.items()
            }
        return out

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> ErrorModel:
        """Read an error model from a TOML file (layout in the module docstring)."""
        source = str(path)
        try:
            data = tomllib.loads(Path(path).read_bytes().decode("utf-8"))
        except OSError as exc:
            raise ErrorModelError(f"cannot read the file: {exc.strerror}", source=source) from exc
        except UnicodeDecodeError as exc:
            raise ErrorModelError(f"not UTF-8 text: {exc}", source=source) from exc
        except tomllib.TOMLDecodeError as exc:
            position = _TOML_POSITION_RE.search(str(exc))
            line, column = (int(position[1]), int(position[2])) if position else (None, None)
            message = f"not valid TOML: {_TOML_POSITION_RE.sub('', str(exc))}"
            raise ErrorModelError(message, source=source, line=line, column=column) from exc
        return cls.from_dict(data, source=source)

    def to_toml(self, path: str | os.PathLike) -> None:
        """Write the model to `path` in um, urad, mm and deg, whole or not at all.

        ``from_toml(path)`` then gives every SI value back to float64 round-off (two roundings).
        """
        text = _HEADER + tomli_w.dumps(self.to_dict(readable=True))
        path = Path(path)
        fd, temp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as file:
                file.write(text)
            os.chmod(temp, 0o644)
            os.replace(temp, path)
        except BaseException:
            os.unlink(temp)
            raise


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


def _table(value: Any, source: str, key: str | None) -> Mapping:
    if not isinstance(value, Mapping):
        raise _fail(f"expected a table, got {_describe(value)}", source, key)
    return value


def _parse(data: Any, source: str) -> ErrorModel:
    for section in _table(data, source, None):
        if section not in _SECTIONS:
            raise _fail(f"unknown section; expected one of {', '.join(_SECTIONS)}", source, section)
    tool_spec = {"offset": ("length", 3), "rotation": ("angle", 3)}
    workpiece_spec = {"delta": ("length", 3)} | {a: ("angle", None) for a in _WORKPIECE_ANGLES}
    tool = _parse_fields(data.get("tool", {}), "tool", tool_spec, source)
    workpiece = _parse_fields(data.get("workpiece", {}), "workpiece", workpiece_spec, source)
    location = {
        axis: _parse_location(axis, table, source)
        for axis, table in _table(data.get("location", {}), source, "location").items()
    }
    component = {
        axis: _parse_component(axis, table, source)
        for axis, table in _table(data.get("component", {}), source, "component").items()
    }
    return ErrorModel(ToolSetting(**tool), WorkpieceSetting(**workpiece), location, component)


def _split_key(key: Any, expected: str, source: str, path: str) -> list[str]:
    if not isinstance(key, str) or not key:
        raise _fail(f"unknown key; expected {expected}", source, path)
    return key.split("_")


def _parse_fields(section: Any, name: str, spec: dict, source: str) -> dict[str, Any]:
    """The fields of [tool] or [workpiece]: `spec` maps a field to (quantity, size or None)."""
    expected = ", ".join(f"{field_}_<{q} unit>" for field_, (q, _) in spec.items())
    out: dict[str, Any] = {}
    for key, value in _table(section, source, name).items():
        path = f"{name}.{key}"
        parts = _split_key(key, expected, source, path)
        if parts[0] not in spec or len(parts) > 2:
            raise _fail(f"unknown key; expected {expected}", source, path)
        quantity, size = spec[parts[0]]
        if len(parts) == 1:
            message = f"key has no unit suffix; expected {parts[0]}_<{quantity} unit>"
            raise _fail(message, source, path)
        factor = _check_unit(parts[1], quantity, source, path)
        if parts[0] in out:
            raise _fail(f"{parts[0]} is given twice (with two units)", source, path)
        if size is None:
            out[parts[0]] = _number(value, source, path) * factor
        else:
            out[parts[0]] = _numbers(value, source, path, size) * factor
    return out


def _symbol_unit(key: Any, axis: str, location: bool, source: str, path: str):
    """(symbol, rest of the key split at '_') of a [location.*] or [component.*] key."""
    zero = "0" if location else ""
    parts = _split_key(key, f"E<d>{zero}{axis}_<unit>", source, path)
    _check_symbol(parts[0], axis, location, source, path)
    if len(parts) == 1:
        message = f"key has no unit suffix; expected {parts[0]}_<{_quantity(parts[0][1])} unit>"
        raise _fail(message, source, path)
    return parts[0], parts[1:]


def _parse_location(axis: Any, table: Any, source: str) -> dict[str, float]:
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
        out[symbol] = _number(value, source, f"{path}.{key}") * factor
    return out


def _parse_component(axis: Any, table: Any, source: str) -> dict[str, ComponentError]:
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
            _check_increasing(in_file, source, key_path)
            positions, position_key = in_file * factor, key
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
            factors = _poly_factors(value_factor, position_factor, coefficients.size)
            out[symbol] = ComponentError("poly", None, coefficients * factors)
            continue
        if len(units) != 1:
            raise _fail(f"expected the key {symbol}_<{quantity} unit>", source, key_path)
        factor = _check_unit(units[0], quantity, source, key_path)
        out[symbol] = None
        tables[symbol] = (key_path, value, _numbers(value, source, key_path) * factor)
    for symbol, (key_path, raw, values) in tables.items():
        if positions is None:
            message = f"a table needs positions: no position_<unit> key in [{path}]"
            raise _fail(message, source, key_path)
        if values.size != positions.size:
            message = f"the table has {values.size} values, {_describe(raw)}, but {position_key} "
            raise _fail(f"{message}has {positions.size} positions", source, key_path)
        out[symbol] = ComponentError("table", positions, values)
    return out
