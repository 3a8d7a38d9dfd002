"""Laser interferometer: positioning, straightness and diagonal tests of the linear axes.

The interferometer of paper 003 reads the machine's actual motion: the displacement of the
tool point relative to the workpiece side, between two sets of axis values
(`Machine.frame_pose` with the injected errors, never the errors themselves). Its optics ride
on the table (paper 003 Fig. 3: the reflector on the corner of the table), so displacements
are read along the axes of the ``table`` frame: the machine axes when the table's rotary
axis stands at zero (the default base position). The workpiece setting error (the part on
the chuck) therefore does not enter, as it would not on a real machine.

Readings are zeroed at a reference position, as a laser interferometer is, then noise is
added and the displayed displacement rounded to the resolution.

Beam alignment (off by default; `machinesim.Lab` draws one per interferometer when
`machinesim.realism.Realism` turns ``registration`` on). A beam set up along the unit
direction ``u`` of a test runs along ``u + a e1 + b e2`` (normalised), ``e1``, ``e2`` a
right-handed pair across ``u`` (``e1`` along ``u x Z``, or ``u x X`` for a beam along Z),
``(a, b)`` the two misalignment angles (rad). The reading is the motion's projection on the
actual beam: a positioning test of travel L then reads ``L cos(theta)``, the cosine error
of ``L theta**2 / 2`` (``theta = hypot(a, b)`` to second order), plus the straightness seen
through the beam's slant.

Diagonal test and squareness (ISO 230-6, paper 003 eq 2). With a squareness error ``e`` of Y
to X (``EC0Y``: the Y motion runs along (-sin e, cos e) in the XY plane; docs/machines.md),
commanding X and Y by ``(a, b)`` moves the tool by ``(a - b sin e, b cos e)``, of length
``P_d`` with ``P_d**2 = a**2 + b**2 - 2 a b sin e``: the law of cosines with the angle
90 deg + e between the axes, which is paper 003 eq 2 with ``P_x = a``, ``P_y = b``. To first
order ``P_d - d = -a b e / d`` (``d = sqrt(a**2 + b**2)``): a positive EC0Y shortens the
diagonal whose X and Y spans have the same sign and lengthens the other. The interferometer
reads the projection of the motion on the nominal diagonal,
``(a**2 - a b sin e + b**2 cos e) / d``, which differs from ``P_d`` only at second order in e.
`squareness_from_diagonal` inverts eq 2.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import AxisLimitError, InputError
from machinesim.metrology._arrays import as_floats, as_number, shown
from machinesim.metrology.instruments import Readout, as_generator, as_machine, motion_of

__all__ = ["InterferometerReading", "LaserInterferometer", "squareness_from_diagonal"]

_REFERENCES = ("least_squares", "end_points", "none")
#: Largest beam misalignment angle (each of ``alignment``'s two), rad: 10 mrad, 100 times
#: the lab's 0.1 mrad (the return beam centred to ~0.03 mm over 300 mm). At 10 mrad the
#: return beam walks 3 mm over a 300 mm travel, half of a ~6 mm beam (assumed, the usual
#: diameter of a heterodyne laser head's beam), so the fringe signal fades; the cosine error
#: is then already 5e-5 of the travel. A mrad given as rad lies above it: alignment=(0.1, 0),
#: 0.1 mrad meant, had read every travel 0.5 % short (a cosine error of 5 mm per metre),
#: as ``scale`` is bounded at 1e-3 for the same slip.
ALIGNMENT_LIMIT = 1e-2


@dataclass(frozen=True, eq=False)
class InterferometerReading:
    """Deviations of a linear motion from its command, at a series of positions.

    Attributes
    ----------
    positions : ndarray, shape (N,), float64, read-only
        Commanded positions along the tested motion, m (axis values, or distances from the
        corner along a diagonal).
    deviation : ndarray, shape (N,), float64, read-only
        Measured minus commanded displacement (positioning, diagonal), or measured lateral
        displacement (straightness), m.
    """

    positions: np.ndarray
    deviation: np.ndarray


class LaserInterferometer:
    """A laser interferometer set up on a machine.

    Parameters
    ----------
    machine : Machine or str
        The machine under test, or the name of a shipped one (`machinesim.load_machine`).
    errors : ErrorModel or None
        Its injected errors: only the machine's kinematics reads them; the interferometer
        keeps no attribute that returns them.
    sigma : float
        Noise of each displacement reading, m. Default 2 nm: the 1 nm resolution class of a
        heterodyne laser system (Renishaw XL-80 / Keysight class) in a temperature-controlled
        room over the short beam paths of an ultraprecision machine, where air turbulence and
        vibration leave a few nm of reading scatter.
    resolution : float
        Rounding of the displayed displacement, m. Default 1 nm.
    noise : bool
        False turns the noise off exactly (``sigma`` ignored); rounding stays (resolution 0
        turns it off).
    rng : numpy.random.Generator or int or None
        Noise source, or its seed.
    frame : str
        The machine frame whose motion is read (where the optic on the tool side sits).
        Default ``"tool_tip"``: the functional point, free of Abbe offsets to the cut.
    alignment : array-like, shape (2,), optional
        The beam's misalignment angles (a, b), rad (module docstring); default none. The
        lab's: 0.1 mrad scatter per angle (`machinesim.realism.PROBE`, assumed). Each at
        most `ALIGNMENT_LIMIT` (10 mrad) in size: more is a unit slip (mrad given as rad).
    scale : float
        Relative error of the scale displacements along the beam are read on (positioning
        and diagonal tests): the part of the air's refractive index the instrument's air
        compensation misses, ``(1 + scale)`` times the displacement; default 0. The lab's:
        0.5 ppm scatter per set-up (`machinesim.realism.PROBE`, its sources there).
    """

    def __init__(self, machine, errors=None, sigma: float = 2e-9, resolution: float = 1e-9,
                 *, noise: bool = True, rng=None, frame: str = "tool_tip",
                 alignment=None, scale: float = 0.0) -> None:
        self.machine = machine = as_machine(machine)
        self._pose = motion_of(machine, errors, frame)
        self.frame = frame
        self.readout = Readout.of(sigma, resolution, noise)
        self._rng = as_generator(rng)
        self._alignment = None if alignment is None else _vector(alignment, 2, "alignment")
        if self._alignment is not None and np.abs(self._alignment).max() > ALIGNMENT_LIMIT:
            raise InputError(f"Expected alignment angles within {ALIGNMENT_LIMIT:g} rad in size "
                             "(ALIGNMENT_LIMIT: beyond it the return beam misses the "
                             "detector; the angles are in rad, not mrad), got "
                             f"{self._alignment.tolist()}", key="alignment")
        self._scale = as_number(scale, "scale", unit="relative")
        if not abs(self._scale) < 1e-3:
            raise InputError(f"Expected a scale error below 1e-3 (1000 ppm) in size, got "
                             f"{scale!r}", key="scale")

    def __repr__(self) -> str:
        return (f"LaserInterferometer({self.machine.name}, frame={self.frame!r}, "
                f"sigma={self.readout.sigma:g} m, resolution={self.readout.resolution:g} m)")

    def positioning(self, axis: str, positions, base=None,
                    reference: float | None = None) -> InterferometerReading:
        """Positioning error of a linear axis (ISO 230-2): measured minus commanded travel.

        Parameters
        ----------
        axis : str
            A linear axis letter, e.g. ``"X"``.
        positions : array-like, shape (N,)
            Target positions of the axis, m.
        base : array-like, shape (n_axes,), optional
            Values of all axes (the tested one is replaced), m and rad; default zeros.
        reference : float, optional
            Axis position at which the reading is zeroed, m; default ``positions[0]``.

        Returns
        -------
        InterferometerReading
            ``deviation[i]`` = displacement along the axis from ``reference`` to
            ``positions[i]``, read, minus ``positions[i] - reference``.
        """
        k = self._linear(axis, "axis")
        x = _positions(positions)
        x_ref = x[0] if reference is None else as_number(reference, "reference")
        q = self._commands(self._base(base), {axis: np.append(x, x_ref)})
        displacement = self._displacement(q, _unit(k)) * (1.0 + self._scale)
        return _reading(x, self.readout.read(displacement, self._rng) - (x - x_ref))

    def straightness(self, axis: str, positions, direction: str, base=None,
                     reference: str = "least_squares") -> InterferometerReading:
        """Straightness of a linear axis: its lateral displacement along another direction.

        Parameters
        ----------
        axis : str
            The moving linear axis, e.g. ``"X"``.
        positions : array-like, shape (N,)
            Axis positions, m (at least 2; 3 for a meaningful least-squares line).
        direction : str
            The machine direction of the lateral reading, ``"X"``, ``"Y"`` or ``"Z"``,
            different from the axis's own.
        base : array-like, shape (n_axes,), optional
            Values of all axes (the tested one is replaced); default zeros.
        reference : {"least_squares", "end_points", "none"}
            The reference straight line removed from the reading (ISO 230-1): the
            least-squares line (default, ISO 230-1's reference straight line), the line
            through the first and last readings (their positions apart: a run there and
            back is refused), or none. A real straightness optic is
            aligned only up to a slope, so only the first two are measurable in practice;
            ``"none"`` gives the virtual optic's reading aligned exactly to the nominal axis
            (zeroed at the first position), slope included (squareness, misalignment).

        Returns
        -------
        InterferometerReading
            ``deviation[i]``: lateral displacement at ``positions[i]`` minus the reference
            line, m.
        """
        k = self._linear(axis, "axis")
        lateral = _direction_index(direction)
        if lateral == k:
            raise InputError(f"Expected a straightness direction across axis {axis} "
                             f"(not {direction!r}, its own direction)", key="direction")
        if reference not in _REFERENCES:
            raise InputError(f"Expected reference in {_REFERENCES}, got {reference!r}",
                             key="reference")
        x = _positions(positions, least=2)
        if reference == "end_points" and x[-1] == x[0]:
            # no line through two readings at one position: its slope was 0 / 0 (NaN)
            raise InputError(f"Expected the first and last positions apart for the end-point "
                             f"reference line, got both {x[0]!r} m (a run there and back): "
                             "read each direction on its own, or take "
                             "reference='least_squares'", key="positions")
        q = self._commands(self._base(base), {axis: np.append(x, x[0])})
        raw = self.readout.read(self._displacement(q, _unit(lateral)), self._rng)
        return _reading(x, _remove_line(x, raw, reference))

    def diagonal(self, positions, corner, opposite, axes: Sequence[str] = ("X", "Y"),
                 base=None) -> InterferometerReading:
        """Diagonal displacement test (ISO 230-6): axes moved together along a diagonal.

        Parameters
        ----------
        positions : array-like, shape (N,)
            Distances from ``corner`` along the diagonal, m, in [0, diagonal length].
        corner, opposite : array-like, shape (len(axes),)
            Axis values at the two ends of the diagonal, m (corners of the tested rectangle,
            or of the box for a body diagonal).
        axes : sequence of str
            The linear axes moved together; default the XY face diagonal.
        base : array-like, shape (n_axes,), optional
            Values of all axes (the moved ones are replaced); default zeros.

        Returns
        -------
        InterferometerReading
            ``deviation[i]``: displacement along the nominal diagonal from the corner, read,
            minus ``positions[i]``. For a squareness error alone see the module docstring
            (about ``-a b e / d`` at the far corner of an XY diagonal with spans a, b).
        """
        axes = tuple(axes)
        if len(set(axes)) != len(axes) or len(axes) < 2:
            raise InputError(f"Expected two or three different linear axes, got {axes!r}",
                             key="axes")
        dirs = [self._linear(a, "axes") for a in axes]
        start = _vector(corner, len(axes), "corner")
        span = _vector(opposite, len(axes), "opposite") - start
        length = float(np.linalg.norm(span))
        if length == 0.0:
            raise InputError("Expected a diagonal of non-zero length, got corner = opposite",
                             key="opposite")
        s = _positions(positions)
        if s.min() < 0.0 or s.max() > length * (1.0 + 1e-12):
            raise InputError(f"Expected positions in [0, {length}] m along the diagonal, got "
                             f"[{s.min()}, {s.max()}]", key="positions")
        along = np.append(s, 0.0)[:, None] * (span / length) + start
        q = self._commands(self._base(base), {a: along[:, i] for i, a in enumerate(axes)})
        u = sum(span[i] * _unit(d) for i, d in enumerate(dirs)) / length
        displacement = self._displacement(q, u) * (1.0 + self._scale)
        return _reading(s, self.readout.read(displacement, self._rng) - s)

    # ---------------------------------------------------------------------------- internals

    def _linear(self, letter, key: str) -> int:
        """Machine direction (0, 1, 2) of a linear axis on this machine."""
        if not isinstance(letter, str) or letter not in self.machine.axes:
            raise InputError(f"Expected an axis of {self.machine.name} "
                             f"({''.join(self.machine.axes)}), got {letter!r}", key=key)
        axis = self.machine.axis(letter)
        if axis.rotary:
            raise InputError(f"Expected a linear axis, got the rotary axis {letter}", key=key)
        return axis.direction

    def _base(self, base) -> np.ndarray:
        n = len(self.machine.axes)
        return np.zeros(n) if base is None else _vector(base, n, "base")

    def _commands(self, base: np.ndarray, moves: dict) -> np.ndarray:
        """Axis values (N, n_axes): ``base`` with the named axes set to the given columns."""
        count = len(next(iter(moves.values())))
        q = np.tile(base, (count, 1))
        for letter, values in moves.items():
            q[:, self.machine.axes.index(letter)] = values
        bad = self.machine.limit_violations(q)
        if bad:
            raise AxisLimitError(f"{self.machine.name}: the test needs " + "; ".join(bad))
        return q

    def _displacement(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Displacement along u (table frame) from the last row of q to each other row, m."""
        wMf = self._pose(self.frame, q)
        wMt = self._pose("table", q)
        # The frame's position in the table frame: R^T (p_frame - p_table).
        p = np.einsum("nji,nj->ni", wMt[:, :3, :3], wMf[:, :3, 3] - wMt[:, :3, 3])
        return (p[:-1] - p[-1]) @ self._beam(u)

    def _beam(self, u: np.ndarray) -> np.ndarray:
        """The beam's actual direction for a test along u (module docstring)."""
        if self._alignment is None:
            return u
        e1 = np.cross(u, [0.0, 0.0, 1.0])
        if np.linalg.norm(e1) < 0.5:
            e1 = np.cross(u, [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(u, e1)
        beam = u + self._alignment[0] * e1 + self._alignment[1] * e2
        return beam / np.linalg.norm(beam)


def squareness_from_diagonal(measured_length: float, x_span: float, y_span: float) -> float:
    """Squareness ``e`` (EC0Y convention) from a diagonal's measured length (paper 003 eq 2).

    Eq 2 gives the angle between the axes, ``theta = acos((P_d**2 - P_x**2 - P_y**2) /
    (2 P_x P_y))``; here ``theta = 90 deg + e`` with signed spans, so
    ``sin e = (a**2 + b**2 - P_d**2) / (2 a b)`` (module docstring).

    Parameters
    ----------
    measured_length : float
        Measured length of the diagonal (commanded length plus the test's deviation at the
        far corner), m.
    x_span, y_span : float
        Signed commanded spans of X and Y along the diagonal (``opposite - corner``), m,
        each non-zero; taken as the true axis travels (P_x, P_y of eq 2, i.e. after the
        positioning errors are compensated or measured).

    Returns
    -------
    float
        The squareness error of Y to X, rad (positive: Y tilted towards -X).
    """
    a, b, pd = (as_number(v, n) for v, n in ((x_span, "x_span"), (y_span, "y_span"),
                                           (measured_length, "measured_length")))
    if a == 0.0 or b == 0.0:
        raise InputError(f"Expected non-zero spans, got x_span={a}, y_span={b}", key="x_span")
    sine = (a * a + b * b - pd * pd) / (2.0 * a * b)
    if abs(sine) > 1.0:
        raise InputError(f"Expected a diagonal length possible for spans {a} and {b} m "
                         f"(between {abs(abs(a) - abs(b))} and {abs(a) + abs(b)} m), got {pd}",
                         key="measured_length")
    return float(np.arcsin(sine))


def _remove_line(x: np.ndarray, y: np.ndarray, reference: str) -> np.ndarray:
    if reference == "none":
        return y
    if reference == "end_points":
        slope = (y[-1] - y[0]) / (x[-1] - x[0])
        return y - (y[0] + slope * (x - x[0]))
    centre = x.mean()
    slope = np.dot(x - centre, y - y.mean()) / np.dot(x - centre, x - centre)
    return y - (y.mean() + slope * (x - centre))


def _unit(k: int) -> np.ndarray:
    u = np.zeros(3)
    u[k] = 1.0
    return u


def _direction_index(direction) -> int:
    if not isinstance(direction, str):
        # an array here (the positions, given before the direction) made `in` raise numpy's
        # "truth value of an array ... is ambiguous" ValueError, with a traceback
        raise InputError(f"Expected a machine direction 'X', 'Y' or 'Z', got a "
                         f"{type(direction).__name__} (straightness takes the axis, its "
                         "positions, then the direction: straightness('X', positions, 'Y'))",
                         key="direction")
    if direction not in ("X", "Y", "Z"):
        raise InputError(f"Expected a machine direction 'X', 'Y' or 'Z', got {direction!r}",
                         key="direction")
    return "XYZ".index(direction)


def _vector(value, length: int, name: str) -> np.ndarray:
    array = as_floats(value, name, f"{length} numbers")
    if array.shape != (length,) or not np.isfinite(array).all():
        raise InputError(f"Expected {name} as {length} finite numbers, got {shown(value)}",
                         key=name)
    return array


#: Most target positions one test takes: an ISO 230-2 run has tens; each position costs
#: about 370 bytes on the way (poses, the beam), so 1e7 took 3.7 GB and 1e8 ran out of memory.
MOST_POSITIONS = 1_000_000


def _positions(values, least: int = 1) -> np.ndarray:
    x = as_floats(values, "positions")
    if x.size > MOST_POSITIONS:
        raise InputError(f"Expected at most {MOST_POSITIONS:,} positions in one test, got "
                         f"{x.size:,} (ISO 230-2 reads tens; a test of more would take about "
                         f"{x.size * 370 / 1e9:.3g} GB)", key="positions")
    if x.ndim != 1 or x.size < least or not np.isfinite(x).all():
        raise InputError(f"Expected at least {least} finite positions of shape (N,), got "
                         f"{shown(values)}", key="positions")
    if least >= 2 and np.ptp(x) == 0.0:
        raise InputError("Expected positions that span a distance, got all equal",
                         key="positions")
    return x


def _reading(positions: np.ndarray, deviation: np.ndarray) -> InterferometerReading:
    positions = positions.copy()
    for array in (positions, deviation):
        array.setflags(write=False)
    return InterferometerReading(positions, deviation)
