"""The FANUC dialect's canned cycles (issue 12) and Haas's: drilling cycles expanded to
FANUC's sequences, incremental with repeats, carried into G91, cancelled by a motion code;
high-speed and variable pecks, dwells with a decimal point, G73 with K; refused cycles and
a peck typed in the wrong unit. Expected values worked out by hand."""

from __future__ import annotations

import numpy as np
import pytest

from machinesim.exceptions import NCProgramError
from machinesim.nc import KIND_DWELL, KIND_LINEAR, KIND_RAPID, parse_program, read_program
from machinesim.nc.cycles import CHIP_BREAK_RETRACT_M, PECK_CLEARANCE_M

MM = 1e-3
#: Targets are a decimal in mm times 1e-3 (plus offsets): float64 round-off is far below this,
#: and it is 10^6 x below 1 nm, so any misreading fails.
EXACT_M = 1e-15


def test_drilling_cycles_expand_to_fanuc_sequences():
    text = ("G00 X0 Y0 Z10.\n"
            "G98 G81 X5. Y5. Z-2. R1. F100.\n"
            "G99 G82 X6. Z-1.5 R0.5 P250\n"
            "G98 G83 X7. Z-3. R1. Q1.2\n"
            "G80 X8.\n")
    program = parse_program(text)
    moves = [(MOVE := ("rapid", "linear", "dwell")[k], *(t[[0, 2]] / MM), d)
             for k, t, d in zip(program.kinds, program.targets, program.dwells, strict=True)]
    del MOVE
    c = PECK_CLEARANCE_M / MM
    expected = [
        ("rapid", 0, 10, 0),
        ("rapid", 5, 10, 0), ("rapid", 5, 1, 0), ("linear", 5, -2, 0), ("rapid", 5, 10, 0),
        ("rapid", 6, 10, 0), ("rapid", 6, 0.5, 0), ("linear", 6, -1.5, 0),
        ("dwell", 6, -1.5, 0.25), ("rapid", 6, 0.5, 0),  # G99: back to R
        ("rapid", 7, 0.5, 0), ("rapid", 7, 1, 0),
        ("linear", 7, -0.2, 0), ("rapid", 7, 1, 0), ("rapid", 7, -0.2 + c, 0),
        ("linear", 7, -1.4, 0), ("rapid", 7, 1, 0), ("rapid", 7, -1.4 + c, 0),
        ("linear", 7, -2.6, 0), ("rapid", 7, 1, 0), ("rapid", 7, -2.6 + c, 0),
        ("linear", 7, -3, 0), ("rapid", 7, 10, 0),  # G98: the initial level of G81
        ("rapid", 8, 10, 0),  # after G80 a plain move
    ]
    assert len(moves) == len(expected)
    for got, want in zip(moves, expected, strict=True):
        assert got[0] == want[0]
        assert got[1:] == pytest.approx(want[1:], abs=1e-12)


def test_incremental_cycle_with_repeats_drills_a_row():
    # G91: R from the initial level, Z from R; K4 drills four holes 3 mm apart in X
    program = parse_program("G00 X0 Y0 Z5.\nG91 G99 G81 X3. Z-2. R-4. K4 F50")
    bottoms = program.targets[program.kinds == KIND_LINEAR]
    assert bottoms[:, 0].tolist() == pytest.approx([3 * MM, 6 * MM, 9 * MM, 12 * MM])
    assert np.all(bottoms[:, 2] == pytest.approx(-1 * MM, abs=EXACT_M))
    assert program.targets[-1, 2] == pytest.approx(1 * MM, abs=EXACT_M)  # G99: at R


def test_a_cycle_carried_into_g91_drills_with_r_and_z_restated_there():
    """G81 begun in G90 (R1, Z-2 from Z5) and repeated in G91 with R and Z given again:
    R-4 from the initial level is the same R plane at 1 mm, Z-3 from it the same bottom at
    -2 mm, one hole 2 mm further along X. (Left unstated, they are refused: controls differ
    on what the kept numbers mean in G91.)"""
    program = parse_program("G00 X2. Y2. Z5.\nG98 G81 X2. Y2. Z-2. R1. F50.\n"
                            "G91 X2. Z-3. R-4.")
    bottoms = program.targets[program.kinds == KIND_LINEAR]
    assert bottoms[:, 0].tolist() == pytest.approx([2 * MM, 4 * MM])
    assert bottoms[:, 2].tolist() == pytest.approx([-2 * MM, -2 * MM], abs=EXACT_M)


def test_p_in_a_g81_block_is_kept_for_the_cycle_and_moves_as_without_it():
    # 'G81 ... P100' had been refused ("word P is only read with G04, G82 ..."): FANUC keeps
    # P, as Z R Q, as the cycle's data until G80, and G81 does not dwell. The holes are those
    # of the block without P; a G82 later in the cycle dwells the kept 100 ms
    head = "G21 G90 G17\nG00 X0 Y0 Z5.\n"
    with_p = parse_program(head + "G98 G81 X1. Y1. Z-1. R1. P100 F100.\nX2.\nG80\n")
    without = parse_program(head + "G98 G81 X1. Y1. Z-1. R1. F100.\nX2.\nG80\n")
    for name in ("kinds", "targets", "dwells", "lines"):
        np.testing.assert_array_equal(getattr(with_p, name), getattr(without, name))
    assert not np.any(with_p.dwells)
    kept = parse_program(head + "G98 G81 X1. Y1. Z-1. R1. P100 F100.\nG82 X2.\nG80\n")
    assert kept.dwells.tolist().count(0.1) == 1
    assert kept.kinds[kept.dwells == 0.1].tolist() == [KIND_DWELL]
    assert kept.targets[kept.dwells == 0.1, 2] == pytest.approx(-1 * MM, abs=EXACT_M)


def test_a_rotary_word_under_a_cycle_is_a_hole_there():
    """FANUC's lathe manual drills `G83 Z-40.0 R-5.0 ...` then `C90.0`, `C180.0`, `C270.0` as
    holes 2 to 4, and Haas positions "X and Y axes (and optional A)": a rotary word alone
    under a cycle positions the axis at rapid and drills (it had turned C and drilled
    nothing: one hole of four, exit 0), and beside X (it had been refused) both move. G91
    C90. K3 drills three more, 90 deg apart."""
    head = "G21 G90\nG00 X0 Y0 Z5. C0\nG98 G81 X3. Y0 Z-0.5 R0.5 F50.\n"
    program = parse_program(head + "C90.\nX4. C180.\nG91 C90. Z-1. R-4.5 K3\nG90 G80\n")
    bottoms = program.targets[program.kinds == KIND_LINEAR]
    assert np.degrees(bottoms[:, 5]).tolist() == pytest.approx([0, 90, 180, 270, 360, 450])
    assert bottoms[:, 0].tolist() == pytest.approx([3 * MM, 3 * MM] + [4 * MM] * 4)
    assert np.all(bottoms[:, 2] == pytest.approx(-0.5 * MM, abs=EXACT_M))
    rows = program.lines == 4  # C90.: to C90 at the initial level, R, the bottom, back up
    assert program.kinds[rows].tolist() == [KIND_RAPID, KIND_RAPID, KIND_LINEAR, KIND_RAPID]
    assert np.degrees(program.targets[rows, 5]).tolist() == pytest.approx([90] * 4)
    assert (program.targets[rows, 2] / MM).tolist() == pytest.approx([5, 0.5, -0.5, 5])


def test_a_motion_code_cancels_the_cycle():
    program = parse_program("G00 Z5.\nG81 X1. Z-1. R1. F10\nG00 X2.\nX3.")
    assert program.targets[-2:, 0].tolist() == [2 * MM, 3 * MM]
    assert program.targets[-1, 2] == pytest.approx(5 * MM, abs=EXACT_M)


def test_high_speed_peck_drilling_breaks_the_chip_within_the_hole():
    # G73 (FANUC's high-speed peck, as Fusion 360's and Haas posts write chip breaking):
    # feed Q, rapid back up by d (parameter 5114; CHIP_BREAK_RETRACT_M), feed Q further from
    # the last depth, to Z; then G99's R. It had been refused, and with it every program
    # that drills so. From R1 in pecks of 0.8 to -1: 0.2, -0.6, -1
    program = parse_program("G00 X0 Y0 Z5.\nG99 G73 X1. Y2. Z-1. R1. Q0.8 F100.\nG80\n")
    rows = program.lines == 2
    kinds = [("rapid", "linear")[k] for k in program.kinds[rows]]
    z = program.targets[rows][:, 2] / MM
    d = CHIP_BREAK_RETRACT_M / MM
    assert kinds == ["rapid", "rapid", "linear", "rapid", "linear", "rapid", "linear", "rapid"]
    assert z == pytest.approx([5, 1, 0.2, 0.2 + d, -0.6, -0.6 + d, -1, 1], abs=1e-12)
    assert np.max(np.abs(program.targets[rows][:, :2] / MM - [1, 2])) <= 1e-12
    assert d == 0.1  # within the hole: every retract stays below R and above the bottom
    with pytest.raises(NCProgramError, match="G73 needs a peck depth Q > 0"):
        parse_program("G00 X0 Y0 Z5.\nG73 X1. Y2. Z-1. R1. F100.\n")


@pytest.mark.parametrize("code", ["G83", "G73"])
def test_haas_variable_peck_i_j_k_and_its_dwell_p_are_read(code):
    # Haas's G73/G83 I (first peck) J (reduction per peck) K (smallest peck) and P (dwell
    # after the last peck) had been refused ("word I is only read with G02/G03 ..."). From
    # R1 to Z-1 with I0.5 J0.1 K0.2: pecks 0.5, 0.4, 0.3, then 0.2 on, ending at
    # 0.5, 0.1, -0.2, -0.4, -0.6, -0.8, -1 mm; then 500 ms at the bottom. The next hole
    # (X2., no P) pecks and dwells alike: Haas keeps P until the cycle is cancelled
    program = parse_program(f"G00 X0 Y0 Z5.\nG98 {code} X1. Y1. Z-1. R1. I0.5 J0.1 K0.2 "
                            "P500 F100.\nX2.\nG80\n")
    for line in (2, 3):
        rows = program.lines == line
        linear = program.targets[rows & (program.kinds == KIND_LINEAR)]
        assert linear[:, 2] / MM == pytest.approx([0.5, 0.1, -0.2, -0.4, -0.6, -0.8, -1],
                                                  abs=1e-12)
        # the dwell follows the last peck, at the bottom, and the hole ends at the
        # initial level (G98)
        kinds, z = program.kinds[rows], program.targets[rows][:, 2] / MM
        assert kinds[-2] == KIND_DWELL and program.dwells[rows][-2] == 0.5
        assert z[-2:] == pytest.approx([-1, 5], abs=1e-12)
        assert np.count_nonzero(program.dwells[rows]) == 1
    # K is the smallest peck here, not a repeat count: one hole per block
    assert np.count_nonzero(program.kinds[program.lines == 2] == KIND_LINEAR) == 7
    # a P carried from G82 does not make a peck cycle dwell (FANUC's G73/G83 take no P)
    carried = parse_program(f"G00 X0 Y0 Z5.\nG82 X1. Z-1. R1. P500 F100.\n{code} X2. "
                            "I0.5 J0.1 K0.2\nG80\n")
    assert np.count_nonzero(carried.dwells[carried.lines == 3]) == 0


@pytest.mark.parametrize("block, seconds", [
    ("G83 X1. Z-1. R1. Q0.5 P5. F100.", 5.0),  # Haas's own example's P5.: five seconds
    ("G73 X1. Z-1. R1. Q0.5 P.25 F100.", 0.25),
    ("G83 X1. Z-1. R1. I0.5 J0.1 K0.2 P2.5 F100.", 2.5),
    ("G82 X1. Z-1. R1. P1.5 F100.", 1.5),
    ("G83 X1. Z-1. R1. Q0.5 P500 F100.", 0.5),  # without a point: ms, as before
])
def test_a_cycle_dwell_with_a_decimal_point_is_seconds_as_haas_reads_it(block, seconds):
    # Haas's G83 'P5.' (96-8000: "dwell for five seconds at the end") had been refused
    # ("dwell time must be an unsigned integer ..."); a FANUC control takes no point in P
    program = parse_program(f"G00 X0 Y0 Z5.\nG98 {block}\nX2.\nG80\n")
    for line in (2, 3):  # kept for the cycle's next hole
        rows = program.lines == line
        assert program.dwells[rows].tolist().count(seconds) == 1
        assert np.count_nonzero(program.dwells[rows]) == 1
        # at the bottom, after the last peck
        dwell = np.flatnonzero(program.kinds[rows] == KIND_DWELL)[0]
        assert program.targets[rows][dwell - 1, 2] / MM == pytest.approx(-1, abs=1e-12)
    with pytest.raises(NCProgramError) as info:
        parse_program("G00 X0 Y0 Z5.\nG83 X1. Z-1. R1. Q0.5 P-5. F100.\n")
    assert (info.value.line, info.value.key) == (2, "P-5.")
    assert "G83's dwell P-5. must be >= 0 (with a decimal point P is seconds" in str(info.value)


@pytest.mark.parametrize("rule", ["calculator", "increment", "is-b", "is-c"])
@pytest.mark.parametrize("units", ["G21", "G20"])
def test_g04_p_with_a_decimal_point_is_seconds_without_milliseconds_as_haas_reads_it(
        rule, units):
    # Haas 96-8000, G04: 'G04 P10.' is a dwell of 10 seconds, 'G04 P10' one of 10
    # milliseconds. 'G04 P10.' had been refused ("G04 P takes integer milliseconds, got
    # P10.; use G04 X<seconds>") while a cycle's P10. was read as 10 s. Neither the unit
    # nor the integer-input rule (which scales a bare X) changes a P; under G91 it is a time
    text = (f"{units} G00 X1.\nG04 P10.\nG04 P10\nG91 G04 P.25\nG04 P1.5\nG04 X1.5\n"
            "G90 G04 P0.\nM30\n")
    program = parse_program(text, integer_input=rule)
    assert program.dwells.tolist() == [0.0, 10.0, 0.010, 0.25, 1.5, 1.5, 0.0]
    assert program.kinds.tolist() == [KIND_RAPID] + [KIND_DWELL] * 6
    assert len(set(program.targets[:, 0].tolist())) == 1  # no dwell moves X
    # the same reading as a cycle's P10.: ten seconds at the bottom of G82
    cycle = parse_program(f"{units} G00 X0 Y0 Z5.\nG82 X1. Z-1. R1. P10. F100.\nG80\n",
                          integer_input=rule)
    assert cycle.dwells[cycle.kinds == KIND_DWELL].tolist() == [10.0]


def test_haas_g73_with_q_and_a_decimal_k_returns_to_r_after_pecks_adding_up_to_k():
    # Haas 96-8000, G73: with both K and Q "the tool is returned to the R plane after a
    # number of passes totals up to the K amount". 'K1.' had been refused as a repeat count
    # ("repeat count must be an unsigned integer ..., got K1."). From R1 to Z-3 in pecks of
    # 0.5 with K1.: back to R after the pecks ending at 0, -1 and -2 (each 1 mm below the
    # last return), then down to PECK_CLEARANCE_M above that depth; a chip break elsewhere
    program = parse_program("G00 X0 Y0 Z5.\nG98 G73 X1. Z-3. R1. Q0.5 K1. F100.\nX2.\n"
                            "G80\n")
    d, c = CHIP_BREAK_RETRACT_M / MM, PECK_CLEARANCE_M / MM
    expected = [(0, 5), (0, 1), (1, 0.5), (0, 0.5 + d), (1, 0)]
    for depth in (0, -1, -2):
        expected += [(0, 1), (0, depth + c), (1, depth - 0.5), (0, depth - 0.5 + d),
                     (1, depth - 1)]
    expected.append((0, 5))  # then up to G98's initial level
    for line in (2, 3):  # modal: the next hole alike, one hole each (K is no repeat here)
        rows = program.lines == line
        kinds = [int(k) for k in program.kinds[rows]]
        z = program.targets[rows][:, 2] / MM
        assert kinds == [KIND_RAPID if k == 0 else KIND_LINEAR for k, _ in expected]
        assert z == pytest.approx([v for _, v in expected], abs=1e-12)
    # a Q without K drills as plain G73 again; K with a point elsewhere is refused by name
    plain = parse_program("G00 X0 Y0 Z5.\nG73 X1. Z-3. R1. Q0.5 K1. F100.\nX2. Q0.5\n")
    up = [np.count_nonzero(plain.targets[plain.lines == line][:, 2] / MM > 0.9)
          for line in (2, 3)]
    assert up == [6, 3]  # positioning, R, 3 returns to R and the initial level; then none
    for block, key, message in [
            ("G83 X1. Z-3. R1. Q0.5 K1.", "K1.", "not in G83"),
            ("G81 X1. Z-3. R1. K2.", "K2.", "so it is no repeat count"),
            ("G73 X1. Z-3. R1. Q0.5 K0.", "K0.", "must be > 0, got K0.")]:
        with pytest.raises(NCProgramError) as info:
            parse_program(f"G00 X0 Y0 Z5.\n{block} F100.\n")
        assert (info.value.line, info.value.key) == (2, key)
        assert message in str(info.value)


@pytest.mark.parametrize("block, code", [
    ("G99 G85 X1. Y1. Z-1. R0.25 F100.", "G85"),  # a public program's boring cycle
    ("G98 G84 X1. Y1. Z-1. R1. P200 F100.", "G84"),
    ("G98 G76 X1. Y1. Z-1. R1. Q0.1 P500 F100.", "G76"),
    ("G98 G87 X1. Y1. Z-1. R-3. I0.1 J0. Q0.1 F100.", "G87"),
])
def test_a_refused_cycle_is_one_problem_not_one_more_for_each_of_its_words(block, code):
    # the cycle's R, P, Q, I, J had each been a further problem ("word R is only read with
    # G02/G03 (radius), G81-G83 (R plane)"), as if the block held more than one mistake
    with pytest.raises(NCProgramError) as info:
        parse_program(f"G00 X0 Y0 Z5.\n{block}\n")
    problems = getattr(info.value, "problems", None) or [info.value]
    assert [(p.line, p.key) for p in problems] == [(2, code)]
    assert f"canned cycle {code}" in str(info.value)


def test_a_peck_typed_in_the_wrong_unit_is_refused_before_it_makes_thousands_of_moves():
    # 1.5 mm from R to Z in pecks of 0.1 um: 15000 pecks, each a sweep to cut
    with pytest.raises(NCProgramError, match="makes 15000 pecks in one hole"):
        parse_program("G00 X2. Y2. Z2.\nG83 X2. Y2. Z-1. R0.5 Q0.0001 F30.\n")
    # 1000 pecks of 1.5 um are a micro drill's and are read
    program = parse_program("G00 X2. Y2. Z2.\nG83 X2. Y2. Z-1. R0.5 Q0.0015 F30.\n")
    assert int(np.sum(np.asarray(program.kinds) == KIND_LINEAR)) == 1000


def test_pecks_too_many_for_float64_are_refused_not_a_crash():
    # 1e307 mm (written out) from R to Z in pecks of 1e-301 mm: the count overflows to inf,
    # and math.ceil(inf) had raised OverflowError out of the reader; 2 mm in such pecks,
    # 2e301 of them, had been named by a 302-digit integer
    tiny = "0." + "0" * 300 + "1"
    with pytest.raises(NCProgramError, match="makes inf pecks in one hole"):
        parse_program(f"G00 X2. Y2. Z2.\nG83 X2. Y2. Z-1{'0' * 307}. R1. Q{tiny} F30.\n")
    with pytest.raises(NCProgramError) as caught:
        parse_program(f"G00 X2. Y2. Z2.\nG83 X2. Y2. Z-1. R1. Q{tiny} F30.\n")
    assert "makes 2e+301 pecks in one hole" in str(caught.value)


@pytest.mark.parametrize("data, expected", [
    ("G00 X1. Y1. Z1.\n".encode("utf-16"), "UTF-16 text"),
    ("G00 X1. Y1. Z1.\n".encode("utf-16-le"), "UTF-16 text"),
    (bytes(range(256)) * 8, "not a text file"),
    # without a byte-order mark, big-endian: the zero before each character
    ("G00 X1. Y1. Z1.\n".encode("utf-16-be"), "UTF-16 text"),
    # a binary full of zeros on both sides of each byte pair (little-endian integers, as an
    # executable or a binary PLY holds) is no UTF-16, and was called so
    (np.arange(1024, dtype="<i4").tobytes(), "not a text file"),
])
def test_a_file_that_is_not_utf8_text_is_refused_in_one_line(tmp_path, data, expected):
    path = tmp_path / "prog.nc"
    path.write_bytes(data)
    with pytest.raises(NCProgramError, match=expected) as info:
        read_program(path)
    assert "\n" not in str(info.value)
