"""The Archimedean spiral of a slow-tool-servo path and the cutting points on it (paper 004,
section 3.1, eqs 3-6): step 2 of `machinesim.cam.spiral`'s CAM pipeline.

`Spiral` winds from the outer radius r to the centre at the pitch f (the feed per
revolution), rho(theta) = r - f theta / (2 pi); the cutting points lie on it by Constant
Angle or Constant Arc Length (`constant_angle`, `constant_arc_length`, `cutting_angles`),
each with the designed height and its radial slope (`cutting_points`). A path is held to
`MAX_PATH_POINTS`. The tool path through these points, its interpolation, the form error
that leaves and the NC program are `machinesim.cam.spiral`, which imports these names as
before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from machinesim.arrays import frozen
from machinesim.cam.designs import Design
from machinesim.exceptions import InputError, brief, check_length
from machinesim.metrology._arrays import as_floats

__all__ = ["MAX_PATH_POINTS", "CuttingPoints", "Spiral", "constant_angle",
           "constant_arc_length", "cutting_angles", "cutting_points"]

#: Most points a path may have (cutting points, or samples of an interpolated path): 10^7
#: take 13 s for points, tool path and program, 10^8 about 2 min and 0.8 GB an array. A
#: step in the wrong unit (1e-12 rad for CA, 1.6e15 points) asked numpy for petabytes, and
#: 10^9 sub-steps a step filled memory for minutes.
MAX_PATH_POINTS = 10**8
#: Newton steps that invert eq 3 (arc length -> angle); it converges monotonically from the
#: start used, quadratically at the end: 6-8 steps reach round-off, the rest is a margin.
_NEWTON_STEPS = 40


# --- the spiral (eqs 3-6) --------------------------------------------------------------------
@dataclass(frozen=True)
class Spiral:
    """Archimedean spiral from the outer radius to the centre, pitch = feed per revolution.

    Eqs 4-6: rho(theta) = r - f_r theta, f_r = f / (2 pi), N_t = r / f turns; theta runs
    from 0 (outer radius, C = 0) to 2 pi N_t (the centre).

    Parameters
    ----------
    radius : float
        r, m.
    feed : float
        f, m per revolution.
    """

    radius: float
    feed: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", check_length(self.radius, "radius", positive=True))
        object.__setattr__(self, "feed", check_length(self.feed, "feed", positive=True))
        if self.feed > self.radius:
            raise InputError(f"Expected a feed below the radius, got feed {self.feed!r} m, "
                             f"radius {self.radius!r} m", key="feed")

    @property
    def turns(self) -> float:
        """Eq 6: N_t = r / f."""
        return self.radius / self.feed

    @property
    def feed_per_radian(self) -> float:
        """Eq 5: f_r = f / (2 pi), m/rad."""
        return self.feed / (2.0 * math.pi)

    @property
    def end_angle(self) -> float:
        """2 pi N_t, rad: theta at the centre."""
        return 2.0 * math.pi * self.turns

    @property
    def length(self) -> float:
        """Arc length of the whole spiral, m (eq 3 at theta = 0)."""
        return float(self.arc_length(0.0))

    def radius_at(self, theta) -> np.ndarray:
        """Eq 4: rho = r - f_r theta, m."""
        return self.radius - self.feed_per_radian * np.asarray(theta, dtype=np.float64)

    def arc_length(self, theta) -> np.ndarray:
        """Eq 3: arc length S from the centre to the point at ``theta``, m.

        With phi = 2 pi N_t - theta (the angle left to the centre; rho = f_r phi),
        S = f_r / 2 [phi sqrt(phi^2 + 1) + asinh(phi)] (ln(phi + sqrt(phi^2 + 1)) = asinh).
        """
        phi = self.end_angle - np.asarray(theta, dtype=np.float64)
        return 0.5 * self.feed_per_radian * (phi * np.sqrt(phi * phi + 1.0) + np.arcsinh(phi))

    def angle_at(self, arc_length) -> np.ndarray:
        """theta at arc length S from the centre (eq 3 inverted by Newton's method)."""
        s = np.asarray(arc_length, dtype=np.float64)
        fr = self.feed_per_radian
        # F(phi) = S is convex and F(phi) >= f_r phi^2 / 2: from sqrt(2 S / f_r) Newton comes
        # down monotonically
        phi = np.sqrt(2.0 * np.maximum(s, 0.0) / fr)
        for _ in range(_NEWTON_STEPS):
            value = 0.5 * fr * (phi * np.sqrt(phi * phi + 1.0) + np.arcsinh(phi)) - s
            step = value / (fr * np.sqrt(phi * phi + 1.0))
            phi = np.maximum(phi - step, 0.0)
            if np.all(np.abs(step) <= 4.0 * np.finfo(float).eps * np.maximum(phi, 1.0)):
                break
        return self.end_angle - phi


# --- distributions of cutting points ----------------------------------------------------------
def _steps(total: float, step: float, unit: str, key: str) -> np.ndarray:
    """0, step, 2 step, ... up to ``total`` inclusive (the last step shorter if need be);
    more than `MAX_PATH_POINTS` values are refused naming ``key`` (``unit``: of both)."""
    _check_points(total / step + 1.0, f"step {step:g} {unit} over the spiral's {total:g} {unit}",
                  key)
    # a total that is a whole number of steps up to round-off ends on a full step
    count = math.floor(total / step * (1.0 + 1e-12))
    values = step * np.arange(count + 1, dtype=np.float64)
    if total - values[-1] > 1e-9 * step:
        values = np.append(values, total)
    else:
        values[-1] = total
    return values


def constant_angle(spiral: Spiral, step: float) -> np.ndarray:
    """Constant Angle (CA): theta = 0, step, 2 step, ... to the centre, rad.

    The last step is shorter unless 2 pi N_t is a whole number of steps.
    """
    step = _positive(step, "step (rad)")
    return frozen(_steps(spiral.end_angle, step, "rad", "step (rad)"))


def constant_arc_length(spiral: Spiral, step: float) -> np.ndarray:
    """Constant Arc Length (CAL): points every ``step`` (m) of arc from the outer end
    inwards (eq 3 inverted), the last step shorter, as angles theta (rad)."""
    step = check_length(step, "step", positive=True)
    total = spiral.length
    s = total - _steps(total, step, "m", "step")
    theta = spiral.angle_at(s)
    theta[0], theta[-1] = 0.0, spiral.end_angle
    return frozen(theta)


def cutting_angles(spiral: Spiral, distribution: str, *, step: float | None = None,
                   count: int | None = None) -> np.ndarray:
    """Angles of the cutting points by ``"CA"`` or ``"CAL"``, given the step (rad for CA,
    m for CAL) or the number of points (then equal steps from the outer end to the
    centre)."""
    if (step is None) == (count is None):
        raise InputError("Expected either step or count", key="step")
    if distribution not in ("CA", "CAL"):
        raise InputError(f"Expected distribution 'CA' or 'CAL', got {distribution!r}",
                         key="distribution")
    if count is not None:
        if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 2:
            raise InputError(f"Expected count as an int >= 2, got {count!r}", key="count")
        _check_points(float(count), f"count {count!r}", "count")
        total = spiral.end_angle if distribution == "CA" else spiral.length
        step = total / (count - 1)
    if distribution == "CA":
        return constant_angle(spiral, step)
    return constant_arc_length(spiral, step)


def _check_points(count: float, what: str, key: str) -> None:
    """Refuse a path of ``count`` points beyond `MAX_PATH_POINTS`, naming ``what`` gave it."""
    if not count <= MAX_PATH_POINTS:
        raise InputError(f"Expected at most {MAX_PATH_POINTS:.0e} points on the path "
                         f"(MAX_PATH_POINTS), got {count:.4g} from {what}: a value in "
                         "another unit?", key=key)


def _check_increasing(angles: np.ndarray, name: str) -> None:
    """Refuse angles (rad) that do not increase strictly: the spiral is cut turning one way,
    C = theta increasing, as `ToolPath` holds it, and each step of the CAM needs it
    (`numpy.interp` read decreasing angles silently wrong, the spline refused them in
    scipy's words, `spiral_program` made a block of a repeated C that the lathe does not
    cut, `machinesim.cutting.servo_path.path_times` ran the time backwards)."""
    back = np.flatnonzero(np.diff(angles) <= 0.0)
    if back.size:
        i = int(back[0]) + 1
        raise InputError(f"Expected {name} strictly increasing (the spindle turning one way), "
                         f"got {float(angles[i])!r} rad at index {i} after "
                         f"{float(angles[i - 1])!r}",
                         key=name)


def _positive(value, name: str) -> float:
    if isinstance(value, bool | np.bool_ | str | bytes):
        raise InputError(f"Expected {name} as a number, got {value!r}", key=name)  # no 1
    try:
        number = float(value)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected {name} as a number, got {value!r}", key=name) from error
    except OverflowError:  # an int beyond float64 (10**400)
        what = (f"an int of {value.bit_length()} bits" if isinstance(value, int)
                else brief(repr(value)))
        raise InputError(f"Expected a finite {name}, got {what}, beyond float64",
                         key=name) from None
    if not math.isfinite(number) or number <= 0.0:
        raise InputError(f"Expected {name} > 0, got {number!r}", key=name)
    return number


@dataclass(frozen=True)
class CuttingPoints:
    """Cutting points on the spiral with the designed surface there.

    Attributes
    ----------
    theta : ndarray, shape (N,)
        Polar angle = C, rad, increasing.
    rho : ndarray, shape (N,)
        Radius, m (eq 4).
    z : ndarray, shape (N,)
        Designed height, m.
    slope : ndarray, shape (N,)
        Radial slope dz/drho = tan(phi) (eq 13).
    design : Design, optional
        The design they were taken from (`cutting_points`), for `tool_path`'s gouging check;
        points made by hand may leave it None (then the path is made without the check).
        Copies (`copy.copy`, `copy.deepcopy`) and pickled points keep it, so a copy warns
        of the same gouging; points whose design does not pickle (a local function) are
        refused by `Design`, naming it.
    """

    theta: np.ndarray
    rho: np.ndarray
    z: np.ndarray
    slope: np.ndarray
    design: Design | None = field(default=None, compare=False, repr=False)

    @property
    def x(self) -> np.ndarray:
        return self.rho * np.cos(self.theta)

    @property
    def y(self) -> np.ndarray:
        return self.rho * np.sin(self.theta)

    def __len__(self) -> int:
        return self.theta.size


def cutting_points(design: Design, spiral: Spiral, theta) -> CuttingPoints:
    """The designed surface at the spiral's points ``theta`` (rad): z(rho, theta) and the
    radial slope (eq 13) for the nose compensation."""
    theta = as_floats(theta, "theta", "angles (rad)")  # ["0", "1"] are no angles
    if theta.ndim != 1 or theta.size < 2 or not np.isfinite(theta).all():
        raise InputError(f"Expected at least 2 finite angles, shape (N,), got {theta.shape}",
                         key="theta")
    _check_increasing(theta, "theta")
    if theta[0] < 0.0 or theta[-1] > spiral.end_angle:
        raise InputError(f"Expected angles within the spiral, 0 .. {spiral.end_angle:.9g} rad "
                         f"(its rim to its centre), got {theta[0]:.9g} .. {theta[-1]:.9g} rad: "
                         "beyond them rho (eq 4) leaves the part or turns negative",
                         key="theta")
    rho = spiral.radius_at(theta)
    cos, sin = np.cos(theta), np.sin(theta)
    x, y = rho * cos, rho * sin
    z = design(x, y)
    gx, gy = design.slope(x, y)
    slope = cos * gx + sin * gy
    if not (np.isfinite(z).all() and np.isfinite(slope).all()):
        i = int(np.flatnonzero(~(np.isfinite(z) & np.isfinite(slope)))[0])
        raise InputError(f"design {design.name!r} is not defined at the cutting point "
                         f"({x[i]!r}, {y[i]!r}) m", key="design")
    return CuttingPoints(*(frozen(v) for v in (theta, rho, z, slope)), design=design)
