"""The injected errors of a machine as one immutable value, `ErrorModel`.

`ErrorModel` holds the values of the families (`machinesim.errors.families`: `ToolSetting`,
`ToolGeometry`, `WorkpieceSetting`, `ComponentError`) and the location errors, checks and
freezes them when built, names every parameter (`ErrorModel.parameters`), reads and writes
TOML through `machinesim.errors.toml`, and meets a machine (`ErrorModel.check_travel`,
`ErrorModel.misfit`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from machinesim.errors._checks import (
    AXES,
    LARGEST_ERROR,
    _check_axis,
    _check_si,
    _check_symbol,
    _describe,
    _fail,
    _in_unit,
    _limit,
    _number,
    _quantity,
    _shown,
)
from machinesim.errors.families import (
    _WORKPIECE_ANGLES,
    ComponentError,
    ToolGeometry,
    ToolSetting,
    WorkpieceSetting,
    _plain,
    _Value,
)
from machinesim.exceptions import ErrorModelError, brief
from machinesim.units import FACTORS, M_PER_MM, RAD_PER_DEG

_PARAMETER_RE = re.compile(
    r"tool\.(?P<tool>x|y|z|rx|ry|rz)|tool_geometry\.(?P<geometry>nose_radius)|workpiece\.(?P<workpiece>x|y|z|alpha|beta|gamma)"
    r"|location\.(?P<laxis>\w)\.(?P<lsym>\w+)|component\.(?P<caxis>\w)\.(?P<csym>\w+)\[(?P<k>\d+)\]",
    re.ASCII,  # \d took 'component.X.EXX[١]' (an Arabic-Indic 1) for entry 1
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


#: Parameters an ErrorModel's repr lists before it says how many more are not zero.
REPR_PARAMETERS = 8


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
    lines : Mapping[str, int]
        The line of each key path of the source file, as written (``tool.offset_um``,
        ``location.C``), for messages (`line_of`); empty for a model not read from a file.
        Read-only; not compared.
    """

    tool: ToolSetting = field(default_factory=ToolSetting)
    workpiece: WorkpieceSetting = field(default_factory=WorkpieceSetting)
    location: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    component: Mapping[str, Mapping[str, ComponentError]] = field(default_factory=dict)
    tool_geometry: ToolGeometry = field(default_factory=ToolGeometry)
    source: str | None = field(default=None, compare=False, repr=False, kw_only=True)
    written: Mapping[str, tuple[str, Any]] = field(default_factory=dict, compare=False,
                                                    repr=False, kw_only=True)
    lines: Mapping[str, int] = field(default_factory=dict, compare=False, repr=False,
                                     kw_only=True)

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
        if not isinstance(self.lines, Mapping):
            raise _fail(f"expected a mapping, got {_describe(self.lines)}", None, "lines")
        object.__setattr__(self, "lines", MappingProxyType(dict(self.lines)))

    def __repr__(self) -> str:
        """Its non-zero parameters with their units (SI), the first `REPR_PARAMETERS`."""
        given = {n: v for n, v in self.parameters().items() if v != 0.0}
        items = [f"{n} = {v:.6g} {self.parameter_unit(n)}"
                 for n, v in list(given.items())[:REPR_PARAMETERS]]
        if len(given) > REPR_PARAMETERS:
            items.append(f"... {len(given) - REPR_PARAMETERS} more non-zero")
        where = "" if self.source is None else f"; from {self.source}"
        return f"ErrorModel({', '.join(items) or 'no errors'}{where})"

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

    def parameter_unit(self, name: str) -> str:
        """The SI unit of parameter ``name`` (as `parameters` and `with_parameters` name them).

        ``"m"`` or ``"rad"``: a tool or workpiece offset or rotation, the nose radius, a
        location error and a component table's value by its symbol (``E<d>...``: ``d`` in X Y
        Z a length, in A B C an angle, `machinesim.errors`). A polynomial's coefficient
        ``k >= 1`` is its value's unit per the axis position's unit to the k
        (``sum c_k x**k``, x in m on X Y Z, in rad on A B C): ``"m/m"``, ``"m/m^2"``,
        ``"rad/m"``, ``"m/rad^3"``; its ``k = 0`` the value's. A location error need not be in
        the model (`with_parameters` adds it); a component parameter must be, as there.

        Raises
        ------
        ErrorModelError
            For a name that is no parameter, and a component entry the model lacks.
        """
        match = _PARAMETER_RE.fullmatch(name) if isinstance(name, str) else None
        if match is None:
            raise _fail(f"unknown parameter name; expected {_PARAMETER_FORMS}", None,
                        name if isinstance(name, str) else brief(repr(name)))
        if match["tool"] or match["workpiece"]:
            rotation = (match["tool"] or "").startswith("r") or match["workpiece"] in (
                _WORKPIECE_ANGLES)
            return "rad" if rotation else "m"
        if match["geometry"]:
            return "m"
        axis, symbol = match["laxis"] or match["caxis"], match["lsym"] or match["csym"]
        _check_axis(axis, None, name)
        _check_symbol(symbol, axis, bool(match["laxis"]), None, name)
        value = "m" if _quantity(symbol[1]) == "length" else "rad"
        if match["laxis"]:
            return value
        error, k = self.component.get(axis, {}).get(symbol), int(match["k"])
        if error is None or k >= error.values.size:
            raise _fail("unknown parameter: the model has no such error"
                        if error is None else f"unknown parameter: index {k}, but the error "
                        f"has {error.values.size} values", None, name)
        if error.kind == "table" or k == 0:
            return value
        position = "m" if _quantity(axis) == "length" else "rad"
        return f"{value}/{position}" + (f"^{k}" if k > 1 else "")

    def with_parameters(self, mapping: Mapping[str, float]) -> ErrorModel:
        """A copy with the named parameters replaced (names as in `parameters`, SI values).

        A location error not yet in the model is added (any valid symbol of a valid axis);
        a component parameter must exist. Any other name raises `ErrorModelError`, and so
        does what is no mapping (pairs ``[(name, value)]`` are given as ``dict(pairs)``).
        """
        if not isinstance(mapping, Mapping):
            # a list of (name, value) pairs had ended in "AttributeError: 'list' object has
            # no attribute 'items'"
            hint = ("; (name, value) pairs are given as dict(pairs)"
                    if isinstance(mapping, list | tuple) else "")
            raise _fail(f"expected the parameters as a mapping {{name: value}} (names as "
                        f"ErrorModel.parameters gives them, SI values), got "
                        f"{_describe(mapping)}{hint}", None, "parameters")
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
            # each value's size is checked under its own name: the settings' own checks named
            # the field ("key 'offset'" for tool.x, "key 'component.X.EXX'" for EXX[1])
            if match["tool"]:
                angle = match["tool"].startswith("r")
                _check_si(value, "angle" if angle else "length", name)
                target = rotation if angle else offset
                target["xyz".index(match["tool"][-1])] = value
            elif match["geometry"]:
                _check_si(value, "length", name)
                nose_radius = value
            elif match["workpiece"] in ("x", "y", "z"):
                _check_si(value, "length", name)
                delta["xyz".index(match["workpiece"])] = value
            elif match["workpiece"]:
                _check_si(value, "angle", name)
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
                if self.component[match["caxis"]][match["csym"]].kind == "table":
                    _check_si(value, _quantity(match["csym"][1]), name)
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
        if not isinstance(path, str | os.PathLike):
            # a dict of the layout given here had ended in "TypeError: stat: path should be
            # string, bytes, os.PathLike or integer, not dict"
            hint = ("; a dict of the TOML layout is read by ErrorModel.from_dict"
                    if isinstance(path, Mapping) else "")
            raise ErrorModelError(f"expected the TOML file's path as a str or Path, got "
                                  f"{type(path).__name__}{hint}", key="path")
        data, lines = _io().read_toml_lines(path)
        return _io().model_from_dict(data, str(path), lines)

    def to_toml(self, path: str | os.PathLike) -> None:
        """Write the model to `path` in um, urad, mm and deg, whole or not at all.

        ``from_toml(path)`` then gives every SI value back to float64 round-off (two roundings).
        `path` ends in ``.toml`` (any case): another ending is refused (InputError), nothing
        written.
        """
        from machinesim._io import check_ending

        check_ending(path, "toml", "ErrorModel.to_toml", "a TOML error model")
        _io().write_toml(self.to_dict(readable=True), path)

    # ------------------------------------------------------------- the model meets a machine

    def key_as_written(self, key: str | None) -> str | None:
        """`key` (``component.X.EYX``, ``location.C.EX0C``) as the model's source wrote it,
        unit and all (``component.X.EYX_poly_um_mm``); `key` itself when the source did not
        write it (a section, a model built in Python)."""
        return self.written.get(key, (key,))[0] if isinstance(key, str) else key

    def line_of(self, key: str | None) -> int | None:
        """The line of the source file on which `key` is written (`key_as_written`'s form
        or the model's own, ``component.X.EYX``); None when the model was not read from a
        file or the file did not write it."""
        if not isinstance(key, str):
            return None
        return self.lines.get(key, self.lines.get(self.key_as_written(key)))

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
            travel = (f"{lower / position:g} .. {upper / position:g} {units[1]}"
                      if units[1] not in ("m", "rad") else
                      f"{_shown(lower, units[1])} .. {_shown(upper, units[1])}")
            first = {"m": M_PER_MM, "rad": RAD_PER_DEG}.get(units[0], FACTORS[units[0]])
            with np.errstate(over="ignore"):  # in the unit shown first (`_shown`)
                shown = value / first
            si = "m" if quantity == "length" else "rad"
            # where the unit shown overflows float64 (1e300 m/rad**10 over a turn, 9.6e307 m,
            # is 9.6e313 um), worked out in decimal, SI beside
            written = {"m": "mm", "rad": "deg"}.get(units[0], units[0])
            reached = (_shown(value, units[0]) if np.isfinite(shown) else
                       f"{_in_unit(value, first)} {written} ({value:g} {si})"
                       if np.isfinite(value) else "more than float64 holds")
            raise _fail(f"over the travel of axis {axis}, {travel}, the polynomial reaches "
                        f"{reached} at {axis} = {_shown(where, units[1])}, no {quantity} "
                        f"error: expected at most {_limit(quantity, units[0], FACTORS[units[0]])}"
                        " either way", self.source if source is None else source,
                        self.key_as_written(name))

    def misfit(self, error: ErrorModelError, machine: str) -> ErrorModelError:
        """`error`, found checking this model against a machine, told from the model's side.

        The one way a misfit is told (command line and Python alike): a model read from a
        file (`source`) is named first, with the line and the key as written there, then the
        machine beside it, as in ``F.toml, line 4, key 'location.C': axis 'C' is not on this
        machine; it has X, Y, Z (machine mill3, mill3.urdf)``. A model built in Python has
        no file:
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
        # the line is of the model's file, where the key is (`line_of`): the machine's
        # error names no line of its own file
        return ErrorModelError(f"{error.message} (machine {where})", source=self.source,
                               line=self.line_of(error.key), key=self.key_as_written(error.key))


def as_error_model(errors, *, key: str = "errors") -> ErrorModel:
    """``errors`` as an `ErrorModel`: one already, a dict in the TOML layout (units in every
    key, `ErrorModel.from_dict`), or the path of a TOML file (`ErrorModel.from_toml`); None
    is the nominal machine, an empty model. ``key``: the argument's name, for a refusal."""
    if errors is None:
        return ErrorModel()
    if isinstance(errors, ErrorModel):
        return errors
    if isinstance(errors, Mapping):
        return ErrorModel.from_dict(errors)
    if isinstance(errors, str | os.PathLike):
        return ErrorModel.from_toml(errors)
    hint = ""
    if isinstance(getattr(errors, "errors", None), ErrorModel):  # an identification's result
        hint = f" (its identified model is {type(errors).__name__}.errors)"
    raise _fail(f"Expected errors as an ErrorModel, a dict (the TOML layout, units in every "
                f"key) or a TOML path, got {type(errors).__name__}{hint}", None, key)
