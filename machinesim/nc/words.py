"""The words and codes of the dialect: limits, G-code groups, integer words, M98 calls.

Internal to the reader (`machinesim.nc.parser`); the rules are in `machinesim.nc` and
docs/nc.md.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

from machinesim.exceptions import brief
from machinesim.nc.lexer import Word
from machinesim.units import RAD_PER_DEG

#: One inch in metres (exact by definition).
M_PER_INCH = 0.0254
#: Least input increments of the "increment" integer-input rule: 1 nm and 0.00001 deg as the
#: machines of the seeds resolve; 0.0000001 inch is the inch increment of that (nano) system.
INCREMENT_M = 1e-9
INCREMENT_INCH_M = 1e-7 * M_PER_INCH
INCREMENT_RAD = 1e-5 * RAD_PER_DEG
#: Least input increments of each integer-input rule that has them: (metric length, m; inch
#: length, m; angle, rad). "increment" is the nanometre machines' above; "is-b" and "is-c"
#: are FANUC's common increment systems (IS-B: 0.001 mm, 0.0001 inch, 0.001 deg; IS-C:
#: 0.0001 mm, 0.00001 inch, 0.0001 deg), which most conventional controls and posts use.
INCREMENTS = {
    "increment": (INCREMENT_M, INCREMENT_INCH_M, INCREMENT_RAD),
    "is-b": (1e-6, 1e-4 * M_PER_INCH, 1e-3 * RAD_PER_DEG),
    "is-c": (1e-7, 1e-5 * M_PER_INCH, 1e-4 * RAD_PER_DEG),
}
#: The dwell time unit of ``G04 X`` without decimal point, s, by integer-input rule: the
#: least input increment of time. FANUC's ISO tables (as Siemens's ISO dialect manual
#: reproduces them: SINUMERIK 802D sl/840D ISO Milling 04.07, 3.3.1 "Dwell (G04)", table
#: 3-7, https://www.easymanua.ls/siemens/sinumerik-802d-sl/manual/592301?p=67): X is in
#: 0.001 s under IS-B, 0.0001 s under IS-C (X10 is 1 ms there, not 10); P is in ms under
#: both. The nanometre machines' rule keeps the millisecond (no table for it was found).
DWELL_INCREMENT_S = {"increment": 1e-3, "is-b": 1e-3, "is-c": 1e-4}
#: The longest a program may take in all, s: 2**39 s, about 17,400 years. A program's clock
#: is a float64 running sum of its moves' and dwells' seconds, spaced at most 2**-14 s (61 us)
#: apart below it, so that it keeps every 0.1 ms: the least increment of time a program writes
#: (IS-C's ``G04 X``, `DWELL_INCREMENT_S`) and the servo loop's default period. A dwell of a
#: billion seconds (31 years, noted as a slip) stays far inside; a time beyond it is a number
#: in the wrong unit or no time at all (``G04 X`` with 1e308 written out: two of them had
#: summed to inf). A dwell word beyond it is refused by the reader, a program whose moves and
#: dwells add up beyond it by the planner (`machinesim.motion.timing.check_total_time`).
MAX_PROGRAM_TIME_S = 2.0**39
#: The slowest feed a program may ask for, m/s: 1 nm a minute, far below any control's
#: least feed (FANUC: 0.001 mm/min at IS-B). Below it a feed was typed in the wrong unit
#: (F0.000...1 took 3e33 s of machining, silently).
SLOWEST_FEED_M_PER_S = 1e-9 / 60.0
#: Integer words (N O G M P L H T D) longer than this are refused: FANUC takes at most 8
#: digits, and the bound keeps int() away from Python's digit limit on hostile input.
MAX_INTEGER_DIGITS = 9
#: Most digits of M98's P: FANUC's M98 P<repeats><program>, a repeat count of up to 4
#: digits before the 4-digit program number (Series 0i-MC Operator's Manual B-64124EN/01,
#: 12.3 "Subprogram (M98, M99)": M98 P51002 calls O1002 five times; later controls take
#: up to 9999 repeats). A P of at most 4 digits is the program number alone, L its repeats.
MAX_CALL_DIGITS = 8
#: The largest program number M98 P can call, its 4 digits (B-64124EN/01, 12.3; FANUC 0i
#: numbers programs O1..O9999). A subprogram numbered above it may be defined, as a control
#: with longer program numbers holds it, but a call to it is refused (`call_of`).
MAX_PROGRAM_NUMBER = 9999
#: Subprograms nest at most this deep (FANUC controls allow 4 to 10 levels); a subprogram
#: that calls itself is refused before it runs.
MAX_SUBPROGRAM_DEPTH = 10
#: Most moves one program may expand to (arcs, cycles, repeats included): twice the 10^7
#: points of the largest freeform programs, ~1.3 GB of move arrays.
MAX_MOVES = 20_000_000
#: Most lines a program file may hold (text after the % that ends it included), refused
#: before any is read: a line holds one block at most, so a file of more lines is a program
#: beyond `MAX_MOVES` but for its blank and comment lines, and reading one costs ~300 bytes a
#: line (5 million `G01 X.. Y..` lines: 1.45 GB) where counting its line ends costs nothing.
MAX_LINES = MAX_MOVES
#: Most blocks one program may run, counting each subprogram repeat, so that nested repeat
#: counts (9999 x 9999 x ...) are refused before they run, not after hours.
MAX_BLOCK_RUNS = 50_000_000

G_GROUPS = {
    "G00": "motion", "G01": "motion", "G02": "motion", "G03": "motion", "G04": "motion",
    "G17": "plane", "G18": "plane", "G19": "plane",
    "G20": "units", "G21": "units",
    "G28": "one-shot", "G53": "one-shot", "G05": "one-shot", "G05.1": "one-shot", "G08": "one-shot",
    "G103": "one-shot", "G187": "one-shot",
    "G40": "cutter compensation",
    "G15": "polar coordinates", "G50": "scaling", "G69": "coordinate rotation",
    "G43": "tool length", "G44": "tool length", "G49": "tool length",
    "G54": "work offset", "G55": "work offset", "G56": "work offset",
    "G57": "work offset", "G58": "work offset", "G59": "work offset",
    "G09": "exact stop", "G61": "path mode", "G64": "path mode",
    "G73": "canned cycle", "G80": "canned cycle", "G81": "canned cycle",
    "G82": "canned cycle", "G83": "canned cycle",
    "G90": "distance", "G91": "distance",
    "G91.1": "arc centre",
    "G94": "feed mode",
    # S in rpm, as every S is read: posts write `G97 S1000 M03` (it had been refused as an
    # unknown G code, and with it the whole program)
    "G97": "spindle speed mode",
    "G98": "return level", "G99": "return level",
}  # fmt: skip
CUTTER_COMPENSATION = (
    "cutter radius compensation ({code}) is not supported: it offsets the path by the tool radius "
    "along its normal, with start-up, corner and cancel rules (FANUC types A, B, C) that a "
    "simulation would have to guess; post the tool-centre path (compensation 'in computer' "
    "in the CAM) and cancel with G40. A program posted with compensation 'in wear' (or "
    "'reverse wear') holds the tool-centre path already, its {code} adding only the wear in "
    "the D register: without the {code} and D words it cuts that path"
)
#: FANUC's canned cycles other than the drilling ones read here, as posts write them for
#: chip breaking, tapping and boring.
OTHER_CYCLES = {
    "G74": "left-hand tapping", "G76": "fine boring",
    "G84": "tapping", "G85": "boring", "G86": "boring", "G87": "back boring",
    "G88": "boring", "G89": "boring",
}
#: Multi-axis programming that a post writes for a control that computes the machine's
#: axes itself.
FIVE_AXIS = {
    "G43.4": "tool centre point control", "G43.5": "tool centre point control",
    "G68.2": "a tilted working plane", "G53.1": "tool axis direction control",
}
#: G15, G50 and G69 (in `G_GROUPS`) cancel polar coordinates, scaling and coordinate
#: rotation (`COORDINATE_CHANGES`: G16, G51, G68), as a post's or a template's safe-start
#: line writes them (Haas: ``G00 G17 G40 G49 G50 G69 G80 G90``). Each sets the state the
#: reader keeps, since those codes are refused, so each is accepted as a state; they had
#: been refused as unknown G codes, and with them the whole program. G50 with an axis word
#: is a lathe's coordinate setting (G code system A, as G92 is on a mill): refused so.
G50_SETTING = (
    "G50 with axis words sets the coordinates (a lathe's G50, G code system A, as G92 does "
    "on a mill), which is not supported: in the milling dialect read here G50 cancels "
    "scaling and takes no axis words; post the coordinates it would give, or set the work "
    "zero with G54..G59 (read_program(..., work_offsets=...))"
)
#: Coordinate changes of old and hand-written programs.
COORDINATE_CHANGES = {
    "G92": "setting the work coordinates at the current position", "G52": "a local "
    "coordinate system", "G68": "coordinate rotation", "G51": "scaling",
    "G51.1": "mirror image", "G16": "polar coordinates",
}
#: Codes of a post's set-up and probing, whose words are data for the control (Fusion 360
#: writes G54.1 P7 for a seventh work offset, G10 L2 to set one, G65 P9810 to call a probe
#: macro): each had been an 'unknown G code', named by the list of codes read.
CONTROL_DATA = {
    "G54.1": "an extended work offset (G54.1 P<n>) is not read: give the offset as one of "
             "G54..G59 (read_program(..., work_offsets=...); on the command line work zero "
             "is machine zero)",
    "G10": "data setting (G10: work offsets, tool offsets, parameters) is not read: give a "
           "work offset with read_program(..., work_offsets=...) and tool lengths in a tool "
           "table (--tools)",
    "G65": "a macro call (G65 P<program>, such as a probing cycle) is not read: its program "
           "runs on the control; post the moves it would make, or leave it out",
}
G_REFUSED = {
    **CONTROL_DATA,
    "G30": "a return to the second, third or fourth reference position (G30, P2..P4), "
           "which the machine's parameters place, is not supported; post G28 to the "
           "reference position (on the command line the machine's home, Z at the top of its "
           "travel) or G53 with machine coordinates",
    "G41": CUTTER_COMPENSATION.format(code="G41"),
    "G42": CUTTER_COMPENSATION.format(code="G42"),
    "G93": "inverse time feed (G93, F = 1/min per block, as multi-axis posts write it) is "
           "not supported; post G94 with F in mm/min",
    "G95": "feed per revolution (G95) is not supported; use G94 with F in mm/min",
    "G96": "constant surface speed (G96, S in m/min) is not supported: S is read as the "
           "spindle speed in rpm (G97); post G97 with S in rpm",
    **{code: f"canned cycle {code} ({what}) is not supported: machinesim expands G73, G81, "
             "G82 and G83 only; post the holes as G73/G81/G82/G83 or as G00/G01 moves"
       for code, what in OTHER_CYCLES.items()},
    "G90.1": "absolute arc centres (G90.1) are not read: I J K are read as the centre's "
             "offset from the arc's start (G91.1, FANUC's only form); post incremental "
             "arc centres",
    **{code: f"{what} ({code}) is not supported: the axis words are read as the machine's "
             "own axis values; post them so (tool centre point and tilted planes off in the "
             "post), as the 5-axis machines here are programmed"
       for code, what in FIVE_AXIS.items()},
    **{code: f"{what} ({code}) is not supported: it would move every later axis word; "
             "post the coordinates it would give, or set the work zero with G54..G59 "
             "(read_program(..., work_offsets=...))"
       for code, what in COORDINATE_CHANGES.items()},
}
#: Refused codes whose block's axis words and P Q R I J K L are the code's own data, not a
#: move or an arc (G52's and G92's X Y Z, G68.2's origin and angles I J K), as are an unknown
#: code's (G10 L2 P1 X.. Y.., G65 P9810 X.., G54.1 P1, G05 P10000): such a block's words are
#: not read. Each had been refused once more beside the code, as 'axis word X without a motion
#: mode; give G00 or G01 first' (which would make G52's origin a move) or 'word P is only read
#: with ...', six problems for one `G68.2 X0. Y0. Z0. I0. J45. K0.`
OWN_WORDS = frozenset({*COORDINATE_CHANGES, *CONTROL_DATA, "G68.2", "G53.1", "G30"})
SINGLE = frozenset("NOSFPXYZABCIJKRQLHTD")
MOTION = {"G00": "rapid", "G01": "linear"}
ARC = ("G02", "G03")
#: Settings of the control's own path smoothing, accepted as states (`read_one_shot`): the
#: path cut here is the programmed one through the servo model, with no look-ahead, corner
#: rounding or acceleration of the control, so none of them moves it. G05.1 (AI contour
#: control) and G08 (look-ahead) are FANUC's; G103 (look-ahead limit) and G187 (smoothness
#: and corner rounding) Haas's, as its posts write them (``G187 P3 E0.0004``, ``G103 P1``).
#: G05 P10000 / P0 is FANUC's high-precision (AI) contour control on / off, as posts for
#: 16i/18i-class controls write it (Mastercam's FANUC post, Makino); it had been refused
#: as an unknown G code. Its other P numbers are not settings but FANUC's high-speed cycle
#: (P1) and binary (P3) operation, whose path is data stored in the control: refused.
NON_MOVING = ("G05", "G05.1", "G08", "G103", "G187")
#: G05's P numbers read as a setting (`NON_MOVING`): on, off.
G05_SETTINGS = (10000, 0)
#: The most blocks G103 P lets a Haas control look ahead: "G103 specifies the maximum number
#: of blocks the control looks ahead (Range 0-15)"; ``G103 P0``, or G103 without P, lifts the
#: limit (Haas Mill Operator's Manual, G103 Limit Block Look-Ahead, Group 00; haascnc.com
#: service/codes-settings, G103).
LOOK_AHEAD_BLOCKS = 15
#: G187's smoothness levels: P1 rough, P2 medium, P3 finish (doubling, keeping, halving the
#: acceleration and corner rounding), overriding Setting 191; E the maximum corner rounding,
#: overriding Setting 85 (Haas, "Advances in Motion Control", diy.haascnc.com/reference-docs/
#: advances-motion-control: "P is the smoothness level mode, 1, 2, or 3, and E is the maximum
#: corner rounding setting"; haas.co.uk, "Smooth Operator": "P1, P2, or P3 ... Rough, Medium
#: or Finish"). G187 without P or E returns to the settings (as posts write it after a
#: drilling operation).
SMOOTHNESS_LEVELS = (1, 2, 3)
M99_IN_MAIN = ("M99 in the main program would jump back to its start forever (FANUC); end "
                "the main program with M30 or M02")
#: A block holding a canned cycle (G73, G81..G83) and a code of G00..G03, G28 or G53, which
#: take the block's axis words too (`Block._run`): LinuxCNC refuses such a block (two motion
#: codes, or a motion code and a G28/G53 that both use axis words); which one a FANUC-style
#: control runs was not found documented. Read as the cycle, the G01 of
#: `G01 G81 X1. Y1. Z-1. R1. F50.` had been read as nothing; read as the G01, the block
#: would be a feed to X1 Y1 Z-1 and no hole. With G28 or G53 the block had moved as the
#: G28/G53, at rapid to Z-1, its R read as nothing.
CYCLE_WITH_MOTION = ("{code} and the canned cycle {cycle} in one block: both take the block's "
                     "axis words, and controls differ on which of the two the block runs "
                     "(LinuxCNC refuses such a block); the holes and the moves of the one "
                     "differ from those of the other: give each its own block (G80 ends the "
                     "cycle)")
#: A subprogram's G20/G21 that switches the units in force (`Block.apply_modal`): FANUC
#: forbids the switch within a program (B-63944EN/02, 8.2: "G20 and G21 must not be switched
#: during a program"), and a subprogram's units stay in force after its M99.
UNITS_IN_SUBPROGRAM = ("{code} in a subprogram switches the units from {was} to {now}: FANUC "
                       "forbids switching G20/G21 within a program, and the blocks after the "
                       "M99 would be read in {now}; select the units once, at the head of the "
                       "main program")
#: The main program's G20/G21 that switches the units after its first motion: the moves
#: before it were read in the other unit (the same FANUC rule; the switch had been taken).
UNITS_AFTER_MOTION = ("{code} switches the units from {was} to {now} after the first motion "
                      "(line {moved}), whose moves were read in {was}: FANUC forbids "
                      "switching G20/G21 within a program; select the units once, at the "
                      "head of the program, before any motion")
#: A feed move under an F given before a G20/G21 that switched the units, with no F since
#: (`Block.check_feed`): FANUC's manual lists the F among the values whose unit the switch
#: changes, but not whether a modal F is converted or kept as a number (B-63944EN/02 8.2; the
#: two readings differ 25.4 times), and wants G20/G21 alone at the head of the program; the
#: reader had kept the F's old reading silently.
FEED_BEFORE_UNITS = ("{code} feeds at the F of line {feed_line} ({number} {was}/min), given "
                     "before {switch} on line {line} switched the units to {now}, and no F "
                     "since: whether a control keeps that F in {was}/min or reads its number "
                     "in {now}/min is not documented for FANUC (B-63944EN/02 8.2 wants "
                     "G20/G21 alone at the head of the program, before any F); give F again "
                     "after the {switch}")
#: A G55..G59 the caller's work offsets do not give (`Block.apply_modal`): with offsets
#: given, a system left out is a mistake more likely than machine zero, and read as zero it
#: had cut the part there silently. Without any offsets every system is zero, and listed.
WORK_OFFSET_NOT_GIVEN = ("{name} selects a work offset that work_offsets does not give (it "
                         "gives {given}): with offsets given, a system left out is not taken "
                         "as zero; give {name} too (read_program(..., work_offsets={{'{name}':"
                         " {{'X': m, 'Y': m, 'Z': m}}}}), SI; {{'{name}': {{}}}} for machine "
                         "zero)")


def integer(word: Word) -> int | None:
    text = word.text
    if not text.isdigit() or len(text) > MAX_INTEGER_DIGITS:
        return None
    return int(text)


def g_name(word: Word) -> str:
    text = word.text
    whole, dot, fraction = text.partition(".")
    if whole.isdigit() and len(text) <= MAX_INTEGER_DIGITS and (
            not dot or (fraction.isdigit() and len(fraction) == 1)):
        return f"G{int(whole):02d}" + (f".{fraction}" if dot else "")
    return word.key


class Call(NamedTuple):
    """One M98 call, with the words it was read from: a problem of the program called
    (not in the file, calling itself) points at ``program_word`` (P), one of its repeats
    at ``repeats_word`` (L, or P when P holds them)."""

    number: int
    repeats: int
    program_word: Word
    repeats_word: Word


class CallProblem(NamedTuple):
    """A malformed M98 block: the message and the word at fault (P or L; M98 when P is
    missing)."""

    message: str
    word: Word


def call_of(words: list[Word], defined: Mapping[int, int] | None = None,
            ) -> Call | CallProblem | None:
    """The call of an M98 block, its problem when malformed, or None when the block has
    no M98. ``defined`` maps the file's subprogram numbers to the (1-based) lines of their
    O blocks: a P that spells one above `MAX_PROGRAM_NUMBER` is refused, since M98 P cannot
    call it (it reads as repeats and a 4-digit number)."""
    m98 = next((w for w in words if w.letter == "M" and integer(w) == 98), None)
    if m98 is None:
        return None
    p = next((w for w in words if w.letter == "P"), None)
    count = next((w for w in words if w.letter == "L"), None)
    if p is None:
        return CallProblem("M98 needs P<program number> (an unsigned integer)", m98)
    whole = integer(p)
    if defined and whole is not None and whole > MAX_PROGRAM_NUMBER and whole in defined:
        keys = brief(p.key) if count is None else f"{brief(p.key)} {brief(count.key)}"
        reading = (f" ({brief(p.key)}: {int(p.text[:-4])} x O{p.text[-4:]})"
                   if count is None and len(p.text) <= MAX_CALL_DIGITS else "")
        return CallProblem(
            f"M98 {keys}: O{whole}, defined on line {defined[whole]}, cannot be called: M98 "
            f"calls programs O1..O{MAX_PROGRAM_NUMBER} (Series 0i-MC Operator's Manual "
            "B-64124EN/01, 12.3), a P of 5 to 8 digits being a repeat count then the 4-digit "
            f"program number{reading}; a control with longer program numbers (Haas: 5 "
            f"digits) reads it as O{whole}. Renumber O{whole} to at most 4 digits and call "
            "it so", p)
    if p.text.isdigit() and len(p.text) > MAX_CALL_DIGITS:
        return CallProblem(
            f"M98 {brief(p.key)} has {len(p.text)} digits; FANUC's P takes at most "
            f"{MAX_CALL_DIGITS}: a repeat count of up to 4 digits, then the 4-digit "
            "program number (M98 P30100: O0100 three times)", p)
    if integer(p) is None:
        return CallProblem(f"M98 needs P<program number> (an unsigned integer), got "
                           f"{brief(p.key)}", p)
    if count is not None:
        repeats = integer(count)
        if len(p.text) > 4:
            packed = (f" or M98 P{repeats}{p.text[-4:]}" if repeats is not None
                      and 0 < repeats < 10_000 else "")
            return CallProblem(
                f"M98 {brief(p.key)} {brief(count.key)}: a P of more than 4 digits holds its "
                f"own repeat count ({int(p.text[:-4])} x O{p.text[-4:]}), so L cannot be given "
                f"beside it; write M98 P{int(p.text[-4:])} {brief(count.key)}{packed}", count)
        if repeats is None:
            return CallProblem(
                f"M98 L takes an unsigned integer repeat count, got {brief(count.key)}", count)
        if repeats == 0:  # as P0<number> below: no call at all, most likely not what was meant
            return CallProblem(f"M98 {brief(p.key)} {brief(count.key)} asks for 0 repeats of "
                               f"O{int(p.text):04d}; leave out L for one call, or the block "
                               "for none", count)
        return Call(int(p.text), repeats, p, count)
    if len(p.text) > 4:  # FANUC's P<repeats><4-digit program number>
        repeats = int(p.text[:-4])
        if repeats == 0:
            return CallProblem(f"M98 {brief(p.key)} asks for 0 repeats of O{p.text[-4:]}; write "
                               f"M98 P{int(p.text[-4:])} for one call or use L", p)
        return Call(int(p.text[-4:]), repeats, p, p)
    return Call(int(p.text), 1, p, p)
