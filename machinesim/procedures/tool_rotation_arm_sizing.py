"""Paper 000's tool and the sizes its plan and pattern need: how deep a ramp may go with the
holder above the stock (`holder_depth`, `max_capture`) and what block and rapid clearance the
uncompensated prism pattern needs for an edge offset within the plan's capture
(`deepest_before`, `pattern_height`, `pattern_clearance`, `check_pattern_fits`).

The procedure that uses them is `machinesim.procedures.tool_rotation_arm` (which re-exports
them); docs/procedures/tool_rotation_arm.md gives the geometry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from machinesim.cam.prisms import APPROACH_MARGIN_M, SEARCH_MARGIN_M, CalibrationPlan, PrismPattern
from machinesim.exceptions import InputError, brief
from machinesim.experiment import check_instance
from machinesim.tools import VTool
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = [
    "PATTERN_FLOOR_M", "PLAN_EXPECTED", "PRISM_FLANK_M", "TOOL", "check_pattern_fits",
    "deepest_before", "holder_depth", "max_capture", "pattern_clearance", "pattern_height",
]

#: Height of the prism's flanks (m): the tool's V reaches 3 mm from its edge (6 mm across),
#: a shank goes on up to the holder at 10 mm. Flanks drawn to the full 10 mm (20 mm across)
#: put, at the 40 deg ramp, the far flank 5 deg from the surface and its top, where the
#: holder begins, under the stock once the edge is 0.3 mm deep: inside the plan's 1 mm
#: capture, a crash the cutter refuses (`HolderContactError`) that a real prism never
#: makes. Every groove the procedure reads lies within 3 mm of the edge, so it is the same.
PRISM_FLANK_M = 3.0 * M_PER_MM
#: The tool of paper 000: a 90-deg V (prism) tool.
TOOL = VTool(math.pi / 2, flank_height=PRISM_FLANK_M)


#: What a plan argument must be (`max_capture`, `ToolRotationArm`).
PLAN_EXPECTED = "a CalibrationPlan (machinesim.cam.prisms), e.g. CalibrationPlan()"
#: Stock kept under the uncompensated pattern's deepest groove (m) in the block
#: `ToolRotationArm` sizes for it (`pattern_height`): the default plan's 1 mm capture cuts
#: down to 0.357 mm, which the default 0.5 mm block holds with this to spare.
PATTERN_FLOOR_M = 0.1 * M_PER_MM


def holder_depth(angles: Sequence[float], tool=TOOL) -> float:
    """Deepest (m) the edge may go below the stock's top at every one of ``angles`` (tool
    angles, rad) with the top of ``tool``'s body, where its holder begins, still above it.

    A corner (y, h) of the body's top, turned by A = t about +X, stands y sin t + h cos t
    over the edge; the least of those over the corners and the angles. `TOOL` (corners at
    y = +-3 mm, h = 10 mm) at 0-40 deg: 10 cos 40 - 3 sin 40 = 5.732 mm, at 40 deg.
    """
    angles_given = angles
    try:
        angles = [float(t) for t in angles]
    except (TypeError, ValueError):
        angles = None
    if not angles or not all(map(math.isfinite, angles)):
        raise InputError(f"expected one or more tool angles (finite numbers, rad), got "
                         f"{brief(repr(angles_given))}", key="angles")
    points = np.asarray(tool.vertices())
    top = points[points[:, 2] == points[:, 2].max()]
    return float(min((top[:, 1] * math.sin(t) + top[:, 2] * math.cos(t)).min()
                     for t in angles))


def max_capture(plan: CalibrationPlan | None = None, tool=TOOL) -> float:
    """Largest capture range (m) that ``plan``'s ramps (its angles and stations, the search
    range derived from the capture) can have and ``tool`` still cut for every edge offset
    within it with its holder above the stock.

    A ramp's programmed edge goes down to ``search = capture + deepest station +
    SEARCH_MARGIN_M`` below the surface, and an offset of length ``capture`` can put the
    real edge up to ``capture`` lower at any angle (the offset vector turned by it), so
    ``2 capture + deepest station + SEARCH_MARGIN_M <= holder_depth``. The default plan
    and `TOOL`: (5.7321 - 0.0160 - 0.0200) / 2 = 2.848 mm. ``plan.capture`` is not used;
    None is the default plan.
    """
    plan = CalibrationPlan() if plan is None else plan
    check_instance(plan, CalibrationPlan, "plan", PLAN_EXPECTED)
    return 0.5 * (holder_depth(plan.angles, tool) - max(plan.station_depths)
                  - SEARCH_MARGIN_M)


def deepest_before(plan: CalibrationPlan, pattern: PrismPattern) -> tuple[float, float]:
    """How deep (m) the uncompensated ``pattern`` may cut below its block's top, for an edge
    offset within ``plan.capture``, and the tool angle (rad) where it does.

    Touched off at 0 deg (`touch_off`), the edge at angle t stands eq 1's rise from 0 deg,
    ``(r - r0) (1 - cos t) + e_ys sin t``, above where the program puts it: the offset
    vector (r - r0, e_ys) dotted with (1 - cos t, sin t), of length 2 sin(|t| / 2); over
    offsets of length up to the capture c its least value is ``-2 c sin(|t| / 2)``, the
    groove that much deeper than programmed, at the pattern's largest |t|. The default plan
    and pattern: 10 um + 1 mm x 2 sin 10 deg = 0.357 mm at 20 deg.
    """
    angle = max(pattern.angles, key=abs)
    return pattern.depth + 2.0 * plan.capture * math.sin(abs(angle) / 2.0), angle


def pattern_height(plan: CalibrationPlan, pattern: PrismPattern) -> float:
    """Least thickness (m) of ``pattern``'s block that holds its uncompensated grooves for
    ``plan``'s capture (`deepest_before`) with `PATTERN_FLOOR_M` under them, rounded up to
    the micrometre: 0.458 mm for the default plan and pattern (their 0.5 mm block holds it),
    1.083 mm at a 2.8 mm capture."""
    deepest, _ = deepest_before(plan, pattern)
    return math.ceil(round((deepest + PATTERN_FLOOR_M) / M_PER_UM, 6)) * M_PER_UM


def pattern_clearance(plan: CalibrationPlan, pattern: PrismPattern) -> float:
    """Least rapid clearance (m) of ``pattern``'s program that keeps the edge
    `APPROACH_MARGIN_M` over its block's top when cut before compensation for an edge
    offset within ``plan``'s capture, rounded up to the micrometre.

    Touched off at 0 deg the edge at angle t stands up to ``2 c sin(|t| / 2)`` lower than
    programmed (`deepest_before`), rapids included: a rapid back over the block at the
    pattern's 1 mm sank to 10.9 um over its top at the largest capture (its own groove,
    0.999 mm deep, under it). 0.448 mm for the default plan (the pattern's 1 mm holds it),
    1.090 mm at the largest capture (2.848 mm).
    """
    deepest, _ = deepest_before(plan, pattern)
    return (math.ceil(round((deepest - pattern.depth + APPROACH_MARGIN_M) / M_PER_UM, 6))
            * M_PER_UM)


def check_pattern_fits(plan: CalibrationPlan, pattern: PrismPattern) -> None:
    """Refuse a ``pattern`` whose block is thinner than `pattern_height` or whose rapids
    are lower than `pattern_clearance` for ``plan``'s capture (`InputError`, key
    ``pattern``), the block first; each message gives the depth the uncompensated cut may
    reach (`deepest_before`), the size needed and what to give instead."""
    height = pattern_height(plan, pattern)
    clearance = pattern_clearance(plan, pattern)
    if pattern.height >= height and pattern.clearance >= clearance:
        return
    deepest, angle = deepest_before(plan, pattern)
    before = "and cut before compensation (the edge touched off at 0 deg)"
    offset = (f"at {math.degrees(angle):g} deg (2 x capture x sin(angle / 2)) for an edge "
              f"offset within the plan's capture {plan.capture:g} m")
    smaller = "or a smaller CalibrationPlan(capture=...)"
    if pattern.height < height:
        raise InputError(
            f"the pattern's block is {pattern.height:g} m thick (PrismPattern(height=...)), "
            f"{before} its grooves go down to {deepest:g} m: the depth {pattern.depth:g} m "
            f"and up to {deepest - pattern.depth:g} m more {offset}; expected a block at "
            f"least {height:g} m thick ({PATTERN_FLOOR_M:g} m of stock under the deepest "
            f"groove): give the pattern height={height:g} (PrismPattern(..., height=...)), or "
            f"no pattern (ToolRotationArm sizes the default's block), {smaller}",
            key="pattern")
    raise InputError(
        f"the pattern's rapids cross its block {pattern.clearance:g} m up "
        f"(PrismPattern(clearance=...)), {before} the edge sinks by up to "
        f"{deepest - pattern.depth:g} m {offset}; expected a clearance at least "
        f"{clearance:g} m ({APPROACH_MARGIN_M:g} m over the block's top): give the pattern "
        f"clearance={clearance:g}, or no pattern (ToolRotationArm sizes the default's), "
        f"{smaller}", key="pattern")
