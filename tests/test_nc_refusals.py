"""What the NC reader refuses, located: each refusal the language describes at its line,
column and word (and the block's N word), text outside a comment, a work offset the given
offsets lack, targets beyond float64, bad arguments; fuzzed text raises only
NCProgramError."""

from __future__ import annotations

import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from machinesim.exceptions import NCProgramError, brief
from machinesim.nc import format_program, parse_program, parser, read_program

#: Targets are a decimal in mm times 1e-3 plus an offset: float64 round-off at <= 0.1 m is
#: below 1e-17 m per operation; 1e-15 m leaves room for a few operations and is 1e6 x below
#: 1 nm, so any real misreading (a unit, an offset, a sign) fails.
EXACT_M = 1e-15


# (text, line, column, word, message): each refusal the language describes.
REFUSALS = [
    ("G00 X0 Y0\nG02 X1. Y1.", 2, 1, "G02", "G02 needs the centre"),
    ("G03 X1 I1", 1, 5, "X1", "the arc starts where X is not known yet"),
    ("G00 X0\n\nG41 X0", 3, 1, "G41", r"cutter radius compensation \(G41\) is not supp"),
    ("G00 X0\nG42 D1 G01 X1. F100.", 2, 1, "G42", "compensation 'in wear' .* holds the "
     "tool-centre path already, its G42 adding only the wear .* without the G42 and D"),
    # Fusion 360's seventh work offset, work offset setting and probing macro had been
    # 'unknown G code' with the list of codes read
    ("G54.1 P7", 1, 1, "G54.1", r"an extended work offset \(G54.1 P<n>\) is not read: give "
     "the offset as one of G54..G59"),
    ("G10 L2 P1 X0 Y0 Z0", 1, 1, "G10", r"data setting \(G10: work offsets, tool offsets, "
     r"parameters\) is not read"),
    ("G65 P9810 X1. F1000.", 1, 1, "G65", r"a macro call \(G65 P<program>, such as a probing "
     r"cycle\) is not read"),
    # G30 had been an 'unknown G code', and M99's, M97's and M198's P 'only read with G04
    # ..., M98 (program)'
    ("G00 X0\nG91 G30 Z0.", 2, 5, "G30", "second, third or fourth reference position "
     r"\(G30, P2..P4\), which the machine's parameters place, is not supported; post G28"),
    ("O1\nM98 P2\nM30\nO2\nG00 X1.\nM99 P10", 6, 5, "P10", "M99 P10 returns to the block "
     "N10 of the calling program, not to the block after its M98, and is not read"),
    ("G00 X0\nM97 P1000\nM30", 2, 5, "P1000", r"M97 P1000 \(Haas's call of the local "
     r"subprogram at N1000 of this program\) is not read: write the subprogram as O1000"),
    ("G00 X0\nM198 P1000\nM30", 2, 6, "P1000", "M198 P1000 calls a subprogram from an "
     "external device"),
    ("G95", 1, 1, "G95", r"feed per revolution \(G95\)"),
    ("G00 X0\nG96 S200 M03", 2, 1, "G96", r"constant surface speed \(G96, S in m/min\) is "
     r"not supported: S is read as the spindle speed in rpm \(G97\)"),
    ("G00 X0 U1", 1, 8, "U1", "unknown word letter 'U'"),
    ("G00 X0 I5", 1, 8, "I5", "word I is only read with G02/G03"),
    ("G00 X0\nM99", 2, 1, "M99", "M99 in the main program would jump back"),
    ("G00 Z0\nG43 H1 Z5.", 2, 5, "H1", "G43 H1 needs tool 1's length"),
    ("G00 X0\nG91 G53 X0", 2, 5, "G53", "machine coordinates, which are absolute"),
    # a bare G28 (26 in one public set of Haas-style programs) is read differently by
    # Haas (every axis home) and FANUC (none): the message had said neither
    ("G28", 1, 1, "G28", "G28 without axis words: a Haas control returns every axis to "
     "machine zero, a FANUC moves none; name the axes it moves, Z first"),
    ("G53", 1, 1, "G53", "G53 needs the axes it moves"),
    ("G05.1 Q2", 1, 1, "G05.1", r"G05.1 needs Q1 \(on\) or Q0 \(off\)"),
    ("G05.1 Q1 X0", 1, 10, "X0", "G05.1 stands in a block of its own"),
    ("G81 X0 Z-1 R1", 1, 1, "G81", "Z is not known yet"),
    ("G00 Z5\nG81 X0 Z3. R2.", 2, 8, "Z3.", "hole bottom Z .* is not below the R plane"),
    # a G01 or G00 beside the cycle code had been read as nothing: the block drilled
    ("G00 X0 Y0 Z5.\nG01 G81 X1. Y1. Z-1. R1. F50.", 2, 5, "G81",
     "G01 and the canned cycle G81 in one block: both take the block.s axis words"),
    ("G00 X0 Y0 Z5.\nG83 G00 X1. Y1. Z-1. R1. Q.5 F50.", 2, 1, "G83",
     r"G00 and the canned cycle G83 in one block: .* give each its own block \(G80 ends"),
    # ... and a G28 or G53 beside it had moved through Z-1 at rapid, its R read as nothing
    ("G00 X0 Y0 Z5.\nG81 G28 X1. Y1. Z-1. R1. F50.", 2, 1, "G81",
     "G28 and the canned cycle G81 in one block: both take the block's axis words"),
    ("G00 X0 Y0 Z5.\nG53 G73 X1. Y1. Z-1. R1. Q.5 F50.", 2, 5, "G73",
     "G53 and the canned cycle G73 in one block"),
    # a cycle's word in a block that drills no hole had been read as nothing: the next hole
    # pecked 0.5, dwelt 0.1 s, went down to R1
    ("G00 X0 Y0 Z5.\nG83 X1. Y1. Z-1. R1. Q0.5 F50.\nQ0.2\nX2.", 3, 1, "Q0.2",
     "word Q while the canned cycle G83 is active, in a block without X, Y, Z, R or a rotary "
     "axis, which drills no hole: .* give it in the block of the hole it is for$"),
    ("G00 X0 Y0 Z5.\nG82 X1. Y1. Z-1. R1. P100 F50.\nP500\nX2.", 3, 1, "P500",
     "word P while the canned cycle G82 is active, in a block without X, Y, Z, R or a "),
    ("G00 X0 Y0 Z5.\nG81 X1. Y1. Z-1. R1. F50.\nG28 Z5. R2.\nX2.", 3, 9, "R2.",
     "word R while the canned cycle G81 is active, in a G28 block, which drills no hole"),
    ("G00 X0 Y0\nG02 X10. Y0 R4. F100", 2, 13, "R4.", "more than the diameter"),
    ("G00 X0 Y0\nG02 X10. Y0 I5.01 F100", 2, 13, "I5.01", "end point is off the arc"),
    ("G00 X0 Y0\nG02 X10. I5. R5.", 2, 14, "R5.", "an arc takes R or I J, not both"),
    ("G00 X0 Y0\nG03 X0 Y0 R5.", 2, 11, "R5.", "cannot be a full circle"),
    # an M98 problem points at the word at fault, P or L (it had pointed at M98)
    ("O1\nM98 P2\nM30", 2, 5, "P2", "M98 calls O0002, which is not in this file"),
    ("O1\nM98 P2\nM30\nO2\nM98 P2\nM99", 5, 5, "P2", "O0002 calls itself"),
    ("O1\nM30\nO2\nG04 P1\nM99\nG04 P2", 6, 1, "G04", "block after M99 on line 5"),
    ("O1\nM30\nO2\nM30\nM99", 4, 1, "M30", "M30 in subprogram O0002"),
    ("M98 P00002", 1, 5, "P00002", "asks for 0 repeats"),
    # L0 is the same 0 repeats as P00002 and is refused alike (it had run no call, silently)
    ("O1\nM98 P2 L0\nM30\nO2\nG00 X1.\nM99", 2, 8, "L0",
     r"M98 P2 L0 asks for 0 repeats of O0002; leave out L for one call, or the block for none$"),
    ("O1\nM98 P2 L00\nM30\nO2\nG00 X1.\nM99", 2, 8, "L00", "asks for 0 repeats"),
    ("M98", 1, 1, "M98", r"M98 needs P<program number> \(an unsigned integer\)$"),
    ("M98 P1.5", 1, 5, "P1.5", r"M98 needs P<program number> \(an unsigned integer\), got P1.5"),
    ("O1\nM98 P2 L1.5\nM30\nO2\nM99", 2, 8, "L1.5", "M98 L takes an unsigned integer"),
    ("O1\nM98 P2 L99999999\nM30\nO2\nM98 P3 L9999\nM99\nO3\nG04 P0\nM99", 2, 8, "L99999999",
     "more than 50000000 blocks"),
    ("G00 X1e5", 1, 7, "E5", "unknown word letter 'E'"),
    ("G00 X1.2.3", 1, 5, "X1.2.3", "malformed number"),
    ("G00 X--1", 1, 5, "X--1", "malformed number .* e.g. X-12.5$"),
    ("G00 X2. Y2. Z5.\nG83 X2. Y2. Z-2. R1. Q.5 F50.\nG91 X2. K3", 3, 1, "G91",
     r"G83 repeated in G91 with R \(line 2\) and Z \(line 2\) given in G90: .* restate R "
     "and Z after changing G90/G91"),
    ("G00 X2. Y2. Z5.\nG83 X2. Y2. Z-2. R1. Q.5 F50.\nG91 X2. R-4. K3", 3, 1, "G91",
     r"with Z \(line 2\) given in G90: .* restate Z after"),
    ("G01 X1 F--5", 1, 8, "F--5", "malformed number .* e.g. F12.5$"),  # F-12.5 is refused
    ("G1.2.3", 1, 1, "G1.2.3", "malformed number .* e.g. G12$"),
    ("G00 Y", 1, 5, "Y", "malformed number"),
    ("G00 Xnan", 1, 5, "Xnan", "Xnan is not a finite number"),
    ("G00 X0\nG01 Z-inf F100.", 2, 5, "Z-inf", "Z-inf is not a finite number"),
    ("G00 X0\nG01 YInfinity F100.", 2, 5, "YInfinity", "YInfinity is not a finite number"),
    ("G00 X1 X2", 1, 8, "X2", "axis word X appears twice in one block"),
    ("G01 X1 F10 F20", 1, 12, "F20", "word F appears twice"),
    ("G00 G01 X1", 1, 5, "G01", "two motion G-codes in one block: G00 and G01"),
    ("G00 X0\nG04 G01 X1", 2, 5, "G01", "two motion G-codes in one block: G04 and G01"),
    ("G90 G91", 1, 5, "G91", "two distance G-codes in one block"),
    # P with a decimal point is seconds (Haas): the messages had said P is milliseconds
    ("G04", 1, 1, "G04", r"dwell without time: G04 needs P<milliseconds> \(with a decimal "
     r"point, P<seconds>, as Haas reads it\) or X<seconds>$"),
    ("G04 P-1.5", 1, 5, "P-1.5", "G04's dwell P-1.5 must be >= 0 .with a decimal point P is "
     "seconds"),
    ("G04 P-1500", 1, 5, "P-1500", "dwell time must be an unsigned integer"),
    ("G04 P100 X1.", 1, 10, "X1.", "got both P and X"),
    ("G04 X-1.", 1, 5, "X-1.", "dwell time must be >= 0"),
    ("G04 Y1", 1, 5, "Y1", r"axis word Y in a dwell block; G04 takes only "
     r"P<milliseconds> \(with a decimal point, P<seconds>, as Haas reads it\) or X<seconds>$"),
    ("G00 X0 P100", 1, 8, "P100", "P is only read with G04"),
    ("X1", 1, 1, "X1", "without a motion mode"),
    ("G91 G00 X1", 1, 9, "X1", "incremental .G91. move on axis X before its position"),
    ("G00 X0\nM30\nG00 X1", 3, 1, "G00", "block after the program end M30 on line 2"),
    ("G00 X0 (unclosed", 1, 8, "(", "comment '\\(' is not closed"),
    ("G00 X0 )", 1, 8, ")", "without an opening"),
    ("G00 X0 (a (b) c)", 1, 11, "(", "comments do not nest: .* opened at column 8"),
    ("O1\nM98 P1\nM30", 2, 5, "P1", "M98 calls O0001, the main program itself"),
    ("G00 X0 / Y1", 1, 8, "/", "block delete '/' is not read: a FANUC control skips"),
    ("G00 X12,5 Y0", 1, 8, ",", "decimal comma in 'X12,5': NC numbers take a decimal point"),
    ("G00 X0 Z1.\nG93 G01 X1. F10.", 2, 1, "G93", "inverse time feed \\(G93"),
    ("G00 X0 Y0 Z5.\nG74 X1. Y1. Z-1. R1. F100.", 2, 1, "G74",
     "canned cycle G74 \\(left-hand tapping\\) is not supported: machinesim expands G73, G81"),
    ("G00 X0 Y0 Z5.\nG98 G84 X1. Y1. Z-1. R1. F100.", 2, 5, "G84",
     "canned cycle G84 \\(tapping\\) is not supported"),
    ("G00 X0 Y0 Z5.\nG43.4 H1", 2, 1, "G43.4",
     "tool centre point control \\(G43.4\\) is not supported: the axis words"),
    ("G92 X0 Y0 Z50.", 1, 1, "G92", "setting the work coordinates at the current position "
     "\\(G92\\) is not supported: it would move every later axis word"),
    ("G00 X0\n/G01 X1. F10.", 2, 1, "/", "block delete '/' is not read"),
    ("G00 X0\n/2 G01 X1. F10.", 2, 1, "/2", "block delete '/2' is not read"),
    ("G00 #1", 1, 5, "#", "macro variable '#1': macro variables and expressions"),
    ("#101=[#1*2.] (CUSTOM MACRO B)", 1, 1, "#", "are not read: post the program with"),
    # one problem for the whole expression: it had been ten, one for each letter of 'sqrt'
    ("G00 X0 Y0\nG02 X600. I[300 + [100 * [0.00099 * sqrt[2]]]]", 2, 11,
     "I[300 + [100 * [0.00099 * sqrt[2]]]]", "^[^\n]*is a macro expression: macro"),
    ("G01 X#146/2+#148 F100.", 1, 5, "X#146/2+#148", r"X#146/2\+#148 is a macro expression"),
    ("G00 10", 1, 5, "10", "without an address letter"),
    ("G01 X0 F0", 1, 8, "F0", "feed must be > 0"),
    ("G01 X0 F-5", 1, 8, "F-5", "feed must be > 0"),
    ("G01 X0 F0." + "0" * 30 + "1", 1, 8, "F0." + "0" * 30 + "1", "below 1 nm a minute"),
    ("G00 X0\nG01 X1. F0.0000009", 2, 9, "F0.0000009", "below 1 nm a minute"),
    ("S-100", 1, 1, "S-100", "spindle speed must be >= 0"),
    ("M3.5", 1, 1, "M3.5", "M code must be an unsigned integer"),
    ("N1234567890", 1, 1, "N1234567890", "at most 9 digits"),
    ("G-1", 1, 1, "G-1", "has a sign"),
    ("G00 X0\nO1", 2, 1, "O1", "must be the first block"),
    ("O1\nM30\nO2\nM99\nO2\nM99", 5, 1, "O2", "subprogram O0002 is defined twice"),
    ("O1 G00", 1, 4, "G00", "must stand alone"),
    ("G00 X0\n% G00", 2, 3, "G00", "must stand alone on its line"),
    # one problem for the text, not one for each of its letters (MPCNC posts write such
    # lines as comments): 'vfd enable' had been nine problems
    ("G00 X0\n% vfd enable (MPCNC)", 2, 3, "vfd enable",
     "^[^\n]*found 'vfd enable' after it: past the opening one, a '%' ends the program"),
    ("G00 X0 %", 1, 8, "%", "found it after words"),
    ("G00 X" + "9" * 400, 1, 5, "X" + "9" * 400, "out of range"),
    ("G00 X1.\nG04 X" + "9" * 400 + ".", 2, 5, "X" + "9" * 400 + ".", "out of range"),
]


#: What a word is, in the refusal of text outside parentheses.
_TEXT_WANTED = ("a word is one letter and a number (X1., M98 P1000); expected a comment in "
                "parentheses")
_MACRO_WANTED = ("(custom macro B: IF, GOTO, WHILE/DO/END, DPRNT) is not read: machinesim reads "
                 "no branches, loops or macro output; post the program with them resolved into "
                 "plain blocks")


@pytest.mark.parametrize(("text", "line", "column", "key", "message"), [
    # prose outside parentheses: one problem for the text (to the line's end, or a comment),
    # not one 'malformed number' for each of its letters (14 for ROUGH THE POCKET)
    ("ROUGH THE POCKET\nG00 X0", 1, 1, "ROUGH THE POCKET",
     f"text 'ROUGH THE POCKET' outside a comment: {_TEXT_WANTED}, e.g. '(ROUGH THE POCKET)'"),
    ("G00 X0\nG01 X1. FEED SLOWLY (NOTE)", 2, 9, "FEED SLOWLY",
     f"text 'FEED SLOWLY' outside a comment: {_TEXT_WANTED}, e.g. '(FEED SLOWLY)'"),
    ("G00 X0 Y0\nA POCKET", 2, 1, "A POCKET",
     f"text 'A POCKET' outside a comment: {_TEXT_WANTED}, e.g. '(A POCKET)'"),
    ("G00 X1.5MM", 1, 9, "MM", f"text 'MM' outside a comment: {_TEXT_WANTED}, e.g. '(MM)'"),
    ("G00 X0\nEND OF PROGRAM", 2, 1, "END OF PROGRAM",
     f"text 'END OF PROGRAM' outside a comment: {_TEXT_WANTED}, e.g. '(END OF PROGRAM)'"),
    # custom macro B statements, refused as macros: each had been one problem per letter
    ("IF [#1 GT 2] GOTO 10", 1, 1, "IF [#1 GT 2] GOTO 10",
     f"macro statement 'IF [#1 GT 2] GOTO 10' {_MACRO_WANTED}"),
    ("G00 X0\nWHILE [#1 LT 3] DO1 (LOOP)", 2, 1, "WHILE [#1 LT 3] DO1",
     f"macro statement 'WHILE [#1 LT 3] DO1' {_MACRO_WANTED}"),
    ("GOTO 10", 1, 1, "GOTO 10", f"macro statement 'GOTO 10' {_MACRO_WANTED}"),
    ("G00 X0\nEND1", 2, 1, "END1", f"macro statement 'END1' {_MACRO_WANTED}"),
    # a lone letter before a word is still a missing number, not text
    ("G00 X Y1.", 1, 5, "X",
     "malformed number '' after 'X'; expected digits with an optional sign and decimal "
     "point, e.g. X-12.5"),
])
def test_text_outside_a_comment_is_one_problem(text, line, column, key, message):
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "prog.nc")
    error = info.value
    assert (error.line, error.column, error.key) == (line, column, key)
    assert str(error) == f"prog.nc, line {line}, column {column}, key '{key}': {message}"


_NAMED = ("LinuxCNC named parameter (#<name>), which this reader of FANUC text does not read "
          "(no parameters or expressions): expand the program with their values before "
          "reading it (docs/nc.md, 'LinuxCNC programs')")
_O_WORD = ("which this reader of FANUC text does not read (its subroutines, branches and loops "
           "are LinuxCNC's, not FANUC's O1234 ... M99 called by M98): expand the program into "
           "plain blocks before reading it (docs/nc.md, 'LinuxCNC programs')")


@pytest.mark.parametrize(("text", "problems"), [
    # LinuxCNC's test-xyzbc.ngc: each construct had been two or three problems (the '#', a
    # "malformed number '<'", stray text 'x_max>'), none naming it
    ("G21 G90\n #<x_max> = #<xy_max> (=30)\nG01 X#<x_max> F#<feedrate>\n"
     "G03 X-#<x_max> Y0 I0 J - #<g3_j>\nM30", [
         (2, 2, "#<x_max> = #<xy_max>", f"'#<x_max> = #<xy_max>' sets a {_NAMED}"),
         (3, 5, "X#<x_max>", f"X#<x_max> takes its value from a {_NAMED}; expected a number, "
          "e.g. X-12.5"),
         (3, 15, "F#<feedrate>", f"F#<feedrate> takes its value from a {_NAMED}; expected a "
          "number, e.g. F12.5"),
         (4, 5, "X-#<x_max>", f"X-#<x_max> takes its value from a {_NAMED}; expected a "
          "number, e.g. X-12.5"),
         (4, 22, "J- #<g3_j>", f"J- #<g3_j> takes its value from a {_NAMED}; expected a "
          "number, e.g. J-12.5"),
     ]),
    ("o<test-xyzbc> sub\nG21 G00 X0\no<test-xyzbc> endsub\no<test-xyzbc> call [20] (b)\n"
     "O100 while [#1 lt 3]\nM30", [
         (1, 1, "o<test-xyzbc> sub",
          f"LinuxCNC O-word subroutine 'o<test-xyzbc> sub', {_O_WORD}"),
         (3, 1, "o<test-xyzbc> endsub",
          f"LinuxCNC O-word subroutine 'o<test-xyzbc> endsub', {_O_WORD}"),
         (4, 1, "o<test-xyzbc> call [20]",
          f"LinuxCNC O-word subroutine 'o<test-xyzbc> call [20]', {_O_WORD}"),
         (5, 1, "O100 while [#1 lt 3]",
          f"LinuxCNC O-word flow control 'O100 while [#1 lt 3]', {_O_WORD}"),
     ]),
])
def test_linuxcnc_constructs_are_one_problem_each_naming_them(text, problems):
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "prog.ngc")
    found = [(p.line, p.column, p.key, p.message) for p in info.value.problems]
    assert found == problems


@pytest.mark.parametrize(("block", "code"), [
    # a Fusion 360 post's tilted plane: six problems, its I J K 'only read with G02/G03'
    # and its X 'without a motion mode; give G00 or G01 first'
    ("G68.2 X0. Y0. Z0. I0. J45. K0.", "G68.2"),
    ("G52 X10. Y5.", "G52"),  # its advice had been to make the origin a move
    ("G10 L2 P1 X0 Y0 Z0", "G10"),  # work offset setting: four problems
    ("G65 P9810 X1. Y2. Z3.", "G65"),  # a probing macro's call
    ("G54.1 P7", "G54.1"),  # an extended work offset, Fusion's for a 7th one
    ("G30 G91 Z0.", "G30"),  # the second reference position, a Mastercam tool change's
])
def test_a_refused_codes_own_words_are_not_refused_again(block, code):
    with pytest.raises(NCProgramError) as info:
        parse_program(f"G90 G21\n{block}\nM30\n", "prog.nc")
    error = info.value
    assert (error.line, error.column, error.key) == (2, 1, code)
    assert "problems in the program" not in str(error)


def test_an_error_of_one_problem_holds_it_in_problems():
    # docs/nc.md: "all in error.problems"; it had been set on an error of several only
    with pytest.raises(NCProgramError) as info:
        parse_program("G90 G21\nG00 X0 U1\nM30\n", "prog.nc")
    assert info.value.problems == (info.value,)
    with pytest.raises(NCProgramError) as info:
        parse_program("G90 G21\nG00 X0 U1\nG00 X0 V1\nM30\n", "prog.nc")
    assert [(p.line, p.key) for p in info.value.problems] == [(2, "U1"), (3, "V1")]


def test_a_fanuc_program_number_with_a_comment_is_no_o_word():
    program = parse_program("O1000 (WHILE SUB)\nG21 G00 X1.\nM30")
    assert program.targets[:, 0].tolist() == [1e-3]


def test_words_packed_without_blanks_are_no_text():
    program = parse_program("g90g21\nG01X1.Y2.F100.\nM98P1000\nM30\nO1000\nx3.y-4.\nM99\n")
    assert program.targets[:, :2].tolist() == [[1e-3, 2e-3], [3e-3, -4e-3]]


@pytest.mark.parametrize(("text", "line", "column", "word", "message"), REFUSALS)
def test_refusals_name_line_column_and_word(text, line, column, word, message):
    with pytest.raises(NCProgramError, match=message) as info:
        parse_program(text, "prog.nc")
    error = info.value
    assert (error.source, error.line, error.column, error.key) == ("prog.nc", line, column, word)
    # the key stays whole; the message shows a long one by its ends (`brief`)
    assert str(error).startswith(f"prog.nc, line {line}, column {column}, key '{brief(word)}': ")


def test_refused_arguments():
    with pytest.raises(NCProgramError, match="integer_input must be one of"):
        parse_program("G00 X0", integer_input="decimal")
    with pytest.raises(NCProgramError, match="unknown work offset 'G60'"):
        parse_program("G00 X0", work_offsets={"G60": {"X": 0.0}})
    with pytest.raises(NCProgramError, match="unknown axis 'U'"):
        parse_program("G00 X0", work_offsets={"G54": {"U": 0.0}})
    with pytest.raises(NCProgramError, match="must be str"):
        parse_program(b"G00 X0")


@pytest.mark.parametrize("code", ["G55", "G56", "G57", "G58", "G59"])
def test_a_work_offset_the_given_offsets_lack_is_refused_naming_its_line(code):
    # G54 X 10 mm given, the program selects another system: it had read as zero (machine
    # zero), the part cut 10 mm from where G54's would be, without a word
    text = f"G90 G21\nG00 X0 Y0 Z1.\nN20 {code}\nG00 X1.\nM30\n"
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "prog.nc", work_offsets={"G54": {"X": 10e-3}})
    error = info.value
    assert (error.line, error.column, error.key) == (3, 5, code)
    assert f"{code} selects a work offset that work_offsets does not give (it gives G54)" in str(
        error)
    # given (an empty system is machine zero), the same text reads: X1. is 1 mm + its offset
    for system, x_mm in (({"X": -20e-3}, -19.0), ({}, 1.0)):
        program = parse_program(text, work_offsets={"G54": {"X": 10e-3}, code: system})
        assert program.targets[:, 0].tolist() == pytest.approx([10e-3, x_mm * 1e-3],
                                                               abs=EXACT_M)
    # without any offsets every system is zero, as documented, and listed with its line
    program = parse_program(text)
    assert program.targets[-1, 0] == pytest.approx(1e-3, abs=EXACT_M)
    assert program.states[code] == 3


def test_g54_left_out_of_the_given_offsets_is_machine_zero():
    # G54 is the system a program runs in without a G54..G59 word; left out it is zero, as
    # the writer and `to_resolution` read it
    text = "G90 G21 G54\nG00 X1.\nG55 X1.\nM30\n"
    program = parse_program(text, work_offsets={"G55": {"X": 5e-3}})
    assert program.targets[:, 0].tolist() == pytest.approx([1e-3, 6e-3], abs=EXACT_M)


@pytest.mark.parametrize("distance", ["G90", "G91"])
def test_target_beyond_float64_is_refused(distance):
    # An offset near the float64 maximum (1.798e308) plus 1e305 m overflows: absolute values
    # add the offset, incremental ones the previous target (which holds the offset).
    huge = "1" + "0" * 308 + "."  # 1e308 mm = 1e305 m
    with pytest.raises(NCProgramError, match="out of range") as info:
        parse_program(f"G00 X0\n{distance} X{huge}", work_offsets={"G54": {"X": 1.797e308}})
    assert (info.value.line, info.value.column, info.value.key) == (2, 5, "X" + huge)


NC_CHARACTERS = "GXYZABCMNFSPOIJKTgxz0123456789.+-  ()%;\n\t/#"
_number = st.one_of(
    st.integers(-10**12, 10**12).map(str),
    st.floats(allow_nan=False, allow_infinity=False, width=64).map(lambda v: f"{v:f}"),
    st.text("0123456789.+-", max_size=6),
)
_any_word = st.tuples(st.sampled_from("GGGMNFSPOXYZABCxyzIT"), _number).map("".join)
# Mostly well-formed words, so that many programs parse and reach the writer too.
_good_word = st.one_of(
    st.sampled_from(["G0", "G00", "G1", "g01", "G04", "G90", "G91", "G20", "G21", "G18",
                     "G55", "G94", "M3", "M08", "M30", "S1000", "F100", "P250"]),
    st.tuples(st.sampled_from("XYZABCxz"), _number).map("".join),
)
_word = st.one_of(_good_word, _good_word, _good_word, _any_word)
_block = st.lists(_word, max_size=6).map(" ".join)
_words_text = st.tuples(
    st.sampled_from(["", "G00 X0 Y0 Z0 A0 B0 C0\n", "G01 X0 F100\n"]),
    st.lists(_block, max_size=12).map("\n".join),
).map("".join)


def _parse_only_nc_errors(text: str, integer_input: str) -> None:
    try:
        program = parse_program(text, "fuzz.nc", integer_input=integer_input)
    except NCProgramError as error:
        assert error.line is not None
        assert 1 <= error.line <= text.count("\n") + 1
        # the line, and the block's N word when it has one: 'line 1,' or 'line 1 (N0),'
        assert re.search(rf"line {error.line}( \(N[0-9]+\))?,", str(error))
        return
    try:
        written = format_program(program)
    except NCProgramError:
        return
    parse_program(written)


@settings(max_examples=300, deadline=None)
@given(st.text(NC_CHARACTERS, max_size=200), st.sampled_from(["calculator", "increment"]))
def test_fuzz_nc_characters_raise_only_nc_errors(text, integer_input):
    _parse_only_nc_errors(text, integer_input)


@settings(max_examples=300, deadline=None)
@given(_words_text, st.sampled_from(["calculator", "increment"]))
def test_fuzz_word_sequences_raise_only_nc_errors(text, integer_input):
    _parse_only_nc_errors(text, integer_input)


def test_a_refusal_names_the_blocks_n_word_beside_its_line():
    # an error names the file's line (an editor's) and, where the block has an N word, that
    # block number (the control's): 'line 4 (N20)'; a block without one reads as before
    text = "%\nO1000\nN10 G21 G90\nN0020 G01 X1. F100. G99.3\nG01 X2. G99.4\nM30\n%\n"
    with pytest.raises(NCProgramError) as info:
        parse_program(text, "p.nc")
    error = info.value
    assert (error.line, error.block) == (4, 20)
    assert str(error).startswith("p.nc, line 4 (N20), column 21, key 'G99.3': 2 problems in "
                                 "the program (the first at line 4 (N20); ")
    assert [str(e).split(": ")[0] for e in error.problems] == [
        "p.nc, line 4 (N20), column 21, key 'G99.3'", "p.nc, line 5, column 9, key 'G99.4'"]
    # a malformed word of the lexer's, and one refused by a single block
    for bad, where in (("N30 G01 X", "p.nc, line 3 (N30), column 9, key 'X'"),
                       ("G01 X", "p.nc, line 3, column 5, key 'X'")):
        with pytest.raises(NCProgramError) as info:
            parse_program(f"%\nG21\n{bad}\nM30\n%\n", "p.nc")
        assert str(info.value).startswith(where + ": malformed number ''"), str(info.value)


def test_a_program_of_more_lines_than_the_limit_is_refused_before_it_is_parsed(
        monkeypatch, tmp_path):
    # A program of MAX_LINES lines reads; one line more is refused, naming the limit, by
    # parse_program and by read_program (which stops reading the file at the line too many),
    # with or without a line end after the last line.
    monkeypatch.setattr(parser, "MAX_LINES", 6)
    monkeypatch.setattr(parser, "READ_CHUNK_BYTES", 8)
    lines = ["G90 G21", "G01 X1. F100.", "X2.", "X3.", "X4."]
    path = tmp_path / "p.nc"
    for end in ("", "\n"):
        text = "\n".join([*lines, "M30"]) + end  # 6 lines
        assert len(parse_program(text)) == 4
        path.write_text(text)
        assert len(read_program(path)) == 4
        text = "\n".join([*lines, "X5.", "M30"]) + end  # 7 lines
        path.write_text(text)
        with pytest.raises(NCProgramError) as parsed:
            parse_program(text, "p.nc")
        with pytest.raises(NCProgramError) as read:
            read_program(path)
        for info, source in ((parsed, "p.nc"), (read, str(path))):
            assert str(info.value).startswith(f"{source}: the program has more than 6 lines, "
                                              "the most machinesim reads")


def test_a_file_of_21_million_lines_is_refused_without_reading_them(tmp_path):
    # 21,000,000 line ends (21 MB): refused at the limit of 20,000,000 lines, where the file
    # had been read whole, split and scanned (3.2 GB and 120 s for 21 million short moves)
    path = tmp_path / "long.nc"
    path.write_bytes(b"G90 G21\nG01 X1. F100.\n" + b"\n" * 21_000_000)
    with pytest.raises(NCProgramError, match=r"more than 20000000 lines") as info:
        read_program(path)
    assert info.value.line is None and info.value.source == str(path)


_LONG = "9" * 100_000


@pytest.mark.parametrize("block, key", [
    (f"N{_LONG} G00 X1.", f"N{_LONG}"), (f"T{_LONG}", f"T{_LONG}"),
    (f"G00 G43 H{_LONG} Z1.", f"H{_LONG}"), (f"G04 P{_LONG}", f"P{_LONG}"),
    (f"G{_LONG} X1.", f"G{_LONG}"), (f"G01 X1. F0.{'0' * 100_000}1", f"F0.{'0' * 100_000}1"),
    (f"M98 P2 L{_LONG}", f"L{_LONG}"), (f"G01 X1. F-{_LONG}.", f"F-{_LONG}.")])
def test_a_refused_word_of_100000_digits_is_shown_by_its_ends(block, key):
    # the message named such a word whole in its text (a 100 MB N word: 100 MB of stderr),
    # though its key was already shown by its ends
    with pytest.raises(NCProgramError) as info:
        parse_program(f"G90 G21\n{block}\nM30\nO2\nG00 X2.\nM99\n", "p.nc")
    assert (info.value.line, info.value.key) == (2, key)
    message = str(info.value)
    assert len(message) < 2000, message[:300]
    assert message.count(brief(key)) >= 1


def test_an_incremental_word_that_takes_the_axis_beyond_float64_is_named_so():
    # 17,980 steps of X 1e307 mm (written out) under G91 pass float64's 1.8e308 mm: each
    # such word had been refused as 'value of X1000... is out of range (not finite in
    # float64)', which the word itself is not
    step = "G00 X1" + "0" * 307 + ".\n"
    with pytest.raises(NCProgramError) as caught:
        parse_program("G90 G21\nG00 X0 Y0 Z1.\nG91\n" + step * 17980 + "M30\n", "g.nc")
    error = caught.value
    assert (error.line, error.column) == (17980, 5)  # X = 1e304 m x 17976 before it
    assert "incremental (G91) X1000" in str(error)
    assert "from X = 1.7976e+308 m takes the axis out of range (beyond float64)" in str(error)
    assert "value of" not in str(error)
