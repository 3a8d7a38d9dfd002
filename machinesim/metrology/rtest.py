"""R-test (ISO 10791-6): a precision ball on the tool side, three displacement sensors in a
nest on the workpiece side, read as the machine moves its axes.

The nest stands on the table where a workpiece would (its placement on the table is the
lab's workpiece setting error: an R-test session has no other workpiece). Two zeros
(``zero=``): ``"first"``, as a real nest is zeroed, on the real ball at the plan's first
pose, so each reading is the change of the ball centre's displacement since that pose and a
constant offset (a tool offset the rotary axes do not turn, the nest's own placement) does
not show; and ``"nominal"`` (the default), an idealisation, as if a perfect ball sat at its
nominal place, so each reading is the displacement of the ball centre from where the nominal
machine would put it and such offsets read in full. Readings are relative to the nest,
along the three sensor directions (here the workpiece frame's X, Y, Z); with ``"first"``
`RTestReading.zero_at` holds the pose, and `machinesim.identification.from_r_test` carries
it into the fit (`Observation.zero_at`). This is what a lab uses to identify a
five-axis machine's location errors (ISO 230-7) and what Heidenhain's KinematicsOpt cycle
reads with a touch probe on a calibration sphere: the machine's actual motion, never its
error model.

The ball's centre is a point fixed in a machine frame (``tool_tip`` by default, or given
coordinates in it: a ball on a stylus of known length). Its actual place comes from the
machine's motion (`machinesim.metrology.instruments.motion_of`); its nominal place from the
nominal kinematics, as the controller knows it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.arrays import frozen
from machinesim.exceptions import AxisLimitError, InputError
from machinesim.metrology._arrays import as_floats, shown
from machinesim.metrology.instruments import Readout, as_generator, as_machine, motion_of
from machinesim.units import M_PER_MM, length_text

__all__ = ["BALL_REACH_FLOOR", "RTest", "RTestReading", "ZEROS", "ball_reach",
           "refuse_far_points"]

#: Where the R-test's sensors read zero (`RTest`).
ZEROS = ("nominal", "first")


#: Most poses one R-test reads: a plan reads tens to hundreds; each pose costs a few
#: hundred bytes on the way (two poses, the readout), as the laser interferometer's
#: positions do (`interferometer.MOST_POSITIONS`).
MOST_POSES = 1_000_000


@dataclass(frozen=True, eq=False)
class RTestReading:
    """Ball-centre displacements read at a set of axis values.

    Attributes
    ----------
    q : ndarray, shape (N, n_axes), read-only
        The commanded axis values, m and rad.
    displacement : ndarray, shape (N, 3), read-only
        Actual minus nominal ball centre, workpiece frame X, Y, Z, m, as displayed (noise and
        rounding).
    sigma : float
        Standard uncertainty of each displacement reading as the instrument states it, m
        (its noise and rounding together; stated even when the lab's noise is off, as a
        data sheet states it, so that a fit can weight the readings). Zeroed readings
        (``zero="first"``) are differences of two displays, n_i - n_0, so sqrt(2) times a
        display's: the n_0 part is common to all readings of one `RTest.read` (correlation
        1/2 between any two), and the first row, the zero itself, reads exactly 0.
    frame : str
    point : ndarray, shape (3,), read-only
        The ball centre in ``frame``, m.
    zero_at : ndarray, shape (n_axes,), read-only, or None
        The pose where the sensors were set to zero (``zero="first"``: the first row of
        ``q``), or None for readings against the nominal place.
    machine : str or None
        The name of the machine the readings were taken on, None when not known (a reading
        pickled before it was recorded): `machinesim.identification.fit` refuses to fit
        them on another machine.
    axes : tuple of str or None
        That machine's axis letters, the columns of ``q`` (None when not known).
    """

    q: np.ndarray
    displacement: np.ndarray
    sigma: float
    frame: str
    point: np.ndarray
    zero_at: np.ndarray | None = None
    machine: str | None = None
    axes: tuple[str, ...] | None = None

    def __repr__(self) -> str:
        ball = ", ".join(f"{v * 1e3:.6g}" for v in self.point)
        zero = "against the nominal place" if self.zero_at is None else "zeroed at q[0]"
        d = self.displacement * 1e6
        spans = ", ".join(f"{a} {d[:, i].min():.6g} .. {d[:, i].max():.6g}"
                          for i, a in enumerate("XYZ")) if len(d) else "none"
        return (f"RTestReading({len(self.q)} poses of {self.q.shape[1]} axes, ball at ({ball}) "
                f"mm in {self.frame}, {zero}: displacement {spans} um, sigma "
                f"{self.sigma:.3g} m)")


#: The least `ball_reach`, m: 200 mm, beyond the styli and tool-holder extensions that carry
#: an R-test's ball (tens of mm, a long one 100-150 mm), whatever the machine's linear travel.
#: A machine with one short linear axis or none (a rotary table on a 10 mm Z stroke) had a
#: reach of its stroke alone, or 0, and refused a ball 40 mm from the nose; a ball given in
#: mm as m still lies beyond it from 0.2 mm on.
BALL_REACH_FLOOR = 0.2


def ball_reach(machine) -> float:
    """Farthest the R-test's ball centre may sit from its frame's origin, m: the diagonal of
    the machine's linear travel (0.343 m on robonano_a0ib: 280 x 150 x 130 mm), at least
    `BALL_REACH_FLOOR` (a machine with a short linear travel or none).

    A real R-test's ball sits on a stylus tens of mm from the spindle nose; one set farther
    from the tool than the machine's whole travel could not be brought over a nest on its table as
    the axes move, so such a ``point`` is a unit slip (``[0, 0, 25]``, mm meant, is 25 m),
    whose lever would multiply every angular error into the readings."""
    linear = ~np.asarray(machine.rotary, dtype=bool)
    diagonal = float(np.linalg.norm((machine.upper - machine.lower)[linear]))
    return max(diagonal, BALL_REACH_FLOOR)


def refuse_far_points(machine, points, frames, *, key: str, what: str) -> None:
    """Refuse a point fixed in a machine frame farther than `ball_reach` from its origin: a
    point on the tool or a probe (an R-test's ball, a kept tool point) given in mm as m.

    ``points`` (N, 3), m, each in its frame of ``frames`` (one name, or one per point);
    ``what`` says what they are in the message (``"a point on the tool or a probe"``). The
    first such point is named, with its index when there are several, its distance and the
    reach; an InputError of ``key``."""
    points = np.atleast_2d(np.asarray(points, dtype=np.float64))
    lever = np.linalg.norm(points, axis=1)
    reach = ball_reach(machine)
    far = np.flatnonzero(lever > reach)
    if not far.size:
        return
    k = int(far[0])
    frame = frames if isinstance(frames, str) else frames[k]
    which = f"reading {k}: " if len(points) > 1 else ""
    raise InputError(f"{which}expected the point at most {reach / M_PER_MM:.6g} mm from "
                     f"{frame}'s origin ({_reach_text(machine, reach)}: {what} sits tens of "
                     f"mm from it; the point is in m, not mm), got "
                     f"{shown(points[k].tolist())}, {length_text(float(lever[k]))} from it",
                     key=key)


def _reach_text(machine, reach: float) -> str:
    """What `ball_reach` is on ``machine``, for the refusal."""
    if reach > BALL_REACH_FLOOR:
        return f"the diagonal of {machine.name}'s linear travel"
    return f"BALL_REACH_FLOOR, {machine.name}'s linear travel being shorter"


class RTest:
    """An R-test device on a machine.

    Parameters
    ----------
    machine : Machine or str
        The machine, or the name of a shipped one (`machinesim.load_machine`).
    errors : ErrorModel or None
        The machine's injected errors; only its motion reads them (`Lab.r_test` builds one
        without handing them out).
    sigma : float
        Noise of each sensor reading, m. Default 50 nm: contact displacement sensors (LVDT
        class) of R-test devices repeat to some tens of nm over the sub-mm ranges they read.
    resolution : float
        Display step, m. Default 1 nm.
    noise : bool
        False turns the noise off exactly; rounding stays.
    rng : numpy.random.Generator or int or None
    frame : str
        The machine frame carrying the ball. Default ``"tool_tip"``.
    point : array-like, shape (3,)
        The ball centre in ``frame``, m. Default the frame's origin. At most `ball_reach`
        (the diagonal of the machine's linear travel, at least `BALL_REACH_FLOOR`, 200 mm)
        from it: farther is refused as a unit slip (mm given as m).
    zero : {"nominal", "first"}
        Where the sensors read zero (module docstring): at the ball's nominal place
        (default, an idealisation), or on the real ball at the first pose of each `read`,
        as a real nest is zeroed (each reading then carries that zero's noise too: its
        stated sigma is sqrt(2) times a display's, `RTestReading.sigma`).
    """

    def __init__(self, machine, errors=None, sigma: float = 50e-9, resolution: float = 1e-9,
                 *, noise: bool = True, rng=None, frame: str = "tool_tip",
                 point=(0.0, 0.0, 0.0), zero: str = "nominal") -> None:
        if zero not in ZEROS:
            raise InputError(f"Expected zero as one of {', '.join(ZEROS)}, got {shown(zero)}",
                             key="zero")
        self.zero = zero
        self.machine = machine = as_machine(machine)
        self._pose = motion_of(machine, errors, frame)
        self.frame = frame
        point = as_floats(point, "point", "3 coordinates (m) of the ball centre")
        if point.shape != (3,) or not np.isfinite(point).all():
            raise InputError(f"Expected the ball centre as 3 finite coordinates (m), got "
                             f"{shown(point)}", key="point")
        lever, reach = float(np.linalg.norm(point)), ball_reach(machine)
        if lever > reach:
            raise InputError(f"Expected the ball centre at most {reach / M_PER_MM:.6g} mm from "
                             f"{frame}'s origin ({_reach_text(machine, reach)}: an R-test's "
                             "ball sits tens of mm from the spindle nose; "
                             "point is in m, not mm), got "
                             f"{shown(point.tolist())}, {length_text(lever)} from it",
                             key="point")
        self.point = frozen(point)
        self.readout = Readout.of(sigma, resolution, noise)
        self.uncertainty = Readout(sigma, resolution).std
        self._rng = as_generator(rng)

    def __repr__(self) -> str:
        return (f"RTest({self.machine.name}, frame={self.frame!r}, sigma="
                f"{self.readout.sigma:g} m, resolution={self.readout.resolution:g} m, "
                f"zero={self.zero!r})")

    def read(self, q) -> RTestReading:
        """Read the ball's displacement at each row of ``q`` (N, n_axes), m and rad."""
        n = len(self.machine.axes)
        q = as_floats(q, "q", "axis values (m, rad)")
        if q.size > MOST_POSES * n:
            raise InputError(f"Expected at most {MOST_POSES:,} poses in one R-test, got "
                             f"{q.size // n:,} (a plan reads tens to hundreds)", key="q")
        if q.ndim == 1:
            q = q[None]
        if q.ndim != 2 or q.shape[1] != n or not len(q) or not np.isfinite(q).all():
            raise InputError(f"Expected finite axis values of shape (N, {n}) (axes "
                             f"{''.join(self.machine.axes)}), got {q.shape}", key="q")
        bad = self.machine.limit_violations(q)
        if bad:
            raise AxisLimitError(f"{self.machine.name}: the R-test plan needs "
                                 + "; ".join(bad) + " (axis values in m and rad, in the order "
                                 f"{''.join(self.machine.axes)}: a rotary axis given in degrees "
                                 "is the usual cause)")
        actual = self._centre(self._pose(self.frame, q))
        nominal = self._centre(self.machine.frame_pose(self.frame, q))
        displayed = self.readout.read(actual - nominal, self._rng)
        taken_on = {"machine": self.machine.name, "axes": tuple(self.machine.axes)}
        if self.zero == "nominal":
            return RTestReading(frozen(q), frozen(displayed), self.uncertainty, self.frame,
                                self.point, **taken_on)
        # zeroed on the ball at the first pose: every display less the one there (both
        # counts of the same sensors, so the difference keeps the display's step)
        return RTestReading(frozen(q), frozen(displayed - displayed[0]),
                            math.sqrt(2.0) * self.uncertainty, self.frame, self.point,
                            frozen(q[0].copy()), **taken_on)

    def _centre(self, wMf: np.ndarray) -> np.ndarray:
        return wMf[:, :3, 3] + wMf[:, :3, :3] @ self.point
