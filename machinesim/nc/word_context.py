"""Which of a block's P Q R I J K L words something reads, in the block's context.

Internal to the reader: `machinesim.nc.blocks.Block` calls `check_word_context` once its
codes are classified. A letter means different things by context (R an arc's radius, a
cycle's R plane, G05.1's switch; K an arc centre, a cycle's repeats; P a dwell, a program,
a level), and where nothing reads it, it is refused at the word, saying what reads it, rather
than read as nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from machinesim.nc.arcs import PLANES
from machinesim.nc.drilling import HOLE_WORDS, PECKING
from machinesim.nc.words import ARC, LOOK_AHEAD_BLOCKS

if TYPE_CHECKING:
    from machinesim.nc.blocks import Block

__all__ = ["check_word_context"]

#: M codes whose P is a call or a return elsewhere than M98 / M99 read, each refused so: the
#: P had been told it 'is only read with G04 ..., M98 (program)', and a Haas program's local
#: subprogram at N1000 then refused as blocks after M30 and an M99 in the main program.
CALLS = {
    99: "M99 P{p} returns to the block N{p} of the calling program, not to the block after "
        "its M98, and is not read: end the subprogram with M99 alone and put the blocks "
        "from N{p} on after the M98",
    97: "M97 P{p} (Haas's call of the local subprogram at N{p} of this program) is not read: "
        "write the subprogram as O{p} ... M99 after the main program's M30 and call it with "
        "M98 P{p}",
    198: "M198 P{p} calls a subprogram from an external device (FANUC's memory card or "
         "data server), which is not read: put O{p} ... M99 in this file after the main "
         "program's M30 and call it with M98 P{p}",
}


def check_word_context(block: Block, motion, one_shot) -> None:
    """Refuse the block's P Q R I J K L where nothing reads them: in its motion (``motion``:
    its motion code and word, or None), its one-shot code (``one_shot``) and the modal
    state, each letter with what reads it."""
    state, single = block.state, block.single
    if block.refused_cycle is not None:
        # the cycle's own words (R plane, P dwell, Q shift or peck, I J K, L repeats):
        # its refusal says what is wrong; "word R is only read with G02/G03 ..., G81-G83"
        # beside it had read as a second mistake in a block with one
        for letter in "PQRIJKL":
            single.pop(letter, None)
        return
    codes = {code for code, _ in block.m_codes}
    g04 = motion is not None and motion[0] == "G04"
    shot = None if one_shot is None else one_shot[0]
    cycle = state.cycle
    arc = state.motion in ARC and cycle is None and one_shot is None and not g04
    # the cycle reads its words in a block that drills (`read_cycle`): in a G28, G53 or
    # G04 block, or one without X Y Z R, they had been read as nothing (`Q0.2` alone)
    drills = (cycle is not None and one_shot is None and not g04
              and any(k in single for k in HOLE_WORDS))
    hole = cycle if drills else None
    plane_words = PLANES[state.plane][1]
    allowed = {
        # G81's P: kept as the cycle's dwell (a later G82 of the cycle dwells it), as
        # FANUC keeps every hole-machining word until G80; G81 itself does not dwell
        "P": (g04 or drills or 98 in codes
              or shot in ("G05", "G08", "G103", "G187")),
        "Q": hole in ("G73", "G83") or shot == "G05.1",
        "R": arc or drills or shot == "G05.1",
        "I": (arc and "I" in plane_words) or hole in PECKING,
        "J": (arc and "J" in plane_words) or hole in PECKING,
        "K": (arc and "K" in plane_words) or drills,
        "L": 98 in codes,
    }
    cycle_reads = {"P", "R", "K"} | ({"Q"} if cycle in ("G73", "G83") else set()) | (
        {"I", "J"} if cycle in PECKING else set())
    # each plane's own centre words: K in a G17 arc had been told it is read "with
    # G02/G03 in G17 (centre words I J)", where it is not
    centres = ("G02/G03 as an arc centre word of its plane ("
               + ", ".join(f"{name}: {' '.join(words)}" for name, (_, words) in PLANES.items())
               + f"; this block is in {state.plane})")
    reads = {
        "P": "G04 (dwell), G82, G73 and G83 (dwell at the bottom; G81 keeps it for a "
             "G82), each in ms, or s with a decimal point as Haas, G05 (P10000/P0), "
             "G08 (P1/P0), G103 "
             f"(P0..P{LOOK_AHEAD_BLOCKS}), G187 (P1..P3) and M98 (program)",
        "Q": "G73 and G83 (peck depth) and G05.1 (Q1/Q0)",
        "R": "G02/G03 (radius), G73 and G81-G83 (R plane) and G05.1",
        "I": f"{centres} and with G73 and G83 (Haas's first peck I, with J and K)",
        "J": f"{centres} and with G73 and G83 (Haas's peck reduction J, with I and K)",
        "K": f"{centres} and with G73 and G81-G83 (repeats; with G73 and G83 beside I "
             "and J, Haas's smallest peck; with G73's Q and a decimal point, Haas's depth "
             "between returns to R)",
        "L": "M98 (repeat count)" + (
            "; a canned cycle's repeat count is K here, as on current FANUC controls "
            "(older ones, and LinuxCNC, write L): write K" if cycle is not None else ""),
    }
    for letter, ok in allowed.items():
        if letter in single and not ok:
            call = next((c for c in CALLS if c in codes), None) if letter == "P" else None
            if call is not None:
                block.refuse(CALLS[call].format(p=single[letter].text), single[letter])
            elif cycle is not None and not drills and letter in cycle_reads:
                where = (f"a {shot or 'G04'} block" if shot or g04
                         else "a block without X, Y, Z, R or a rotary axis")
                block.refuse(f"word {letter} while the canned cycle {cycle} is active, in "
                            f"{where}, which drills no hole: {cycle} reads its "
                            f"{letter} in the block of a hole (with X, Y, Z, R or a "
                            "rotary axis), and "
                            f"here it would be read as nothing; give it in the block of "
                            "the hole it is for", single[letter])
            else:
                block.refuse(f"word {letter} is only read with {reads[letter]}",
                            single[letter])
            del single[letter]
