"""The error families as immutable values: `ToolSetting`, `ToolGeometry`,
`WorkpieceSetting` and `ComponentError` (a location error is a float).

Each checks and freezes its inputs when built; `ComponentError`, a table or a polynomial of
an axis position, evaluates itself, its basis and its extremes. `ErrorModel`
(`machinesim.errors.model`) holds them for one machine.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any, Literal

import numpy as np

from machinesim.errors._checks import (
    _check_increasing,
    _check_si,
    _describe,
    _fail,
    _number,
    _numbers,
)

_WORKPIECE_ANGLES = ("alpha", "beta", "gamma")


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


#: Coefficients beyond which a polynomial is no axis error's: one of a few degrees gives
#: an error curve (finer detail is a table). Every evaluation makes a pass over the
#: coefficients, so 300,000 of them (600 kB of zeros, under the 4 MB a file may hold) cut
#: in 15 s and `machinesim view` of the program did not end within 3 minutes.
MAX_POLY_COEFFICIENTS = 1000


def check_poly_size(count: int, source: str | None, key: str | None) -> None:
    """Refuse a polynomial of more than `MAX_POLY_COEFFICIENTS` coefficients."""
    if count > MAX_POLY_COEFFICIENTS:
        raise _fail(f"a polynomial of {count} coefficients (degree {count - 1}); expected at "
                    f"most {MAX_POLY_COEFFICIENTS}: an axis error's polynomial has a few, and "
                    "finer detail is a table (position_<unit> beside the values)", source, key)


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
            _check_increasing(positions, None, "positions", "m or rad")
            if positions.size != values.size:
                message = f"got {values.size} values for {positions.size} positions"
                raise _fail(f"a table needs one value per position, {message}", None, "values")
        elif self.kind != "poly":
            raise _fail(f"expected 'table' or 'poly', got {_describe(self.kind)}", None, "kind")
        elif positions is not None:
            message = f"a polynomial has no positions, got {_describe(positions)}"
            raise _fail(message, None, "positions")
        else:
            check_poly_size(values.size, None, "values")
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
            raise _fail(f"expected lower <= upper, got {lower!r} .. {upper!r} m or rad",
                        None, "upper")
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
