"""Reading paper 001's plates under the microscope: the touch-off staircase, the A sets, the
B grooves and the C triangle with its reference mark.

Each plate (`machinesim.cam.tool_setting_plates`) is read with the lab's confocal
microscope only, as `GrooveReading`s (`machinesim.identification.tool_setting_6axis`): the
groove centres and depths of profiles across each groove, the A grooves' end points, each
with its standard uncertainty, and the axis values of the block that cut the groove. The
procedure that cuts and identifies is `machinesim.procedures.tool_setting_6axis`;
docs/procedures/tool_setting_6axis.md derives each reading.
"""

from __future__ import annotations

import math

import numpy as np

from machinesim.cam.tool_setting_plates import (
    B_GROOVE_X,
    B_WINDOW,
    C_TURNS,
    CAPTURE_RANGE,
    OFFSET_RANGE,
    PARKED,
    SET_LENGTH,
    TOUCH_COUNT,
    TOUCH_SEGMENT,
    TOUCH_STEP,
    TOUCH_TOP,
    TRACK_WINDOW,
    TRIANGLE_R,
    Plan,
    a_grooves,
    mark_point,
)
from machinesim.compensation import program_axes
from machinesim.exceptions import InputError
from machinesim.identification.tool_setting_6axis import GrooveReading
from machinesim.metrology import (
    fit_line,
    fit_v_groove,
    fit_v_grooves,
    profile_points,
    step_positions,
)
from machinesim.nc import Program
from machinesim.rotations import rot_z
from machinesim.units import M_PER_MM, M_PER_NM, M_PER_UM

__all__ = ["a_direction", "read_plate", "touch_off_z"]

#: Touch-off: only segments this deep (m) are used: 2 um clears the microscope's noise; the
#: 90-deg V (10 mm tall: deeper segments show too) of depth D is 2 D wide, so at 190 um it
#: lies whole in the profile (+-0.95 mm, TOUCH_WINDOW + 0.2 mm) with 0.26 mm of plate beside
#: it wherever |dy| <= 0.5 mm puts its centre (a V to 0.45 mm deep is whole there too, but
#: with no plate beside it at the worst dy). 188 um holds one of the staircase's 150 um steps.
TOUCH_DEPTHS = (2 * M_PER_UM, 190 * M_PER_UM)
#: Half width (m) of the windows across the touch-off: the capture range and a quarter
#: millimetre of plate either side.
TOUCH_WINDOW = OFFSET_RANGE + 0.25 * M_PER_MM
#: What a plate reading that finds no groove, or no end, where the layout puts one adds:
#: the plan's capture range (`CAPTURE_RANGE`), worded as paper 000's scenario words its own.
BEYOND_CAPTURE = f"the errors may exceed the plan's capture range ({CAPTURE_RANGE})"
#: The paper's plan, for which the plates' layout and the reading windows are sized.
PAPER_PLAN = Plan()
#: Half width (m) of the windows across the A grooves and along them about their programmed
#: end: how far a groove lands from its programmed place (`A_REACH`, 2.707 mm) and 43 um
#: more, a landed groove's 10 um half width and flat plate beside it (set as A_REACH + 0.25
#: mm when A_REACH was taken as 2.5 mm; the paper's figures are read with this window, and
#: the capture's worst corner, `A_REACH` itself, is read right: tests).
A_WINDOW = 2.75 * M_PER_MM
#: Each A groove is followed out to its end by short profiles across it (half width
#: TRACK_WINDOW) every TRACK_STEP, each centred where the centres so far put the line: the
#: five stations alone would place the line 6 mm out only to about 4 um with the stage's
#: 1 um per profile, a third of the V's 10 um half width. The end face is then read along
#: the line within TRACK_STEP / 2 + TRACK_MARGIN of the middle of the step where the groove
#: was last seen. The step is not a round number, so that round settings do not put an end
#: on a station, where the registration's few micrometres would decide whether the station
#: sees the groove (and so how many stage draws the later profiles take).
#: (TRACK_WINDOW is the layout's: `Plan` keeps the V narrower than these profiles.)
TRACK_STEP, TRACK_MARGIN = 0.47 * M_PER_MM, 0.1 * M_PER_MM
#: The end face is read on a profile along the centre line at the instrument's spacing,
#: then zoomed in to +-ZOOM at FINE_SPACING: the face is vertical (zero-thickness edge
#: profile), so its position is known to half the spacing, 0.025 nm, whatever the height noise.
ZOOM, FINE_SPACING = 0.5 * M_PER_UM, 0.05e-9
#: Half windows (m) across the triangle's sides and across the C plate's reference mark (cut
#: with dx, dy compensated: within a few um of its place, and 3.5 mm from the nearest other
#: groove along its profiles); the B grooves' is the layout's (`B_WINDOW`).
C_WINDOW, MARK_WINDOW = 2.0 * M_PER_MM, 0.5 * M_PER_MM
#: Sample pitch of the profiles across grooves: the microscope's 0.3 um less (1 - 0.618) nm.
#: At a whole number of nanometres every sample of a 45-deg flank would sit at the same phase
#: of the 1 nm height display, all would round alike and the fitted centre would snap to
#: whole nanometres; a golden-ratio phase step spreads the rounding evenly over each flank.
ACROSS_SPACING = 0.3 * M_PER_UM - (1.0 - 0.5 * (math.sqrt(5.0) - 1.0)) * 1e-9
#: Stations (m along a groove) of the profiles across it.
STATIONS = {# each A groove, from the shared start: beyond A_REACH, where neither the other
            # groove of its set nor the other set can be, and short of its nearest end
            "a": (3.0 * M_PER_MM, 3.5 * M_PER_MM, 4.0 * M_PER_MM, 4.5 * M_PER_MM,
                  5.0 * M_PER_MM),
            "b": (-1.0 * M_PER_MM, -0.5 * M_PER_MM, 0.0, 0.5 * M_PER_MM, 1.0 * M_PER_MM),
            "c": (-2.0 * M_PER_MM, -1.0 * M_PER_MM, 0.0, 1.0 * M_PER_MM, 2.0 * M_PER_MM),
            # the reference mark, from its crossing with the C = 0 side: clear of that
            # side's 20 um width by 0.3 mm either way
            "mark": (-1.0 * M_PER_MM, -0.65 * M_PER_MM, -0.3 * M_PER_MM, 0.3 * M_PER_MM,
                     0.65 * M_PER_MM, 1.0 * M_PER_MM)}


def touch_off_z(part, microscope) -> float:
    """Z (m) at which the edge meets the plate at B = 0, from the touch-off staircase.

    Each segment k, cut at Z_k, is ``Z_touch - Z_k`` deep where seen; the segments 2..190 um
    deep give ``Z_touch = Z_k + depth``, averaged.
    """
    found = []
    for k in range(TOUCH_COUNT):
        x = (k + 0.5) * TOUCH_SEGMENT
        p = microscope.profile(part, (x, -TOUCH_WINDOW - 0.2 * M_PER_MM),
                               (x, TOUCH_WINDOW + 0.2 * M_PER_MM))
        try:
            grooves = fit_v_grooves(p.s, p.z)
        except InputError:
            continue
        found += [TOUCH_TOP - k * TOUCH_STEP + g.depth for g in grooves
                  if TOUCH_DEPTHS[0] <= g.depth <= TOUCH_DEPTHS[1]]
    if not found:
        reach = (TOUCH_WINDOW + 0.2 * M_PER_MM) / M_PER_MM
        raise InputError(f"touch-off: no staircase segment 2..190 um deep within {reach:g} mm "
                         f"of y = 0; the edge meets the plate outside Z -0.6 .. +0.79 mm, or "
                         f"sits more than {reach:g} mm off the A centre across the groove "
                         f"(the plan's range: |d| <= {OFFSET_RANGE / M_PER_MM:g} mm)")
    return float(np.mean(found))


def read_plate(stage: str, part, microscope, program: Program, machine,
               plan: Plan | None = None) -> tuple[GrooveReading, ...]:
    """Read the grooves of the ``stage`` plate ("a", "b" or "c") under the microscope.

    Parameters
    ----------
    stage : str
    part : Part
        The plate as cut.
    microscope : Microscope
    program : Program
        The program the plate was cut with (the axis values of each groove come from it).
    machine : Machine
        The nominal machine (its axes and their order).
    plan : Plan, optional
        Default the paper's.

    Returns
    -------
    tuple of GrooveReading
        In cutting order: the A sets' four grooves (`a_grooves`); B = 0, theta2, theta3;
        C = 0, 120, 240 deg and the reference mark.
    """
    if stage not in ("a", "b", "c"):
        raise InputError(f"Expected stage 'a', 'b' or 'c', got {stage!r}", key="stage")
    blocks = _cutting_blocks(program, machine)
    read = {"a": _read_a, "b": _read_b, "c": _read_c}[stage]
    return read(part, microscope, blocks, Plan() if plan is None else plan)


def _cutting_blocks(program: Program, machine) -> list[tuple[np.ndarray, np.ndarray]]:
    """(axis values at the start, at the end) of each block that cuts a groove: a linear
    block that moves in X or Y, in program order."""
    q = program_axes(program, machine, start=PARKED)
    before = np.vstack([PARKED, q[:-1]])
    x, y = machine.axes.index("X"), machine.axes.index("Y")
    return [(before[n], q[n]) for n, move in enumerate(program.moves)
            if move.kind == "linear" and (q[n, x] != before[n, x] or q[n, y] != before[n, y])]


def _beyond(plan: Plan) -> str:
    """What a plate reading that finds no groove, or no end, adds: the capture range, and
    the plan's fields that are not the paper's (the layout and the windows are sized for
    the paper's: a V 40 um deep is 80 um wide, the A grooves' tracking profiles 80 um)."""
    changed = []
    for name in ("depth", "b_depth", "theta1", "theta2", "theta3", "feed_mm_per_min"):
        value = getattr(plan, name)
        if value != getattr(PAPER_PLAN, name):
            changed.append(f"{name} = {value / M_PER_UM:g} um" if "depth" in name else
                           f"{name} = {math.degrees(value):g} deg" if "theta" in name else
                           f"{name} = {value:g}")
    if not changed:
        return BEYOND_CAPTURE
    return (f"{BEYOND_CAPTURE}, or the plan's {', '.join(changed)} (not the paper's) beyond "
            f"what the plates' layout and reading windows are sized for")


def _fits(part, microscope, origin, along, stations, half_width, what,
          beyond: str = BEYOND_CAPTURE):
    """Grooves across profiles at ``stations`` along ``along`` from ``origin``: (VGroove, xy).
    ``beyond``: what a profile without a groove adds to its refusal (`_beyond`)."""
    across = np.array([-along[1], along[0]])
    out = []
    for t in stations:
        mid = np.asarray(origin) + t * along
        p0, p1 = mid - half_width * across, mid + half_width * across
        p = microscope.profile(part, p0, p1, spacing=ACROSS_SPACING)
        try:
            g = fit_v_groove(p.s, p.z)
        except InputError as error:
            raise InputError(f"{what}, profile {t / M_PER_MM:+.2f} mm along: {error}; "
                             f"{beyond}") from error
        out.append((g, profile_points(p0, p1, [g.centre])[0]))
    return out


def _reading(fits, block, stage_sigma: float, end=None) -> GrooveReading:
    """A groove's reading. Each profile, and the end face's zoom, is its own placement of
    the stage: its stated positioning (``stage_sigma``, m) moves a centre across the groove
    and an end point along it, in quadrature with the fit's and the zoom pitch's."""
    return GrooveReading(
        q_start=block[0], q_end=block[1], points=[xy for _, xy in fits],
        point_sigma=[math.hypot(g.centre_sigma, stage_sigma) for g, _ in fits],
        depths=[g.depth for g, _ in fits], depth_sigma=[g.depth_sigma for g, _ in fits],
        end=end, end_sigma=(math.hypot(FINE_SPACING / math.sqrt(12.0), stage_sigma)
                            if end is not None else math.nan))


def _end_point(part, microscope, points, spot, along, reach, depth, what,
               beyond: str = BEYOND_CAPTURE) -> np.ndarray:
    """Where the centre line meets the groove's end face, known to lie within ``reach`` of
    ``spot``: a profile along the line there, then zoomed. A face is a step of the cut
    ``depth`` (m); a profile whose heights span less than half of it has none."""
    foot, direction = _on_line(points, spot, along)
    p0 = foot - reach * direction
    with microscope.placement():  # one field: the zoom is into the same image
        coarse = microscope.profile(part, p0, foot + reach * direction)
        level = 0.5 * (float(np.nanmin(coarse.z)) + float(np.nanmax(coarse.z)))
        steps = step_positions(coarse.s, coarse.z, level)
        span = float(np.nanmax(coarse.z)) - float(np.nanmin(coarse.z))
        if steps.size != 1 or not span > 0.5 * depth:
            x, y = (round(float(v) / M_PER_MM, 4) + 0.0 for v in foot)  # + 0.0: no -0
            # a profile all plate (or all groove bottom) crosses its mid level wherever the
            # noise does: its count of "faces" says nothing
            found = (f"{steps.size}" if span > 0.5 * depth else
                     f"none: nothing stands out of the surface's noise there (its heights "
                     f"span {span / M_PER_NM:.3g} nm; an end face is a step of the "
                     f"{depth / M_PER_UM:g} um cut depth)")
            raise InputError(f"{what}: expected one end face within {reach / M_PER_MM:g} mm "
                             f"of (x, y) = ({x:g}, {y:g}) mm along the groove, found "
                             f"{found}; {beyond}")
        q0 = p0 + (steps[0] - ZOOM) * direction
        fine = microscope.profile(part, q0, q0 + 2 * ZOOM * direction, spacing=FINE_SPACING)
    return q0 + step_positions(fine.s, fine.z, level)[0] * direction


def _on_line(points, spot, along) -> tuple[np.ndarray, np.ndarray]:
    """The foot of ``spot`` on the line fitted to ``points``, and the line's direction
    pointing along ``along``."""
    line = fit_line(points)
    direction = line.direction if line.direction @ along > 0 else -line.direction
    return line.point + ((np.asarray(spot) - line.point) @ direction) * direction, direction


def _followed(part, microscope, fits, along, depth, what, beyond: str = BEYOND_CAPTURE):
    """Follow a groove from its last profile out to where it ends: a short profile across
    it every `TRACK_STEP`, each centred where the line through the centres so far predicts,
    until one finds no groove at least half ``depth`` deep. Returns the fits with the new
    ones added and the station (m along ``along`` from the origin) halfway between the last
    profile that found the groove and the first that did not."""
    fits = list(fits)
    station = STATIONS["a"][-1]
    while True:
        station += TRACK_STEP
        if station > SET_LENGTH + A_WINDOW:
            raise InputError(f"{what}: the groove runs on past {station / M_PER_MM:g} mm "
                             f"from its start; {beyond}")
        centre, direction = _on_line([xy for _, xy in fits], station * along, along)
        across = np.array([-direction[1], direction[0]])
        p0, p1 = centre - TRACK_WINDOW * across, centre + TRACK_WINDOW * across
        p = microscope.profile(part, p0, p1, spacing=ACROSS_SPACING)
        try:
            g = fit_v_groove(p.s, p.z)
        except InputError:
            g = None
        if g is None or not g.depth > 0.5 * depth:
            return fits, station - 0.5 * TRACK_STEP
        fits.append((g, profile_points(p0, p1, [g.centre])[0]))


def _read_a(part, microscope, blocks, plan) -> tuple[GrooveReading, ...]:
    grooves = a_grooves()
    if len(blocks) != len(grooves):
        raise InputError(f"A plate: expected {len(grooves)} grooves in the program, got "
                         f"{len(blocks)}", key="program")
    out = []
    for (angle, turn), block in zip(grooves, blocks, strict=True):
        along = a_direction(angle, turn)
        what = f"A axis, groove at A = {math.degrees(angle):g}, C = {math.degrees(turn):g} deg"
        fits = _fits(part, microscope, (0.0, 0.0), along, STATIONS["a"], A_WINDOW, what,
                     _beyond(plan))
        fits, station = _followed(part, microscope, fits, along, plan.depth, what,
                                  _beyond(plan))
        end = _end_point(part, microscope, [xy for _, xy in fits], station * along, along,
                         0.5 * TRACK_STEP + TRACK_MARGIN, plan.depth, what, _beyond(plan))
        out.append(_reading(fits, block, microscope.stage_sigma, end))
    return tuple(out)


def a_direction(angle: float, turn: float) -> np.ndarray:
    """Direction (2,) on the plate of the A groove cut at A = ``angle``, C = ``turn``: the
    tool's own X at A, turned with the plate by C."""
    return rot_z(turn + angle)[:2, 0]


def _read_b(part, microscope, blocks, plan: Plan) -> tuple[GrooveReading, ...]:
    out = []
    for x, tilt, block in zip(B_GROOVE_X, plan.tilts, blocks, strict=True):
        fits = _fits(part, microscope, (x, 0.0), np.array([0.0, 1.0]), STATIONS["b"],
                     B_WINDOW, f"B axis, groove at B = {math.degrees(tilt):g} deg",
                     _beyond(plan))
        out.append(_reading(fits, block, microscope.stage_sigma))
    return tuple(out)


def _read_c(part, microscope, blocks, plan) -> tuple[GrooveReading, ...]:
    if len(blocks) != len(C_TURNS) + 1:
        raise InputError(f"C plate: expected {len(C_TURNS)} triangle grooves and a reference "
                         f"mark in the program, got {len(blocks)} grooves", key="program")
    out = []
    for turn, block in zip(C_TURNS, blocks, strict=False):
        rot = rot_z(turn)[:2, :2]
        fits = _fits(part, microscope, rot @ (0.0, -TRIANGLE_R), rot @ (1.0, 0.0),
                     STATIONS["c"], C_WINDOW, f"C axis, groove at C = {math.degrees(turn):g} deg",
                     _beyond(plan))
        out.append(_reading(fits, block, microscope.stage_sigma))
    fits = _fits(part, microscope, mark_point(), np.array([0.0, 1.0]), STATIONS["mark"],
                 MARK_WINDOW, "C axis, reference mark", _beyond(plan))
    return (*out, _reading(fits, blocks[-1], microscope.stage_sigma))
