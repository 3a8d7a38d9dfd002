"""Paper 002's two workpieces as CAM prepares them: the crossing grooves and the diamond crown.

Both run on `robonano_a0ib` with a R2.0 round-nose diamond tool (Tables 1 and 2), on
workpieces that carry three R2 mm reference spheres (ball-end-milled cavities) for the
setting identification (`machinesim.identification.workpiece_setting`). Programs are
written for the ideal workpiece; the tool cuts along its own +X (docs/machines.md), so where
the paper feeds along Y the programs feed along X, with C turned to point the cut: nothing
else changes. Nothing here cuts or measures: `machinesim.procedures.workpiece_setting` does.

Grooves (section 3.1): four grooves 3 um deep and 1 mm long from a common point, cut at
C = 0, 90, 180, 270 deg (`groove_program`) on a block (`GROOVE_STOCK`): in
`machinesim.cam.grooves`, with the feed and heights both programs share; their names are
imported here as before.

Crown (section 3.2): the roughly machined crown (`workpiece.diamond_crown`, 10 um oversize,
here on a 20 x 20 mm base with the spheres in its flat, `crown_stock`) is finished with 1 um
layers (Table 2: 10 um in all, pitch feed 12.5 um): the top face by passes along X at C = 0,
each side face by passes down its slope (X and Z together) at C = k 45 deg (`crown_passes`,
`passes_program`), every pass clipped to its face. `crown_roi` gives the measuring windows
and the passes that reach them; `machining_time` the time of the finishing against cutting
the crown out of the cuboid with the same passes (section 3.2.4). The crown's size (Fig. 9
is missing) is chosen so that the finishing takes the paper's 9.5 h with its 12 min of
setting (`CrownPlan`). `crown_blank` is the rough crown without its spheres, for
`machinesim.Lab.make_artefacts`; `crown_stock` has them as designed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

from machinesim import motion
from machinesim.arrays import frozen
from machinesim.cam.grooves import (  # the grooves' names, re-exported
    CLEARANCE,
    FEED_MM_PER_MIN,
    GROOVE_BLANK,
    GROOVE_ROI,
    GROOVE_SPHERE_DESIGN,
    GROOVE_SPHERES,
    GROOVE_STOCK,
    SAFE_Z,
    groove_program,
    groove_rapids_crash,
)
from machinesim.exceptions import InputError
from machinesim.identification.workpiece_setting import ReferenceSpheres
from machinesim.metrology._arrays import as_number
from machinesim.nc import Program, ProgramBuilder
from machinesim.realism import SphereArtefacts, draw_spheres, make_spheres
from machinesim.tolerances import SPHERE_CHORD_M
from machinesim.tools import RoundNoseTool
from machinesim.units import M_PER_MM, M_PER_UM
from machinesim.workpiece import Part, diamond_crown

__all__ = [
    "CLEARANCE", "CROWN", "CROWN_BASE", "CROWN_BASE_HEIGHT", "FEED_MM_PER_MIN", "GROOVE_BLANK",
    "GROOVE_ROI", "GROOVE_SPHERE_DESIGN", "GROOVE_SPHERES", "GROOVE_STOCK", "MAX_PASSES", "PARK",
    "SAFE_Z",
    "SETTING_S", "CrownPlan", "PassGroup", "crown_blank", "crown_design", "crown_passes",
    "crown_roi", "crown_sphere_design", "crown_spheres", "crown_stock", "crown_tool",
    "groove_program", "groove_rapids_crash", "machining_time", "passes_program",
]

MM, UM = M_PER_MM, M_PER_UM
#: Most passes a `CrownPlan` may make (all layers and faces): Table 2's plan makes 26,000;
#: a pitch or depth of cut in the wrong unit (12.5e-12 m) asked for 10^10 and filled memory.
MAX_PASSES = 10**7
#: Pass ends are moved along the pass by up to this (m, in air, golden-ratio sequence): the
#: material-removal engine slows down by orders of magnitude on unions of sweeps whose end
#: faces are coplanar but turned off the machine axes (measured: 25 passes at gamma = 1 mrad
#: 13 s and 1.3 M triangles, staggered 0.2 s); the cut is the same.
STAGGER = 5 * UM
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class CrownPlan:
    """The designed crown and its finishing passes (Fig. 9, Table 2), m and rad.

    Fig. 9 (the crown's dimensions) is missing from the paper's text; the apothem and height
    are chosen so that the finishing time with Table 2's passes, plus the paper's 12 min of
    setting, is the paper's 9.5 h (section 3.2.4; docs/procedures/workpiece_setting.md).

    Attributes
    ----------
    apothem : float
        Half the top face's across-flats.
    height : float
        Crown height above the flat.
    slope : float
        Side-face slope, rad (11.31 deg, tan = 0.2).
    oversize : float
        Stock allowance of the rough crown (Table 2: total depth 10 um).
    depth_of_cut, pitch : float
        Table 2: 1 um and 12.5 um.
    overrun : float
        Top passes run this far past the top octagon's edges (the stock allowance over the
        slope: where a top layer leaves the rough side face).
    """

    apothem: float = 1.5 * MM
    height: float = 0.07 * MM
    slope: float = math.atan(0.2)
    oversize: float = 10 * UM
    depth_of_cut: float = 1 * UM
    pitch: float = 12.5 * UM
    overrun: float = 50 * UM

    def __post_init__(self) -> None:
        # each field a finite float of its sign: a pitch of 0 was a ZeroDivisionError in
        # crown_passes, a NaN one numpy's ValueError, a negative one no pass at all
        for name in ("apothem", "height", "oversize", "depth_of_cut", "pitch"):
            object.__setattr__(self, name, as_number(getattr(self, name), name, sign="> 0"))
        object.__setattr__(self, "overrun", as_number(self.overrun, "overrun", sign=">= 0"))
        slope = as_number(self.slope, "slope", sign="> 0", unit="rad")
        if not slope < 0.5 * math.pi:
            raise InputError(f"Expected slope, the side faces' angle from the flat, below pi/2 "
                             f"rad (90 deg), got {slope!r}", key="slope")
        object.__setattr__(self, "slope", slope)
        if not self.height > self.oversize:
            raise InputError(f"Expected height, the rough crown's over its flat, above the "
                             f"oversize {self.oversize!r} m (the finished crown stands height - "
                             f"oversize high), got {self.height!r} m", key="height")
        ratio = self.oversize / self.depth_of_cut
        if abs(ratio - round(ratio)) > 1e-9 * ratio:
            raise InputError(f"Expected the oversize {self.oversize!r} m a whole number of "
                             f"depth_of_cut, got depth_of_cut {self.depth_of_cut!r} m "
                             f"({ratio:.6g} layers): the first layer would cut deeper than "
                             "depth_of_cut", key="depth_of_cut")
        # passes of the finishing: every face's rows over the cuboid's width, per layer
        passes = 9.0 * ratio * (2.0 * (self.cuboid_half + self.overrun) / self.pitch + 1.0)
        if not passes <= MAX_PASSES:
            # named by the field furthest from Table 2's plan in the passes' direction: a
            # slope of 1e-9 rad (a foot 60 km out) or an overrun of 1 m was told as the pitch
            key = self._furthest()
            unit = "rad" if key == "slope" else "m"
            paper = next(f.default for f in fields(CrownPlan) if f.name == key)
            raise InputError(f"Expected at most {MAX_PASSES:.0e} passes (MAX_PASSES), got about "
                             f"{passes:.3g}: {round(ratio)} layers of rows {self.pitch!r} m "
                             f"apart over {2.0 * (self.cuboid_half + self.overrun):.3g} m (2 "
                             "(apothem + (height - oversize) / tan(slope) + overrun)); "
                             f"{key} {getattr(self, key)!r} "
                             f"{unit} (Table 2's plan: {paper:.6g} {unit}) asks for them most: "
                             "a value in another unit?", key=key)

    def _furthest(self) -> str:
        """The field whose ratio to Table 2's plan (the fields' defaults) multiplies the
        passes most, each taken as if alone (the width's terms by their own ratio)."""
        paper = {f.name: f.default for f in fields(CrownPlan)}
        standing = (self.height - self.oversize) / (paper["height"] - paper["oversize"])
        times = {"pitch": paper["pitch"] / self.pitch,
                 "depth_of_cut": paper["depth_of_cut"] / self.depth_of_cut,
                 "oversize": self.oversize / paper["oversize"],
                 "apothem": self.apothem / paper["apothem"],
                 "overrun": self.overrun / paper["overrun"],
                 "slope": math.tan(paper["slope"]) / math.tan(self.slope),
                 "height": standing}
        return max(times, key=times.__getitem__)

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
    def run(self) -> float:
        """Horizontal run of a finished side face, top edge to foot, m."""
        return (self.rough_top - self.oversize - self.rough_flat) / math.tan(self.slope)

    @property
    def foot_distance(self) -> float:
        """Designed distance between opposite foot edges of the finished crown, m."""
        return 2.0 * (self.apothem + self.run)

    @property
    def cuboid_half(self) -> float:
        """Half width of the cuboid the crown is cut from without rough machining (section
        3.2.4): the smallest square block holding the crown's foot, its top at the rough
        top, m."""
        return self.apothem + self.run


#: The crown of `workpiece.diamond_crown` and Table 2.
CROWN = CrownPlan()
#: Base of the crown workpiece (m): 20 mm square, 3 mm thick, room for the spheres.
CROWN_BASE, CROWN_BASE_HEIGHT = 20 * MM, 3 * MM


def crown_spheres(plan: CrownPlan = CROWN) -> ReferenceSpheres:
    """The crown workpiece's spheres: R2 mm cavities centred in its flat, 6 mm off its axes."""
    z = plan.rough_flat
    return ReferenceSpheres(np.array([[-6.0, -6.0, 0.0], [6.0, -6.0, 0.0],
                                      [-6.0, 6.0, 0.0]]) * MM + [0.0, 0.0, z], 2.0 * MM)


def crown_blank(plan: CrownPlan = CROWN) -> Part:
    """The roughly machined crown on its base, without its sphere cavities (Fig. 9b): what
    `machinesim.Lab.make_artefacts` cuts the spheres into (`crown_sphere_design`)."""
    return diamond_crown(plan.oversize, 2 * plan.apothem, plan.height, CROWN_BASE,
                         CROWN_BASE_HEIGHT, plan.slope)


def crown_sphere_design(plan: CrownPlan = CROWN, chord_tol: float = SPHERE_CHORD_M
                        ) -> SphereArtefacts:
    """The crown workpiece's reference spheres as designed (`crown_spheres`), cavities."""
    spheres = crown_spheres(plan)
    return SphereArtefacts(spheres.centres, spheres.radius, cavities=True, chord_tol=chord_tol)


def crown_stock(plan: CrownPlan = CROWN, chord_tol: float = SPHERE_CHORD_M) -> Part:
    """The roughly machined crown with its three sphere cavities exactly as designed."""
    design = crown_sphere_design(plan, chord_tol)
    return make_spheres(crown_blank(plan), design, draw_spheres(design, None))


def crown_design(plan: CrownPlan = CROWN) -> Part:
    """The finished crown as designed, on the flat as roughed (a reference for views)."""
    return diamond_crown(0.0, 2 * plan.apothem, plan.height - plan.oversize, CROWN_BASE,
                         CROWN_BASE_HEIGHT, plan.slope)


def crown_tool(height: float = 50 * UM) -> RoundNoseTool:
    """Table 2's tool, R2.0 nose, 90 deg, its profile ``height`` tall (m).

    50 um is five times the stock allowance; a deeper cut (setting errors above 40 um) would
    reach the profile's top. A low profile keeps the side passes' sweeps thin. Its top is
    not a holder: on a side face the face uphill of a pass rises over it, which the cutter
    would refuse as a holder crash; cut with ``allow_holder_contact=True``.
    """
    return RoundNoseTool(2.0 * MM, math.radians(90.0), height=height)


@dataclass(frozen=True, eq=False)
class PassGroup:
    """Parallel passes at one C whose ends move linearly from pass to pass, in machine
    coordinates at that C (m, rad).

    Attributes
    ----------
    c : float
        C axis value.
    start, end : ndarray, shape (3,)
        Tip at the start and end of the first pass; the tool cuts along +X.
    step : ndarray, shape (3,)
        From one pass's start to the next's.
    count : int
    end_step : ndarray, shape (3,), optional
        From one pass's end to the next's (default ``step``: equal passes).
    """

    c: float
    start: np.ndarray
    end: np.ndarray
    step: np.ndarray
    count: int
    end_step: np.ndarray | None = None

    @property
    def equal(self) -> bool:
        """All passes the same, shifted by ``step``."""
        return self.end_step is None or bool(np.array_equal(self.end_step, self.step))

    def pass_ends(self, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Start and end of pass ``j``."""
        end_step = self.step if self.end_step is None else self.end_step
        return self.start + j * self.step, self.end + j * end_step


#: tan(22.5 deg): half an octagon side over its apothem; a side face's hip lines run at
#: |v| = r tan(22.5 deg) in its own axes (r out along the face, v along its edge).
HIP = math.tan(math.pi / 8.0)


def crown_passes(plan: CrownPlan = CROWN, offsets=None, cuboid: bool = False,
                 top_rows=None, side_rows=None) -> tuple[PassGroup, ...]:
    """The crown's passes, groups per face and layer: top face first, then the sides.

    Every pass is clipped to its face (Fig. 10): a top pass along X at row y runs over the
    octagon's chord at y, `CrownPlan.overrun` past its edges; a side pass down the slope at
    v along the edge starts on the face's layer where the layer meets the rough top, or on
    the hip line to the next face (|v| = r tan 22.5 deg), and ends 1 um above the flat.
    Rows are spaced by the pitch feed about the face's centre line.

    Parameters
    ----------
    plan : CrownPlan
    offsets : sequence of float, optional
        Layer offsets above the finished faces, m, in cutting order. Default: the
        finishing layers, ``oversize - depth_of_cut`` down to 0.
    cuboid : bool
        Cut from the cuboid instead (`CrownPlan.cuboid_half`, section 3.2.4): the same
        passes, the top face over the whole block, each side with layers out to the
        block's top corner, passes ending at its walls.
    top_rows, side_rows : (float, float), optional
        Keep only the passes with y (top) or v (sides) in this range, m (a window's cut).
    """
    if offsets is None:
        offsets = [plan.depth_of_cut * (plan.layers - 1 - j) for j in range(plan.layers)]
    offsets = [float(o) for o in offsets]
    tan_s, sin_s, cos_s = math.tan(plan.slope), math.sin(plan.slope), math.cos(plan.slope)
    groups = []
    reach = plan.apothem + plan.overrun
    top_lanes = _rows(_lanes(plan.cuboid_half if cuboid else reach, plan.pitch), top_rows)
    if cuboid:
        x1 = np.full(len(top_lanes), plan.cuboid_half + plan.overrun)
    else:
        # the octagon of apothem `reach`: |x| <= reach and |x| + |y| <= reach sqrt 2
        x1 = np.minimum(reach, reach * math.sqrt(2.0) - np.abs(top_lanes))
    keep = x1 > 0.0
    top_lanes, x1 = top_lanes[keep], x1[keep]
    for o in offsets:
        starts = np.column_stack([-x1, top_lanes, np.full(len(x1), o)])
        ends = np.column_stack([x1, top_lanes, np.full(len(x1), o)])
        groups += _groups(0.0, starts, ends)
    side_offsets = offsets
    if cuboid:
        wall = plan.cuboid_half * math.sqrt(2.0)  # the block's corner, seen from a 45 deg face
        corner = sin_s * (wall - plan.apothem) + cos_s * plan.rough_top
        side_offsets = list(np.arange(corner // plan.depth_of_cut, -0.5, -1.0)
                            * plan.depth_of_cut)
    for k in range(8):
        for o in side_offsets:
            lift = o / cos_s
            top_r = plan.apothem + (lift - plan.rough_top) / tan_s
            # 1 um above the flat: a tip exactly on it would touch, not cut
            foot_r = plan.apothem + (lift - plan.rough_flat - plan.depth_of_cut) / tan_s
            lanes = _rows(_lanes(foot_r * HIP, plan.pitch), side_rows)
            r0 = np.maximum(top_r, np.abs(lanes) / HIP)
            r1 = np.full(len(lanes), foot_r)
            if cuboid:
                r1 = np.minimum(r1, _wall_r(k, lanes, plan.cuboid_half))
            keep = r1 > r0
            lanes, r0, r1 = lanes[keep], r0[keep], r1[keep]
            if not len(lanes):
                continue
            starts = np.column_stack([r0, lanes, lift - (r0 - plan.apothem) * tan_s])
            ends = np.column_stack([r1, lanes, lift - (r1 - plan.apothem) * tan_s])
            groups += _groups(math.radians(45.0 * k), starts, ends)
    return tuple(groups)


def _lanes(half: float, pitch: float) -> np.ndarray:
    """Rows at multiples of the pitch within [-half, half]."""
    n = math.floor(half / pitch + 1e-9)
    return np.arange(-n, n + 1) * pitch


def _wall_r(k: int, v: np.ndarray, half: float) -> np.ndarray:
    """r where a row at v of face k meets the wall of the square block of half width
    ``half`` (face axes: r out along the face at k 45 deg, v along its edge)."""
    if k % 2 == 0:
        return np.full(len(v), half)
    return half * math.sqrt(2.0) - np.abs(v)


def _groups(c: float, starts: np.ndarray, ends: np.ndarray) -> list[PassGroup]:
    """Rows (in order) split into runs whose starts and ends each move by a constant step."""
    groups, i, n = [], 0, len(starts)
    steps, end_steps = np.diff(starts, axis=0), np.diff(ends, axis=0)
    while i < n:
        j = i + 1
        if j < n:
            step, end_step = steps[i], end_steps[i]
            same = (np.all(np.abs(steps[j:] - step) <= 1e-12, axis=1)
                    & np.all(np.abs(end_steps[j:] - end_step) <= 1e-12, axis=1))
            j += len(same) if same.all() else int(np.argmin(same))
        else:
            step = end_step = np.zeros(3)
        count = j - i + 1 if j < n else 1
        equal = np.allclose(end_step, step, rtol=0.0, atol=1e-12)
        groups.append(PassGroup(c, frozen(starts[i]), frozen(ends[i]), frozen(step), count,
                                None if equal else frozen(end_step)))
        i += count
    return groups


def _rows(lanes: np.ndarray, span) -> np.ndarray:
    if span is None:
        return lanes
    low, high = float(span[0]), float(span[1])
    if not low < high:
        raise InputError(f"Expected a row range (low, high) with low < high, got {span!r}")
    return lanes[(lanes >= low - 1e-12) & (lanes <= high + 1e-12)]


#: Section 3.2.4: workpiece setting time counted in the paper's 9.5 h (12 min), s.
SETTING_S = 12 * 60.0

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
        for j in range(group.count):
            start, end = group.pass_ends(j)
            run = end - start
            unit = run / np.linalg.norm(run)
            # a pass that ends going down ends on the part (the foot of a face): shorten it
            sign_end = -1.0 if run[2] < 0.0 else 1.0
            e = ((n * GOLDEN) % 1.0) * STAGGER if stagger else 0.0
            n += 1
            start = start - e * unit
            end = end + sign_end * e * unit
            b.rapid(X=float(start[0]), Y=float(start[1]), Z=float(start[2] + CLEARANCE))
            b.linear(Z=float(start[2]), feed_mm_per_min=FEED_MM_PER_MIN)
            b.linear(X=float(end[0]), Y=float(end[1]), Z=float(end[2]))
            b.linear(Z=float(end[2] + CLEARANCE))


def machining_time(machine, groups) -> float:
    """Time of ``passes_program(groups, stagger=False)`` by `motion.plan`, s, from `PARK`.

    The program is not built whole: each group is planned from where the groups before it
    left the axes, with its first one, two (and three) passes. Equal passes repeat exactly:
    ``t1 + (count - 1) (t2 - t1)``. Where the ends move by different steps the feed moves'
    lengths change linearly from pass to pass and the time per pass is taken as linear in
    the pass number, from the first three: exact for the feed moves, while the short rapid
    between passes changes its length slightly non-linearly (tested against the whole
    program's plan).
    """
    total, q, c_now = 0.0, np.array(PARK), 0.0
    for group in groups:
        counts = (1, 2) if group.equal else (1, 2, 3)
        counts = tuple(k for k in counts if k <= group.count)
        times = []
        for count in counts:
            b = ProgramBuilder(0, source="workpiece_setting timing")
            _add_passes(b, [replace(group, count=count)], c_now, stagger=False)
            times.append(motion.plan(b.build(), machine, start=q).duration)
        n = group.count
        if n <= len(times):
            total += times[n - 1]
        elif len(times) == 2:
            total += times[0] + (n - 1) * (times[1] - times[0])
        else:
            first, growth = times[1] - times[0], (times[2] - times[1]) - (times[1] - times[0])
            total += times[0] + (n - 1) * first + 0.5 * (n - 1) * (n - 2) * growth
        c_now = group.c
        end = group.pass_ends(group.count - 1)[1]
        q = np.array([end[0], end[1], end[2] + CLEARANCE, 0.0, c_now])
    closing = ProgramBuilder(0, source="workpiece_setting timing").rapid(Z=SAFE_Z)
    closing.rapid(X=0.0, Y=0.0, C=0.0)
    return total + motion.plan(closing.build(), machine, start=q).duration


#: The cut's boxes reach this far past the measuring windows, m.
ROI_PAD = 20 * UM
#: A face's image window reaches this far inside its top edge and past its foot, m: the
#: top either side of the top edge and what lies beyond the foot in its profiles.
IMAGE_REACH = 100 * UM


def crown_roi(plan: CrownPlan = CROWN, margin: float = 0.35 * MM, top: float = 0.4 * MM,
              side: float = 0.25 * MM):
    """Measurement windows, the cut's ROI boxes and pass rows (`crown_passes`) to cut them.

    The top window is ``top`` square about the centre (half size, m); each side window runs
    over the middle half of the face's run out along it (at most 0.3 mm) and ``side``
    either side along its edge (m); four flat patches 0.4 mm square sit 4.5 mm out
    between the faces. Each face's image window (the profiles of
    `machinesim.metrology.crown_image`) runs from `IMAGE_REACH` inside its top edge to as
    far past its foot, as wide along the edge as the side window.

    Returns
    -------
    windows : dict
        ``"top"``: (x0, x1, y0, y1); ``"side"``, ``"image"``: (r0, r1, v0, v1) in each
        face's own axes; ``"flat"``: list of (x0, x1, y0, y1), m.
    roi : list of (x0, x1, y0, y1)
        Axis-aligned boxes holding every window, m.
    rows : dict
        ``top_rows``, ``side_rows`` for `crown_passes`: the passes within ``margin`` of a
        window (default 0.35 mm, the R2 mm nose's half width at a 30 um cut).
    """
    middle, reach = plan.apothem + 0.5 * plan.run, min(0.15 * MM, 0.25 * plan.run)
    image = (plan.apothem - IMAGE_REACH, plan.apothem + plan.run + IMAGE_REACH, -side, side)
    side = (middle - reach, middle + reach, -side, side)
    flat_r, flat_half = 4.5 * MM, 0.2 * MM
    flats = []
    for j in range(4):
        angle = math.radians(22.5 + 90.0 * j)
        cx, cy = flat_r * math.cos(angle), flat_r * math.sin(angle)
        flats.append((cx - flat_half, cx + flat_half, cy - flat_half, cy + flat_half))
    boxes = [(-top, top, -top, top), *flats]
    for k in range(8):
        corners = np.array([_face_point(k, r, v) for r in image[:2] for v in image[2:]])
        boxes.append((corners[:, 0].min(), corners[:, 0].max(), corners[:, 1].min(),
                      corners[:, 1].max()))
    # the cut reaches past the windows, so no sample falls on a wall of the clipped part
    roi = [(x0 - ROI_PAD, x1 + ROI_PAD, y0 - ROI_PAD, y1 + ROI_PAD) for x0, x1, y0, y1 in boxes]
    windows = {"top": (-top, top, -top, top), "side": side, "image": image, "flat": flats}
    # the image windows reach the top edges all round: every top row within `margin` of
    # one (the top face's rows out to its corners)
    rows = {"top_rows": (-plan.apothem / math.cos(math.pi / 8) - margin,
                         plan.apothem / math.cos(math.pi / 8) + margin),
            "side_rows": (side[2] - margin, side[3] + margin)}
    return windows, roi, rows


def _face_point(k: int, r: float, v: float) -> np.ndarray:
    """Workpiece (x, y) of the point r along face k's outward direction and v along it."""
    c, s = math.cos(k * math.pi / 4), math.sin(k * math.pi / 4)
    return np.array([r * c - v * s, r * s + v * c])
