"""Cutting tools as convex point sets in the ``tool_tip`` frame (metres).

Every tool has its edge point at the origin and points along -Z: the body lies at z >= 0.
A non-rotational tool (V, round nose) cuts along its frame's +X axis; its cutting edge is a
profile in the tool's Y-Z plane. The profile has zero thickness along X on purpose: the
convex hull of the profile at the two ends of a linear move is then the exact volume swept
by the edge, with no body behind the edge that a real tool clears with its clearance angle.
The consequence at groove ends: where a move starts or stops inside the material, the
simulated groove ends in the flat plane of the profile, whereas a real tool's body (rake and
clearance faces) would also leave its shape there. A move inside the profile plane (a
sideways drag) sweeps no volume with a zero-thickness profile: the engine flags those moves.

A ball end mill is modelled by its rotating envelope, a sphere, without the shank.

Arcs and spheres are inscribed polygons whose vertices lie on the true surface; the chord
tolerance (the sagitta between a chord and its arc) is a parameter of each tool.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import manifold3d
import numpy as np

from machinesim.exceptions import InputError
from machinesim.tolerances import BALL_CHORD_M, PROFILE_CHORD_M
from machinesim.units import M_PER_MM, RAD_PER_DEG

#: Height of V and round-nose profiles above the edge point (m): 8x the deepest groove of
#: the seed experiments (25 um pyramids, seed 003), so no depth of cut reaches the top of
#: the profile. The engine clips sweeps just above the stock, so a taller profile costs
#: nothing; it only matters where a real tool's shank could touch the part.
PROFILE_HEIGHT_M = 0.2e-3


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


def _check_positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(f"{name} must be a positive finite number, got {value!r}", key=name)
    return value


def _check_angle(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or not 0.0 < value < math.pi:
        raise InputError(
            f"{name} must lie in (0, pi) rad, got {value!r} rad ({math.degrees(value)!r} deg)",
            key=name,
        )
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


@dataclass(frozen=True)
class VTool:
    """V (prism) tool: flanks at +-included_angle/2 from -Z, from the edge point up to height.

    Parameters
    ----------
    included_angle : float
        Included angle of the V (rad), in (0, pi). An included-angle error is part of it.
    height : float
        Height of the profile above the edge point (m), see `PROFILE_HEIGHT_M`.
    """

    included_angle: float
    height: float = PROFILE_HEIGHT_M
    rotational = False

    def __post_init__(self) -> None:
        _check_angle("included_angle", self.included_angle)
        _check_positive("height", self.height)

    def vertices(self) -> np.ndarray:
        """Profile corners, shape (3, 3) (m): edge point, then the flank tops at -Y and +Y."""
        half = self.height * math.tan(self.included_angle / 2.0)
        return _profile_points(np.array([[0.0, 0.0], [-half, self.height], [half, self.height]]))

    def edges(self) -> np.ndarray:
        """Index pairs of the profile's edges into `vertices`, shape (3, 2) int64."""
        return _polygon_edges(3)

    def with_errors(self, included_angle_error: float = 0.0) -> VTool:
        """The same tool with its included angle off by ``included_angle_error`` (rad)."""
        return replace(self, included_angle=self.included_angle + included_angle_error)


@dataclass(frozen=True)
class RoundNoseTool:
    """Round-nose tool: an arc of radius R centred at (0, 0, R), then tangent straight flanks.

    The arc spans +-included_angle/2 about -Z and the flanks continue tangentially up to
    ``height``; where the arc already rises above ``height`` the profile is the arc cut by
    the plane z = height.

    Parameters
    ----------
    nose_radius : float
        Nose radius (m). A nose-radius error dR is part of it: ``RoundNoseTool(R + dR, ...)``.
    included_angle : float
        Included angle between the flanks (rad), in (0, pi).
    height : float
        Height of the profile above the edge point (m).
    chord_tol : float
        Largest sagitta of the arc polygon (m); vertices lie on the true arc.
    """

    nose_radius: float
    included_angle: float
    height: float = PROFILE_HEIGHT_M
    chord_tol: float = PROFILE_CHORD_M
    rotational = False

    def __post_init__(self) -> None:
        _check_positive("nose_radius", self.nose_radius)
        _check_angle("included_angle", self.included_angle)
        _check_positive("height", self.height)
        _check_positive("chord_tol", self.chord_tol)

    def vertices(self) -> np.ndarray:
        """Profile polygon from the -Y top round to the +Y top, shape (k, 3) (m).

        The edge point (0, 0, 0) is always a vertex.
        """
        radius, height = self.nose_radius, self.height
        end = self.included_angle / 2.0
        arc_top = radius * (1.0 - math.cos(end))
        if arc_top > height:
            end = math.acos(1.0 - height / radius)
        # An even count keeps phi = 0, the edge point, exactly on a vertex.
        half = arc_segments(radius, end, self.chord_tol)
        phi = np.linspace(-end, end, 2 * half + 1)
        phi[half] = 0.0
        yz = np.stack([radius * np.sin(phi), radius * (1.0 - np.cos(phi))], axis=1)
        if arc_top > height:
            yz[[0, -1], 1] = height
        else:
            rise = (height - arc_top) / math.sin(end)
            top = yz[-1] + rise * np.array([math.cos(end), math.sin(end)])
            top[1] = height
            yz = np.vstack([[-top[0], height], yz, top])
        return _profile_points(yz)

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
        )


@functools.lru_cache(maxsize=16)
def sphere_polygon(radius: float, chord_tol: float) -> manifold3d.Manifold:
    """Sphere polygon about the origin, vertices on the sphere, facets within ``chord_tol``.

    manifold3d's geodesic sphere puts its vertices on the sphere; the segment count (a
    multiple of 4) starts from the arc formula and grows until the measured facet depth
    (radius minus the least facet-plane distance from the centre) is within tolerance.

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


@functools.lru_cache(maxsize=16)
def _sphere_mesh(radius: float, chord_tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Sphere polygon centred at (0, 0, radius): vertices (k, 3) m, triangles (t, 3) int64."""
    mesh = sphere_polygon(radius, chord_tol).to_mesh64()
    vertices = np.array(mesh.vert_properties[:, :3], dtype=np.float64)
    vertices[:, 2] += radius
    triangles = np.array(mesh.tri_verts, dtype=np.int64)
    vertices.flags.writeable = False
    triangles.flags.writeable = False
    return vertices, triangles


@dataclass(frozen=True)
class BallEndMill:
    """Envelope of a rotating ball end mill: a sphere of radius R centred at (0, 0, R).

    Parameters
    ----------
    radius : float
        Ball radius (m).
    chord_tol : float
        Largest distance of a facet of the sphere polygon from the true sphere (m).
    """

    radius: float
    chord_tol: float = BALL_CHORD_M
    rotational = True

    def __post_init__(self) -> None:
        _check_positive("radius", self.radius)
        _check_positive("chord_tol", self.chord_tol)

    def _mesh(self) -> tuple[np.ndarray, np.ndarray]:
        return _sphere_mesh(self.radius, self.chord_tol)

    def vertices(self) -> np.ndarray:
        """Sphere polygon vertices, shape (k, 3) (m), all at distance R from (0, 0, R)."""
        return self._mesh()[0]

    def edges(self) -> np.ndarray:
        """Index pairs of the sphere polygon's edges into `vertices`, shape (e, 2) int64."""
        triangles = self._mesh()[1]
        pairs = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
        return np.unique(np.sort(pairs, axis=1), axis=0)

    def with_errors(self, radius_error: float = 0.0) -> BallEndMill:
        """The same tool with its radius off by ``radius_error`` (m)."""
        return replace(self, radius=self.radius + radius_error)


Tool = VTool | RoundNoseTool | BallEndMill

_SPEC_FORMS = "'v:ANGLE_DEG', 'nose:RADIUS_MM:ANGLE_DEG' or 'ball:RADIUS_MM'"


def tool_from_spec(spec: str) -> Tool:
    """Build a tool from a text spec in mm and degrees.

    Parameters
    ----------
    spec : str
        ``"v:90"`` (included angle, deg), ``"nose:2.0:90"`` (nose radius mm, included angle
        deg) or ``"ball:2.0"`` (radius mm).

    Returns
    -------
    VTool or RoundNoseTool or BallEndMill

    Raises
    ------
    InputError
        If the spec does not have one of these forms or a number is out of range.
    """
    fields = str(spec).strip().split(":")
    kind = fields[0].lower()
    arity = {"v": 1, "nose": 2, "ball": 1}
    if kind not in arity or len(fields) != arity[kind] + 1:
        raise InputError(f"tool spec {spec!r}: expected {_SPEC_FORMS}", key="tool")
    try:
        values = [float(field) for field in fields[1:]]
    except ValueError:
        raise InputError(
            f"tool spec {spec!r}: expected numbers after the kind, as in {_SPEC_FORMS}",
            key="tool",
        ) from None
    try:
        if kind == "v":
            return VTool(values[0] * RAD_PER_DEG)
        if kind == "nose":
            return RoundNoseTool(values[0] * M_PER_MM, values[1] * RAD_PER_DEG)
        return BallEndMill(values[0] * M_PER_MM)
    except InputError as error:
        raise InputError(f"tool spec {spec!r}: {error}", key="tool") from None
