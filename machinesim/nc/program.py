"""The parsed NC program as immutable values: `Move`, `Program` and `ProgramBuilder`.

Everything here is SI (m for X Y Z, rad for A B C, s, m/s). A `Program` checks on
construction that its moves follow the modal rules of the NC language (see `machinesim.nc`),
so that every `Program`, however it was made, can be written back as NC text.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from machinesim.exceptions import NCProgramError
from machinesim.units import M_PER_MM

#: Axis letters in their canonical order: linear (m), then rotary (rad).
AXES = ("X", "Y", "Z", "A", "B", "C")
ROTARY_AXES = ("A", "B", "C")
#: Work coordinate systems selectable by G54..G59.
WORK_OFFSETS = ("G54", "G55", "G56", "G57", "G58", "G59")
#: M codes that end the program.
PROGRAM_END = (2, 30)
MOVE_KINDS = ("rapid", "linear", "dwell")


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
        G00, G01, or G04 (a block with M codes but no motion is a dwell of 0 s).
    target : Mapping[str, float]
        Absolute machine axis values after this block (m for X Y Z, rad for A B C), work
        offset applied; every axis given a value so far in the program (modal). Frozen.
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


@dataclass(frozen=True)
class Program:
    """An NC program as a sequence of moves in SI machine coordinates.

    Attributes
    ----------
    moves : tuple of Move
        The blocks that move, dwell or carry M codes, in order.
    number : int or None
        The O number.
    source : str
        Where the program came from (a path, ``"<string>"`` or ``"<builder>"``).
    work_offsets : Mapping[str, Mapping[str, float]]
        Work offsets G54..G59 (axis letter -> m or rad) the targets were computed with; the
        writer emits coordinates relative to G54. Absent systems and axes are zero.

    Raises
    ------
    NCProgramError
        When the moves break the modal rules: an axis dropped from the target, a dwell that
        moves, a linear move without feed after one with feed, a spindle speed that vanishes,
        a program end (M02/M30) before the last move.
    """

    moves: tuple[Move, ...]
    number: int | None = None
    source: str = "<moves>"
    work_offsets: Mapping[str, Mapping[str, float]] = field(default_factory=FrozenMapping)

    def __post_init__(self) -> None:
        object.__setattr__(self, "moves", tuple(self.moves))
        object.__setattr__(self, "work_offsets",
                           work_offsets_si(self.work_offsets, source=self.source))
        if self.number is not None and (not _is_int(self.number) or self.number < 0):
            raise NCProgramError(f"number must be None or an int >= 0, got {self.number!r}",
                                 source=self.source, key="number")
        self._check_modal()

    def _check_modal(self) -> None:
        previous: Move | None = None
        last_feed: float | None = None
        for index, move in enumerate(self.moves):
            if not isinstance(move, Move):
                raise NCProgramError(f"move {index} must be a Move, got {type(move).__name__}",
                                     source=self.source, key="moves")
            where = {"source": self.source, "line": move.line}
            before = previous.target if previous is not None else FrozenMapping()
            dropped = [a for a in before if a not in move.target]
            if dropped:
                raise NCProgramError(
                    f"move {index} drops axis {dropped[0]} from its target; targets are modal "
                    "and keep every axis given so far",
                    **where,
                    key=dropped[0],
                )
            if move.kind == "dwell" and move.target != before:
                raise NCProgramError(
                    f"move {index} is a dwell but its target {dict(move.target)} differs from "
                    f"the position before it {dict(before)}",
                    **where,
                    key="target",
                )
            if move.kind == "linear":
                if move.feed_m_per_s is None and last_feed is not None:
                    raise NCProgramError(
                        f"move {index} is linear without feed after a linear move with feed "
                        f"{last_feed!r} m/s; F is modal",
                        **where,
                        key="feed_m_per_s",
                    )
                last_feed = move.feed_m_per_s
            if previous is not None and previous.spindle_rpm is not None and (
                move.spindle_rpm is None
            ):
                raise NCProgramError(f"move {index} has no spindle speed after one with "
                                     "spindle speed; S is modal", **where, key="spindle_rpm")
            ends = [c for c in move.m_codes if c in PROGRAM_END]
            if ends and index < len(self.moves) - 1:
                raise NCProgramError(
                    f"move {index} ends the program (M{ends[0]:02d}) but "
                    f"{len(self.moves) - 1 - index} move(s) follow it",
                    **where,
                    key=f"M{ends[0]:02d}",
                )
            previous = move

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

    @property
    def axes(self) -> tuple[str, ...]:
        """Axis letters used by the program, in canonical order X Y Z A B C."""
        used = {a for move in self.moves for a in move.target}
        return tuple(a for a in AXES if a in used)

    def __len__(self) -> int:
        return len(self.moves)

    def __iter__(self) -> Iterator[Move]:
        return iter(self.moves)


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
