"""Cut an NC program on a machine with errors: program -> motion -> poses -> material removal.

Every move removes material, rapids (G00) included: a rapid into the part is a crash, and
the part shows it. Rapids that met material still there when they ran are listed with their
lines; blocks outside the travel of an axis stop the cut (`AxisLimitError`) unless
``allow_overtravel`` is set, when they are cut and listed; a move that takes the tool's
holder into the part stops the cut (`HolderContactError`) unless ``allow_holder_contact`` is
set, when the body alone cuts and the lines are listed.
"""

from __future__ import annotations

import inspect
import math
import os
import time

import numpy as np

from machinesim import motion
from machinesim._keywords import keywords_checked
from machinesim.cutting.engine import remove
from machinesim.cutting.holder import holder_reach
from machinesim.cutting.holder_allowance import sweep_allowances
from machinesim.cutting.rapids import rapids_that_cut
from machinesim.cutting.refusals import (  # re-exported: windows, lathe, lathe_following
    _format,  # noqa: F401
    _holder_refusal,
    _more_lines,  # noqa: F401
    _overtravel,
    _refuse_far,
    _refuse_turning,
    block_at,  # noqa: F401
    line_text,  # noqa: F401
    refuse_far_ends,
    refuse_start_outside,
    subtraction_refusal,
)
from machinesim.cutting.report import (
    CutReport,
    arc_chord_note,
    nc_summary,
    no_moves_note,
    nothing_left_note,
    peak_following_error,
)
from machinesim.cutting.roi import check_roi_meets, roi_cells
from machinesim.cutting.run_check import check_runs_value
from machinesim.cutting.sheets import SheetReport, trim_sheets
from machinesim.cutting.sideways import dragged_past_clearance, within_edge_plane
from machinesim.cutting.tool_runs import _Moves, _ToolSections
from machinesim.errors import as_error_model
from machinesim.exceptions import InputError, ProgramTimeError, SubtractionError
from machinesim.metrology._arrays import as_flag
from machinesim.motion.faces import ProfileEdges
from machinesim.nc import MOVE_KINDS
from machinesim.nc.moves import ROTARY_AXES
from machinesim.servo import check_servo
from machinesim.tool_specs import tool_from_spec
from machinesim.tools import (
    Tool,
    check_path_chord,
    flat_face_radius,
    path_chord_tolerance,
)
from machinesim.workpiece import Part, stock_from_spec


def check_progress(progress) -> None:
    """Refuse a ``progress`` that is neither None nor callable: the engine called it only
    after the planning, with a TypeError."""
    if progress is not None and not callable(progress):
        raise InputError(f"Expected progress as a callable(done, total) or None, got "
                         f"{progress!r:.60}", key="progress")


def _run_progress(progress, number, line):
    """``progress`` for the run of one tool of a program with several, each run built and cut
    in turn, its sweeps counted on their own: a callable that takes a ``stage`` keyword is
    told the run's tool in it, ``stage="cutting (T18 from line 29)"``, as `machinesim cut`
    names the runs in its summary (the bar had shown "cutting 310/310", "building 384/384",
    "cutting 310/310" with no word of which count was which tool's); any other is left as
    it is."""
    if progress is None:
        return None
    try:
        inspect.signature(progress).bind(0, 0, stage="cutting")
    except (TypeError, ValueError):
        return progress
    name = ("--tool before the first change" if number is None
            else f"T{number} from line {line}")

    def told(done: int, total: int, stage: str = "cutting") -> None:
        progress(done, total, stage=f"{stage} ({name})")

    return told


def _arguments(program, tool, stock, errors):
    """`cut`'s program, tool, stock and errors as the objects it works on, or an InputError
    naming the argument and what it takes."""
    from machinesim.nc import Program, read_program

    if isinstance(tool, str):
        tool = tool_from_spec(tool)
    elif not isinstance(tool, Tool):
        raise InputError(f"Expected tool as a spec such as 'v:90' or a tool object "
                         f"(machinesim.tools), got {type(tool).__name__}", key="tool")
    if isinstance(program, str | os.PathLike):  # its arcs as fine as the tool is drawn
        program = read_program(program, chord_tolerance=path_chord_tolerance([tool]))
    elif not isinstance(program, Program):
        raise InputError(f"Expected program as a machinesim.nc.Program or an NC file's path, "
                         f"got {type(program).__name__}", key="program")
    if isinstance(stock, str):
        stock = stock_from_spec(stock)
    elif not isinstance(stock, Part):
        raise InputError(f"Expected stock as a spec such as 'block:10x10x2' or a Part, got "
                         f"{type(stock).__name__}", key="stock")
    return program, tool, stock, None if errors is None else as_error_model(errors)


@keywords_checked
def cut(program, machine, tool="v:90", stock="block:10x10x2", errors=None, *, roi=None,
        start=None, chord_tolerance: float | None = None, servo=None,
        progress=None, allow_overtravel: bool = False, allow_holder_contact: bool = False,
        check_runs: str = "turning") -> tuple[Part, CutReport]:
    """Run ``program`` on ``machine`` (with ``errors``) and return the machined part.

    Parameters
    ----------
    program : machinesim.nc.Program or str or Path
        A program, or the path of an NC file (read with `machinesim.nc.read_program`'s
        defaults, its arcs split within ``path_chord_tolerance([tool])``). A `Program`
        keeps the chords its arcs were read as: read at another tolerance than this cut
        follows (`parse_program`'s 1 nm under a ball or flat end mill), the report's notes
        say so (`report.arc_chord_note`).
    machine : machinesim.Machine or str
        A machine or a machine name.
    tool : str or tool
        ``"v:90"``, ``"nose:2.0:90"``, ``"ball:2.0"``, ``"flat:1.0"`` (mm, deg) or a tool object.
    stock : str or Part
        ``"block:10x10x2"``, ``"cylinder:5x2"`` (mm), optionally ``@x,y,z``, or a Part.
    errors : ErrorModel, dict or str or Path, optional
        The machine's injected errors (None: the nominal machine), as a model, a dict in the
        TOML layout or a TOML file's path (`machinesim.errors.as_error_model`).
    roi : sequence of (xmin, xmax, ymin, ymax), optional
        Windows in the workpiece frame (m): cut only there (see `engine.remove`).
    start : array_like, optional
        Axis values before the first block (default zeros).
    chord_tolerance : float, optional
        Rotary moves are split so the swept chord stays this close to the path (m), from
        1e-9 (the axes' resolution) to 1 (`machinesim.tools.check_path_chord`, as
        ``--chord-nm``). Default: `machinesim.tools.path_chord_tolerance` of the program's
        tools: 1 nm for a V or nose tool, 100 nm for a ball or flat end mill drawn within 1 um.
    servo : motion.ServoModel, optional
        Axis follow-up model (default ideal).
    progress : callable(done, total), optional
        Called as the engine works through the sweeps. With tool changes each tool's run is
        built and cut in turn, counted on its own, and a callable that takes a ``stage``
        keyword is told the run's tool in it: ``stage="cutting (T18 from line 29)"``.
    allow_overtravel : bool
        Cut a program that takes an axis outside its travel, listing where, instead of
        refusing it.
    allow_holder_contact : bool
        Cut a program that takes the tool deeper than its body (its holder, which is not
        modelled, would hit the part), the body alone cutting and the lines listed in
        `CutReport.holder_contact`, instead of refusing it. The part is then not what a
        real machine leaves: that one crashes.
    check_runs : {"turning", "all", "off"}
        Which runs of sweeps have their subtraction checked for material the boolean kernel
        left inside the sweeps (`machinesim.cutting.run_check`; cut again one sweep at a time
        where there is): those with a sweep that turns the tool (the default: where
        manifold3d was seen to leave such material, a rotary turn), every run (plain
        milling then takes 16-26 % longer), or none (docs/cutting.md).

    Returns
    -------
    part : Part
    report : CutReport
        Its ``notes`` end with those on ``errors`` (`machinesim.errors.notes.error_file_notes`:
        a value perhaps written in other units than its key asks, location errors of an axis
        the program keeps at zero, which move nothing), as ``machinesim cut --errors`` prints
        them. A `Lab`'s cut carries none: its errors are the truth.

    Raises
    ------
    AxisLimitError
        When an axis leaves its travel (and ``allow_overtravel`` is False): the message names
        the axis, the value, the travel and the program's lines. Nothing is cut.
    HolderContactError
        When a move takes the top of the tool's body, where its holder begins, below the top
        of the stock over it (and ``allow_holder_contact`` is False): the message names the
        program's lines, the tool's height and the stock's top. Nothing is returned.
    SubtractionError
        When a run of sweeps subtracted one at a time still leaves material inside them: the
        message names the program's lines. Nothing is returned.
    """
    return _cut(program, machine, tool, stock, errors, roi=roi, start=start,
                chord_tolerance=chord_tolerance, servo=servo, progress=progress,
                allow_overtravel=allow_overtravel, allow_holder_contact=allow_holder_contact,
                check_runs=check_runs, file_notes=True)


def _cut(program, machine, tool, stock, errors, *, file_notes: bool, roi=None, start=None,
         chord_tolerance: float | None = None, servo=None, progress=None,
         allow_overtravel: bool = False, allow_holder_contact: bool = False,
         check_runs: str = "turning") -> tuple[Part, CutReport]:
    """`cut`, its notes on ``errors`` added when ``file_notes``: `Lab.cut` passes False, its
    errors being the truth (a note names their keys and values). Its options default as
    `cut`'s (`Lab.cut` leaves out those it was not given)."""
    from machinesim.errors.notes import error_file_notes
    from machinesim.machines import Machine, load_machine

    began = time.perf_counter()
    if chord_tolerance is not None:  # as --chord-nm: 1 nm to 1 m, before any work
        chord_tolerance = check_path_chord(chord_tolerance)
    allow_overtravel = as_flag(allow_overtravel, "allow_overtravel")  # "no" is no True
    allow_holder_contact = as_flag(allow_holder_contact, "allow_holder_contact")
    check_runs = check_runs_value(check_runs)
    check_progress(progress)
    program, tool, stock, errors = _arguments(program, tool, stock, errors)
    check_roi_meets(roi, stock)
    machine = machine if isinstance(machine, Machine) else load_machine(machine)
    machine.check_errors(errors)
    if servo is not None:  # as a Lab checks it: one column per axis, each named right
        check_servo(machine, servo)
    _refuse_turning(program, machine, start)
    refuse_start_outside(machine, start, allow_overtravel)
    tools = _ToolSections(program, tool, errors)
    if chord_tolerance is None:
        chord_tolerance = path_chord_tolerance(t for _, t, _ in tools.runs)
    try:
        trajectory = motion.plan(program, machine, errors, start=start,
                                 tool_points=tools.points(), chord_tolerance=chord_tolerance,
                                 servo=servo,
                                 face_radius=flat_face_radius(t for _, t, _ in tools.runs),
                                 profile=ProfileEdges.of(tools.setups(), stock))
    except ProgramTimeError:  # a move out of the travel or 1 km away is the likelier cause
        refuse_far_ends(program, machine, errors, start, allow_overtravel)
        raise
    following = peak_following_error(trajectory, machine)
    moves = _Moves(trajectory, len(machine.axes))
    limits = _overtravel(machine, moves, program, allow_overtravel)
    poses = machine.tool_pose(moves.q, errors) if len(moves.q) else np.zeros((0, 4, 4))
    _refuse_far(poses, moves, program)
    part, engines, rapids, holder, sideways, sections = stock, [], [], set(), set(), []
    in_plane: set[int] = set()
    done: list = []  # the tools cut so far, with their paths
    own = np.broadcast_to(np.asarray(holder_tolerance(program, chord_tolerance, trajectory),
                                     dtype=np.float64), (len(trajectory.kinds),))
    floor, chorded = written_rounding(program), None
    for section_tool, length, section, (lo, hi), (number, line) in tools.split(moves):
        section_poses = poses[lo:hi] if length == 0.0 else poses[lo:hi] @ _beyond_tip(length)
        paths = np.split(section_poses, section.breaks) if len(section_poses) else []
        before = part
        refuse = None if allow_holder_contact else _holder_refusal(
            program, section_tool, before, section.sweep_line)
        allowance, lent = own[section.sweep_move], None
        if refuse is not None:  # its own chord, or one of the chorded cuts about its holder
            allowance, chorded, lent = sweep_allowances(section_tool, paths, allowance,
                                                        float(stock.bounds[1, 2]), floor,
                                                        chorded, carry=len(tools.runs) > 1)
        told = progress if len(tools.runs) == 1 else _run_progress(progress, number, line)
        try:
            part, engine = remove(before, section_tool, paths, roi=roi, progress=told,
                                  sheets=False, on_holder_contact=refuse,
                                  holder_stock=_outside_windows(stock, roi, done, section_tool,
                                                                paths, allow_holder_contact),
                                  holder_tolerance=allowance, holder_lent=lent,
                                  check_runs=check_runs)
        except SubtractionError as error:
            raise subtraction_refusal(error, program, section.sweep_line) from None
        done.append((section_tool, paths))
        rapids += rapids_that_cut(before, section_tool, section_poses, section,
                                   engine.reached, roi)
        holder |= {int(section.sweep_line[i]) for i in engine.holder_contact}
        sideways |= _feed_lines(section, engine.sideways, _dragged(section_poses))
        if not section_tool.rotational:
            in_plane |= _feed_lines(section, engine.reached, _in_edge_plane(section_poses))
        engines.append(engine)
        sections.append({"tool": number, "line": line, "length_m": length,
                         "removed_volume_m3": float(engine.removed_volume),
                         "empty_cut": bool(engine.empty_cut), "engine": engine.method})
    if not engines:  # no tool moved: the stock as it is, and an engine report saying so
        part, engine = remove(stock, tool, [], roi=roi, progress=progress)
        engines.append(engine)
    sheets, sheet_note = SheetReport(), None
    if any(e.method == "boolean" for e in engines):
        part, sheets, sheet_note = trim_sheets(part)
    removed = float(sum(e.removed_volume for e in engines) + sheets.volume)
    report = CutReport(
        removed_volume_m3=removed,
        machining_time_s=trajectory.duration,
        cutting_time_s=trajectory.cutting_time,
        sweeps=sum(int(e.n_sweeps_cut) for e in engines),
        substeps=trajectory.substeps,
        rapids_that_cut=tuple(dict.fromkeys(rapids)),
        limit_violations=limits,
        sideways_sweeps=sum(len(e.sideways) for e in engines),
        empty_cut=all(bool(e.empty_cut) for e in engines),
        engine="+".join(dict.fromkeys(e.method for e in engines)),
        elapsed_s=time.perf_counter() - began,
        notes=tuple(note for note in (no_moves_note(program), *trajectory.notes,
                                      *tools.notes, sheet_note,
                                      arc_chord_note(program, chord_tolerance),
                                      nothing_left_note(part, removed, roi),
                                      *(error_file_notes(errors, machine, program, start)
                                        if file_notes and errors is not None else ()))
                     if note),
        holder_contact=tuple(sorted(holder)),
        sideways_lines=tuple(sorted(sideways)),
        edge_plane_lines=tuple(sorted(in_plane)),
        peak_following_error=following,
        engine_s=sum(e.elapsed_s for e in engines),
        nc=nc_summary(program),
        tools=tuple(sections),
        thin_sheets=sheets.count,
    )
    return part, report


def holder_tolerance(program, chord_tolerance: float, trajectory) -> np.ndarray:
    """How far the holder of each move of ``trajectory`` may enter the material on its own
    account (m, shape (M,)): one chord of the move. A move the planner split (more than one
    sub-step: a rotary move, or one of an axis whose errors bend it) gets the chord
    tolerance it was split within, a chord of an arc the tolerance the arcs were read within
    (`Program.arc_chord_tolerance`; the reader keeps no arc length for the chords of an arc
    that turns a rotary axis, so a feed that turns one, in a program with arcs, gets it
    too), and the larger where both; any other move, straight and cut exactly, only the
    rounding of the words it was written with (`written_rounding`: sqrt(2) digits of the
    text's finest length word, 1.414 um at 3 decimals of mm, 100 nm at the least, whatever
    the chord tolerance). One arc read coarse, or one rotary move under a coarse
    ``--chord-nm``, anywhere in the program had given every move its chord, and a holder
    0.2 mm into a straight wall was cut.

    The holder at a chord's end meets the wall the body cut along another chord's middle,
    that much short of the arc, and a straight pass's holder meets the walls chorded moves
    cut: `holder_allowance.sweep_allowances` gives each sweep the largest of its own and of
    the chorded sweeps that cut next to its holder before (docs/cutting.md)."""
    count = len(trajectory.kinds)
    allowance = np.full(count, written_rounding(program))
    moving = trajectory.kinds != MOVE_KINDS.index("dwell")
    split = moving & (np.diff(trajectory.offsets) > 2)
    allowance[split] = np.maximum(allowance[split], chord_tolerance)
    read = getattr(program, "arc_chord_tolerance", None)
    if read is not None:
        lengths = getattr(program, "arc_lengths", None)
        arcs = (np.isfinite(lengths) if isinstance(lengths, np.ndarray)
                and lengths.shape == (count,) else np.zeros(count, dtype=bool))
        rotary = [k for k, axis in enumerate(trajectory.axes) if axis in ROTARY_AXES]
        first, last = trajectory.offsets[:-1], np.maximum(trajectory.offsets[1:] - 1, 0)
        turns = (trajectory.kinds == MOVE_KINDS.index("linear")) & (
            trajectory.q[first][:, rotary] != trajectory.q[last][:, rotary]).any(axis=1)
        arcs |= turns
        allowance[arcs] = np.maximum(allowance[arcs], float(read))
    return allowance


#: The least allowance of the holder on a straight move (m): that of a program built from
#: moves, and of one written to 5 decimals of mm or more (`written_rounding`). The text's
#: rounding, not the chord tolerance's: capped by it, a plunge cut at the default chord was
#: refused under --chord-nm 1. A straight pass 50 um into a wall is a crash at any
#: --chord-nm and any decimals.
WRITTEN_ROUNDING_M = 1e-7
#: The coarsest last digit a program's lengths are taken as written to (m): 3 decimals of
#: mm (G21, or no unit word) and 4 of inch (G20), as CAM posts write them. A hand-written
#: program of fewer decimals (``X1.5``) meant its positions as written, and gets no more.
COARSEST_DIGIT_M = {"G21": 1e-6, "G20": 2.54e-6}


def written_rounding(program) -> float:
    """The holder's allowance on a straight move of ``program`` (m): the rounding of the
    words it was written with, sqrt(2) d.

    d is `Program.length_digit`, what the last digit of the text's finest length word
    stands for, taken at most `COARSEST_DIGIT_M`. A position computed and then written lies
    up to d / 2 off in each coordinate. A plunge meant down a tilted tool's axis runs from a
    written start to a written end, both computed (a post writes the point above the hole
    along the axis too), so the written move's direction is off the axis by the difference
    of two roundings, up to d in each coordinate it changes. The holder follows the body
    down the hole the body drilled along the written move: h above the body's top it is
    where the body's top was h back along the move, h / L of the move's offset across the
    axis beside it (L the move's length), and h < L, so it enters the wall by less than
    that offset. The tool tilted by one rotary axis (B, in the Z-X plane, on every shipped
    machine), a move down its axis changes two coordinates, X and Z (one it does not change
    is the same word at both ends): at most sqrt(2) d across the axis. A tool tilted out of
    every plane of two linear axes changes three, up to sqrt(3) d, and such a plunge may
    still be refused. The finest word sets d: a program of 3 decimals with one word of 6 is
    allowed the 6 decimals' rounding.

    So 1.414 um at 3 decimals of mm, 3.592 um at 4 of inch, 141 nm at 4 of mm, and never
    below `WRITTEN_ROUNDING_M` (100 nm: 5 decimals of mm and more, and a program with no
    `length_digit`, built from moves). A compensated program (`Program.with_targets`)
    keeps the text's: the rounding of its words is still in its targets.
    """
    digit = getattr(program, "length_digit", None)
    if digit is None:
        return WRITTEN_ROUNDING_M
    coarsest = COARSEST_DIGIT_M["G20" if program.unit_in_force == "G20" else "G21"]
    return max(WRITTEN_ROUNDING_M, math.sqrt(2.0) * min(float(digit), coarsest))


def _outside_windows(stock: Part, roi, done: list, tool, paths: list,
                     allowed: bool) -> Part | None:
    """The material a later tool's holder is judged against when the part is cut within
    windows ``roi``: the part the engine is given holds only the windows, and the holder
    meeting the part outside them is a crash all the same. None where that part serves:
    no windows, the first tool (the engine judges it over ``stock``), or rooms of the
    holder (`holder_reach`) within one window. With ``allowed`` (holder contact allowed)
    the stock itself, whose box is all the listing reads. Otherwise the tools ``done``
    (tool, paths) are cut again from ``stock`` over the rooms' box alone."""
    if roi is None or not done:
        return None
    if allowed:
        return stock
    box = holder_reach(stock, tool, paths)
    if box is None:
        return None  # no sweep's holder comes below the stock's top over it
    (x0, y0, _), (x1, y1, _) = stock.bounds
    box = (max(box[0], x0), min(box[1], x1), max(box[2], y0), min(box[3], y1))
    if box[0] >= box[1] or box[2] >= box[3]:
        return None
    if any(c[0] <= box[0] and box[1] <= c[1] and c[2] <= box[2] and box[3] <= c[3]
           for c in roi_cells(roi, stock.bounds)):
        return None  # the part given holds all the rooms see
    material = stock
    for earlier, earlier_paths in done:
        material, _ = remove(material, earlier, earlier_paths, roi=[box], sheets=False)
    return material


def _beyond_tip(length: float) -> np.ndarray:
    """The pose of an edge ``length`` beyond ``tool_tip`` along the tool axis (-z)."""
    shift = np.eye(4)
    shift[2, 3] = -length
    return shift


def _feed_lines(moves: _Moves, sweeps, which) -> set[int]:
    """Lines of the feeds (a rapid that cuts is listed among the rapids) among ``sweeps``
    for which ``which(starts)`` holds, ``starts`` the sweeps' first poses."""
    sweeps = np.asarray(sweeps, dtype=np.int64)
    sweeps = sweeps[~moves.sweep_rapid[sweeps]]
    return {int(line) for line in moves.sweep_line[sweeps[which(moves.sweep_start[sweeps])]]}


def _dragged(poses: np.ndarray):
    """``which`` for `_feed_lines`: the sweeps that drag the tool sideways by more than
    `tolerances.SIDEWAYS_WARN_RAD` (`dragged_past_clearance`)."""
    return lambda first: dragged_past_clearance(poses, first)


def _in_edge_plane(poses: np.ndarray):
    """``which`` for `_feed_lines`: the sweeps that move a V or nose tool within its edge
    plane (`within_edge_plane`), where its zero-thickness edge removes nothing and a real
    tool would leave the imprint of its body."""
    return lambda first: within_edge_plane(poses[first, :3, :3],
                                           poses[first + 1, :3, 3] - poses[first, :3, 3])
