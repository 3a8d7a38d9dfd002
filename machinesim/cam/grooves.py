"""Paper 002's first workpiece as CAM prepares it: the crossing grooves (section 3.1).

Four grooves 3 um deep and 1 mm long from a common point, cut at C = 0, 90, 180, 270 deg
(`groove_program`) with a R2.0 round-nose diamond tool on `robonano_a0ib` (Table 1), on a
block (`GROOVE_STOCK`) that carries three R2 mm reference spheres (ball-end-milled
cavities) for the setting identification (`machinesim.identification.workpiece_setting`);
`groove_rapids_crash` says whether the program's rapids meet a block set as a lab's robot
landed it. The program is written for the ideal workpiece; the tool cuts along its own +X
(docs/machines.md). The feed and the heights of the tool's approach and rapids are those of
the crown's programs too (`machinesim.cam.crown`, which imports them from here). Nothing
here cuts or measures: `machinesim.procedures.workpiece_setting` does.
"""

from __future__ import annotations

import math

import numpy as np

from machinesim.exceptions import InputError
from machinesim.identification.workpiece_setting import ReferenceSpheres
from machinesim.metrology._arrays import as_number
from machinesim.nc import Program, ProgramBuilder
from machinesim.realism import SphereArtefacts
from machinesim.rotations import rotation_xyz
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = ["CLEARANCE", "FEED_MM_PER_MIN", "GROOVE_BLANK", "GROOVE_ROI", "GROOVE_SPHERE_DESIGN",
           "GROOVE_SPHERES", "GROOVE_STOCK", "GROOVE_THICKNESS", "SAFE_Z", "groove_program",
           "groove_rapids_crash"]

MM, UM = M_PER_MM, M_PER_UM
#: Table 1 and 2: feed 20 (printed "mm/rev" for a tool that does not turn: read mm/min).
FEED_MM_PER_MIN = 20.0
#: Heights above a pass's start where the tool arrives (rapid) and leaves (feed), and the
#: height of rotary moves, m. 60 um clears the 10 um stock allowance plus setting errors of
#: 50 um; rapids stay above the stock, so the engine never needs to check them against it.
CLEARANCE, SAFE_Z = 60 * UM, 0.5 * MM

#: The groove workpiece: a 20 x 20 x 3 mm block centred on C with three R2 mm sphere
#: cavities 4 mm in from its edges (`workpiece.block_with_spheres`, dimples).
GROOVE_STOCK = "spheres:20x20x3:2:dimples@-10,-10,0"
#: Its thickness, m: the deepest `groove_program` may cut is short of it.
GROOVE_THICKNESS = 3 * MM
#: The same block without its spheres (`machinesim.Lab.make_artefacts` cuts them).
GROOVE_BLANK = "block:20x20x3@-10,-10,0"
GROOVE_SPHERES = ReferenceSpheres(np.array([[-6.0, -6.0, 0.0], [6.0, -6.0, 0.0],
                                            [-6.0, 6.0, 0.0]]) * MM, 2.0 * MM)
#: The same as a design for `machinesim.Lab.make_artefacts`.
GROOVE_SPHERE_DESIGN = SphereArtefacts(GROOVE_SPHERES.centres, GROOVE_SPHERES.radius)
#: The grooves are cut and read inside this window (xmin, xmax, ymin, ymax), m.
GROOVE_ROI = ((-1.5 * MM, 1.5 * MM, -1.5 * MM, 1.5 * MM),)


def groove_program(depth: float = 3 * UM, length: float = 1 * MM,
                   feed_mm_per_min: float = FEED_MM_PER_MIN) -> Program:
    """Four grooves from the C centre, one at each of C = 0, 90, 180, 270 deg (Fig. 7).

    Each groove: rapid above the crossing point, plunge to ``-depth`` at the feed (the edge
    plunging cuts nothing), feed ``length`` along the tool's +X, leave upwards at the feed.
    ``depth`` lies between 0 and the thickness of `GROOVE_STOCK` (3 mm), ``length`` > 0 (m).
    """
    # a negative depth made grooves in the air over the block, silently (Z = +3 um), one
    # of 3 mm or more cut through it, a negative length ran the grooves back along -X
    depth = as_number(depth, "depth", sign="> 0")
    if not depth < GROOVE_THICKNESS:
        raise InputError(f"Expected depth below the groove block's thickness "
                         f"{GROOVE_THICKNESS:g} m (GROOVE_STOCK {GROOVE_STOCK!r}), got "
                         f"{depth!r} m", key="depth")
    length = as_number(length, "length", sign="> 0")
    b = ProgramBuilder(2, source="workpiece_setting grooves")
    b.rapid(X=0.0, Y=0.0, Z=SAFE_Z, B=0.0, C=0.0)
    for k in range(4):
        b.rapid(C=math.radians(90.0 * k)).rapid(Z=CLEARANCE)
        b.linear(Z=-depth, feed_mm_per_min=feed_mm_per_min)
        b.linear(X=length).linear(Z=CLEARANCE).rapid(Z=SAFE_Z).rapid(X=0.0)
    return b.build()


def groove_rapids_crash(setting, length: float = 1 * MM) -> str | None:
    """Whether `groove_program`'s rapids run into the block of a workpiece set by
    ``setting`` (a `WorkpieceSetting`, as a lab's robot landed it): what they meet, or None.

    The program comes down at rapid to `CLEARANCE` over the crossing and turns C and
    returns along X at `SAFE_Z`, over the grooves' ``length``; the block's top (z = 0 as
    designed) stands at ``delta_z + R[2, :2] . (x, y)`` there, highest on the circle of
    radius ``length`` about the crossing. (The tool's nose rises faster than any tilt a
    probed setting can have, so its tip is what meets the block first; the C centre's
    offset, micrometres across, is left out.)
    """
    rotation = rotation_xyz(setting.alpha, setting.beta, setting.gamma)
    height = float(setting.delta[2])
    highest = height + math.hypot(rotation[2, 0], rotation[2, 1]) * length
    if height >= CLEARANCE:
        return (f"its top stands {height / UM:.1f} um high at the crossing, where the groove "
                f"program comes down at rapid to {CLEARANCE / UM:.0f} um (CLEARANCE)")
    if highest >= SAFE_Z:
        return (f"its top stands up to {highest / UM:.1f} um high within {length / MM:g} mm "
                f"of the crossing, where the groove program turns C and returns at "
                f"{SAFE_Z / UM:.0f} um (SAFE_Z)")
    return None
