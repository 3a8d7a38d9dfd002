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
    LARGEST_ERROR,
    _check_axis,
    _check_increasing,
    _check_si,
    _check_symbol,
    _describe,
    _fail,
    _limit,
    _number,
    _numbers,
    _quantity,
)
from machinesim.exceptions import ErrorModelError
from machinesim.units import FACTORS

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
    """Exact equality (of the compared fields) and pickling through the constructor (which
    freezes the copies). A pickle holds the compared fields only, so equal values pickle
    alike: the cut memo, which keys a cut on its inputs' pickles, reuses the cut of an equal
    model read from another file."""

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name))
                   for f in fields(self) if f.compare)

    __hash__ = None

    def __reduce__(self):
        return type(self), tuple(_plain(getattr(self, f.name)) for f in fields(self)
                                 if f.compare)


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
        last value) beyond the first and last position; on a rotary axis a table of a whole
        turn or more repeats each turn instead (read a whole number of turns back into it,
        `machinesim.errors.turns.each_turn`: its values a turn apart should agree). ``"poly"``:
        sum c_k x**k (refused on an axis that turns more than a turn each way: it does not
        repeat).
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

    def largest(self, lower: float, upper: float) -> tuple[float, float]:
        """The value of largest magnitude over the positions `lower` .. `upper`, and where.

        A table's extremes lie at its breakpoints or the ends; a polynomial's at the ends or
        where its derivative vanishes (its real roots, with a grid of 1025 positions besides,
        should round-off move a root).

        Parameters
        ----------
        lower, upper : float, m or rad
            The range of positions, e.g. an axis travel; ``lower <= upper``.

        Returns
        -------
        value : float, m or rad
            The error of largest magnitude, signed; inf when a polynomial overflows float64.
        position : float, m or rad
            A position where it occurs (the lowest, of several).
        """
        lower, upper = _number(lower, None, "lower"), _number(upper, None, "upper")
        if upper < lower:
            raise _fail(f"expected lower <= upper, got {lower!r} .. {upper!r}", None, "upper")
        if self.kind == "table":
            inside = self.positions[(self.positions > lower) & (self.positions < upper)]
            x = np.concatenate(([lower], inside, [upper]))
        else:
            x = np.linspace(lower, upper, 1025)
            derivative = np.polynomial.polynomial.polytrim(
                np.polynomial.polynomial.polyder(self.values))
            if derivative.size > 1:
                try:
                    roots = np.polynomial.polynomial.polyroots(derivative)
                except (np.linalg.LinAlgError, ValueError):  # a companion matrix not finite
                    roots = np.empty(0)
                real = roots.real[np.abs(roots.imag) <= 1e-9 * np.maximum(1.0, np.abs(roots))]
                x = np.sort(np.concatenate((x, np.clip(real, lower, upper))))
        with np.errstate(over="ignore", invalid="ignore"):
            values = self.evaluate(x)
        values = np.where(np.isnan(values), np.inf, values)  # inf - inf: an overflow too
        i = int(np.argmax(np.abs(values)))
        return float(values[i]), float(x[i])

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
                message += f"{_describe(grid)}, not {_describe(first)}"
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
    source : str or None
        The file (or ``from_dict``'s source) the model was read from, for messages; None for
        a model built in Python. Not compared: models of equal values are equal.
    written : Mapping[str, tuple[str, Any]]
        What the source wrote: ``<section>.<field>`` (``tool.offset``,
        ``tool_geometry.nose_radius``, ``workpiece.alpha``), ``location.<axis>.<SYM>`` or
        ``component.<axis>.<SYM>`` (and ``component.<axis>.position``) -> (the key path as
        written, unit and all, and its value in that unit), e.g.
        ``{"tool_geometry.nose_radius": ("tool_geometry.nose_radius_mm", -0.6)}``; empty
        for a model built in Python. Read-only; not compared.
    """

    tool: ToolSetting = field(default_factory=ToolSetting)
    workpiece: WorkpieceSetting = field(default_factory=WorkpieceSetting)
    location: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    component: Mapping[str, Mapping[str, ComponentError]] = field(default_factory=dict)
    tool_geometry: ToolGeometry = field(default_factory=ToolGeometry)
    source: str | None = field(default=None, compare=False, repr=False, kw_only=True)
    written: Mapping[str, tuple[str, Any]] = field(default_factory=dict, compare=False,
                                                    repr=False, kw_only=True)

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
        if self.source is not None and not isinstance(self.source, str):
            raise _fail(f"expected a str or None, got {_describe(self.source)}", None, "source")
        if not isinstance(self.written, Mapping):
            raise _fail(f"expected a mapping, got {_describe(self.written)}", None, "written")
        object.__setattr__(self, "written", MappingProxyType(dict(self.written)))

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

    # ------------------------------------------------------------- the model meets a machine

    def key_as_written(self, key: str | None) -> str | None:
        """`key` (``component.X.EYX``, ``location.C.EX0C``) as the model's source wrote it,
        unit and all (``component.X.EYX_poly_um_mm``); `key` itself when the source did not
        write it (a section, a model built in Python)."""
        return self.written.get(key, (key,))[0] if isinstance(key, str) else key

    def check_travel(self, axis: str, lower: float, upper: float,
                     source: str | None = None) -> None:
        """Refuse a polynomial of `axis` that leaves `LARGEST_ERROR` within its travel.

        A polynomial is bounded by nothing until it meets an axis: it is evaluated over the
        travel `lower` .. `upper` (`ComponentError.largest`) and held to the bound of a
        single value (1 m, 180 deg). Tables were checked when read, value by value.

        Parameters
        ----------
        axis : str
            The axis letter (X Y Z A B C); a letter the model has no component error of
            passes.
        lower, upper : float, m or rad
            The axis travel.
        source : str, optional
            The source to name (the machine's file, as when a symbol does not fit it);
            default the model's `source`.

        Raises
        ------
        ErrorModelError
            Naming the key as written, the largest value and where in the travel it occurs,
            in the units of the key (um or urad, mm or deg for a model built in Python).
        """
        linear = _quantity(axis) == "length"
        for symbol, error in self.component.get(axis, {}).items():
            if error.kind != "poly":
                continue
            quantity = _quantity(symbol[1])
            value, where = error.largest(lower, upper)
            if abs(value) <= LARGEST_ERROR[quantity]:
                continue
            name = f"component.{axis}.{symbol}"
            units = self.key_as_written(name).rsplit("_", 2)[1:]
            if len(units) != 2 or units[0] not in FACTORS or units[1] not in FACTORS:
                units = ["um" if quantity == "length" else "urad", "mm" if linear else "deg"]
            position = FACTORS[units[1]]
            travel = f"{lower / position:g} .. {upper / position:g} {units[1]}"
            with np.errstate(over="ignore"):
                shown = value / FACTORS[units[0]]
            si = "m" if quantity == "length" else "rad"
            reached = (f"{shown:g} {units[0]}" if np.isfinite(shown) else
                       f"{value:g} {si}" if np.isfinite(value) else "more than float64 holds")
            raise _fail(f"over the travel of axis {axis}, {travel}, the polynomial reaches "
                        f"{reached} at {axis} = {where / position:g} {units[1]}, no {quantity} "
                        f"error: expected at most {_limit(quantity, units[0], FACTORS[units[0]])}"
                        " either way", self.source if source is None else source,
                        self.key_as_written(name))

    def misfit(self, error: ErrorModelError, machine: str) -> ErrorModelError:
        """`error`, found checking this model against a machine, told from the model's side.

        The one way a misfit is told (command line and Python alike): a model read from a
        file (`source`) is named first, with the key as written there, then the machine
        beside it, as in ``F.toml, key 'location.C': axis 'C' is not on this machine; it
        has X, Y, Z (machine mill3, mill3.urdf)``. A model built in Python has no file:
        `error` comes back unchanged, naming the machine's file.

        Parameters
        ----------
        error : ErrorModelError
            As the machine raised it: its ``source`` is the machine's file.
        machine : str
            The machine's name.

        Returns
        -------
        ErrorModelError
            To raise (``raise model.misfit(exc, name) from None``).
        """
        if self.source is None or error.source == self.source:
            return error
        where = machine if error.source is None else f"{machine}, {error.source}"
        return ErrorModelError(f"{error.message} (machine {where})", source=self.source,
                               line=error.line, column=error.column,
                               key=self.key_as_written(error.key))


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
