"""Observations: what displacement sensors read, as the input of `machinesim.identification.fit`.

An observation is one reading: how far a point fixed in a machine frame (the centre of a ball
on the tool, a probe tip) lies from its nominal place, relative to the workpiece, along a
unit direction of the workpiece frame, with its standard uncertainty. `Observation` is one,
`Observations` a batch held as arrays; `observations` builds a batch. Each takes the axis
values first and everything else by keyword (``values=``, ``directions=``, ``sigma=``):
readings and sigma are both lengths in metres, and swapped by position they passed whenever
every reading was positive (as a sigma must be).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import KW_ONLY, dataclass, field

import numpy as np

from machinesim._keywords import keywords_checked
from machinesim.arrays import frozen
from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_floats
from machinesim.metrology.rtest import RTestReading

__all__ = ["Observation", "Observations", "SIGMA_RANGE_M", "from_r_test", "is_angle",
           "observations"]

#: The standard uncertainties a reading may have, m: from an attometre, below any sensor
#: (noise-free readings are given a sigma of 1 pm or more here), to a metre, beyond any
#: displacement sensor. Outside it the fit's weights 1/sigma leave float64 (1e-200 and
#: 1e200 had ended in numpy's "SVD did not converge"), or the unit is wrong (50 nm given
#: as 50).
SIGMA_RANGE_M = (1e-18, 1.0)
#: Below this norm a direction's square loses digits (subnormal); normalised from its
#: largest component instead.
_SMALLEST_NORM = 1e-150


def is_angle(name: str) -> bool:
    """True for a parameter in rad (rotations, ISO 230 symbols E[ABC]..), False for m."""
    if name.startswith("tool."):
        return name[5:].startswith("r")
    if name.startswith("workpiece."):
        return name[10:] in ("alpha", "beta", "gamma")
    parts = name.split(".")
    return len(parts) == 3 and len(parts[2]) > 1 and parts[2][1] in "ABC"


@dataclass(frozen=True, eq=False)
class Observation:
    """One displacement reading: ``Observation(q, value=, direction=, sigma=, ...)``.

    Parameters
    ----------
    q : array_like, shape (n_axes,)
        Axis values at the reading, m and rad, in `Machine.axes` order.
    value : float
        The reading, m: the displacement of the point from its nominal place (its position
        on the nominal machine at ``q``), relative to the workpiece, along `direction`.
    direction : array_like, shape (3,)
        Sensing direction in the workpiece frame; normalised here, zero refused.
    sigma : float
        Standard uncertainty of the reading, m, > 0.
    frame : str
        The machine frame the point is fixed in (``tool_tip``, ``probe_tip``, ...).
    point : array_like, shape (3,)
        Coordinates of the point in ``frame``, m (default its origin).
    zero_at : array_like, shape (n_axes,), optional
        Axis values where the sensor was set to zero (a dial or an R-test nest zeroed at a
        start pose): the reading is then the change of the displacement from there to
        ``q``, which no constant offset moves. None: the displacement itself.
    machine : str, optional
        The name of the machine the reading was taken on; `fit` refuses it on another.
        None (the default): not known, not checked.
    axes : str or sequence of str, optional
        That machine's axis letters in ``q``'s order (``"XYZA"``); kept as a tuple.
    """

    q: np.ndarray
    _: KW_ONLY
    value: float
    direction: np.ndarray
    sigma: float
    frame: str = "tool_tip"
    point: np.ndarray = field(default_factory=lambda: np.zeros(3))
    zero_at: np.ndarray | None = None
    machine: str | None = None
    axes: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        for key, want in (("q", 1), ("value", 0), ("direction", 1), ("sigma", 0),
                          ("point", 1)):
            if np.ndim(getattr(self, key)) != want:
                raise InputError(f"expected {key} of one observation as "
                                 f"{'a vector' if want else 'a number'}, got shape "
                                 f"{np.shape(getattr(self, key))}", key=key)
        if self.zero_at is not None and np.ndim(self.zero_at) != 1:
            raise InputError(f"expected zero_at of one observation as a vector, got shape "
                             f"{np.shape(self.zero_at)}", key="zero_at")
        batch = Observations(self.q, values=self.value, directions=self.direction,
                             sigma=self.sigma, frames=self.frame, points=self.point,
                             zero_at=self.zero_at, machine=self.machine, axes=self.axes)
        object.__setattr__(self, "axes", batch.axes)
        object.__setattr__(self, "zero_at", None if self.zero_at is None
                           else frozen(batch.zero_at[0]))
        object.__setattr__(self, "q", frozen(batch.q[0]))
        object.__setattr__(self, "value", float(batch.values[0]))
        object.__setattr__(self, "direction", frozen(batch.directions[0]))
        object.__setattr__(self, "sigma", float(batch.sigma[0]))
        object.__setattr__(self, "point", frozen(batch.points[0]))


@dataclass(frozen=True, eq=False)
class Observations:
    """Many displacement readings as arrays (what `fit` works on).

    ``Observations(q, values=, directions=, sigma=, ...)``: the axis values first, the rest
    by keyword. Every argument is either one value for all readings or one per reading; the
    number of readings N comes from those given per reading. See `Observation` for the
    meaning.

    Parameters
    ----------
    q : array_like, shape (n_axes,) or (N, n_axes)
        Axis values, m and rad.
    values : float or array_like, shape (N,)
        Readings, m.
    directions : array_like, shape (3,) or (N, 3)
        Sensing directions in the workpiece frame; normalised here, zero refused.
    sigma : float or array_like, shape (N,)
        Standard uncertainties, m, > 0.
    frames : str or sequence of str, length N
        Machine frame of each point.
    points : array_like, shape (3,) or (N, 3), optional
        Point coordinates in their frame, m (default the frame origins).
    zero_at : array_like, shape (n_axes,) or (N, n_axes), optional
        Axis values where each reading's sensor was set to zero (`Observation.zero_at`);
        a row of NaN (and the default, None) for a reading of the displacement itself.
    machine : str, optional
        The name of the machine the readings were taken on (`Observation.machine`).
    axes : str or sequence of str, optional
        That machine's axis letters in ``q``'s order; kept as a tuple.

    Attributes
    ----------
    q, zero_at : ndarray, shape (N, n_axes)
    values, sigma : ndarray, shape (N,)
    directions, points : ndarray, shape (N, 3)
        Read-only; directions of unit length.
    frames : tuple of str, length N
    """

    q: np.ndarray
    _: KW_ONLY
    values: np.ndarray
    directions: np.ndarray
    sigma: np.ndarray
    frames: tuple[str, ...] | str = "tool_tip"
    points: np.ndarray | None = None
    zero_at: np.ndarray | None = None
    machine: str | None = None
    axes: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        # numbers only: text ("1e-6", even read as a number), None, booleans, complex values
        # and ragged nesting are refused, naming the argument, not converted or traced back
        q = as_floats(self.q, "q", "axis values (m, rad)")
        values = as_floats(self.values, "values", "readings (m)")
        directions = as_floats(self.directions, "directions", "direction vectors")
        sigma = as_floats(self.sigma, "sigma", "standard uncertainties (m)")
        points = (np.zeros(3) if self.points is None
                  else as_floats(self.points, "points", "point coordinates (m)"))
        frames = self.frames
        # a frame is named by text: 3 or None had ended in "object of type 'int' has no
        # len()", and a lone name's letters are not read as one frame each
        if not isinstance(frames, str):
            named = tuple(frames) if isinstance(frames, Iterable) else None
            if named is None or not all(isinstance(f, str) for f in named):
                raise InputError(f"expected the frame as a name (str), e.g. 'tool_tip', or one "
                                 f"name per reading, got {frames!r} ({type(frames).__name__})",
                                 key="frames")
            frames = named
        if q.ndim not in (1, 2) or q.shape[-1] == 0:
            raise InputError(f"expected axis values of shape (n_axes,) or (N, n_axes), got "
                             f"{q.shape}", key="q")
        axes = _axes(self.machine, self.axes, q.shape[-1])
        zero_at = (np.full(q.shape[-1], np.nan) if self.zero_at is None
                   else as_floats(self.zero_at, "zero_at", "axis values (m, rad)"))
        if zero_at.ndim not in (1, 2) or zero_at.shape[-1] != q.shape[-1]:
            raise InputError(f"expected zero_at of shape ({q.shape[-1]},) or (N, "
                             f"{q.shape[-1]}) as q, got {zero_at.shape}", key="zero_at")
        sizes = {"q": q.shape[0] if q.ndim == 2 else None,
                 "zero_at": zero_at.shape[0] if zero_at.ndim == 2 else None,
                 "values": values.shape[0] if values.ndim == 1 else None,
                 "directions": directions.shape[0] if directions.ndim == 2 else None,
                 "sigma": sigma.shape[0] if sigma.ndim == 1 else None,
                 "frames": None if isinstance(frames, str) else len(frames),
                 "points": points.shape[0] if points.ndim == 2 else None}
        given = {k: v for k, v in sizes.items() if v is not None}
        n = max(given.values(), default=1)
        bad = {k: v for k, v in given.items() if v != n}
        if bad:
            listed = ", ".join(f"{k} {v}" for k, v in given.items())
            raise InputError(f"per-reading inputs disagree on the number of readings ({listed});"
                             " expected one value for all or one per reading",
                             key=next(iter(bad)))
        for key, arr, width in (("directions", directions, 3), ("points", points, 3)):
            if arr.shape[-1:] != (width,) or arr.ndim > 2:
                raise InputError(f"expected {key} of shape (3,) or (N, 3), got {arr.shape}",
                                 key=key)
        for key, arr in (("values", values), ("sigma", sigma)):
            if arr.ndim > 1:
                raise InputError(f"expected {key} as a number or shape (N,), got {arr.shape}",
                                 key=key)
        if n == 0:
            raise InputError("expected at least one reading, got none (zero-length arrays)",
                             key=next(iter(given), "q"))
        q = np.broadcast_to(q, (n, q.shape[-1]))
        values = np.broadcast_to(values, (n,))
        directions = np.broadcast_to(directions, (n, 3))
        sigma = np.broadcast_to(sigma, (n,))
        points = np.broadcast_to(points, (n, 3))
        zero_at = np.broadcast_to(zero_at, (n, q.shape[1]))
        given_zero = np.isfinite(zero_at)
        rows = np.flatnonzero(given_zero.any(axis=1) & ~given_zero.all(axis=1)
                              | np.isinf(zero_at).any(axis=1))
        if rows.size:
            raise InputError(f"reading {rows[0]}: zero_at {zero_at[rows[0]].tolist()}; expected "
                             "finite axis values, or all NaN for a reading not zeroed",
                             key="zero_at")
        frames = (frames,) * n if isinstance(frames, str) else tuple(frames)
        for key, arr in (("q", q), ("values", values), ("directions", directions),
                         ("points", points)):
            rows = np.flatnonzero(~np.isfinite(arr.reshape(n, -1)).all(axis=1))
            if rows.size:
                raise InputError(f"reading {rows[0]}: {key} {arr[rows[0]].tolist()} has NaN "
                                 "or inf; expected finite numbers (SI)", key=key)
        largest = np.max(np.abs(directions), axis=1)
        rows = np.flatnonzero(~(largest > 0.0))
        if rows.size:
            raise InputError(f"reading {rows[0]}: direction {directions[rows[0]].tolist()} is "
                             "zero; expected a non-zero vector (it is normalised)",
                             key="directions")
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            norms = np.linalg.norm(directions, axis=1)
            unit = directions / norms[:, None]
        # a length whose square leaves float64 (1e300: its norm was inf, and the direction
        # came out zero; 1e-320: refused as zero) is normalised from its largest component
        odd = ~np.isfinite(norms) | (norms < _SMALLEST_NORM)
        if odd.any():
            scaled = directions[odd] / largest[odd, None]
            unit[odd] = scaled / np.linalg.norm(scaled, axis=1)[:, None]
        low, high = SIGMA_RANGE_M
        rows = np.flatnonzero(~((sigma >= low) & (sigma <= high)))
        if rows.size:
            raise InputError(f"reading {rows[0]}: sigma {float(sigma[rows[0]])!r} m; expected a "
                             f"finite standard uncertainty from {low:g} m to {high:g} m (a "
                             "sigma beyond is no displacement sensor's, and its weight 1/sigma "
                             "leaves float64 in the fit: given in um or nm?)", key="sigma")
        object.__setattr__(self, "q", frozen(q))
        object.__setattr__(self, "values", frozen(values))
        object.__setattr__(self, "directions", frozen(unit))
        object.__setattr__(self, "sigma", frozen(sigma))
        object.__setattr__(self, "frames", frames)
        object.__setattr__(self, "points", frozen(points))
        object.__setattr__(self, "zero_at", frozen(zero_at))
        object.__setattr__(self, "axes", axes)

    @property
    def zeroed(self) -> np.ndarray:
        """(N,) bool: the readings taken from a sensor set to zero at `zero_at`."""
        return np.isfinite(self.zero_at[:, 0])

    def __len__(self) -> int:
        return self.values.shape[0]

    def __getitem__(self, i: int) -> Observation:
        return Observation(self.q[i], value=self.values[i], direction=self.directions[i],
                           sigma=self.sigma[i], frame=self.frames[i], point=self.points[i],
                           zero_at=self.zero_at[i] if self.zeroed[i] else None,
                           machine=self.machine, axes=self.axes)

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    @classmethod
    def of(cls, items: Observations | Observation | Iterable) -> Observations:
        """One batch from an `Observations`, an `Observation`, or a sequence of either."""
        if isinstance(items, Observations):
            return items
        if isinstance(items, Observation):
            items = (items,)
        if not isinstance(items, Iterable) or isinstance(items, str | bytes | Mapping):
            raise InputError(f"expected Observation or Observations, or a sequence of them, got "
                             f"{_kind(items)}", key="observations")
        parts = []
        for item in items:
            if isinstance(item, Observation):
                parts.append(Observations(item.q, values=item.value,
                                          directions=item.direction, sigma=item.sigma,
                                          frames=item.frame, points=item.point,
                                          zero_at=item.zero_at, machine=item.machine,
                                          axes=item.axes))
            elif isinstance(item, Observations):
                parts.append(item)
            else:
                raise InputError(f"expected Observation or Observations, got {_kind(item)}",
                                 key="observations")
        if not parts:
            raise InputError("expected at least one observation, got none", key="observations")
        widths = {p.q.shape[1] for p in parts}
        if len(widths) > 1:
            raise InputError(f"observations have axis values of different lengths "
                             f"{sorted(widths)}; expected one machine's n_axes", key="q")
        machine, axes = None, None
        for p in parts:  # one machine's readings: the first known, the rest checked against it
            if machine is None and axes is None:
                machine, axes = p.machine, p.axes
            elif not p.taken_on(machine, axes):
                raise InputError(f"observations taken on {_named(p.machine, p.axes)} and on "
                                 f"{_named(machine, axes)}; expected one machine's readings",
                                 key="observations")
        return cls(np.concatenate([p.q for p in parts]),
                   values=np.concatenate([p.values for p in parts]),
                   directions=np.concatenate([p.directions for p in parts]),
                   sigma=np.concatenate([p.sigma for p in parts]),
                   frames=tuple(f for p in parts for f in p.frames),
                   points=np.concatenate([p.points for p in parts]),
                   zero_at=np.concatenate([p.zero_at for p in parts]),
                   machine=machine, axes=axes)

    def taken_on(self, machine: str | None, axes) -> bool:
        """False when the readings are known to be from a machine other than the one named
        ``machine`` with axis letters ``axes`` (each None: not known, not compared)."""
        return ((self.machine is None or machine is None or self.machine == machine)
                and (self.axes is None or axes is None or self.axes == tuple(axes)))

    def check_machine(self, machine) -> None:
        """Refuse readings taken on a machine other than ``machine`` (a `Machine`): their
        columns are another machine's axes, even when as many."""
        if not self.taken_on(machine.name, machine.axes):
            raise InputError(f"the readings were taken on {_named(self.machine, self.axes)}, "
                             f"not on {_named(machine.name, machine.axes)}; expected readings "
                             f"taken on {machine.name} (fit them on the machine they were "
                             "taken on)", key="observations")


def _axes(machine, axes, width: int) -> tuple[str, ...] | None:
    """The machine's axis letters as a tuple (None when not given), checked against q's
    width; ``machine`` checked to be a name."""
    if machine is not None and not isinstance(machine, str):
        raise InputError(f"expected the machine the readings were taken on as its name (str), "
                         f"got {type(machine).__name__}", key="machine")
    if axes is None:
        return None
    letters = tuple(axes) if isinstance(axes, str | Iterable) else None
    if letters is None or not all(isinstance(a, str) for a in letters):
        raise InputError(f"expected the axes as letters, e.g. 'XYZA', got {axes!r}", key="axes")
    if len(letters) != width:
        raise InputError(f"expected {width} axis letters, one per column of q, got "
                         f"{''.join(letters)!r}", key="axes")
    return letters


def _named(machine: str | None, axes) -> str:
    """``planer_4axis (axes XYZA)``, as a message names a reading's machine."""
    name = "a machine not named" if machine is None else machine
    return name if axes is None else f"{name} (axes {''.join(axes)})"


def _kind(value) -> str:
    """What arrived instead of observations, and for an R-test's reading the way in."""
    if isinstance(value, RTestReading):
        return "an RTestReading: an R-test's readings go in as from_r_test(reading)"
    return type(value).__name__


def from_r_test(reading) -> Observations:
    """The readings of an R-test (`machinesim.metrology.RTestReading`) as observations: three
    per position, along the workpiece frame's X, Y and Z, with the reading's uncertainty, and
    the pose where its sensors were set to zero (`RTestReading.zero_at`, if any)."""
    if not isinstance(reading, RTestReading):
        raise InputError(f"expected the RTestReading that lab.r_test().read(q) returns, got "
                         f"{type(reading).__name__}; readings of other sensors go in as "
                         "observations(q, directions=..., values=..., sigma=...)",
                         key="reading")
    n = len(reading.q)
    return Observations(np.repeat(reading.q, 3, axis=0),
                        values=reading.displacement.reshape(-1),
                        directions=np.tile(np.eye(3), (n, 1)), sigma=reading.sigma,
                        frames=reading.frame, points=reading.point,
                        zero_at=getattr(reading, "zero_at", None),
                        machine=getattr(reading, "machine", None),
                        axes=getattr(reading, "axes", None))


@keywords_checked
def observations(q, *, directions, values, sigma, frame="tool_tip",
                 point=None, zero_at=None, machine=None, axes=None) -> Observations:
    """Readings as one `Observations` batch (each argument one for all, or one per reading):
    ``observations(q, directions=u, values=readings, sigma=50e-9)``, the axis values first and
    the rest by keyword, as `Observations` and `plan_quality` take them.

    Parameters
    ----------
    q : array_like, shape (n_axes,) or (N, n_axes)
        Axis values, m and rad.
    directions : array_like, shape (3,) or (N, 3)
        Sensing directions in the workpiece frame (normalised here).
    values : float or array_like, shape (N,)
        Readings, m.
    sigma : float or array_like, shape (N,)
        Standard uncertainties, m.
    frame : str or sequence of str
        Frame of the point(s).
    point : array_like, shape (3,) or (N, 3), optional
        Point coordinates in the frame, m.
    zero_at : array_like, shape (n_axes,) or (N, n_axes), optional
        Axis values where the sensors were set to zero (`Observation.zero_at`).
    machine : str, optional
        The name of the machine the readings were taken on (`Observation.machine`).
    axes : str or sequence of str, optional
        That machine's axis letters in ``q``'s order.
    """
    return Observations(q, values=values, directions=directions, sigma=sigma, frames=frame,
                        points=point, zero_at=zero_at, machine=machine, axes=axes)


