"""What a FANUC control reads of an NC file: not the leader section after the opening %,
and nothing after the % that ends the program.

FANUC Series 16i/18i Operator's Manual (B-63524EN/01, 8. "Data input/output", "File
format", http://cncmanuals.com/fanuc/150/series-16i-18i-160i-180i-tb-operators-manual/page/675):
"A file starts with % or LF, followed by the actual data. A file always ends with %." So
the % that opens a file is the start mark and the next one ends it; in a file that does not
open with one, the first % ends it. What follows is not read (another program a DNC sender
appended, an editor's leftovers), and had been read here as more of the program.

FANUC Fast Ethernet / Data Server Operator's Manual (B-64014EN/03, 2.5 "NC program
format"): the text from the opening % up to the first end of block is the leader section,
and the control ignores it. Posts and DNC senders put a title there (``% TITLE``,
``%O1234 (PART)``); it had been refused as words beside the %.
"""

from __future__ import annotations

import re

__all__ = ["end_of_program", "programs_after_end", "without_leader"]

#: A program number at a line's start (after white space): O, or ':' as ISO tapes write it.
_PROGRAM_NUMBER = re.compile(rb"^[ \t]*[Oo:][ \t]*([0-9]+)")


def without_leader(data: bytes) -> bytes:
    """``data`` with the text after the opening % on its line (the leader section) blanked,
    one space a character, so that every line keeps its number and every column its place.

    The opening % is the first character of the first line that holds anything but white
    space. The leader ends at the line's LF, or at a CR or ';' before it: a lone CR (old Mac
    line ends) and blocks after a ';' (FANUC's end of block as printed) are left for the
    reader to refuse, where taking them for part of the leader would drop a whole program
    written on one such "line" and read it as empty.
    """
    start = len(data) - len(data.lstrip())
    if not data[start:start + 1] == b"%":
        return data
    end = len(data)
    for mark in (b"\n", b"\r", b";"):
        found = data.find(mark, start)
        if found >= 0:
            end = min(end, found)
    blanks = b" " * len(data[start + 1:end].decode("utf-8", "replace"))
    return data[:start + 1] + blanks + data[end:]


def end_of_program(data: bytes) -> tuple[bytes, int | None]:
    """``data`` up to the end of its line with the % that ends the program (with its line
    end), and the first
    line (1-based) after it that holds anything but white space (None when none does, or
    when no % ends the program)."""
    lines = data.split(b"\n")
    marks = [i for i, line in enumerate(lines) if line.strip().startswith(b"%")]
    if not marks:
        return data, None
    first_text = next((i for i, line in enumerate(lines) if line.strip()), None)
    end = marks[0] if marks[0] != first_text else (marks[1] if len(marks) > 1 else None)
    if end is None:
        return data, None
    after = next((i + 1 for i in range(end + 1, len(lines)) if lines[i].strip()), None)
    return data[:sum(len(line) + 1 for line in lines[:end + 1])], after


def programs_after_end(data: bytes, kept: bytes) -> tuple[int, dict[int, int]]:
    """The line (1-based) of the % that ends the program (``kept`` being what
    `end_of_program` kept of ``data``), and the program numbers that start a line after it,
    each with its first line: programs a FANUC control does not read, named when the
    program calls one of them. A main program and its subprograms are loaded from one file
    by reading it up to its closing % (CNC Concepts, "Controlling when the machine stops
    reading a program", https://www.cncci.com/post/controlling-when-the-machine-stops-reading-a-program:
    with the control set to stop at the %, the programs before it are all loaded), and
    that % ends the file (B-63524EN/01 above): one after it is not loaded."""
    mark = kept.count(b"\n") + (0 if kept.endswith(b"\n") else 1)
    numbers: dict[int, int] = {}
    for i, line in enumerate(data[len(kept):].split(b"\n")):
        found = _PROGRAM_NUMBER.match(line)
        if found:
            numbers.setdefault(int(found.group(1)), mark + 1 + i)
    return mark, numbers
