"""A tool length change (G43/G44 H, G49) that waits for a Z to carry it.

FANUC by default (parameter 5006#6 TOS = 0) moves Z by the change in the G43/G44/G49 block
itself (after G28 Z or G53 Z, which cancel the offset on Z, a change from 0); LinuxCNC, and
controls that shift coordinates, carry it with the next absolute Z only
(docs/nc.md, "Tool table"), as machinesim's reader does. Until an absolute Z (or G28 Z,
G53 Z, a cycle's absolute R and Z) carries the change, the two readings put what follows
the change apart in Z, so it is refused, naming the line of the change and the difference:
an incremental Z (or a G91 cycle's R or Z), whose end differs, and a G90 move without Z,
which runs at the new height on a FANUC and at the old one here. The fix is to give Z in
the block of the change (``G43 H1 Z5.``), as CAM posts write it.

Internal to the reader: a block (`machinesim.nc.blocks.Block`) notes the change
(`note_length_change`) and checks its moves against it (`check_length_carried`); the Z
words that carry it clear ``state.length_change`` where they are read.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from machinesim.exceptions import brief

if TYPE_CHECKING:
    from machinesim.nc.blocks import Block
    from machinesim.nc.lexer import Word

__all__ = ["check_length_carried", "note_length_change"]


def note_length_change(block: Block, length_before: float) -> None:
    """After ``block``'s G43/G44/G49 and H words: the change of the tool length offset from
    ``length_before`` (m) waits for a Z, unless it returns to the length a Z last carried."""
    state = block.state
    length_after = block.reader.tool_length()
    if state.length_change is None and state.length_cancelled:
        # G28 Z or G53 Z cancelled the offset on Z (FANUC B-63844EN/02, 14.1.2): a G43, G44,
        # G49 or H of this block changes it from 0, so a post's G49 after its G28 G91 Z0.
        # changes nothing (it had been refused as a change of the whole length), and a
        # G43 H1 there lifts Z by H1's length on a FANUC
        if "tool length" not in block.g_codes and "H" not in block.single:
            return
        length_before = 0.0
    if length_after == length_before:
        return
    words = "G49" if state.length_mode == "G49" else f"{state.length_mode} H{state.h}"
    carried = length_before if state.length_change is None else state.length_change[2]
    state.length_change = None if length_after == carried else (block.line, words, carried)


def check_length_carried(block: Block, word: Word | None, axes: list[Word] = ()) -> None:
    """Refuse an incremental Z (or a G91 cycle's R: ``word``) while a tool length change
    waits for an absolute Z, and a G90 move without Z (``axes``, ``word`` None) then."""
    state = block.state
    length = block.reader.tool_length()
    if (state.length_cancelled and word is not None and state.incremental
            and length != 0.0):
        raise block.fail(
            f"incremental {brief(word.key)} after the G28 Z or G53 Z at line "
            f"{state.length_cancelled}, which cancelled the tool length offset on Z while "
            f"{state.length_mode} H{state.h} ({length * 1e3:.6g} mm) stayed modal: a FANUC "
            "restores the offset with this move and ends it that much apart from a control "
            "that kept it; give an absolute Z after the reference return (G90 Z..) before "
            "incremental moves along Z", word)
    change = state.length_change
    if change is None:
        return
    line, words, carried = change
    delta = block.reader.tool_length() - carried
    if word is None and axes and not state.incremental and "Z" in state.target:
        side = "higher" if delta > 0.0 else "lower"  # Z targets carry + the length
        raise block.fail(
            f"{brief(axes[0].key)} moves without Z after {words} at line {line}, which changed the "
            f"tool length offset by {delta * 1e3:+.6g} mm, before any Z: FANUC by default "
            "(parameter 5006#6 TOS = 0) moves Z by the change in that block, so this move "
            f"runs there {abs(delta) * 1e3:.6g} mm {side} than here, where (as on LinuxCNC) "
            f"nothing moves until the next Z; give Z in the block of the change (e.g. G90 "
            f"{words} Z5.) or before this move", axes[0])
    if word is None or not state.incremental:
        return
    raise block.fail(
        f"incremental {brief(word.key)} after {words} at line {line}, which changed the tool "
        f"length offset by {delta * 1e3:+.6g} mm, before any absolute Z: controls differ "
        f"on where it ends, {abs(delta) * 1e3:.6g} mm apart (FANUC by default, parameter "
        "5006#6 TOS = 0, moves Z by the change in that block; LinuxCNC, or a control that "
        "shifts coordinates, carries it with the next absolute Z); give an absolute Z "
        "with or after the change (G90 G43 Z.. H..) before incremental moves along Z",
        word)
