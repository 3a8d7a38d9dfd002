"""Rotating tools, ball and flat end mills, as the closed convex polyhedra of their envelopes.

A ball end mill is a hemisphere of radius R about (0, 0, R) under a cylindrical shank of the
same radius up to ``height``; a flat end mill a cylinder of radius R standing on its end
face at the origin. Their vertices lie on the true surface, within the tool's
``chord_tol``; the ball's are on rings of latitude, so that its volume has a closed form (a
sum of frusta of regular pyramids, `BallEndMill.rings`). Both are in the ``tool_tip`` frame
(metres) as `machinesim.tools` describes, and are importable from there.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from machinesim.exceptions import InputError
from machinesim.tolerances import BALL_CHORD_M
from machinesim.tool_sizes import (
    TOOL_HEIGHT_M,
    _check_count,
    _check_positive,
    _check_shank,
    _check_size,
)
from machinesim.units import length_text


def ring_facet_depth(radius: float, rings: int, segments: int) -> float:
    """Largest facet depth (m) of the ring polygon of a hemisphere.

    The hemisphere's vertices lie on ``rings`` rings of latitude at polar angles
    k pi / (2 rings) from the pole, each a regular ``segments``-gon at the same azimuths, so
    each facet is a planar trapezoid (a triangle at the pole). Its plane's distance from the
    centre follows from the two edge midpoints in its meridian plane; the depth is the radius
    minus that distance. The shank's faces lie at the equator polygon's apothem.
    """
    theta = np.linspace(0.0, math.pi / 2.0, rings + 1)
    a, b = theta[:-1], theta[1:]
    c = math.cos(math.pi / segments)
    distance = c * np.sin(b - a) / np.hypot(c * (np.sin(b) - np.sin(a)), np.cos(b) - np.cos(a))
    return float(radius * (1.0 - min(distance.min(), c)))


def ball_rings(radius: float, chord_tol: float) -> tuple[int, int]:
    """(rings, segments) of the hemisphere's polygon within ``chord_tol`` (m) of a ball of
    ``radius`` (m) (`BallEndMill.rings`), refused (InputError, key chord_tol) when its
    vertices would pass `MAX_TOOL_VERTICES`."""
    if chord_tol >= radius:
        rings, segments = 1, 4
    else:
        step = 2.0 * math.acos(1.0 - chord_tol / (2.0 * radius))
        rings = max(1, math.ceil(math.pi / 2.0 / step))
        segments = max(4, 4 * math.ceil(2.0 * math.pi / step / 4.0))
    while True:
        _check_count("ball polygon", rings * segments + segments + 1, chord_tol)
        if ring_facet_depth(radius, rings, segments) <= chord_tol:
            return rings, segments
        rings += math.ceil(rings / 8)
        segments += 4 * math.ceil(segments / 32)


@functools.lru_cache(maxsize=16)
def _ball_mesh(radius: float, chord_tol: float, height: float):
    """Hemisphere ring polygon under a prism shank: vertices (k, 3), triangles (t, 3) int64,
    rings and segments (see `BallEndMill.rings`)."""
    rings, segments = ball_rings(radius, chord_tol)
    theta = np.linspace(0.0, math.pi / 2.0, rings + 1)[1:]
    phi = 2.0 * math.pi * np.arange(segments) / segments
    ring_radius = radius * np.sin(theta)
    ring_z = radius * (1.0 - np.cos(theta))
    ring_radius[-1], ring_z[-1] = radius, radius  # the equator exactly
    if height > radius:
        ring_radius = np.append(ring_radius, radius)
        ring_z = np.append(ring_z, height)
    count = len(ring_z)
    vertices = np.zeros((1 + count * segments, 3))
    vertices[1:, 0] = (ring_radius[:, None] * np.cos(phi)[None, :]).ravel()
    vertices[1:, 1] = (ring_radius[:, None] * np.sin(phi)[None, :]).ravel()
    vertices[1:, 2] = np.repeat(ring_z, segments)
    j = np.arange(segments)
    nxt = (j + 1) % segments

    def ring(i, k):
        return 1 + i * segments + k

    triangles = [np.stack([np.zeros(segments, dtype=np.int64), ring(0, nxt), ring(0, j)], 1)]
    for i in range(count - 1):
        triangles.append(np.stack([ring(i, j), ring(i, nxt), ring(i + 1, nxt)], 1))
        triangles.append(np.stack([ring(i, j), ring(i + 1, nxt), ring(i + 1, j)], 1))
    top = count - 1
    inner = np.arange(1, segments - 1)
    triangles.append(np.stack([np.full(len(inner), ring(top, 0)), ring(top, inner),
                               ring(top, inner + 1)], 1))
    triangles = np.concatenate(triangles).astype(np.int64)
    vertices.flags.writeable = False
    triangles.flags.writeable = False
    return vertices, triangles, rings, segments


class _RotatingBody:
    """What a rotating tool's envelope (a closed convex polyhedron from ``_mesh()``, its
    vertices first, its outward triangles second) offers the engine: vertices, triangles,
    edges, and the same tool with another radius."""

    def vertices(self) -> np.ndarray:
        """Polyhedron vertices, shape (k, 3) (m), in the order the class states."""
        return self._mesh()[0]

    def triangles(self) -> np.ndarray:
        """Outward-oriented triangles of the polyhedron, indices into `vertices`, (t, 3)."""
        return self._mesh()[1]

    def edges(self) -> np.ndarray:
        """Index pairs of the polyhedron's edges into `vertices`, shape (e, 2) int64."""
        triangles = self.triangles()
        pairs = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
        return np.unique(np.sort(pairs, axis=1), axis=0)

    def with_errors(self, radius_error: float = 0.0):
        """The same tool with its radius off by ``radius_error`` (m)."""
        return replace(self, radius=self.radius + radius_error)


@dataclass(frozen=True)
class BallEndMill(_RotatingBody):
    """Envelope of a rotating ball end mill: a hemisphere of radius R about (0, 0, R) under a
    cylindrical shank of radius R up to ``height``.

    Parameters
    ----------
    radius : float
        Ball radius (m).
    chord_tol : float
        Largest distance of a facet of the polygon from the true surface (m).
    height : float, optional
        Length from the tip to the holder (m), at least ``radius``. Default: the larger of
        `TOOL_HEIGHT_M` and the diameter.
    shank_radius : float, optional
        Radius of the shank or holder above ``height`` (m), for the holder check: 0 (the
        default) takes it as wide as the tool.
    """

    radius: float
    chord_tol: float = BALL_CHORD_M
    height: float | None = None
    shank_radius: float = 0.0
    rotational = True
    planar = False

    def __post_init__(self) -> None:
        _check_size("radius", self.radius)
        _check_positive("chord_tol", self.chord_tol)
        if self.height is None:
            object.__setattr__(self, "height", max(TOOL_HEIGHT_M, 2.0 * self.radius))
        _check_size("height", self.height)
        if self.height < self.radius:
            raise InputError(f"height {length_text(self.height)} must be at least the "
                             f"radius, {length_text(self.radius)}", key="height")
        _check_shank(self.shank_radius)
        self._mesh()

    def _mesh(self):
        return _ball_mesh(self.radius, self.chord_tol, self.height)

    @property
    def rings(self) -> tuple[int, int]:
        """(rings, segments): the hemisphere's vertices lie on ``rings`` rings of latitude at
        polar angles k pi / (2 rings), k = 1 .. rings, from the tip, each a regular
        ``segments``-gon at azimuths 2 pi j / segments; the shank's top is the equator's
        polygon at ``height``. The polyhedron is a stack of frusta of regular pyramids; its
        vertices are the tip, then ring by ring."""
        return self._mesh()[2:]


@functools.lru_cache(maxsize=16)
def _cylinder_mesh(radius: float, chord_tol: float, height: float):
    """A regular polygon inscribed in the circle of ``radius`` at z = 0 and at ``height``:
    vertices (2 n, 3), outward triangles (t, 3) int64 and n."""
    if chord_tol >= radius:
        segments = 4
    else:
        segments = max(4, 4 * math.ceil(math.pi / math.acos(1.0 - chord_tol / radius) / 4.0))
    _check_count("end mill polygon", 2 * segments, chord_tol)
    phi = 2.0 * math.pi * np.arange(segments) / segments
    ring = np.stack([radius * np.cos(phi), radius * np.sin(phi), np.zeros(segments)], axis=1)
    vertices = np.concatenate([ring, ring + np.array([0.0, 0.0, height])])
    j = np.arange(segments)
    nxt = (j + 1) % segments
    inner = np.arange(1, segments - 1)
    triangles = np.concatenate([
        np.stack([np.zeros(len(inner), dtype=np.int64), inner + 1, inner], 1),  # bottom, -z
        np.stack([np.full(len(inner), segments), segments + inner,
                  segments + inner + 1], 1),  # top, +z
        np.stack([j, nxt, segments + nxt], 1),  # sides
        np.stack([j, segments + nxt, segments + j], 1),
    ]).astype(np.int64)
    vertices.flags.writeable = False
    triangles.flags.writeable = False
    return vertices, triangles, segments


@dataclass(frozen=True)
class FlatEndMill(_RotatingBody):
    """Envelope of a rotating flat end mill: a cylinder of radius R from its flat end face at
    z = 0 (the ``tool_tip`` frame's origin is the face's centre) up to ``height``.

    The circle is a regular polygon with `segments` corners on it (a multiple of 4, one at
    azimuth 0), so the sagitta between a side and the circle is within ``chord_tol``: the
    cut is up to that much narrower than the true cylinder's, as a ball's is.

    Parameters
    ----------
    radius : float
        Radius (m): half the end mill's diameter.
    chord_tol : float
        Largest distance of a side of the polygon from the circle (m).
    height : float, optional
        Length from the end face to the holder (m). Default: `TOOL_HEIGHT_M`.
    shank_radius : float, optional
        Radius of the shank or holder above ``height`` (m), for the holder check: 0 (the
        default) takes it as wide as the tool.
    """

    radius: float
    chord_tol: float = BALL_CHORD_M
    height: float = TOOL_HEIGHT_M
    shank_radius: float = 0.0
    rotational = True
    planar = False

    def __post_init__(self) -> None:
        _check_size("radius", self.radius)
        _check_positive("chord_tol", self.chord_tol)
        _check_size("height", self.height)
        _check_shank(self.shank_radius)
        self._mesh()

    def _mesh(self):
        return _cylinder_mesh(self.radius, self.chord_tol, self.height)

    @property
    def segments(self) -> int:
        """Corners of the polygon (a multiple of 4): the vertices are the end face's n, then
        the top's."""
        return self._mesh()[2]
