"""A tool length change (G43/G44 H, G49) in G90 without Z, followed by a move without Z.

FANUC by default (parameter 5006#6 TOS = 0) moves Z by the change in the G43/G44/G49 block
itself, so the X/Y moves after it run at the new height; LinuxCNC, and controls that shift
coordinates, carry it with the next Z only (docs/nc.md, "Tool table"), so they run at the
old one, as machinesim's reader had read them. The two put those moves the change apart in Z,
so such a move is refused with the line of the change and both heights, as an incremental
Z after the change is (`Block.check_length_carried`); the fix is to give Z in the block
of the change (``G43 H1 Z5.``), as CAM posts write it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from machinesim.nc.lexer import Word

__all__ = ["check_length_moved"]


def check_length_moved(block, word: Word, line: int, words: str, delta: float) -> None:
    """Refuse ``word`` (the first axis word of a G90 move without Z in ``block``) after the
    tool length change ``words`` at ``line`` (by ``delta``, m) that no Z has carried."""
    side = "higher" if delta > 0.0 else "lower"  # Z targets carry + the length
    raise block.fail(
        f"{word.key} moves without Z after {words} at line {line}, which changed the tool "
        f"length offset by {delta * 1e3:+.6g} mm, before any Z: FANUC by default (parameter "
        "5006#6 TOS = 0) moves Z by the change in that block, so this move runs there "
        f"{abs(delta) * 1e3:.6g} mm {side} than here, where (as on LinuxCNC) nothing moves "
        f"until the next Z; give Z in the block of the change (e.g. G90 {words} Z5.) or "
        "before this move", word)
