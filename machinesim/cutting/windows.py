"""The fast path for parts cut face by face at many C positions: each C group in its own frame.

`cut_turned` makes the part `machinesim.cutting.cut` makes (tested to 1e-12 in volume and
height) for a program whose feed moves each run at one of a few positions of a rotary axis
about the workpiece Z (a crown's eight faces at C = k 45 deg, paper 002). The booleans of
sweeps turned 45 deg off the machine axes are 4-5 times slower than of sweeps along them
(measured: 105 side passes, 9.8 s at C = 45 deg, 2.2 s at 0), so the feed moves are grouped
by that axis' value, rounded to ``turn_step``, and each group is cut in the part turned back
by its angle. `clip_to` cuts a stock down to measuring windows first.
"""

from __future__ import annotations

import math
import time

import manifold3d
import numpy as np

from machinesim import motion
from machinesim.cutting.engine import EMPTY_SWEPT_REL, remove
from machinesim.cutting.holder import check_holder
from machinesim.cutting.holder_allowance import sweep_allowances
from machinesim.cutting.program import (
    _holder_refusal,
    _overtravel,
    check_progress,
    holder_tolerance,
    written_rounding,
)
from machinesim.cutting.refusals import subtraction_refusal
from machinesim.cutting.report import (
    CutReport,
    arc_chord_note,
    nc_summary,
    nothing_left_note,
    peak_following_error,
)
from machinesim.cutting.roi import check_roi_meets
from machinesim.cutting.run_check import check_runs_value
from machinesim.cutting.sheets import trim_sheets
from machinesim.cutting.sideways import dragged_past_clearance
from machinesim.cutting.tool_runs import _Moves
from machinesim.errors import as_error_model
from machinesim.exceptions import InputError, SubtractionError
from machinesim.metrology._arrays import as_flag, as_number
from machinesim.motion.faces import ProfileEdges
from machinesim.nc import MOVE_KINDS
from machinesim.rotations import rot_z
from machinesim.tool_specs import tool_from_spec
from machinesim.tools import check_path_chord, flat_face_radius
from machinesim.units import M_PER_MM
from machinesim.workpiece import Part, stock_from_spec

__all__ = ["clip_to", "cut_turned"]

#: The clipping boxes reach this far past the stock above it (and below, without a floor), m.
CLIP_PAD = 1.0 * M_PER_MM


def clip_to(stock: Part, boxes, floor: float | None = None) -> Part:
    """The stock inside the boxes (x0, x1, y0, y1), m, above ``floor`` (m; default all)."""
    low, high = stock.bounds
    bottom = low[2] - CLIP_PAD if floor is None else floor
    pieces = [manifold3d.Manifold.cube((x1 - x0, y1 - y0, high[2] + CLIP_PAD - bottom))
              .translate((x0, y0, bottom)) for x0, x1, y0, y1 in boxes]
    return Part(stock.manifold ^ manifold3d.Manifold.batch_boolean(pieces,
                                                                   manifold3d.OpType.Add))


def _holder_lines(program, machine, errors, tool, stock: Part, feeds: list,
                  allowed: bool, own: np.ndarray, floor: float) -> set[int]:
    """The lines of the feeds ``feeds`` (the trajectory's linear segments, in the program's
    order) whose holder meets ``stock``, judged in that order over the whole stock
    (`holder.check_holder`); unless ``allowed``, the cut is refused there
    (`HolderContactError`). The turn groups are cut in another order, and a group's own
    check read the part as the groups before it had left it: a pass at C = 0 in the slot a
    pass at C = 90 deg cut before it was refused when the C = 0 group came first, where
    `machinesim.cutting.cut` cuts it. The holder may enter the material by one chord, each
    feed's own (``own``, m, one per feed: `program.holder_tolerance`) or that of the chorded
    feeds before it about its holder (``floor`` the allowance of a feed that is no chord:
    `holder_allowance.sweep_allowances`)."""
    if not feeds:
        return set()
    paths = machine.tool_poses([s.q for s in feeds], errors)
    counts = [max(len(s.q) - 1, 1) for s in feeds]
    sweep_line = np.repeat([s.line for s in feeds], counts)
    refuse = None if allowed else _holder_refusal(program, tool, stock, sweep_line)
    tolerance, lent = np.repeat(own, counts), None
    if refuse is not None:
        tolerance, _, lent = sweep_allowances(tool, paths, tolerance,
                                              float(stock.bounds[1, 2]), floor)
    return {int(sweep_line[i])
            for i in check_holder(stock, tool, paths, refuse, tolerance, lent)}


def cut_turned(program, machine, tool="v:90", stock="block:10x10x2", errors=None, *,
               roi=None, floor: float | None = None, start=None, turn_step: float = math.pi / 4,
               turn_axis: str = "C", chord_tolerance: float = motion.CHORD_TOLERANCE_M,
               servo=None, allow_overtravel: bool = False,
               allow_holder_contact: bool = False, progress=None, check_runs: str = "turning"
               ) -> tuple[Part, CutReport]:
    """Cut ``program`` as `machinesim.cutting.cut` does, each turn group in its own frame.

    The feed moves are grouped by the value of ``turn_axis`` at their start, rounded to a
    multiple k of ``turn_step``; each group's sweeps are subtracted from the part turned by
    -k ``turn_step`` about the workpiece Z, with the poses turned alike, and the part turned
    back. Rapids are neither cut nor checked against the part (the program must keep them
    above it; the report says so in its notes). The holder is judged before any group is
    cut, over the feeds in the program's order and the whole stock, windows or not
    (`_holder_lines`): the material a holder meets is what the feeds before it left.

    Parameters
    ----------
    program : Program
    machine : Machine
    tool, stock
        As `machinesim.cutting.cut`.
    errors : ErrorModel, dict or str or Path, optional
        The machine's errors (None: the nominal machine), as `machinesim.cutting.cut` takes
        them (`machinesim.errors.as_error_model`).
    roi : sequence of (x0, x1, y0, y1), optional
        Cut only inside these boxes (m): the stock is clipped to them first (`clip_to`),
        and below ``floor`` (m) if given.
    floor : float, optional
    start : array_like, optional
        Axis values before the first block (default zeros).
    turn_step : float
        rad, > 0.
    turn_axis : str
        The rotary axis about the workpiece Z whose positions group the feed moves.
    chord_tolerance, servo, allow_overtravel, allow_holder_contact, check_runs
        As `machinesim.cutting.cut` (an axis outside its travel raises `AxisLimitError`
        unless ``allow_overtravel``, a holder that would hit the part `HolderContactError`
        unless ``allow_holder_contact``; a subtraction that leaves material `SubtractionError`).
    progress : callable(done, total), optional
        Called before the first group and after each, in feed sweeps (a group's sweeps
        count as done once its cut is).

    Returns
    -------
    part : Part
    report : CutReport
        ``sweeps`` counts the feed sweeps that reached the material; ``sideways_sweeps`` those
        the engine flags as dragging the tool across its edge. Its ``notes`` end with those
        on ``errors``, as `machinesim.cutting.cut`'s (a `Lab`'s cut carries none).
    """
    return _cut_turned(program, machine, tool, stock, errors, roi=roi, floor=floor,
                       start=start, turn_step=turn_step, turn_axis=turn_axis,
                       chord_tolerance=chord_tolerance, servo=servo,
                       allow_overtravel=allow_overtravel,
                       allow_holder_contact=allow_holder_contact, progress=progress,
                       check_runs=check_runs, file_notes=True)


def _cut_turned(program, machine, tool, stock, errors, *, file_notes: bool, roi=None,
                floor: float | None = None, start=None, turn_step: float = math.pi / 4,
                turn_axis: str = "C", chord_tolerance: float = motion.CHORD_TOLERANCE_M,
                servo=None, allow_overtravel: bool = False,
                allow_holder_contact: bool = False, progress=None,
                check_runs: str = "turning") -> tuple[Part, CutReport]:
    """`cut_turned`, its notes on ``errors`` added when ``file_notes`` (`Lab.cut` passes
    False: its errors are the truth). Its options default as `cut_turned`'s (`Lab.cut`
    leaves out those it was not given)."""
    from machinesim.errors.notes import error_file_notes
    from machinesim.machines import Machine, load_machine

    began = time.perf_counter()
    chord_tolerance = check_path_chord(chord_tolerance)
    machine = machine if isinstance(machine, Machine) else load_machine(machine)
    allow_overtravel = as_flag(allow_overtravel, "allow_overtravel")  # "no" is no True
    allow_holder_contact = as_flag(allow_holder_contact, "allow_holder_contact")
    check_runs = check_runs_value(check_runs)
    check_progress(progress)
    # a dict in the TOML layout or a TOML file's path, as `cut` takes them: the notes on
    # them read an ErrorModel's, and a dict ended the whole cut with an AttributeError
    errors = None if errors is None else as_error_model(errors)
    tool = tool_from_spec(tool) if isinstance(tool, str) else tool
    stock = stock_from_spec(stock) if isinstance(stock, str) else stock
    check_roi_meets(roi, stock)
    if turn_axis not in machine.axes:
        raise InputError(f"{machine.name} has no axis {turn_axis} (axes "
                         f"{''.join(machine.axes)})", key="turn_axis")
    turn_step = as_number(turn_step, "turn_step", sign="> 0", unit="rad")  # not "0.5", True
    machine.check_errors(errors)
    trajectory = motion.plan(program, machine, errors, start=start,
                             tool_points=tool.vertices(), chord_tolerance=chord_tolerance,
                             servo=servo, face_radius=flat_face_radius([tool]),
                             profile=ProfileEdges.of([(tool, 0.0)], stock))
    limits = _overtravel(machine, _Moves(trajectory, len(machine.axes)), program,
                         allow_overtravel)
    part = stock if roi is None else clip_to(stock, roi, floor)
    column = machine.axes.index(turn_axis)
    groups: dict[int, list] = {}
    linear = trajectory.kinds == MOVE_KINDS.index("linear")
    feeds = [trajectory.segment(int(k)) for k in np.flatnonzero(linear)]
    for segment in feeds:
        key = int(round(float(segment.q[0, column]) / turn_step))
        groups.setdefault(key, []).append(segment)
    own = np.broadcast_to(np.asarray(holder_tolerance(program, chord_tolerance, trajectory),
                                     dtype=np.float64), linear.shape)[linear]
    holder = _holder_lines(program, machine, errors, tool, stock, feeds, allow_holder_contact,
                           own, written_rounding(program))
    removed = swept = engine_s = 0.0
    sweeps = sideways = 0
    sideways_lines: set[int] = set()
    step_deg = math.degrees(turn_step)
    total = sum(len(s.q) - 1 for segments in groups.values() for s in segments)
    done = 0
    if progress is not None:
        progress(done, total)
    for key, segments in groups.items():
        turn = np.eye(4)
        turn[:3, :3] = rot_z(-key * turn_step)
        turned = Part(part.manifold.rotate((0.0, 0.0, -step_deg * key)))
        paths = [turn @ poses for poses in machine.tool_poses([s.q for s in segments], errors)]
        sweep_line = np.repeat([s.line for s in segments], [len(s.q) - 1 for s in segments])
        # the holder was judged before, in the program's order (`_holder_lines`)
        try:
            cut_part, report = remove(turned, tool, paths, sheets=False, check_runs=check_runs)
        except SubtractionError as error:
            raise subtraction_refusal(error, program, sweep_line) from None
        part = Part(cut_part.manifold.rotate((0.0, 0.0, step_deg * key)))
        sweeps += report.n_sweeps_cut
        sideways += len(report.sideways)
        if report.sideways:  # the feeds among them that a real tool would not cut cleanly
            drags = np.array(report.sideways)
            offsets = np.cumsum([0] + [len(path) for path in paths[:-1]])
            starts = np.concatenate([o + np.arange(len(path) - 1)
                                     for o, path in zip(offsets, paths, strict=True)])[drags]
            beyond = dragged_past_clearance(np.concatenate(paths), starts)
            sideways_lines.update(sweep_line[drags[beyond]].tolist())
        removed += report.removed_volume
        swept += report.swept_volume
        engine_s += report.elapsed_s
        done += sum(len(s.q) - 1 for s in segments)
        if progress is not None:
            progress(done, total)
    part, sheets, sheet_note = trim_sheets(part)
    total_removed = float(removed + sheets.volume)
    return part, CutReport(
        removed_volume_m3=total_removed, machining_time_s=trajectory.duration,
        cutting_time_s=trajectory.cutting_time, sweeps=sweeps, substeps=trajectory.substeps,
        rapids_that_cut=(), limit_violations=limits, sideways_sweeps=sideways,
        empty_cut=not removed > EMPTY_SWEPT_REL * swept, engine="boolean, turned groups",
        elapsed_s=time.perf_counter() - began,
        notes=tuple(note for note in (
            *trajectory.notes, "rapids not cut nor checked against the part (turned groups)",
            sheet_note, arc_chord_note(program, chord_tolerance, takes_path=False),
            nothing_left_note(part, total_removed, roi),
            *(error_file_notes(errors, machine, program, start)
              if file_notes and errors is not None else ())) if note),
        holder_contact=tuple(sorted(holder)), engine_s=engine_s, nc=nc_summary(program),
        thin_sheets=sheets.count, sideways_lines=tuple(sorted(sideways_lines)),
        peak_following_error=peak_following_error(trajectory, machine))
