"""Canned drilling cycles G73, G81, G82, G83 as the moves of one hole along the drilling axis.

FANUC's sequence (G17: drilling along Z): position in X Y at rapid, rapid down to the R
plane, feed to the bottom Z (G81), with a dwell P there (G82), or in pecks of Q (G83:
after each peck a rapid back to the R plane, then a rapid down to a clearance d above the
last depth, and feed on; G73, high-speed peck drilling for chip breaking: after each peck a
rapid back up by d only, and feed on); then a rapid back to the initial level (G98) or the
R plane (G99).

Haas's G73 and G83 also take a variable peck, I J K: the first peck I, each next one J
smaller, none smaller than K; and P, a dwell at the bottom after the last peck; Haas's G73
with both Q and K returns to the R plane whenever its pecks add up to K (Haas Mill
Operator's Manual 96-8000, G73 and G83).
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

#: Haas's G73 K (with Q) counts as reached this short of it, m: pecks of 0.1 mm add up to
#: 0.30000000000000004 mm, not 0.3, and far below any axis's resolution.
RETURN_SLACK_M = 1e-12

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
    variable_peck: tuple[float, float, float] | None = None,
    dwell_s: float = 0.0,
    return_every: float | None = None,
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
    variable_peck : (float, float, float), m, optional
        G73's and G83's variable peck instead of ``peck``, Haas's I J K: the first peck, the
        reduction of each next one, the smallest (each > 0).
    dwell_s : float, s
        G82's dwell at the bottom; G73's and G83's after the last peck (Haas's P).
    return_every : float, m, optional
        G73's K beside Q (Haas): once the pecks since R (or since the last return) add up to
        this much, the drill rapids back to the R plane and down to `PECK_CLEARANCE_M` above
        the depth, as G83's, instead of backing off by `CHIP_BREAK_RETRACT_M`.
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
        if variable_peck is not None:
            depths = _variable_pecks(cycle, r_z, bottom_z, variable_peck)
        else:
            depths = _pecks(cycle, r_z, bottom_z, peck)
        if max_steps is not None and 3 * len(depths) > max_steps:
            raise NCProgramError(f"{cycle} with {_peck_words(peck, variable_peck)} makes "
                                 f"{len(depths)} pecks, more than the {max_steps // 3} left; "
                                 f"raise {'Q' if variable_peck is None else 'I and K'}")
        top = r_z  # where the pecks since the last return to R began
        for k, depth in enumerate(depths):
            last = depths[k - 1] if k > 0 else r_z
            if k > 0 and (cycle == "G83" or (return_every is not None
                                             and top - last >= return_every - RETURN_SLACK_M)):
                steps.append(("rapid", r_z))
                steps.append(("rapid", min(last + PECK_CLEARANCE_M, r_z)))
                top = last
            elif k > 0:  # G73: back up by d, breaking the chip, and on
                steps.append(("rapid", min(last + CHIP_BREAK_RETRACT_M, r_z)))
            steps.append(("linear", depth))
        if dwell_s > 0.0:
            steps.append(("dwell", dwell_s))
    else:
        steps.append(("linear", bottom_z))
        if cycle == "G82" and dwell_s > 0.0:
            steps.append(("dwell", dwell_s))
    steps.append(("rapid", return_z))
    return steps


def _pecks(cycle: str, r_z: float, bottom_z: float, peck: float | None) -> list[float]:
    """Machine Z at the end of each peck of Q ``peck``, the last one at ``bottom_z``."""
    if peck is None or not peck > 0.0:
        raise NCProgramError(f"{cycle} needs a peck depth Q > 0 (or Haas's I J K)")
    count = (r_z - bottom_z) / peck  # inf for a depth of 1e305 m over a peck of 1e-304 m
    if not count <= MOST_PECKS:  # math.ceil(inf) had raised OverflowError
        raise NCProgramError(
            f"{cycle} with Q {peck * 1e3:.6g} mm makes "
            f"{math.ceil(count) if count < 1e15 else f'{count:.3g}'} pecks in one hole "
            f"({(r_z - bottom_z) * 1e3:.6g} mm from R to Z), more than {MOST_PECKS} (a "
            f"micro drill pecking 1 um at a time through 1 mm). Check Q "
            f"(a Q without a decimal point is read by --integer-input: 'increment' makes "
            f"Q1 1 nm)")
    pecks = math.ceil(count)
    depths = []
    for k in range(1, pecks + 1):
        depths.append(bottom_z if k == pecks else max(r_z - k * peck, bottom_z))
        if depths[-1] == bottom_z:
            break
    return depths


def _variable_pecks(cycle: str, r_z: float, bottom_z: float,
                    variable_peck: tuple[float, float, float]) -> list[float]:
    """Machine Z at the end of each of Haas's variable pecks: I first, each next one J less,
    none less than K; the last one at ``bottom_z``."""
    first, reduction, least = variable_peck
    depths: list[float] = []
    depth, size = r_z, first
    while depth > bottom_z:
        if len(depths) == MOST_PECKS:
            raise NCProgramError(
                f"{cycle} with {_peck_words(None, variable_peck)} makes more than "
                f"{MOST_PECKS} pecks in one hole "
                f"({(r_z - bottom_z) * 1e3:.6g} mm from R to Z; a micro drill pecking 1 um at "
                "a time through 1 mm makes 1000). Check K, the smallest peck (a K without a "
                "decimal point is read by --integer-input: 'increment' makes K1 1 nm)")
        depth = max(depth - size, bottom_z)
        depths.append(depth)
        size = max(size - reduction, least)
    return depths


def _peck_words(peck: float | None, variable_peck: tuple[float, float, float] | None) -> str:
    """The peck words as written, in mm: ``Q 0.5 mm`` or ``I 1 mm, J 0.2 mm and K 0.1 mm``."""
    if variable_peck is None:
        return f"Q {peck * 1e3:.6g} mm"
    first, reduction, least = (f"{value * 1e3:.6g} mm" for value in variable_peck)
    return f"I {first}, J {reduction} and K {least}"
