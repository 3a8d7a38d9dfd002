"""The brass test plates of paper 001's tool setting (6-axis ROBOnano Ui): layout, stock and
NC programs.

Paper 001 (Nakamoto et al., docs/procedures/tool_setting_6axis.md) cuts simple grooves in
brass with a 90-deg V tool, the NC data written with the tool edge on the rotary centres.
This module is the CAM side only: where each groove goes, at which A, B, C and depth, on
which plate. Cutting them is the lab's business, reading them the procedure's
(`machinesim.procedures.tool_setting_6axis`), the formulas the identification's
(`machinesim.identification.tool_setting_6axis`).

Four plates, each its own program, each on a fresh plate of the same workpiece frame:

``touch``
    One groove along X stepping down in Z (a lab's tool-length touch-off).
``a``
    Two sets of two grooves sharing their start point (paper Fig. 4): at A = 0, one groove
    cut at C = 0 and one at C = 180 deg, both from the programmed origin along the tool's
    own X, so that they leave the shared start in opposite directions on the plate; then the
    tool turned by A = 180 deg and the same two grooves, turned a quarter on the plate
    (C = 90 and 270 deg) so that the two sets cross instead of overlapping
    (docs/procedures/tool_setting_6axis.md).
``c``
    One groove cut at C = 0, 120 and 240 deg: a triangle (paper Fig. 3), and a reference
    mark: a short groove across the C = 0 side, cut at C = 0 and A = 90 deg (along +Y), whose
    crossing with that side places the triangle without the microscope stage's origin.
``b``
    Grooves along Y at A = theta1 and B = 0, theta2, theta3 (paper Fig. 5).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from machinesim.exceptions import InputError
from machinesim.identification.tool_setting_6axis import MIN_DETERMINANT, b_tilt_determinant
from machinesim.metrology._arrays import as_number
from machinesim.nc import Program, ProgramBuilder
from machinesim.tolerances import SIDEWAYS_WARN_RAD
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = [
    "A_REACH", "A_SETS", "B_GROOVE_X", "B_WINDOW", "CAPTURE_RANGE", "CENTRE_RANGE", "C_TURNS",
    "MACHINE", "MARK_HALF",
    "MARK_X", "OFFSET_RANGE", "PARKED", "Plan", "PlateCut", "SET_LENGTH", "TOUCH_COUNT",
    "TOUCH_SEGMENT", "TOUCH_STEP", "TOUCH_TOP", "TRACK_WINDOW", "TRIANGLE_HALF", "TRIANGLE_R",
    "a_grooves", "b_depth_range", "b_tilt_limit", "mark_point", "plate_cuts",
]

#: Capture range of the plan: the layout below keeps every groove inside its microscope
#: windows and clear of its neighbours for tool offsets |dx|, |dy|, |dz| up to this (m) and a
#: C centre |e| up to `CENTRE_RANGE`; beyond, a measurement finds no groove and says so.
OFFSET_RANGE = 0.5 * M_PER_MM
CENTRE_RANGE = 1.0 * M_PER_MM
#: The capture range in words, as the refusals of errors beyond it name it (the scenario's
#: before any cutting, a plate reading's after).
CAPTURE_RANGE = (f"|dx|, |dy|, |dz| <= {OFFSET_RANGE / M_PER_MM:g} mm, "
                 f"|e| <= {CENTRE_RANGE / M_PER_MM:g} mm")
#: Heights of the tool edge above the plate for rotary moves and before a plunge (m): above
#: the 0.6 mm touch-off range, so rapids never reach the plate.
SAFE_Z, CLEAR_Z = 2.0 * M_PER_MM, 0.1 * M_PER_MM
#: Axis values (m, rad; X Y Z A B C) the machine is parked at before every program: the edge
#: high above the plates (at zero it would sit on them, or in them with a long tool).
PARKED = (0.0, 0.0, SAFE_Z, 0.0, 0.0, 0.0)
#: Touch-off staircase: segment length, first Z, Z step and count. The touch-off reads the
#: segments 2..190 um deep (`TOUCH_DEPTHS` of the reading module: why), a range 188 um wide,
#: so a 150 um step always leaves one segment in it for a touch Z in -0.6 .. +0.79 mm.
TOUCH_SEGMENT, TOUCH_TOP, TOUCH_STEP, TOUCH_COUNT = (1.5 * M_PER_MM, 0.6 * M_PER_MM,
                                                     0.15 * M_PER_MM, 9)
#: A plate: the sets (A; C of the set's two grooves), in cutting order. Each groove is
#: programmed from the origin (the rotary centres) along the tool's own X at A.
A_SETS = ((0.0, (0.0, math.pi)), (math.pi, (0.5 * math.pi, 1.5 * math.pi)))
#: How far (m) a groove of the A plate lands from where the program puts it, at most: a
#: groove cut at C lands at ``e + Rz(C) (P + Rz(A) d - e)``, off by up to |(dx, dy)| + 2 |e|
#: (dz turns with A about the tool's Z, out of the plate): with dx, dy each within
#: `OFFSET_RANGE`, sqrt(2) 0.5 + 2 = 2.707 mm (d = (-0.5, 0.5) mm, e = (0.707, -0.707) mm at
#: C = 180 deg). It was taken as |d| <= 0.5 mm + 2 |e| = 2.5 mm.
A_REACH = math.hypot(OFFSET_RANGE, OFFSET_RANGE) + 2.0 * CENTRE_RANGE
#: Length L (m) of each A-plate groove: its far end lies within `A_REACH` of L from the
#: shared start, so with L = 8 mm each groove is whole from 3 mm out to at least 5.5 mm,
#: where it is read, clear of the other groove of its set and of the other set, which stay
#: within `A_REACH` (2.707 mm) of the origin along the line.
SET_LENGTH = 8.0 * M_PER_MM
#: B plate: x of the grooves at B = 0, theta2, theta3 (1 mm apart: a 0.5 mm dZ moves a
#: groove tilted by 20 deg by 0.17 mm) and their half length in y.
B_GROOVE_X, B_HALF = (-1.0 * M_PER_MM, 0.0, 1.0 * M_PER_MM), 2.5 * M_PER_MM
#: C plate: inradius of the programmed triangle and half length of each groove. With r = 5 mm
#: a side moves at most sqrt(3) |e| (1.7 mm) and the other sides stay > 4 mm from any window.
TRIANGLE_R, TRIANGLE_HALF = 5.0 * M_PER_MM, 11.5 * M_PER_MM
C_TURNS = (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)
#: C plate's reference mark: x of the groove across the C = 0 side (clear of the side's
#: profiles at -2 .. 2 mm and 4.5 mm from the other sides) and its half length in y.
MARK_X, MARK_HALF = 3.5 * M_PER_MM, 1.2 * M_PER_MM
#: The machine the plates are written for: a `Plan`'s A and B angles must lie within its
#: travel (its URDF's joint limits), its feed within its linear axes' velocity limit.
MACHINE = "robonano_ui"
#: Half width (m) of the profiles that follow each A groove out to its end (read by
#: `machinesim.procedures.tool_setting_6axis_reading`): a 90-deg V of depth D is 2 D wide,
#: so a `Plan`'s ``depth`` must stay below it (with the default errors 39 um is read, 40 um,
#: as wide as these profiles, is not).
TRACK_WINDOW = 40 * M_PER_UM
#: Half width (m) of the profiles across the B grooves (1 mm apart): the room a groove has
#: there, whatever its tilt (`b_depth_range`).
B_WINDOW = 0.45 * M_PER_MM


@dataclass(frozen=True)
class Plan:
    """The paper's measurement plan: groove depths, tilts and feed.

    Attributes
    ----------
    depth : float
        Depth of cut D of the A- and C-axis grooves (m), below `TRACK_WINDOW` (40 um).
    b_depth : float
        Depth of cut D of the B-axis grooves (m): with each tilt, within `b_depth_range`
        (30.2 .. 99.9 um at +-20 deg; below `B_WINDOW` at B = 0).
    theta1, theta2, theta3 : float
        A angle that turns the cutting direction onto Y (+-90 or +-270 deg, within
        `tolerances.SIDEWAYS_WARN_RAD`), and the two B tilts (rad), each within the travel
        of `MACHINE` (its URDF: A +-360 deg, B +-100 deg) and within `b_tilt_limit` of
        ``b_depth`` (+-23.07 deg at 40 um). Eqs 1-2 need the tilts non-zero and distinct
        (`b_tilt_determinant`).
    feed_mm_per_min : float
        Cutting feed, up to the velocity limit of `MACHINE`'s linear axes (its URDF: 0.025
        m/s, 1500 mm/min).

    Every field is checked when the plan is made (`InputError` naming the field and the
    range that works), not when a plate is read minutes later.

    Notes
    -----
    The plate layout (module constants) is sized for the defaults and the capture range;
    the bounds on depths and tilts are what keeps every groove cut and within its reading
    window over the whole capture range (|dz| <= `OFFSET_RANGE`).
    """

    depth: float = 10 * M_PER_UM
    b_depth: float = 40 * M_PER_UM
    theta1: float = math.pi / 2.0
    theta2: float = math.radians(20.0)
    theta3: float = math.radians(-20.0)
    feed_mm_per_min: float = 200.0

    def __post_init__(self) -> None:
        for name, unit in (("depth", "m"), ("b_depth", "m"), ("feed_mm_per_min", "mm/min")):
            object.__setattr__(self, name, as_number(getattr(self, name), name, sign="> 0",
                                                     unit=unit))
        for name, axis in (("theta1", "A"), ("theta2", "B"), ("theta3", "B")):
            _check_angle(name, getattr(self, name), axis)
        _check_sizes(self)
        # The B grooves run along Y and the V tool cuts along its own X, Rz(theta1) x at A =
        # theta1: any other theta1 drags the edge sideways (at 0 along its own plane, which
        # removes nothing: the B plate was then read as "the errors may exceed the capture
        # range" after the A and C plates had been cut)
        drag = math.asin(min(1.0, abs(math.cos(self.theta1))))
        if drag > SIDEWAYS_WARN_RAD:
            raise InputError(f"Expected theta1 turning the tool's cutting direction (its own X) "
                             f"onto Y, +-90 or +-270 deg within "
                             f"{math.degrees(SIDEWAYS_WARN_RAD):g} deg (the B grooves run "
                             f"along Y), got {_angle(self.theta1)}: the V tool would be "
                             f"dragged {math.degrees(drag):.6g} deg sideways", key="theta1")
        if not abs(b_tilt_determinant(self.theta2, self.theta3)) > MIN_DETERMINANT:
            zero = min(abs(self.theta2), abs(self.theta3)) < abs(self.theta2 - self.theta3)
            name = ("theta2" if abs(self.theta2) <= abs(self.theta3) else "theta3") if zero \
                else "theta3"
            expected = ("a non-zero B tilt" if zero else
                        "a B tilt other than theta2 (two distinct tilts)")
            raise InputError(
                f"Expected {expected}: eqs 1-2 of paper 001 take dX and dZ from the depth "
                f"changes at two distinct non-zero tilts, got theta2 = {_angle(self.theta2)}, "
                f"theta3 = {_angle(self.theta3)}", key=name)
        for name in ("theta2", "theta3"):
            _check_tilt(name, getattr(self, name), self.b_depth)

    @property
    def tilts(self) -> tuple[float, float, float]:
        """B of the three B-plate grooves: 0, theta2, theta3 (rad)."""
        return (0.0, self.theta2, self.theta3)


def _angle(value: float) -> str:
    return f"{value:.9g} rad ({math.degrees(value):.6g} deg)"


def b_depth_range(tilt: float) -> tuple[float, float]:
    """(lower, upper) (m), exclusive, of the B plate's depth of cut D for which a groove at
    B = ``tilt`` (rad) is cut and read over the whole capture range (|dz| <= R,
    `OFFSET_RANGE`); lower >= upper where no D is.

    The B grooves are cut with dx, dy compensated and Z touched off at B = 0 (a work
    offset that B does not turn), so at B = t the edge lies dz sin t across the groove and
    dz (1 - cos t) deeper than at B = 0 (docs/procedures/tool_setting_6axis.md, stage 3):

    - cut at all where dz = -R: D - R (1 - cos t) > 0 (the lower bound);
    - within its profiles' half width `B_WINDOW` where dz = +R: the 90-deg V tilted by t,
      d = D + R (1 - cos t) deep, reaches d tan(45 deg + |t|) to its lower flank's side of
      the edge, which lies R sin|t| off: R sin|t| + d tan(45 deg + |t|) < B_WINDOW (the
      upper bound). From 45 deg on the lower flank lies on the plate: no D.

    The grooves are 1 mm apart, so a groove within its own window stays out of the next
    one's. Measured at the capture's corner (dx, dy, dz = 500, -500, +-500 um, e = 600,
    -800 um; noise off): at 20 deg D = 90 um is read and 110 um is not (here 99.9 um), at
    D = 40 um 22 deg is read and 25 deg is not (here 23.07 deg).
    """
    t = abs(float(tilt))
    if t >= 0.25 * math.pi:
        return (0.0, 0.0)
    sag = OFFSET_RANGE * (1.0 - math.cos(t))
    return (sag, (B_WINDOW - OFFSET_RANGE * math.sin(t)) / math.tan(0.25 * math.pi + t) - sag)


def b_tilt_limit(b_depth: float) -> float:
    """The largest |B| (rad) at which a groove ``b_depth`` (m) deep is cut and read over the
    capture range (`b_depth_range`; bisected to 1e-12 rad: the lower bound grows and the
    upper one falls with the tilt); 0 where even B = 0 is not."""
    def fits(t):
        lower, upper = b_depth_range(t)
        return lower < b_depth < upper

    if not fits(0.0):
        return 0.0
    low, high = 0.0, 0.25 * math.pi
    while high - low > 1e-12:
        middle = 0.5 * (low + high)
        low, high = (middle, high) if fits(middle) else (low, middle)
    return low


def _check_sizes(plan: Plan) -> None:
    """A `Plan`'s feed within `MACHINE`'s linear axes' velocity limit, its depth below
    `TRACK_WINDOW` and its B depth below `B_WINDOW`."""
    limit = _feed_limit()
    if plan.feed_mm_per_min > limit:
        raise InputError(f"Expected feed_mm_per_min up to {limit:g} mm/min, the velocity "
                         f"limit of {MACHINE}'s linear axes (its URDF), got "
                         f"{plan.feed_mm_per_min!r} mm/min", key="feed_mm_per_min")
    if not plan.depth < TRACK_WINDOW:
        raise InputError(f"Expected depth below {TRACK_WINDOW / M_PER_UM:g} um, got "
                         f"{plan.depth / M_PER_UM:g} um: the 90-deg V of depth D is 2 D wide "
                         f"and the profiles that follow the A grooves to their ends are "
                         f"{2.0 * TRACK_WINDOW / M_PER_UM:g} um wide (TRACK_WINDOW)",
                         key="depth")
    if not plan.b_depth < B_WINDOW:
        raise InputError(f"Expected b_depth below {B_WINDOW / M_PER_UM:g} um, got "
                         f"{plan.b_depth / M_PER_UM:g} um: the B = 0 groove, 2 D wide, would "
                         f"fill the {2.0 * B_WINDOW / M_PER_MM:g} mm profiles across it "
                         "(B_WINDOW)", key="b_depth")


def _check_tilt(name: str, tilt: float, b_depth: float) -> None:
    """A B tilt at which a groove ``b_depth`` deep is cut and read over the capture range
    (`b_depth_range`): else refused with the tilts that are, and the depths that are at
    this tilt."""
    lower, upper = b_depth_range(tilt)
    if lower < b_depth < upper:
        return
    depths = (f"at {abs(math.degrees(tilt)):g} deg b_depth {lower / M_PER_UM:.4g} .. "
              f"{upper / M_PER_UM:.4g} um" if lower < upper else
              f"at {abs(math.degrees(tilt)):g} deg no b_depth")
    reach = f"{OFFSET_RANGE / M_PER_MM:g} mm"
    where = (f"the groove is not cut where dz = -{reach}" if b_depth <= lower else
             f"the tilted V reaches beyond the profiles across it where dz = +{reach}")
    raise InputError(f"Expected {name} within +-{math.degrees(b_tilt_limit(b_depth)):.4g} deg "
                     f"for b_depth = {b_depth / M_PER_UM:g} um ({depths}, over the capture "
                     f"range {CAPTURE_RANGE}), got {_angle(tilt)}: {where}", key=name)


@lru_cache(maxsize=1)
def _feed_limit() -> float:
    """The slowest velocity limit of `MACHINE`'s linear axes (its URDF), mm/min: a feed
    move along any of them runs no faster."""
    from machinesim.machines import load_machine

    machine = load_machine(MACHINE)
    rates = [float(rate) for rate, rotary in zip(machine.rapid_rate, machine.rotary,
                                                 strict=True) if not rotary]
    return min(rates) * 60.0 / M_PER_MM


@lru_cache(maxsize=1)
def _travel() -> dict[str, tuple[float, float]]:
    """(lower, upper) (rad) of `MACHINE`'s rotary axes, from its URDF."""
    from machinesim.machines import load_machine

    machine = load_machine(MACHINE)
    return {a: (float(lo), float(hi))
            for a, lo, hi in zip(machine.axes, machine.lower, machine.upper, strict=True)}


def _check_angle(name: str, value, axis: str) -> None:
    """A `Plan` angle: a finite number of rad within the travel of `MACHINE`'s ``axis``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(value):
        raise InputError(f"Expected {name} as a finite angle in rad (the {axis} axis of "
                         f"{MACHINE}), got {value!r}", key=name)
    lower, upper = _travel()[axis]
    if not lower <= value <= upper:
        hint = (f"; the angles are in rad: {value:g} deg is math.radians({value:g}) = "
                f"{math.radians(value):.6g} rad"
                if abs(value) > 2.0 * math.pi and lower <= math.radians(value) <= upper
                else "")  # more than a turn: degrees, likely
        raise InputError(f"Expected {name} within the {axis} travel of {MACHINE}, "
                         f"{lower:.6g} .. {upper:.6g} rad ({math.degrees(lower):g} .. "
                         f"{math.degrees(upper):g} deg), got {_angle(value)}{hint}", key=name)


@dataclass(frozen=True)
class PlateCut:
    """An NC program and the brass plate (stock spec, mm) it is cut on."""

    program: Program
    stock: str


def plate_cuts(plan: Plan = Plan()) -> dict[str, PlateCut]:
    """The NC data of each stage (edge on the rotary centres), each on its own brass plate.

    Every program starts with all six axes given, high above the plate (`PARKED`), and turns
    the rotary axes only there.

    Returns
    -------
    dict
        ``"touch"``, ``"a"``, ``"b"``, ``"c"`` -> `PlateCut`.
    """
    f = plan.feed_mm_per_min
    mm = M_PER_MM
    touch = _builder(1, "touch-off").rapid(X=-1 * mm).rapid(Z=TOUCH_TOP)
    for k in range(TOUCH_COUNT):
        if k:
            touch.linear(Z=TOUCH_TOP - k * TOUCH_STEP, feed_mm_per_min=f)
        end = (k + 1) * TOUCH_SEGMENT + (1 * mm if k == TOUCH_COUNT - 1 else 0.0)
        touch.linear(X=end, feed_mm_per_min=f)
    touch.rapid(Z=SAFE_Z)
    a = _builder(2, "A axis")
    for angle, turn in a_grooves():
        end = SET_LENGTH * np.array([math.cos(angle), math.sin(angle)])
        _groove(a, (0.0, 0.0), end, -plan.depth, angle, 0.0, turn, f, inside=True)
    b = _builder(3, "B axis")
    for x, tilt in zip(B_GROOVE_X, plan.tilts, strict=True):
        _groove(b, (x, -B_HALF), (x, B_HALF), -plan.b_depth, plan.theta1, tilt, 0.0, f)
    c = _builder(4, "C axis")
    for turn in C_TURNS:
        _groove(c, (-TRIANGLE_HALF, -TRIANGLE_R), (TRIANGLE_HALF, -TRIANGLE_R), -plan.depth,
                0.0, 0.0, turn, f)
    _groove(c, (MARK_X, -TRIANGLE_R - MARK_HALF), (MARK_X, -TRIANGLE_R + MARK_HALF),
            -plan.depth, math.pi / 2.0, 0.0, 0.0, f, inside=True)
    return {"touch": PlateCut(touch.build(),
                              f"block:{TOUCH_COUNT * TOUCH_SEGMENT / mm:g}x3x1@0,-1.5,0"),
            "a": PlateCut(a.build(), "block:24x24x1@-12,-12,0"),
            "b": PlateCut(b.build(), "block:4x3x1@-2,-1.5,0"),
            "c": PlateCut(c.build(), "block:16x16x1@-8,-8,0")}


def mark_point() -> np.ndarray:
    """Programmed crossing (2,) m of the C plate's reference mark with the C = 0 side."""
    return np.array([MARK_X, -TRIANGLE_R])


def a_grooves() -> list[tuple[float, float]]:
    """(A, C) (rad) of the four A-plate grooves in cutting order: the two of each set, C and
    C + 180 deg apart, one after the other. Each runs `SET_LENGTH` from the programmed
    origin along the tool's own X at A, so on the plate along ``Rz(C + A) x``."""
    return [(angle, turn) for angle, turns in A_SETS for turn in turns]


def _builder(number: int, name: str) -> ProgramBuilder:
    """A program that starts with every axis given, high above the plate at zero."""
    return ProgramBuilder(number, source=f"tool_setting_6axis {name}").rapid(
        X=0.0, Y=0.0, Z=SAFE_Z, A=0.0, B=0.0, C=0.0)


def _groove(builder, start, end, z, a, b, c, feed, inside=False) -> None:
    """One groove: turn the axes high above the plate, then plunge and cut along start->end.

    A groove starting on the plate (``inside``) is plunged and left at the feed, as its
    zero-thickness edge sweeps nothing then; one starting off the plate is entered by rapid
    (a tilted plunge would drag the edge sideways).
    """
    builder.rapid(Z=SAFE_Z).rapid(A=a, B=b, C=c).rapid(X=start[0], Y=start[1])
    if inside:
        builder.rapid(Z=CLEAR_Z).linear(Z=z, feed_mm_per_min=feed)
    else:
        builder.rapid(Z=z)
    builder.linear(X=end[0], Y=end[1], feed_mm_per_min=feed)
    if inside:
        builder.linear(Z=CLEAR_Z)
    builder.rapid(Z=SAFE_Z)
