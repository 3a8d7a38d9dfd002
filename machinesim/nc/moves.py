"""NC moves as immutable values: the axis letters and move kinds, `Move`, and the checks of
axis values and work offsets every way of making a program goes through.

Everything here is SI (m for X Y Z, rad for A B C, s, m/s). `machinesim.nc.program` keeps
moves as arrays (`Program`); this module is the single move and its words.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from machinesim.exceptions import NCProgramError

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
INTEGER_INPUTS = ("calculator", "increment", "is-b", "is-c")


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
    # text and flags are refused, not converted: X="0.001" had built 1 mm, X=True 1 m
    try:
        if isinstance(value, str | bytes | bool | np.bool_):
            raise TypeError
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


def feed_problem(kind: str, feed: float) -> str:
    """What is wrong with a move's ``feed`` (m/s): a feed on a move that has none, or a
    linear move's feed that is not above zero."""
    if kind != "linear":
        return f"feed must be None for a {kind} move (only a linear move has one), got {feed!r}"
    return f"feed must be > 0 for a linear move, got {feed!r} m/s"


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
        Feed rate in m/s for linear moves (the modal F); None for rapid and dwell. A linear
        move built without one is refused by the planner where it moves (the reader refuses
        its block: no F in force).
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
    arc_length_m : float or None
        For the chord of an arc (G02/G03), the length of the piece of arc it stands for, m
        (`machinesim.nc.Program.arc_lengths`): `plan` times the chord by it over F, as the
        control holds F along the arc. None for a move that is no arc's chord.
    """

    kind: Literal["rapid", "linear", "dwell"]
    target: Mapping[str, float]
    feed_m_per_s: float | None = None
    dwell_s: float = 0.0
    line: int = 1
    block_number: int | None = None
    spindle_rpm: float | None = None
    m_codes: tuple[int, ...] = field(default=())
    arc_length_m: float | None = None

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
                raise NCProgramError(feed_problem(self.kind, feed), **where,
                                     key="feed_m_per_s")
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
        if self.arc_length_m is not None:
            arc = _finite(self.arc_length_m, "arc length", **where, key="arc_length_m")
            if arc < 0.0:
                raise NCProgramError(f"arc_length_m must be None (no arc) or >= 0 m, got "
                                     f"{arc!r}", **where, key="arc_length_m")
            object.__setattr__(self, "arc_length_m", arc)


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _trusted_move(kind: str, target: FrozenMapping, feed: float | None, dwell: float,
                  line: int, block_number: int | None, spindle: float | None,
                  m_codes: tuple[int, ...], arc_length: float | None = None) -> Move:
    """A `Move` from values a `Program` has already checked (no second validation)."""
    move = object.__new__(Move)
    for name, value in (("kind", kind), ("target", target), ("feed_m_per_s", feed),
                        ("dwell_s", dwell), ("line", line), ("block_number", block_number),
                        ("spindle_rpm", spindle), ("m_codes", m_codes),
                        ("arc_length_m", arc_length)):
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
