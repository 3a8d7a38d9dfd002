"""A canned-cycle block (G73, G81, G82, G83): its words, its pecks, its moves.

Internal to the reader: a block (`machinesim.nc.blocks.Block`) with X Y Z R or a rotary
axis under a canned cycle reads here (`read_cycle`), keeping the cycle's R plane, hole bottom, peck
(Q, or Haas's variable peck I J K: `variable_peck`; with G73's Q, Haas's K of depth between
returns to R: `return_depth`) and dwell P in the modal state until
G80 or a motion code; the steps of one hole come from `machinesim.nc.cycles`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from machinesim.exceptions import NCProgramError, brief
from machinesim.nc.cycles import drill_steps
from machinesim.nc.length import check_length_carried
from machinesim.nc.words import MAX_MOVES

if TYPE_CHECKING:
    from machinesim.nc.blocks import Block
    from machinesim.nc.lexer import Word

__all__ = ["HOLE_WORDS", "PECKING", "read_cycle", "return_depth", "variable_peck"]

#: The words that make a block under a canned cycle a hole: its position in X Y and the
#: rotary axes (FANUC's lathe manual drills `G83 Z-40.0 R-5.0 ...` then `C90.0`, `C180.0`
#: as holes 2 and 3; Haas positions "X and Y axes (and optional A)"), its bottom Z, its R.
HOLE_WORDS = "XYZRABC"

#: The peck drilling cycles, which take Q or Haas's I J K, and a P of their own.
PECKING = ("G73", "G83")


def read_cycle(block: Block, axes: list[Word], block_number: int | None) -> None:
    """The canned-cycle ``block``: its R Z Q P K (or I J K) kept in the modal state, its
    hole (each of K repeats) added to the reader's moves."""
    state, single = block.state, block.single
    cycle_word = block.g_codes.get("canned cycle", (None, next(iter(block.words))))[1]
    check_length_carried(block, single.get("R") or single.get("Z"))
    if "R" in single:
        r = block.real(single["R"]) * block.length_of(single["R"])
        if state.incremental:
            r += state.initial_z
        else:
            r += block.offsets.get(state.work_offset, {}).get("Z", 0.0)
            r += block.reader.tool_length()
        state.cycle_r = block.finite(r, single["R"])
    if "Z" in single:
        z = block.real(single["Z"]) * block.length_of(single["Z"])
        if state.incremental:
            if state.cycle_r is None:
                raise block.fail("an incremental hole depth Z counts from the R plane; "
                                 "give R first", single["Z"])
            z += state.cycle_r
        else:
            z += block.offsets.get(state.work_offset, {}).get("Z", 0.0)
            z += block.reader.tool_length()
            state.length_change = None  # the hole's R and Z carry it
            state.length_cancelled = None
        state.cycle_z = block.finite(z, single["Z"])
    if "Q" in single:
        state.cycle_q = abs(block.real(single["Q"]) * block.length_of(single["Q"]))
        state.cycle_pecks = None
        state.cycle_return = None  # a Q without Haas's K. drills without its returns to R
    if "P" in single:
        state.cycle_p = block.dwell_p(single["P"], state.cycle)
        state.cycle_p_word = f"{brief(single['P'].key)} of line {block.line}"
        # Haas's G73/G83 dwell it after the last peck; one kept from a G82 does not
        # make them dwell (FANUC's sequences, docs/nc.md)
        state.peck_dwell = state.cycle in PECKING
    if state.cycle in PECKING and ("I" in single or "J" in single):
        state.cycle_pecks = variable_peck(block)
        state.cycle_q = state.cycle_return = None
        repeats = 1  # K is the smallest peck here
    elif "K" in single and "." in single["K"].text:
        state.cycle_return = return_depth(block)
        repeats = 1  # K is a depth here
    else:
        repeats = block.integer(single["K"], "repeat count") if "K" in single else 1
    if state.cycle_z is None or state.cycle_r is None:
        raise block.fail(f"{state.cycle} needs the hole bottom Z and the R plane R",
                         cycle_word)
    given = state.cycle_given
    given.update({k: (state.incremental, block.line) for k in "RZ" if k in single})
    stale = [k for k in "RZ" if given.get(k, (state.incremental,))[0] != state.incremental]
    if stale:
        mode = "G91" if state.incremental else "G90"
        earlier = " and ".join(f"{k} (line {given[k][1]})" for k in stale)
        raise block.fail(
            f"{state.cycle} repeated in {mode} with {earlier} given in "
            f"{'G90' if mode == 'G91' else 'G91'}: controls differ on what a kept R or Z "
            "means in the new distance mode (LinuxCNC reads the number again in it); "
            f"restate {' and '.join(stale)} after changing G90/G91",
            cycle_word)
    return_z = state.initial_z if state.retract == "G98" else state.cycle_r
    try:
        dwell_s = state.cycle_p if state.peck_dwell or state.cycle == "G82" else 0.0
        if dwell_s > 0.0 and "P" not in single:
            _note_kept_p(block, dwell_s)
        steps = drill_steps(state.cycle, r_z=state.cycle_r, bottom_z=state.cycle_z,
                            return_z=return_z, peck=state.cycle_q,
                            variable_peck=state.cycle_pecks, dwell_s=dwell_s,
                            return_every=state.cycle_return,
                            max_steps=MAX_MOVES - block.reader.out.count)
    except NCProgramError as error:
        word = next((single[k] for k in "ZRQIK" if k in single), cycle_word)
        raise block.fail(str(error), word) from None
    if repeats:  # K0 keeps the cycle's data and drills nothing: no feed move to refuse
        block.check_feed(state.cycle, cycle_word)
    block.reserve(repeats * (len(steps) + 1), cycle_word)
    # the hole's position: X Y and the rotary axes, as FANUC's `C90.0` in G83 mode drills a
    # hole at C90 and Haas positions A with X Y (a rotary word alone had turned the axis
    # and drilled nothing; beside X or Y it had been refused)
    position = [w for w in axes if w.letter != "Z"]
    for _ in range(repeats):
        if position or repeats > 1:
            state.target.update({w.letter: block.machine(w) for w in position})
        block.add("rapid", 0.0, block_number)
        for kind, value in steps:
            if kind == "dwell":
                block.add("dwell", value, block_number)
            else:
                state.target["Z"] = value
                block.add(kind, 0.0, block_number)


def _note_kept_p(block: Block, dwell_s: float) -> None:
    """Name, for the dwell note of ``block``'s line (`Program.dwell_words`), the P kept from
    an earlier block that its hole dwells: ``"P5000000 of line 3"``. A line read more than
    once (a subprogram) under other kept Ps names the one of its longest dwell, the dwell
    the note is about."""
    reader, line = block.reader, block.line
    if dwell_s > reader.kept_dwells.get(line, 0.0):
        reader.kept_dwells[line] = dwell_s
        reader.dwell_words[line] = block.state.cycle_p_word


def return_depth(block: Block) -> float:
    """Haas's K of a G73 with Q, m: a K with a decimal point, a length, after which the drill
    goes back to the R plane ("the tool is returned to the R plane after a number of passes
    totals up to the K amount": Haas Mill Operator's Manual 96-8000, G73). Refused in any
    other cycle, where K is the repeat count (an integer) or, beside I and J, the smallest
    peck."""
    state, word = block.state, block.single["K"]
    if state.cycle != "G73" or state.cycle_q is None:
        where = "G73 without a peck Q" if state.cycle == "G73" else state.cycle
        raise block.fail(
            f"{brief(word.key)} has a decimal point, so it is no repeat count (FANUC's K, an "
            f"integer: K2); a length K is read only in G73 with Q (Haas: back to the R plane after "
            f"pecks adding up to K) and in G73/G83 beside I and J (the smallest peck), not in "
            f"{where}", word)
    value = block.finite(block.real(word) * block.length_of(word), word)
    if not value > 0.0:
        raise block.fail(f"G73's K with Q (Haas's depth drilled between returns to the R "
                         f"plane) must be > 0, got {brief(word.key)}", word)
    return value


def variable_peck(block: Block) -> tuple[float, float, float]:
    """Haas's variable peck of a G73 or G83 block, its I J K in m: given together, each
    > 0, K at most I, and no Q beside them."""
    single, cycle = block.single, block.state.cycle
    missing = [k for k in "IJK" if k not in single]
    word = single.get("I") or single["J"]
    if missing:
        raise block.fail(f"{cycle}'s variable peck takes I (first peck), J (reduction per "
                         f"peck) and K (smallest peck) together (Haas); {' and '.join(missing)}"
                         " missing", word)
    if "Q" in single:
        raise block.fail(f"{cycle} takes a peck Q or I J K (Haas's variable peck), not both",
                         single["Q"])
    values = []
    for letter in "IJK":
        value = block.finite(block.real(single[letter]) * block.length_of(single[letter]),
                             single[letter])
        if not value > 0.0:
            raise block.fail(f"{cycle}'s {letter} must be > 0 (a length: Haas's I J K are "
                             f"always positive), got {brief(single[letter].key)}", single[letter])
        values.append(value)
    if values[2] > values[0]:
        raise block.fail(f"{cycle}'s smallest peck K ({brief(single['K'].key)}) is larger than its "
                         f"first peck I ({brief(single['I'].key)}); expected K <= I", single["K"])
    return values[0], values[1], values[2]
