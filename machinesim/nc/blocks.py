"""One block of NC: its words checked, the modal state updated, its moves emitted.

Internal to the reader (`machinesim.nc.reader`); arc blocks read in `machinesim.nc.arc_block`,
canned-cycle blocks in `machinesim.nc.drilling`, and dwell (G04), G28, G53, G08 and G05.1
blocks in `machinesim.nc.one_shot`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from machinesim.exceptions import NCProgramError, brief
from machinesim.nc.arc_block import read_arc
from machinesim.nc.drilling import HOLE_WORDS, read_cycle
from machinesim.nc.length import check_length_carried, note_length_change
from machinesim.nc.lexer import Word
from machinesim.nc.one_shot import read_dwell, read_one_shot
from machinesim.nc.program import AXES, MOVE_KINDS, PROGRAM_END, ROTARY_AXES
from machinesim.nc.rotary_feed import inch_feed_scale
from machinesim.nc.word_context import check_word_context
from machinesim.nc.words import (
    ARC,
    CYCLE_WITH_MOTION,
    FEED_BEFORE_UNITS,
    G50_SETTING,
    G_GROUPS,
    G_REFUSED,
    M99_IN_MAIN,
    M_PER_INCH,
    MAX_INTEGER_DIGITS,
    MAX_MOVES,
    MAX_PROGRAM_TIME_S,
    MOTION,
    OTHER_CYCLES,
    OWN_WORDS,
    SINGLE,
    SLOWEST_FEED_M_PER_S,
    UNITS_AFTER_MOTION,
    UNITS_IN_SUBPROGRAM,
    WORK_OFFSET_NOT_GIVEN,
    CallProblem,
    call_of,
    g_name,
    integer,
)
from machinesim.units import M_PER_MM, RAD_PER_DEG

#: M06 puts the tool selected by the last T word in the spindle (FANUC machining centres).
TOOL_CHANGE = 6
#: The most decimals a length word's last digit is counted to (`Block.digit`): 1e-30 of a
#: unit, far below anything the holder's allowance reads.
MOST_DECIMALS = 30

if TYPE_CHECKING:
    from machinesim.nc.reader import Reader


class Block:
    """One block: checks its words, updates the modal state and emits its moves."""

    def __init__(self, reader: Reader, words: list[Word], line: int, depth: int) -> None:
        self.reader = reader
        self.words = words
        self.state = reader.state
        self.offsets = reader.offsets
        self.increment = reader.increment
        self.source = reader.source
        self.line = line
        self.depth = depth
        self.single: dict[str, Word] = {}
        self.g_codes: dict[str, tuple[str, Word]] = {}
        self.m_codes: list[tuple[int, Word]] = []
        self.refused_cycle: str | None = None  # a canned cycle not read (G74, G84..G89)
        self.refused_code: str | None = None  # a code not read whose words are its own

    def fail(self, message: str, word: Word | None) -> NCProgramError:
        return self.reader.fail(message, self.line, word)

    def refuse(self, message: str, word: Word) -> None:
        """Record a refused word; the block goes on without it."""
        self.reader.problems.add(self.fail(message, word))

    def run(self) -> str | None:
        try:
            return self._run()
        except NCProgramError as error:
            self.reader.problems.add(error)
            return None
        except KeyError as error:  # a tool the tool table lacks
            self.reader.problems.add(self.fail(error.args[0], self.tool_word()))
            self.state.h = 0
            return None

    def _run(self) -> str | None:
        state = self.state
        self.classify()
        single, g = self.single, self.g_codes
        if self.refused_code is not None:
            # its words are its data (words.OWN_WORDS): its refusal says what is wrong
            for letter in (*AXES, *"PQRIJKL"):
                single.pop(letter, None)
        if "O" in single:
            raise self.fail("the O number must stand alone in the first block of the program "
                            "or of a subprogram", single["O"])
        motion, cycle = g.get("motion"), g.get("canned cycle")
        if cycle is not None and cycle[0] != "G80":
            # `G01 G81 X1. Y1. Z-1. R1. F50.` had drilled, its G01 read as nothing, and
            # `G81 G28 X1. Y1. Z-1. R1.` had gone through Z-1 at rapid, its R read as nothing
            for group, codes in (("motion", (*MOTION, *ARC)), ("one-shot", ("G28", "G53"))):
                if group in g and g[group][0] in codes:
                    raise self.fail(CYCLE_WITH_MOTION.format(code=g[group][0],
                                                             cycle=cycle[0]), cycle[1])
        length_before = self.reader.tool_length()
        self.apply_modal()
        block_number = self.integer(single["N"], "block number") if "N" in single else None
        self.feed_and_spindle()
        self.tool_words()
        note_length_change(self, length_before)
        if "T" in single:
            self.reader.tool_events.append(
                (self.reader.out.count, self.integer(single["T"], "tool number"), self.line))
        one_shot = g.get("one-shot")
        if motion is not None and motion[0] == "G04" and one_shot is not None:
            raise self.fail(f"G04 and {one_shot[0]} in one block; give each its own block",
                            one_shot[1])
        if motion is not None and motion[0] != "G04":
            state.motion = motion[0]
            if state.cycle is not None and "canned cycle" not in g:
                state.cycle = None  # a motion code cancels the canned cycle
        check_word_context(self, motion, one_shot)
        codes = [code for code, _ in self.m_codes]
        ends = [c for c in codes if c in PROGRAM_END]
        first_move = self.reader.out.count
        axes = [single[a] for a in AXES if a in single]
        if motion is not None and motion[0] == "G04":
            read_dwell(self, motion[1], axes, block_number)
        elif one_shot is not None:
            read_one_shot(self, one_shot, axes, block_number)
        elif state.cycle is not None and any(k in single for k in HOLE_WORDS):
            read_cycle(self, axes, block_number)
        elif state.motion in ARC and (axes or any(k in single for k in "IJKR")):
            read_arc(self, axes, block_number)
        elif axes:
            self.straight(axes, block_number)
        passed = tuple(c for c in codes if c not in (98, 99))
        out = self.reader.out
        if out.count > first_move:
            if passed:
                out.m_codes[out.count - 1] = passed
            if state.exact_stop or "exact stop" in g:  # G61, or G09 in this block
                out.stops.append(np.array([out.count - 1], dtype=np.int64))
        elif any(c not in PROGRAM_END for c in passed):
            self.add("dwell", 0.0, block_number)
            out.m_codes[out.count - 1] = passed
        if TOOL_CHANGE in codes:
            self.reader.tool_events.append((out.count, None, self.line))
        if ends and self.depth == 0:  # in a subprogram, refused by the layout
            state.end = (self.line, f"M{ends[0]:02d}")
        if 98 in codes:
            call = call_of(self.words, self.reader.layout.defined)
            if isinstance(call, CallProblem):
                raise self.fail(call.message, call.word)
            self.reader.call(call, self.depth, self.line)
        if 99 in codes:
            if self.depth == 0:
                raise self.fail(M99_IN_MAIN, dict((c, w) for c, w in self.m_codes)[99])
            return "return"
        return None

    # --- words

    def classify(self) -> None:
        for word in self.words:
            letter = word.letter
            if letter == "G":
                self.g_code(word)
            elif letter == "M":
                code = integer(word)
                if code is None:
                    self.refuse(f"M code must be an unsigned integer of at most "
                                f"{MAX_INTEGER_DIGITS} digits, got {brief(word.key)}", word)
                else:
                    self.m_codes.append((code, word))
            elif letter not in SINGLE and not (letter == "E" and self.smoothing()):
                self.refuse(f"unknown word letter {letter!r}; machinesim reads "
                            "N O G M S F P X Y Z A B C I J K R Q L H T D, and E in a G187 "
                            "block (Haas's maximum corner rounding)", word)
            elif letter in self.single:
                first = self.single[letter]
                kind = "axis word" if letter in AXES else "word"
                self.refuse(f"{kind} {letter} appears twice in one block (first as "
                            f"{brief(first.key)} at column {first.column})", word)
            else:
                self.single[letter] = word

    def smoothing(self) -> bool:
        """Whether the block holds G187 (Haas's smoothness and corner rounding), the one
        code that reads an E word (`machinesim.nc.one_shot`)."""
        return any(w.letter == "G" and g_name(w) == "G187" for w in self.words)

    def g_code(self, word: Word) -> None:
        if word.text[0] in "+-":
            self.refuse(f"G code {brief(word.key)} has a sign; expected e.g. G01", word)
            return
        name = g_name(word)
        if name in G_REFUSED:
            self.refuse(G_REFUSED[name], word)
            if name in OTHER_CYCLES:
                self.refused_cycle = name
            if name in OWN_WORDS:
                self.refused_code = name
            return
        group = G_GROUPS.get(name)
        if group is None:
            self.refuse(f"unknown G code {brief(name)}; machinesim reads "
                        f"{' '.join(sorted(G_GROUPS))}", word)
            self.refused_code = name
            return
        if group in self.g_codes:
            first = self.g_codes[group][0]
            what = "two motion G-codes" if group == "motion" else f"two {group} G-codes"
            self.refuse(f"{what} in one block: {first} and {name}", word)
            return
        self.g_codes[group] = (name, word)

    def apply_modal(self) -> None:
        state, g, line = self.state, self.g_codes, self.line
        if "units" in g:
            code, word = g["units"]
            if state.inch != (code == "G20"):
                was, now = ("inch", "mm") if state.inch else ("mm", "inch")
                if self.depth:
                    raise self.fail(UNITS_IN_SUBPROGRAM.format(code=code, was=was, now=now),
                                    word)
                moved = self.reader.out.first_motion
                if moved is not None:
                    raise self.fail(UNITS_AFTER_MOTION.format(code=code, was=was, now=now,
                                                              moved=moved), word)
                state.unit_switch = (code, line)
            state.inch = code == "G20"
            self.reader.unit_words.setdefault(g["units"][0], line)
        if "distance" in g:
            state.incremental = g["distance"][0] == "G91"
        if "plane" in g:
            state.plane = g["plane"][0]
        if "work offset" in g:
            name, word = g["work offset"]
            if name != "G54" and name not in self.offsets:
                if self.offsets:
                    raise self.fail(WORK_OFFSET_NOT_GIVEN.format(
                        name=name, given=" ".join(self.offsets)), word)
                # no offsets at all: every system is G54's zero (machine zero), listed since
                # the program meant one (`machinesim cut` notes it)
                self.reader.note(name, line)
            state.work_offset = name
        if "return level" in g:
            state.retract = g["return level"][0]
        if "scaling" in g and any(a in self.single for a in AXES):
            raise self.fail(G50_SETTING, g["scaling"][1])
        for group in ("cutter compensation", "path mode", "arc centre", "exact stop",
                      "polar coordinates", "scaling", "coordinate rotation"):
            if group in g:
                self.reader.note(g[group][0], line)
        if "path mode" in g:
            state.exact_stop = g["path mode"][0] == "G61"
        if "tool length" in g:
            state.length_mode = g["tool length"][0]
        if "canned cycle" in g:
            name, word = g["canned cycle"]
            if name == "G80":
                self.reader.note("G80", line)
                state.cycle = None
            else:
                if state.plane != "G17":
                    raise self.fail(f"canned cycle {name} in {state.plane}: machinesim drills "
                                    "along Z only (G17)", word)
                if state.cycle is None:
                    if "Z" not in state.target:
                        raise self.fail(f"{name} starts a canned cycle but Z is not known "
                                        "yet (the initial level); move Z first", word)
                    state.initial_z = state.target["Z"]
                    state.cycle_z = state.cycle_r = state.cycle_q = None
                    state.cycle_pecks = state.cycle_return = None
                    state.cycle_given = {}
                    state.cycle_p = 0.0
                    state.peck_dwell = False
                state.cycle = name

    def feed_and_spindle(self) -> None:
        state, single = self.state, self.single
        if "F" in single:
            feed = self.real(single["F"])
            if feed <= 0.0:
                raise self.fail(f"feed must be > 0, got {brief(single['F'].key)}", single["F"])
            state.feed = self.finite(feed * self.length_unit() / 60.0, single["F"])
            state.feed_inch = state.inch
            state.feed_line = self.line
            if state.feed < SLOWEST_FEED_M_PER_S:
                raise self.fail(f"feed {brief(single['F'].key)} is below 1 nm a minute (1e-6 "
                                "mm/min), slower than any control feeds: a feed in the wrong "
                                "unit?",
                                single["F"])
        if "S" in single:
            spindle = self.real(single["S"])
            if spindle < 0.0:
                raise self.fail(f"spindle speed must be >= 0, got {brief(single['S'].key)}",
                                single["S"])
            state.spindle = spindle

    def tool_words(self) -> None:
        state, single, reader = self.state, self.single, self.reader
        for letter, what in (("T", "tool number"), ("D", "cutter radius offset number")):
            if letter in single:
                number = self.integer(single[letter], what)
                reader.note(f"{letter}{number}", self.line)
                if reader.tools is not None and number != 0 and number not in reader.tools.tools:
                    raise self.fail(f"{letter}{number}: tool {number} is not in the tool "
                                    f"table {reader.tools.source}", single[letter])
        if "H" in single:
            state.h = self.integer(single["H"], "tool length offset number")
            state.h_given = True
        length = self.g_codes.get("tool length")
        if length is not None and length[0] != "G49" and not state.h_given:
            name = length[0]
            raise self.fail(f"{name} without H, and no H given before it: which tool length "
                            f"is meant is not known; write {name} H<n> (H0 for none). A bare "
                            f"{name} takes the last H on FANUC and the loaded tool's length "
                            "on LinuxCNC; read as zero it would cut that length too deep",
                            length[1])
        if state.length_mode != "G49" and state.h != 0:
            if reader.tools is None:
                message = (f"{state.length_mode} H{state.h} needs tool {state.h}'s length, "
                           "and no tool table was given: write one, a TOML file such as "
                           f"tools.toml holding the two lines '[tool.{state.h}]' and "
                           "'length_mm = 0.0' (the tool's length beyond the machine model's "
                           "tool: 0 for the tool the model carries; docs/nc.md, 'Tool table'), "
                           "and give it: machinesim cut ... --tools tools.toml, or "
                           "read_program(..., tools='tools.toml')")
                state.h = 0
                raise self.fail(message, self.tool_word())
            reader.tools.length(state.h)  # refuses a tool the table lacks

    def tool_word(self) -> Word | None:
        return self.single.get("H") or self.g_codes.get("tool length", (None, None))[1]

    # --- moves

    def add(self, kind: str, dwell_s: float, block_number: int | None, *,
            feed: float | None = None, units_free: bool = False) -> None:
        """Add a move to the modal target; a linear one at ``feed`` (m/s), the modal feed
        when None. ``units_free``: its target is the same in mm and inch (`_Output.add`)."""
        out, state = self.reader.out, self.state
        if out.count + 1 > MAX_MOVES:
            raise self.fail(f"the program expands to more than {MAX_MOVES} moves",
                            self.words[0])
        if kind == "linear" and feed is None:
            feed = state.feed
        out.add(MOVE_KINDS.index(kind), state.target, feed if kind == "linear" else None,
                dwell_s, self.line, block_number, state.spindle, units_free=units_free)

    def reserve(self, n: int, word: Word) -> None:
        if self.reader.out.count + n > MAX_MOVES:
            raise self.fail(f"this block expands to {n} moves: the program would exceed "
                            f"{MAX_MOVES} moves", word)

    def machine(self, word: Word, *, machine_coordinates: bool = False) -> float:
        """The machine value of one axis word (absolute or incremental, offsets applied)."""
        state = self.state
        letter = word.letter
        value = self.real(word) * self.axis_unit(word)
        if machine_coordinates:  # measured from the reference position (machine zero)
            return self.finite(value + self.reader.reference.get(letter, 0.0), word)
        if state.incremental:
            if letter not in state.target:
                raise self.fail(
                    f"incremental (G91) move on axis {letter} before its position is known; "
                    "give an absolute (G90) value first",
                    word,
                )
            step, value = value, value + state.target[letter]
            if not math.isfinite(value) and math.isfinite(step):
                # the word is finite, its sum with the position not: it had been refused
                # as 'value of X1000... is out of range', which the word is not
                raise self.fail(
                    f"incremental (G91) {brief(word.key)} from {letter} = "
                    f"{state.target[letter]:.6g} {'rad' if letter in 'ABC' else 'm'} takes "
                    "the axis out of range (beyond float64); expected a position within the "
                    "machine's travel",
                    word)
        else:
            value += self.offsets.get(state.work_offset, {}).get(letter, 0.0)
            if letter == "Z":
                value += self.reader.tool_length()
                state.length_change = None  # carried by this Z
                state.length_cancelled = None
        return self.finite(value, word)

    def straight(self, axes: list[Word], block_number: int | None) -> None:
        state = self.state
        if state.motion is None:
            raise self.fail(f"axis word {axes[0].letter} without a motion mode; give G00 or "
                            "G01 first", axes[0])
        check_length_carried(self, self.single.get("Z"), axes)
        values = {word.letter: self.machine(word) for word in axes}
        if state.motion == "G01":
            self.check_feed("G01", self.g_codes.get("motion", (None, axes[0]))[1])
        start = dict(state.target)
        state.target.update(values)
        feed = None
        if (state.motion == "G01" and state.feed_inch and state.feed is not None
                and any(word.letter in ROTARY_AXES for word in axes)):
            feed = state.feed * self.inch_feed_scale(start, state.target, axes)
        self.add(MOTION[state.motion], 0.0, block_number, feed=feed,
                 units_free=self.units_free(axes))

    def units_free(self, axes: list[Word]) -> bool:
        """Whether the move of these axis words (G00, G01, G28 or G53) reaches the same
        target read in mm or in inch: its length words are all zero. Under G90 the zeros
        are the work zero (a work offset and a tool length are in m), G53's the reference
        position, G28's intermediate point either; under G91 they are where the axes stand,
        which before the first motion the units rule counts is where units-free moves left
        them (an axis with no position yet is refused); an angle is in degrees in either
        unit. Such a move is no first motion for the units rule (`apply_modal`): a post's
        ``G91 G28 Z0.`` or ``G90 G00 X0 Y0`` before its G20 is read."""
        return all(self.real(axis) == 0.0 for axis in axes if axis.letter not in ROTARY_AXES)

    def check_feed(self, code: str, word: Word) -> None:
        """Refuse a feed move of ``code`` (G01, G02/G03, a canned cycle's feed to the hole
        bottom) when no F is in force: it has no time (FANUC stops there with alarm PS0011,
        "feed zero"); ``word`` locates the refusal."""
        state = self.state
        if state.feed is None:
            raise self.fail(f"{code} feeds with no F in force: no feed rate has been given "
                            "yet (a FANUC control stops with alarm PS0011, feed zero); give "
                            "F in this block or before it (mm/min; inch/min under G20)", word)
        if state.feed_inch != state.inch and state.unit_switch is not None:
            was, now = ("inch", "mm") if state.feed_inch else ("mm", "inch")
            number = state.feed * 60.0 / (M_PER_INCH if state.feed_inch else M_PER_MM)
            switch, line = state.unit_switch
            raise self.fail(FEED_BEFORE_UNITS.format(
                code=code, feed_line=state.feed_line, number=f"{number:.10g}", was=was,
                now=now, switch=switch, line=line), word)

    def inch_feed_scale(self, start: dict[str, float], end: dict[str, float],
                        axes: list[Word]) -> float:
        """The factor on the feed of a move from ``start`` to ``end`` that turns a rotary
        axis under an F read in inch/min (`machinesim.nc.rotary_feed`); refused where an
        axis's start is not known and the factor depends on it."""
        row = [[values.get(a, math.nan) for a in AXES] for values in (start, end)]
        scale, unknown = inch_feed_scale(np.array(row[:1]), np.array(row[1:]))
        if unknown[0]:
            first = [w for w in axes if w.letter not in start]
            raise self.fail(
                f"a feed move under an F in inch/min that turns a rotary axis and moves a "
                f"linear one, where {' '.join(w.letter for w in first)} had no position yet: "
                "its degrees count as inches in the feed (FANUC), so its time needs the "
                f"distance; give {' and '.join(w.letter for w in first)} a position first "
                "(e.g. with G00)", first[0])
        return float(scale[0])

    # --- numbers

    def length_unit(self) -> float:
        return M_PER_INCH if self.state.inch else M_PER_MM

    def bare(self, word: Word) -> None:
        """Keep the first line of a non-zero length or angle written without a point, whose
        reading depends on the integer-input rule (`Program.integer_words`)."""
        if self.real(word) != 0.0:
            self.reader.integer_words.setdefault(word.letter, self.line)

    def length_of(self, word: Word) -> float:
        """Metres per unit of a length word (X Y Z I J K R Q). A zero written without a
        point keeps no digit (`digit`): it reads the same whatever the integer input."""
        if "." not in word.text:
            self.bare(word)
            unit = self.length_unit()
            if self.increment is not None:
                metric, inch, _ = self.increment
                unit = inch if self.state.inch else metric
            return unit if self.real(word) == 0.0 else self.digit(unit, word)
        return self.digit(self.length_unit(), word)

    def axis_unit(self, word: Word) -> float:
        if word.letter not in ROTARY_AXES:
            return self.length_of(word)
        if "." not in word.text:
            self.bare(word)
            if self.increment is not None:
                return self.increment[2]
        return RAD_PER_DEG

    def digit(self, unit: float, word: Word) -> float:
        """``unit`` (m per unit of the length ``word``), its last digit's value kept for
        `Program.length_digit` (`Reader.written_to`). Past `MOST_DECIMALS` decimals the
        digit is taken as that many's: ``X1.`` with 400 zeros is 1 mm, and 10 ** 400 is
        beyond float64."""
        point = word.text.find(".")
        self.reader.written_to(unit if point < 0 else unit / 10.0 ** min(
            len(word.text) - 1 - point, MOST_DECIMALS))
        return unit

    def real(self, word: Word) -> float:
        return self.finite(float(word.text), word)

    def finite(self, value: float, word: Word) -> float:
        if not math.isfinite(value):
            raise self.fail(f"value of {brief(word.key)} is out of range (not finite in "
                            "float64)", word)
        return value

    def dwell_p(self, word: Word, code: str) -> float:
        """The dwell P of G04 or of the canned cycle ``code``, s: integer milliseconds, as
        FANUC's, or, written with a decimal point, seconds, as Haas reads it (Haas Mill
        Operator's Manual 96-8000, G04: ``G04 P10.`` is a dwell of 10 seconds, ``G04 P10``
        one of 10 milliseconds; G83: ``G83 Z-0.62 F15. R0.1 Q0.175 P5.`` "will peck several
        times and dwell for five seconds at the end"). A FANUC control takes no decimal
        point in P, so no program it runs reads otherwise here."""
        self.reader.dwell_words[self.line] = word.key
        if "." not in word.text:
            return self.integer(word, "dwell time") / 1000.0
        seconds = self.real(word)
        if not seconds >= 0.0:
            raise self.fail(f"{code}'s dwell {brief(word.key)} must be >= 0 (with a decimal "
                            "point P is seconds, as Haas reads it; without, milliseconds)", word)
        return self.dwell_within(seconds, word, code)

    def dwell_within(self, seconds: float, word: Word, code: str) -> float:
        """``seconds``, the dwell ``word`` of ``code`` states, refused beyond
        `MAX_PROGRAM_TIME_S`, the longest a whole program may take: no program holding it
        could be timed. A long dwell within it is read (and noted by the planner)."""
        if seconds > MAX_PROGRAM_TIME_S:
            raise self.fail(
                f"{code}'s dwell {brief(word.key)} waits {seconds:.3g} s, more than the "
                f"{MAX_PROGRAM_TIME_S:.6g} s (2**39 s, about 17,400 years) a whole program may "
                "take: its clock, a float64 sum of seconds, keeps 0.1 ms only up to there; "
                "is the time in the unit meant (P counts milliseconds without a decimal "
                "point, seconds with one; X seconds)?", word)
        return seconds

    def integer(self, word: Word, what: str) -> int:
        number = integer(word)
        if number is None:
            raise self.fail(f"{what} must be an unsigned integer of at most "
                            f"{MAX_INTEGER_DIGITS} digits, got {brief(word.key)}", word)
        return number
