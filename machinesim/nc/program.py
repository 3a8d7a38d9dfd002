"""The parsed NC program as immutable arrays: `Program`.

Everything here is SI (m for X Y Z, rad for A B C, s, m/s). A `Program` keeps its moves as
read-only arrays, one row per move (`Program.targets`, `kinds`, `feeds`, ...), so that a
program of 10^6 or 10^7 points costs tens of bytes per move and can be planned without
Python loops; `Program.moves` hands out `Move` values (`machinesim.nc.moves`) made on demand
from those rows. A `Program` checks on construction that its moves follow the modal rules of
the NC language (see `machinesim.nc`; the checks are in `machinesim.nc.checks`), so that
every `Program`, however it was made, can be written back as NC text.
`machinesim.nc.builder.ProgramBuilder` builds one in Python.
"""

from __future__ import annotations

import operator
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any, overload

import numpy as np

from machinesim.exceptions import NCProgramError, line_of
from machinesim.nc.checks import (
    _arc_lengths,
    _check,
    _exact_stops,
    _length_digit,
    _line_words,
    _m_codes,
    _states,
)
from machinesim.nc.moves import (  # noqa: F401  (re-exported: the names of this module before)
    _KIND_CODE,
    AXES,
    INTEGER_INPUTS,
    KIND_DWELL,
    KIND_LINEAR,
    KIND_RAPID,
    MOVE_KINDS,
    PROGRAM_END,
    ROTARY_AXES,
    SUBPROGRAM_CODES,
    WORK_OFFSETS,
    FrozenMapping,
    Move,
    _finite,
    _is_int,
    _trusted_move,
    axis_values,
    work_offsets_si,
)


def move_index(index: Any, n: int) -> int:
    """The move ``index`` names among ``n`` moves, counted from 0 (a negative one from the
    end), as a tuple reads an index: an integer (anything with ``__index__``: a NumPy
    integer, a bool) within -n .. n - 1, else IndexError; anything else (a float such as
    1.0, a string, None) TypeError, as a tuple refuses it. Both `Moves` and the planned
    trajectory's `machinesim.motion.Segments` read their indices so."""
    try:
        i = operator.index(index)
    except TypeError:
        raise TypeError(f"move indices must be integers or slices, not "
                        f"{type(index).__name__} ({index!r})") from None
    if not -n <= i < n:
        raise IndexError(f"move index {i} out of range for {n} moves")
    return i % n


class Moves(Sequence):
    """The moves of a `Program` as a read-only sequence of `Move` values made on demand.

    Indexing, slicing (gives a tuple), ``len`` and iteration work as on a tuple; equality
    compares with any sequence of moves.
    """

    __slots__ = ("_program",)

    def __init__(self, program: Program) -> None:
        self._program = program

    def __len__(self) -> int:
        return len(self._program._kinds)

    @overload
    def __getitem__(self, index: int) -> Move: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[Move, ...]: ...

    def __getitem__(self, index):
        if isinstance(index, slice):
            return tuple(self._program._move(i) for i in range(*index.indices(len(self))))
        return self._program._move(move_index(index, len(self)))

    def __iter__(self) -> Iterator[Move]:
        program = self._program
        return (program._move(i) for i in range(len(self)))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Moves):
            return self._program._same_moves(other._program)
        if isinstance(other, Sequence) and not isinstance(other, str):
            return len(other) == len(self) and all(a == b for a, b in zip(self, other, strict=True))
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._program)

    def __repr__(self) -> str:
        return f"Moves({len(self)} moves of {self._program.source!r})"


def modal_values(values: np.ndarray, start=None) -> np.ndarray:
    """Axis values block by block, modal: a NaN (an axis the block does not name) takes the
    value before it, the first block's from ``start`` (one value per column; default NaN,
    which stays until the axis is named).

    ``values`` (N, k) are target columns, such as ``Program.targets[:, columns]``."""
    values = np.asarray(values, dtype=np.float64)
    if start is not None:
        values = np.vstack([np.asarray(start, dtype=np.float64)[None], values])
    named = ~np.isnan(values)
    last = np.where(named, np.arange(len(values))[:, None], 0)
    np.maximum.accumulate(last, axis=0, out=last)
    held = values[last, np.arange(values.shape[1])]
    return held if start is None else held[1:]


def _readonly(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


class Program:
    """An NC program as a sequence of moves in SI machine coordinates.

    Parameters
    ----------
    moves : iterable of Move
        The blocks that move, dwell or carry M codes, in order.
    number : int or None
        The O number.
    source : str
        Where the program came from (a path, ``"<string>"`` or ``"<builder>"``).
    work_offsets : Mapping[str, Mapping[str, float]]
        Work offsets G54..G59 (axis letter -> m or rad) the targets were computed with; the
        writer emits coordinates relative to G54. Absent systems and axes are zero.
    states : Mapping[str, int], optional
        Words read as modal states without geometric effect (``"G40"``, ``"G05.1 Q1"``,
        ``"T1"``, ...) -> the first line each appeared on, for reports.
    integer_input : {"calculator", "increment"} or None
        How axis numbers without a decimal point were read (None: not read from text).
    tool_table : str or None
        Where the tool table the program was read with came from (its path), or None.

    Attributes
    ----------
    moves : Sequence of Move
        The moves, made on demand from the arrays below.
    targets : ndarray, shape (N, 6), float64
        Absolute machine axis values after each move, columns `AXES` (X Y Z in m, A B C in
        rad); NaN where the axis has no value yet. Once a column holds a value, every later
        row does (targets are modal).
    kinds : ndarray, shape (N,), int8
        Index into `MOVE_KINDS`: 0 rapid, 1 linear, 2 dwell.
    feeds : ndarray, shape (N,), float64
        Feed, m/s; NaN where `Move.feed_m_per_s` is None.
    dwells : ndarray, shape (N,), float64
        Dwell time, s.
    lines : ndarray, shape (N,), int64
        1-based source line of each move (an arc, a canned cycle or a subprogram call gives
        several moves with the line of its block).
    spindles : ndarray, shape (N,), float64
        Spindle speed, rev/min; NaN where None.
    block_numbers : ndarray, shape (N,), int64
        N words; -1 where None.
    m_codes : Mapping[int, tuple of int]
        Move index -> its M codes, for the moves that carry any.
    tool_changes : tuple of machinesim.nc.tooltable.ToolChange
        The tools put in the spindle and the moves they cut from (read from T and M06
        with a tool table; empty otherwise, and for programs built from moves).
    arc_blocks : int
        How many G02/G03 blocks were read (each run of a subprogram counted): their moves
        are chords within the reader's ``chord_tolerance``. 0 for programs built from moves.
    arc_chord_tolerance : float or None
        That ``chord_tolerance`` (m) when arcs were read (``arc_blocks`` > 0), else None:
        `machinesim.cutting.cut` notes a program whose arcs are chords finer or coarser than
        the tolerance it cuts with.
    length_digit : float or None
        What the last digit of the text's finest length word stands for, m: the unit of the
        length words (mm, or inch under G20) over 10 to the most digits written after the
        point in any of them (X Y Z I J K R Q; ``X1.2345`` in mm: 1e-7 m), or the unit a
        number without a point is read in (`integer_input`) where that is finer (not a zero
        without a point: ``Y0`` reads 0 in any unit). A position computed and then written
        is that text's rounding off the place it was computed for:
        `machinesim.cutting.program.written_rounding` allows the holder that much on a
        straight move. None when no length word was read, and for programs built from moves
        (`with_targets` keeps it).
    unit_words : Mapping[str, int]
        The length units the text selected (``"G20"`` inch, ``"G21"`` mm) -> the first line
        each appeared on. Empty when it selected neither: its lengths were read in mm (the
        reader's default), and for programs built from moves.
    unit_in_force : str or None
        The one of those the moves were read in: the last selected before the first motion
        (the reader refuses a switch after it). None where ``unit_words`` is empty.
    dwell_words : Mapping[int, str]
        The line of each dwell word the text wrote (G04's P or X, a canned cycle's P) -> that
        word as written (``"P1500"``, ``"X2."``), and of each hole that dwells a canned
        cycle's P kept from an earlier block -> that P and its line (``"P1500 of line 3"``;
        on a line read more than once, the P of its longest dwell), for notes on a dwell
        (its time is `dwells`). Empty for programs built from moves.
    integer_words : Mapping[str, int]
        The letters of the non-zero lengths and angles written without a decimal point
        (``X1``, ``R5``) -> the first line each appeared on: they read as
        ``integer_input`` says (mm under "calculator", increments otherwise). Empty for a
        text that wrote every such number with a point, and for programs built from moves.
    end_words : Mapping[str, int]
        The program end the text's main program reached (``"M30"`` or ``"M02"``) -> its
        line. Empty when the main program ran out at the end of the file without one (a
        FANUC control stops there with an alarm: a file cut short?), and for programs built
        from moves.
    arc_lengths : ndarray, shape (N,), float64
        For each chord of an arc (G02/G03) in its plane, the length of the piece of arc it
        stands for, m (NaN for every other move, and for the chords of an arc block that
        turns a rotary axis): the control holds F along the arc, so the chord takes that
        length over F, not its own (`machinesim.motion.timing`). For programs built from
        moves, their `Move.arc_length_m` (NaN where None); `moves` hands them back.
    exact_stops : ndarray, shape (K,), int64
        The moves that end in an exact stop (G09 in their block, or any block under G61):
        the control waits there until the axes are in position before the next block, so
        servo lag does not carry across it (`machinesim.motion.plan`). Sorted, unique;
        empty for programs built from moves.
    after_end : int or None
        The first line holding text after the % that ended the program (a FANUC control
        stops reading there: that text is not read), or None.

    All arrays are read-only.

    Raises
    ------
    NCProgramError
        When the moves break the modal rules: an axis dropped from the target, a dwell that
        moves, a linear move without feed after one with feed, a spindle speed that vanishes,
        a program end (M02/M30) before the last move.
    """

    __slots__ = ("_targets", "_kinds", "_feeds", "_dwells", "_lines", "_spindles", "_blocks",
                 "_m_codes", "number", "source", "work_offsets", "states", "integer_input",
                 "tool_table", "tool_changes", "arc_blocks", "arc_chord_tolerance",
                 "length_digit", "unit_words", "unit_in_force", "dwell_words", "_moves",
                 "exact_stops", "integer_words", "end_words", "after_end", "_arc_lengths")

    def __init__(
        self,
        moves: Iterable[Move] = (),
        number: int | None = None,
        source: str = "<moves>",
        work_offsets: Mapping[str, Mapping[str, float]] | None = None,
        *,
        states: Mapping[str, int] | None = None,
        integer_input: str | None = None,
        tool_table: str | None = None,
    ) -> None:
        moves = tuple(moves)
        for index, move in enumerate(moves):
            if not isinstance(move, Move):
                raise NCProgramError(f"move {index} must be a Move, got {type(move).__name__}",
                                     source=source, key="moves")
        n = len(moves)
        targets = np.full((n, len(AXES)), np.nan)
        column = {a: i for i, a in enumerate(AXES)}
        for row, move in enumerate(moves):
            for letter, value in move.target.items():
                targets[row, column[letter]] = value
        self._init(
            targets,
            np.array([_KIND_CODE[m.kind] for m in moves], dtype=np.int8),
            np.array([np.nan if m.feed_m_per_s is None else m.feed_m_per_s for m in moves],
                     dtype=np.float64),
            np.array([m.dwell_s for m in moves], dtype=np.float64),
            np.array([m.line for m in moves], dtype=np.int64),
            np.array([np.nan if m.spindle_rpm is None else m.spindle_rpm for m in moves],
                     dtype=np.float64),
            np.array([-1 if m.block_number is None else m.block_number for m in moves],
                     dtype=np.int64),
            {i: m.m_codes for i, m in enumerate(moves) if m.m_codes},
            number, source, work_offsets, states, integer_input, tool_table,
            arc_lengths=np.array([np.nan if m.arc_length_m is None else m.arc_length_m
                                  for m in moves], dtype=np.float64),
        )

    @classmethod
    def from_arrays(
        cls,
        targets: Any,
        kinds: Any,
        feeds: Any = None,
        dwells: Any = None,
        lines: Any = None,
        *,
        spindles: Any = None,
        block_numbers: Any = None,
        m_codes: Mapping[int, Iterable[int]] | None = None,
        number: int | None = None,
        source: str = "<arrays>",
        work_offsets: Mapping[str, Mapping[str, float]] | None = None,
        states: Mapping[str, int] | None = None,
        integer_input: str | None = None,
        tool_table: str | None = None,
        exact_stops: Any = None,
        arc_lengths: Any = None,
    ) -> Program:
        """A program from its arrays (layout as the attributes), checked like any program.

        ``feeds``, ``spindles`` and ``arc_lengths`` default to NaN (None), ``dwells`` to 0,
        ``lines`` to 1..N, ``block_numbers`` to -1 (None), ``exact_stops`` (move indices) to
        none. Arrays are copied.
        """
        def array(values: Any, dtype: type, name: str) -> np.ndarray:
            try:
                return np.array(values, dtype=dtype)
            except (TypeError, ValueError, OverflowError) as error:
                raise NCProgramError(f"{name} must be an array of {np.dtype(dtype).name}: "
                                     f"{error}", source=source, key=name) from None

        codes = array(kinds, np.int64, "kinds").reshape(-1)
        if ((codes < 0) | (codes >= len(MOVE_KINDS))).any():
            bad = int(codes[(codes < 0) | (codes >= len(MOVE_KINDS))][0])
            raise NCProgramError(f"kinds must be codes 0..{len(MOVE_KINDS) - 1} "
                                 f"({', '.join(MOVE_KINDS)}), got {bad}", source=source,
                                 key="kinds")
        kinds = codes.astype(np.int8)
        n = kinds.size
        targets = array(targets, np.float64, "targets")
        if targets.shape != (n, len(AXES)):
            raise NCProgramError(f"targets must have shape ({n}, {len(AXES)}) for {n} kinds, "
                                 f"got {targets.shape}", source=source, key="targets")

        def column(values: Any, default: float | int, dtype: type, name: str) -> np.ndarray:
            if values is None:
                return np.full(n, default, dtype=dtype)
            result = array(values, dtype, name)
            if result.shape != (n,):
                raise NCProgramError(f"{name} must have shape ({n},), got {result.shape}",
                                     source=source, key=name)
            return result

        program = object.__new__(cls)
        program._init(
            targets,
            kinds,
            column(feeds, np.nan, np.float64, "feeds"),
            column(dwells, 0.0, np.float64, "dwells"),
            column(np.arange(1, n + 1) if lines is None else lines, 1, np.int64, "lines"),
            column(spindles, np.nan, np.float64, "spindles"),
            column(block_numbers, -1, np.int64, "block_numbers"),
            {} if m_codes is None else m_codes,
            number, source, work_offsets, states, integer_input, tool_table,
            exact_stops=() if exact_stops is None else array(exact_stops, np.int64,
                                                             "exact_stops"),
            arc_lengths=column(arc_lengths, np.nan, np.float64, "arc_lengths"),
        )
        return program

    @classmethod
    def _from_parts(cls, targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes, *,
                    number, source, work_offsets, states, integer_input,
                    tool_table=None, tool_changes=(), arc_blocks=0,
                    unit_words=None, exact_stops=(), integer_words=None,
                    end_words=None, after_end=None, arc_chord_tolerance=None,
                    dwell_words=None, unit_in_force=None, arc_lengths=None,
                    length_digit=None) -> Program:
        """A program that takes the reader's arrays without copying them (still checked)."""
        program = object.__new__(cls)
        program._init(targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes, number,
                      source, work_offsets, states, integer_input, tool_table, tool_changes,
                      arc_blocks, unit_words, exact_stops, integer_words, end_words,
                      after_end, arc_chord_tolerance, dwell_words, unit_in_force, arc_lengths,
                      length_digit)
        return program

    def _init(self, targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes, number,
              source, work_offsets, states, integer_input, tool_table=None,
              tool_changes=(), arc_blocks=0, unit_words=None, exact_stops=(),
              integer_words=None, end_words=None, after_end=None,
              arc_chord_tolerance=None, dwell_words=None, unit_in_force=None,
              arc_lengths=None, length_digit=None) -> None:
        set_ = object.__setattr__
        set_(self, "after_end", None if after_end is None else int(after_end))
        set_(self, "source", source)
        set_(self, "number", number)
        set_(self, "work_offsets", work_offsets_si(work_offsets, source=source))
        if number is not None and (not _is_int(number) or number < 0):
            raise NCProgramError(f"number must be None or an int >= 0, got {number!r}",
                                 source=source, key="number")
        if integer_input is not None and integer_input not in INTEGER_INPUTS:
            raise NCProgramError(f"integer_input must be None or one of {INTEGER_INPUTS}, "
                                 f"got {integer_input!r}", source=source, key="integer_input")
        set_(self, "integer_input", integer_input)
        if tool_table is not None and not isinstance(tool_table, str):
            raise NCProgramError(f"tool_table must be None or a str (where the table came "
                                 f"from), got {tool_table!r}", source=source, key="tool_table")
        set_(self, "tool_table", tool_table)
        set_(self, "states", _states(states, source))
        set_(self, "tool_changes", tuple(tool_changes))
        set_(self, "arc_blocks", int(arc_blocks))
        set_(self, "arc_chord_tolerance", None if arc_chord_tolerance is None or not arc_blocks
             else float(arc_chord_tolerance))
        set_(self, "length_digit", _length_digit(length_digit, source))
        set_(self, "unit_words", _states(unit_words, source, "unit_words"))
        if unit_in_force is not None and unit_in_force not in self.unit_words:
            raise NCProgramError(f"unit_in_force must be None or one of unit_words "
                                 f"{sorted(self.unit_words)}, got {unit_in_force!r}",
                                 source=source, key="unit_in_force")
        set_(self, "unit_in_force", unit_in_force)
        set_(self, "integer_words", _states(integer_words, source, "integer_words"))
        set_(self, "end_words", _states(end_words, source, "end_words"))
        set_(self, "dwell_words", _line_words(dwell_words, source, "dwell_words"))
        codes = _m_codes(m_codes, len(kinds), source)
        for name, array in (("_targets", targets), ("_kinds", kinds), ("_feeds", feeds),
                            ("_dwells", dwells), ("_lines", lines), ("_spindles", spindles),
                            ("_blocks", blocks)):
            set_(self, name, _readonly(array))
        set_(self, "_m_codes", codes)
        set_(self, "exact_stops", _readonly(_exact_stops(exact_stops, len(kinds), source)))
        set_(self, "_arc_lengths", _readonly(_arc_lengths(arc_lengths, len(kinds), source)))
        set_(self, "_moves", Moves(self))
        _check(self)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"Program is immutable (cannot set {name!r})")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"Program is immutable (cannot delete {name!r})")

    @classmethod
    def from_moves(
        cls,
        moves: Iterable[Move],
        *,
        number: int | None = None,
        source: str = "<moves>",
        work_offsets: Mapping[str, Mapping[str, float]] | None = None,
    ) -> Program:
        """A program from moves (checked against the modal rules)."""
        return cls(tuple(moves), number, source, work_offsets)

    targets = property(lambda self: self._targets, doc="(N, 6) machine targets, SI, NaN unset")
    kinds = property(lambda self: self._kinds, doc="(N,) int8 index into MOVE_KINDS")
    feeds = property(lambda self: self._feeds, doc="(N,) feed m/s, NaN = None")
    dwells = property(lambda self: self._dwells, doc="(N,) dwell s")
    lines = property(lambda self: self._lines, doc="(N,) 1-based source lines")
    spindles = property(lambda self: self._spindles, doc="(N,) spindle rev/min, NaN = None")
    block_numbers = property(lambda self: self._blocks, doc="(N,) N words, -1 = None")
    m_codes = property(lambda self: self._m_codes, doc="move index -> M codes")
    moves = property(lambda self: self._moves, doc="the moves as a Sequence of Move")
    arc_lengths = property(lambda self: self._arc_lengths,
                           doc="(N,) the arc (m) each arc chord stands for, NaN = none")

    def block_at(self, line: int) -> int | None:
        """The N word of the block at source ``line`` (of its first move there), None when
        it has none or no move comes from that line."""
        at = np.flatnonzero(self._lines == line)
        block = int(self._blocks[at[0]]) if at.size else -1
        return None if block < 0 else block

    def line_text(self, line: int) -> str:
        """``line 12 (N120)`` for a source line whose block has an N word, else ``line 12``:
        how the cut's warnings and refusals name a line (`machinesim.exceptions.line_of`)."""
        return line_of(line, self.block_at(line))

    @property
    def axes(self) -> tuple[str, ...]:
        """Axis letters used by the program, in canonical order X Y Z A B C."""
        used = ~np.all(np.isnan(self._targets), axis=0)
        return tuple(a for a, u in zip(AXES, used, strict=True) if u)

    def _move(self, i: int) -> Move:
        row = self._targets[i]
        target = FrozenMapping((a, float(v)) for a, v in zip(AXES, row.tolist(), strict=True)
                               if v == v)
        feed = float(self._feeds[i])
        spindle = float(self._spindles[i])
        block = int(self._blocks[i])
        arc = float(self._arc_lengths[i])
        return _trusted_move(MOVE_KINDS[self._kinds[i]], target,
                             None if feed != feed else feed, float(self._dwells[i]),
                             int(self._lines[i]), None if block < 0 else block,
                             None if spindle != spindle else spindle,
                             self._m_codes.get(i, ()), None if arc != arc else arc)

    def _same_moves(self, other: Program) -> bool:
        return (
            np.array_equal(self._targets, other._targets, equal_nan=True)
            and np.array_equal(self._kinds, other._kinds)
            and np.array_equal(self._feeds, other._feeds, equal_nan=True)
            and np.array_equal(self._dwells, other._dwells)
            and np.array_equal(self._lines, other._lines)
            and np.array_equal(self._spindles, other._spindles, equal_nan=True)
            and np.array_equal(self._blocks, other._blocks)
            and dict(self._m_codes) == dict(other._m_codes)
            and np.array_equal(self.exact_stops, other.exact_stops)
            and np.array_equal(self._arc_lengths, other._arc_lengths, equal_nan=True)
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Program):
            return NotImplemented
        return (
            (self.number, self.source, self.work_offsets, self.states, self.integer_input,
             self.tool_table, self.unit_words, self.unit_in_force, self.tool_changes)
            == (other.number, other.source, other.work_offsets, other.states,
                other.integer_input, other.tool_table, other.unit_words, other.unit_in_force,
                other.tool_changes)
            and self._same_moves(other)
        )

    def with_targets(self, targets) -> Program:
        """The same program with new axis targets, shape (N, 6) in `AXES` order (m, rad; NaN
        where an axis has no value yet): kinds, feeds, dwells, lines, spindle speeds, block
        numbers, M codes, tool changes, exact stops and everything read with the text kept,
        `length_digit` too: targets moved from the text's (compensated) keep its rounding,
        as they keep its arcs' chords (`arc_chord_tolerance`)."""
        targets = np.array(targets, dtype=np.float64)
        if targets.shape != self._targets.shape:
            raise NCProgramError(f"expected targets of shape {self._targets.shape}, got "
                                 f"{targets.shape}", source=self.source, key="targets")
        return Program._from_parts(
            targets, self._kinds, self._feeds, self._dwells, self._lines, self._spindles,
            self._blocks, dict(self._m_codes), number=self.number, source=self.source,
            work_offsets=self.work_offsets, states=self.states,
            integer_input=self.integer_input, tool_table=self.tool_table,
            tool_changes=self.tool_changes, arc_blocks=self.arc_blocks,
            unit_words=self.unit_words, exact_stops=self.exact_stops,
            integer_words=self.integer_words, end_words=self.end_words,
            after_end=self.after_end, arc_chord_tolerance=self.arc_chord_tolerance,
            dwell_words=self.dwell_words, unit_in_force=self.unit_in_force,
            arc_lengths=self._arc_lengths, length_digit=self.length_digit)

    def __hash__(self) -> int:
        return hash((self.number, self.source, len(self._kinds)))

    def __reduce__(self):
        return (_rebuild, (self._targets, self._kinds, self._feeds, self._dwells, self._lines,
                           self._spindles, self._blocks, dict(self._m_codes), self.number,
                           self.source, {k: dict(v) for k, v in self.work_offsets.items()},
                           dict(self.states), self.integer_input, self.tool_table,
                           self.tool_changes, self.arc_blocks, dict(self.unit_words),
                           self.exact_stops, dict(self.integer_words),
                           dict(self.end_words), self.after_end, self.arc_chord_tolerance,
                           dict(self.dwell_words), self.unit_in_force, self._arc_lengths,
                           self.length_digit))

    def __len__(self) -> int:
        return len(self._kinds)

    def __iter__(self) -> Iterator[Move]:
        return iter(self._moves)

    def __repr__(self) -> str:
        return (f"Program({len(self)} moves, number={self.number!r}, source={self.source!r}, "
                f"axes={''.join(self.axes)!r})")


def _rebuild(targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes, number, source,
             work_offsets, states, integer_input, tool_table=None, tool_changes=(),
             arc_blocks=0, unit_words=None, exact_stops=(), integer_words=None,
             end_words=None, after_end=None, arc_chord_tolerance=None,
             dwell_words=None, unit_in_force=None, arc_lengths=None,
             length_digit=None) -> Program:
    """Unpickle a `Program` (the arrays come back writeable copies: made read-only again;
    one pickled before `Program.arc_lengths` or `Program.length_digit` has none)."""
    return Program._from_parts(targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes,
                               number=number, source=source, work_offsets=work_offsets,
                               states=states, integer_input=integer_input,
                               tool_table=tool_table, tool_changes=tool_changes,
                               arc_blocks=arc_blocks, unit_words=unit_words,
                               exact_stops=exact_stops, integer_words=integer_words,
                               end_words=end_words, after_end=after_end,
                               arc_chord_tolerance=arc_chord_tolerance,
                               dwell_words=dwell_words, unit_in_force=unit_in_force,
                               arc_lengths=arc_lengths, length_digit=length_digit)
