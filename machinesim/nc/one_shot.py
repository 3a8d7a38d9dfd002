"""A block of a one-shot G code: a dwell (G04), a rapid through the intermediate point to the
reference position (G28) or to machine coordinates (G53), or a setting of the control's
path smoothing (G05, G05.1, G08, G103, G187: `machinesim.nc.words.NON_MOVING`).

Internal to the reader: a block (`machinesim.nc.blocks.Block`) with G04 reads here
(`read_dwell`), one with G28, G53 or a setting in `read_one_shot`; none of them changes
the modal motion (G00 G01 G02 G03) or cancels a canned cycle.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from machinesim.exceptions import brief
from machinesim.nc.words import (
    DWELL_INCREMENT_S,
    G05_SETTINGS,
    LOOK_AHEAD_BLOCKS,
    NON_MOVING,
    SINGLE,
    SMOOTHNESS_LEVELS,
    integer,
)

if TYPE_CHECKING:
    from machinesim.nc.blocks import Block
    from machinesim.nc.lexer import Word

__all__ = ["read_dwell", "read_one_shot"]

#: The numbers a G05.1's Q may be written as, with its setting: Q1 and Q0, and with a
#: decimal point (Q1., Q0.0), which FANUC reads as the value (Q is one of the addresses a
#: decimal point may be given in; programs and G-code lists write ``G05.1 Q1.``). G08's P
#: takes no decimal point on a FANUC control (as G04's P), so ``P1.`` is refused there.
_SWITCH_NUMBERS = {"Q": {"0": 0, "1": 1, "0.": 0, "1.": 1}, "P": {"0": 0, "1": 1}}


def _switch(word: Word) -> int | None:
    """The setting, 1 (on) or 0 (off), of a G05.1's Q or a G08's P, or None when the number
    is no such setting (`_SWITCH_NUMBERS`; a decimal point's trailing zeros are the same)."""
    text = word.text
    if "." in text:
        text = text.rstrip("0")
    return _SWITCH_NUMBERS[word.letter].get(text)


def _switch_found(word: Word | None) -> str:
    """What a refused G05.1 or G08 block gave instead of its setting, for the message."""
    if word is None:
        return ""
    whole, dot, fraction = word.text.partition(".")
    if dot and whole in ("0", "1") and not fraction.strip("0"):  # G08 P1.
        return (f", got {brief(word.key)}: a FANUC control takes no decimal point in {word.letter} "
                f"here (write {word.letter}{whole})")
    return f", got {brief(word.key)}"


def _setting(block: Block, name: str, word: Word) -> str:
    """The state a smoothing setting's block (`NON_MOVING`) is noted as, its words checked:
    G05 P10000/P0, G05.1 Q1/Q0 (R level), G08 P1/P0, G103 P0..P15 or alone, G187 P1..P3
    and E or alone."""
    single = block.single
    words = {"G05": "P", "G05.1": "QR", "G08": "P", "G103": "P", "G187": "PE"}[name]
    shown = {"G05": "with P10000 or P0", "G05.1": "with Q1 or Q0", "G08": "with P1 or P0",
             "G103": f"with P0..P{LOOK_AHEAD_BLOCKS} or nothing",
             "G187": "with P1..P3, E or nothing"}[name]
    # letters the block refused as unknown (an E outside G187) are not named again here
    extra = [w for w in block.words
             if w.letter not in "NG" + words and (w.letter in SINGLE or w.letter == "M")]
    if extra:
        raise block.fail(f"{name} stands in a block of its own ({shown}), found "
                         f"{brief(extra[0].key)}", extra[0])
    if name == "G103":
        return _level(block, name, single.get("P"), range(LOOK_AHEAD_BLOCKS + 1),
                      "the most blocks the control looks ahead (0: no limit)")
    if name == "G187":
        key = _level(block, name, single.get("P"), SMOOTHNESS_LEVELS,
                     "the smoothness level (1 rough, 2 medium, 3 finish)")
        rounding = single.get("E")
        if rounding is not None:
            if rounding.text.startswith("-"):
                raise block.fail(f"G187's E is the maximum corner rounding, a distance >= 0, "
                                 f"got {brief(rounding.key)}", rounding)
            block.real(rounding)
            key += f" E{rounding.text.lstrip('+')}"
        return key
    if name == "G05":
        given = single.get("P")
        number = None if given is None else integer(given)
        if number not in G05_SETTINGS:
            found = "no P" if given is None else brief(given.key)
            raise block.fail(
                f"G05 is read as FANUC's high-precision contour control, P10000 (on) or P0 "
                f"(off), got {found}: its other P numbers run high-speed cycle (P1) or "
                "binary (P3) operation, whose path is data stored in the control, not in "
                "this program; post the path as blocks", word if given is None else given)
        return f"G05 P{number}"
    letter = "Q" if name == "G05.1" else "P"
    given = single.get(letter)
    setting = None if given is None else _switch(given)
    if setting is None:
        raise block.fail(f"{name} needs {letter}1 (on) or {letter}0 (off)"
                         f"{_switch_found(given)}", word)
    key = f"{name} {letter}{setting}"
    if "R" in single:
        block.integer(single["R"], "AI contour precision level")
        key += f" {brief(single['R'].key)}"
    return key


def _level(block: Block, name: str, given: Word | None, levels, what: str) -> str:
    """``name`` with its P (``"G103 P1"``), or ``name`` alone when no P is given; a P outside
    ``levels`` or with a decimal point (a Haas takes whole numbers there) is refused."""
    if given is None:
        return name
    number = integer(given)
    if number is None or number not in levels:
        whole, dot, fraction = given.text.partition(".")
        hint = (f" (write P{whole}: a Haas takes a whole number here)"
                if dot and whole.isdigit() and len(whole) <= 2 and not fraction.strip("0")
                and int(whole) in levels else "")
        raise block.fail(f"{name}'s P is {what}, P{levels[0]}..P{levels[-1]}, got "
                         f"{brief(given.key)}{hint}", given)
    return f"{name} P{number}"


#: The words of a dwell time, as the refusals of a G04 block name them (`Block.dwell_p`).
DWELL_WORDS = ("P<milliseconds> (with a decimal point, P<seconds>, as Haas reads it) or "
               "X<seconds>")


def read_dwell(block: Block, g04: Word, axes: list[Word], block_number: int | None) -> None:
    """The G04 ``block``: one dwell at the current position, of P (`Block.dwell_p`) or of X
    (s; without a point, the integer-input rule's unit of time)."""
    single = block.single
    for word in axes:
        if word.letter != "X":
            raise block.fail(f"axis word {word.letter} in a dwell block; G04 takes only "
                             f"{DWELL_WORDS}", word)
    if "P" in single and "X" in single:
        raise block.fail("G04 takes one dwell time, got both P and X", single["X"])
    if "P" in single:
        dwell_s = block.dwell_p(single["P"], "G04")
    elif "X" in single:
        word = single["X"]
        block.reader.dwell_words[block.line] = word.key
        dwell_s = block.real(word)
        if block.increment is not None and "." not in word.text:
            dwell_s *= DWELL_INCREMENT_S[block.reader.integer_input]
        if dwell_s < 0.0:
            raise block.fail(f"dwell time must be >= 0, got {brief(word.key)}", word)
        dwell_s = block.dwell_within(dwell_s, word, "G04")
    else:
        raise block.fail(f"dwell without time: G04 needs {DWELL_WORDS}", g04)
    block.add("dwell", dwell_s, block_number)


def read_one_shot(block: Block, code: tuple[str, Word], axes: list[Word],
                  block_number: int | None) -> None:
    """The ``block`` of the one-shot G ``code`` (G28, G53, or a setting: G05, G05.1, G08, G103,
    G187): its rapids, or its setting noted as a state (`Program.states`)."""
    name, word = code
    state, single = block.state, block.single
    if name in NON_MOVING:
        block.reader.note(_setting(block, name, word), block.line)
        return
    if not axes and name == "G28":
        # a bare G28, as hand-written Haas programs start: controls differ
        raise block.fail("G28 without axis words: a Haas control returns every axis to "
                         "machine zero, a FANUC moves none; name the axes it moves, Z "
                         "first to clear the part: G28 G91 Z0, then G28 G91 X0 Y0 (and "
                         "G90 after)", word)
    if not axes:
        raise block.fail(f"{name} needs the axes it moves, e.g. {name} G91 Z0", word)
    if name == "G53":
        if state.incremental:
            raise block.fail("G53 moves to machine coordinates, which are absolute; found "
                             "under G91", word)
        for axis in axes:
            state.target[axis.letter] = block.machine(axis, machine_coordinates=True)
        units_free = block.units_free(axes)
        if "Z" in single:  # a machine position: every control's Z is the same again
            state.length_change = None
            state.length_cancelled = block.line  # and the offset vector on Z is cancelled
        block.add("rapid", 0.0, block_number, units_free=units_free)
        return
    # G28: through the intermediate point to the reference position of these axes (the
    # reader's `reference`, machine zero where it gives none).
    # An incremental 0 on an axis whose position is not known yet (the CAM header's
    # G28 G91 Z0) is the current position whatever it is: no intermediate move there.
    units_free = block.units_free(axes)
    here = [a for a in axes if not (state.incremental and a.letter not in state.target
                                    and block.real(a) == 0.0)]
    if here:
        state.target.update({axis.letter: block.machine(axis) for axis in here})
        block.add("rapid", 0.0, block_number, units_free=units_free)
    for axis in axes:
        state.target[axis.letter] = block.reader.reference.get(axis.letter, 0.0)
    if "Z" in single:  # at the reference, every control's Z is the same again
        state.length_change = None
        state.length_cancelled = block.line  # and the offset vector on Z is cancelled
    block.add("rapid", 0.0, block_number, units_free=units_free)

