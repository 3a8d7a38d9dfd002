"""Canned drilling cycles G73, G81, G82, G83 as the moves of one hole along the drilling axis.

FANUC's sequence (G17: drilling along Z): position in X Y at rapid, rapid down to the R
plane, feed to the bottom Z (G81), with a dwell P there (G82), or in pecks of Q (G83:
after each peck a rapid back to the R plane, then a rapid down to a clearance d above the
last depth, and feed on; G73, high-speed peck drilling for chip breaking: after each peck a
rapid back up by d only, and feed on); then a rapid back to the initial level (G98) or the
R plane (G99).
"""

from __future__ import annotations

import math

from machinesim.exceptions import NCProgramError

#: The G83 clearance d above the previous peck's depth that the rapid down stops at, m. FANUC
#: sets it by a parameter (No. 5115); 0.1 mm keeps the rapid clear of the chips and the
#: hole's bottom (so it never counts as a rapid that cuts) at any peck depth.
PECK_CLEARANCE_M = 1e-4


#: The G73 retract d after each peck, m: FANUC sets it by a parameter (No. 5114), Haas by
#: setting 22. It moves the drill up and down within the hole it has drilled, so the part
#: is the same for any d; 0.1 mm, as `PECK_CLEARANCE_M`.
CHIP_BREAK_RETRACT_M = 1e-4

#: Most pecks of one G73 or G83 hole. A micro drill pecking 1 um at a time through 1 mm makes
#: 1000; more is a Q typed in the wrong unit, and each peck is a sweep to cut.
MOST_PECKS = 1000


def drill_steps(
    cycle: str,
    *,
    r_z: float,
    bottom_z: float,
    return_z: float,
    peck: float | None = None,
    dwell_s: float = 0.0,
    max_steps: int | None = None,
) -> list[tuple[str, float]]:
    """The Z moves of one hole after positioning, as ``(kind, value)`` pairs.

    Parameters
    ----------
    cycle : {"G73", "G81", "G82", "G83"}
    r_z, bottom_z, return_z : float, m
        Machine Z of the R plane, the hole bottom and the level to return to.
    peck : float, m
        G73's and G83's peck depth Q (> 0).
    dwell_s : float, s
        G82's dwell at the bottom.
    max_steps : int, optional
        Refuse a hole needing more moves than this.

    Returns
    -------
    list of (kind, value)
        ``("rapid", z)``, ``("linear", z)`` or ``("dwell", seconds)``.
    """
    if not bottom_z < r_z:
        raise NCProgramError(
            f"the hole bottom Z ({bottom_z * 1e3:.6g} mm, machine) is not below the R plane "
            f"({r_z * 1e3:.6g} mm); a drilling cycle goes down -Z from R to Z"
        )
    steps: list[tuple[str, float]] = [("rapid", r_z)]
    if cycle in ("G73", "G83"):
        if peck is None or not peck > 0.0:
            raise NCProgramError(f"{cycle} needs a peck depth Q > 0")
        pecks = math.ceil((r_z - bottom_z) / peck)
        if pecks > MOST_PECKS:
            raise NCProgramError(
                f"{cycle} with Q {peck * 1e3:.6g} mm makes {pecks} pecks in one hole "
                f"({(r_z - bottom_z) * 1e3:.6g} mm from R to Z), more than {MOST_PECKS} (a "
                f"micro drill pecking 1 um at a time through 1 mm). Check Q "
                f"(a Q without a decimal point is read by --integer-input: 'increment' makes "
                f"Q1 1 nm)")
        if max_steps is not None and 3 * pecks > max_steps:
            raise NCProgramError(f"{cycle} with Q {peck * 1e3:.6g} mm makes {pecks} pecks, "
                                 f"more than the {max_steps // 3} left; raise Q")
        depth = r_z
        for k in range(1, pecks + 1):
            if k > 1 and cycle == "G83":
                steps.append(("rapid", r_z))
                steps.append(("rapid", min(depth + PECK_CLEARANCE_M, r_z)))
            elif k > 1:  # G73: back up by d, breaking the chip, and on
                steps.append(("rapid", min(depth + CHIP_BREAK_RETRACT_M, r_z)))
            depth = bottom_z if k == pecks else max(r_z - k * peck, bottom_z)
            steps.append(("linear", depth))
            if depth == bottom_z:
                break
    else:
        steps.append(("linear", bottom_z))
        if cycle == "G82" and dwell_s > 0.0:
            steps.append(("dwell", dwell_s))
    steps.append(("rapid", return_z))
    return steps
