"""The vectorised reading path against the word-by-word one: identical programs (or identical
errors) on the corpus and on generated point lists, and the scanner against the tokenizer."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from machinesim.exceptions import NCProgramError
from machinesim.nc import fastscan, parse_program, read_program
from machinesim.nc import parser as nc_parser
from machinesim.nc.lexer import tokenize

CORPUS = Path(__file__).parent / "nc_corpus"

_digits = st.text("0123456789", min_size=1, max_size=8)
_number = st.one_of(
    st.tuples(st.sampled_from(["", "-", "+"]), _digits, st.sampled_from(["", "."]),
              st.text("0123456789", max_size=7)).map(
        lambda t: t[0] + t[1] + (t[2] + t[3] if t[2] else "")),
    st.tuples(st.sampled_from(["", "-"]), st.text("0123456789", min_size=1, max_size=6)).map(
        lambda t: f"{t[0]}.{t[1]}"),
    st.floats(-1e3, 1e3, allow_nan=False).map(lambda v: f"{v:.6f}"),
    st.sampled_from(["0", "-0.", "12345678901234567", "1.2.3", "--1", ".", "9" * 320,
                     "1e5"]),
)
_axis_word = st.tuples(st.sampled_from("XYZABCxyzc"), _number).map("".join)
_motion_line = st.tuples(
    st.one_of(st.none(), st.integers(0, 10**10).map(lambda n: f"N{n}")),
    st.one_of(st.none(), st.sampled_from(["G0", "G1", "G00", "G01", "g1", "G2", "G001"])),
    st.lists(_axis_word, max_size=4),
    st.one_of(st.none(), st.sampled_from(["F100", "F.5", "f20.", "F0", "F-1"])),
    st.sampled_from([" ", "", "  ", "\t"]),
    st.sampled_from(["", "\r", " "]),
).map(lambda t: t[4].join(w for w in (t[0], t[1], *t[2], t[3]) if w) + t[5])
_other_line = st.sampled_from([
    "(comment)", "G91", "G90", "G20", "G21", "M08", "S1000", "G04 P10", "; note", "",
    "G55", "X 1.", "Z - .5", "X+ 1", "Y -\t2.", "G00 X0 Y0 Z0 A0 B0 C0", "G43 H1", "G49",
    "%", "M30", "O12",
])
_program = st.tuples(
    st.sampled_from(["", "G00 X0 Y0 Z0 A0 B0 C0\n", "G01 X0 Z0 C0 F100\n"]),
    st.lists(st.one_of(_motion_line, _motion_line, _motion_line, _motion_line, _other_line),
             min_size=0, max_size=60),
).map(lambda t: t[0] + "\n".join(t[1]))


def _outcome(text: str, **kwargs):
    try:
        program = parse_program(text, "gen.nc", **kwargs)
        return program, program.length_digit  # (not part of ==: read from the text)
    except NCProgramError as error:
        return ("error", str(error), [str(p) for p in getattr(error, "problems", ())])


@pytest.mark.parametrize("path", sorted(CORPUS.glob("*.nc")), ids=lambda p: p.name)
def test_corpus_is_identical_on_both_paths(path):
    for integer_input in ("calculator", "increment"):
        fast = read_program(path, tools=CORPUS / "tools.toml", integer_input=integer_input)
        slow = read_program(path, tools=CORPUS / "tools.toml", integer_input=integer_input,
                            fast=False)
        assert fast == slow
        assert fast.length_digit == slow.length_digit


@settings(max_examples=300, deadline=None)
@given(_program, st.sampled_from(["calculator", "increment"]),
       st.sampled_from([None, {"G54": {"X": 0.01, "Z": -0.002, "C": 0.5}}]))
def test_generated_programs_are_identical_on_both_paths(text, integer_input, offsets):
    kwargs = {"integer_input": integer_input, "work_offsets": offsets,
              "tools": {"tool": {"1": {"length_mm": 3.0}}}}
    assert _outcome(text, fast=True, **kwargs) == _outcome(text, fast=False, **kwargs)


def test_a_point_list_takes_the_fast_path(monkeypatch):
    runs = []
    original = nc_parser.Reader.fast_run

    def counting(self, i, j):
        runs.append((i, j))
        return original(self, i, j)

    monkeypatch.setattr(nc_parser.Reader, "fast_run", counting)
    body = "\n".join(f"X{k * 0.001:.6f} Z{-k * 1e-6:.6f} C{k * 0.01:.5f}" for k in range(100))
    program = parse_program(f"G90\nG01 X0 Z0 C0 F10\n{body}\nM30")
    assert runs == [(1, 102)]  # lines 2..102 (0-based 1..101): one run
    assert len(program) == 101


@settings(max_examples=300, deadline=None)
@given(st.lists(st.one_of(_motion_line, _other_line), min_size=1, max_size=8))
def test_scanner_agrees_with_the_tokenizer(lines):
    text = "\n".join(lines)
    scan = fastscan.scan(text.encode())
    assert scan.simple.size == len(lines)
    for i, line in enumerate(lines):
        words, problems = tokenize(line, "s", i + 1)
        if not scan.simple[i]:
            continue
        assert not problems
        assert scan.empty[i] == (not words)
        letters = [w.letter for w in words]
        assert len(set(letters)) == len(letters) and set(letters) <= set(fastscan.LETTERS)
        for w in words:
            column = fastscan.COLUMN[w.letter]
            assert scan.values[column, i] == float(w.text)  # exactly float(text)
            assert str(scan.values[column, i]) == str(float(w.text))  # -0.0 too
            assert scan.point[column, i] == ("." in w.text)
        decimals = [len(w.text) - 1 - w.text.index(".") for w in words
                    if w.letter in "XYZ" and "." in w.text]
        assert scan.decimals[i] == max(decimals, default=0)


@settings(max_examples=500, deadline=None)
@given(st.integers(-(10**17), 10**17), st.integers(0, 17))
def test_scanned_numbers_round_like_float(mantissa, places):
    digits = str(abs(mantissa)).rjust(places + 1, "0")
    text = ("-" if mantissa < 0 else "") + digits[:len(digits) - places] + "." + \
        digits[len(digits) - places:]
    scan = fastscan.scan(f"X{text}".encode())
    if len(digits) <= fastscan.MAX_DIGITS:
        assert scan.simple[0]
        assert scan.values[fastscan.COLUMN["X"], 0] == float(text)  # correctly rounded
    else:
        assert not scan.simple[0]  # left to the word-by-word path


def test_big_files_use_threads_with_the_same_result(monkeypatch):
    body = "\n".join(f"X{k * 0.001:.6f} Z{np.sin(k) * 0.01:.6f}" for k in range(20000))
    data = f"G01 F10\n{body}\n".encode()
    monkeypatch.setattr(fastscan, "CHUNK_BYTES", 4096)
    threaded = fastscan.scan(data)
    monkeypatch.setattr(fastscan, "WORKERS", 1)
    single = fastscan.scan(data)
    assert np.array_equal(threaded.values, single.values, equal_nan=True)
    assert np.array_equal(threaded.simple, single.simple)
    assert threaded.simple[1:-1].all()


def test_a_line_longer_than_a_chunk_is_left_to_the_word_by_word_path(monkeypatch):
    # one 48 MB line was scanned as one chunk, its per-character arrays 50 bytes a character
    # (2.6 GB and 16 s before the reader refused it); a line longer than a chunk is not
    # simple now, and the word-by-word path reads it as the scan would have
    monkeypatch.setattr(fastscan, "CHUNK_BYTES", 4096)
    text = ("G00 X0. Y0. Z1.\nG01 F100.\nG01 X1." + " " * 5000 + "Y2.\n"
            + "X3. Y4.\n" * 2000 + "M30\n")
    scan = fastscan.scan(text.encode())
    assert not scan.simple[2] and scan.simple[3:2003].all()
    fast = parse_program(text, "long.nc")
    assert fast == parse_program(text, "long.nc", fast=False)
    assert fast.targets[1, :2].tolist() == [0.001, 0.002]  # the long line's X1. Y2. (m)
    assert fast.targets[2, :2].tolist() == [0.003, 0.004]
