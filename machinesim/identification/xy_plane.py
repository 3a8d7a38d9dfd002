"""The XY plane's 2-D position errors from 1-D laser measurements (paper 003 eq 1).

Inputs are interferometer readings only (`machinesim.metrology.LaserInterferometer`, read
through the lab): the positioning of X along the table's centre line Y = 0 and of Y along
X = 0 (ISO 230-2 mean bidirectional deviations), the straightness of X read in Y and of Y
read in X (least-squares reference line removed, ISO 230-1), and the squareness from a face
diagonal: by the paper's eq 2, one diagonal against the X and Y travels
(`machinesim.metrology.interferometer.squareness_from_diagonal`), or from the two diagonals
(ISO 230-6, `machinesim.metrology.iso230.squareness_from_diagonals`).

Sign convention (docs/procedures/xy_plane_errors.md): every deviation is the tool's actual
displacement relative to the table, read along the table's axes, minus the commanded one,
``a(x, y) = (dPx, dPy)``; X is the reference axis and the squareness ``e`` is that of Y to X
as ISO 230-1's EC0Y (Y's motion runs along ``(-sin e, cos e)``). Eq 1 of paper 003 then reads

    dPx(x, y) = Px(x) + Sx(y) - e y
    dPy(x, y) = Py(y) + Sy(x)

with ``Px``, ``Py`` the positioning deviations, ``Sx(y)`` the straightness of Y in X,
``Sy(x)`` that of X in Y. The paper prints the squareness term ``a_x(i) theta_xy`` in the Y
row (Y taken as the reference, the X motion tilted); the two forms differ by a rigid turn of
the plate by ``e`` and describe the same machine, but not the same figures: which row's
range holds the squareness depends on the form. `XYPlaneMap.ranges` gives either
(``reference="y"``: the paper's); the compensation table applies the X-reference form.

Because the straightness lines are least-squares lines, the diagonal squareness (eq 2 or
the two diagonals: both read the corner-to-corner chords) is corrected by the chord slopes
of the straightness curves over the diagonals' spans (`squareness_of_lines`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError
from machinesim.identification.fit import Estimate, fit
from machinesim.identification.observations import Observations, observations

__all__ = ["Curve", "DiagonalReading", "XYPlaneMap", "fit_xy_plane", "fit_parameters",
           "plane_observations", "squareness_of_lines"]


@dataclass(frozen=True, eq=False)
class Curve:
    """A 1-D deviation curve: values at increasing positions, linear in between, m.

    Beyond the first and last position the end values hold (as the error tables do).
    """

    positions: np.ndarray
    values: np.ndarray

    def __post_init__(self) -> None:
        p = np.array(self.positions, dtype=np.float64)
        v = np.array(self.values, dtype=np.float64)
        if p.ndim != 1 or p.shape != v.shape or p.size < 2:
            raise InputError(f"Expected positions and values of one shape (N >= 2,), got "
                             f"{p.shape} and {v.shape}", key="positions")
        if not (np.isfinite(p).all() and np.isfinite(v).all()) or np.any(np.diff(p) <= 0):
            raise InputError("Expected finite, strictly increasing positions and finite "
                             "values", key="positions")
        for array in (p, v):
            array.setflags(write=False)
        object.__setattr__(self, "positions", p)
        object.__setattr__(self, "values", v)

    def __call__(self, x) -> np.ndarray:
        return np.interp(np.asarray(x, dtype=np.float64), self.positions, self.values)

    @classmethod
    def zero(cls, start: float, end: float) -> Curve:
        return cls(np.array([start, end]), np.zeros(2))


@dataclass(frozen=True, eq=False)
class XYPlaneMap:
    """Eq 1's 2-D error map of the XY plane (module docstring), m.

    Attributes
    ----------
    position_x, position_y : Curve
        Positioning deviations Px(x) (on Y = 0) and Py(y) (on X = 0).
    straightness_x_in_y, straightness_y_in_x : Curve
        Sy(x): the lateral (Y) deviation of the X motion; Sx(y): the lateral (X) deviation
        of the Y motion, each about its least-squares line.
    squareness : float
        ``e``, rad, of the least-squares lines (EC0Y sense).
    """

    position_x: Curve
    position_y: Curve
    straightness_x_in_y: Curve
    straightness_y_in_x: Curve
    squareness: float

    def deviation(self, x, y, reference: str = "x") -> tuple[np.ndarray, np.ndarray]:
        """(dPx, dPy) at commanded positions (x, y), m; broadcast like numpy.

        ``reference="x"``: X the reference axis, the squareness in the dPx row (ISO 230-1's
        EC0Y; the form the compensation table applies). ``"y"``: eq 1 as the paper prints
        it, Y the reference and the squareness in the dPy row, ``dPy = Py(y) + Sy(x) - e x``
        (the same machine turned rigidly by -e, module docstring).
        """
        x, y = np.broadcast_arrays(np.asarray(x, dtype=np.float64),
                                   np.asarray(y, dtype=np.float64))
        if reference not in ("x", "y"):
            raise InputError(f"Expected reference 'x' or 'y', got {reference!r}",
                             key="reference")
        dx = self.position_x(x) + self.straightness_y_in_x(y)
        dy = self.position_y(y) + self.straightness_x_in_y(x)
        if reference == "x":
            return dx - self.squareness * y, dy
        return dx, dy - self.squareness * x

    def grid(self, x_range, y_range, count: int = 41, reference: str = "x"):
        """(X, Y, dPx, dPy) on a count x count grid over the ranges, m (as Figs 2 and 5);
        ``reference`` as in `deviation`."""
        xs = np.linspace(*_range(x_range, "x_range"), count)
        ys = np.linspace(*_range(y_range, "y_range"), count)
        gx, gy = np.meshgrid(xs, ys, indexing="xy")
        dx, dy = self.deviation(gx, gy, reference)
        return gx, gy, dx, dy

    def ranges(self, x_range, y_range, count: int = 41,
               reference: str = "x") -> tuple[float, float]:
        """Maximum deviation (peak to valley) of dPx and of dPy over the plate, m.

        The paper's "maximum deviation of the 2-D position errors" (11.59 um in X, 12.33 um
        in Y before compensation), taken here as the range over the plate, the figure
        insensitive to where the readings were zeroed. Which row holds the squareness
        depends on the reference axis (`deviation`); the paper's figures are
        ``reference="y"``.

        Read on the count x count grid and on every knot of the curves within the ranges:
        each row is a sum of piecewise-linear curves of x and of y (and a plane), whose
        extremes lie on the knots, which a grid between them cuts off.
        """
        (x0, x1), (y0, y1) = _range(x_range, "x_range"), _range(y_range, "y_range")
        xs = _with_knots(np.linspace(x0, x1, count), (self.position_x,
                                                      self.straightness_x_in_y), x0, x1)
        ys = _with_knots(np.linspace(y0, y1, count), (self.position_y,
                                                      self.straightness_y_in_x), y0, y1)
        dx, dy = self.deviation(*np.meshgrid(xs, ys, indexing="xy"), reference)
        return float(np.ptp(dx)), float(np.ptp(dy))

    def diagonal(self, corner, opposite, positions) -> np.ndarray:
        """The diagonal test this map predicts: deviation along the diagonal from the
        corner (measured minus commanded distance) at distances ``positions``, m."""
        c = np.asarray(corner, dtype=np.float64)
        span = np.asarray(opposite, dtype=np.float64) - c
        u = span / np.linalg.norm(span)
        s = np.asarray(positions, dtype=np.float64)
        px, py = c[0] + s * u[0], c[1] + s * u[1]
        dx, dy = self.deviation(px, py)
        dx0, dy0 = self.deviation(c[0], c[1])
        return (dx - dx0) * u[0] + (dy - dy0) * u[1]


def squareness_of_lines(diagonal_squareness: float, straightness_x_in_y: Curve,
                        straightness_y_in_x: Curve, x_range, y_range) -> float:
    """The squareness of the least-squares lines from that of the diagonals, rad.

    The two-diagonal formula measures the angle between the chords joining the rectangle's
    corners. With the map of the module docstring, opposite minus same diagonal deviation is
    ``(2 a b e - 2 a dSx - 2 b dSy) / d`` (``dSx = Sx(y1) - Sx(y0)``, ``dSy = Sy(x1) -
    Sy(x0)``), so ``e = e_diagonals + dSx / b + dSy / a``. Eq 2 from one diagonal of spans
    (a, b) reads the same chords: its deviation is ``(a (dPx + dSx - e b) + b (dPy + dSy))
    / d`` and the axes' travels carry ``dPx``, ``dPy``, so ``e_eq2 = e - dSx / b - dSy / a``
    too.
    """
    x0, x1 = _range(x_range, "x_range")
    y0, y1 = _range(y_range, "y_range")
    d_sx = float(straightness_y_in_x(y1) - straightness_y_in_x(y0))
    d_sy = float(straightness_x_in_y(x1) - straightness_x_in_y(x0))
    return float(diagonal_squareness) + d_sx / (y1 - y0) + d_sy / (x1 - x0)


@dataclass(frozen=True, eq=False)
class DiagonalReading:
    """A diagonal test's mean deviations (m) at distances ``positions`` from ``corner``
    towards ``opposite`` (X, Y in m), read at the frame ``frame`` with Z at ``z``."""

    corner: tuple
    opposite: tuple
    positions: np.ndarray
    deviation: np.ndarray
    frame: str = "tool_tip"
    z: float = 0.0


def fit_parameters(knots) -> list[str]:
    """The parameter names `fit_xy_plane` identifies: the positioning and straightness
    tables of X and Y at ``knots`` (all but the knot at 0, where every reading is zeroed,
    and EXY at the last knot, the datum between Y's straightness and the squareness) and
    the squareness ``location.Y.EC0Y``."""
    k = _knots(knots)
    inner = [i for i, v in enumerate(k) if v != 0.0]
    names = [f"component.{axis}.{symbol}[{i}]"
             for axis, symbols in (("X", ("EXX", "EYX")), ("Y", ("EYY",)))
             for symbol in symbols for i in inner]
    # EXY's straight part and EC0Y move every reading alike (both an X deviation
    # proportional to Y): the datum keeps EXY at the last knot at zero, so EC0Y is the
    # squareness of the chord of Y's straightness from 0 to the last knot.
    names += [f"component.Y.EXY[{i}]" for i in inner[:-1]]
    return names + ["location.Y.EC0Y"]


def plane_observations(curves, diagonals, sigma: float, n_axes: int, knots) -> Observations:
    """The 1-D readings and the diagonals as `fit` observations.

    ``curves`` are ``(position_x, position_y, straightness_x_in_y, straightness_y_in_x)``;
    the straightness curves are read against the table's axes (the optic aligned to the
    nominal axis, no reference line removed: a least-squares line removed would hide the
    slopes the diagonals see). Every curve is taken at ``knots`` and zeroed at position 0
    (the table's centre, where the fitted tables are fixed at zero); the diagonals are
    zeroed at their midpoint, the table's centre.
    """
    k = _knots(knots)
    rows_q, rows_u, values, frames = [], [], [], []

    def add(x, y, z, u, value, frame="tool_tip"):
        q = np.zeros((np.size(x), n_axes))
        q[:, 0], q[:, 1], q[:, 2] = x, y, z
        rows_q.append(q)
        rows_u.append(np.tile(u, (q.shape[0], 1)))
        values.append(np.asarray(value, dtype=np.float64))
        frames.extend([frame] * q.shape[0])

    zero = np.zeros_like(k)
    ex, ey = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    for curve, along_x, u in zip(curves, (True, False, True, False), (ex, ey, ey, ex),
                                 strict=True):
        value = curve(k) - curve(0.0)
        add(k if along_x else zero, zero if along_x else k, 0.0, u, value)
    for d in diagonals:
        c = np.asarray(d.corner, dtype=np.float64)
        span = np.asarray(d.opposite, dtype=np.float64) - c
        u = span / np.linalg.norm(span)
        s = np.asarray(d.positions, dtype=np.float64)
        mid = float(np.interp(0.5 * np.linalg.norm(span), s, d.deviation))
        points = c + s[:, None] * u
        add(points[:, 0], points[:, 1], d.z, np.append(u, 0.0), d.deviation - mid, d.frame)
    q = np.concatenate(rows_q)
    return observations(q, directions=np.concatenate(rows_u),
                        values=np.concatenate(values), sigma=sigma, frame=frames)


def fit_xy_plane(machine, curves, diagonals, knots, *, sigma: float = 2e-9) -> Estimate:
    """Eq 1's parameters identified by `machinesim.identification.fit` from the readings.

    The prior holds zero tables of EXX, EYX (X) and EYY, EXY (Y) at ``knots`` and a zero
    squareness; `fit_parameters` lists what is fitted. The result's ``errors`` is an
    `ErrorModel` for the model-based compensation.
    """
    k = _knots(knots)
    table = {"position_mm": (k * 1e3).tolist()}
    zeros = [0.0] * k.size
    prior = ErrorModel.from_dict({
        "location": {"Y": {"EC0Y_urad": 0.0}},
        "component": {"X": {**table, "EXX_um": zeros, "EYX_um": zeros},
                      "Y": {**table, "EYY_um": zeros, "EXY_um": zeros}}})
    obs = plane_observations(curves, diagonals, sigma, len(machine.axes), k)
    return fit(machine, obs, fit_parameters(k), prior=prior)


def _with_knots(points: np.ndarray, curves, start: float, end: float) -> np.ndarray:
    """``points`` and the curves' knots within [start, end], sorted, each once."""
    knots = np.concatenate([c.positions for c in curves])
    return np.union1d(points, knots[(knots >= start) & (knots <= end)])


def _knots(knots) -> np.ndarray:
    k = np.array(knots, dtype=np.float64)
    if k.ndim != 1 or k.size < 2 or np.any(np.diff(k) <= 0) or not np.isfinite(k).all():
        raise InputError(f"Expected increasing knot positions (m), got {knots!r}",
                         key="knots")
    if not np.any(k == 0.0):
        raise InputError("Expected the knots to include 0 (the zero of every reading)",
                         key="knots")
    return k


def _range(value, name: str) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected {name} as (start, end) in m, got {value!r}",
                         key=name) from error
    if not (np.isfinite(a) and np.isfinite(b) and b > a):
        raise InputError(f"Expected {name} with start < end, got {value!r}", key=name)
    return a, b
