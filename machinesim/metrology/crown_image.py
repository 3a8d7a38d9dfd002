"""Paper 002's crown read as the paper reads it: edges picked in microscope images.

Section 3.2.3 of the paper: the distance of two opposite edges is "measured by making one
line consisting of two points on an edge and another parallel line located on the other
edge", the measurement "repeated three times to take the average value"; the angle of a
side face to the bottom surface is "calculated based on measuring the height and length of
the side surface". `crown_image_reading` does that on a simulated part:

- each face is one image of the microscope at a 10x objective (`machinesim.realism.
  OBJECTIVE_10X`: one field holds a whole top edge and the face with the top and the flat
  either side), taken in one placement of the stage (`Microscope.placement`); the part is
  turned on the stage so the face's own axes are the image's, as `crown_features` does;
- in it, profiles across the face (at v = -a, 0, +a along the edge) are levelled on the
  bottom surface (the plane fitted to the flat's patches, as an analysis program's tilt
  correction) and their edges found as the corners of lines fitted either side of each
  edge: the top and the face, the face and the flat (`profile_edges`);
- an operator's cursor sits on a pixel: with the instrument's lateral resolution
  (``microscope.spot`` set) each edge is the sample nearest that corner and its height the
  height read there; without, the corner itself on the fitted lines (exact readings); a
  foot before an uncut band is the face's last sample, kept clear of the wall the band
  stands on by the spot's reach (`spot_clearance`), as an operator who sees the wall keeps
  the cursor off its blur;
- S_k = atan(height / length) between the top and foot cursors of the middle profile;
  L_k: the distance from face k + 4's top edge point (middle profile) to the line through
  face k's two top edge points (v = -a, +a), averaged over three readings, each of two
  images (two placements: the crown is wider than a field, so the stage moves between
  the edges and its positioning enters L, as in the paper's reading).

Plane fits over windows (`machinesim.metrology.part_features.crown_features`) average the
same faces over thousands of samples; this reading uses a few pixels, and so carries the
instrument's height noise and pixel pitch into L and S as a reading in the image does.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from machinesim.arrays import frozen
from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_number
from machinesim.metrology.fits import fit_plane, height_map_points
from machinesim.metrology.meshindex import MeshIndex
from machinesim.rotations import rot_z
from machinesim.units import M_PER_UM
from machinesim.workpiece import Part

__all__ = ["CLEARANCE_SIGMAS", "EDGE_GUARD", "REPEATS", "ROUGH_FACE_FRACTION", "CrownImageReading",
           "ProfileEdges", "crown_image_reading", "profile_edges", "profile_reading",
           "rough_face", "spot_clearance", "turned_placements"]

UM = M_PER_UM

#: Samples this close to an edge (m) are left out of the lines fitted either side of it:
#: the spot (1 um) and the pass scallops blur the corner.
EDGE_GUARD = 5 * UM
#: The lines whose corner is an edge are fitted this far either side of it, m.
EDGE_REACH = 60 * UM
#: Readings of each edge distance averaged (paper 002 section 3.2.3: three).
REPEATS = 3
#: The flat patches are read at this spacing for the levelling plane, m.
FLAT_SPACING = 10 * UM
#: A sample keeps to a level or a line if within this many sigmas of the instrument's
#: height noise plus `BAND_FLOOR` of it.
BAND_SIGMAS, BAND_FLOOR = 5.0, 0.5 * UM
#: A face read farther out from its design, along its normal, than this fraction of the
#: stock allowance (`machinesim.cam.crown.CrownPlan.oversize`, 10 um) is the rough face, not
#: a cut one. The drawing's rough crown is the design with every face moved out by the
#: allowance (`machinesim.workpiece.diamond_crown`), so an uncut face reads the allowance
#: out; a cut face reads at or inside its design (the finishing layers reach it; a setting
#: off cuts deeper, or leaves a band of stock that the slope and residual limits catch),
#: within its scallops and the height noise, nm to tens of nm, and the finishing's own
#: miss. Heights are taken above the flat read in the same placement, so the instrument's
#: height offset and tilt cancel; its sideways offset (5 um sd, `machinesim.realism.
#: MICROSCOPE`, one draw a session) moves a face at 11.31 deg by 1 um sd along its normal,
#: opposite faces oppositely. Read so (seed 0, --quick): the default run's cut faces -136 ..
#: -20 um before and -0.8 .. +2.3 um after; the large setting's (--delta-um 80,-60,20
#: --rot-deg 0.5,-0.3,2.0) uncut ones +9.3 .. +10.8 um before, its cut ones -34 .. -3 um
#: before and -0.7 .. +2.4 um after. Half the allowance, 5 um, lies between with 2.6 um to
#: spare on the cut side and 4.3 um on the rough side.
ROUGH_FACE_FRACTION = 0.5
#: Where a face steps away (an uncut band beyond its last pass), its foot cursor keeps this
#: many spot sigmas before the face's last sample, so that the wall the band stands on does
#: not lift the height read there. A Gaussian spot of standard deviation sigma reads a step
#: of height h at distance d before it lifted by h Phi(-d / sigma): Phi(-3.1) = 9.7e-4, under
#: 0.1 % of the wall (9 nm on paper 002's 9.5 um wall, against the 10x's 0.18 um noise). The
#: face's last sample keeps within the band of the face's line, so a wall higher than twice
#: the band lies beyond it (the blur reads half the step at the wall): the cursor lies at
#: least this far from the wall (`spot_clearance`).
CLEARANCE_SIGMAS = 3.1


@dataclass(frozen=True)
class ProfileEdges:
    """A profile's top and foot edges as read (m; s along the profile from its start,
    heights above the levelled bottom surface)."""

    s_top: float
    z_top: float
    s_foot: float
    z_foot: float

    @property
    def inclination(self) -> float:
        """atan(height / length) of the face between the two edges, rad."""
        return math.atan2(self.z_top - self.z_foot, self.s_foot - self.s_top)


@dataclass(frozen=True, eq=False)
class CrownImageReading:
    """Table 3's quantities read in images.

    Attributes
    ----------
    edge_distances : ndarray, shape (4,)
        Pairs (L1, L5) .. (L4, L8), m, each the mean of `REPEATS` readings.
    inclinations : ndarray, shape (8,)
        S1..S8 (faces at C = 0, 45, .. deg), rad, from height over length.
    NaN where a face's profile does not run from a top over a cut face to the flat (an
    uncut one: `rough_face`).
    unread : Mapping
        Why, for each NaN (keys ``"L1_L5"`` .. ``"L4_L8"``, ``"S1"`` .. ``"S8"``): which
        face's profile and what it found instead (`profile_reading`). Empty if all read.
    """

    edge_distances: np.ndarray
    inclinations: np.ndarray
    unread: Mapping[str, str] = field(default_factory=lambda: MappingProxyType({}))


def _line(s: np.ndarray, z: np.ndarray, keep: np.ndarray):
    keep = keep & np.isfinite(z)
    return np.polyfit(s[keep], z[keep], 1) if np.count_nonzero(keep) >= 3 else None


def _top_level(s: np.ndarray, z: np.ndarray, band: float, guard: float, reach: float,
               iterations: int) -> np.ndarray:
    """The top's line along a profile, from its start as far as the profile keeps to it.

    First the line of the first ``reach``; then refitted, ``iterations`` times, on the
    samples from the start to ``guard`` before the first that leaves it by more than
    ``band``. A top need not be level with the flat (a crown cut level on a tilted
    workpiece), and a gentle slope (1 um over 60, 3 um over 200) leaves a level by more
    than ``band`` before its edge."""
    head = _line(s, z, s < s[0] + reach)
    if head is None:
        return np.full_like(z, np.median(z[:10][np.isfinite(z[:10])]))
    level = np.polyval(head, s)
    for _ in range(iterations):
        off = np.flatnonzero(~(np.abs(z - level) <= band))
        line = _line(s, z, s < (float(s[off[0]]) if len(off) else np.inf) - guard)
        if line is None:
            break
        level = np.polyval(line, s)
    return level


def spot_clearance(spot) -> float:
    """How far (m) a foot cursor keeps before a wall seen through ``spot``
    (`machinesim.metrology.Spot`, or None: 0): `CLEARANCE_SIGMAS` sigmas of a Gaussian spot
    (its width is the full width at half maximum, sigma = width / (2 sqrt(2 ln 2)),
    0.425 um for the 10x's 1.0 um), half the side of a top-hat (which reads nothing of a
    step farther off than that)."""
    if spot is None:
        return 0.0
    if spot.shape == "tophat":
        return 0.5 * spot.width
    return CLEARANCE_SIGMAS * spot.width / (2.0 * math.sqrt(2.0 * math.log(2.0)))


def _corner(a: np.ndarray, b: np.ndarray) -> float:
    return float((b[1] - a[1]) / (a[0] - b[0]))


def _cursor(s: np.ndarray, z: np.ndarray, at: float) -> int:
    finite = np.flatnonzero(np.isfinite(z))
    return int(finite[np.argmin(np.abs(s[finite] - at))])


def profile_edges(s, z, *, pixel: bool, band: float, guard: float = EDGE_GUARD,
                  reach: float = EDGE_REACH, iterations: int = 4,
                  design: tuple[np.ndarray, float] | None = None,
                  clearance: float = 0.0) -> ProfileEdges | None:
    """The top edge and the foot of the face in a profile across it, levelled on the flat.

    Top edge: from where the profile first falls below the top's line (`_top_level`) by more
    than ``band`` (m; a few times the height noise), refined to the corner of two lines
    fitted to the samples either side of it, ``guard`` to ``reach`` away (the eye judges a
    corner by what is near it), ``iterations`` times. Where the level is first left upward
    (uncut stock standing above the top between it and the cut face), the top's line is
    fitted on the top up to ``reach`` before that and the edge is its corner with the face.
    Foot: where the profile leaves the face's line (refitted on what keeps to it) by more
    than ``band`` going out; if what follows runs on from the face (a ledge or the flat),
    the corner of the face's line and its line; if it steps away (an uncut band beyond the
    finished face), the face's last sample at least ``clearance`` (m) before the last that
    keeps to its line: the wall that band stands on lies beyond that, and its blur through
    the instrument's spot lifts the samples next to it (`spot_clearance`: a few sigmas of
    the spot; 0, the default, where no spot is known: the last that keeps to the line).
    ``pixel``: each cursor on the sample nearest
    its edge and the height read there (an operator reading an image); else the edges on
    the fitted lines. ``design``: the designed face's line along the profile (`np.polyfit`'s
    coefficients, heights above the flat, m) and the stock allowance (m); given, a face
    whose line lies where the rough face does is not read (`rough_face`). None where the
    profile does not run from a top down a cut face (`profile_reading` says why).
    """
    edges = profile_reading(s, z, pixel=pixel, band=band, guard=guard, reach=reach,
                            iterations=iterations, design=design, clearance=clearance)
    return edges if isinstance(edges, ProfileEdges) else None


def _um(length: float) -> str:
    return f"{length / UM:.3g} um"


def rough_face(out: float, allowance: float) -> str | None:
    """Why a face read ``out`` (m) from its design along its normal, outward positive, is
    the rough face left ``allowance`` (m) out and not a cut one (`ROUGH_FACE_FRACTION`), or
    None."""
    if out < ROUGH_FACE_FRACTION * allowance:
        return None
    return (f"lies {out / UM:.3f} um out from the design along its normal, the rough face "
            f"{_um(allowance)} (a cut face lies at or inside the design; "
            f"{ROUGH_FACE_FRACTION:g} of the allowance out or more is uncut): the face is not "
            "cut there")


def profile_reading(s, z, *, pixel: bool, band: float, guard: float = EDGE_GUARD,
                    reach: float = EDGE_REACH, iterations: int = 4,
                    design: tuple[np.ndarray, float] | None = None,
                    clearance: float = 0.0) -> ProfileEdges | str:
    """`profile_edges`, or where the profile does not run from a top down a face, what it
    found instead (a sentence: which edge or line could not be read, and why)."""
    clearance = as_number(clearance, "clearance", sign=">= 0")
    s, z = np.asarray(s, dtype=np.float64), np.asarray(z, dtype=np.float64)
    finite = np.isfinite(z)
    if np.count_nonzero(finite[:10]) < 5:
        return (f"no top: {10 - np.count_nonzero(finite[:10])} of the profile's first 10 "
                "samples read nothing (no surface under the objective at its start)")
    level = _top_level(s, z, band, guard, reach, iterations)
    off = np.flatnonzero(~(np.abs(z - level) <= band))
    below = np.flatnonzero(z < level - band)
    if len(below) == 0:
        length = _um(float(s[-1] - s[0]))
        if len(off) == 0:
            return (f"no top edge: the profile does not fall from the top down a face; it "
                    f"keeps within {_um(band)} of the top's line over its whole {length} "
                    "(the face is not cut there)")
        return (f"no top edge: the profile does not fall from the top down a face; it "
                f"leaves the top's line only upward (stock up to "
                f"{_um(float(np.nanmax(z - level)))} above it from {_um(float(s[off[0]]))} "
                f"along the profile on) and never falls {_um(band)} below it in its {length} "
                "(the face is not cut there)")
    # Where the top is followed by stock standing above it (a band the face's passes did
    # not reach), its line is fitted on the top ``reach`` clear of that band (whose rise may
    # begin below ``band``, as the top's pass ends leave it at a diagonal face) and the edge
    # is where the face below crosses it; otherwise the line is fitted next to the edge.
    ridge = below[0] != off[0]
    s_level_end, s_top = float(s[off[0]]), float(s[below[0]])
    clear = s < s_level_end - reach
    if np.count_nonzero(clear & finite) < 3:
        clear = s < s_level_end - guard
    for _ in range(iterations):
        top = _line(s, z, clear if ridge else (s > s_top - reach) & (s < s_top - guard))
        upper = _line(s, z, (s > s_top + guard) & (s < s_top + reach))
        if top is None or upper is None or top[0] == upper[0]:
            side = "the top" if top is None else "the face"
            return (f"no top edge near {_um(s_top)}, where the profile falls below the "
                    "top's line: "
                    + (f"{side} has fewer than 3 samples read within {_um(reach)} of it"
                       if top is None or upper is None else
                       "the top's line and the face's are parallel"))
        s_top = _corner(top, upper)
        if not s[0] < s_top < s[-1]:
            return (f"no top edge: the top's line and the face's meet at {_um(s_top)}, "
                    f"outside the profile ({_um(float(s[0]))} .. {_um(float(s[-1]))})")
    # the face: out from the top edge while the profile keeps to its line, the line refitted
    # on what keeps to it (a line fitted next to the edge drifts off a long face)
    face, s_end = upper, float(s[-1])
    for _ in range(iterations):
        on = (s > s_top + guard) & ~(np.abs(z - np.polyval(face, s)) > band)
        past = np.flatnonzero(~on & (s > s_top + reach))
        s_end = float(s[past[0]]) if len(past) else float(s[-1])
        face = _line(s, z, (s > s_top + guard) & (s < s_end - guard))
        if face is None:
            return (f"no face: the profile leaves the face's line at {_um(s_end)}, "
                    f"fewer than 3 samples read past the top edge at {_um(s_top)}")
    beyond = _line(s, z, (s > s_end + guard) & (s < s_end + reach))
    last = float(s[np.flatnonzero((s < s_end) & finite)[-1]])
    s_foot = last
    stepped = len(past) > 0  # the profile leaves the face's line (not its own end)
    if beyond is not None and beyond[0] != face[0]:
        corner = _corner(face, beyond)
        if last - reach < corner < s_end + reach and abs(
                np.polyval(beyond, corner) - np.polyval(face, corner)) <= band:
            # the foot's corner, refined as the top's: the face leaves its line by the band
            # only band / (its slope change) past the corner, more than ``guard`` at a foot
            # of 11 deg read with the 10x's noise
            for _ in range(iterations):
                inner = _line(s, z, (s > s_top + guard) & (s < corner - guard))
                outer = _line(s, z, (s > corner + guard) & (s < corner + reach))
                if inner is None or outer is None or inner[0] == outer[0]:
                    break
                face, corner = inner, _corner(inner, outer)
            s_foot, stepped = corner, False
    if design is not None:
        # the face's line against the design's, at the middle of the face as read
        line, allowance = design
        mid = 0.5 * (s_top + s_foot)
        out = float(np.polyval(face, mid) - np.polyval(line, mid)) * math.cos(
            math.atan(float(line[0])))
        if (why := rough_face(out, allowance)) is not None:
            return (f"the rough face: the face's line, read from the top edge at "
                    f"{_um(s_top)} to the foot at {_um(s_foot)} along the profile, {why}")
    if stepped and clearance > 0.0:
        # the foot cursor clear of the wall's blur: on the last face sample (one the face's
        # line was fitted on, guard past the top edge) ``clearance`` before the last sample
        # that keeps to the line
        clear = np.flatnonzero((s <= last - clearance) & (s > s_top + guard) & finite)
        if len(clear) == 0:
            return (f"no foot clear of the wall: the face steps away after its last sample "
                    f"on its line at {_um(last)}, and no sample of the face from the top "
                    f"edge at {_um(s_top)} on lies {_um(clearance)} (the spot's reach) "
                    "before it, where the wall's blur does not lift the height read")
        s_foot = float(s[clear[-1]])
    if not pixel:
        return ProfileEdges(s_top, float(np.polyval(top, s_top)), s_foot,
                            float(np.polyval(face, s_foot)))
    i, j = _cursor(s, z, s_top), _cursor(s, z, s_foot)
    return ProfileEdges(float(s[i]), float(z[i]), float(s[j]), float(z[j]))


def turned_placements(part) -> list:
    """The part turned by -k 45 deg, k = 0..3 (MeshIndex each): face k's outward direction
    along +x, as a stage turns the sample under the objective."""
    return [MeshIndex.from_surface(part if k == 0
                                   else Part(part.manifold.rotate((0.0, 0.0, -45.0 * k))))
            for k in range(4)]


#: Sides of a box `inscribed` takes as square may differ by this fraction of the larger
#: (a window built as centre -+ half size has sides a few ulps apart).
SQUARE_TOLERANCE = 1e-9


def inscribed(box, turn: float):
    """The axis-aligned box, in a frame turned by ``turn`` (rad) about Z, about the turned
    centre of the square ``box`` (x0, x1, y0, y1) that lies inside ``box`` at any turn: half
    sizes divided by sqrt(2) (its corners on the square's inscribed circle).

    Only a square keeps that at every turn: a 4 x 1 box turned 90 deg would give a box
    reaching 1.41 out along y against the box's 0.5, so a box whose sides differ by more
    than `SQUARE_TOLERANCE` of the larger is refused (InputError). Every window read so
    (`machinesim.cam.crown.crown_roi`'s top and flat patches) is square."""
    x0, x1, y0, y1 = box
    wide, high = x1 - x0, y1 - y0
    if not (wide > 0 and high > 0 and abs(wide - high) <= SQUARE_TOLERANCE * max(wide, high)):
        raise InputError(
            "expected a square box (x0, x1, y0, y1) with x1 > x0, y1 > y0 (m), got ("
            + ", ".join(f"{float(b):.9g}" for b in box) + f"): {float(wide):.9g} m by "
            f"{float(high):.9g} m; only a square's box divided by sqrt(2) stays inside it at "
            "every turn", key="box")
    c = rot_z(-turn)[:2, :2] @ np.array([(x0 + x1) / 2.0, (y0 + y1) / 2.0])
    hx, hy = (x1 - x0) / (2.0 * math.sqrt(2.0)), (y1 - y0) / (2.0 * math.sqrt(2.0))
    return (c[0] - hx, c[0] + hx, c[1] - hy, c[1] + hy)


def _bottom(mesh, microscope, flats, turn: float):
    """The plane fitted to the flat's patches read in this placement (the turned frame)."""
    points = []
    for box in flats:
        area = microscope.height_map(mesh, *inscribed(box, turn), spacing=FLAT_SPACING)
        points.append(height_map_points(area.x, area.y, area.z))
    return fit_plane(np.vstack(points))


def _levelled(read, bottom) -> np.ndarray:
    """A profile's heights above the bottom plane (its tilt and height taken out)."""
    xy = read.xy
    n, p = bottom.normal, bottom.point
    return read.z - (p[2] - (n[0] * (xy[:, 0] - p[0]) + n[1] * (xy[:, 1] - p[1])) / n[2])


def _face_edges(mesh, microscope, bottom, sign: float, vs, image, design) -> list:
    """One image of a face (one placement): its profiles at ``vs`` read outward from inside
    the top edge across the foot; ``sign`` -1 for the face on -x; ``design`` as
    `profile_reading`'s. Returns, per profile,
    the top edge point (x, y) and the `ProfileEdges` (NaN and why, `profile_reading`, where
    unreadable)."""
    r0, r1 = image[0], image[1]
    pixel = microscope.spot is not None
    band = BAND_SIGMAS * microscope.readout.sigma + BAND_FLOOR
    clearance = spot_clearance(microscope.spot)  # the objective's resolution, as published
    out = []
    with microscope.placement():
        for v in vs:
            start, end = sign * np.array([r0, v]), sign * np.array([r1, v])
            read = microscope.profile(mesh, start, end)
            edges = profile_reading(read.s, _levelled(read, bottom), pixel=pixel, band=band,
                                    design=design, clearance=clearance)
            point = (np.full(2, np.nan) if isinstance(edges, str)
                     else start + (end - start) / (r1 - r0) * edges.s_top)
            out.append((point, edges))
    return out


def _face(j: int) -> str:
    return f"face S{j + 1} (C = {45 * j} deg)"


def _point_to_line(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    d = (b - a) / np.hypot(*(b - a))
    w = q - a
    return float(abs(w[0] * d[1] - w[1] * d[0]))


def crown_image_reading(part, microscope, windows, plan, *, meshes=None,
                        repeats: int = REPEATS) -> CrownImageReading:
    """Read L and S of paper 002's crown as the paper does (module docstring).

    Parameters
    ----------
    part : Part
        The machined crown (workpiece frame, m).
    microscope : Microscope
        Best the lab's at `machinesim.realism.OBJECTIVE_10X`
        (``lab.microscope(objective=OBJECTIVE_10X)``).
    windows : dict
        `machinesim.cam.crown.crown_roi`'s: ``"image"`` (r0, r1, v0, v1) and ``"flat"``.
    plan : CrownPlan
        The designed crown (its apothem: L's design; its faces and allowance: a face whose
        profile lies where the rough face does is not read, `rough_face`).
    meshes : list, optional
        `turned_placements` of ``part``, if already built.
    """
    meshes = turned_placements(part) if meshes is None else meshes
    image = windows["image"]
    a = 0.8 * min(-image[2], image[3])  # the two points on an edge, v = -a and +a
    # the designed face along a profile (s = r - image[0]), above the flat: the top edge at
    # the apothem, the foot one run farther out
    rise = math.tan(plan.slope)
    design = (np.array([-rise, (plan.apothem + plan.run - image[0]) * rise]), plan.oversize)
    lengths, inclinations, unread = np.zeros((4, repeats)), np.zeros(8), {}
    for k in range(4):
        bottom = _bottom(meshes[k], microscope, windows["flat"], k * math.pi / 4)
        missed = {}  # the top edge profiles L_k needs, not read: why, in each reading
        for n in range(repeats):
            near = _face_edges(meshes[k], microscope, bottom, 1.0, (-a, 0.0, a), image, design)
            far = _face_edges(meshes[k], microscope, bottom, -1.0, (0.0,), image, design)
            lengths[k, n] = _point_to_line(far[0][0], near[0][0], near[2][0])
            for j, v, (_, edges) in ((k, -a, near[0]), (k, a, near[2]), (k + 4, 0.0, far[0])):
                if isinstance(edges, str):
                    missed.setdefault((j, v), []).append(edges)
            for j, (_, edges) in ((k, near[1]), (k + 4, far[0])) if n == 0 else ():
                if isinstance(edges, str):
                    inclinations[j] = np.nan
                    unread[f"S{j + 1}"] = f"{_face(j)}, the profile across its middle: {edges}"
                else:
                    inclinations[j] = edges.inclination
        if missed:
            unread[f"L{k + 1}_L{k + 5}"] = "; ".join(
                f"{_face(j)}, the profile across "
                + ("its middle" if v == 0.0 else f"it at {v / UM:+.0f} um along its edge")
                + f" (not read in {len(whys)} of {repeats} readings): {whys[0]}"
                for (j, v), whys in missed.items())
    return CrownImageReading(frozen(lengths.mean(axis=1)), frozen(inclinations),
                             MappingProxyType(unread))
