"""What `cut` refuses in a program, and how its messages name a program's lines.

A program that turns a work spindle (`cut` does not turn), takes the tool beyond
`FARTHEST_M` from the origin, takes an axis outside its travel (`AxisLimitError`, unless
allowed) or the tool's holder into the part (`HolderContactError`, unless allowed) is
refused naming its lines (``line 12 (N120)``). The turning engine
(`machinesim.cutting.lathe`) refuses by the same travel and distance checks.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import TYPE_CHECKING

import numpy as np

from machinesim.cutting.engine import FARTHEST_M
from machinesim.exceptions import (
    AxisLimitError,
    HolderContactError,
    NCProgramError,
    SubtractionError,
    line_of,
)
from machinesim.nc import AXES, Program
from machinesim.nc.program import modal_values
from machinesim.tolerances import LIMIT_SLACK

if TYPE_CHECKING:
    from machinesim.cutting.tool_runs import _Moves
    from machinesim.workpiece import Part


def _refuse_far(poses: np.ndarray, moves: _Moves, program) -> None:
    """Raise InputError when a move takes the tool beyond `FARTHEST_M` from the origin,
    naming the first such move's line (and the farthest's, where that is another): the
    farthest alone had named `G00 Z1.` after a `G01 X1000000.`, which went out first."""
    if not len(poses):
        return
    # hypot, not norm: a tool 1e304 m out squared to inf ('inf m', 'spacing nan m'), and a
    # distance not finite is beyond too (NaN > FARTHEST_M is False)
    where = poses[:, :3, 3]
    distance = np.hypot(np.hypot(where[:, 0], where[:, 1]), where[:, 2])
    beyond = ~(distance <= FARTHEST_M)
    if not beyond.any():
        return
    first = int(np.argmax(beyond))
    worst = int(np.argmax(np.where(np.isnan(distance), np.inf, distance)))
    farthest = ""
    if int(moves.line[worst]) != int(moves.line[first]):
        farthest = (f" (the farthest, {distance[worst]:.3g} m, at "
                    f"{line_text(program, int(moves.line[worst]))})")
    raise NCProgramError(
        f"the move takes the tool {distance[first]:.3g} m from the "
        f"workpiece origin{farthest}; expected within {FARTHEST_M:g} m, beyond any machine's "
        "travel, where float64 keeps no nanometre (its spacing there is "
        f"{np.spacing(distance[first]):.2g} m) and the part would come out wrong; nothing "
        "was cut. A length in the wrong unit is the usual cause",
        source=getattr(program, "source", None), line=int(moves.line[first]),
        block=block_at(program, int(moves.line[first])))


def refuse_far_ends(program, machine, errors, start, allow_overtravel: bool) -> None:
    """What `cut` refuses after planning, checked on ``program``'s move ends: an axis beyond
    its travel (unless ``allow_overtravel``), the tool beyond `FARTHEST_M`. Called where the
    planner refused the program's time in all (`machinesim.exceptions.ProgramTimeError`): a
    move a billion metres out at a feed took more than 2**39 s, and that refusal had
    replaced the one naming the distance, the likelier cause (a length in the wrong unit).
    The moves are straight in axis space, so their ends bound the axes' values."""
    axes = tuple(machine.axes)
    q0 = np.zeros(len(axes)) if start is None else np.asarray(start, dtype=np.float64)
    targets = np.asarray(program.targets)[:, [AXES.index(a) for a in axes]]
    q = modal_values(targets, start=q0)
    moves = SimpleNamespace(q=q, line=np.asarray(program.lines))
    _overtravel(machine, moves, program, allow_overtravel)
    _refuse_far(machine.tool_pose(q, errors), moves, program)


def refuse_start_outside(machine, start, allow: bool) -> None:
    """Raise AxisLimitError when ``start`` puts an axis outside its travel, unless ``allow``;
    checked before planning (a rapid from 100 m away is long to plan). A start in mm or deg
    (``[0, 0, 0.1, 90]`` for C at 90 deg) had been refused at the program's first line,
    naming a value the program never wrote there: an axis it does not move stays at start."""
    from machinesim.motion.planner import _start_values

    if start is None or allow:
        return
    q0 = _start_values(start, tuple(machine.axes))
    if q0.shape != (len(machine.axes),) or not np.isfinite(q0).all():
        return  # the planner refuses it, naming the shape or the values
    outside = machine.limit_violations(q0)
    if outside:
        raise AxisLimitError(
            f"start: {'; '.join(outside)}: the axes stand at start before the first block, "
            "and an axis the program does not move stays there (start is in m and rad, in "
            f"the order {''.join(machine.axes)}); nothing was cut (allow_overtravel=True cuts "
            "it anyway)")


def _overtravel(machine, moves: _Moves, program, allow: bool) -> tuple[str, ...]:
    """Descriptions of the blocks that take an axis outside its travel, with their lines.

    Raises AxisLimitError listing them all unless ``allow``.
    """
    if not len(moves.q):
        return ()
    found = []
    for i, letter in enumerate(machine.axes):
        low, high = machine.lower[i], machine.upper[i]
        bad = np.flatnonzero((moves.q[:, i] < low - LIMIT_SLACK)
                             | (moves.q[:, i] > high + LIMIT_SLACK))
        if not bad.size:
            continue
        lines = list(dict.fromkeys(int(n) for n in moves.line[bad]))
        worst = bad[np.argmax(np.maximum(low - moves.q[bad, i], moves.q[bad, i] - high))]
        unit = _format(machine.rotary[i], moves.q[worst, i], (low, high))
        found.append(f"axis {letter} = {unit(moves.q[worst, i])} at "
                     f"{line_text(program, int(moves.line[worst]))} outside its travel "
                     f"{unit(low)} .. "
                     f"{unit(high)}{_more_lines(lines)}")
    if found and not allow:
        source = getattr(program, "source", None)
        where = f"{source}: " if source else ""
        raise AxisLimitError(
            f"{where}{'; '.join(found)}; nothing was cut (allow_overtravel=True, "
            "machinesim cut --allow-overtravel on the command line, cuts it anyway and "
            "lists it)")
    return tuple(found)


def block_at(program, line: int) -> int | None:
    """The N word of ``program``'s block at ``line`` (`Program.block_at`), None when it has
    none or ``program`` is no `Program`."""
    return program.block_at(line) if isinstance(program, Program) else None


def line_text(program, line: int) -> str:
    """``line 12 (N120)``, or ``line 12`` when that block has no N word (`line_of`)."""
    return line_of(line, block_at(program, line))


def _more_lines(lines: list[int]) -> str:
    """`` (lines 3, 4, 9)`` after the first of several lines in a message (the first ten,
    then how many more); nothing for one line."""
    if len(lines) < 2:
        return ""
    tail = f" and {len(lines) - 10} more)" if len(lines) > 10 else ")"
    return f" (lines {', '.join(map(str, lines[:10]))}{tail}"


def _refuse_turning(program, machine, start) -> None:
    """Refuse a program that turns a work spindle (`Axis.spindle`) while it feeds, or starts
    one with M03/M04: that is turning, which `cut` does not do. Its engine moves a tool
    through the part one sweep at a time, and a tool whose edge lies in the plane it turns
    in cuts only a line per move: the part would come out as scratches, with exit 0."""
    from machinesim.nc.moves import AXES, KIND_RAPID
    from machinesim.nc.program import modal_values

    source = getattr(program, "source", None) or "<program>"
    lines = np.asarray(program.lines)
    how = ("turn it with the turning engine, in Python: machinesim.cutting.lathe.turn("
           "program, machine, tool) or Lab.turn (docs/lab.md), whose part is the turned "
           "face as an exact height field; the command line does not turn")
    for k, letter in enumerate(machine.axes):
        if not machine.axis(letter).spindle:
            continue
        for index, codes in sorted(program.m_codes.items()):
            if 3 in codes or 4 in codes:
                raise NCProgramError(
                    f"M0{3 if 3 in codes else 4} runs the work spindle {letter} of "
                    f"{machine.name}, which is turning: a spindle run by M03/M04 at S rpm is "
                    f"not simulated. Program {letter} as an axis (as a slow-tool-servo "
                    f"program does) and {how}", source=source, line=int(lines[index]),
                    block=block_at(program, int(lines[index])))
        begin = 0.0 if start is None else float(np.asarray(start, dtype=np.float64)[k])
        values = modal_values(np.asarray(program.targets)[:, [AXES.index(letter)]],
                              start=[begin])[:, 0]
        before = np.concatenate([[begin], values[:-1]])
        turning = np.flatnonzero((np.asarray(program.kinds) != KIND_RAPID)
                                 & (values != before) & np.isfinite(values))
        if turning.size:
            move = int(turning[0])
            raise NCProgramError(
                f"feeds while it turns the work spindle {letter} of {machine.name} "
                f"({np.degrees(before[move]):.6g} to {np.degrees(values[move]):.6g} deg), "
                f"which is turning, and `cut` does not turn (its tool would cut one line a "
                f"move); {how}", source=source, line=int(lines[move]),
                block=block_at(program, int(lines[move])))


def _holder_refusal(program, tool, stock: Part, sweep_line: np.ndarray):
    """An ``on_holder_contact`` for `engine.remove` that refuses the cut: raises
    `HolderContactError` naming the lines of the sweeps, the tool's height and the top of
    ``stock``."""
    def refuse(sweeps) -> None:
        lines = list(dict.fromkeys(int(sweep_line[i]) for i in sweeps))
        height = getattr(tool, "height", None)
        shank = float(getattr(tool, "shank_radius", 0.0) or 0.0)
        across = f", {2e3 * shank:.6g} mm across" if shank else ""
        body = ("" if height is None
                else f" ({height * 1e3:.6g} mm from its edge, where its holder begins{across})")
        source = getattr(program, "source", None)
        where = f"{source}: " if source else ""
        raise HolderContactError(
            f"{where}{line_text(program, lines[0])}{_more_lines(lines)} takes the top of the "
            "tool's "
            f"body{body} below the top of the stock (z = {stock.bounds[1, 2] * 1e3:.6g} mm): "
            "the holder would hit the part, and the body alone would leave material "
            "standing over a tunnel; nothing was cut. Use a longer tool (--tool ...:h=MM, "
            "the tool's height) or a shallower cut; allow_holder_contact=True "
            "(machinesim cut --allow-holder-contact on the command line) cuts the body "
            "alone and lists the lines")
    return refuse


def subtraction_refusal(error: SubtractionError, program,
                        sweep_line: np.ndarray) -> SubtractionError:
    """``error`` (`engine.remove`'s, naming sweeps of a tool's run) naming the program's
    lines of those sweeps (``sweep_line``: the line of each sweep of the run)."""
    lines = list(dict.fromkeys(int(sweep_line[i]) for i in error.sweeps))
    if not lines:
        return error
    source = getattr(program, "source", None)
    where = f"{source}: " if source else ""
    return SubtractionError(f"{where}{line_text(program, lines[0])}{_more_lines(lines)}: "
                            f"{error}", sweeps=error.sweeps)


def _format(rotary: bool, value: float | None = None, limits=()):
    """A formatter of axis values in deg or mm: 5 or 6 decimals, more when ``value`` would
    print as one of ``limits`` (a value just past a travel of 1e5 rad)."""
    scale, unit = (np.degrees(1.0), "deg") if rotary else (1e3, "mm")
    decimals = 5 if rotary else 6
    while decimals < 12 and value is not None and any(
            f"{value * scale:.{decimals}f}" == f"{limit * scale:.{decimals}f}"
            for limit in limits):
        decimals += 1
    # beyond 1e15 mm (deg) float64's spacing is 0.125 and more, the decimals noise: a value
    # of 1e307 mm had been printed with its 308 digits and 6 decimals
    return lambda v: (f"{v * scale:.{decimals}f} {unit}" if abs(v * scale) < 1e15
                      else f"{v * scale:.6g} {unit}")
