"""Cutting tools as convex bodies of their full height, in the ``tool_tip`` frame (metres).

Every tool has its edge point at the origin and points along -Z: its body lies at
0 <= z <= ``height``, and the holder begins at z = ``height``. A cut of any depth up to
``height`` is therefore exact, with no hidden tunnel above a short profile; where the top of
the body (the holder's face) comes below the top of the stock the engine reports holder
contact (`machinesim.cutting.EngineReport.holder_contact`), since the holder itself is not
modelled.

A non-rotational tool (V, round nose) cuts along its frame's +X axis; its cutting edge is a
profile in the tool's Y-Z plane, continued up to the holder: the flanks rise to
``flank_height`` (by default all the way), then straight shank sides as wide as the flanks'
top rise to ``height``. The profile has zero thickness along X on purpose: the prism of the
profile at the two ends of a linear move is then the exact volume swept by the edge, with no
body behind the edge that a real tool clears with its clearance angle. The consequence at
groove ends: where a move starts or stops inside the material, the simulated groove ends in
the flat plane of the profile, whereas a real tool's body (rake and clearance faces) would
also leave its shape there. A move inside the profile plane (a sideways drag, a plunge)
sweeps no volume with a zero-thickness profile: the engine flags those moves.

A ball end mill is modelled by its rotating envelope: a hemisphere of radius R about
(0, 0, R) under a cylindrical shank of the same radius up to ``height``; a flat end mill by
a cylinder of radius R standing on its end face at the origin.

Arcs and spheres are inscribed polygons whose vertices lie on the true surface; the chord
tolerance (the sagitta between a chord and its arc) is a parameter of each tool. The ball's
polygon is a stack of rings of latitude, so that its volume has a closed form (a sum of
frusta of regular pyramids, `BallEndMill.rings`).

Ball and flat end mills are in `machinesim.end_mills`; a tool's default height and the
bounds on its sizes (`MIN_TOOL_SIZE_M`, `MAX_TOOL_SIZE_M`, `MAX_TOOL_VERTICES`) in
`machinesim.tool_sizes`: a tool smaller than the engine resolves, larger than the machines,
or a polygon of millions of vertices is an input error, refused with `InputError`. All are
importable from here.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import manifold3d
import numpy as np

from machinesim.end_mills import BallEndMill, FlatEndMill, ring_facet_depth
from machinesim.exceptions import InputError
from machinesim.tolerances import (
    CHORD_TOLERANCE_M,
    PATH_CHORD_SHARE,
    PROFILE_CHORD_M,
)
from machinesim.tool_sizes import (
    _MIN_SHORT,
    MAX_TOOL_SIZE_M,
    MAX_TOOL_VERTICES,
    MIN_TOOL_SIZE_M,
    TOOL_HEIGHT_M,
    _bound,
    _check_angle,
    _check_count,
    _check_positive,
    _check_size,
)
from machinesim.units import LENGTH, M_PER_NM, angle_text, length_text

# BallEndMill, FlatEndMill and the bounds are defined in end_mills and tool_sizes, and
# importable from here, where they were until those modules were split off.
__all__ = ["MAX_TOOL_SIZE_M", "MAX_TOOL_VERTICES", "MIN_TOOL_SIZE_M", "TOOL_HEIGHT_M",
           "BallEndMill", "FlatEndMill", "RoundNoseTool", "Tool", "VTool", "arc_segments",
           "NoseRadiusMisfit", "flat_face_radius", "path_chord_tolerance", "ring_facet_depth",
           "sphere_polygon", "with_nose_radius_error"]


class NoseRadiusMisfit(InputError):
    """`with_nose_radius_error` refuses a tool the error model's nose radius error does not
    fit. ``tool`` is the tool as given (commanded, without the error), ``has_radius`` whether
    it has a radius at all (a V tool has not): what `machinesim.Lab` tells instead of the
    message, which names the error (the lab's truth)."""

    def __init__(self, message: str, *, tool, has_radius: bool, **where) -> None:
        super().__init__(message, **where)
        self.tool = tool
        self.has_radius = has_radius


def arc_segments(radius: float, angle: float, chord_tol: float) -> int:
    """Fewest equal segments of an arc whose chords stay within ``chord_tol`` of it.

    Parameters
    ----------
    radius : float
        Arc radius (m).
    angle : float
        Arc span (rad).
    chord_tol : float
        Largest allowed sagitta (m): ``radius * (1 - cos(step / 2)) <= chord_tol``.

    Returns
    -------
    int
        Segment count, at least 1.
    """
    if chord_tol >= radius:
        return max(1, math.ceil(angle / math.pi))
    step = 2.0 * math.acos(1.0 - chord_tol / radius)
    return max(1, math.ceil(angle / step - 1e-12))


def _flank_height(tool, top_half_width) -> float:
    """``tool.flank_height`` checked, or its default: the full height, or lower where the
    flanks' top would be wider than `MAX_TOOL_SIZE_M` (an included angle near 180 deg).
    The flanks' top must be at least `MIN_TOOL_SIZE_M` wide (`_check_top_width`)."""
    height = _unchecked_flank_height(tool, top_half_width)
    _check_top_width(tool, 2.0 * top_half_width(height), height)
    return height


def _check_top_width(tool, width: float, height: float) -> None:
    """Refuse flanks whose top, at ``height``, is narrower than `MIN_TOOL_SIZE_M`: a V of
    1e-9 deg (flanks 1.7e-13 m apart 10 mm up) cut nothing of a 6 mm groove inside a 10 mm
    block, one of 1e-7 deg (1.7e-11 m) 1.4e-5 of it too little."""
    if width < MIN_TOOL_SIZE_M:
        raise InputError(
            f"included_angle {angle_text(tool.included_angle)} leaves the flanks "
            f"{length_text(width)} apart at their top, {length_text(height)} up; they must be "
            f"at least {_bound(MIN_TOOL_SIZE_M, _MIN_SHORT)} apart: give a wider included "
            "angle or higher flanks",
            key="included_angle")


def _refuse_flat_flanks(tool, height: float) -> None:
    """Refuse an included angle whose flanks are `MAX_TOOL_SIZE_M` apart ``height`` (under
    `MIN_TOOL_SIZE_M`) above the edge point, where their default top stops them: 'nose:1:1e-9'
    made a blade 1 m wide and 4.4e-12 m high, though a flank_height that low is refused."""
    # a V's flanks open with its angle, a nose's tangent flanks as the arc's angle closes
    wider = "smaller" if isinstance(tool, VTool) else "larger"
    raise InputError(
        f"included_angle {angle_text(tool.included_angle)} opens the flanks "
        f"{_bound(MAX_TOOL_SIZE_M, 'MAX_TOOL_SIZE_M, where their default top stops them')} "
        f"apart {length_text(height)} above the edge point, under "
        f"{_bound(MIN_TOOL_SIZE_M, _MIN_SHORT)}: a blade, not a tool; give a {wider} "
        "included angle", key="included_angle")


def _unchecked_flank_height(tool, top_half_width) -> float:
    if tool.flank_height is None:
        height = tool.height
        if 2.0 * top_half_width(height) > MAX_TOOL_SIZE_M:
            low, high = 0.0, height
            for _ in range(200):  # bisection to float64 resolution: the width is monotonic
                middle = 0.5 * (low + high)
                if 2.0 * top_half_width(middle) > MAX_TOOL_SIZE_M:
                    high = middle
                else:
                    low = middle
            height = low
            if height < MIN_TOOL_SIZE_M:
                _refuse_flat_flanks(tool, height)
        return height
    value = _check_size("flank_height", tool.flank_height)
    if value > tool.height:
        raise InputError(f"flank_height {length_text(value)} must not exceed the height, "
                         f"{length_text(tool.height)}", key="flank_height")
    if 2.0 * top_half_width(value) > MAX_TOOL_SIZE_M:
        raise InputError(
            f"the flanks are {length_text(2.0 * top_half_width(value))} wide at flank_height "
            f"{length_text(value)}, over {_bound(MAX_TOOL_SIZE_M, 'MAX_TOOL_SIZE_M')}; give a "
            "lower flank_height", key="flank_height")
    return value


def _polygon_edges(count: int) -> np.ndarray:
    index = np.arange(count, dtype=np.int64)
    return np.stack([index, (index + 1) % count], axis=1)


def _profile_points(yz: np.ndarray) -> np.ndarray:
    """Profile polygon in the Y-Z plane (k, 2) -> points (k, 3) with x = 0, read-only."""
    points = np.zeros((len(yz), 3))
    points[:, 1:] = yz
    points.flags.writeable = False
    return points


def _with_shank(yz: np.ndarray, flank_height: float, height: float) -> np.ndarray:
    """Profile (from the -Y flank top round to the +Y one) with straight shank sides from
    the flanks' top at ``flank_height`` up to ``height``, when it is higher."""
    if height <= flank_height:
        return yz
    half = yz[-1, 0]
    return np.vstack([[-half, height], yz, [half, height]])


@dataclass(frozen=True)
class VTool:
    """V (prism) tool: flanks at +-included_angle/2 from -Z from the edge point up to
    ``flank_height``, then straight shank sides up to ``height``, where the holder begins.

    Parameters
    ----------
    included_angle : float
        Included angle of the V (rad), in (0, pi). An included-angle error is part of it.
    height : float
        Length of the body from the edge point to the holder (m), `TOOL_HEIGHT_M` by default.
    flank_height : float, optional
        Height the flanks reach (m), at most ``height``. Default: ``height``, or lower where
        the flanks' top would be wider than `MAX_TOOL_SIZE_M`.
    """

    included_angle: float
    height: float = TOOL_HEIGHT_M
    flank_height: float | None = None
    rotational = False
    planar = True

    def __post_init__(self) -> None:
        _check_angle("included_angle", self.included_angle)
        _check_size("height", self.height)
        tangent = math.tan(self.included_angle / 2.0)
        object.__setattr__(self, "flank_height",
                           _flank_height(self, lambda h: h * tangent))

    def vertices(self) -> np.ndarray:
        """Profile corners (m), shape (3, 3), or (5, 3) with a shank: the edge point, then
        round the polygon up the -Y side (flank top, shank top) and down the +Y side."""
        half = self.flank_height * math.tan(self.included_angle / 2.0)
        yz = np.array([[-half, self.flank_height], [0.0, 0.0], [half, self.flank_height]])
        yz = _with_shank(yz, self.flank_height, self.height)
        # The edge point first, then up the -Y side: the polygon read backwards and rotated.
        yz = yz[::-1]
        start = int(np.flatnonzero(np.all(yz == 0.0, axis=1))[0])
        return _profile_points(np.roll(yz, -start, axis=0))

    def edges(self) -> np.ndarray:
        """Index pairs of the profile's edges into `vertices`, shape (k, 2) int64."""
        return _polygon_edges(len(self.vertices()))

    def with_errors(self, included_angle_error: float = 0.0) -> VTool:
        """The same tool with its included angle off by ``included_angle_error`` (rad)."""
        return replace(self, included_angle=self.included_angle + included_angle_error,
                       flank_height=None if self.flank_height == self.height
                       else self.flank_height)


@dataclass(frozen=True)
class RoundNoseTool:
    """Round-nose tool: an arc of radius R centred at (0, 0, R), then tangent straight flanks
    up to ``flank_height``, then straight shank sides up to ``height``.

    The arc spans +-included_angle/2 about -Z and the flanks continue tangentially; where the
    arc already rises above ``flank_height`` the profile is the arc cut by that plane.

    Parameters
    ----------
    nose_radius : float
        Nose radius (m). A nose-radius error dR is part of it: ``RoundNoseTool(R + dR, ...)``.
    included_angle : float
        The angle the nose arc subtends (rad), in (0, pi): the arc spans +-included_angle/2
        about -Z. The flanks continue tangent to it, so between them they make pi -
        included_angle: the same as the arc only at 90 deg, the angle every shipped use
        takes (a `VTool`'s included angle is the angle between its flanks).
    height : float
        Length of the body from the edge point to the holder (m).
    chord_tol : float
        Largest sagitta of the arc polygon (m); vertices lie on the true arc.
    flank_height : float, optional
        Height the arc and flanks reach (m), at most ``height`` (default as `VTool`).
    """

    nose_radius: float
    included_angle: float
    height: float = TOOL_HEIGHT_M
    chord_tol: float = PROFILE_CHORD_M
    flank_height: float | None = None
    rotational = False
    planar = True

    def __post_init__(self) -> None:
        _check_size("nose_radius", self.nose_radius)
        _check_angle("included_angle", self.included_angle)
        _check_size("height", self.height)
        _check_positive("chord_tol", self.chord_tol)
        object.__setattr__(self, "flank_height", _flank_height(self, self._half_width))
        end = min(self.included_angle / 2.0, self._arc_end(self.flank_height))
        _check_count("nose arc", 2 * arc_segments(self.nose_radius, end, self.chord_tol) + 1,
                     self.chord_tol)

    def _arc_end(self, level: float) -> float:
        """Angle from -Z at which the arc reaches ``level`` (pi / 2 above the centre)."""
        return math.acos(max(-1.0, 1.0 - level / self.nose_radius))

    def _half_width(self, level: float) -> float:
        """Half width of the profile at ``level`` above the edge point (m).

        Above the arc a flank leaves it along its tangent, (cos end, sin end) in (y, z) as
        `_nose_profile` draws it, so it widens by 1 / tan(end) per unit of height: by
        tan(end), as this had it, the half width was right at 90 deg only, and the flanks'
        default top (`MAX_TOOL_SIZE_M`) wrong elsewhere ('nose:1:0.1' made a tool 22.9 m
        wide, 'nose:0.5:179' stopped its flanks at 4.85 mm, taking them for 1 m wide)."""
        radius, end = self.nose_radius, self.included_angle / 2.0
        arc_top = radius * (1.0 - math.cos(end))
        if level <= arc_top:
            return radius * math.sin(self._arc_end(level))
        return radius * math.sin(end) + (level - arc_top) / math.tan(end)

    def vertices(self) -> np.ndarray:
        """Profile polygon from the -Y top round to the +Y top, shape (k, 3) (m).

        The edge point (0, 0, 0) is always a vertex.
        """
        return _nose_profile(self.nose_radius, self.included_angle, self.flank_height,
                             self.height, self.chord_tol)

    def edges(self) -> np.ndarray:
        """Index pairs of the profile's edges into `vertices`, shape (k, 2) int64."""
        return _polygon_edges(len(self.vertices()))

    def with_errors(
        self, nose_radius_error: float = 0.0, included_angle_error: float = 0.0
    ) -> RoundNoseTool:
        """The same tool with nose radius and included angle off by the given errors (m, rad)."""
        return replace(
            self,
            nose_radius=self.nose_radius + nose_radius_error,
            included_angle=self.included_angle + included_angle_error,
            flank_height=None if self.flank_height == self.height else self.flank_height,
        )


@functools.lru_cache(maxsize=32)
def _nose_profile(radius: float, included_angle: float, flank_height: float, height: float,
                  chord_tol: float) -> np.ndarray:
    end = included_angle / 2.0
    arc_top = radius * (1.0 - math.cos(end))
    if arc_top > flank_height:
        end = math.acos(1.0 - flank_height / radius)
    # An even count keeps phi = 0, the edge point, exactly on a vertex.
    half = arc_segments(radius, end, chord_tol)
    phi = np.linspace(-end, end, 2 * half + 1)
    phi[half] = 0.0
    yz = np.stack([radius * np.sin(phi), radius * (1.0 - np.cos(phi))], axis=1)
    if arc_top > flank_height:
        yz[[0, -1], 1] = flank_height
    else:
        rise = (flank_height - arc_top) / math.sin(end)
        top = yz[-1] + rise * np.array([math.cos(end), math.sin(end)])
        top[1] = flank_height
        yz = np.vstack([[-top[0], flank_height], yz, top])
    return _profile_points(_with_shank(yz, flank_height, height))


@functools.lru_cache(maxsize=16)
def sphere_polygon(radius: float, chord_tol: float) -> manifold3d.Manifold:
    """Sphere polygon about the origin, vertices on the sphere, facets within ``chord_tol``.

    manifold3d's geodesic sphere puts its vertices on the sphere; the segment count (a
    multiple of 4) starts from the arc formula and grows until the measured facet depth
    (radius minus the least facet-plane distance from the centre) is within tolerance.
    Used for stock features (reference spheres); tools use `BallEndMill`'s rings.

    Parameters
    ----------
    radius, chord_tol : float
        Sphere radius and largest facet depth (m).
    """
    segments = 4 * math.ceil(arc_segments(radius, 2.0 * math.pi, chord_tol) / 4)
    while True:
        sphere = manifold3d.Manifold.sphere(radius, segments)
        mesh = sphere.to_mesh64()
        corner = np.asarray(mesh.vert_properties[:, :3])[np.asarray(mesh.tri_verts)]
        normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        if radius - np.min(np.einsum("ij,ij->i", normal, corner[:, 0])) <= chord_tol:
            return sphere
        segments += 4 * math.ceil(segments / 16)


Tool = VTool | RoundNoseTool | BallEndMill | FlatEndMill


def path_chord_tolerance(tools) -> float:
    """The chord tolerance (m) of the polygons a cut with ``tools`` makes of its arcs and
    rotary moves: `PATH_CHORD_SHARE` (a tenth) of the finest facet tolerance (``chord_tol``)
    among them, and never below `CHORD_TOLERANCE_M` (1 nm, the axes' resolution).

    A V tool, drawn exactly, and a nose, drawn within 1 nm, give 1 nm; a ball or flat end
    mill drawn within 1 um gives 100 nm, so that the path's polygon never adds more than a
    tenth to the tool's own and the cut is not split a thousand times finer than its tool
    is drawn.
    """
    finest = min((getattr(tool, "chord_tol", 0.0) for tool in tools), default=0.0)
    return max(CHORD_TOLERANCE_M, PATH_CHORD_SHARE * finest)


def flat_face_radius(tools) -> float:
    """Half-width (m) of the widest flat face normal to the tool axis among ``tools``: a
    flat end mill's end face, its radius; 0 without one. A move that tilts such a face is
    split finer than its vertices' chords ask (`machinesim.motion.faces`): as the hull of
    two poses, a face tilted by d per sub-step cut a * d / 2 below its true sweep (1.9 um
    under `flat:0.5` on a 4th axis at the default 100 nm)."""
    return max((float(tool.radius) for tool in tools if isinstance(tool, FlatEndMill)),
               default=0.0)


#: The finest path chord tolerance a cut takes (m): the machines' 1 nm axis resolution
#: (`CHORD_TOLERANCE_M`), the finest any of them follows a path, and the finest the tools
#: are drawn (a nose within 1 nm, `PROFILE_CHORD_M`). Float64 at 10 m of travel (2e-15 m)
#: and the engine's booleans (1e-14 m on a 10 mm block) resolve far finer, so the bound is
#: not theirs; but chords finer than the axes change the part by less than the machine can,
#: while their number grows as 1 / sqrt(chord): a 3 mm half circle with ball:0.5 is 1,364
#: sweeps at 1 nm (40 s), 13,607 at 0.01 nm and 1.36 million at 1e-6 nm, which ran on
#: without a word.
MIN_PATH_CHORD_M = CHORD_TOLERANCE_M
#: The coarsest path chord tolerance (m): 1 m, more than any shipped machine travels on an
#: axis (as `MAX_TOOL_SIZE_M` bounds a tool); a 4 mm circle at 1e21 m was cut as a hexagon.
MAX_PATH_CHORD_M = 1.0


def check_path_chord(value, name: str = "chord_tolerance", unit: str = "m",
                     symbol: str | None = None) -> float:
    """``value`` (in ``unit``, a `machinesim.units.LENGTH` name) as a path chord tolerance
    in m, or an InputError naming ``name`` (the argument or option) when it is not a number
    from `MIN_PATH_CHORD_M` to `MAX_PATH_CHORD_M`.

    The Python API (``chord_tolerance``, m) and the command line (``--chord-nm``, nm,
    ``symbol`` its metavar ``NM``) refuse with the same words, in their own unit.
    """
    factor = LENGTH[unit]
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not MIN_PATH_CHORD_M <= number * factor <= MAX_PATH_CHORD_M:
        raise InputError(
            f"{name} {value!r}: expected a length in {unit} from "
            f"{MIN_PATH_CHORD_M / factor:g}, the axes' resolution (no machine follows a path "
            "more finely, and the chords grow in number as "
            f"1/sqrt({symbol or name}): ten times 1 nm's at {0.01 * M_PER_NM / factor:g}), "
            f"to {MAX_PATH_CHORD_M / factor:g} (1 m, more than any machine's travel)")
    return number * factor


def with_nose_radius_error(tool: Tool, errors) -> Tool:
    """The tool as it is with the error model's nose radius error (``errors``, an
    `machinesim.errors.ErrorModel` or None): a round-nose tool's nose, a ball's or a flat end
    mill's radius that much larger, still set by its tip. A refusal names the key and the
    value as the model's file wrote them (``ErrorModel.written``), and the file.

    Raises
    ------
    NoseRadiusMisfit
        When the error is not zero and the tool has no radius (a V tool), or the radius
        would not be positive.
    """
    d_radius = 0.0 if errors is None else errors.tool_geometry.nose_radius
    if d_radius == 0.0:
        return tool
    written = errors.written.get("tool_geometry.nose_radius")
    key, shown = (("tool_geometry.nose_radius", f"{d_radius!r} m") if written is None
                  else (written[0], f"{written[1]:g}"))
    source = None if errors.source is None else str(errors.source)
    try:
        if isinstance(tool, RoundNoseTool):
            return tool.with_errors(nose_radius_error=d_radius)
        if isinstance(tool, BallEndMill | FlatEndMill):
            return tool.with_errors(radius_error=d_radius)
    except InputError as error:  # name the error model's key the user wrote, and the value
        raise NoseRadiusMisfit(f"the error model's {key} = {shown} does not fit the "
                               f"{type(tool).__name__} ({error.message})", tool=tool,
                               has_radius=True, source=source, line=errors.line_of(key),
                               key=key) from None
    raise NoseRadiusMisfit(f"the error model has {key} = {shown}, but a {type(tool).__name__} "
                           "has no nose radius; expected a round-nose ('nose:R:ANGLE'), ball or "
                           "flat end mill", tool=tool, has_radius=False, source=source,
                           line=errors.line_of(key), key=key)
