"""The programs of one NC file: the main program, its subprograms, their calls.

Internal to the reader (`machinesim.nc.reader`): the first pass, which also refuses before
anything runs what would never end (recursion, nesting, runaway repeat counts).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from machinesim.exceptions import NCProgramError
from machinesim.nc.program import PROGRAM_END
from machinesim.nc.words import (
    M99_IN_MAIN,
    MAX_BLOCK_RUNS,
    MAX_SUBPROGRAM_DEPTH,
    Call,
    call_of,
    integer,
)

if TYPE_CHECKING:
    from machinesim.nc.reader import Reader


@dataclass
class Subprogram:
    number: int
    line: int  # 0-based line of its O block
    first: int  # 0-based first line of its body
    stop: int  # 0-based line after its body
    ret: int | None = None  # 0-based line of its M99
    ended: bool = False  # an M02/M30 in it is refused: its missing M99 is the same mistake


class Layout:
    """The programs of the file: the main program, the subprograms and their calls."""

    def __init__(self, reader: Reader) -> None:
        self.reader = reader
        scan = reader.scan
        n = scan.simple.size
        problems = reader.problems
        simple_blocks = np.flatnonzero(scan.simple & ~scan.empty)
        first_simple = int(simple_blocks[0]) if simple_blocks.size else n
        self.first_block = first_simple
        self.main_first, self.main_stop = 0, n
        self.subprograms: dict[int, Subprogram] = {}
        self.skip: set[int] = set()  # O lines refused here, not run
        calls: dict[int | None, list[tuple[Call, int]]] = {None: []}
        current: Subprogram | None = None
        main_end: int | None = None
        blocks: list[int] = []
        for i in np.flatnonzero(~scan.simple).tolist():
            words = reader.words(i)
            if not words:
                continue
            if not blocks:
                self.first_block = min(first_simple, i)
            blocks.append(i)
            line = i + 1
            o_word = next((w for w in words if w.letter == "O"), None)
            if o_word is not None and i != self.first_block:
                self.skip.add(i)
                number = integer(o_word)
                if current is None and main_end is None:
                    message = ("the O number must be the first block of the program; a "
                               "subprogram starts with its O number after the main "
                               "program's end (M02/M30)")
                    error = reader.fail(message, line, o_word)
                    if reader.text(i)[o_word.column - 1] == ":":
                        # NX's sample posts number a tool change block ':0030' (the ISO
                        # alignment function); it had been named 'O0030', never written
                        error = NCProgramError(
                            f"':{o_word.text}' is a program number (':' is the ISO-code "
                            f"address of O: O{o_word.text}): {message}; if it numbers the "
                            f"block, as NX posts write a tool change block, write "
                            f"N{o_word.text}", source=error.source, line=line,
                            column=o_word.column, key=":" + o_word.text)
                    problems.add(error)
                    continue
                if current is None:
                    self.main_stop = i
                else:
                    current.stop = i
                current = Subprogram(-1 if number is None else number, i, i + 1, n)
                if number is None or len(words) > 1:
                    problems.add(reader.fail(
                        f"a subprogram starts with its O number alone in the block, e.g. "
                        f"O2000; got {' '.join(w.key for w in words)}", line, o_word))
                elif number in self.subprograms:
                    problems.add(reader.fail(
                        f"subprogram O{number:04d} is defined twice (first on line "
                        f"{self.subprograms[number].line + 1})", line, o_word))
                else:
                    self.subprograms[number] = current
                    calls[number] = []
                continue
            for word in words:
                code = integer(word) if word.letter == "M" else None
                if code == 99:
                    if current is None:
                        problems.add(reader.fail(M99_IN_MAIN, line, word))
                    elif current.ret is None:
                        current.ret = i
                elif code in PROGRAM_END:
                    if current is None:
                        main_end = i if main_end is None else main_end
                    else:
                        current.ended = True
                        problems.add(reader.fail(
                            f"M{code:02d} in subprogram O{current.number:04d}: a subprogram "
                            "returns with M99. A file is read as one main program (its first) "
                            "and the subprograms after its M02/M30; a file of several main "
                            "programs, each ending in M30, is cut one program a file",
                            line, word))
            call = call_of(words)
            if isinstance(call, Call):
                calls.setdefault(None if current is None else current.number, []).append(
                    (call, i))
        is_block = scan.simple & ~scan.empty
        is_block[blocks] = True
        block_lines = np.flatnonzero(is_block)

        def between(first: int, stop: int) -> np.ndarray:
            return block_lines[np.searchsorted(block_lines, first):
                               np.searchsorted(block_lines, stop)]

        for sub in self.subprograms.values():
            if sub.ret is None:
                if not sub.ended:
                    problems.add(reader.fail(f"subprogram O{sub.number:04d} has no M99 "
                                             "(return) before the next O number or the end "
                                             "of the file", sub.line + 1))
                continue
            late = between(sub.ret + 1, sub.stop)
            if late.size:
                first = int(late[0])
                problems.add(reader.fail(
                    f"block after M99 on line {sub.ret + 1}, which ends subprogram "
                    f"O{sub.number:04d}; it would never run", first + 1,
                    (reader.words(first) or [None])[0]))
        counts = {None: between(self.main_first, self.main_stop).size}
        counts.update({s.number: between(s.first, s.stop).size
                       for s in self.subprograms.values()})
        # subprogram number -> line of its O block (1-based), for the calls' checks
        self.defined = {s.number: s.line + 1 for s in self.subprograms.values()}
        self.check_calls(calls, counts)

    def check_calls(self, calls, counts) -> None:
        """Refuse recursion, nesting beyond the limit and runaway repeat counts, statically."""
        reader = self.reader
        runs: dict[int | None, int] = {}

        def total(key: int | None, chain: tuple[int | None, ...]) -> int:
            if key in runs:
                return runs[key]
            count = counts.get(key, 0)
            for call, i in calls.get(key, []):
                number = call.number
                if number not in self.subprograms:
                    continue  # refused where it runs
                if number in chain or len(chain) > MAX_SUBPROGRAM_DEPTH:
                    path = " -> ".join("main" if k is None else f"O{k:04d}"
                                       for k in chain + (number,))
                    what = ("calls itself" if number in chain
                            else f"nests deeper than {MAX_SUBPROGRAM_DEPTH} levels")
                    why = ("the program would never end" if number in chain else
                           f"FANUC controls nest 4 to {MAX_SUBPROGRAM_DEPTH} levels; call the "
                           "deepest ones from a shallower level")
                    raise reader.fail(f"subprogram O{number:04d} {what} ({path}); {why}",
                                      i + 1, call.program_word)
                count += call.repeats * total(number, chain + (number,))
                if count > MAX_BLOCK_RUNS:
                    raise reader.fail(f"with its repeats the program runs more than "
                                      f"{MAX_BLOCK_RUNS} blocks; machinesim refuses it before "
                                      "running it", i + 1, call.repeats_word)
            runs[key] = count
            return count

        try:
            total(None, (None,))
        except NCProgramError as error:
            reader.problems.add(error)
            for sub in self.subprograms.values():
                sub.ret = None  # no call runs: the program is refused anyway
