"""Compensation: rewrite an NC program so the real machine cuts what the nominal one would.

The last arrow of the data flow (shared/DESIGN.md): identified errors -> corrected
`Program`. Every compensation procedure maps programs the same way, by one rule:

The rule
--------
1. **Walk.** The program is walked move by move with the modal state of *all* axes of the
   machine, exactly as motion planning walks it (`machinesim.motion.plan`,
   ``cut(start=...)``): before the first block every axis is at ``start`` (default the
   machine's zero, ``np.zeros(n_axes)``), and an axis not yet programmed stays there. Each
   move so has a full axis vector (n_axes,), SI, in `Machine.axes` order
   (`program_axes`). An axis the machine lacks is an `NCProgramError`, as in planning.
2. **Map.** The full vectors of the motion blocks (rapid G00 and linear G01 alike: a
   rapid's target is where the tool goes) are mapped, all in one call: by a paper's own
   formulas (`map_program`) or through the identified model (`model_based`).
3. **Round.** Mapped values are rounded to the machine's resolution (`Machine.resolution`,
   1 nm and 0.00001 deg on the shipped machines) on the grid the NC text carries, i.e.
   relative to the program's G54 work offset, to the very float that `read_program` gives
   back (`to_resolution`). Writing the result with `write_program` and reading it back
   therefore gives exactly the same moves.
4. **Write.** Every motion block of the output carries *every* machine axis (its target is
   the full mapped vector): the output never depends on what a later reader assumes about an
   unprogrammed axis. A dwell (G04, or a block of M codes only) stays where the motion before
   it ended (the mapped target; before the first motion block it keeps its empty target: the
   machine is still at ``start``). Kinds, feeds, dwell times, spindle speeds, block numbers,
   M codes, source lines, tool changes (T words, with the table they were read with), the
   program number, source and work offsets are kept unchanged.

Incremental mode and work offsets need no special case: a `Program` holds absolute machine
targets (the parser has already applied G91 and G54..G59), and the writer emits absolute
G90 words relative to G54. An output pins every axis, so it is valid for the ``start`` it
was made with (the default zero is the planner's default too).

A move is compensated at its ends. The control interpolates linearly in axis space, so a
move that turns a rotary axis is exact only at its two ends; split such moves before
compensating when the path between them matters.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from machinesim import tolerances
from machinesim._keywords import keywords_checked
from machinesim.errors import as_error_model
from machinesim.exceptions import (
    AxisLimitError,
    InputError,
    MachineSimWarning,
    NCProgramError,
    line_of,
)
from machinesim.inverse import singular_note
from machinesim.machines import Machine, load_machine
from machinesim.metrology._arrays import as_flag, as_floats, shown
from machinesim.metrology.rtest import refuse_far_points
from machinesim.nc.moves import AXES, KIND_DWELL
from machinesim.nc.program import Program, modal_values
from machinesim.nc.writer import LINEAR_DECIMALS, ROTARY_DECIMALS
from machinesim.units import M_PER_MM, RAD_PER_DEG

__all__ = [
    "Compensated",
    "map_program",
    "model_based",
    "program_axes",
    "rewrite",
    "start_axes",
    "to_resolution",
]

#: A kept tool point (``model_based(point=...)``) is reached by moving the tip target by the
#: point's miss and solving again. The miss comes only from the orientation change of the
#: new solution, a second-order effect of a nanometre move, so two rounds reach round-off;
#: five leave room for a badly conditioned pose, and the residual is reported either way.
POINT_ITERATIONS = 5


@dataclass(frozen=True)
class Compensated:
    """A program compensated through the identified model, and what it could not match.

    Attributes
    ----------
    program : Program
        The compensated program (the rule of `machinesim.compensation`).
    unmatched : str
        Empty when every block's tool orientation was matched; else what the machine's axes
        cannot produce (`AxisSolution.unmatched`), e.g. a tilt about X on five axes.
    max_position_residual : float
        Largest distance, m, between where the kept tool point lands on the identified model
        and where the nominal program puts it on the nominal machine, before rounding to the
        resolution (which adds at most half a resolution step per axis: 0.5 nm for a
        linear one, r * step / 2 at the tool for a rotary one, r the tool point's
        distance from its line: 10.9 nm for 0.00001 deg at 125 mm; docs/compensation.md).
    max_rotation_residual : float
        Largest tool orientation left unmatched, rad (axis-angle norm), before rounding.
    singular : str
        Empty unless blocks stand at a singularity of the axes, where the orientation the
        axes turn the tool to at the poses around is left unmatched: the lines, the largest
        such turn in urad and its direction (`machinesim.inverse.singular_note`, also given
        as a `MachineSimWarning`). What the machine's structure can never match (a tilt on
        four axes) is only in ``unmatched``.
    """

    program: Program
    unmatched: str
    max_position_residual: float
    max_rotation_residual: float
    singular: str = ""

    def __repr__(self) -> str:
        left = "; ".join(x for x in (self.unmatched, self.singular) if x) or "all matched"
        return (f"Compensated({self.program!r}, position residual "
                f"{self.max_position_residual:.3g} m, rotation residual "
                f"{self.max_rotation_residual:.3g} rad before rounding; {left})")


def start_axes(machine: Machine, start=None) -> np.ndarray:
    """The axis values before the first block, (n_axes,), SI: ``start`` or zeros.

    The same convention and check as `machinesim.motion.plan`.
    """
    axes = machine.axes
    q = np.zeros(len(axes)) if start is None else as_floats(start, "start", "axis values (m, rad)")
    if q.shape != (len(axes),):
        raise InputError(f"start must have shape ({len(axes)},) for axes {''.join(axes)}, "
                         f"got {q.shape}", key="start")
    if not np.all(np.isfinite(q)):
        raise InputError(f"start must be finite, got {q.tolist()}", key="start")
    return q


def program_axes(program: Program, machine: Machine | str, *, start=None) -> np.ndarray:
    """The full axis vector of every move, walked with the modal state of all axes.

    Parameters
    ----------
    program : Program
    machine : Machine or str
    start : array_like, shape (n_axes,), optional
        Axis values before the first block (default zeros); axes not yet programmed are here.

    Returns
    -------
    q : ndarray, shape (len(program), n_axes)
        m and rad, `Machine.axes` order; a dwell repeats the position it waits at.

    Raises
    ------
    NCProgramError
        When the program moves an axis the machine does not have.
    """
    machine = _machine(machine)
    _check_program(program)
    targets = program.targets
    foreign = [k for k, letter in enumerate(AXES) if letter not in machine.axes]
    named = ~np.isnan(targets[:, foreign])
    if np.any(named):
        row = int(np.argmax(named.any(axis=1)))
        letter = AXES[foreign[int(np.argmax(named[row]))]]
        raise NCProgramError(
            f"axis {letter} is not on {machine.name} (axes {''.join(machine.axes)})",
            source=program.source, line=int(program.lines[row]), key=letter,
            block=program.block_at(int(program.lines[row])))
    columns = [AXES.index(letter) for letter in machine.axes]
    return modal_values(targets[:, columns], start=start_axes(machine, start))


def to_resolution(q, machine: Machine | str, work_offsets=None) -> np.ndarray:
    """Axis values rounded to the machine's resolution, as the NC text carries them.

    Each value is rounded to a whole number of resolution steps relative to the G54 work
    offset (the writer's reference) and returned as the float `read_program` makes of the
    written word: ``float(text) * unit + offset``. Writing and reading it back is exact.

    Parameters
    ----------
    q : array_like, shape (n_axes,) or (N, n_axes)
        m and rad, `Machine.axes` order.
    machine : Machine or str
    work_offsets : mapping, optional
        `Program.work_offsets`; only G54 matters (absent: zero).

    Returns
    -------
    ndarray, the shape of ``q``

    Raises
    ------
    InputError
        When an axis resolution is not a whole number of the NC word's increment (1 nm,
        0.00001 deg): the text could not carry it.
    """
    machine = _machine(machine)
    q = as_floats(q, "q", "axis values (m, rad)")  # text had raised numpy's ValueError
    if q.shape[-1:] != (len(machine.axes),) or q.ndim not in (1, 2):
        raise InputError(f"expected axis values of shape ({len(machine.axes)},) or "
                         f"(N, {len(machine.axes)}) for axes {''.join(machine.axes)}, "
                         f"got {q.shape}", key="q")
    if not np.isfinite(q).all():  # NaN had come back NaN: no value an NC word can carry
        raise InputError(f"expected finite axis values (m, rad), got {shown(q.tolist())}",
                         key="q")
    g54 = (work_offsets or {}).get("G54", {})
    offset = np.array([g54.get(a, 0.0) for a in machine.axes])
    # The parser reads a word as float(text) * unit + offset; n / scale is that float(text)
    # (IEEE division of two exact floats is correctly rounded, as float() of a decimal is).
    unit = np.where(machine.rotary, RAD_PER_DEG, M_PER_MM)
    scale = 10.0 ** np.where(machine.rotary, ROTARY_DECIMALS, LINEAR_DECIMALS)
    steps = _increments_per_step(machine, unit, scale)
    n = np.round((q - offset) / unit * scale / steps) * steps
    return (n / scale) * unit + offset


def rewrite(program: Program, machine: Machine | str, q, *, rounded: bool = True) -> Program:
    """The program with new axis values for its motion blocks (steps 3 and 4 of the rule).

    Parameters
    ----------
    program : Program
    machine : Machine or str
    q : array_like, shape (n_motion, n_axes)
        One row per motion block (rapid or linear), in program order; m and rad.
    rounded : bool
        Round to the machine's resolution (`to_resolution`). False keeps the exact floats
        (for analysis: the NC text would round them, so writing and reading back differs).

    Returns
    -------
    Program
        Every motion block with every machine axis; everything else unchanged.
    """
    machine = _machine(machine)
    _check_program(program)
    rounded = as_flag(rounded, "rounded")
    motion = [n for n, move in enumerate(program.moves) if move.kind != "dwell"]
    q = as_floats(q, "q", "axis values (m, rad)")
    shape = (len(motion), len(machine.axes))
    if q.shape != shape:
        raise InputError(f"expected axis values of shape {shape} (one row per motion block, "
                         f"axes {''.join(machine.axes)}), got {q.shape}",
                         source=program.source)
    bad = np.argwhere(~np.isfinite(q))
    if len(bad):  # NaN is an unprogrammed axis in a target: it had read as a dropped axis
        row, col = bad[0]
        raise InputError(f"axis {machine.axes[col]} of this motion block is given as "
                         f"{float(q[row, col])!r} ({len(bad)} value(s) not finite); expected "
                         "finite axis values (m, rad)", source=program.source,
                         line=program.moves[motion[row]].line, key=machine.axes[col])
    if rounded and len(q):
        q = to_resolution(q, machine, program.work_offsets)
    # each motion block's row, and a dwell the row of the motion before it (none before the
    # first: the machine is still at start)
    rows = np.cumsum(program.kinds != KIND_DWELL) - 1
    targets = np.full((len(program), len(AXES)), np.nan)
    columns = [AXES.index(a) for a in machine.axes]
    moved = rows >= 0
    targets[np.ix_(moved, columns)] = q[rows[moved]]
    return program.with_targets(targets)


@keywords_checked
def map_program(
    program: Program,
    machine: Machine | str,
    function: Callable[[np.ndarray], np.ndarray],
    *,
    start=None,
    rounded: bool = True,
) -> Program:
    """Compensate a program by a paper's own formulas (route 1).

    Parameters
    ----------
    program : Program
        Written for the nominal machine.
    machine : Machine or str
    function : callable
        ``function(q) -> q_compensated``: nominal axis values, shape (N, n_axes), one row per
        motion block with every axis (m and rad, `Machine.axes` order), to the compensated
        values of the same shape. Called once with all blocks (a fresh array it may change);
        not called when the program has no motion block.
    start : array_like, shape (n_axes,), optional
        Axis values before the first block (default zeros).
    rounded : bool
        Round to the machine's resolution (default; see `rewrite`).

    Returns
    -------
    Program
        By the rule of `machinesim.compensation`.

    Raises
    ------
    InputError
        When ``function`` returns something other than a finite (N, n_axes) array.
    """
    machine = _machine(machine)
    if not callable(function):
        # an array of compensated values given for the function raised "'numpy.ndarray'
        # object is not callable" from inside this module
        raise InputError(f"expected the compensation as a function q -> q_compensated of the "
                         f"(N, {len(machine.axes)}) axis values of the motion blocks (columns "
                         f"{' '.join(machine.axes)}, m and rad), got {type(function).__name__}"
                         f"{f' of shape {np.shape(function)}' if np.ndim(function) else ''}; "
                         "values computed before are given as lambda q: values",
                         key="function")
    nominal, motion = _motion_axes(program, machine, start)
    if not len(motion):
        return rewrite(program, machine, nominal, rounded=rounded)
    result = function(nominal.copy())
    shape = nominal.shape
    expected = (f"an array of shape {shape} (one row per motion block, columns "
                f"{' '.join(machine.axes)} in m and rad)")
    try:
        kind = np.asarray(result).dtype  # flags and text are no axis values (True: 1 m)
    except (TypeError, ValueError):
        raise InputError(f"the compensation function must return {expected}, got "
                         f"{type(result).__name__}", source=program.source) from None
    if kind.kind not in "iuf":  # judged before converting: complex had warned, then refused
        name = {"b": "bool", "U": "str", "S": "bytes", "O": "object"}.get(kind.kind, kind.name)
        got = f"an array of {name}" if np.ndim(result) else type(result).__name__
        raise InputError(f"the compensation function must return {expected}, of numbers, got "
                         f"{got}", source=program.source)
    mapped = np.asarray(result, dtype=np.float64)
    if mapped.shape != shape:
        raise InputError(f"the compensation function must return {expected}, got shape "
                         f"{mapped.shape}", source=program.source)
    bad = np.argwhere(~np.isfinite(mapped))
    if len(bad):
        row, col = bad[0]
        raise InputError(f"the compensation function returned {float(mapped[row, col])!r} for axis "
                         f"{machine.axes[col]} ({len(bad)} value(s) not finite); expected "
                         "finite values", source=program.source,
                         line=program.moves[motion[row]].line, key=machine.axes[col])
    _check_travel(program, machine, motion, nominal, mapped)
    return rewrite(program, machine, mapped, rounded=rounded)


@keywords_checked
def model_based(
    program: Program,
    machine: Machine | str,
    identified,
    *,
    start=None,
    point=None,
    rounded: bool = True,
) -> Compensated:
    """Compensate a program through the identified model (route 2), as a control would.

    For each motion block: the pose the nominal machine (no errors) gives the tool at the
    programmed axis values, then the axis values that put the tool at that pose on the
    identified model (`Machine.axis_values`, starting from the programmed values): the kept
    point exactly, the orientation as far as the machine's axes can produce it.

    Parameters
    ----------
    program : Program
        Written for the nominal machine.
    machine : Machine or str
    identified : ErrorModel, dict, TOML path or None
        The identified errors (None: the nominal machine, which returns the program); a
        fit's `Estimate` gives its model as ``estimate.errors``.
    start : array_like, shape (n_axes,), optional
        Axis values before the first block (default zeros).
    point : array_like, shape (3,), optional
        The tool point kept on the path, m, in the ``tool_tip`` frame (default the tip, its
        origin). It matters only where orientation is left unmatched.
    rounded : bool
        Round to the machine's resolution (default; see `rewrite`).

    Returns
    -------
    Compensated

    Warns
    -----
    MachineSimWarning
        When blocks stand at a singularity of the axes (`Compensated.singular`).

    Raises
    ------
    UnreachableError, AxisLimitError
        From `Machine.axis_values`, when no axis values (within travel) reach a pose.
    """
    machine = _machine(machine)
    if identified is not None:  # refused under its own name (an Estimate: use its .errors)
        identified = as_error_model(identified, key="identified")
    machine.check_errors(identified)
    p = (np.zeros(3) if point is None
         else as_floats(point, "point", "3 coordinates (m) in the tool_tip frame"))
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise InputError(f"point must be 3 finite coordinates (m) in the tool_tip frame, got "
                         f"{np.asarray(point).tolist()!r}", key="point")
    refuse_far_points(machine, p, "tool_tip", key="point",
                      what="a point of the tool kept on the path")
    nominal, motion = _motion_axes(program, machine, start)
    if not len(motion):
        return Compensated(rewrite(program, machine, nominal, rounded=rounded), "", 0.0, 0.0)
    target = machine.tool_pose(nominal)
    wanted = _points(target, p)
    solution = machine.axis_values(target, identified, q_start=nominal, check_limits=False)
    for _ in range(POINT_ITERATIONS if np.any(p) else 0):
        miss = wanted - _points(machine.tool_pose(solution.q, identified), p)
        if np.max(np.linalg.norm(miss, axis=1)) < tolerances.IK_POSITION_M:
            break
        target[:, :3, 3] += miss
        solution = machine.axis_values(target, identified, q_start=solution.q,
                                       check_limits=False)
    _check_travel(program, machine, motion, nominal, solution.q)
    miss = wanted - _points(machine.tool_pose(solution.q, identified), p)
    blocks = program.block_numbers
    singular = singular_note(machine, solution.singular_residual, lambda row: line_of(
        int(program.lines[motion[row]]),
        None if blocks[motion[row]] < 0 else int(blocks[motion[row]])))
    if singular:
        warnings.warn(f"{program.source}: {singular}", MachineSimWarning, stacklevel=2)
    return Compensated(
        program=rewrite(program, machine, solution.q, rounded=rounded),
        unmatched=solution.unmatched,
        max_position_residual=float(np.max(np.linalg.norm(miss, axis=1))),
        max_rotation_residual=float(np.max(np.linalg.norm(solution.rotation_residual,
                                                          axis=1))),
        singular=singular,
    )


def _check_travel(program: Program, machine: Machine, motion: list[int], nominal: np.ndarray,
                  q: np.ndarray) -> None:
    """Refuse compensated axis values outside the travel where the nominal ones were inside,
    naming the program's lines (`AxisLimitError`)."""
    slack = tolerances.LIMIT_SLACK
    lower, upper = machine.lower - slack, machine.upper + slack
    outside = ((q < lower) | (q > upper)) & (nominal >= lower) & (nominal <= upper)
    if not outside.any():
        return
    rows = np.flatnonzero(outside.any(axis=1))
    row = int(rows[0])
    i = int(np.flatnonzero(outside[row])[0])

    def shown(value):
        return machine.format_axis_value(i, value)

    # at the limit: within one resolution step of it, where a G28, the home or a start puts
    # the axis (1 mm or 1 mrad, as before, took a program running 1 um inside the travel
    # for one standing at its end, and blamed a G28 for a correction larger than the room)
    at_limit = min(abs(nominal[row, i] - machine.lower[i]),
                   abs(nominal[row, i] - machine.upper[i])) <= machine.resolution[i]
    hint = ("A correction cannot be made at the end of an axis' travel: a move to the "
            "reference position (G28) with the axis at its limit, or a start there "
            "(start=...), is the usual cause" if at_limit else
            "The correction is larger than the room the axis has there: check the "
            "identified errors' size and units")
    lines = sorted({int(program.lines[motion[r]]) for r in rows.tolist()})
    listed = ", ".join(map(str, lines[:10])) + (" ..." if len(lines) > 10 else "")
    raise AxisLimitError(
        f"{program.source}, line {lines[0]}: the compensated program takes axis "
        f"{machine.axes[i]} to {shown(q[row, i])}, outside "
        f"its travel {shown(machine.lower[i])} .. {shown(machine.upper[i])} (the program had "
        f"{shown(nominal[row, i])}); {len(lines)} line(s) need a value past a limit: "
        f"{listed}. {hint}")


def _check_program(program) -> None:
    """Refuse anything but a `Program` (a path or NC text is read first, `read_program`)."""
    if not isinstance(program, Program):
        raise InputError(f"expected the program as a machinesim.nc.Program, got "
                         f"{type(program).__name__} {shown(program)}; read an NC file with "
                         "machinesim.nc.read_program(path) (text: parse_program)",
                         key="program")


def _machine(machine: Machine | str) -> Machine:
    return machine if isinstance(machine, Machine) else load_machine(machine)


def _motion_axes(program: Program, machine: Machine, start) -> tuple[np.ndarray, list[int]]:
    """Full axis vectors (n_motion, n_axes) of the motion blocks, and their move indices.

    A ``start`` outside the travel is refused, as `cut` refuses it: C given as 90 (deg
    meant) had been written, 90 rad, into every block before the program's first C word."""
    outside = [] if start is None else machine.limit_violations(start_axes(machine, start))
    if outside:
        where = f"{program.source}: " if program.source else ""
        raise AxisLimitError(f"{where}start: {'; '.join(outside)}: an axis stays there, in "
                             "every block written, until the program moves it (start is in m "
                             f"and rad, in the order {''.join(machine.axes)})")
    q = program_axes(program, machine, start=start)
    motion = [n for n, move in enumerate(program.moves) if move.kind != "dwell"]
    return q[motion], motion


def _points(poses: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The point ``p`` of the tool_tip frame at each pose (N, 4, 4), in the workpiece frame."""
    return poses[:, :3, :3] @ p + poses[:, :3, 3]


def _increments_per_step(machine: Machine, unit: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Each axis resolution as a whole number of NC word increments (unit / scale)."""
    ratio = machine.resolution / (unit / scale)
    steps = np.round(ratio)
    # A URDF may give an angle resolution with fewer digits (1.74532925e-07 rad for
    # 0.00001 deg is 1e-9 relative off); 1e-6 accepts that and no resolution really off it.
    bad = (steps < 1) | (np.abs(ratio - steps) > 1e-6 * steps)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        increment = float(unit[i] / scale[i])
        si = "rad" if machine.rotary[i] else "m"
        word = (f"{10.0 ** -ROTARY_DECIMALS:g} deg ({increment!r} rad)" if machine.rotary[i]
                else f"{10.0 ** -LINEAR_DECIMALS * M_PER_MM:g} m")
        nearest = max(1.0, float(steps[i])) * increment
        raise InputError(f"{machine.path}: <machinesim:axis joint={machine.axes[i]!r}> "
                         f"resolution {float(machine.resolution[i])!r} ({si}) is not a whole "
                         f"number of the NC word's increment {word}, so an NC program cannot "
                         f"carry it; expected a whole number of increments, e.g. "
                         f"{nearest!r} {si}", key=machine.axes[i])
    return steps
