"""Read FANUC-style NC text into a `Program`; the language rules are in `machinesim.nc`.

`parse_program` (text) and `read_program` (a file) check their arguments and the bytes (a byte
order mark and a DOS end-of-file mark are skipped; a file that is empty, UTF-16 or not text
at all is refused in one line), then run a `machinesim.nc.reader.Reader` over them: its two
passes, the layout of the file's programs and the main program's run block by block, are
described there. Every refusal is collected, and one `NCProgramError` lists them all at the
end.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from typing import Any, Literal

from machinesim._io import check_readable_file
from machinesim.exceptions import NCProgramError
from machinesim.nc.arcs import ARC_CHORD_M
from machinesim.nc.program import (
    INTEGER_INPUTS,
    Program,
    axis_values,
    work_offsets_si,
)
from machinesim.nc.reader import FAST_MIN_LINES as FAST_MIN_LINES  # defined here before
from machinesim.nc.reader import MAX_LISTED as MAX_LISTED
from machinesim.nc.reader import MAX_PROBLEMS as MAX_PROBLEMS
from machinesim.nc.reader import Reader
from machinesim.nc.tape import end_of_program, programs_after_end, without_leader
from machinesim.nc.tooltable import tool_table
from machinesim.nc.words import (
    INCREMENT_INCH_M,
    INCREMENT_M,
    INCREMENT_RAD,
    M_PER_INCH,
    MAX_BLOCK_RUNS,
    MAX_INTEGER_DIGITS,
    MAX_LINES,
    MAX_MOVES,
    MAX_SUBPROGRAM_DEPTH,
)

IntegerInput = Literal["calculator", "increment", "is-b", "is-c"]


def parse_program(
    text: str,
    source: str = "<string>",
    *,
    work_offsets: Mapping[str, Mapping[str, float]] | None = None,
    reference: Mapping[str, float] | None = None,
    integer_input: IntegerInput = "calculator",
    tools: Any = None,
    chord_tolerance: float = ARC_CHORD_M,
    fast: bool = True,
) -> Program:
    """Read an NC program.

    Parameters
    ----------
    text : str
        The program, in the language described in `machinesim.nc`.
    source : str
        Name of the program in messages and in `Program.source`.
    work_offsets : mapping, optional
        {"G54": {"X": m, ...}, ...} in SI; absent axes are zero, and so is G54. A G55..G59
        the program selects is refused when absent from a mapping given (not empty), and
        zero, listed in `Program.states`, when none is given.
    reference : mapping, optional
        {"Z": m, ...}: the machine coordinates (SI) of the reference position G28 returns
        to, and from which G53's words are measured (FANUC's machine zero, where its
        reference point is by default); absent axes are at machine zero. ``machinesim cut``
        gives the machine's home (`Machine.home`): Z at the top of its travel.
    integer_input : {"calculator", "increment", "is-b", "is-c"}
        How a length or angle without decimal point reads: "calculator" (X10 is 10 mm, the
        default) or in least input increments (`words.INCREMENTS`): "increment" (the
        nanometre machines': X10 is 10 nm, A10 0.0001 deg), "is-b" (FANUC IS-B: X10 is
        0.01 mm, A10 0.01 deg) or "is-c" (IS-C: X10 is 0.001 mm, A10 0.001 deg). Which
        axis words were read without a point is kept (`Program.integer_words`).
    tools : path, dict or ToolTable, optional
        The tool table for H (tool length, G43/G44), T and D words
        (`machinesim.nc.tooltable`).
    chord_tolerance : float
        Largest distance, m, between an arc and the straight moves that replace it; kept as
        `Program.arc_chord_tolerance`. The default, 1 nm (the axes' resolution), is what a
        cut with a V or nose tool follows; one with a ball or flat end mill follows 100 nm
        (`machinesim.tools.path_chord_tolerance`) and runs ten times fewer sweeps on arcs
        read so (`machinesim.cutting.cut` notes a program read otherwise).
    fast : bool
        Read runs of plain motion lines with the vectorised path (the same result; False
        is for tests and benchmarks).

    Returns
    -------
    Program
        Moves with absolute machine targets in SI; `Program.states` lists the words read
        as states and `Program.integer_input` the rule used.

    Raises
    ------
    NCProgramError
        For anything not understood, naming source, line, column and word; when there are
        several, one error lists them all (its ``problems`` holds each).
    """
    if not isinstance(text, str):
        raise NCProgramError(f"NC program text must be str, got {type(text).__name__}",
                             source=source)
    return _parse(text.encode("utf-8", "surrogatepass"), "surrogatepass", source,
                  work_offsets, integer_input, tools, chord_tolerance, fast, reference=reference)


def read_program(path: str | os.PathLike, **kwargs) -> Program:
    """Read an NC program file (keyword arguments as `parse_program`; source is the path).

    Bytes that are not UTF-8 read as U+FFFD and are refused where they stand. An empty file
    (or one of white space only) is refused: it is a wrong path far more often than a
    program.
    """
    if not isinstance(path, str | os.PathLike):
        raise NCProgramError(f"expected the NC program's path as a str or Path, got "
                             f"{type(path).__name__}", key="path")
    source = os.fspath(path)
    if isinstance(source, str) and "\n" in source:  # the program's text, given as a path
        first = source.strip().splitlines()[0][:40] if source.strip() else ""
        raise NCProgramError(f"expected the NC program's path, got text of "
                             f"{source.count(chr(10)) + 1} lines ({first!r} ...): read text "
                             "with machinesim.nc.parse_program(text)", key="path")
    check_readable_file(path, "NC program")
    try:
        data = _read_lines_bounded(path, source)
    except OSError as exc:
        raise NCProgramError(f"cannot read the NC program: {exc.strerror or exc}",
                             source=source) from None
    _refuse_binary(data, source)
    if not data.removeprefix(UTF8_BOM).strip():
        raise NCProgramError(
            f"the file is empty ({len(data)} bytes{', all white space' if data else ''}); "
            "expected an NC program (blocks such as G01 X1. F100.)", source=source)
    return _parse(data, "replace", source, kwargs.pop("work_offsets", None),
                  kwargs.pop("integer_input", "calculator"), kwargs.pop("tools", None),
                  kwargs.pop("chord_tolerance", ARC_CHORD_M), kwargs.pop("fast", True),
                  **kwargs)


def _parse(data: bytes, errors: str, source: str, work_offsets, integer_input, tools,
           chord_tolerance, fast, reference=None, **unknown) -> Program:
    if unknown:
        raise NCProgramError(f"unknown keyword argument(s) {sorted(unknown)}; expected "
                             "work_offsets, reference, integer_input, tools, chord_tolerance, "
                             "fast", source=source)
    if reference is not None and not isinstance(reference, Mapping):
        raise NCProgramError(f"reference must be a mapping like {{'Z': 0.1}} (m, rad), got "
                             f"{type(reference).__name__}", source=source, key="reference")
    if integer_input not in INTEGER_INPUTS:
        raise NCProgramError(f"integer_input must be one of {INTEGER_INPUTS}, got "
                             f"{integer_input!r}", source=source, key="integer_input")
    try:
        tolerance = float(chord_tolerance)
    except (TypeError, ValueError):
        tolerance = math.nan
    if not tolerance > 0.0 or not math.isfinite(tolerance):
        raise NCProgramError(f"chord_tolerance must be a length > 0 (m), got "
                             f"{chord_tolerance!r}", source=source, key="chord_tolerance")
    offsets = work_offsets_si(work_offsets, source=source)
    if data.count(b"\n") + (not data.endswith(b"\n")) > MAX_LINES:
        _refuse_many_lines(source)
    data = data.removeprefix(UTF8_BOM)  # Windows editors start UTF-8 files with one
    if data.rstrip().endswith(DOS_EOF):  # DOS editors and DNC senders end files with one
        data = data.rstrip().rstrip(DOS_EOF)
    whole = without_leader(data)
    data, after_end = end_of_program(whole)
    reader = Reader(data, errors, source, offsets, integer_input, tool_table(tools),
                     tolerance, fast, axis_values(reference or {}, source=source))
    reader.after_end = after_end
    if after_end is not None:
        reader.end_mark, reader.unread_programs = programs_after_end(whole, data)
    return reader.read()


#: The byte order mark some editors write at the start of a UTF-8 file; not part of line 1.
UTF8_BOM = b"\xef\xbb\xbf"
#: Ctrl-Z, the end-of-file mark DOS editors and DNC programs write after a program's last
#: line; read as the file's end there (anywhere else it is refused as a control byte).
DOS_EOF = b"\x1a"
#: Bytes read to tell text from not, and the share of them that are not text (control bytes
#: other than white space, or not UTF-8) above which a file is refused whole, in one line,
#: rather than as a problem at every block.
TEXT_PROBE_BYTES = 4096
NOT_TEXT_SHARE = 0.05
#: ... and at least this many of them: a short program's comment holding a terminal colour
#: code (ESC and a NUL, 2 of 39 characters) had made the file 'not text', where the reader
#: reads any character in a comment and names a stray one elsewhere at its line.
NOT_TEXT_FEWEST = 8
#: UTF-16 without a byte-order mark: more than this share of the bytes on one side of each
#: character are zero (and almost none on the other side).
UTF16_ZERO_SHARE = 0.3
#: Text in a one-byte encoding (Latin-1, Windows-1252) with more than this share of bytes
#: that are not UTF-8 is refused whole too: an NC program is mostly ASCII words.
NOT_ASCII_SHARE = 0.5
_TEXT_CONTROLS = frozenset(b"\t\n\r\f\v")


#: Bytes read at a time by `read_program`, counting line ends as it goes.
READ_CHUNK_BYTES = 1 << 24


def _read_lines_bounded(path, source: str) -> bytes:
    """The file's bytes, read a chunk at a time and refused as soon as they hold more than
    `words.MAX_LINES` lines: a file of 21 million short lines had been read whole, split
    into lines and scanned (3.2 GB after 120 s) before its moves reached `MAX_MOVES`."""
    chunks = []
    line_ends = 0
    with open(path, "rb") as file:
        while chunk := file.read(READ_CHUNK_BYTES):
            line_ends += chunk.count(b"\n")
            if line_ends > MAX_LINES:
                _refuse_many_lines(source)
            chunks.append(chunk)
    return b"".join(chunks)


def _refuse_many_lines(source: str) -> None:
    raise NCProgramError(
        f"the program has more than {MAX_LINES} lines, the most machinesim reads "
        f"(nc.words.MAX_LINES; each line holds one block at most, and a program may expand "
        f"to {MAX_MOVES} moves), refused before any is parsed: split it into programs of "
        "fewer lines", source=source)


def _refuse_binary(data: bytes, source: str) -> None:
    """Refuse, in one message, a file that is UTF-16 or not text at all (a binary picked by
    mistake); a stray byte in a text program is left to the reader, which names its line."""
    probe = data[:TEXT_PROBE_BYTES]
    if probe[:4] in (b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff") or _utf32_zeros(probe):
        raise NCProgramError(
            "the file is UTF-32 text (a byte-order mark, or three zero bytes beside each "
            "character); expected ASCII or UTF-8: save it as UTF-8", source=source)
    if probe[:2] in (b"\xff\xfe", b"\xfe\xff") or _utf16_zeros(probe):
        raise NCProgramError(
            "the file is UTF-16 text (a byte-order mark or a zero byte beside each "
            "character, as Windows Notepad's 'Unicode' saves it); expected ASCII or UTF-8: "
            "save it as UTF-8", source=source)
    text = probe.decode("utf-8", "replace")
    if len(data) <= TEXT_PROBE_BYTES and data.rstrip().endswith(DOS_EOF):
        text = text[:text.rindex("\x1a")]  # a DOS end-of-file mark, skipped where it stands
    controls = [i for i, ch in enumerate(text)
                if ord(ch) == 127 or (ord(ch) < 32 and ord(ch) not in _TEXT_CONTROLS)]
    odd = sorted(controls + [i for i, ch in enumerate(text) if ch == "\ufffd"])
    # Text in a one-byte encoding (Latin-1, Windows-1252: a comment's 'ä' or '°') holds no
    # control byte and is mostly ASCII: its bytes that are not UTF-8 are left to the reader,
    # which reads them in a comment and names any other; a short program's one comment had
    # made it 'not text'.
    size = max(len(text), 1)
    if len(odd) > max(NOT_TEXT_SHARE * size, NOT_TEXT_FEWEST) and (
            controls or len(odd) > NOT_ASCII_SHARE * size):
        odd, first = len(odd), odd[0]
        raise NCProgramError(
            f"not a text file: {odd} of its first {len(text)} characters are control bytes "
            f"or not UTF-8 (the first at character {first + 1}); expected an NC program as "
            "ASCII or UTF-8 text", source=source)


def _utf32_zeros(probe: bytes) -> bool:
    """Whether ``probe`` reads as UTF-32 without a byte-order mark: ASCII saved so has three
    zero bytes beside each character, the same three of every four, and the fourth text, not
    the low bytes of small binary integers (it had been called UTF-16 with its mark, 'not a
    text file' without)."""
    quarter = len(probe) // 4
    if quarter < 2:
        return False
    lanes = sorted((probe[k::4] for k in range(4)), key=lambda lane: lane.count(0))
    if lanes[1].count(0) != quarter:
        return False
    text = lanes[0]  # the characters' lane, which in text holds few controls or zeros
    odd = sum(1 for b in text if b == 127 or (b < 32 and b not in _TEXT_CONTROLS))
    return odd < NOT_TEXT_SHARE * quarter


def _utf16_zeros(probe: bytes) -> bool:
    """Whether ``probe`` reads as UTF-16 without a byte-order mark: ASCII saved so has a
    zero beside each character, on one side only (the high byte). A binary (an executable,
    a PLY picked by mistake) has zeros on both sides and is no text at all."""
    if len(probe) < 4:
        return False
    half = len(probe) // 2
    even, odd = probe[0::2].count(0), probe[1::2].count(0)
    return max(even, odd) > UTF16_ZERO_SHARE * half and min(even, odd) < NOT_TEXT_SHARE * half


__all__ = ["INCREMENT_INCH_M", "INCREMENT_M", "INCREMENT_RAD", "MAX_BLOCK_RUNS",
           "MAX_INTEGER_DIGITS", "MAX_LINES", "MAX_MOVES", "MAX_SUBPROGRAM_DEPTH", "M_PER_INCH",
           "parse_program", "read_program"]
