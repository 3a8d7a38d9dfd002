"""Paper 002's two machining experiments: crossing grooves and the finished diamond crown.

Both run on `robonano_a0ib` with a R2.0 round-nose diamond tool (Tables 1 and 2), on
workpieces that carry three R2 mm reference spheres (ball-end-milled cavities) for
`machinesim.identification.seed002`. Programs are written for the ideal workpiece; the
tool cuts along its own +X (docs/machines.md), so where the paper feeds along Y the
programs feed along X, with C turned to point the cut: nothing else changes.

Grooves (section 3.1): four grooves 3 um deep and 1 mm long from a common point, cut at
C = 0, 90, 180, 270 deg; their depth is read along each (`groove_depths`).

Crown (section 3.2): the roughly machined crown (`workpiece.diamond_crown`, 10 um oversize,
here on a 20 x 20 mm base with the spheres in its flat) is finished with 1 um layers
(Table 2: 10 um in all, pitch feed 12.5 um): the top face by passes along X at C = 0, each
side face by passes down its slope (X and Z together) at C = k 45 deg. `crown_features`
reads the distances between opposite top edges (L1..L8) and the side-face inclinations
(S1..S8) from planes fitted to microscope height maps. `machining_time` gives the time of
the finishing against cutting the crown out of the full prism with the same passes.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import manifold3d
import numpy as np

from machinesim import motion
from machinesim.cutting import remove
from machinesim.exceptions import InputError
from machinesim.identification.seed002 import ReferenceSpheres
from machinesim.metrology import MeshIndex, fit_plane, plane_angle
from machinesim.nc import Program, ProgramBuilder
from machinesim.tolerances import SPHERE_CHORD_M
from machinesim.tools import RoundNoseTool, sphere_polygon
from machinesim.workpiece import Part, diamond_crown

__all__ = [
    "CROWN", "GROOVE_ROI", "GROOVE_SPHERES", "GROOVE_STOCK", "MAP_SPACING", "PARK", "CrownCut",
    "CrownFeatures", "CrownPlan", "GrooveDepths", "PassGroup", "clip_to", "crown_features",
    "crown_passes", "crown_roi", "crown_spheres", "crown_stock", "crown_tool", "cut_crown",
    "groove_depths", "groove_program", "machining_time", "passes_program",
]

MM, UM = 1e-3, 1e-6
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
#: Stations along each groove where its depth is read (m from the crossing point); 0.95 mm
#: is the paper's "end of each groove".
STATIONS = (0.5 * MM, 0.6 * MM, 0.7 * MM, 0.8 * MM, 0.9 * MM, 0.95 * MM)
#: Half length of a profile across a groove, and the fitted stretch about its bottom, m: a
#: R2 mm groove 30 um deep is 0.7 mm wide; 25 um either side of the bottom rises 0.16 um.
PROFILE_HALF, BOTTOM_HALF = 0.35 * MM, 25 * UM
#: Patches of the uncut top face between the grooves, centre distance from the crossing
#: along the diagonals and half size, m: the reference surface for the depths.
PATCH_AT, PATCH_HALF = 0.75 * MM, 0.15 * MM


def groove_program(depth: float = 3 * UM, length: float = 1 * MM,
                   feed_mm_per_min: float = FEED_MM_PER_MIN) -> Program:
    """Four grooves from the C centre, one at each of C = 0, 90, 180, 270 deg (Fig. 7).

    Each groove: rapid above the crossing point, plunge to ``-depth`` at the feed (the edge
    plunging cuts nothing), feed ``length`` along the tool's +X, leave upwards at the feed.
    """
    b = ProgramBuilder(2, source="seed002 grooves")
    b.rapid(X=0.0, Y=0.0, Z=SAFE_Z, B=0.0, C=0.0)
    for k in range(4):
        b.rapid(C=math.radians(90.0 * k)).rapid(Z=CLEARANCE)
        b.linear(Z=-depth, feed_mm_per_min=feed_mm_per_min)
        b.linear(X=length).linear(Z=CLEARANCE).rapid(Z=SAFE_Z).rapid(X=0.0)
    return b.build()


@dataclass(frozen=True, eq=False)
class GrooveDepths:
    """Depths read along the four grooves (m).

    Attributes
    ----------
    stations : ndarray, shape (n,)
        Distances from the crossing point, m.
    depths : ndarray, shape (4, n)
        Depth of groove k (cut at C = 90 k deg) at each station, below the top face.
    """

    stations: np.ndarray
    depths: np.ndarray

    @property
    def ends(self) -> np.ndarray:
        """Depths at the last station, shape (4,)."""
        return self.depths[:, -1]


def groove_depths(part, microscope, stations=STATIONS) -> GrooveDepths:
    """Read each groove's depth along it with the microscope (paper Fig. 8b).

    The top face is the plane fitted to four patches between the grooves; at each station a
    profile across the groove gives its bottom (parabola through the stretch about the
    lowest sample) and the depth is the plane's height there less the bottom.
    """
    points = []
    for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
        cx, cy = sx * PATCH_AT, sy * PATCH_AT
        area = microscope.height_map(part, cx - PATCH_HALF, cx + PATCH_HALF, cy - PATCH_HALF,
                                     cy + PATCH_HALF, spacing=5 * UM)
        gx, gy = np.meshgrid(area.x, area.y)
        points.append(np.column_stack([gx.ravel(), gy.ravel(), area.z.ravel()]))
    top = fit_plane(np.vstack(points))
    stations = np.asarray(stations, dtype=np.float64)
    depths = np.zeros((4, len(stations)))
    for k in range(4):
        along = np.array([math.cos(k * math.pi / 2), math.sin(k * math.pi / 2)])
        across = np.array([-along[1], along[0]])
        for j, t in enumerate(stations):
            centre = t * along
            read = microscope.profile(part, centre - PROFILE_HALF * across,
                                      centre + PROFILE_HALF * across)
            xy, z = read.xy, read.z
            lowest = int(np.nanargmin(z))
            near = (np.abs(read.s - read.s[lowest]) <= BOTTOM_HALF) & ~np.isnan(z)
            s = read.s[near] - read.s[lowest]
            c2, c1, c0 = np.polyfit(s, z[near], 2)
            vertex = -c1 / (2.0 * c2) if c2 > 0.0 else 0.0
            bottom = c0 + c1 * vertex + c2 * vertex**2 if abs(vertex) <= BOTTOM_HALF else (
                float(np.mean(z[near])))
            p = xy[lowest]
            level = top.point[2] - (top.normal[0] * (p[0] - top.point[0])
                                    + top.normal[1] * (p[1] - top.point[1])) / top.normal[2]
            depths[k, j] = level - bottom
    return GrooveDepths(_frozen(stations), _frozen(depths))


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
            groups.append(PassGroup(0.0, _frozen([-plan.top_half, top_lanes[0], o]),
                                    _frozen([plan.top_half, top_lanes[0], o]),
                                    _frozen([0.0, plan.pitch, 0.0]), len(top_lanes)))
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
                                    _frozen([r0, side_lanes[0], height[0]]),
                                    _frozen([r1, side_lanes[0], height[1]]),
                                    _frozen([0.0, plan.pitch, 0.0]), len(side_lanes)))
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
                   source: str = "seed002 crown") -> Program:
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
            b = ProgramBuilder(0, source="seed002 timing")
            _add_passes(b, [replace(group, count=count)], c_now, stagger=False)
            times.append(motion.plan(b.build(), machine, start=q).duration)
        total += times[0] + (group.count - 1) * (times[1] - times[0])
        c_now = group.c
        end = group.end + (group.count - 1) * group.step
        q = np.array([end[0], end[1], end[2] + CLEARANCE, 0.0, c_now])
    closing = ProgramBuilder(0, source="seed002 timing").rapid(Z=SAFE_Z)
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


@dataclass(frozen=True)
class CrownCut:
    """What `cut_crown` did.

    Attributes
    ----------
    machining_time_s, cutting_time_s : float
        From the feeds (`motion.plan`), the whole program and its feed moves.
    sweeps : int
        Feed sweeps that reached the windows' material.
    sideways : int
        Feed sweeps the engine flags as dragging the tool across its edge: a compensated
        program's plunges, retracts and slope passes, where the roll five axes cannot undo
        turns the tool ~1e-4 rad off the plane of its motion.
    removed_volume_m3 : float
    elapsed_s : float
    """

    machining_time_s: float
    cutting_time_s: float
    sweeps: int
    sideways: int
    removed_volume_m3: float
    elapsed_s: float


def clip_to(stock: Part, boxes, floor: float | None = None) -> Part:
    """The stock inside the boxes (x0, x1, y0, y1), m, above ``floor`` (m; default all)."""
    low, high = stock.bounds
    pad = 1.0 * MM
    bottom = low[2] - pad if floor is None else floor
    pieces = [manifold3d.Manifold.cube((x1 - x0, y1 - y0, high[2] + pad - bottom))
              .translate((x0, y0, bottom)) for x0, x1, y0, y1 in boxes]
    return Part(stock.manifold ^ manifold3d.Manifold.batch_boolean(pieces,
                                                                   manifold3d.OpType.Add))


def cut_crown(program: Program, machine, tool, stock: Part, errors=None, boxes=None,
              floor: float | None = None) -> tuple[Part, CrownCut]:
    """Cut a crown program, each C position's passes in that face's own frame.

    The part is the same as `cutting.cut` makes (tested), but the booleans of passes turned
    45 deg off the machine axes are 4-5 times slower than of passes along them (measured:
    105 side passes, 9.8 s at C = 45 deg, 2.2 s at 0): so the feed moves are grouped by
    their C, rounded to 45 deg, and each group is cut in the part turned back by that angle.
    Rapids are not checked against the part: crown programs keep them above it.

    Parameters
    ----------
    program : Program
        A crown program (`passes_program`), nominal or compensated.
    machine : Machine
    tool : RoundNoseTool
    stock : Part
    errors : ErrorModel, optional
        The machine's (injected) errors.
    boxes : sequence of (x0, x1, y0, y1), optional
        Cut only inside these boxes (m): the stock is clipped to them first, and below
        ``floor`` (m) if given.
    floor : float, optional
    """
    began = time.perf_counter()
    part = stock if boxes is None else clip_to(stock, boxes, floor)
    trajectory = motion.plan(program, machine, errors, start=PARK,
                             tool_points=tool.vertices())
    step = math.pi / 4.0
    groups: dict[int, list[np.ndarray]] = {}
    for segment in trajectory.segments:
        if segment.kind == "linear":
            key = int(round(float(segment.q[0, 4]) / step))
            groups.setdefault(key, []).append(machine.tool_pose(segment.q, errors))
    before = part.volume
    sweeps = sideways = 0
    for key, paths in groups.items():
        turn = np.eye(4)
        turn[:3, :3] = _turn(-key * step)
        turned = Part(part.manifold.rotate((0.0, 0.0, -45.0 * key)))
        cut_part, report = remove(turned, tool, [turn @ path for path in paths])
        part = Part(cut_part.manifold.rotate((0.0, 0.0, 45.0 * key)))
        sweeps += report.n_sweeps_cut
        sideways += len(report.sideways)
    return part, CrownCut(trajectory.duration, trajectory.cutting_time, sweeps, sideways,
                          before - part.volume, time.perf_counter() - began)


def _turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


#: Sample spacing of the crown's height maps, m: about a tenth of the 12.5 um pitch feed, and
#: chosen so an 11.31 deg face (tan = 0.2) rises 248.618 nm a sample, not a whole number of
#: nm: on 2.5 um (500 nm a sample) the microscope's 1 nm rounding, without noise, rounds every
#: sample of a row alike and the fitted inclination locks onto the rounding (measured: 3e-5
#: deg on one face for a 0.1 nm shift of the cut); here the rounding averages out (1e-7 deg).
MAP_SPACING = 1.24309 * UM


@dataclass(frozen=True, eq=False)
class CrownFeatures:
    """Table 3's quantities of a machined crown.

    Attributes
    ----------
    edge_distances : ndarray, shape (4,)
        Distances between opposite top edges, pairs (L1, L5) .. (L4, L8), m: the lines where
        the fitted side planes meet the fitted top plane.
    inclinations : ndarray, shape (8,)
        Angle of each side face (S1..S8, faces at C = 0, 45, .. deg) to the bottom face, rad.
    foot_distances : ndarray, shape (4,)
        Distances between opposite foot edges (side planes on the flat's plane), m.
    """

    edge_distances: np.ndarray
    inclinations: np.ndarray
    foot_distances: np.ndarray


def crown_features(part, microscope, windows, spacing: float = MAP_SPACING) -> CrownFeatures:
    """Read Table 3's quantities with the microscope (Fig. 12).

    Planes are fitted to height maps in the ``windows`` of `crown_roi`: the top face, each
    side face and four patches of the flat. Each side face is mapped with the part turned so
    that the face's own axes (r out, v along its edge) are the map's, as a microscope stage
    turns a sample: a map's cost grows with the triangles' boxes, which the long scallop
    triangles of a face at 45 deg make large. ``spacing``: see `MAP_SPACING`.
    """
    mesh = MeshIndex.from_surface(part)
    top = fit_plane(_map_points(mesh, microscope, windows["top"], spacing))
    flat = fit_plane(np.vstack([_map_points(mesh, microscope, box, 4 * spacing)
                                for box in windows["flat"]]))
    sides, edges, feet = [], [], []
    for k in range(8):
        turned = Part(part.manifold.rotate((0.0, 0.0, -45.0 * k)))
        local = fit_plane(_map_points(turned, microscope, windows["side"], spacing))
        back = _turn(k * math.pi / 4)
        side = replace(local, point=_frozen(back @ local.point),
                       normal=_frozen(back @ local.normal))
        sides.append(side)
        edges.append(_meet(top, side))
        feet.append(_meet(flat, side))
    inclinations = np.array([plane_angle(side, flat) for side in sides])
    return CrownFeatures(_frozen([_distance(edges[k], edges[k + 4]) for k in range(4)]),
                         _frozen(inclinations),
                         _frozen([_distance(feet[k], feet[k + 4]) for k in range(4)]))


def _map_points(part, microscope, box, spacing: float) -> np.ndarray:
    area = microscope.height_map(part, *box, spacing=spacing)
    gx, gy = np.meshgrid(area.x, area.y)
    points = np.column_stack([gx.ravel(), gy.ravel(), area.z.ravel()])
    return points[~np.isnan(points[:, 2])]


def _meet(first, second) -> tuple[np.ndarray, np.ndarray]:
    """The line where two fitted planes meet: a point on it and its unit direction."""
    direction = np.cross(first.normal, second.normal)
    direction /= np.linalg.norm(direction)
    normals = np.array([first.normal, second.normal, direction])
    offsets = np.array([first.normal @ first.point, second.normal @ second.point,
                        direction @ (0.5 * (first.point + second.point))])
    return np.linalg.solve(normals, offsets), direction


def _distance(first, second) -> float:
    """Distance between two (nearly) parallel lines, across their mean direction, m."""
    (p, d), (q, e) = first, second
    mean = d + (e if d @ e >= 0.0 else -e)
    mean /= np.linalg.norm(mean)
    gap = q - p
    return float(np.linalg.norm(gap - (gap @ mean) * mean))


def _frozen(values) -> np.ndarray:
    array = np.array(values, dtype=np.float64)
    array.flags.writeable = False
    return array
