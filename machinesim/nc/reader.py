"""The reader's run over one file: the modal state, the problems, the moves as they come.

`Reader` makes the reader's two passes. The first (`machinesim.nc.layout`) finds the programs
in the file (the main program and its O-numbered subprograms), their calls, and every
malformed word. The second runs the main program block by block (`machinesim.nc.blocks`) on a
modal state (`_State`), expanding arcs, canned cycles and subprogram calls into moves
(`_Output`); runs of plain modal motion lines go through the vectorised fast path
(`Reader.fast_run`, on `machinesim.nc.fastscan`'s scan) with identical results. Every refusal
is collected (`_Problems`), and one `NCProgramError` lists them all at the end.

Internal to the reader: `machinesim.nc.parser` checks the arguments and the bytes, then runs a
`Reader`.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from machinesim.exceptions import MachineSimWarning, NCProgramError, brief, line_of
from machinesim.nc import fastscan
from machinesim.nc.arcs import NearCircle, near_circle_warning
from machinesim.nc.blocks import Block
from machinesim.nc.layout import Layout
from machinesim.nc.lexer import Word, tokenize
from machinesim.nc.program import (
    AXES,
    KIND_DWELL,
    KIND_LINEAR,
    ROTARY_AXES,
    FrozenMapping,
    Program,
)
from machinesim.nc.rotary_feed import inch_feed_scale
from machinesim.nc.tooltable import ToolTable
from machinesim.nc.words import (
    INCREMENTS,
    M_PER_INCH,
    MAX_INTEGER_DIGITS,
    MAX_MOVES,
    MAX_SUBPROGRAM_DEPTH,
    SLOWEST_FEED_M_PER_S,
    Call,
    integer,
)
from machinesim.units import M_PER_MM, RAD_PER_DEG

__all__ = ["FAST_MIN_LINES", "MAX_LISTED", "MAX_PROBLEMS", "Reader"]

#: Problems listed in the message of the one error (all are in its ``problems``).
MAX_LISTED = 100
#: Reading stops after this many problems: the rest would be consequences.
MAX_PROBLEMS = 10_000
#: Runs of at least this many simple lines go through the vectorised fast path (below, the
#: per-line Python path is as fast as numpy's per-call overhead).
FAST_MIN_LINES = 16


@dataclass
class _State:
    """The modal state of the control while reading, in SI."""

    motion: str | None = None  # G00 G01 G02 G03
    incremental: bool = False
    inch: bool = False
    plane: str = "G17"
    work_offset: str = "G54"
    feed: float | None = None
    #: the F was read under G20 (inch/min): a move turning a rotary axis counts its degrees
    #: as inches (`machinesim.nc.rotary_feed`)
    feed_inch: bool = False
    feed_line: int | None = None  # the line of the F in force
    #: the G20/G21 that last switched the units, and its line (an F before it: `check_feed`)
    unit_switch: tuple[str, int] | None = None
    spindle: float | None = None
    target: dict[str, float] = field(default_factory=dict)
    number: int | None = None
    end: tuple[int, str] | None = None
    length_mode: str = "G49"
    h: int = 0
    h_given: bool = False  # an H word has been read: a bare G43/G44 then takes it
    #: (line, words, the length the last absolute Z carried, m) of a tool length change that
    #: no absolute Z has carried yet: an incremental Z then ends apart on different controls
    length_change: tuple[int, str, float] | None = None
    #: Z last moved to the reference position (G28 Z) or to machine coordinates (G53 Z),
    #: which cancel the tool length offset vector on Z until a Z word restores it, G43/G44
    #: staying modal (FANUC Series 0i-MB B-63844EN/02, 14.1.2): a G43/G44/G49 then changes
    #: the offset from 0, and a post's G49 after its G28 G91 Z0. changes nothing
    length_cancelled: int | None = None  # the line of that G28 Z or G53 Z
    cycle: str | None = None
    cycle_z: float | None = None  # machine Z of the hole bottom
    cycle_r: float | None = None  # machine Z of the R plane
    cycle_q: float | None = None
    #: Haas's variable peck (I first, J reduction, K smallest, m) in place of Q
    cycle_pecks: tuple[float, float, float] | None = None
    #: Haas's G73 K beside Q: the depth, m, drilled between returns to the R plane
    cycle_return: float | None = None
    #: the distance mode (G91: True) and line each of R and Z was last given in
    cycle_given: dict = field(default_factory=dict)
    cycle_p: float = 0.0
    cycle_p_word: str = ""  # that P as written and its line, for a later block's dwell note
    peck_dwell: bool = False  # P given in a G73/G83 block: they dwell it after the last peck
    initial_z: float | None = None
    retract: str = "G98"
    exact_stop: bool = False  # G61 (every block ends in position) until G64


class _Problems:
    """Every refusal, once each (a subprogram run 100 times reports its error once)."""

    def __init__(self, source: str, block_at: Callable[[int], int | None]) -> None:
        self.found: dict[tuple, NCProgramError] = {}
        self.source = source  # the program's: a line of another file has no N word here
        self.block_at = block_at  # a line's N word (`Reader.block_at`)

    def add(self, error: NCProgramError) -> None:
        if len(self.found) >= MAX_PROBLEMS:
            return  # within one line too: a line of 2 million repeated words is one mistake
        if error.line is not None and error.block is None and error.source == self.source:
            block = self.block_at(error.line)
            if block is not None:  # every refusal passes here: its line named with its N
                error = NCProgramError(error.message, source=error.source, line=error.line,
                                       column=error.column, key=error.key, block=block)
        key = (error.line, error.column, error.key, str(error))
        self.found.setdefault(key, error)

    def __len__(self) -> int:
        return len(self.found)

    def raise_all(self, source: str) -> None:
        if not self.found:
            return
        errors = sorted(self.found.values(), key=lambda e: (e.line or 0, e.column or 0))
        if len(errors) == 1:
            raise errors[0]
        listed = "\n".join(f"  {e}" for e in errors[:MAX_LISTED])
        more = len(errors) - MAX_LISTED
        tail = f"\n  ... and {more} more (all in .problems)" if more > 0 else ""
        first = errors[0]
        stopped = "reading stopped there; " if len(errors) >= MAX_PROBLEMS else ""
        error = NCProgramError(
            f"{len(errors)} problems in the program ({stopped}the first at "
            f"{line_of(first.line or 0, first.block)}; a "
            "refused block moves nothing, so a later problem may follow from an earlier "
            f"one: mend them in order):\n{listed}{tail}",
            source=source, line=first.line, column=first.column, key=first.key,
            block=first.block,
        )
        error.problems = tuple(errors)
        raise error


class _Output:
    """The moves as they come: Python lists for single blocks, arrays for expanded runs."""

    def __init__(self) -> None:
        self.chunks: list[tuple[np.ndarray, ...]] = []
        self.lists: tuple[list, ...] = tuple([] for _ in range(8))
        self.m_codes: dict[int, tuple[int, ...]] = {}
        self.stops: list[np.ndarray] = []  # indices of moves that end in an exact stop
        self.count = 0
        # the line of the first move that is no dwell and whose target depends on the units
        self.first_motion: int | None = None

    def add(self, kind: int, target: Mapping[str, float], feed: float | None, dwell: float,
            line: int, block: int | None, spindle: float | None, *,
            units_free: bool = False) -> None:
        """One move; ``units_free`` when its target is the same read in mm or in inch (a
        G00, G01, G28 or G53 of zero lengths, `Block.units_free`): it is no first motion for
        the units rule."""
        rows, kinds, feeds, dwells, lines, spindles, blocks, arcs = self.lists
        rows.append(tuple(target.get(a, math.nan) for a in AXES))
        kinds.append(kind)
        feeds.append(math.nan if feed is None else feed)
        dwells.append(dwell)
        lines.append(line)
        spindles.append(math.nan if spindle is None else spindle)
        blocks.append(-1 if block is None else block)
        arcs.append(math.nan)
        self.count += 1
        if self.first_motion is None and kind != KIND_DWELL and not units_free:
            self.first_motion = line

    def add_arrays(self, *arrays: np.ndarray, units_free: np.ndarray | None = None) -> None:
        """Moves as arrays: targets, kinds, feeds, dwells, lines, spindles, blocks and, for
        an arc's chords, the length of the arc each stands for (`Program.arc_lengths`;
        default NaN: none); ``units_free``: which of them reach the same target in mm or
        inch (`add`)."""
        if len(arrays) == 7:
            arrays = (*arrays, np.full(len(arrays[1]), math.nan))
        self.flush()
        self.chunks.append(arrays)
        self.count += len(arrays[1])
        if self.first_motion is None:
            moving = arrays[1] != KIND_DWELL
            motion = np.flatnonzero(moving if units_free is None else moving & ~units_free)
            if motion.size:
                self.first_motion = int(arrays[4][motion[0]])

    def flush(self) -> None:
        rows, kinds, feeds, dwells, lines, spindles, blocks, arcs = self.lists
        if kinds:
            self.chunks.append((
                np.array(rows, dtype=np.float64).reshape(-1, len(AXES)),
                np.array(kinds, dtype=np.int8), np.array(feeds, dtype=np.float64),
                np.array(dwells, dtype=np.float64), np.array(lines, dtype=np.int64),
                np.array(spindles, dtype=np.float64), np.array(blocks, dtype=np.int64),
                np.array(arcs, dtype=np.float64)))
            for items in self.lists:
                items.clear()

    def arrays(self) -> tuple[np.ndarray, ...]:
        self.flush()
        if not self.chunks:
            return (np.empty((0, len(AXES))), np.empty(0, np.int8), np.empty(0), np.empty(0),
                    np.empty(0, np.int64), np.empty(0), np.empty(0, np.int64), np.empty(0))
        if len(self.chunks) == 1:
            return self.chunks[0]
        return tuple(np.concatenate(parts) for parts in zip(*self.chunks, strict=True))

class Reader:
    """Both passes over one file: the layout, then the main program's run."""

    def __init__(self, data: bytes, errors: str, source: str, offsets, integer_input: str,
                 tools: ToolTable | None, chord_tolerance: float, fast: bool,
                 reference: FrozenMapping) -> None:
        self.data = data
        self.errors = errors
        self.source = source
        self.offsets = offsets
        self.reference = reference  # G28's reference position (`parse_program`)
        self.integer_input = integer_input
        self.increment = INCREMENTS.get(integer_input)  # (m, inch in m, rad), or None
        self.integer_words: dict[str, int] = {}  # letter -> first line read without a point
        self.tools = tools
        self.chord_tolerance = chord_tolerance
        self.fast = fast
        self.scan = fastscan.scan(data)
        self.line_blocks: dict[int, int | None] = {}  # line -> its N (`block_at`)
        self.problems = _Problems(source, self.block_at)
        self.state = _State()
        self.out = _Output()
        self.states: dict[str, int] = {}
        # (move index, tool number, line) of each T word and (move index, None, line) of
        # each M06, in the order they run
        self.tool_events: list[tuple[int, int | None, int]] = []
        self.arc_blocks = 0  # G02/G03 blocks run
        #: m, what the last digit of the finest length word read stands for (`Program`'s
        #: ``length_digit``; inf: none read yet)
        self.length_digit = math.inf
        #: line -> an arc read short whose end is nearly its start (`near_circle_warning`)
        self.near_circles: dict[int, NearCircle] = {}
        self.unit_words: dict[str, int] = {}  # G20/G21 -> first line
        self.dwell_words: dict[int, str] = {}  # line -> its dwell's P or X, as written
        self.kept_dwells: dict[int, float] = {}  # line -> its longest dwell of a kept P, s
        self.cache: dict[int, list[Word] | None] = {}
        self.after_end: int | None = None  # the first line of text after the closing %
        self.end_mark: int | None = None  # the line of that %, when text follows it
        self.unread_programs: dict[int, int] = {}  # O number after that % -> its line
        n = self.scan.simple.size
        # the end of the run of simple lines each line is in (itself when not simple)
        index = np.where(self.scan.simple, n, np.arange(n))
        self.run_end = np.minimum.accumulate(index[::-1])[::-1]

    def fail(self, message: str, line: int, word: Word | None = None) -> NCProgramError:
        return NCProgramError(message, source=self.source, line=line,
                              column=None if word is None else word.column,
                              key=None if word is None else word.key)

    def block_at(self, line: int) -> int | None:
        """The N word's number of the block at ``line`` (1-based), None when it has none (or
        the line is not in the text): an error's message names both."""
        if line in self.line_blocks:  # once a line: a line of 10,000 refused words
            return self.line_blocks[line]
        block = None
        if 1 <= line <= len(self.scan.starts):
            words = (self.cache.get(line - 1)
                     or tokenize(self.text(line - 1), self.source, line)[0])
            number = next((w.text for w in words if w.letter == "N"), "")
            if number.isdigit() and len(number) <= MAX_INTEGER_DIGITS:
                block = int(number)
        self.line_blocks[line] = block
        return block

    def text(self, i: int) -> str:
        return self.data[self.scan.starts[i]:self.scan.ends[i]].decode("utf-8", self.errors)

    def words(self, i: int, cache: bool = False) -> list[Word] | None:
        """The words of line i (0-based); None when the line has malformed words."""
        if i in self.cache:
            return self.cache[i]
        words, problems = tokenize(self.text(i), self.source, i + 1,
                                   line_feed=bool(self.scan.ends[i] < len(self.data)))
        for problem in problems:
            self.problems.add(problem)
        result = None if problems else words
        if cache:
            self.cache[i] = result
        return result

    def note(self, key: str, line: int) -> None:
        self.states.setdefault(key, line)

    def written_to(self, digit: float) -> None:
        """Keep ``digit`` (m, what the last digit of a length word read stands for) where it
        is finer than those before (`Program.length_digit`)."""
        if digit < self.length_digit:
            self.length_digit = digit

    # --- the whole program

    def read(self) -> Program:
        self.layout = Layout(self)
        self.run(self.layout.main_first, self.layout.main_stop, 0)
        self.problems.raise_all(self.source)
        if self.near_circles:  # read_program / parse_program -> _parse -> here
            warnings.warn(near_circle_warning(self.near_circles, self.source),
                          MachineSimWarning, stacklevel=4)
        targets, kinds, feeds, dwells, lines, spindles, blocks, arcs = self.out.arrays()
        return Program._from_parts(
            targets, kinds, feeds, dwells, lines, spindles, blocks, self.out.m_codes,
            number=self.state.number, source=self.source, work_offsets=self.offsets,
            states=self.states, integer_input=self.integer_input,
            tool_table=None if self.tools is None else self.tools.source,
            tool_changes=self.tool_changes(), arc_blocks=self.arc_blocks,
            unit_words=self.unit_words, integer_words=self.integer_words,
            # no switch after the first motion (`Block.apply_modal`): the units at the end
            unit_in_force=(("G20" if self.state.inch else "G21") if self.unit_words
                           else None),
            dwell_words=self.dwell_words,
            end_words={} if self.state.end is None else {self.state.end[1]: self.state.end[0]},
            exact_stops=np.concatenate(self.out.stops) if self.out.stops else (),
            after_end=self.after_end, arc_chord_tolerance=self.chord_tolerance,
            arc_lengths=arcs,
            length_digit=None if self.length_digit == math.inf else self.length_digit)

    def tool_changes(self) -> tuple:
        """The tools put in the spindle (`ToolChange`), from the T words and M06: at each
        M06 the tool the last T before it selected; in a program without M06 (a turret, a
        machine without changer), each T itself. Empty without a tool table (T words are
        then only listed as states)."""
        if self.tools is None:
            return ()
        events = self.tool_events
        if all(number is not None for _, number, _ in events):
            return tuple(self.tools.change(*event) for event in events)
        found, selected = [], None
        for move, number, line in events:
            if number is not None:
                selected = number
            elif selected is None:
                # it had been passed over, the cut going on with --tool and no word said
                raise NCProgramError(
                    "M06 with no tool selected before it (no T word): which tool it puts "
                    "in the spindle is the control's, not the program's; give T<n> before it "
                    "or in its block (T1 M06), as the tool table's tools are selected",
                    source=self.source, line=line, key="M06")
            else:
                found.append(self.tools.change(move, selected, line))
        return tuple(found)

    def run(self, first: int, stop: int, depth: int) -> None:
        """Run lines [first, stop) (0-based); stops at M99 in a subprogram."""
        scan = self.scan
        state = self.state
        i = first
        slow_until = first
        while i < stop:
            if len(self.problems) >= MAX_PROBLEMS:
                return
            if scan.simple[i]:
                if scan.empty[i]:
                    i += 1
                    continue
                j = min(int(self.run_end[i]), stop)
                if (self.fast and i >= slow_until and j - i >= FAST_MIN_LINES
                        and self.fast_state()):
                    if state.end is None and self.fast_run(i, j):
                        i = j
                        continue
                    slow_until = j
            words = self.words(i, cache=depth > 0)
            if words is None or not words:
                i += 1
                continue
            if state.end is not None and depth == 0:
                self.problems.add(self.fail(
                    f"block after the program end {state.end[1]} on line {state.end[0]}; "
                    "blocks after M02/M30 are refused (subprograms start with their O "
                    "number)", i + 1, words[0]))
                return
            if i in self.layout.skip:
                pass
            elif i == self.layout.first_block and any(w.letter == "O" for w in words):
                self.program_number(words, i + 1)
            elif Block(self, words, i + 1, depth).run() == "return":
                return
            i += 1

    def fast_state(self) -> bool:
        state = self.state
        return (not state.incremental and state.cycle is None
                and state.motion in (None, "G00", "G01"))

    def fast_run(self, i: int, j: int) -> bool:
        """Apply simple lines [i, j) at once; False (nothing done) when any needs the slow
        path's judgement (an error, a move before any motion mode)."""
        state = self.state
        values = self.scan.values[:, i:j]
        point = self.scan.point[:, i:j]
        col = fastscan.COLUMN
        length_unit = M_PER_INCH if state.inch else M_PER_MM
        offset = self.offsets.get(state.work_offset, {})
        tlo = self.tool_length()
        present = [~np.isnan(values[col[letter]]) for letter in AXES]
        moves = present[0].copy()
        for given in present[1:]:
            moves |= given
        rows = np.flatnonzero(moves)
        n = rows.size
        if self.out.count + n > MAX_MOVES:
            return False
        targets = np.empty((n, len(AXES)))
        for k, letter in enumerate(AXES):
            given = present[k]
            if not given.any():
                targets[:, k] = state.target.get(letter, math.nan)
                continue
            unit = RAD_PER_DEG if letter in ROTARY_AXES else length_unit
            bare = given & ~point[col[letter]] & (values[col[letter]] != 0.0)
            if bare.any():
                self.integer_words.setdefault(letter, i + 1 + int(np.argmax(bare)))
            if self.increment:
                metric, inch, angle = self.increment
                small = angle if letter in ROTARY_AXES else (inch if state.inch else metric)
                machine = values[col[letter]] * np.where(point[col[letter]], unit, small)
            else:
                machine = values[col[letter]] * unit
            machine += offset.get(letter, 0.0)
            if letter == "Z":
                machine += tlo
            if np.isinf(machine).any():
                return False
            if np.array_equal(given, moves):  # on every move: no fill needed
                targets[:, k] = machine[rows]
            else:
                targets[:, k] = _fill(machine, given, state.target.get(letter, math.nan), rows)
        g = values[col["G"]]
        start = {None: math.nan, "G00": 0.0, "G01": 1.0}[state.motion]
        has_g = ~np.isnan(g)
        motion = _fill(g, has_g, start, None) if has_g.any() else np.full(j - i, start)
        if state.motion is None and np.isnan(motion[rows]).any():
            return False
        f = values[col["F"]]
        has_f = ~np.isnan(f)
        feed_before = math.nan if state.feed is None else state.feed
        if has_f.any():
            feed = f * length_unit / 60.0
            if np.isinf(feed).any() or (feed[has_f] < SLOWEST_FEED_M_PER_S).any():
                return False  # the block-by-block path names the word
            feed = _fill(feed, has_f, feed_before, None)
        else:
            feed = np.full(j - i, feed_before)
        kinds = motion[rows].astype(np.int8)
        if state.feed is not None and state.feed_inch != state.inch:
            first_f = int(np.argmax(has_f)) if has_f.any() else j - i
            if ((kinds == KIND_LINEAR) & (rows < first_f)).any():
                return False  # a feed under an F from before a unit switch: refused there
        feeds = np.where(kinds == KIND_LINEAR, feed[rows], math.nan)
        if np.isnan(feeds[kinds == KIND_LINEAR]).any():
            return False  # a feed move with no F in force: the block-by-block path names it
        if any(present[k].any() for k, a in enumerate(AXES) if a in ROTARY_AXES):
            if has_f.any() and state.inch != state.feed_inch:
                return False  # Fs in both units in one run: the block-by-block path
            if state.feed_inch:  # degrees count as inches in the feed (`rotary_feed`)
                starts = np.vstack([[state.target.get(a, math.nan) for a in AXES],
                                    targets[:-1]])
                scale, unknown = inch_feed_scale(starts, targets)
                if (unknown & (kinds == KIND_LINEAR)).any():
                    return False  # the block-by-block path names the word
                feeds *= scale
        numbers = values[col["N"], rows]
        blocks = np.where(np.isnan(numbers), -1, numbers).astype(np.int64)
        spindle = math.nan if state.spindle is None else state.spindle
        if state.exact_stop:  # G61: every block ends in position
            self.out.stops.append(self.out.count + np.arange(n, dtype=np.int64))
        # a line whose length words are all zero reaches the same target in mm and inch
        # (`Block.units_free`; G90 only here): no first motion for the units rule
        lengths = [present[AXES.index(a)] & (values[col[a]] != 0.0) for a in "XYZ"]
        self.written_to(fastscan.written_digit(self.scan, i, j, length_unit, length_unit
                                               if self.increment is None else
                                               self.increment[1 if state.inch else 0]))
        self.out.add_arrays(targets, kinds, feeds, np.zeros(n), rows + (i + 1),
                            np.full(n, spindle), blocks,
                            units_free=~(lengths[0] | lengths[1] | lengths[2])[rows])
        if n:
            state.target = {a: float(v) for a, v in zip(AXES, targets[-1].tolist(), strict=True)
                            if v == v}
        if present[AXES.index("Z")].any():  # an absolute Z carries a tool length change
            state.length_change = None
            state.length_cancelled = None
        if not np.isnan(motion[-1]):
            state.motion = ("G00", "G01")[int(motion[-1])]
        if not np.isnan(feed[-1]):
            state.feed = float(feed[-1])
        if has_f.any():
            state.feed_inch = state.inch
            state.feed_line = i + 1 + int(np.flatnonzero(has_f)[-1])
        return True

    def tool_length(self) -> float:
        """The tool length offset added to absolute Z words now, m."""
        state = self.state
        if state.length_mode == "G49" or state.h == 0 or self.tools is None:
            return 0.0
        length = self.tools.length(state.h)
        return length if state.length_mode == "G43" else -length

    def program_number(self, words: list[Word], line: int) -> None:
        word = next(w for w in words if w.letter == "O")
        others = [w for w in words if w is not word]
        if others:
            self.problems.add(self.fail(f"the O number must stand alone in its block, found "
                                        f"{brief(others[0].key)} with it", line, others[0]))
            return
        number = integer(word)
        if number is None:
            self.problems.add(self.fail(f"program number must be an unsigned integer of at "
                                        f"most {MAX_INTEGER_DIGITS} digits, got {brief(word.key)}",
                                        line, word))
            return
        self.state.number = number

    def call(self, call: Call, depth: int, line: int) -> None:
        number, word = call.number, call.program_word
        sub = self.layout.subprograms.get(number)
        if sub is None:
            have = " ".join(f"O{n:04d}" for n in self.layout.subprograms) or "none"
            where = ("the main program itself, which M98 cannot call (a subprogram starts "
                     "with its O number after M02/M30)" if number == self.state.number
                     else "which is not in this file")
            if number in self.unread_programs and number != self.state.number:
                where = (f"which is at line {self.unread_programs[number]}, after the '%' on "
                         f"line {self.end_mark} that ends the program: a FANUC control stops "
                         "reading at that '%' and so does the reader; remove the '%' lines "
                         f"between the M30 and O{number:04d}, so that both programs stand "
                         "before the file's closing '%'")
            # a P of 5 to 8 digits: say how it was read, as O12345 may have been meant
            what = (f"M98 {brief(word.key)} calls O{number:04d} ({call.repeats} x: FANUC's "
                    "P<repeats><4-digit program number>)" if len(word.text) > 4
                    else f"M98 calls O{number:04d}")
            raise self.fail(f"{what}, {where} (subprograms: {have})", line, word)
        if depth + 1 > MAX_SUBPROGRAM_DEPTH:
            raise self.fail(f"subprograms nest deeper than {MAX_SUBPROGRAM_DEPTH} levels",
                            line, word)
        if sub.ret is None:
            return  # the layout has refused it already
        for _ in range(call.repeats):
            self.run(sub.first, sub.stop, depth + 1)


def _fill(values: np.ndarray, given: np.ndarray, initial: float,
          rows: np.ndarray | None) -> np.ndarray:
    """Forward fill of ``values`` where ``given``, starting from ``initial``; at ``rows``.

    Modal words are either rare (G, F: a few lines of a point list) or on nearly every line
    (the axes): both have a path that touches only the exceptions.
    """
    n = values.size
    count = int(np.count_nonzero(given))
    if count == 0:
        filled = np.full(n, initial)
    elif count <= n // 8:
        where = np.flatnonzero(given)
        filled = np.empty(n)
        filled[:where[0]] = initial
        filled[where[0]:] = np.repeat(values[where], np.diff(np.append(where, n)))
    elif n - count <= n // 8:
        filled = values.copy()
        gaps = np.flatnonzero(~given)
        first = np.flatnonzero(np.diff(gaps, prepend=-2) != 1)  # gap runs, by first index
        source = np.repeat(gaps[first] - 1, np.diff(np.append(first, gaps.size)))
        filled[gaps] = np.where(source >= 0, values[np.maximum(source, 0)], initial)
    else:
        index = np.where(given, np.arange(n), -1)
        np.maximum.accumulate(index, out=index)
        filled = np.where(index >= 0, np.take(values, np.maximum(index, 0)), initial)
    return filled if rows is None else filled[rows]
