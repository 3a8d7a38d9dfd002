"""The injected errors of a machine as immutable values (the families: `machinesim.errors`).

`ToolSetting`, `WorkpieceSetting`, `ComponentError` and `ErrorModel` check and freeze their
inputs when built; `ErrorModel` reads and writes TOML through `machinesim.errors.toml`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from machinesim.errors._checks import (
    AXES,
    _check_axis,
    _check_increasing,
    _check_si,
    _check_symbol,
    _describe,
    _fail,
    _number,
    _numbers,
    _quantity,
)

_WORKPIECE_ANGLES = ("alpha", "beta", "gamma")
_PARAMETER_RE = re.compile(
    r"tool\.(?P<tool>x|y|z|rx|ry|rz)|tool_geometry\.(?P<geometry>nose_radius)|workpiece\.(?P<workpiece>x|y|z|alpha|beta|gamma)"
    r"|location\.(?P<laxis>\w)\.(?P<lsym>\w+)|component\.(?P<caxis>\w)\.(?P<csym>\w+)\[(?P<k>\d+)\]"
)
_PARAMETER_FORMS = (
    "tool.<x|y|z|rx|ry|rz>, tool_geometry.nose_radius, workpiece.<x|y|z|alpha|beta|gamma>, "
    "location.<axis>.<SYM> or "
    "component.<axis>.<SYM>[k]"
)


def _io():
    # The toml module builds ErrorModel values, so it imports this one: load it on use.
    from machinesim.errors import toml

    return toml


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
        _check_si(self.offset, "length", "offset")
        _check_si(self.rotation, "angle", "rotation")


@dataclass(frozen=True, eq=False)
class ToolGeometry(_Value):
    """Tool geometry error: the tool as it is against the tool as programmed.

    Attributes
    ----------
    nose_radius : float, m
        Nose (or ball) radius error dR: the edge's radius is the nominal one plus dR, the
        tool still set by its tip (the ``tool_tip`` frame), so its centre sits dR higher
        (paper 004, eq 20). It moves no frame of the machine: the cutting engines apply it
        to the tool's shape.
    """

    nose_radius: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "nose_radius", _number(self.nose_radius, None, "nose_radius"))
        _check_si(self.nose_radius, "length", "nose_radius")


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
        _check_si(self.delta, "length", "delta")
        for name in _WORKPIECE_ANGLES:
            object.__setattr__(self, name, _number(getattr(self, name), None, name))
            _check_si(getattr(self, name), "angle", name)


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


def _location_value(value: Any, key: str) -> float:
    number = _number(value, None, key)
    _check_si(number, _quantity(key.rsplit(".", 1)[1][1]), key)
    return number


def _component_value(error: Any, key: str) -> Any:
    if isinstance(error, ComponentError) and error.kind == "table":
        _check_si(error.values, _quantity(key.rsplit(".", 1)[1][1]), key)
    return error


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
    tool_geometry : ToolGeometry
        The tool's shape errors (nose radius).
    """

    tool: ToolSetting = field(default_factory=ToolSetting)
    workpiece: WorkpieceSetting = field(default_factory=WorkpieceSetting)
    location: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    component: Mapping[str, Mapping[str, ComponentError]] = field(default_factory=dict)
    tool_geometry: ToolGeometry = field(default_factory=ToolGeometry)

    def __post_init__(self) -> None:
        for name, kind in (("tool", ToolSetting), ("workpiece", WorkpieceSetting),
                           ("tool_geometry", ToolGeometry)):
            if not isinstance(getattr(self, name), kind):
                message = f"expected a {kind.__name__}, got {_describe(getattr(self, name))}"
                raise _fail(message, None, name)
        location = _freeze(self.location, "location", _location_value)
        component = _freeze(self.component, "component", _component_value)
        _check_component(component)
        object.__setattr__(self, "location", location)
        object.__setattr__(self, "component", component)

    @property
    def is_zero(self) -> bool:
        """True when every parameter is zero: the model injects no error."""
        return all(value == 0.0 for value in self.parameters().values())

    def parameters(self) -> dict[str, float]:
        """Every parameter, by canonical name, in SI (m or rad).

        Order: ``tool.x .y .z .rx .ry .rz``, ``tool_geometry.nose_radius`` (only when not
        zero), ``workpiece.x .y .z .alpha .beta .gamma``, ``location.<axis>.<SYM>``,
        ``component.<axis>.<SYM>[k]`` (table value or polynomial coefficient k), axes and
        symbols in X Y Z A B C order.
        """
        tool = np.concatenate([self.tool.offset, self.tool.rotation]).tolist()
        names = ("tool.x", "tool.y", "tool.z", "tool.rx", "tool.ry", "tool.rz")
        out = dict(zip(names, tool, strict=True))
        if self.tool_geometry.nose_radius != 0.0:
            out["tool_geometry.nose_radius"] = self.tool_geometry.nose_radius
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
        nose_radius = self.tool_geometry.nose_radius
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
            elif match["geometry"]:
                nose_radius = value
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
        return ErrorModel(tool, workpiece, location, component, ToolGeometry(nose_radius))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], source: str = "<dict>") -> ErrorModel:
        """Read the TOML structure (package docstring); errors name `source`, the key, the value.

        Parameters
        ----------
        d : Mapping
            Sections ``tool``, ``tool_geometry``, ``workpiece``, ``location``, ``component``,
            all optional.
            Numbers may be ints or floats; lists may be lists, tuples or 1-D arrays.
        source : str
            Where `d` came from, for error messages.
        """
        return _io().model_from_dict(d, source)

    def to_dict(self, *, readable: bool = False) -> dict[str, Any]:
        """The TOML structure of this model.

        With ``readable=False`` (default) every key is in m or rad and
        ``from_dict(to_dict())`` reproduces the model exactly; with ``readable=True`` the
        units are those of `to_toml` (um, urad, mm, deg).
        """
        return _io().dict_from_model(self, readable)

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> ErrorModel:
        """Read an error model from a TOML file (layout in the `machinesim.errors` docstring)."""
        return cls.from_dict(_io().read_toml(path), source=str(path))

    def to_toml(self, path: str | os.PathLike) -> None:
        """Write the model to `path` in um, urad, mm and deg, whole or not at all.

        ``from_toml(path)`` then gives every SI value back to float64 round-off (two roundings).
        """
        _io().write_toml(self.to_dict(readable=True), path)


def as_error_model(errors) -> ErrorModel:
    """``errors`` as an `ErrorModel`: one already, a dict in the TOML layout (units in every
    key, `ErrorModel.from_dict`), or the path of a TOML file (`ErrorModel.from_toml`); None
    is the nominal machine, an empty model."""
    if errors is None:
        return ErrorModel()
    if isinstance(errors, ErrorModel):
        return errors
    if isinstance(errors, Mapping):
        return ErrorModel.from_dict(errors)
    if isinstance(errors, str | os.PathLike):
        return ErrorModel.from_toml(errors)
    raise _fail(f"Expected errors as an ErrorModel, a dict (the TOML layout, units in every "
                f"key) or a TOML path, got {type(errors).__name__}", None, "errors")
