"""Split one line of NC text into words; the rules are in `machinesim.nc`."""

from __future__ import annotations

import re
import string
from dataclasses import dataclass

from machinesim.exceptions import NCProgramError

_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)")
_BLANK = " \t\r"
_LETTERS = frozenset(string.ascii_letters)


@dataclass(frozen=True)
class Word:
    """One word: an address letter and its number, as written."""

    letter: str  # upper case
    text: str  # the number as written
    column: int  # 1-based column of the letter

    @property
    def key(self) -> str:
        return self.letter + self.text


def tokenize(raw: str, source: str, line: int) -> tuple[list[Word], list[NCProgramError]]:
    """Words of one line and the problems found in it (comments, blanks, '%' give no words).

    A problem does not stop the line: the reader skips to the next blank, letter or comment
    and goes on, so that one pass lists every malformed word of the line.
    """
    words: list[Word] = []
    problems: list[NCProgramError] = []
    percent = False
    i, n = 0, len(raw)

    def fail(message: str, column: int, key: str) -> None:
        problems.append(NCProgramError(message, source=source, line=line, column=column,
                                       key=key))

    while i < n:
        c = raw[i]
        if c in _BLANK:
            i += 1
        elif c == "(":
            close = raw.find(")", i + 1)
            if close < 0:
                fail("comment '(' is not closed on its line", i + 1, "(")
                break
            inner = raw.find("(", i + 1, close)
            if inner >= 0:  # one problem, not one per word of the comment's rest
                fail("comments do not nest: this '(' is inside the comment opened at "
                     f"column {i + 1}, which ends at the first ')'", inner + 1, "(")
                close = max(close, raw.rfind(")"))
            i = close + 1
        elif c == ";":
            break
        elif c == ")":
            fail("')' without an opening '('", i + 1, ")")
            i += 1
        elif c == "%" or percent:
            if words or percent:
                fail("'%' must stand alone on its line (comments aside)", i + 1, c)
                if c != "%":
                    i = _end_of_garbage(raw, i + 1)
                    continue
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
                stop = _end_of_garbage(raw, i)
                tail = raw[i:stop]
                fail(
                    f"malformed number {tail!r} after {c.upper()!r}; expected digits with an "
                    f"optional sign and decimal point, e.g. {c.upper()}-12.5",
                    start + 1,
                    c.upper() + tail,
                )
                i = max(stop, i)
                continue
            words.append(Word(c.upper(), match.group(), start + 1))
            i = end
        elif c in "0123456789+-.":
            stop = _end_of_garbage(raw, i)
            fail(f"number {raw[i:stop]!r} without an address letter", i + 1, raw[i:stop])
            i = stop
        else:
            fail(
                f"unexpected character {c!r}; expected words (a letter and a number), "
                "'(comment)', ';comment' or a lone '%'",
                i + 1,
                c,
            )
            i = max(_end_of_garbage(raw, i + 1), i + 1)
    return words, problems


def _end_of_garbage(raw: str, i: int) -> int:
    while i < len(raw) and raw[i] not in _BLANK and raw[i] not in _LETTERS and raw[i] not in "(;":
        i += 1
    return i
