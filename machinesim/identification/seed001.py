"""Paper 001 (Nakamoto et al., 6-axis ROBOnano Ui): tool setting errors against A, B and C.

NC data for the 6-axis machine is written with the tool edge on the rotary centres. The
edge really sits at ``d = (dx, dy, dz)`` from the A/B centres (tool_mount axes) and the C
centre line at ``e = (ex, ey)`` (workpiece frame at C = 0), so with ``P = (X, Y, Z)`` the
edge lands at ``e + Rz(C) (P + Ry(B) Rz(A) d - e)`` instead of ``Rz(C) P``. Every stage
cuts grooves in brass with the 90-deg V tool and reads them with the virtual confocal
microscope only (docs/procedures/seed001.md derives each step):

0. Touch-off: a groove along X stepping down in Z finds the Z at which the edge meets the
   plate at B = 0 (a lab's tool-length setting; it only lets the later grooves be cut at a
   known depth).
1. A axis (paper Fig. 4): pairs of grooves sharing a start point, cut at A = 0 / 180 deg
   (along +X / -X) and at A = 90 / -90 deg (along +Y / -Y). A groove shows the offset
   across its cutting direction in its centre line and the offset along it in its start
   face: the start point (centre line at the face) moves by ``Rz(A) d``, so each pair's
   start points differ by ``2 (dx, dy)`` (X pair) or ``2 (-dy, dx)`` (Y pair).
2. C axis: one NC groove cut at C = 0, 120, 240 deg makes a triangle whose centre (the
   centroid of the three `groove_crossing` points) is the C centre line, whatever ``d``.
3. B axis (Fig. 5): grooves along Y at A = theta1 = 90 deg and B = 0, theta2, theta3; their
   depths give the edge offset from the B centre, dX across the grooves and dZ along the
   tool, by eq 1 and the corrected eq 2 (`b_axis_offsets`).

`identify` runs the stages in the paper's order (A, C, B), each cut with what the earlier
stages found; `compensate` rewrites any program (eqs of the module docstring inverted).
The procedure receives a function that cuts a program on the machine; it never sees the
injected errors (the honesty rule of DESIGN.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology import (
    Line2D,
    Microscope,
    fit_line,
    fit_v_groove,
    fit_v_grooves,
    groove_crossing,
    profile_points,
    step_positions,
)
from machinesim.nc import Program, ProgramBuilder
from machinesim.workpiece import Part

__all__ = [
    "PARKED", "AAxisResult", "BAxisResult", "CAxisResult", "Compensation", "Identification", "Plan",
    "PlateCut", "b_axis_offsets", "compensate", "identify", "layout_lines", "measure",
    "plate_cuts", "touch_off_z",
]

MM = 1e-3
UM = 1e-6
#: Capture range of the plan: the layout below keeps every groove inside its microscope
#: windows and clear of its neighbours for tool offsets |dx|, |dy|, |dz| up to this (m) and a
#: C centre |e| up to `CENTRE_RANGE`; beyond, a measurement finds no groove and says so.
OFFSET_RANGE = 0.5 * MM
CENTRE_RANGE = 1.0 * MM
#: Heights of the tool edge above the plate for rotary moves and before a plunge (m): above
#: the 0.6 mm touch-off range, so rapids never reach the plate.
SAFE_Z, CLEAR_Z = 2.0 * MM, 0.1 * MM
#: Axis values (m, rad; X Y Z A B C) the machine is parked at before every program: the edge
#: high above the plates (at zero it would sit on them, or in them with a long tool).
PARKED = (0.0, 0.0, SAFE_Z, 0.0, 0.0, 0.0)
#: Touch-off staircase: segment length, first Z, Z step and count. Only grooves 0..200 um
#: deep are seen (the V profile is 0.2 mm tall; deeper sweeps are buried), so a 150 um step
#: always leaves one segment 2..190 um deep for a touch Z in -0.6 .. +0.79 mm.
TOUCH_SEGMENT, TOUCH_TOP, TOUCH_STEP, TOUCH_COUNT = 1.5 * MM, 0.6 * MM, 0.15 * MM, 9
TOUCH_DEPTHS = (2 * UM, 190 * UM)
#: A plan: half the lateral separation of a pair (keeps the two grooves apart for any
#: offset in range), groove length, and the plate spots of the X and Y pairs.
PAIR_HALF_GAP, PAIR_LENGTH = 1.0 * MM, 2.0 * MM
X_PAIR_START, Y_PAIR_START = (0.0, -3.0 * MM), (0.0, 3.0 * MM)
#: The start face is read on a profile along the centre line at the instrument's spacing,
#: then zoomed in to +-ZOOM at FINE_SPACING: the face is vertical (zero-thickness edge
#: profile), so its position is known to half the spacing, 0.025 nm, whatever the height noise.
ZOOM, FINE_SPACING = 0.5 * UM, 0.05e-9
#: B plan: x of the grooves at B = 0, theta2, theta3 (1 mm apart: a 0.5 mm dZ moves a groove
#: tilted by 20 deg by 0.17 mm), and their half window.
B_GROOVE_X, B_WINDOW = (-1.0 * MM, 0.0, 1.0 * MM), 0.45 * MM
#: C plan: inradius of the programmed triangle and half length of each groove. With r = 5 mm
#: a side moves at most sqrt(3) |e| (1.7 mm) and the other sides stay > 4 mm from any window.
TRIANGLE_R, TRIANGLE_HALF = 5.0 * MM, 11.5 * MM
C_TURNS = (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)
C_WINDOW = 2.0 * MM
#: Smallest |den| of eqs 1-2 accepted: there (tilts of +-0.06 deg) a 1 nm depth error already
#: moves dZ by ~1 mm, so the tilts measure nothing.
MIN_DETERMINANT = 1e-9
#: Sample pitch of the profiles across grooves: the microscope's 0.3 um less (1 - 0.618) nm.
#: At a whole number of nanometres every sample of a 45-deg flank would sit at the same phase
#: of the 1 nm height display, all would round alike and the fitted centre would snap to
#: whole nanometres; a golden-ratio phase step spreads the rounding evenly over each flank.
ACROSS_SPACING = 0.3 * UM - (1.0 - 0.5 * (math.sqrt(5.0) - 1.0)) * 1e-9
#: Stations (m along a groove) of the profiles across it.
STATIONS = {"pair": (0.6 * MM, 0.8 * MM, 1.0 * MM, 1.2 * MM, 1.4 * MM),
            "b": (-1.0 * MM, -0.5 * MM, 0.0, 0.5 * MM, 1.0 * MM),
            "c": (-2.0 * MM, -1.0 * MM, 0.0, 1.0 * MM, 2.0 * MM)}
PAIR_WINDOW = OFFSET_RANGE + 0.25 * MM


@dataclass(frozen=True)
class Plan:
    """The paper's measurement plan: groove depths, tilts and feed.

    Attributes
    ----------
    depth : float
        Depth of cut D of the A- and C-axis grooves (m).
    b_depth : float
        Depth of cut D of the B-axis grooves (m): a tilt theta adds dZ (1 - cos theta), up to
        33 um at 20 deg, and the low flank of the tilted V ends 120 um above the edge.
    theta1, theta2, theta3 : float
        A angle that turns the cutting direction onto Y, and the two B tilts (rad).
    feed_mm_per_min : float
        Cutting feed.

    Notes
    -----
    The plate layout (module constants) is sized for the defaults and the capture range.
    """

    depth: float = 10 * UM
    b_depth: float = 40 * UM
    theta1: float = math.pi / 2.0
    theta2: float = math.radians(20.0)
    theta3: float = math.radians(-20.0)
    feed_mm_per_min: float = 200.0

    def __post_init__(self) -> None:
        for name in ("depth", "b_depth", "feed_mm_per_min"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise InputError(f"Expected {name} > 0, got {value!r}", key=name)


@dataclass(frozen=True)
class PlateCut:
    """An NC program and the brass plate (stock spec, mm) it is cut on."""

    program: Program
    stock: str


@dataclass(frozen=True, eq=False)
class Compensation:
    """What the NC data must cancel (m, workpiece frame; SI).

    Attributes
    ----------
    tool_offset : ndarray, shape (3,)
        Edge offset (dx, dy, dz) from the A/B centres, tool_mount axes.
    c_centre : ndarray, shape (2,)
        C centre line (ex, ey) in the workpiece frame at C = 0.
    z_shift : float
        Added to every Z (a work offset: the touch-off of stage 0).
    """

    tool_offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    c_centre: np.ndarray = field(default_factory=lambda: np.zeros(2))
    z_shift: float = 0.0

    def __post_init__(self) -> None:
        for name, n in (("tool_offset", 3), ("c_centre", 2)):
            value = np.array(getattr(self, name), dtype=np.float64)
            if value.shape != (n,) or not np.isfinite(value).all():
                raise InputError(f"Expected {name} as {n} finite numbers (m), got {value!r}",
                                 key=name)
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        if not math.isfinite(self.z_shift):
            raise InputError(f"Expected a finite z_shift (m), got {self.z_shift!r}",
                             key="z_shift")


@dataclass(frozen=True, eq=False)
class AAxisResult:
    """A-axis pairs: start points (m) and what they give.

    Attributes
    ----------
    starts : ndarray, shape (4, 2)
        Start points of the grooves cut at A = 0, 180, 90, -90 deg.
    distances : ndarray, shape (2, 2)
        Start-point displacement within the X pair and the Y pair, minus the programmed one:
        ``2 (dx, dy)`` and ``2 (-dy, dx)`` (Table 1's "distance between grooves").
    offset : ndarray, shape (2,)
        (dx, dy), least squares over both pairs.
    """

    starts: np.ndarray
    distances: np.ndarray
    offset: np.ndarray


@dataclass(frozen=True, eq=False)
class BAxisResult:
    """B-axis grooves: depths (3,) at B = 0, theta2, theta3, and eqs 1-2's edge offset from
    the B centre, dX (machine X at A = theta1, B = 0) and dZ (along the tool), all in m."""

    depths: np.ndarray
    offset_x: float
    offset_z: float


@dataclass(frozen=True, eq=False)
class CAxisResult:
    """C-axis triangle: its three crossings (3, 2), its centre (2,) and its sides (m)."""

    vertices: np.ndarray
    centre: np.ndarray
    sides: tuple[Line2D, ...]


@dataclass(frozen=True, eq=False)
class Identification:
    """All stages: the touch Z (m), the A, B and C results, and the final compensation."""

    z_touch: float
    a: AAxisResult
    b: BAxisResult
    c: CAxisResult
    compensation: Compensation


def b_axis_offsets(d0: float, d1: float, d2: float, theta2: float, theta3: float):
    """Edge offset from the B centre from three groove depths (paper 001, eqs 1-2).

    At B = theta the edge offset (dX, dZ) (machine X and Z at B = 0) turns to
    ``Ry(theta) (dX, dZ)``, whose z is ``-dX sin(theta) + dZ cos(theta)``, so the groove
    depth grows by ``d - D = dX sin(theta) + dZ (1 - cos(theta))`` over the B = 0 depth D.
    Solved for the two tilts (Cramer's rule)::

        dX = ((d1 - D)(1 - cos t3) - (d2 - D)(1 - cos t2)) / den       (eq 1, sign below)
        dZ = ((d2 - D) sin t2 - (d1 - D) sin t3) / den                  (eq 2, corrected)
        den = sin t2 (1 - cos t3) - sin t3 (1 - cos t2)

    The paper's eq 1 is -dX: its positive B tilts the other way (theta -> -theta changes
    the signs of dX and den only), and dZ is the same in both senses. The printed eq 2,
    ``((d1 - D) sin t2 + (d2 - D) sin t3) / den``, follows from neither.

    Parameters
    ----------
    d0, d1, d2 : float
        Depths (m) at B = 0 (D), theta2 and theta3.
    theta2, theta3 : float
        The B tilts (rad).

    Returns
    -------
    (float, float)
        dX, dZ (m).
    """
    den = (math.sin(theta2) * (1.0 - math.cos(theta3))
           - math.sin(theta3) * (1.0 - math.cos(theta2)))
    if not abs(den) > MIN_DETERMINANT:
        raise InputError(f"Expected two distinct non-zero B tilts, got theta2 = "
                         f"{math.degrees(theta2):g} deg, theta3 = {math.degrees(theta3):g} deg")
    u, v = d1 - d0, d2 - d0
    return ((u * (1.0 - math.cos(theta3)) - v * (1.0 - math.cos(theta2))) / den,
            (v * math.sin(theta2) - u * math.sin(theta3)) / den)


def compensate(program: Program, compensation: Compensation) -> Program:
    """Rewrite X, Y, Z so that the edge lands where the NC data put it.

    ``P' = P - Ry(B) Rz(A) d + e - Rz(-C) e`` (e in xy) and ``Z' += z_shift``: then the edge
    at ``e + Rz(C) (P' + Ry(B) Rz(A) d - e)`` is ``Rz(C) P``. Exact at every block end; a
    block that turns A, B or C while it moves is exact only at its ends.
    """
    d, e = compensation.tool_offset, compensation.c_centre
    moves = []
    for move in program.moves:
        target = dict(move.target)
        if {"X", "Y", "Z"} <= target.keys():
            a, b, c = (target.get(k, 0.0) for k in "ABC")
            shift = -_rot_y(b) @ _rot_z(a) @ d
            shift[:2] += e - _rot_z(-c)[:2, :2] @ e
            shift[2] += compensation.z_shift
            target.update(X=target["X"] + shift[0], Y=target["Y"] + shift[1],
                          Z=target["Z"] + shift[2])
        moves.append(replace(move, target=target))
    return Program.from_moves(moves, number=program.number, source=program.source,
                              work_offsets=program.work_offsets)


def plate_cuts(plan: Plan = Plan()) -> dict[str, PlateCut]:
    """The NC data of each stage (edge on the rotary centres), each on its own brass plate.

    Returns
    -------
    dict
        ``"touch"``, ``"a"``, ``"b"``, ``"c"`` -> `PlateCut`.
    """
    f = plan.feed_mm_per_min
    touch = _builder(1, "touch-off").rapid(X=-1 * MM).rapid(Z=TOUCH_TOP)
    for k in range(TOUCH_COUNT):
        if k:
            touch.linear(Z=TOUCH_TOP - k * TOUCH_STEP, feed_mm_per_min=f)
        end = (k + 1) * TOUCH_SEGMENT + (1 * MM if k == TOUCH_COUNT - 1 else 0.0)
        touch.linear(X=end, feed_mm_per_min=f)
    touch.rapid(Z=SAFE_Z)
    a = _builder(2, "A axis")
    for angle, start in _pair_grooves():
        direction = np.array([math.cos(angle), math.sin(angle)])
        _groove(a, start, start + PAIR_LENGTH * direction, -plan.depth, angle, 0.0, 0.0, f,
                inside=True)
    b = _builder(3, "B axis")
    for x, tilt in zip(B_GROOVE_X, (0.0, plan.theta2, plan.theta3), strict=True):
        _groove(b, (x, -2.5 * MM), (x, 2.5 * MM), -plan.b_depth, plan.theta1, tilt, 0.0, f)
    c = _builder(4, "C axis")
    for turn in C_TURNS:
        _groove(c, (-TRIANGLE_HALF, -TRIANGLE_R), (TRIANGLE_HALF, -TRIANGLE_R), -plan.depth,
                0.0, 0.0, turn, f)
    return {"touch": PlateCut(touch.build(),
                              f"block:{TOUCH_COUNT * TOUCH_SEGMENT / MM:g}x3x1@0,-1.5,0"),
            "a": PlateCut(a.build(), "block:6x12x1@-3,-6,0"),
            "b": PlateCut(b.build(), "block:4x3x1@-2,-1.5,0"),
            "c": PlateCut(c.build(), "block:16x16x1@-8,-8,0")}


def touch_off_z(part: Part, microscope: Microscope) -> float:
    """Z (m) at which the edge meets the plate at B = 0, from the touch-off staircase.

    Each segment k, cut at Z_k, is ``Z_touch - Z_k`` deep where seen; the segments 2..190 um
    deep give ``Z_touch = Z_k + depth``, averaged.
    """
    found = []
    for k in range(TOUCH_COUNT):
        x = (k + 0.5) * TOUCH_SEGMENT
        p = microscope.profile(part, (x, -PAIR_WINDOW - 0.2 * MM), (x, PAIR_WINDOW + 0.2 * MM))
        try:
            grooves = fit_v_grooves(p.s, p.z)
        except InputError:
            continue
        found += [TOUCH_TOP - k * TOUCH_STEP + g.depth for g in grooves
                  if TOUCH_DEPTHS[0] <= g.depth <= TOUCH_DEPTHS[1]]
    if not found:
        raise InputError("touch-off: no staircase segment 2..190 um deep; the edge meets the "
                         "plate outside the range of Z -0.6 .. +0.79 mm")
    return float(np.mean(found))


def measure(stage: str, part: Part, microscope: Microscope, plan: Plan = Plan()):
    """Measure the plate of ``stage`` ("a", "b" or "c") as `identify` does.

    Returns
    -------
    AAxisResult, BAxisResult or CAxisResult
    """
    if stage not in ("a", "b", "c"):
        raise InputError(f"Expected stage 'a', 'b' or 'c', got {stage!r}", key="stage")
    return {"a": _measure_a, "b": _measure_b, "c": _measure_c}[stage](part, microscope, plan)


def identify(cut_plate: Callable[[Program, str], Part], microscope: Microscope,
             plan: Plan = Plan()) -> Identification:
    """Run the paper's procedure: touch-off, A, C, then B, each cut with what came before.

    Parameters
    ----------
    cut_plate : callable (Program, stock spec) -> Part
        Cuts a program on the machine (with whatever errors it has), starting from `PARKED`,
        and returns the plate.
    microscope : Microscope
        The instrument that reads every plate.
    plan : Plan

    Returns
    -------
    Identification
        ``compensation`` holds d = (dx, dy, dZ) and e, with no Z shift: applied with
        `compensate`, the NC data needs no touch-off.
    """
    cuts = plate_cuts(plan)
    z_touch = touch_off_z(cut_plate(cuts["touch"].program, cuts["touch"].stock), microscope)
    a = _stage(cut_plate, cuts["a"], Compensation(z_shift=z_touch), microscope, "a", plan)
    known = Compensation(tool_offset=[a.offset[0], a.offset[1], 0.0], z_shift=z_touch)
    c = _stage(cut_plate, cuts["c"], known, microscope, "c", plan)
    b = _stage(cut_plate, cuts["b"], known, microscope, "b", plan)
    final = Compensation(tool_offset=[a.offset[0], a.offset[1], b.offset_z], c_centre=c.centre)
    return Identification(z_touch, a, b, c, final)


def layout_lines(result: CAxisResult | AAxisResult) -> Sequence[tuple[str, np.ndarray]]:
    """Polylines (label, (k, 2) m) for a layout plot of a measured plate."""
    if isinstance(result, CAxisResult):
        v = result.vertices
        return [("triangle (crossings)", np.vstack([v, v[:1]])),
                ("centre", result.centre[None, :])]
    out = []
    for (angle, _), start, name in zip(_pair_grooves(), result.starts,
                                       ("A=0", "A=180", "A=90", "A=-90"), strict=True):
        along = np.array([math.cos(angle), math.sin(angle)])
        out.append((f"groove {name}", np.vstack([start, start + PAIR_LENGTH * along])))
    return out


def _stage(cut_plate, plate: PlateCut, known: Compensation, microscope, stage, plan):
    return measure(stage, cut_plate(compensate(plate.program, known), plate.stock),
                   microscope, plan)


def _builder(number: int, name: str) -> ProgramBuilder:
    """A program that starts with every axis given, high above the plate at zero."""
    return ProgramBuilder(number, source=f"seed001 {name}").rapid(X=0.0, Y=0.0, Z=SAFE_Z, A=0.0,
                                                                  B=0.0, C=0.0)


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


def _pair_grooves():
    """(A angle, programmed start point) of the four A-axis grooves: X pair, then Y pair."""
    out = []
    for angle, spot in ((0.0, X_PAIR_START), (math.pi, X_PAIR_START),
                        (math.pi / 2, Y_PAIR_START), (-math.pi / 2, Y_PAIR_START)):
        # the pair's two grooves run on either side of the spot, across their direction
        side = np.array([-math.sin(angle), math.cos(angle)])
        out.append((angle, np.array(spot) + PAIR_HALF_GAP * side))
    return out


def _fits(part, microscope, origin, along, stations, half_width, what):
    """Grooves across profiles at ``stations`` along ``along`` from ``origin``: (VGroove, xy)."""
    across = np.array([-along[1], along[0]])
    out = []
    for t in stations:
        mid = np.asarray(origin) + t * along
        p0, p1 = mid - half_width * across, mid + half_width * across
        p = microscope.profile(part, p0, p1, spacing=ACROSS_SPACING)
        try:
            g = fit_v_groove(p.s, p.z)
        except InputError as error:
            raise InputError(f"{what}, profile {t / MM:+.2f} mm along: {error}; the errors may "
                             f"exceed the plan's range (|d| <= {OFFSET_RANGE / MM} mm, |e| <= "
                             f"{CENTRE_RANGE / MM} mm)") from error
        out.append((g, profile_points(p0, p1, [g.centre])[0]))
    return out


def _start_point(part, microscope, line: Line2D, spot, along) -> np.ndarray:
    """Where the centre line meets the groove's start face: coarse profile, then zoomed."""
    direction = line.direction if line.direction @ along > 0 else -line.direction
    foot = line.point + ((np.asarray(spot) - line.point) @ direction) * direction
    p0 = foot - PAIR_WINDOW * direction
    coarse = microscope.profile(part, p0, foot + PAIR_WINDOW * direction)
    level = 0.5 * (float(np.nanmin(coarse.z)) + float(np.nanmax(coarse.z)))
    steps = step_positions(coarse.s, coarse.z, level)
    if steps.size != 1:
        raise InputError(f"A axis: expected one start face near {np.round(foot / MM, 4)} mm "
                         f"along the groove, found {steps.size}")
    q0 = p0 + (steps[0] - ZOOM) * direction
    fine = microscope.profile(part, q0, q0 + 2 * ZOOM * direction, spacing=FINE_SPACING)
    return q0 + step_positions(fine.s, fine.z, level)[0] * direction


def _measure_a(part, microscope, plan) -> AAxisResult:
    starts = []
    for angle, spot in _pair_grooves():
        along = np.array([math.cos(angle), math.sin(angle)])
        fits = _fits(part, microscope, spot, along, STATIONS["pair"], PAIR_WINDOW,
                     f"A axis, groove at A = {math.degrees(angle):g} deg")
        starts.append(_start_point(part, microscope, fit_line([xy for _, xy in fits]), spot,
                                   along))
    starts = np.array(starts)
    nominal = np.array([spot for _, spot in _pair_grooves()])
    distances = (starts[[0, 2]] - starts[[1, 3]]) - (nominal[[0, 2]] - nominal[[1, 3]])
    # X pair: 2 (dx, dy); Y pair: 2 (-dy, dx); each component of d is read twice
    offset = 0.25 * np.array([distances[0, 0] + distances[1, 1],
                              distances[0, 1] - distances[1, 0]])
    return AAxisResult(*(_frozen(v) for v in (starts, distances, offset)))


def _measure_b(part, microscope, plan: Plan) -> BAxisResult:
    depths = []
    for x, tilt in zip(B_GROOVE_X, (0.0, plan.theta2, plan.theta3), strict=True):
        fits = _fits(part, microscope, (x, 0.0), np.array([0.0, 1.0]), STATIONS["b"],
                     B_WINDOW, f"B axis, groove at B = {math.degrees(tilt):g} deg")
        depths.append(np.mean([g.depth for g, _ in fits]))
    dx, dz = b_axis_offsets(*depths, plan.theta2, plan.theta3)
    return BAxisResult(_frozen(np.array(depths)), float(dx), float(dz))


def _measure_c(part, microscope, plan) -> CAxisResult:
    centres = []
    for turn in C_TURNS:
        rot = _rot_z(turn)[:2, :2]
        fits = _fits(part, microscope, rot @ (0.0, -TRIANGLE_R), rot @ (1.0, 0.0),
                     STATIONS["c"], C_WINDOW, f"C axis, groove at C = {math.degrees(turn):g} deg")
        centres.append(np.array([xy for _, xy in fits]))
    crossings = [groove_crossing(centres[i], centres[j]) for i, j in ((0, 1), (1, 2), (2, 0))]
    vertices = np.array([cr.point for cr in crossings])
    sides = (crossings[0].first, crossings[1].first, crossings[2].first)
    return CAxisResult(_frozen(vertices), _frozen(vertices.mean(axis=0)), sides)


def _rot_z(t: float) -> np.ndarray:
    return np.array([[math.cos(t), -math.sin(t), 0.0], [math.sin(t), math.cos(t), 0.0],
                     [0.0, 0.0, 1.0]])


def _rot_y(t: float) -> np.ndarray:
    return np.array([[math.cos(t), 0.0, math.sin(t)], [0.0, 1.0, 0.0],
                     [-math.sin(t), 0.0, math.cos(t)]])


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=np.float64)
    array.setflags(write=False)
    return array
