"""Paper 002's two workpieces as CAM prepares them: the crossing grooves and the diamond crown.

Both run on `robonano_a0ib` with a R2.0 round-nose diamond tool (Tables 1 and 2), on
workpieces that carry three R2 mm reference spheres (ball-end-milled cavities) for the
setting identification (`machinesim.identification.workpiece_setting`). Programs are
written for the ideal workpiece; the tool cuts along its own +X (docs/machines.md), so where
the paper feeds along Y the programs feed along X, with C turned to point the cut: nothing
else changes. Nothing here cuts or measures: `machinesim.procedures.workpiece_setting` does.

Grooves (section 3.1): four grooves 3 um deep and 1 mm long from a common point, cut at
C = 0, 90, 180, 270 deg (`groove_program`) on a block (`GROOVE_STOCK`).

Crown (section 3.2): the roughly machined crown (`workpiece.diamond_crown`, 10 um oversize,
here on a 20 x 20 mm base with the spheres in its flat, `crown_stock`) is finished with 1 um
layers (Table 2: 10 um in all, pitch feed 12.5 um): the top face by passes along X at C = 0,
each side face by passes down its slope (X and Z together) at C = k 45 deg (`crown_passes`,
`passes_program`). `crown_roi` gives the measuring windows and the passes that reach them;
`machining_time` the time of the finishing against cutting the crown out of the full prism
with the same passes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import manifold3d
import numpy as np

from machinesim import motion
from machinesim.arrays import frozen
from machinesim.exceptions import InputError
from machinesim.identification.workpiece_setting import ReferenceSpheres
from machinesim.nc import Program, ProgramBuilder
from machinesim.tolerances import SPHERE_CHORD_M
from machinesim.tools import RoundNoseTool, sphere_polygon
from machinesim.units import M_PER_MM, M_PER_UM
from machinesim.workpiece import Part, diamond_crown

__all__ = [
    "CLEARANCE", "CROWN", "CROWN_BASE", "CROWN_BASE_HEIGHT", "FEED_MM_PER_MIN", "GROOVE_ROI",
    "GROOVE_SPHERES", "GROOVE_STOCK", "PARK", "SAFE_Z", "CrownPlan", "PassGroup",
    "crown_design", "crown_passes", "crown_roi", "crown_spheres", "crown_stock", "crown_tool",
    "groove_program", "machining_time", "passes_program",
]

MM, UM = M_PER_MM, M_PER_UM
#: Table 1 and 2: feed 20 (printed "mm/rev" for a tool that does not turn: read mm/min).
FEED_MM_PER_MIN = 20.0
#: Heights above a pass's start where the tool arrives (rapid) and leaves (feed), and the
#: height of rotary moves, m. 60 um clears the 10 um stock allowance plus setting errors of
#: 50 um; rapids stay above the stock, so the engine never needs to check them against it.
CLEARANCE, SAFE_Z = 60 * UM, 0.5 * MM
#: Pass ends are moved along the pass by up to this (m, in air, golden-ratio sequence): the
#: material-removal engine slows down by orders of magnitude on unions of sweeps whose end
#: faces are coplanar but turned off the machine axes (measured: 25 passes at gamma = 1 mrad
#: 13 s and 1.3 M triangles, staggered 0.2 s); the cut is the same.
STAGGER = 5 * UM
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0

# ------------------------------------------------------------------------------ grooves

#: The groove workpiece: a 20 x 20 x 3 mm block centred on C with three R2 mm sphere
#: cavities 4 mm in from its edges (`workpiece.block_with_spheres`, dimples).
GROOVE_STOCK = "spheres:20x20x3:2:dimples@-10,-10,0"
GROOVE_SPHERES = ReferenceSpheres(np.array([[-6.0, -6.0, 0.0], [6.0, -6.0, 0.0],
                                            [-6.0, 6.0, 0.0]]) * MM, 2.0 * MM)
#: The grooves are cut and read inside this window (xmin, xmax, ymin, ymax), m.
GROOVE_ROI = ((-1.5 * MM, 1.5 * MM, -1.5 * MM, 1.5 * MM),)


def groove_program(depth: float = 3 * UM, length: float = 1 * MM,
                   feed_mm_per_min: float = FEED_MM_PER_MIN) -> Program:
    """Four grooves from the C centre, one at each of C = 0, 90, 180, 270 deg (Fig. 7).

    Each groove: rapid above the crossing point, plunge to ``-depth`` at the feed (the edge
    plunging cuts nothing), feed ``length`` along the tool's +X, leave upwards at the feed.
    """
    b = ProgramBuilder(2, source="workpiece_setting grooves")
    b.rapid(X=0.0, Y=0.0, Z=SAFE_Z, B=0.0, C=0.0)
    for k in range(4):
        b.rapid(C=math.radians(90.0 * k)).rapid(Z=CLEARANCE)
        b.linear(Z=-depth, feed_mm_per_min=feed_mm_per_min)
        b.linear(X=length).linear(Z=CLEARANCE).rapid(Z=SAFE_Z).rapid(X=0.0)
    return b.build()


# -------------------------------------------------------------------------------- crown


@dataclass(frozen=True)
class CrownPlan:
    """The designed crown and its finishing passes (Fig. 9, Table 2), m and rad.

    Attributes
    ----------
    apothem : float
        Half the top face's across-flats (`workpiece.diamond_crown`: 4 mm across).
    height : float
        Crown height above the flat.
    slope : float
        Side-face slope, rad (11.31 deg, tan = 0.2).
    oversize : float
        Stock allowance of the rough crown (Table 2: total depth 10 um).
    depth_of_cut, pitch : float
        Table 2: 1 um and 12.5 um.
    top_half : float
        Top passes run x in [-top_half, top_half] at y in the same range.
    side_half : float
        Side passes run across the face for v (along its edge) in [-side_half, side_half].
    prism_apothem : float
        The solid the crown is cut from in the comparison without rough machining: the
        octagonal prism standing on the crown's foot, its top at the rough top.
    """

    apothem: float = 2.0 * MM
    height: float = 0.2 * MM
    slope: float = math.atan(0.2)
    oversize: float = 10 * UM
    depth_of_cut: float = 1 * UM
    pitch: float = 12.5 * UM
    top_half: float = 2.3 * MM
    side_half: float = 1.25 * MM
    prism_apothem: float = 3.0 * MM

    @property
    def rough_top(self) -> float:
        """z of the rough top face, m."""
        return self.oversize

    @property
    def rough_flat(self) -> float:
        """z of the flat the crown stands on (left as roughed), m."""
        return -self.height + self.oversize

    @property
    def layers(self) -> int:
        """Finishing layers (Table 2: 10 um in 1 um cuts)."""
        return int(round(self.oversize / self.depth_of_cut))

    @property
    def foot_distance(self) -> float:
        """Designed distance between opposite foot edges of the finished crown, m."""
        return 2.0 * (self.apothem + (self.rough_top - self.oversize - self.rough_flat)
                      / math.tan(self.slope))


#: The crown of `workpiece.diamond_crown` and Table 2.
CROWN = CrownPlan()
#: Base of the crown workpiece (m): 20 mm square, 3 mm thick, room for the spheres.
CROWN_BASE, CROWN_BASE_HEIGHT = 20 * MM, 3 * MM


def crown_spheres(plan: CrownPlan = CROWN) -> ReferenceSpheres:
    """The crown workpiece's spheres: R2 mm cavities centred in its flat, 6 mm off its axes."""
    z = plan.rough_flat
    return ReferenceSpheres(np.array([[-6.0, -6.0, 0.0], [6.0, -6.0, 0.0],
                                      [-6.0, 6.0, 0.0]]) * MM + [0.0, 0.0, z], 2.0 * MM)


def crown_stock(plan: CrownPlan = CROWN, chord_tol: float = SPHERE_CHORD_M) -> Part:
    """The roughly machined crown on its base, with the three sphere cavities (Fig. 9b)."""
    crown = diamond_crown(plan.oversize, 2 * plan.apothem, plan.height, CROWN_BASE,
                          CROWN_BASE_HEIGHT, plan.slope)
    sphere = sphere_polygon(crown_spheres(plan).radius, chord_tol)
    cavities = manifold3d.Manifold.batch_boolean(
        [sphere.translate(tuple(float(v) for v in c)) for c in crown_spheres(plan).centres],
        manifold3d.OpType.Add)
    return Part(crown.manifold - cavities)


def crown_design(plan: CrownPlan = CROWN) -> Part:
    """The finished crown as designed, on the flat as roughed (a reference for views)."""
    return diamond_crown(0.0, 2 * plan.apothem, plan.height - plan.oversize, CROWN_BASE,
                         CROWN_BASE_HEIGHT, plan.slope)


def crown_tool(height: float = 50 * UM) -> RoundNoseTool:
    """Table 2's tool, R2.0 nose, 90 deg, its profile ``height`` tall (m).

    50 um is five times the stock allowance; a deeper cut (setting errors above 40 um) would
    reach the profile's top. A low profile keeps the side passes' sweeps thin.
    """
    return RoundNoseTool(2.0 * MM, math.radians(90.0), height=height)


@dataclass(frozen=True, eq=False)
class PassGroup:
    """Equal parallel passes at one C, in machine coordinates at that C (m, rad).

    Attributes
    ----------
    c : float
        C axis value.
    start, end : ndarray, shape (3,)
        Tip at the start and end of the first pass; the tool cuts along +X.
    step : ndarray, shape (3,)
        From one pass to the next.
    count : int
    """

    c: float
    start: np.ndarray
    end: np.ndarray
    step: np.ndarray
    count: int


def crown_passes(plan: CrownPlan = CROWN, offsets=None, prism: bool = False,
                 top_rows=None, side_rows=None) -> tuple[PassGroup, ...]:
    """The crown's passes, one group per face and layer: top face first, then the sides.

    Parameters
    ----------
    plan : CrownPlan
    offsets : sequence of float, optional
        Layer offsets above the finished faces, m, in cutting order. Default: the
        finishing layers, ``oversize - depth_of_cut`` down to 0.
    prism : bool
        Cut from the prism instead (`CrownPlan.prism_apothem`): the top layers as above,
        each side with layers out to the prism's top corner, passes ending at its wall.
    top_rows, side_rows : (float, float), optional
        Keep only the passes with y (top) or v (sides) in this range, m (a window's cut).
    """
    if offsets is None:
        offsets = [plan.depth_of_cut * (plan.layers - 1 - j) for j in range(plan.layers)]
    offsets = [float(o) for o in offsets]
    tan_s, sin_s, cos_s = math.tan(plan.slope), math.sin(plan.slope), math.cos(plan.slope)
    groups = []
    lanes = np.arange(-plan.top_half, plan.top_half + 0.5 * plan.pitch, plan.pitch)
    top_lanes = _rows(lanes, top_rows)
    for o in offsets:
        if len(top_lanes):
            groups.append(PassGroup(0.0, frozen([-plan.top_half, top_lanes[0], o]),
                                    frozen([plan.top_half, top_lanes[0], o]),
                                    frozen([0.0, plan.pitch, 0.0]), len(top_lanes)))
    side_offsets = offsets
    if prism:
        corner = sin_s * (plan.prism_apothem - plan.apothem) + cos_s * plan.rough_top
        side_offsets = list(np.arange(corner // plan.depth_of_cut, -0.5, -1.0)
                            * plan.depth_of_cut)
    lanes = np.arange(-plan.side_half, plan.side_half + 0.5 * plan.pitch, plan.pitch)
    side_lanes = _rows(lanes, side_rows)
    for k in range(8):
        for o in side_offsets:
            lift = o / cos_s
            r0 = plan.apothem + (lift - plan.rough_top) / tan_s
            # 1 um above the flat: a tip exactly on it would touch, not cut
            r1 = plan.apothem + (lift - plan.rough_flat - plan.depth_of_cut) / tan_s
            if prism:
                r1 = min(r1, plan.prism_apothem)
            if r1 <= r0 or not len(side_lanes):
                continue
            height = [lift - (r - plan.apothem) * tan_s for r in (r0, r1)]
            groups.append(PassGroup(math.radians(45.0 * k),
                                    frozen([r0, side_lanes[0], height[0]]),
                                    frozen([r1, side_lanes[0], height[1]]),
                                    frozen([0.0, plan.pitch, 0.0]), len(side_lanes)))
    return tuple(groups)


def _rows(lanes: np.ndarray, span) -> np.ndarray:
    if span is None:
        return lanes
    low, high = float(span[0]), float(span[1])
    if not low < high:
        raise InputError(f"Expected a row range (low, high) with low < high, got {span!r}")
    return lanes[(lanes >= low - 1e-12) & (lanes <= high + 1e-12)]


#: Axis values (X Y Z B C; m, rad) every crown program starts and ends at: above the centre.
PARK = (0.0, 0.0, SAFE_Z, 0.0, 0.0)


def passes_program(groups, number: int = 3, stagger: bool = True,
                   source: str = "workpiece_setting crown") -> Program:
    """The NC program of pass groups, from and back to `PARK`.

    Each pass: rapid to its start + `CLEARANCE`, feed down, feed along, feed up; every turn
    of C at `SAFE_Z` over the C centre.

    Parameters
    ----------
    groups : sequence of PassGroup
    number : int
        O number.
    stagger : bool
        Move each pass's ends by up to `STAGGER` in air (see there): the ends stretch out
        where the pass ends in air above the part, and stop short at the foot of a slope.
    """
    b = ProgramBuilder(number, source=source)
    b.rapid(**dict(zip("XYZBC", PARK, strict=True)))
    _add_passes(b, groups, 0.0, stagger)
    b.rapid(Z=SAFE_Z).rapid(X=0.0, Y=0.0, C=0.0)
    return b.build()


def _add_passes(b: ProgramBuilder, groups, c_now: float, stagger: bool) -> None:
    n = 0
    for group in groups:
        if group.c != c_now:
            b.rapid(Z=SAFE_Z).rapid(X=0.0, Y=0.0).rapid(C=group.c)
            c_now = group.c
        run = group.end - group.start
        unit = run / np.linalg.norm(run)
        # a pass that ends going down ends on the part (the foot of a face): shorten it there
        sign_end = -1.0 if run[2] < 0.0 else 1.0
        for j in range(group.count):
            e = ((n * GOLDEN) % 1.0) * STAGGER if stagger else 0.0
            n += 1
            start = group.start + j * group.step - e * unit
            end = group.end + j * group.step + sign_end * e * unit
            b.rapid(X=float(start[0]), Y=float(start[1]), Z=float(start[2] + CLEARANCE))
            b.linear(Z=float(start[2]), feed_mm_per_min=FEED_MM_PER_MIN)
            b.linear(X=float(end[0]), Y=float(end[1]), Z=float(end[2]))
            b.linear(Z=float(end[2] + CLEARANCE))


def machining_time(machine, groups) -> float:
    """Time of ``passes_program(groups, stagger=False)`` by `motion.plan`, s, from `PARK`.

    The program is not built whole: each group is planned with one and with two of its
    passes, from where the groups before it left the axes; its passes repeat exactly, so it
    takes ``t1 + (count - 1) (t2 - t1)``.
    """
    total, q, c_now = 0.0, np.array(PARK), 0.0
    for group in groups:
        times = []
        for count in (1, 2):
            b = ProgramBuilder(0, source="workpiece_setting timing")
            _add_passes(b, [replace(group, count=count)], c_now, stagger=False)
            times.append(motion.plan(b.build(), machine, start=q).duration)
        total += times[0] + (group.count - 1) * (times[1] - times[0])
        c_now = group.c
        end = group.end + (group.count - 1) * group.step
        q = np.array([end[0], end[1], end[2] + CLEARANCE, 0.0, c_now])
    closing = ProgramBuilder(0, source="workpiece_setting timing").rapid(Z=SAFE_Z)
    closing.rapid(X=0.0, Y=0.0, C=0.0)
    return total + motion.plan(closing.build(), machine, start=q).duration


#: The cut's boxes reach this far past the measuring windows, m.
ROI_PAD = 20 * UM


def crown_roi(plan: CrownPlan = CROWN, margin: float = 0.35 * MM, top: float = 0.4 * MM,
              side: float = 0.25 * MM):
    """Measurement windows, the cut's ROI boxes and pass rows (`crown_passes`) to cut them.

    The top window is ``top`` square about the centre (half size, m); each side window runs
    r = 2.35 .. 2.65 mm out along the face and ``side`` either side along its edge (m); four
    flat patches 0.4 mm square sit 4.5 mm out between the faces.

    Returns
    -------
    windows : dict
        ``"top"``: (x0, x1, y0, y1); ``"side"``: (r0, r1, v0, v1) in each face's own axes;
        ``"flat"``: list of (x0, x1, y0, y1), m.
    roi : list of (x0, x1, y0, y1)
        Axis-aligned boxes holding every window, m.
    rows : dict
        ``top_rows``, ``side_rows`` for `crown_passes`: the passes within ``margin`` of a
        window (default 0.35 mm, the R2 mm nose's half width at a 30 um cut).
    """
    side = (plan.apothem + 0.35 * MM, plan.apothem + 0.65 * MM, -side, side)
    flat_r, flat_half = 4.5 * MM, 0.2 * MM
    flats = []
    for j in range(4):
        angle = math.radians(22.5 + 90.0 * j)
        cx, cy = flat_r * math.cos(angle), flat_r * math.sin(angle)
        flats.append((cx - flat_half, cx + flat_half, cy - flat_half, cy + flat_half))
    boxes = [(-top, top, -top, top), *flats]
    for k in range(8):
        corners = np.array([_face_point(k, r, v) for r in side[:2] for v in side[2:]])
        boxes.append((corners[:, 0].min(), corners[:, 0].max(), corners[:, 1].min(),
                      corners[:, 1].max()))
    # the cut reaches past the windows, so no sample falls on a wall of the clipped part
    roi = [(x0 - ROI_PAD, x1 + ROI_PAD, y0 - ROI_PAD, y1 + ROI_PAD) for x0, x1, y0, y1 in boxes]
    windows = {"top": (-top, top, -top, top), "side": side, "flat": flats}
    rows = {"top_rows": (-top - margin, top + margin),
            "side_rows": (side[2] - margin, side[3] + margin)}
    return windows, roi, rows


def _face_point(k: int, r: float, v: float) -> np.ndarray:
    """Workpiece (x, y) of the point r along face k's outward direction and v along it."""
    c, s = math.cos(k * math.pi / 4), math.sin(k * math.pi / 4)
    return np.array([r * c - v * s, r * s + v * c])
