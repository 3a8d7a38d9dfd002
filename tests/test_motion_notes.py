"""Motion: the planner's notes on a move longer than a day and a dwell longer than an hour."""

from __future__ import annotations

import pytest

from machinesim import load_machine
from machinesim.motion import plan
from machinesim.nc import ProgramBuilder, parse_program


def test_a_move_of_more_than_a_day_is_noted_with_its_line_and_feed():
    # 10 mm at F0.0001 mm/min: 1e5 min = 6e6 s, by hand; it had been planned without a word
    machine = load_machine("grooving_4axis")
    slow = plan(parse_program("G90 G21\nG01 X1. F100.\nG01 X11. F0.0001\nM30\n"), machine)
    assert slow.duration == pytest.approx(0.6 + 6e6, rel=1e-12)
    (note,) = slow.notes
    assert "line 3" in note and "6e+06 s" in note and "F0.0001" in note
    # an hour-long finishing pass is a plan, not a slip: 100 mm at F1 mm/min
    assert plan(parse_program("G90 G21\nG01 X100. F1.\nM30\n"), machine).notes == ()


@pytest.mark.parametrize("text, duration, feed", [
    # 0.4 inch at F0.0001 inch/min: 4000 min; it was noted as 'F0.00254 (mm/min or deg/min)'
    ("G90 G20\nG01 X0.1 F10.\nG01 X0.5 F0.0001\nM30\n", 0.1 / 10 * 60 + 4000 * 60,
     "F0.0001 (inch/min under G20; 0.00254 mm/min or deg/min)"),
    # C alone: F in deg/min under G20 too (FANUC), 90 deg at F0.001: 90,000 min
    ("G90 G20\nG00 X0. C0.\nG01 C90. F0.001\nM30\n", 90000 * 60,
     "F0.001 (deg/min under G20; 0.001 mm/min or deg/min)"),
    # X and C: a degree counts as an inch, sqrt(1 + 10**2) / 0.001 min; the planner's
    # equivalent counts it as a mm: 0.001 * sqrt(25.4**2 + 10**2) / sqrt(1 + 10**2)
    ("G90 G20\nG00 X0. C0.\nG01 X1. C10. F0.001\nM30\n", 101 ** 0.5 / 0.001 * 60,
     f"F0.001 (inch/min under G20; {0.001 * 745.16 ** 0.5 / 101 ** 0.5:.6g} mm/min or "
     "deg/min)"),
    # G21 and G20 both before the move: the last before the first motion is in force (a
    # switch after it is refused), 1.5 inch = 38.1 mm at F0.0001 inch/min = 0.00254 mm/min;
    # each had been noted with both readings, 'F0.00254 (mm/min or deg/min), or F0.0001
    # (inch/min) if written under G20', Program.unit_words keeping first lines only
    ("G90 G21\nG20\nG01 X1.5 F0.0001\nM30\n", 38.1 / 0.00254 * 60,
     "F0.0001 (inch/min under G20; 0.00254 mm/min or deg/min)"),
    ("G20\nG21\nG20\nG01 X1.5 F0.0001\nM30\n", 38.1 / 0.00254 * 60,
     "F0.0001 (inch/min under G20; 0.00254 mm/min or deg/min)"),
    ("G90 G20\nG21\nG01 X38.1 F0.00254\nM30\n", 38.1 / 0.00254 * 60,
     "F0.00254 (mm/min or deg/min)"),
    ("G21\nG20\nG21\nG01 X38.1 F0.00254\nM30\n", 38.1 / 0.00254 * 60,
     "F0.00254 (mm/min or deg/min)"),
])
def test_a_slow_move_under_g20_is_noted_with_its_f_as_the_program_wrote_it(text, duration,
                                                                           feed):
    import pickle

    program = parse_program(text)
    slow = plan(program, load_machine("grooving_4axis"))
    assert slow.duration == pytest.approx(duration, rel=1e-12)
    (note,) = slow.notes
    in_force = "G20" if "under G20" in feed else "G21"
    assert program.unit_in_force == pickle.loads(pickle.dumps(program)).unit_in_force == in_force
    line = text.count("\n") - 1
    assert note == (f"the feed move of line {line} takes {duration:.3g} s "
                    f"({duration / 3600:.3g} h) at {feed}, more than the 24 h one move of a "
                    "program takes: is F in the program's unit (G94: per minute)?")


@pytest.mark.parametrize("dwell, word, seconds", [
    # a billion seconds (31 years) with no word: P with a decimal point counts seconds
    ("G04 P1000000000.", " (P1000000000.)", 1e9),
    ("G04 X5000", " (X5000)", 5000.0),  # X counts seconds: 5000 ms meant?
    ("G82 X2. Z-0.1 R1. P4000000. F10.", " (P4000000.)", 4e6),  # a cycle's dwell
])
def test_a_dwell_longer_than_an_hour_is_noted_with_its_word_and_seconds(dwell, word,
                                                                        seconds):
    import pickle

    text = f"G90 G21\nG00 X1. Z1.\n{dwell}\nG80\nM30\n"
    program = parse_program(text)
    trajectory = plan(program, load_machine("grooving_4axis"))
    (note,) = trajectory.notes
    assert note == (f"the dwell of line 3{word} waits {seconds:.6g} s ({seconds / 3600:.3g} "
                    "h), more than the 1 h a dwell of a program waits: is its time in the unit "
                    "meant (P counts milliseconds without a decimal point, seconds with one; X "
                    "seconds)?")
    assert pickle.loads(pickle.dumps(program)).dwell_words == {3: word[2:-1]}


#: A note on the dwell of line {line}, {word} as the note names it, of {seconds} s.
DWELL_NOTE = ("the dwell of line {line} ({word}) waits {seconds:.6g} s ({hours:.3g} h), more "
              "than the 1 h a dwell of a program waits: is its time in the unit meant (P "
              "counts milliseconds without a decimal point, seconds with one; X seconds)?")


@pytest.mark.parametrize("holes, line, word, seconds", [
    # G81 keeps its P for a G82: line 4 writes no P, and the note had named no word at all
    ("G81 X1. Z-0.1 R1. P5000000 F10.\nG82 X2.\n", 4, "P5000000 of line 3", 5000.0),
    # a G83's P kept by the G82 after it (Haas's peck dwell of line 3 waits it too: 5000 s)
    ("G83 X1. Z-0.1 R1. Q0.05 P7000000 F10.\nG82 X2.\n", 3, "P7000000", 7000.0),
    # a G82 repeated with the P written: its first hole, the P's own line, as before
    ("G82 X1. Z-0.1 R1. P100 F10.\nX2. P7000000\nX3.\n", 4, "P7000000", 7000.0),
    # a P given to a G81 (no dwell) between two G82s: the hole after it dwells it
    ("G82 X1. Z-0.1 R1. P100 F10.\nG81 X2. P6000000\nG82 X3.\n", 5,
     "P6000000 of line 4", 6000.0),
])
def test_a_long_dwell_of_a_kept_cycle_p_names_the_p_and_the_line_it_was_written_on(
        holes, line, word, seconds):
    text = f"G90 G21\nG00 X1. Z1.\n{holes}G80\nM30\n"
    notes = plan(parse_program(text), load_machine("grooving_4axis")).notes
    assert notes == (DWELL_NOTE.format(line=line, word=word, seconds=seconds,
                                       hours=seconds / 3600),)


def test_a_subprograms_hole_under_two_kept_ps_names_the_p_of_its_longest_dwell():
    # O100's line 10 drills under the P of line 4 (5000 s), then under that of line 6 (2 s):
    # its note names P5000000 of line 4, the dwell it is about, not the last P kept
    text = ("O1\nG90 G21\nG00 X1. Z1.\nG81 X1. Z-0.1 R1. P5000000 F10.\nM98 P100\n"
            "G81 X1. P2000\nM98 P100\nG80\nM30\nO100\nG82 X2.\nM99\n")
    program = parse_program(text)
    assert [float(d) for d in program.dwells if d > 0] == [5000.0, 2.0]
    assert program.dwell_words[11] == "P5000000 of line 4"
    assert plan(program, load_machine("grooving_4axis")).notes == (
        DWELL_NOTE.format(line=11, word="P5000000 of line 4", seconds=5000.0,
                          hours=5000 / 3600),)


def test_a_dwell_of_an_hour_is_not_noted_and_a_built_one_is_noted_without_a_word():
    machine = load_machine("grooving_4axis")
    # 3,600,000 ms is the hour itself: a long settling, not a slip
    assert plan(parse_program("G00 X1. Z1.\nG04 P3600000\nM30\n"), machine).notes == ()
    built = ProgramBuilder(1).rapid(X=1e-3, Z=1e-3).dwell(1e9).build()
    assert built.dwell_words == {}
    assert plan(built, machine).notes == (
        "the dwell of line 2 waits 1e+09 s (2.78e+05 h), more than the 1 h a dwell of a "
        "program waits: is its time in the unit meant (P counts milliseconds without a "
        "decimal point, seconds with one; X seconds)?",)


def test_a_long_dwells_note_shows_a_long_word_by_its_ends():
    # X5000. written with 300 leading zeros: the note had held the whole 306-character word
    word = "X" + "0" * 300 + "5000."
    program = parse_program(f"G90 G21\nG00 X1. Z1.\nG04 {word}\nM30\n")
    (note,) = plan(program, load_machine("grooving_4axis")).notes
    shown = f"X{'0' * 39}...00000005000. (306 characters)"  # 40 and 12 characters
    assert note == DWELL_NOTE.format(line=3, word=shown, seconds=5000.0, hours=5000 / 3600)
    assert program.dwell_words == {3: word}  # kept whole
