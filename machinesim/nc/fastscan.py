"""Vectorised reading of the lines that are plain modal motion: the NC reader's fast path.

A point-list program (slow tool servo, ruled surfaces: 10^5 to 10^7 lines such as
``X1.234567 Z-0.012345 C123.45678``) is read here with numpy over the whole text instead of
word by word in Python. `scan` classifies every line and, for the *simple* ones, returns the
number of each word; the parser applies the modal state to runs of simple lines at once and
hands every other line to its word-by-word path. Both paths give bit-identical moves
(tests/test_nc_fast.py compares them on the corpus and on generated programs).

A line longer than `CHUNK_BYTES` is not simple, whatever it holds: its per-character arrays
had cost 50 bytes a character (a 48 MB line: 2.6 GB and 16 s here alone, where 48 MB of
short lines take 0.6 GB).

A line is simple when it holds only words N G X Y Z A B C F (either case), each at most
once, every letter directly followed by its number (``X 1.`` is read by the word-by-word
path), numbers of the form ``[+-]digits[.digits]`` or ``[+-].digits`` with at most
`MAX_DIGITS` digits, G0/G1 without sign or point, N an unsigned integer of at most 9 digits,
F > 0; blanks are space, tab and a carriage return right before the line feed (the CR of
CRLF). A line of blanks only is simple and empty. A line with a lone CR (not followed by LF,
as old Mac files end lines) is not simple: the word-by-word path refuses it.

Exactness: a number with at most 15 digits is an integer m < 10^15 < 2^53 over 10^k
(k <= 15), both exact in float64, so the one IEEE division m / 10^k is the correctly
rounded value of the decimal: exactly what ``float(text)`` gives.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from machinesim._cores import usable_cores

#: Letters of simple lines, in the column order of `Scan.values`.
LETTERS = "NGXYZABCF"
COLUMN = {letter: i for i, letter in enumerate(LETTERS)}
#: Longest digit string read here: m < 10^15 < 2^53 keeps m / 10^k correctly rounded.
MAX_DIGITS = 15
#: Bytes of text per numpy pass: small enough for the per-character arrays to stay in cache.
CHUNK_BYTES = 1 << 18
#: Threads that read chunks at once: the cores there are, up to 4 (beyond that memory
#: bandwidth, not arithmetic, bounds the scan).
WORKERS = min(4, usable_cores())

_LF, _CR, _TAB, _SPACE = (np.uint8(ord(c)) for c in "\n\r\t ")
_ZERO, _DOT, _PLUS, _MINUS, _LOWER_A = (np.uint8(ord(c)) for c in "0.+-a")
#: Column in `LETTERS` of each byte (either case), -1 for every other byte.
_COLUMN_OF = np.full(256, -1, dtype=np.int64)
for _i, _ch in enumerate(LETTERS.encode()):
    _COLUMN_OF[_ch] = _COLUMN_OF[_ch + 32] = _i
_POW10 = 10.0 ** np.arange(MAX_DIGITS + 4)
_N, _G, _F = COLUMN["N"], COLUMN["G"], COLUMN["F"]
_NIBBLE = 16.0 ** np.arange(len(LETTERS))
_TWICE = int("E" * len(LETTERS), 16)


@dataclass(frozen=True)
class Scan:
    """What `scan` found, one row per line (lines split at ``\\n`` as `str.split`).

    Attributes
    ----------
    starts, ends : ndarray, shape (n_lines,), int64
        Byte offsets of each line in the scanned bytes (end excluding the ``\\n``).
    simple : ndarray, shape (n_lines,), bool
        The line is simple (module docstring); its words are in ``values``.
    empty : ndarray, shape (n_lines,), bool
        Simple and without words (blanks only).
    values : ndarray, shape (9, n_lines), float64
        The number of each word, rows `LETTERS` (one contiguous row a letter),
        ``float(text)`` exactly; NaN where the line has no such word (or is not simple).
    point : ndarray, shape (9, n_lines), bool
        The number was written with a decimal point (for integer input).
    decimals : ndarray, shape (n_lines,), int8
        The most digits written after the point in the line's X, Y and Z words (0 where it
        has none with digits there, or is not simple): the resolution the text wrote its
        positions to (`machinesim.nc.Program.length_digit`).
    """

    starts: np.ndarray
    ends: np.ndarray
    simple: np.ndarray
    empty: np.ndarray
    values: np.ndarray
    point: np.ndarray
    decimals: np.ndarray


def scan(data: bytes) -> Scan:
    """Classify the lines of ``data`` (UTF-8 NC text) and read the numbers of simple ones.

    Chunks of `CHUNK_BYTES` (whole lines) are read by up to `WORKERS` threads: numpy
    releases the GIL in its array loops, and each chunk writes its own rows.
    """
    size = len(data)
    everything = np.frombuffer(data, dtype=np.uint8)
    newlines = np.flatnonzero(everything == ord("\n"))
    n_lines = newlines.size + 1
    starts = np.empty(n_lines, dtype=np.int64)
    starts[0] = 0
    starts[1:] = newlines + 1
    ends = np.empty(n_lines, dtype=np.int64)
    ends[:-1] = newlines
    ends[-1] = size
    # filled by the chunks, each its own rows (first touch of the pages in the threads)
    simple = np.empty(n_lines, dtype=bool)
    words = np.empty(n_lines, dtype=np.int64)
    values = np.empty((len(LETTERS), n_lines))
    point = np.empty((len(LETTERS), n_lines), dtype=bool)
    decimals = np.empty(n_lines, dtype=np.int8)
    jobs = []
    line = 0
    position = 0
    while position < size:
        stop = min(size, position + CHUNK_BYTES)
        long_line = False
        if stop < size:
            cut = data.rfind(b"\n", position, stop)
            if cut < 0:  # one line longer than a chunk (no simple line is that long)
                cut = data.find(b"\n", stop)
                long_line = True
            stop = size if cut < 0 else cut + 1
        lines = int(np.searchsorted(newlines, stop)) - line + (stop == size)
        jobs.append((None if long_line else everything[position:stop], line, lines))
        line += lines
        position = stop

    def run(job: tuple[np.ndarray | None, int, int]) -> None:
        chunk, first, count = job
        if chunk is None:  # left to the word-by-word path, which reads any line alike
            rows = slice(first, first + count)
            simple[rows], words[rows], values[:, rows], point[:, rows] = False, 0, np.nan, False
            decimals[rows] = 0
        else:
            _scan_chunk(chunk, first, count, simple, words, values, point, decimals)

    if not jobs:  # empty text: one empty line
        jobs.append((everything, 0, 1))
    if len(jobs) > 1 and WORKERS > 1:
        with ThreadPoolExecutor(min(WORKERS, len(jobs))) as pool:
            list(pool.map(run, jobs))
    else:
        for job in jobs:
            run(job)
    empty = simple & (words == 0)
    return Scan(starts, ends, simple, empty, values, point, decimals)


def written_digit(found: Scan, i: int, j: int, unit: float, bare: float) -> float:
    """What the last digit of the finest X, Y or Z word of lines [i, j) stands for (m; inf
    where they have none): ``unit`` (m per unit of the lengths) over 10 to the most digits
    after a point, or ``bare`` (m per unit of a number without a point) where finer. A zero
    without a point counts for nothing (`machinesim.nc.blocks.Block.length_of`)."""
    digit = math.inf
    rows = [COLUMN[letter] for letter in "XYZ"]
    values = found.values[rows, i:j]
    given = ~np.isnan(values)
    pointed = found.point[rows, i:j]
    if (given & pointed).any():
        digit = unit / 10.0 ** int(found.decimals[i:j].max())
    if (given & ~pointed & (values != 0.0)).any():
        digit = min(digit, bare)
    return digit


def _scan_chunk(a: np.ndarray, line0: int, n_lines: int, simple: np.ndarray,
                words: np.ndarray, values: np.ndarray, point: np.ndarray,
                decimals: np.ndarray) -> None:
    """Read one chunk (whole lines, starting at line ``line0``) into the output arrays."""
    size = a.size
    rows = slice(line0, line0 + n_lines)
    values[:, rows] = np.nan
    point[:, rows] = False
    newline = a == _LF
    line_of = np.cumsum(newline, dtype=np.int32)  # line (in the chunk) of each character
    bad = np.zeros(n_lines + 1, dtype=bool)
    digit = (a - _ZERO) < 10  # uint8 arithmetic wraps below '0'
    dot = a == _DOT
    sign = (a == _MINUS) | (a == _PLUS)
    numeric = digit | dot | sign
    alpha = ((a | 32) - _LOWER_A) < 26
    cr = a == _CR
    blank = (a == _SPACE) | (a == _TAB) | cr
    bad[line_of[np.flatnonzero(~(numeric | alpha | blank | newline))]] = True
    # a lone CR: not followed by LF (a chunk ends after an LF or at the end of the text, so a
    # CR as its last byte is lone too)
    lone = cr  # in place: cr is not used after this
    lone[:-1] &= ~newline[1:]
    bad[line_of[np.flatnonzero(lone)]] = True
    # numeric runs [start, stop); padded[i + 1] is numeric[i]
    padded = np.zeros(size + 2, dtype=bool)
    padded[1:-1] = numeric
    edges = np.flatnonzero(padded[1:] != padded[:-1])
    starts, stops = edges[0::2], edges[1::2]
    bad[line_of[np.flatnonzero(alpha & ~padded[2:])]] = True  # a letter without its number
    column = np.take(_COLUMN_OF, a[starts - 1])  # the letter before each run (a[-1]: none)
    column[starts == 0] = -1
    bad[line_of[starts[column < 0]]] = True  # a number without (a known) letter
    signs = np.flatnonzero(sign)
    bad[line_of[signs[padded[signs]]]] = True  # a sign inside a number
    dots = np.flatnonzero(dot)
    run_of = np.cumsum(padded[1:-1] & ~padded[:-2], dtype=np.int32) - 1  # run of each char
    dot_run = run_of[dots]
    bad[line_of[dots[1:][dot_run[1:] == dot_run[:-1]]]] = True  # two points in a number
    sign_run = run_of[signs]
    dot_at = np.full(starts.size, -1, dtype=np.int64)
    dot_at[dot_run] = dots
    signed = sign[starts]
    dotted = dot_at >= 0
    others = np.bincount(dot_run, minlength=starts.size) + np.bincount(sign_run,
                                                                       minlength=starts.size)
    n_digits = stops - starts - others
    frac = np.where(dotted, stops - 1 - dot_at, 0)
    # mantissa: each digit times 10^(digits after it in its run), summed per run; exact, for
    # every partial sum of a run of <= 15 digits is an integer below 2^53
    last = np.cumsum(n_digits)
    exponent = np.repeat(last, n_digits) - np.arange(1, last[-1] + 1 if last.size else 1)
    np.minimum(exponent, _POW10.size - 1, out=exponent)
    weighted = (np.compress(digit, a) - _ZERO) * np.take(_POW10, exponent)
    # a trailing 0 so that a run without digits at the very end still has an index
    mantissa = np.add.reduceat(np.append(weighted, 0.0), last - n_digits)
    number = mantissa / np.take(_POW10, np.minimum(frac, _POW10.size - 1))
    number = np.where(a[starts] == _MINUS, -number, number)
    # the words: one per run that follows a letter read here
    word = column >= 0
    column, number, signed, dotted = column[word], number[word], signed[word], dotted[word]
    frac = frac[word]
    nd = n_digits[word]
    token_line = line_of[starts[word]]
    integer_word = (column == _N) | (column == _G)
    wrong = (nd < 1) | (nd > MAX_DIGITS)
    wrong |= integer_word & (signed | dotted | (nd > 9))
    wrong |= (column == _G) & (number > 1.0)
    wrong |= (column == _F) & ~(number > 0.0)
    bad[token_line[wrong]] = True
    # a letter twice in a line: count each letter in a hexadecimal digit of its own (exact
    # in float64: 16^9 < 2^53); a line of more than 9 words repeats a letter anyway
    count = np.bincount(token_line, minlength=n_lines + 1)
    nibbles = np.bincount(token_line, weights=np.take(_NIBBLE, column),
                          minlength=n_lines + 1).astype(np.int64)
    bad |= (count > len(LETTERS)) | ((nibbles & _TWICE) != 0)
    bad = bad[:n_lines]
    keep = ~bad[token_line]
    flat = column[keep] * values.shape[1] + (line0 + token_line[keep])
    values.reshape(-1)[flat] = number[keep]
    point.reshape(-1)[flat] = dotted[keep]
    # each letter at most once in a kept line: one assignment per letter, then the most
    found = np.zeros((3, n_lines), dtype=np.int8)
    for row, letter in enumerate("XYZ"):
        ours = keep & (column == COLUMN[letter])
        found[row, token_line[ours]] = frac[ours]
    decimals[line0:line0 + n_lines] = found.max(axis=0)
    words[line0:line0 + n_lines] = np.where(bad, 0, count[:n_lines])
    simple[line0:line0 + n_lines] = ~bad
