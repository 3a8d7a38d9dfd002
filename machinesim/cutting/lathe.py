"""Turning an NC program on a lathe: the program's moves through the machine's servo loops and
errors, cut by the turning engine (`machinesim.cutting.turning`).

A slow-tool-servo (STS) or facing program on a lathe (``sts_lathe``: X carries the work
spindle C, the tool rides Z) is a list of feed moves that turn C while X and Z follow. What
the machine does with it, in order:

1. **Axis values.** Every move's target (modal: an axis not named keeps its value), from
   the first move that sets every axis of the machine.
2. **Times.** The control runs each feed move in length / F, the length with rotary axes in
   degrees counted as millimetres (FANUC, as `machinesim.motion` plans it), and no axis
   faster than its velocity limit (the machine's rapid rate, ``sts_lathe``'s C 150 rad/s):
   a feed beyond it is clamped there, as the planner clamps it; a dwell waits its time
   (counted in the report's time, noted beyond an hour, not cut). Steps 1 and 2, and the
   runs of step 3, are `machinesim.cutting.lathe_program`'s.
3. **Servo.** Each run of feed moves that turn C is one continuous motion: the servo loops
   (`machinesim.servo`, any ``follow(t, q)``) follow it, entering it settled at its first
   step's speed (the spindle is run up before the tool engages: `followed`), and the axes
   reach the followed values, not the commanded ones. A dwell ends a run; the run after it
   is entered settled too, not from the rest the dwell leaves the axes in. The followed
   samples keep the command's rules (a quarter turn of C a step, each straight join within
   the chord tolerance of the servo's own motion): where they break them, the run is sampled
   finer and followed again (`machinesim.cutting.lathe_following`).
4. **Kinematics and errors.** The tool tip's pose for the reached axis values, through the
   machine's errors (tool setting dx, dy, dz and any geometric error), gives the edge plane
   of each point (`edge_path_from_poses`); the tool's nose is its nominal radius plus the
   error model's ``tool_geometry.nose_radius``, still set by its tip.
5. **Surface.** The lower envelope of the nose arc along each run (`turned_heights`), the
   lowest over all runs, clipped at the stock's top.

Moves that do not turn C (the plunge to the first point, the retract) are not cut: at one
spindle angle the edge marks a line, not a surface; a program whose C stands still
throughout is refused. Rapids are never cut.

A program that takes an axis outside its travel is refused before anything is cut, with
`AxisLimitError` naming the axis, the value, the travel and the program's lines, as
`machinesim.cutting.cut` refuses it (the same check, on the program's axis values, move by
move); ``allow_overtravel=True`` turns it anyway and lists it in
`TurningReport.limit_violations`. So is a run whose servo-followed path takes an axis
beyond a travel its command keeps (a loop that overshoots), naming the axis, the line and
by how much (`machinesim.cutting.lathe_following.followed_overtravel`). A move that takes
the tool beyond `machinesim.cutting.engine.FARTHEST_M` (1 km) of the workpiece origin is
refused either way (InputError naming its line), as `cut` refuses it: float64 keeps no
nanometre there. A turn
that leaves the stock as it was (the tool's tip
never below its top: a program above the part, a tool set too high or a workpiece too low)
is reported, as `cut` reports one: `TurningReport.empty_cut`, with a note saying why.

The result is a `TurnedPart`: a height field evaluated on demand (exactly, at any points),
which the optical instruments read like a mesh part (`machinesim.metrology.optical`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from machinesim.cutting.lathe_following import (
    follow_run,
    followed_beyond,
    refuse_followed,
    worst_beyond,
)
from machinesim.cutting.lathe_program import (
    MOST_C_STEP_RAD,  # noqa: F401 (importable from here, as before the split)
    STILL_C_RAD,  # noqa: F401 (importable from here, as before the split)
    _program_moves,
    _rapids_below_top,
    _timed_runs,
    _untimed_moves,
    turning_runs,
)
from machinesim.cutting.program import _overtravel, _refuse_far
from machinesim.cutting.report import following_note
from machinesim.cutting.turning import edge_path_from_poses, turned_heights
from machinesim.errors import as_error_model
from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_flag, as_floats, as_number
from machinesim.nc.program import modal_values
from machinesim.servo import check_servo
from machinesim.tool_specs import tool_from_spec
from machinesim.tools import RoundNoseTool, with_nose_radius_error

__all__ = ["TurnedFace", "TurnedPart", "TurningReport", "check_lathe", "followed", "turn",
           "turning_runs", "turning_tool"]

#: How long the servo loops follow the run's first velocity before its start (s): the
#: spindle run up before the tool engages. 3 s is a revolution at paper 004's 20 rpm and
#: ~10 time constants of its loops' integral action.
LEAD_IN_S = 3.0
LEAD_IN_SAMPLES = 30
#: Largest stock top accepted either way (m, workpiece frame): the shipped machines travel
#: at most 0.5 m, so a top a metre or more from the workpiece's origin is a unit mix-up (a
#: top in um given as m), as a tool of a metre is (`machinesim.tool_sizes.MAX_TOOL_SIZE_M`).
MOST_TOP_M = 1.0


@dataclass(frozen=True, eq=False)
class TurnedPart:
    """A turned face: the height field the tool left, evaluated on demand.

    Attributes
    ----------
    paths : tuple of EdgePath
        The edge's path of each turning run, workpiece frame.
    tool : RoundNoseTool
        The tool as it cut (its nose radius error included).
    top : float
        The stock's top, m: heights above it, and points the edge never reached, read it.
    """

    paths: tuple
    tool: RoundNoseTool
    top: float

    def __repr__(self) -> str:
        points = sum(p.angle.size for p in self.paths)
        turns = sum(abs(p.angle[-1] - p.angle[0]) for p in self.paths) / (2 * math.pi)
        return (f"TurnedPart({len(self.paths)} run{'' if len(self.paths) == 1 else 's'}, "
                f"{points} path points over {turns:.6g} turns, nose radius "
                f"{self.tool.nose_radius * 1e3:.6g} mm, top {self.top:.6g} m)")

    def heights_at(self, px, py) -> np.ndarray:
        """Heights at the points ``(px[i], py[i])`` (m, workpiece frame), shape (n,)."""
        px = as_floats(px, "px").ravel()
        py = as_floats(py, "py").ravel()
        if px.size != py.size:
            raise InputError(f"heights_at(px, py) takes the points' x and y as two arrays of "
                             f"one length, got {px.size} and {py.size} values (an (n, 2) "
                             "array is heights_at(points[:, 0], points[:, 1]))")
        out = np.full(px.size, self.top)
        for path in self.paths:
            np.minimum(out, turned_heights(path, self.tool, px, py, top=self.top), out=out)
        return out

    def heights(self, x, y) -> np.ndarray:
        """Heights over the grid ``x`` x ``y`` (m), shape (ny, nx): ``z[j, i]`` at
        ``(x[i], y[j])``."""
        gx = as_floats(x, "x")  # text was a ValueError, True read as 1 m
        gy = as_floats(y, "y")
        px, py = np.meshgrid(gx, gy)
        return self.heights_at(px, py).reshape(gy.size, gx.size)


class TurnedFace:
    """A turned face as `machinesim.Lab.turn` hands it out: its heights, which the optical
    instruments read, and its top. How it was cut is the lab's truth and kept private: the
    `TurnedPart`'s tool has the nose radius error, its paths the tool setting error; its
    repr names the nose radius as commanded."""

    __slots__ = ("__commanded", "__part")

    def __init__(self, part: TurnedPart, commanded: RoundNoseTool) -> None:
        self.__part = part
        self.__commanded = commanded

    @property
    def top(self) -> float:
        """The stock's top, m."""
        return self.__part.top

    def __repr__(self) -> str:
        paths = self.__part.paths
        points = sum(p.angle.size for p in paths)
        turns = sum(abs(p.angle[-1] - p.angle[0]) for p in paths) / (2 * math.pi)
        return (f"TurnedFace({len(paths)} run{'' if len(paths) == 1 else 's'}, {points} path "
                f"points over {turns:.6g} turns, nose radius "
                f"{self.__commanded.nose_radius * 1e3:.6g} mm as commanded, top "
                f"{self.top:.6g} m)")

    def heights_at(self, px, py) -> np.ndarray:
        """`TurnedPart.heights_at`."""
        return self.__part.heights_at(px, py)

    def heights(self, x, y) -> np.ndarray:
        """`TurnedPart.heights`."""
        return self.__part.heights(x, y)


@dataclass(frozen=True)
class TurningReport:
    """What the turn did.

    Attributes
    ----------
    points : int
        Path points cut (all runs).
    runs : int
        Runs of feed moves that turn C.
    machining_time_s : float
        Time of the turning runs at the programmed feeds and of the program's dwells (G04,
        a canned cycle's P), s; the moves that do not turn C (a plunge, a retract) and the
        rapids are not timed.
    revolutions : float
        Spindle revolutions cut.
    peak_following_error : dict
        Axis letter -> largest |command - reached| over the runs (m or rad); zeros without
        servo loops.
    empty_cut : bool
        True when nothing was cut: the tool's tip (the nose's lowest point) stays at or
        above the stock's top over the whole turn, so the part is the stock's top
        everywhere. ``notes`` says how far above it the tip stayed.
    limit_violations : tuple of str
        Axis values outside their travel, with their lines (only with ``allow_overtravel``:
        otherwise `turn` raises `AxisLimitError`).
    notes : tuple of str
        What a reader of the part should know (an empty cut).
    """

    points: int
    runs: int
    machining_time_s: float
    revolutions: float
    peak_following_error: dict
    empty_cut: bool = False
    limit_violations: tuple[str, ...] = ()
    notes: tuple[str, ...] = field(default=())

    def __repr__(self) -> str:
        plural = "" if self.runs == 1 else "s"
        flagged = (f"; {len(self.limit_violations)} limit violation"
                   f"{'' if len(self.limit_violations) == 1 else 's'}"
                   if self.limit_violations else "") + ("; empty cut" if self.empty_cut else "")
        return (f"TurningReport({self.runs} run{plural}, {self.points} path points over "
                f"{self.revolutions:.6g} revolutions, machining {self.machining_time_s:.6g} s"
                f"{following_note(self.peak_following_error)}{flagged}; {len(self.notes)} "
                f"note{'' if len(self.notes) == 1 else 's'})")


def turn(program, machine, tool="nose:1.0:90", errors=None, *, servo=None,
         top: float = 0.0, allow_overtravel: bool = False
         ) -> tuple[TurnedPart, TurningReport]:
    """Cut ``program`` on the lathe ``machine`` with the turning engine (module docstring).

    Parameters
    ----------
    program : Program or str or Path
        The NC program (`machinesim.nc`, axis values SI), or an NC file's path (read with
        `machinesim.nc.read_program`'s defaults).
    machine : Machine or str
        A lathe: axes X, Z and a work spindle C about Z, e.g. ``"sts_lathe"`` (`check_lathe`;
        any other machine is refused, InputError).
    tool : str or RoundNoseTool
        The tool as programmed (``"nose:RADIUS_MM:ANGLE_DEG"``).
    errors : ErrorModel, dict or str or Path, optional
        The machine's errors (tool setting, tool geometry, geometric; None: the nominal
        machine), as a model, a dict in the TOML layout or a TOML file's path
        (`machinesim.errors.as_error_model`, as `cut` takes them).
    servo : ServoModel, optional
        Servo loops (``follow(t, q)``, columns in the machine's axis order); None: the axes
        follow exactly.
    top : float
        The stock's top, m (default 0: the face at Z = 0); finite and within `MOST_TOP_M`
        (1 m) of 0 either way, else InputError.
    allow_overtravel : bool
        Turn a program that takes an axis outside its travel, listing where, instead of
        refusing it.

    Returns
    -------
    (TurnedPart, TurningReport)

    Raises
    ------
    AxisLimitError
        When an axis leaves its travel (and ``allow_overtravel`` is False): the message names
        the axis, the value, the travel and the program's lines. Nothing is turned. Also
        when the servo's followed path leaves it where the command does not (with the
        line and the overshoot).
    """
    return _turn(program, machine, tool, errors, servo=servo, top=top,
                 allow_overtravel=allow_overtravel, truth_told=True)


def _turn(program, machine, tool, errors, *, servo, top: float, allow_overtravel: bool,
          truth_told: bool) -> tuple[TurnedPart | TurnedFace, TurningReport]:
    """`turn`; with ``truth_told`` False (`Lab.turn`: its errors are the lab's truth) the part
    is a `TurnedFace`, and an empty cut's note does not say how far above the stock the tip
    stayed (the tool setting and workpiece errors, to the digit)."""
    from machinesim.machines import Machine, load_machine
    from machinesim.nc import Program, read_program

    if isinstance(program, str | os.PathLike):
        program = read_program(program)
    elif not isinstance(program, Program):
        raise InputError(f"Expected program as a machinesim.nc.Program or an NC file's path, "
                         f"got {type(program).__name__}", key="program")
    machine = machine if isinstance(machine, Machine) else load_machine(machine)
    check_lathe(machine)
    tool = turning_tool(tool)
    top = as_number(top, "top")
    if abs(top) > MOST_TOP_M:
        raise InputError(f"Expected top within +-{MOST_TOP_M:g} m (the stock's top in the "
                         f"workpiece frame, m; the machines travel at most 0.5 m: was it "
                         f"given in mm or um?), got {top!r}", key="top")
    allow_overtravel = as_flag(allow_overtravel, "allow_overtravel")  # "no" is no True
    errors = None if errors is None else as_error_model(errors)
    machine.check_errors(errors)
    if servo is not None:  # as a Lab checks it: one column per axis, each named right
        check_servo(machine, servo)
    moves = _program_moves(program, machine)
    limits = _overtravel(machine, moves, program, allow_overtravel)
    # as `cut` refuses a move beyond FARTHEST_M (1 km), allowed overtravel or not: the
    # moves are straight in X and Z, so their ends bound the tool's distance
    _refuse_far(machine.tool_pose(modal_values(moves.q, start=machine.home), errors), moves,
                program)
    # the dwells and feed moves timed (and their total checked) before any run is turned
    waits, slow = _untimed_moves(program, machine)
    commanded = tool
    tool = with_nose_radius_error(tool, errors)
    paths, seconds, turns, peak = [], 0.0, 0.0, dict.fromkeys(machine.axes, 0.0)
    beyond = {entry.split(" ", 2)[1] for entry in limits}  # the axes the command takes out
    overshoots = []  # per run, `followed_beyond`'s axes: each listed once, at its worst
    for command_t, points, lines in _timed_runs(program, machine, with_lines=True):
        t, points, reached = follow_run(servo, command_t, points, lines, machine,
                                        getattr(program, "source", "<program>"),
                                        block_at=program.block_at)
        if reached is not points:  # refused at the first run that overshoots, or listed
            overshoots.append(followed_beyond(machine, command_t, lines, t, reached, beyond,
                                              block_at=program.block_at))
            refuse_followed(worst_beyond(machine, overshoots[-1]),
                            getattr(program, "source", None), allow_overtravel)
        for k, axis in enumerate(machine.axes):
            peak[axis] = max(peak[axis], float(np.max(np.abs(points[:, k] - reached[:, k]))))
        poses = machine.tool_pose(reached, errors)
        paths.append(edge_path_from_poses(poses, tool.nose_radius))
        seconds += float(t[-1])
        c = points[:, machine.axes.index("C")]
        turns += abs(float(c[-1] - c[0])) / (2.0 * math.pi)
    limits += worst_beyond(machine, *overshoots)
    part = TurnedPart(tuple(paths), tool, top)
    lowest = min(float(path.z.min()) for path in paths)
    empty = not lowest < top  # the nose's lowest point is its tip (`nose_profile`)
    above = f"{(lowest - top) * 1e6:.6g} um or more above" if truth_told else "above"
    notes = ((f"nothing was cut: the tool's tip stays {above} the stock's top "
              f"(z = {top * 1e6:.6g} um) throughout; does the program reach the stock, and do "
              "the errors set the tool too high or the workpiece too low (tool.z, "
              "workpiece.z)?",) if empty else ())
    if not truth_told:
        part = TurnedFace(part, commanded)
    seconds += waits
    notes += _rapids_below_top(program, machine, top) + slow
    report = TurningReport(sum(len(p) for p in paths), len(paths), seconds, turns, peak,
                           empty_cut=empty, limit_violations=limits, notes=notes)
    return part, report


def check_lathe(machine) -> None:
    """Refuse ``machine`` (a `Machine`) unless it is a lathe as the turning engine models one:
    a work spindle C (`Axis.spindle`) about Z, the tool moved in the XZ plane through the
    spindle axis by X (radial) and Z alone, as ``sts_lathe``. A table C of a few turns is a
    milling machine's, cut by `machinesim.cutting.cut`; a Y would take the tool off the
    spindle axis, an A or B turn it out of its edge plane (`edge_path_from_poses`)."""
    from machinesim.kinematics import SPINDLE_TRAVEL_RAD

    axes = machine.axes
    found = [f"no {letter} axis" for letter in ("X", "Z", "C") if letter not in axes]
    c = machine.axis("C") if "C" in axes else None
    if c is not None and not c.spindle:
        found.append(f"its C travels {math.degrees(c.lower):g} .. {math.degrees(c.upper):g} "
                     f"deg: a table's travel, not a work spindle's, beyond "
                     f"{SPINDLE_TRAVEL_RAD:g} rad ({SPINDLE_TRAVEL_RAD / (2 * math.pi):.3g} "
                     "turns: a spindle turns many in one program)")
    elif c is not None and c.direction != 2:
        found.append(f"its C turns about {'XYZ'[c.direction]}, not Z")
    extra = [letter for letter in axes if letter not in ("X", "Z", "C")]
    if extra:
        found.append(f"{'axes' if len(extra) > 1 else 'axis'} {', '.join(extra)}, which a "
                     "lathe has not (a Y takes the tool off the XZ plane through the spindle "
                     "axis, an A or B turns it out of its edge plane)")
    if found:
        raise InputError(f"Expected a lathe: a work spindle C about Z and the tool moved in "
                         f"the XZ plane by X and Z alone (axes X, Z, C, as sts_lathe); "
                         f"{machine.name} (axes {', '.join(axes)}): {'; '.join(found)}. "
                         "A milling machine (a C table's too) cuts with machinesim.cutting.cut",
                         key="machine")


def turning_tool(tool) -> RoundNoseTool:
    """``tool`` (a spec, ``"nose:RADIUS_MM:ANGLE_DEG"``, or a tool) as the `RoundNoseTool`
    the turning engine turns with; any other tool is refused."""
    tool = tool_from_spec(tool) if isinstance(tool, str) else tool
    if not isinstance(tool, RoundNoseTool):
        raise InputError(f"Expected a round-nose tool for turning ('nose:R:ANGLE'), got "
                         f"{type(tool).__name__}", key="tool")
    return tool


def followed(follow, t: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The axis values the servo loops (``follow(t, q)``, or None: exact) reach for a run.

    The axes enter the run already moving at its first step's speed, as on the machine,
    where the spindle is run up and the slides follow before the tool engages: the loops
    follow `LEAD_IN_S` of the first step's velocity before the run's start point, so they
    start it settled rather than from rest.
    """
    if follow is None:
        return points
    velocity = (points[1] - points[0]) / (t[1] - t[0]) if t[1] > t[0] else 0.0 * points[0]
    lead = np.linspace(-LEAD_IN_S, 0.0, LEAD_IN_SAMPLES + 1)[:-1]
    times = np.concatenate([lead + t[0], t])
    q = np.concatenate([points[0] + lead[:, None] * velocity, points])
    reached = np.asarray(follow(times, q), dtype=np.float64)
    if reached.shape != q.shape:
        raise InputError(f"servo.follow must return shape {q.shape}, got {reached.shape}",
                         key="servo")
    if not np.all(np.isfinite(reached)):
        raise InputError("servo.follow returned axis values that are not finite (NaN or inf): "
                         "nothing is turned with them", key="servo")
    return reached[LEAD_IN_SAMPLES:]


