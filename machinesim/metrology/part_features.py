"""Features of paper 002's machined parts, read with the laser microscope.

`groove_depths`: the depths along four grooves cut from a common point (paper 002, Fig. 8b),
below the top face fitted between them. `crown_features`: the edge distances L and side-face
inclinations S of an octagonal crown (Table 3, Fig. 12) from planes fitted to height maps in
measuring windows (`machinesim.cam.crown.crown_roi`). Both take a part and a microscope
(`machinesim.Lab.microscope`) and return what was read; `machinesim.procedures.
workpiece_setting` calls them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np

from machinesim.arrays import frozen
from machinesim.metrology.crown_image import inscribed, rough_face, turned_placements
from machinesim.metrology.fits import fit_plane, height_map_points, plane_angle
from machinesim.metrology.planes import line_distance, plane_intersection
from machinesim.rotations import rot_z
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = ["MAP_SPACING", "STATIONS", "UNCUT_DEPTH", "CrownFeatures", "GrooveDepths",
           "crown_features", "groove_depths"]

MM, UM = M_PER_MM, M_PER_UM

# ------------------------------------------------------------------------------ grooves

#: Stations along each groove where its depth is read (m from the crossing point); 0.95 mm
#: is the paper's "end of each groove".
STATIONS = (0.5 * MM, 0.6 * MM, 0.7 * MM, 0.8 * MM, 0.9 * MM, 0.95 * MM)
#: Half length of a profile across a groove, and the fitted stretch about its bottom, m: a
#: R2 mm groove 30 um deep is 0.7 mm wide; 25 um either side of the bottom rises 0.16 um.
PROFILE_HALF, BOTTOM_HALF = 0.35 * MM, 25 * UM
#: Patches of the uncut top face between the grooves, centre distance from the crossing
#: along the diagonals and half size, m: the reference surface for the depths.
PATCH_AT, PATCH_HALF = 0.75 * MM, 0.15 * MM
#: A station read shallower than this (m) holds no groove the tool cut: its profile's
#: lowest stretch is the top face's noise (a block set 5 um low, its grooves not cut at all,
#: read -2 .. +4 nm with the lab's 12 nm microscope), not a depth (`GrooveDepths.uncut`).
UNCUT_DEPTH = 0.05 * UM


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

    @property
    def uncut(self) -> np.ndarray:
        """Where no groove was cut, shape (4, n): the stations read shallower than
        `UNCUT_DEPTH`, the top face's own noise (the tool above the face there)."""
        return ~(self.depths >= UNCUT_DEPTH)


def groove_depths(part, microscope, stations=STATIONS) -> GrooveDepths:
    """Read each groove's depth along it with the microscope (paper 002 Fig. 8b).

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
    return GrooveDepths(frozen(stations), frozen(depths))


# -------------------------------------------------------------------------------- crown

#: Sample spacing of the crown's height maps, m: about a tenth of the 12.5 um pitch feed, and
#: chosen so an 11.31 deg face (tan = 0.2) rises 248.618 nm a sample, not a whole number of
#: nm: on 2.5 um (500 nm a sample) the microscope's 1 nm rounding, without noise, rounds every
#: sample of a row alike and the fitted inclination locks onto the rounding (measured: 3e-5
#: deg on one face for a 0.1 nm shift of the cut); here the rounding averages out (1e-7 deg).
MAP_SPACING = 1.24309 * UM

#: A side plane whose angle to the flat is farther than this from the designed slope is not
#: a cut face's reading, rad. A cut face reads the design plus the workpiece's tilt against
#: the flat (the default crown: 11.31 deg + 1.93 deg cos(theta_k - 90 deg), read 10.07 ..
#: 13.21 deg; the paper's largest "before" error 2.30 deg): 5 deg is more than twice that.
#: The probe's capture does not bound it more tightly: spheres 8.5 mm out, 0.34 mm of
#: sideways reach and a bottom touch from 0.3 mm above a 2 mm sphere find a crown tilted up
#: to 13.8 deg, more than the 11.31 deg that separates a face from the flat. A window on
#: uncut stock reads 0.0 .. 0.3 deg (--delta-um 300,0,55: S2, S4, S5, S6).
FACE_SLOPE_TOLERANCE = math.radians(5.0)
#: A side plane whose residual RMS exceeds this is not a cut face's reading, m: a cut face's
#: window reads 12-13 nm (its scallops and the microscope's noise), one that takes in a band
#: of uncut stock 0.25 .. 20 um (the default crown before: S4 1.9, S5 16, S6 2.4, S7 0.25
#: um; --delta-um 300,0,55: S2 16, S8 21 um).
FACE_RMS_LIMIT = 0.1 * UM


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
    NaN where a face's window does not hold a cut face (`face_unread`).
    unread : Mapping
        Why, for each NaN (keys ``"L1_L5"`` .. ``"L4_L8"`` for the edge and foot distances,
        ``"S1"`` .. ``"S8"``), as `CrownImageReading.unread`. Empty if all read.
    """

    edge_distances: np.ndarray
    inclinations: np.ndarray
    foot_distances: np.ndarray
    unread: Mapping[str, str] = field(default_factory=lambda: MappingProxyType({}))


def _map_points(part, microscope, box, spacing: float) -> np.ndarray:
    area = microscope.height_map(part, *box, spacing=spacing)
    return height_map_points(area.x, area.y, area.z)


def _turned_back(points, back: np.ndarray):
    """The plane fitted to ``points`` of a placement turned on the stage, in the part's
    frame (``back``: the turn back, 3 x 3)."""
    local = fit_plane(points)
    return replace(local, point=frozen(back @ local.point), normal=frozen(back @ local.normal))


def _height(plane, xy) -> float:
    """The plane's z over the point ``xy``."""
    n, p = plane.normal, plane.point
    return float(p[2] - (n[0] * (xy[0] - p[0]) + n[1] * (xy[1] - p[1])) / n[2])


def face_out(j: int, side, flat, plan, centre) -> float:
    """How far face S(j + 1)'s fitted plane ``side`` lies out from the designed face of
    ``plan`` (a `machinesim.cam.crown.CrownPlan`) along its normal, m, outward positive: its
    height above the fitted ``flat`` (the flat left as roughed, the design's too) at the
    window's ``centre`` (r out from the C axis, v along the edge, m) less the design's
    there, times cos(slope)."""
    u = np.array([math.cos(j * math.pi / 4), math.sin(j * math.pi / 4)])
    xy = centre[0] * u + centre[1] * np.array([-u[1], u[0]])
    rise = math.tan(plan.slope)
    designed = (plan.apothem + plan.run - centre[0]) * rise
    return (_height(side, xy) - _height(flat, xy) - designed) * math.cos(plan.slope)


def face_unread(j: int, side, flat, slope: float, *, plan=None,
                centre=None) -> str | None:
    """Why face S(j + 1)'s fitted plane ``side`` is not a cut face's reading, or None: its
    angle to ``flat`` more than `FACE_SLOPE_TOLERANCE` off the designed ``slope`` (rad), its
    residual RMS above `FACE_RMS_LIMIT` (the window holds uncut stock as well), or, given
    the ``plan`` and the window's ``centre`` (`face_out`), it lying where the rough face does
    (`ROUGH_FACE_FRACTION` of the allowance out or more, `rough_face`)."""
    angle = plane_angle(side, flat)
    where = f"face S{j + 1} (C = {45 * j} deg), the plane fitted in its window"
    if abs(angle - slope) > FACE_SLOPE_TOLERANCE:
        return (f"{where}: fitted slope {math.degrees(angle):.2f} deg, designed "
                f"{math.degrees(slope):.4g} (more than {math.degrees(FACE_SLOPE_TOLERANCE):g} "
                "deg off): the face is not cut there")
    if side.residual_rms > FACE_RMS_LIMIT:
        return (f"{where}: residual RMS {side.residual_rms / UM:.3g} um, a cut face's "
                f"{FACE_RMS_LIMIT / UM:g} um or less (fitted slope "
                f"{math.degrees(angle):.2f} deg): the window holds uncut stock as well")
    if plan is not None and (why := rough_face(face_out(j, side, flat, plan, centre),
                                               plan.oversize)) is not None:
        return f"{where}: the rough face: it {why}"
    return None


def crown_features(part, microscope, windows, spacing: float = MAP_SPACING, *,
                   meshes=None, slope: float | None = None, plan=None) -> CrownFeatures:
    """Read Table 3's quantities with the microscope (paper 002 Fig. 12).

    Planes are fitted to height maps in the ``windows`` of `machinesim.cam.crown.crown_roi`:
    the top face, each side face and four patches of the flat. Each pair of opposite faces
    (k, k + 4) is read in one placement of the sample, turned on the stage by k 45 deg so
    that the faces' own axes (r out, v along the edge) are the map's: the top, both faces
    and the flat's patches (their largest boxes that stay inside the windows at any turn,
    `_inscribed`), so that the edge distance L_k and the foot distance come from one
    placement, as the paper reads two opposite edges in one image. Read in placements turned
    apart, they would carry the instrument's registration (its offset from the part's
    origin, several um) twice, turned: a stage's turn is about its own axis, not the part's.
    A map's cost grows with the triangles' boxes, which the long scallop triangles of a face
    at 45 deg make large: hence the turn. ``spacing``: see `MAP_SPACING`. ``meshes``: the
    part's `machinesim.metrology.crown_image.turned_placements`, if already built.
    ``slope``: the faces' designed slope (rad); given, a face whose plane is not a cut face's
    (`face_unread`) leaves its S, L and foot distance NaN with the reason in ``unread``.
    ``plan``: the designed crown (`machinesim.cam.crown.CrownPlan`; its slope if ``slope``
    is not given); given, so does a face whose plane lies where the rough face does.
    """
    meshes = turned_placements(part) if meshes is None else meshes
    r0, r1, v0, v1 = windows["side"]
    sides, flats, tops = [None] * 8, [None] * 8, [None] * 8
    for k in range(4):
        turn = k * math.pi / 4
        mesh = meshes[k]
        back = rot_z(turn)
        top = _turned_back(_map_points(mesh, microscope, inscribed(windows["top"], turn),
                                       spacing), back)
        flat = _turned_back(np.vstack([_map_points(mesh, microscope, inscribed(box, turn),
                                                   4 * spacing) for box in windows["flat"]]),
                            back)
        for j, box in ((k, (r0, r1, v0, v1)), (k + 4, (-r1, -r0, -v1, -v0))):
            sides[j] = _turned_back(_map_points(mesh, microscope, box, spacing), back)
            flats[j], tops[j] = flat, top
    slope = plan.slope if slope is None and plan is not None else slope
    centre = (0.5 * (r0 + r1), 0.5 * (v0 + v1))
    faces = {} if slope is None else {
        j: why for j in range(8)
        if (why := face_unread(j, sides[j], flats[j], slope, plan=plan, centre=centre))}
    inclinations = np.array([plane_angle(side, flat) for side, flat in zip(sides, flats,
                                                                           strict=True)])
    lengths, foot, unread = np.full(4, np.nan), np.full(4, np.nan), {}
    for j, why in faces.items():
        inclinations[j] = np.nan
        unread[f"S{j + 1}"] = why
    for k in range(4):
        if whys := [faces[j] for j in (k, k + 4) if j in faces]:
            # no lines: an uncut face's plane may lie parallel to the top and the flat
            unread[f"L{k + 1}_L{k + 5}"] = "; ".join(whys)
            continue
        lengths[k] = line_distance(*(plane_intersection(tops[j], sides[j])
                                     for j in (k, k + 4)))
        foot[k] = line_distance(*(plane_intersection(flats[j], sides[j])
                                  for j in (k, k + 4)))
    return CrownFeatures(frozen(lengths), frozen(inclinations), frozen(foot),
                         MappingProxyType(unread))
