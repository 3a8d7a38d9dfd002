"""Read FANUC-style NC text into a `Program`; the language rules are in `machinesim.nc`."""

from __future__ import annotations

import math
import os
import re
import string
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

from machinesim.exceptions import NCProgramError
from machinesim.nc.program import (
    AXES,
    PROGRAM_END,
    ROTARY_AXES,
    Move,
    Program,
    work_offsets_si,
)
from machinesim.units import M_PER_MM, RAD_PER_DEG

#: One inch in metres (exact by definition).
M_PER_INCH = 0.0254
#: Least input increments of the "increment" integer-input rule: 1 nm and 0.00001 deg as the
#: machines of the seeds resolve; 0.0000001 inch is the inch increment of that (nano) system.
INCREMENT_M = 1e-9
INCREMENT_INCH_M = 1e-7 * M_PER_INCH
INCREMENT_RAD = 1e-5 * RAD_PER_DEG
#: Integer words (N O G M P) longer than this are refused: FANUC takes at most 8 digits, and
#: the bound keeps int() away from Python's digit limit on hostile input.
MAX_INTEGER_DIGITS = 9

IntegerInput = Literal["calculator", "increment"]
INTEGER_INPUTS = ("calculator", "increment")

_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)")
_BLANK = " \t\r"
_LETTERS = frozenset(string.ascii_letters)
_READ_LETTERS = frozenset("NOGMSFPXYZABC")
_ARC_LETTERS = frozenset("IJKR")
_MOTION_KINDS = {"G00": "rapid", "G01": "linear"}
_G_GROUPS = {
    "G00": "motion", "G01": "motion", "G04": "motion",
    "G17": "plane", "G18": "plane", "G19": "plane",
    "G20": "units", "G21": "units",
    "G54": "work offset", "G55": "work offset", "G56": "work offset",
    "G57": "work offset", "G58": "work offset", "G59": "work offset",
    "G90": "distance", "G91": "distance",
    "G94": "feed mode",
}  # fmt: skip
_CIRCULAR = (
    "circular interpolation (G02/G03) is not supported; approximate the arc with G01 "
    "segments within your chord tolerance"
)
_G_REFUSED = {
    "G02": _CIRCULAR,
    "G03": _CIRCULAR,
    "G95": "feed per revolution (G95) is not supported; use G94 with F in mm/min",
}


@dataclass(frozen=True)
class _Word:
    letter: str  # upper case
    text: str  # the number as written
    column: int  # 1-based column of the letter

    @property
    def key(self) -> str:
        return self.letter + self.text


@dataclass
class _State:
    """The modal state of the control while reading, in SI."""

    motion: str | None = None
    incremental: bool = False
    inch: bool = False
    plane: str = "G17"
    work_offset: str = "G54"
    feed: float | None = None
    spindle: float | None = None
    target: dict[str, float] = field(default_factory=dict)
    number: int | None = None
    blocks: int = 0
    end: tuple[int, str] | None = None


def parse_program(
    text: str,
    source: str = "<string>",
    *,
    work_offsets: Mapping[str, Mapping[str, float]] | None = None,
    integer_input: IntegerInput = "calculator",
) -> Program:
    """Read an NC program.

    Parameters
    ----------
    text : str
        The program, in the language described in `machinesim.nc`.
    source : str
        Name of the program in messages and in `Program.source`.
    work_offsets : mapping, optional
        {"G54": {"X": m, ...}, ...} in SI; absent systems and axes are zero.
    integer_input : {"calculator", "increment"}
        How an axis number without decimal point reads: "calculator" (X10 is 10 mm, the
        default) or "increment" (X10 is 10 least input increments: 10 nm, 0.0001 deg).

    Returns
    -------
    Program
        Moves with absolute machine targets in SI.

    Raises
    ------
    NCProgramError
        For anything not understood, naming source, line, column and word.
    """
    if not isinstance(text, str):
        raise NCProgramError(f"NC program text must be str, got {type(text).__name__}",
                             source=source)
    if integer_input not in INTEGER_INPUTS:
        raise NCProgramError(f"integer_input must be one of {INTEGER_INPUTS}, got "
                             f"{integer_input!r}", source=source, key="integer_input")
    offsets = work_offsets_si(work_offsets, source=source)
    state = _State()
    moves: list[Move] = []
    for line, raw in enumerate(text.split("\n"), start=1):
        words = _tokenize(raw, source, line)
        if not words:
            continue
        if state.end is not None:
            raise NCProgramError(
                f"block after the program end {state.end[1]} on line {state.end[0]}; blocks "
                "after M02/M30 are refused",
                source=source,
                line=line,
                column=words[0].column,
                key=words[0].key,
            )
        state.blocks += 1
        move = _Block(words, state, offsets, integer_input, source, line).run()
        if move is not None:
            moves.append(move)
    return Program(tuple(moves), state.number, source, offsets)


def read_program(path: str | os.PathLike, **kwargs) -> Program:
    """Read an NC program file (keyword arguments as `parse_program`; source is the path)."""
    with open(path, encoding="utf-8", errors="replace", newline="") as file:
        text = file.read()
    return parse_program(text, os.fspath(path), **kwargs)


def _tokenize(raw: str, source: str, line: int) -> list[_Word]:
    """Words of one line; comments, blanks and a lone '%' give no words."""
    words: list[_Word] = []
    percent = False
    i, n = 0, len(raw)

    def fail(message: str, column: int, key: str) -> NCProgramError:
        return NCProgramError(message, source=source, line=line, column=column, key=key)

    while i < n:
        c = raw[i]
        if c in _BLANK:
            i += 1
        elif c == "(":
            close = raw.find(")", i + 1)
            if close < 0:
                raise fail("comment '(' is not closed on its line", i + 1, "(")
            i = close + 1
        elif c == ";":
            break
        elif c == ")":
            raise fail("')' without an opening '('", i + 1, ")")
        elif c == "%" or percent:
            if words or percent:
                raise fail("'%' must stand alone on its line (comments aside)", i + 1, c)
            percent = True
            i += 1
        elif c in _LETTERS:
            start = i
            i += 1
            while i < n and raw[i] in _BLANK:
                i += 1
            match = _NUMBER.match(raw, i)
            end = match.end() if match else i
            if match is None or (end < n and raw[end] in "0123456789.+-"):
                tail = raw[i:_end_of_garbage(raw, i)]
                raise fail(
                    f"malformed number {tail!r} after {c.upper()!r}; expected digits with an "
                    f"optional sign and decimal point, e.g. {c.upper()}-12.5",
                    start + 1,
                    c.upper() + tail,
                )
            words.append(_Word(c.upper(), match.group(), start + 1))
            i = end
        elif c in "0123456789+-.":
            tail = raw[i:_end_of_garbage(raw, i)]
            raise fail(f"number {tail!r} without an address letter", i + 1, tail)
        else:
            raise fail(
                f"unexpected character {c!r}; expected words (a letter and a number), "
                "'(comment)', ';comment' or a lone '%'",
                i + 1,
                c,
            )
    return words


def _end_of_garbage(raw: str, i: int) -> int:
    while i < len(raw) and raw[i] not in _BLANK and raw[i] not in _LETTERS and raw[i] not in "(;":
        i += 1
    return i


class _Block:
    """One block: checks its words, updates the modal state and returns its move."""

    def __init__(self, words: list[_Word], state: _State, offsets: Mapping,
                 integer_input: str, source: str, line: int) -> None:
        self.words = words
        self.state = state
        self.offsets = offsets
        self.increment = integer_input == "increment"
        self.source = source
        self.line = line

    def fail(self, message: str, word: _Word) -> NCProgramError:
        return NCProgramError(message, source=self.source, line=self.line,
                              column=word.column, key=word.key)

    def run(self) -> Move | None:
        state = self.state
        single: dict[str, _Word] = {}
        g_codes: dict[str, tuple[str, _Word]] = {}
        m_codes: list[int] = []
        for word in self.words:
            if word.letter not in _READ_LETTERS:
                hint = (" (arc words belong to G02/G03, which are not supported)"
                        if word.letter in _ARC_LETTERS else "")
                raise self.fail(f"unknown word letter {word.letter!r}{hint}; machinesim reads "
                                "N O G M S F P X Y Z A B C", word)
            if word.letter == "G":
                self.g_code(word, g_codes)
            elif word.letter == "M":
                m_codes.append(self.integer(word, "M code"))
            elif word.letter in single:
                first = single[word.letter]
                kind = "axis word" if word.letter in AXES else "word"
                raise self.fail(f"{kind} {word.letter} appears twice in one block (first as "
                                f"{first.key} at column {first.column})", word)
            else:
                single[word.letter] = word
        if "O" in single:
            self.program_number(single["O"])
            return None
        self.apply_modal(g_codes)
        block_number = self.integer(single["N"], "block number") if "N" in single else None
        if "F" in single:
            feed = self.real(single["F"])
            if feed <= 0.0:
                raise self.fail(f"feed must be > 0, got {single['F'].key}", single["F"])
            state.feed = self.finite(feed * self.length_unit() / 60.0, single["F"])
        if "S" in single:
            spindle = self.real(single["S"])
            if spindle < 0.0:
                raise self.fail(f"spindle speed must be >= 0, got {single['S'].key}",
                                single["S"])
            state.spindle = spindle
        motion = g_codes.get("motion")
        if "P" in single and (motion is None or motion[0] != "G04"):
            raise self.fail("word P is only read with G04 (dwell time in milliseconds)",
                            single["P"])
        ends = [m for m in m_codes if m in PROGRAM_END]
        if ends:
            state.end = (self.line, f"M{ends[0]:02d}")
        axes = [single[a] for a in AXES if a in single]
        if motion is not None and motion[0] == "G04":
            return self.dwell(motion[1], single, axes, block_number, m_codes)
        if motion is not None:
            state.motion = _MOTION_KINDS[motion[0]]
        if axes:
            return self.motion(axes, block_number, m_codes)
        if any(m not in PROGRAM_END for m in m_codes):
            return self.move("dwell", 0.0, block_number, m_codes)
        return None

    def g_code(self, word: _Word, g_codes: dict[str, tuple[str, _Word]]) -> None:
        text = word.text
        if text[0] in "+-":
            raise self.fail(f"G code {word.key} has a sign; expected e.g. G01", word)
        if "." in text or len(text) > MAX_INTEGER_DIGITS:
            name = word.key
        else:
            name = f"G{int(text):02d}"
        if name in _G_REFUSED:
            raise self.fail(_G_REFUSED[name], word)
        group = _G_GROUPS.get(name)
        if group is None:
            raise self.fail(f"unknown G code {name}; machinesim reads "
                            f"{' '.join(sorted(set(_G_GROUPS)))}", word)
        if group in g_codes:
            first = g_codes[group][0]
            what = "two motion G-codes" if group == "motion" else f"two {group} G-codes"
            raise self.fail(f"{what} in one block: {first} and {name}", word)
        g_codes[group] = (name, word)

    def apply_modal(self, g_codes: dict[str, tuple[str, _Word]]) -> None:
        state = self.state
        if "units" in g_codes:
            state.inch = g_codes["units"][0] == "G20"
        if "distance" in g_codes:
            state.incremental = g_codes["distance"][0] == "G91"
        if "plane" in g_codes:
            state.plane = g_codes["plane"][0]
        if "work offset" in g_codes:
            state.work_offset = g_codes["work offset"][0]

    def program_number(self, word: _Word) -> None:
        others = [w for w in self.words if w is not word]
        if others:
            raise self.fail(f"the O number must stand alone in its block, found "
                            f"{others[0].key} with it", others[0])
        if self.state.blocks != 1:
            raise self.fail("the O number must be the first block of the program", word)
        self.state.number = self.integer(word, "program number")

    def dwell(self, g04: _Word, single: dict[str, _Word], axes: list[_Word],
              block_number: int | None, m_codes: list[int]) -> Move:
        for word in axes:
            if word.letter != "X":
                raise self.fail(f"axis word {word.letter} in a dwell block; G04 takes only "
                                "P<milliseconds> or X<seconds>", word)
        if "P" in single and "X" in single:
            raise self.fail("G04 takes one dwell time, got both P and X", single["X"])
        if "P" in single:
            word = single["P"]
            if "." in word.text:
                raise self.fail(f"G04 P takes integer milliseconds, got {word.key}; use "
                                "G04 X<seconds> for fractions", word)
            dwell_s = self.integer(word, "dwell time") / 1000.0
        elif "X" in single:
            word = single["X"]
            dwell_s = self.real(word)
            if self.increment and "." not in word.text:
                dwell_s /= 1000.0
            if dwell_s < 0.0:
                raise self.fail(f"dwell time must be >= 0, got {word.key}", word)
        else:
            raise self.fail("dwell without time: G04 needs P<milliseconds> or X<seconds>", g04)
        return self.move("dwell", dwell_s, block_number, m_codes)

    def motion(self, axes: list[_Word], block_number: int | None,
               m_codes: list[int]) -> Move:
        state = self.state
        if state.motion is None:
            raise self.fail(f"axis word {axes[0].letter} without a motion mode; give G00 or "
                            "G01 first", axes[0])
        offset = self.offsets.get(state.work_offset, {})
        for word in axes:
            value = self.real(word) * self.axis_unit(word)
            if state.incremental:
                if word.letter not in state.target:
                    raise self.fail(
                        f"incremental (G91) move on axis {word.letter} before its position is "
                        "known; give an absolute (G90) value first",
                        word,
                    )
                value += state.target[word.letter]
            else:
                value += offset.get(word.letter, 0.0)
            state.target[word.letter] = self.finite(value, word)
        return self.move(state.motion, 0.0, block_number, m_codes)

    def move(self, kind: str, dwell_s: float, block_number: int | None,
             m_codes: list[int]) -> Move:
        state = self.state
        return Move(kind, dict(state.target), state.feed if kind == "linear" else None,
                    dwell_s, self.line, block_number, state.spindle, tuple(m_codes))

    def length_unit(self) -> float:
        return M_PER_INCH if self.state.inch else M_PER_MM

    def axis_unit(self, word: _Word) -> float:
        rotary = word.letter in ROTARY_AXES
        if self.increment and "." not in word.text:
            if rotary:
                return INCREMENT_RAD
            return INCREMENT_INCH_M if self.state.inch else INCREMENT_M
        return RAD_PER_DEG if rotary else self.length_unit()

    def real(self, word: _Word) -> float:
        return self.finite(float(word.text), word)

    def finite(self, value: float, word: _Word) -> float:
        if not math.isfinite(value):
            raise self.fail(f"value of {word.key} is out of range (not finite in float64)",
                            word)
        return value

    def integer(self, word: _Word, what: str) -> int:
        text = word.text
        if not text.isdigit() or len(text) > MAX_INTEGER_DIGITS:
            raise self.fail(f"{what} must be an unsigned integer of at most "
                            f"{MAX_INTEGER_DIGITS} digits, got {word.key}", word)
        return int(text)
