"""The parsed NC program as immutable values: `Move`, `Program` and `ProgramBuilder`.

Everything here is SI (m for X Y Z, rad for A B C, s, m/s). A `Program` keeps its moves as
read-only arrays, one row per move (`Program.targets`, `kinds`, `feeds`, ...), so that a
program of 10^6 or 10^7 points costs tens of bytes per move and can be planned without
Python loops; `Program.moves` hands out `Move` values made on demand from those rows.
A `Program` checks on construction that its moves follow the modal rules of the NC language
(see `machinesim.nc`), so that every `Program`, however it was made, can be written back as
NC text.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, overload

import numpy as np

from machinesim.exceptions import NCProgramError
from machinesim.units import M_PER_MM

#: Axis letters in their canonical order: linear (m), then rotary (rad); the columns of
#: `Program.targets`.
AXES = ("X", "Y", "Z", "A", "B", "C")
ROTARY_AXES = ("A", "B", "C")
#: Work coordinate systems selectable by G54..G59.
WORK_OFFSETS = ("G54", "G55", "G56", "G57", "G58", "G59")
#: M codes that end the program.
PROGRAM_END = (2, 30)
#: M codes of subprogram call (M98) and return (M99): control flow, never on a move.
SUBPROGRAM_CODES = (98, 99)
#: Move kinds; `Program.kinds` holds the index into this tuple.
MOVE_KINDS = ("rapid", "linear", "dwell")
KIND_RAPID, KIND_LINEAR, KIND_DWELL = 0, 1, 2
_KIND_CODE = {name: code for code, name in enumerate(MOVE_KINDS)}
INTEGER_INPUTS = ("calculator", "increment")


class FrozenMapping(Mapping):
    """An immutable, hashable mapping that keeps the order it was given.

    Parameters
    ----------
    items : iterable of (key, value) pairs
        Keys must be unique; values must be hashable for `hash` to work.
    """

    __slots__ = ("_dict", "_items")

    def __init__(self, items: Iterable[tuple[Any, Any]] = ()) -> None:
        pairs = tuple(items)
        object.__setattr__(self, "_items", pairs)
        object.__setattr__(self, "_dict", dict(pairs))

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __getitem__(self, key: Any) -> Any:
        return self._dict[key]

    def __iter__(self) -> Iterator[Any]:
        return iter(self._dict)

    def __len__(self) -> int:
        return len(self._items)

    def __hash__(self) -> int:
        return hash(frozenset(self._items))

    def __reduce__(self):
        return (type(self), (self._items,))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._dict!r})"


def _finite(value: Any, what: str, *, source: str, line: int | None, key: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise NCProgramError(
            f"{what} must be a real number, got {value!r}", source=source, line=line, key=key
        ) from None
    if not math.isfinite(number):
        raise NCProgramError(
            f"{what} must be finite, got {number!r}", source=source, line=line, key=key
        )
    return number


def axis_values(
    values: Mapping[str, Any] | Iterable[tuple[str, Any]],
    *,
    source: str = "<moves>",
    line: int | None = None,
) -> FrozenMapping:
    """Check axis letters and values and freeze them in the canonical order X Y Z A B C.

    Parameters
    ----------
    values : mapping or iterable of pairs
        Axis letter -> value in SI (m for X Y Z, rad for A B C).
    source, line : optional
        Where the values came from, for the error message.

    Returns
    -------
    FrozenMapping
        Axis letter -> float, letters in canonical order.
    """
    given = dict(values.items() if isinstance(values, Mapping) else values)
    for letter in given:
        if letter not in AXES:
            raise NCProgramError(
                f"unknown axis {letter!r}; expected one of {' '.join(AXES)}",
                source=source,
                line=line,
                key=str(letter),
            )
    return FrozenMapping(
        (a, _finite(given[a], f"axis {a}", source=source, line=line, key=a))
        for a in AXES
        if a in given
    )


@dataclass(frozen=True)
class Move:
    """One block of an NC program that moves, dwells, or carries M codes.

    Attributes
    ----------
    kind : {"rapid", "linear", "dwell"}
        G00, G01, or G04 (a block with M codes but no motion is a dwell of 0 s). Arcs and
        canned cycles arrive as the linear and rapid moves they expand to.
    target : Mapping[str, float]
        Absolute machine axis values after this block (m for X Y Z, rad for A B C), work
        offset and tool length offset applied; every axis given a value so far in the
        program (modal). Frozen.
    feed_m_per_s : float or None
        Feed rate in m/s for linear moves (the modal F); None for rapid and dwell, and for a
        linear move before any F.
    dwell_s : float
        Dwell time in s; 0.0 unless ``kind == "dwell"``.
    line : int
        1-based source line of the block (for built programs: the 1-based move index).
    block_number : int or None
        The N word of the block.
    spindle_rpm : float or None
        The modal S word, passed through (rev/min).
    m_codes : tuple of int
        The M words of this block, in source order, passed through.
    """

    kind: Literal["rapid", "linear", "dwell"]
    target: Mapping[str, float]
    feed_m_per_s: float | None = None
    dwell_s: float = 0.0
    line: int = 1
    block_number: int | None = None
    spindle_rpm: float | None = None
    m_codes: tuple[int, ...] = field(default=())

    def __post_init__(self) -> None:
        where = {"source": "<move>", "line": self.line if _is_int(self.line) else None}
        if not _is_int(self.line) or self.line < 1:
            raise NCProgramError(f"line must be an int >= 1, got {self.line!r}", key="line")
        if self.kind not in MOVE_KINDS:
            raise NCProgramError(
                f"kind must be one of {MOVE_KINDS}, got {self.kind!r}", **where, key="kind"
            )
        object.__setattr__(self, "target", axis_values(self.target, source="<move>",
                                                       line=self.line))
        if self.kind != "dwell" and not self.target:
            raise NCProgramError(f"a {self.kind} move needs at least one axis value",
                                 **where, key="target")
        if self.feed_m_per_s is not None:
            feed = _finite(self.feed_m_per_s, "feed", **where, key="feed_m_per_s")
            if self.kind != "linear" or feed <= 0.0:
                raise NCProgramError(
                    f"feed must be None for a {self.kind} move and > 0 for a linear move, "
                    f"got {feed!r}",
                    **where,
                    key="feed_m_per_s",
                )
            object.__setattr__(self, "feed_m_per_s", feed)
        dwell = _finite(self.dwell_s, "dwell time", **where, key="dwell_s")
        if dwell < 0.0 or (dwell != 0.0 and self.kind != "dwell"):
            raise NCProgramError(
                f"dwell_s must be >= 0 for a dwell and 0.0 otherwise, got {dwell!r} for a "
                f"{self.kind} move",
                **where,
                key="dwell_s",
            )
        object.__setattr__(self, "dwell_s", dwell)
        if self.block_number is not None and (
            not _is_int(self.block_number) or self.block_number < 0
        ):
            raise NCProgramError(f"block_number must be None or an int >= 0, got "
                                 f"{self.block_number!r}", **where, key="block_number")
        if self.spindle_rpm is not None:
            rpm = _finite(self.spindle_rpm, "spindle speed", **where, key="spindle_rpm")
            if rpm < 0.0:
                raise NCProgramError(f"spindle_rpm must be >= 0, got {rpm!r}", **where,
                                     key="spindle_rpm")
            object.__setattr__(self, "spindle_rpm", rpm)
        codes = tuple(self.m_codes)
        if not all(_is_int(c) and c >= 0 for c in codes):
            raise NCProgramError(f"m_codes must be ints >= 0, got {codes!r}", **where,
                                 key="m_codes")
        object.__setattr__(self, "m_codes", tuple(int(c) for c in codes))


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _trusted_move(kind: str, target: FrozenMapping, feed: float | None, dwell: float,
                  line: int, block_number: int | None, spindle: float | None,
                  m_codes: tuple[int, ...]) -> Move:
    """A `Move` from values a `Program` has already checked (no second validation)."""
    move = object.__new__(Move)
    for name, value in (("kind", kind), ("target", target), ("feed_m_per_s", feed),
                        ("dwell_s", dwell), ("line", line), ("block_number", block_number),
                        ("spindle_rpm", spindle), ("m_codes", m_codes)):
        object.__setattr__(move, name, value)
    return move


def work_offsets_si(
    offsets: Mapping[str, Mapping[str, float]] | None, *, source: str = "<work_offsets>"
) -> Mapping[str, FrozenMapping]:
    """Check and freeze work offsets {"G54": {"X": m, ...}, ...} (SI, default all zero)."""
    if offsets is None:
        return FrozenMapping()
    if not isinstance(offsets, Mapping):
        raise NCProgramError(f"work_offsets must be a mapping like {{'G54': {{'X': 0.0}}}}, "
                             f"got {type(offsets).__name__}", source=source, key="work_offsets")
    for name in offsets:
        if name not in WORK_OFFSETS:
            raise NCProgramError(
                f"unknown work offset {name!r}; expected one of {' '.join(WORK_OFFSETS)}",
                source=source,
                key=str(name),
            )
        if not isinstance(offsets[name], Mapping):
            raise NCProgramError(f"work offset {name} must map axis letters to values in SI, "
                                 f"got {offsets[name]!r}", source=source, key=name)
    return FrozenMapping(
        (name, axis_values(offsets[name], source=source)) for name in WORK_OFFSETS
        if name in offsets
    )


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
        n = len(self)
        i = index.__index__()
        if not -n <= i < n:
            raise IndexError(f"move index {index} out of range for {n} moves")
        return self._program._move(i % n)

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
                 "_moves")

    def __init__(
        self,
        moves: Iterable[Move] = (),
        number: int | None = None,
        source: str = "<moves>",
        work_offsets: Mapping[str, Mapping[str, float]] | None = None,
        *,
        states: Mapping[str, int] | None = None,
        integer_input: str | None = None,
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
            number, source, work_offsets, states, integer_input,
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
    ) -> Program:
        """A program from its arrays (layout as the attributes), checked like any program.

        ``feeds``, ``spindles`` default to NaN (None), ``dwells`` to 0, ``lines`` to
        1..N, ``block_numbers`` to -1 (None). Arrays are copied.
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
            number, source, work_offsets, states, integer_input,
        )
        return program

    @classmethod
    def _from_parts(cls, targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes, *,
                    number, source, work_offsets, states, integer_input) -> Program:
        """A program that takes the reader's arrays without copying them (still checked)."""
        program = object.__new__(cls)
        program._init(targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes, number,
                      source, work_offsets, states, integer_input)
        return program

    def _init(self, targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes, number,
              source, work_offsets, states, integer_input) -> None:
        set_ = object.__setattr__
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
        set_(self, "states", _states(states, source))
        codes = _m_codes(m_codes, len(kinds), source)
        for name, array in (("_targets", targets), ("_kinds", kinds), ("_feeds", feeds),
                            ("_dwells", dwells), ("_lines", lines), ("_spindles", spindles),
                            ("_blocks", blocks)):
            set_(self, name, _readonly(array))
        set_(self, "_m_codes", codes)
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
        return _trusted_move(MOVE_KINDS[self._kinds[i]], target,
                             None if feed != feed else feed, float(self._dwells[i]),
                             int(self._lines[i]), None if block < 0 else block,
                             None if spindle != spindle else spindle,
                             self._m_codes.get(i, ()))

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
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Program):
            return NotImplemented
        return (
            (self.number, self.source, self.work_offsets, self.states, self.integer_input)
            == (other.number, other.source, other.work_offsets, other.states,
                other.integer_input)
            and self._same_moves(other)
        )

    def __hash__(self) -> int:
        return hash((self.number, self.source, len(self._kinds)))

    def __reduce__(self):
        return (_rebuild, (self._targets, self._kinds, self._feeds, self._dwells, self._lines,
                           self._spindles, self._blocks, dict(self._m_codes), self.number,
                           self.source, {k: dict(v) for k, v in self.work_offsets.items()},
                           dict(self.states), self.integer_input))

    def __len__(self) -> int:
        return len(self._kinds)

    def __iter__(self) -> Iterator[Move]:
        return iter(self._moves)

    def __repr__(self) -> str:
        return (f"Program({len(self)} moves, number={self.number!r}, source={self.source!r}, "
                f"axes={''.join(self.axes)!r})")


def _rebuild(targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes, number, source,
             work_offsets, states, integer_input) -> Program:
    """Unpickle a `Program` (the arrays come back writeable copies: made read-only again)."""
    return Program._from_parts(targets, kinds, feeds, dwells, lines, spindles, blocks, m_codes,
                               number=number, source=source, work_offsets=work_offsets,
                               states=states, integer_input=integer_input)


def _states(states: Mapping[str, int] | None, source: str) -> FrozenMapping:
    if states is None:
        return FrozenMapping()
    if not isinstance(states, Mapping) or not all(
        isinstance(k, str) and _is_int(v) and v >= 1 for k, v in states.items()
    ):
        raise NCProgramError(f"states must map words (str) to first lines (int >= 1), got "
                             f"{states!r}", source=source, key="states")
    return FrozenMapping(states.items())


def _m_codes(m_codes: Mapping[int, Iterable[int]], n: int, source: str) -> FrozenMapping:
    if not isinstance(m_codes, Mapping):
        raise NCProgramError(f"m_codes must map move indices to M codes, got "
                             f"{type(m_codes).__name__}", source=source, key="m_codes")
    items = []
    for index in sorted(m_codes):
        codes = tuple(m_codes[index])
        if not _is_int(index) or not 0 <= index < n:
            raise NCProgramError(f"m_codes index {index!r} is not a move index (0..{n - 1})",
                                 source=source, key="m_codes")
        if not all(_is_int(c) and c >= 0 for c in codes):
            raise NCProgramError(f"m_codes must be ints >= 0, got {codes!r} for move {index}",
                                 source=source, key="m_codes")
        if codes:
            items.append((index, codes))
    return FrozenMapping(items)


def _check(program: Program) -> None:
    """The modal rules of the NC language, vectorised; the first broken rule is raised.

    Each rule is first tested on the whole array and only located when broken, so that a
    program of 10^6 moves is checked in a few passes.
    """
    t, kinds, feeds = program._targets, program._kinds, program._feeds
    dwells, lines, spindles = program._dwells, program._lines, program._spindles
    n = len(kinds)
    if n == 0:
        return
    failures: list[tuple[int, int, str, str]] = []  # (move, rule order, message, key)

    def first(mask: np.ndarray, order: int, message, key) -> None:
        if not mask.any():
            return
        i = int(np.argmax(mask))
        failures.append((i, order, message(i) if callable(message) else message,
                         key(i) if callable(key) else key))

    first(lines < 1, 0, lambda i: f"line must be an int >= 1, got {int(lines[i])}", "line")
    if (kinds.view(np.uint8) > 2).any():
        i = int(np.argmax(kinds.view(np.uint8) > 2))
        raise NCProgramError(f"move {i}: kind must be one of {MOVE_KINDS}, got code "
                             f"{int(kinds[i])}", source=program.source, key="kind")
    unset = np.isnan(t)
    if np.isinf(t).any():
        first(np.isinf(t).any(axis=1), 2, "axis values must be finite (NaN: no value yet)",
              "target")
    moving = kinds != KIND_DWELL
    columns = [unset[:, k] for k in range(len(AXES))]  # per column: cheap reductions
    nothing = columns[0].copy()
    for column in columns[1:]:
        nothing &= column
    first(moving & nothing, 3,
          lambda i: f"a {MOVE_KINDS[kinds[i]]} move needs at least one axis value", "target")
    has_feed = ~np.isnan(feeds)
    linear = kinds == KIND_LINEAR
    first(has_feed & ~(linear & (feeds > 0.0) & (feeds < math.inf)), 4,
          lambda i: f"feed must be None for a {MOVE_KINDS[kinds[i]]} move and > 0 for a "
                    f"linear move, got {float(feeds[i])!r}", "feed_m_per_s")
    first(~((dwells >= 0.0) & (dwells < math.inf)) | ((dwells != 0.0) & moving), 5,
          lambda i: f"dwell_s must be >= 0 for a dwell and 0.0 otherwise, got "
                    f"{float(dwells[i])!r} for a {MOVE_KINDS[kinds[i]]} move", "dwell_s")
    first(program._blocks < -1, 6, "block_number must be None or an int >= 0",
          "block_number")
    has_spindle = ~np.isnan(spindles)
    first(has_spindle & ~((spindles >= 0.0) & (spindles < math.inf)), 7,
          lambda i: f"spindle_rpm must be >= 0, got {float(spindles[i])!r}", "spindle_rpm")
    # a column, once set, stays set: its NaNs all come before its first value
    if any(column[int(np.argmin(column)):].any() for column in columns if not column.all()):
        dropped = np.zeros(n, dtype=bool)
        dropped[1:] = (unset[1:] & ~unset[:-1]).any(axis=1)
        first(dropped, 8,
              lambda i: f"move {i} drops axis {_dropped_axis(unset, i)} from its target; "
                        "targets are modal and keep every axis given so far",
              lambda i: _dropped_axis(unset, i))
    dwelling = np.flatnonzero(~moving)
    if dwelling.size:
        here = t[dwelling]
        before = np.where((dwelling > 0)[:, None], t[np.maximum(dwelling - 1, 0)], np.nan)
        moved = ~((here == before) | (np.isnan(here) & np.isnan(before))).all(axis=1)
        if moved.any():
            k = int(np.argmax(moved))
            failures.append((int(dwelling[k]), 9,
                             f"move {int(dwelling[k])} is a dwell but its target "
                             f"{_target_text(here[k])} differs from the position before it "
                             f"{_target_text(before[k])}", "target"))
    fed = linear & has_feed
    if fed.any():
        fed_before = np.zeros(n, dtype=bool)
        fed_before[1:] = np.logical_or.accumulate(fed)[:-1]
        first(linear & ~has_feed & fed_before, 10,
              lambda i: f"move {i} is linear without feed after a linear move with feed; F is "
                        "modal", "feed_m_per_s")
    if has_spindle.any():
        first(np.concatenate([[False], has_spindle[:-1] & ~has_spindle[1:]]), 11,
              lambda i: f"move {i} has no spindle speed after one with spindle speed; S is "
                        "modal", "spindle_rpm")
    for index, codes in program._m_codes.items():
        calls = [c for c in codes if c in SUBPROGRAM_CODES]
        if calls:
            failures.append((index, 12, f"move {index} carries M{calls[0]}, a subprogram call "
                                        "or return: the reader expands those into moves, a "
                                        "move cannot carry them", f"M{calls[0]}"))
        ends = [c for c in codes if c in PROGRAM_END]
        if ends and index < n - 1:
            failures.append((index, 12, f"move {index} ends the program (M{ends[0]:02d}) but "
                                        f"{n - 1 - index} move(s) follow it", f"M{ends[0]:02d}"))
    if failures:
        index, _, message, key = min(failures, key=lambda f: (f[0], f[1]))
        line = int(lines[index]) if lines[index] >= 1 else None
        raise NCProgramError(message, source=program.source, line=line, key=key)


def _dropped_axis(unset: np.ndarray, i: int) -> str:
    return AXES[int(np.argmax(unset[i] & ~unset[i - 1]))]


def _target_text(row: np.ndarray) -> str:
    return str({a: float(v) for a, v in zip(AXES, row, strict=True) if v == v})


class ProgramBuilder:
    """Build a `Program` in Python, with axis values in SI machine coordinates.

    Each method appends one move and returns the builder, so calls chain::

        ProgramBuilder(number=1).rapid(X=0.0, Z=1e-3).linear(X=0.01, feed_mm_per_min=100.0)
            .dwell(0.5).build()

    Targets are modal as in NC: an axis keeps its value until given a new one. Feed and
    spindle speed are modal too. A block with M codes but no motion is ``dwell(0.0,
    m_codes=(...))``.

    Parameters
    ----------
    number : int, optional
        The O number.
    work_offsets : mapping, optional
        {"G54": {"X": m, ...}}; the axis values given to the builder are machine values
        (offset already applied), the offsets only matter to the writer.
    source : str
        Name of the program in messages.
    """

    def __init__(
        self,
        number: int | None = None,
        *,
        work_offsets: Mapping[str, Mapping[str, float]] | None = None,
        source: str = "<builder>",
    ) -> None:
        self._number = number
        self._offsets = work_offsets_si(work_offsets, source=source)
        self._source = source
        self._moves: list[Move] = []
        self._target: dict[str, float] = {}
        self._feed: float | None = None
        self._spindle: float | None = None

    def spindle(self, rpm: float) -> ProgramBuilder:
        """Set the modal spindle speed (rev/min) for the moves that follow."""
        self._spindle = rpm
        return self

    def rapid(self, *, block_number: int | None = None, m_codes: Iterable[int] = (),
              **axes: float) -> ProgramBuilder:
        """Append a rapid move (G00) to the given axis values (m, rad)."""
        return self._motion("rapid", None, block_number, m_codes, axes)

    def linear(
        self,
        *,
        feed_mm_per_min: float | None = None,
        feed_m_per_s: float | None = None,
        block_number: int | None = None,
        m_codes: Iterable[int] = (),
        **axes: float,
    ) -> ProgramBuilder:
        """Append a linear move (G01); the feed (one of the two units) is modal."""
        if feed_mm_per_min is not None and feed_m_per_s is not None:
            raise NCProgramError("give the feed once: feed_mm_per_min or feed_m_per_s",
                                 source=self._source, key="feed")
        if feed_mm_per_min is not None:
            self._feed = _finite(feed_mm_per_min, "feed", source=self._source,
                                 line=len(self._moves) + 1, key="feed_mm_per_min") * (
                M_PER_MM / 60.0
            )
        elif feed_m_per_s is not None:
            self._feed = feed_m_per_s
        return self._motion("linear", self._feed, block_number, m_codes, axes)

    def dwell(self, seconds: float, *, block_number: int | None = None,
              m_codes: Iterable[int] = ()) -> ProgramBuilder:
        """Append a dwell (G04) of ``seconds`` at the current position."""
        self._append("dwell", self._target, None, seconds, block_number, m_codes)
        return self

    def _motion(self, kind: str, feed: float | None, block_number: int | None,
                m_codes: Iterable[int], axes: Mapping[str, float]) -> ProgramBuilder:
        if not axes:
            raise NCProgramError(f"a {kind} move needs at least one axis value",
                                 source=self._source, line=len(self._moves) + 1, key=kind)
        given = axis_values(axes, source=self._source, line=len(self._moves) + 1)
        self._append(kind, {**self._target, **given}, feed, 0.0, block_number, m_codes)
        return self

    def _append(self, kind: str, target: Mapping[str, float], feed: float | None,
                dwell_s: float, block_number: int | None, m_codes: Iterable[int]) -> None:
        move = Move(kind, target, feed, dwell_s, len(self._moves) + 1, block_number,
                    self._spindle, tuple(m_codes))
        self._moves.append(move)
        self._target = dict(move.target)

    def build(self) -> Program:
        """The program built so far (the builder can go on)."""
        return Program(tuple(self._moves), self._number, self._source, self._offsets)
