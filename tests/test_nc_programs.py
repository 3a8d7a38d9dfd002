"""NC programs built and written: the builder against the equivalent NC text and what it
refuses (a bad feed, numbers given as text or flags), immutable and hashable moves and
programs, what from_moves and Move refuse, write/read round trips at the resolution, the
written text, and whole-or-nothing writes."""

from __future__ import annotations

import dataclasses
import math
import os
from decimal import ROUND_HALF_EVEN, Decimal

import numpy as np
import pytest

from machinesim.exceptions import NCProgramError
from machinesim.nc import (
    AXES,
    Move,
    Program,
    ProgramBuilder,
    format_program,
    parse_program,
    read_program,
    write_program,
)

DEG = math.pi / 180.0
#: Targets are a decimal in mm times 1e-3 plus an offset: float64 round-off at <= 0.1 m is
#: below 1e-17 m per operation; 1e-15 m leaves room for a few operations and is 1e6 x below
#: 1 nm, so any real misreading (a unit, an offset, a sign) fails.
EXACT_M = 1e-15
#: The same for angles in rad (values <= 2 pi).
EXACT_RAD = 1e-15


MM_PER_MIN = 1e-3 / 60.0


def test_builder_matches_the_equivalent_nc_text():
    built = (
        ProgramBuilder(number=1)
        .spindle(8000)
        .rapid(X=0.0, Z=1e-3, m_codes=(3,))
        .linear(X=0.01, feed_mm_per_min=100.0)
        .linear(Z=0.0)
        .dwell(0.5)
        .dwell(0.0, m_codes=(8,))
        .build()
    )
    text = "O1\nG00 X0 Z1. S8000 M03\nG01 X10. F100.\nZ0\nG04 P500\nM08\n"
    parsed = parse_program(text)
    assert len(built) == len(parsed) == 5
    for b, p in zip(built, parsed, strict=True):
        assert dataclasses.replace(b, line=p.line) == p
    assert built.moves[2].target == {"X": 0.01, "Z": 0.0}
    assert built.moves[2].feed_m_per_s == pytest.approx(100 * MM_PER_MIN, rel=1e-15)


def test_moves_and_programs_are_immutable_and_hashable():
    program = ProgramBuilder().rapid(X=0.0).linear(Y=1e-3, feed_m_per_s=1e-3).build()
    move = program.moves[1]
    with pytest.raises(TypeError):
        move.target["X"] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        move.kind = "rapid"
    with pytest.raises(TypeError):
        program.work_offsets["G54"] = {"X": 1.0}
    assert hash(move) == hash(Move("linear", {"Y": 1e-3, "X": 0.0}, 1e-3, line=2))
    assert list(move.target) == ["X", "Y"]


@pytest.mark.parametrize(
    ("moves", "message"),
    [
        ([Move("rapid", {"X": 0.0, "Y": 0.0}), Move("rapid", {"X": 1.0})], "drops axis Y"),
        ([Move("rapid", {"X": 0.0}), Move("dwell", {"X": 1.0}, dwell_s=1.0)], "is a dwell but"),
        ([Move("linear", {"X": 0.0}, 1e-3), Move("linear", {"X": 1.0})], "without feed after"),
        ([Move("rapid", {"X": 0.0}, m_codes=(30,)), Move("rapid", {"X": 1.0})], "ends the prog"),
        ([Move("rapid", {"X": 0.0}, spindle_rpm=1.0), Move("rapid", {"X": 1.0})], "S is modal"),
    ],
)
def test_from_moves_refuses_what_nc_cannot_say(moves, message):
    with pytest.raises(NCProgramError, match=message):
        Program.from_moves(moves)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "arc", "target": {"X": 0.0}}, "kind must be one of"),
        ({"kind": "rapid", "target": {}}, "needs at least one axis"),
        ({"kind": "rapid", "target": {"X": 0.0}, "feed_m_per_s": 1.0}, "feed must be None"),
        ({"kind": "linear", "target": {"X": math.nan}}, "must be finite"),
        ({"kind": "linear", "target": {"X": 0.0}, "dwell_s": 1.0}, "dwell_s must be"),
        ({"kind": "dwell", "target": {}, "m_codes": (-1,)}, "m_codes must be"),
    ],
)
def test_move_refuses_bad_fields(kwargs, message):
    with pytest.raises(NCProgramError, match=message):
        Move(**kwargs)


@pytest.mark.parametrize(("kind", "feed", "message"), [
    ("linear", -1e-3, "feed must be > 0 for a linear move, got -0.001 m/s"),
    ("linear", 0.0, "feed must be > 0 for a linear move, got 0.0 m/s"),
    ("rapid", 1e-3, "feed must be None for a rapid move (only a linear move has one), got "
                    "0.001"),
])
def test_a_bad_feed_is_named_for_what_is_wrong_with_it(kind, feed, message):
    # the message had read "feed must be None for a linear move and > 0 for a linear move"
    # for a linear move's negative feed; the same from a Move and from Program.from_arrays
    with pytest.raises(NCProgramError) as error:
        Move(kind, {"X": 0.0}, feed)
    assert message in str(error.value)
    code = {"rapid": 0, "linear": 1}[kind]
    with pytest.raises(NCProgramError) as error:
        Program.from_arrays(np.array([[0.0] + [np.nan] * 5]), np.array([code], np.uint8),
                            np.array([feed]), np.zeros(1), np.ones(1, np.int64))
    assert message in str(error.value)


@pytest.mark.parametrize(("feed", "message"), [
    ({"feed_mm_per_min": -100.0}, "feed_mm_per_min must be > 0, got -100.0"),
    ({"feed_mm_per_min": 0.0}, "feed_mm_per_min must be > 0, got 0.0"),
    ({"feed_m_per_s": -1e-3}, "feed_m_per_s must be > 0, got -0.001"),
    ({"feed_m_per_s": "fast"}, "feed must be a real number, got 'fast'"),
])
def test_the_builder_names_a_bad_feed_as_it_was_given(feed, message):
    # a builder's feed_mm_per_min=-100 was refused by the move, as key 'feed_m_per_s' of
    # '<move>' in m/s: neither the argument the caller wrote nor its unit
    builder = ProgramBuilder().rapid(X=0.0)
    with pytest.raises(NCProgramError) as error:
        builder.linear(X=1e-3, **feed)
    assert message in str(error.value)
    assert error.value.source == "<builder>"
    assert error.value.key == next(iter(feed))
    assert error.value.line == 2


def test_the_builder_refuses_a_linear_move_before_any_feed_naming_the_argument():
    # it built, and the planner refused it later as 'a feed move (G01) with no feed rate F
    # given so far', at the move's line: an F the builder's caller never writes
    builder = ProgramBuilder().rapid(X=0.0).rapid(Z=1e-3)
    with pytest.raises(NCProgramError) as error:
        builder.linear(X=1e-3)
    assert str(error.value).startswith(
        "<builder>, line 3, key 'feed_mm_per_min': a linear move needs a feed and none was "
        "given before it: give feed_mm_per_min (or feed_m_per_s) on the first linear move")
    assert len(builder.build().moves) == 2  # nothing appended
    # the feed is modal: given once, the next linear moves keep it (100 mm/min in m/s)
    program = builder.linear(X=1e-3, feed_mm_per_min=100.0).linear(Y=1e-3).build()
    assert [m.feed_m_per_s for m in program.moves[2:]] == [100.0 * 1e-3 / 60.0] * 2


def _rounded(value: float, decimals: int) -> float:
    """Round-half-even of the exact binary value with Decimal: a second method to f-strings."""
    quantum = Decimal(1).scaleb(-decimals)
    return float(Decimal(value).quantize(quantum, rounding=ROUND_HALF_EVEN))


def _random_program(rng: np.random.Generator) -> Program:
    offsets = {"G54": {"X": rng.uniform(-0.05, 0.05), "Z": rng.uniform(-0.05, 0.05),
                       "C": rng.uniform(-1.0, 1.0)}}
    builder = ProgramBuilder(number=int(rng.integers(0, 10000)), work_offsets=offsets)
    axes = list(rng.choice(AXES, size=int(rng.integers(1, 7)), replace=False))
    last: dict[str, float] = {}
    fed = False
    n_moves = 40
    for index in range(n_moves):
        if rng.random() < 0.1:
            builder.spindle(float(rng.choice([0.0, 12000.0, rng.uniform(0.0, 20000.0)])))
        number = int(rng.integers(0, 100000)) if rng.random() < 0.3 else None
        m_codes = tuple(int(c) for c in rng.choice([0, 1, 3, 5, 8, 9, 97],
                                                   size=int(rng.integers(0, 3))))
        if index == n_moves - 1 and rng.random() < 0.5:
            m_codes += (30,)
        kind = rng.choice(["rapid", "linear", "linear", "dwell", "m"])
        if kind in ("rapid", "linear"):
            chosen = rng.choice(axes, size=int(rng.integers(1, len(axes) + 1)), replace=False)
            values = {
                str(a): (last[a] if a in last and rng.random() < 0.2  # zero-length moves too
                         else rng.uniform(-2 * math.pi, 2 * math.pi) if a in "ABC"
                         else rng.uniform(-0.5, 0.5))
                for a in chosen
            }
            last.update(values)
            if kind == "rapid":
                builder.rapid(block_number=number, m_codes=m_codes, **values)
            else:
                feed = rng.uniform(0.1, 2000.0) if rng.random() < 0.3 else None
                if feed is None and not fed:  # the first linear move has one
                    feed = rng.uniform(0.1, 2000.0)
                fed = True
                builder.linear(feed_mm_per_min=feed, block_number=number, m_codes=m_codes,
                               **values)
        elif kind == "dwell":
            seconds = float(rng.choice([0.0, int(rng.integers(0, 100000)) / 1000.0,
                                        rng.uniform(0.0, 10.0)]))
            builder.dwell(seconds, block_number=number, m_codes=m_codes)
        else:
            builder.dwell(0.0, block_number=number, m_codes=m_codes or (8,))
    return builder.build()


@pytest.mark.parametrize("seed", range(20))
def test_write_read_round_trip_at_the_resolution(seed, tmp_path):
    program = _random_program(np.random.default_rng(seed))
    path = tmp_path / "out.nc"
    write_program(program, path)
    text = path.read_text()
    assert text == format_program(program)
    back = read_program(path, work_offsets=program.work_offsets)
    assert format_program(back) == text  # the format is stable
    offset = program.work_offsets["G54"]
    assert len(back) == len(program)
    assert back.number == program.number
    for before, after in zip(program, back, strict=True):
        assert (after.kind, after.block_number, after.m_codes, after.spindle_rpm) == (
            before.kind, before.block_number, before.m_codes, before.spindle_rpm)
        assert after.dwell_s == before.dwell_s  # dwell is written exactly
        assert list(after.target) == list(before.target)
        for axis, value in before.target.items():
            off = offset.get(axis, 0.0)
            if axis in "ABC":
                # Within half the 0.00001 deg resolution (+ round-off), and exactly the
                # Decimal-rounded value read back.
                assert abs(after.target[axis] - value) <= 0.5e-5 * DEG + EXACT_RAD
                expected = _rounded((value - off) / DEG, 5) * DEG + off
            else:
                # Within half the 1 nm resolution (+ round-off), and exactly the rounded value.
                assert abs(after.target[axis] - value) <= 0.5e-9 + EXACT_M
                expected = _rounded((value - off) / 1e-3, 6) * 1e-3 + off
            assert after.target[axis] == expected
        if before.feed_m_per_s is None:
            assert after.feed_m_per_s is None
        else:
            expected = _rounded(before.feed_m_per_s * 60.0 / 1e-3, 6) * 1e-3 / 60.0
            assert after.feed_m_per_s == expected


def test_written_text_looks_as_documented():
    offsets = {"G54": {"Z": 0.001}}
    program = (ProgramBuilder(number=12, work_offsets=offsets)
               .rapid(X=1e-3, Z=1.0000004e-3, A=math.pi)
               .linear(X=2e-3, feed_mm_per_min=50.0, block_number=7)
               .linear(X=2e-3)
               .dwell(0.1234)
               .dwell(0.123456789)
               .dwell(0.0)
               .dwell(0.0, m_codes=(9,))
               .dwell(0.0, m_codes=(30,))
               .build())
    text = format_program(program)
    assert text == (
        "%\nO0012\nG90 G21 G94 G54\n"
        "G00 X1. Z0. A180.\n"   # Z: 1.0000004 mm - 1 mm offset rounds to 0 at 1 nm
        "N7 G01 X2. F50.\n"
        "X2.\n"                 # a move that changes nothing still gets a block
        "G04 X0.1234\n"         # 0.1234 s is not whole milliseconds
        "G04 X0.123456789\n"
        "G04 P0\n"
        "M09\n"                 # M codes without motion: a 0 s dwell
        "G04 P0 M30\n"          # a lone M30 would make no move; no second M30
        "%\n"
    )
    back = parse_program(text, work_offsets=offsets)
    assert [(m.kind, m.dwell_s, m.m_codes) for m in back.moves[-3:]] == [
        ("dwell", 0.0, ()), ("dwell", 0.0, (9,)), ("dwell", 0.0, (30,))]
    assert len(back) == len(program)


def test_writing_what_is_not_a_program_says_what_came(tmp_path):
    # write_program(model_based(...), path), the result for its .program, ended in
    # "AttributeError: 'Compensated' object has no attribute 'work_offsets'"; a path that
    # is not one in "TypeError: expected str, bytes or os.PathLike object, not int"
    from machinesim.compensation import model_based

    program = ProgramBuilder(1).rapid(X=1e-3, Y=2e-3, Z=1e-3).build()
    result = model_based(program, "grooving_4axis", {"tool": {"offset_um": [4.0, -2.0, 0.0]}})
    path = tmp_path / "c.nc"
    for wrong, message in [
        (result, "expected a machinesim.nc.Program, got Compensated; write its .program, the "
                 "rewritten Program (Compensated.program)"),
        ("part.nc", "expected a machinesim.nc.Program, got str; read an NC file with "
                    "machinesim.nc.read_program(path)"),
        (None, "expected a machinesim.nc.Program, got NoneType")]:
        with pytest.raises(NCProgramError) as info:
            write_program(wrong, path)
        assert (info.value.key, str(info.value)) == ("program", f"key 'program': {message}")
        with pytest.raises(NCProgramError) as info:
            format_program(wrong)
        assert info.value.key == "program"
    with pytest.raises(NCProgramError, match="key 'path': expected the path to write the "
                                             "program to as a str or Path, got int"):
        write_program(program, 3)
    assert not path.exists()
    write_program(result.program, path)
    assert read_program(path).targets[0, :2].tolist() == pytest.approx([0.996e-3, 2.002e-3],
                                                                        abs=1e-15)


def test_write_is_whole_or_nothing(tmp_path, monkeypatch):
    path = tmp_path / "p.nc"
    good = ProgramBuilder().rapid(X=0.0).build()
    write_program(good, path)
    before = path.read_text()
    too_slow = ProgramBuilder().linear(X=0.0, feed_m_per_s=1e-15).build()
    with pytest.raises(NCProgramError, match=r"line 1, key .F.: feed 1e-15 m/s rounds to F0"):
        write_program(too_slow, path)

    def failing_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError, match="disk full"):
        write_program(ProgramBuilder().rapid(X=1.0).build(), path)
    assert path.read_text() == before
    assert os.listdir(tmp_path) == ["p.nc"]


@pytest.mark.parametrize(("build", "message"), [
    (lambda b: b.rapid(X="0.001"), r"axis X must be a real number, got '0.001'"),
    (lambda b: b.rapid(X=True), r"axis X must be a real number, got True"),
    (lambda b: b.rapid(Z=np.bool_(True)), r"axis Z must be a real number, got "),
    (lambda b: b.linear(X=1e-3, feed_m_per_s="0.1"), r"feed must be a real number, got '0.1'"),
    (lambda b: b.linear(X=1e-3, feed_mm_per_min="100"),
     r"feed must be a real number, got '100'"),
    (lambda b: b.dwell("2"), r"dwell time must be a real number, got '2'"),
    (lambda b: b.spindle("1000").rapid(X=0.0), r"spindle speed must be a real number, got "
                                               r"'1000'"),
])
def test_the_builder_takes_numbers_not_text_or_flags(build, message):
    # ProgramBuilder().rapid(X="0.001") built X = 1 mm from the text and X=True X = 1 m;
    # a dwell("2"), spindle("1000") and feed_m_per_s="0.1" were converted alike, where
    # every instrument refuses a number spelt as text (docs/metrology.md)
    with pytest.raises(NCProgramError, match=message):
        build(ProgramBuilder(1)).build()
    exact = ProgramBuilder(1).rapid(X=np.float64(1e-3), Y=2).dwell(np.int64(2)).build()
    assert exact.targets[0, :2].tolist() == [1e-3, 2.0] and exact.dwells[1] == 2.0
