"""A rotating tool (ball or flat end mill) tilted across its sides, cut in pieces.

A turning sweep is cut as the convex hull of the tool at its two poses (`SweepSet.hulls`).
A ball or flat end mill's sides are straight lines along its axis; when a rotary move tilts
the tool about a line that crosses them below the clip plane (a B swing whose pivot lies
inside the cut height), the side's points below that line move one way along its normal
and those above it the other way, and the hull fills the waist of the bow-tie the side
truly sweeps: ``A B / (A + B) * d`` beyond it for a tilt d, the side reaching A below and
B above the line, first order in d as for a tilted profile (`tilted_profiles`). Measured
before this: flat:0.5 and ball:0.5 swung +-1 deg in 20 sweeps about a Y line 50 um under
the stock's top and 50 um above the flat's end face (or the ball's equator) cut 40.6 nm
past the side's true sweep at that line's height (4.0 nm in 200 sweeps: first order). The
planner's chord rule does not hold it: for a ball (no face sub-steps), at about 0.5 deg a
sub-step (100 nm on a 10 mm tool), it is 25 um * 8.7 mrad = 218 nm for a pivot 50 um inside
a cut 100 um high (by hand; 211 nm measured in 4 sweeps of 0.5 deg).

The displacement of the tool's points along a side's mean normal between the two poses is
affine, zero on a plane through the line the tool turns about (for a tilt about a line
across the axis, the same plane across the axis for every side); where it takes both signs
on a side's part below the clip plane and the hull would leave that side's sweep by more
than `tilted_profiles.SPLIT_M`, the tool is cut by that plane and the sweep is the union of
the pieces' hulls at the two poses: each piece's sides move to one side only and its hull is
their sweep to second order, as a point's chord. The cut faces the pieces share tilt across
themselves, but what their hulls add there lies in the neighbouring piece's sweep. The
ball's facets are not split: they lie within the round ball, whose sweep's hull leaves it
only by its centre's chord. A flat end mill's end face tilted across itself is held by the
planner's sub-steps (`machinesim.motion.faces`): split here instead, a turn about a far
axis (a 4th axis under the tool) leaves each half's hull rho d**2 / 2 under the face's
sweep, rho the face's distance from that axis, four times a point's chord, more than the
vertices' chord tolerance where rho is large beside the tool.

A tilt combined with a move along the line it turns about (a B swing with Y on a 5-axis
machine) gives each side its own plane, where the move and the tilt cancel along the side's
normal: for a side at azimuth phi from the tilt's plane, at the height h* = -t tan(phi) / d
from the line, t the move. The tool is cut by every such plane that crosses a side's part
below the clip plane (as many as the sides whose h* falls there: 22 of a 52-sided flat
end mill's for d = 0.5 deg, t = 0.1 um; the sides half a turn apart share one). With at
most 4 planes, flat:0.5 of 52 sides swung 2 deg in 4 sweeps about a Y line 50 um up while
moving 2 um along Y cut 52 nm past the sweep of the same move in 40 sweeps (78 um^3 more);
now 17 nm (0.23 um^3). What is left lies at the polygon's corners: between two sides' planes
a corner's own zero, for the normals between theirs, is not cut, and its hull leaves its
sweep by up to about t (2 pi / n) / (4 cos phi) for n sides (20 nm here), first order in the
move t a sweep and not in the tilt.

A turn's part about the tool's own axis is a symmetry of the round tool: it is taken out
before the planes are sought (`tilt_only`). On the polygon it tilts every side across its
middle, by a first-order amount (the hull of a side fills s d / 4 of a notch the turning
polygon leaves, s the side's width) that stays inside the round tool's sweep, and such a
sweep was cut into 8 pieces for nothing (a spin about the axis, A on robonano_ui).
"""

from __future__ import annotations

import manifold3d
import numpy as np

from machinesim.cutting.tilted_profiles import SPLIT_M, clip_halfspace

__all__ = ["SolidSplitter", "tilt_only"]

#: A face is straight along the tool's axis (a side) when its normal's axial part is within
#: this of 0.
_AXIAL_TOLERANCE = 1e-9
#: A face whose normals at the two poses add up to less than this (2 cos of half the
#: angle it turns by: within 1e-6 rad of a half turn) is turned right over, has no mean
#: normal to measure an excess along, and is not split for (its sweep in one sub-step is no
#: hull's, whatever the pieces).
_TURNED_OVER = 1e-6
#: Faces' offsets from the tool frame's origin are told apart to this (m, times
#: `_AXIAL_TOLERANCE`: 1e-12 m) when the triangles are grouped into faces.
_FACE_ROUND_M = 1e-3


def tilt_only(r0: np.ndarray, r1: np.ndarray) -> np.ndarray:
    """The orientation (..., 3, 3) the tool at ``r0`` (..., 3, 3) takes when it is turned
    the shortest way to the axis (third column) of ``r1``: ``r1`` less its turn about the
    tool's own axis, which moves no point of a round tool. ``r1`` itself where the axis
    turns by a half turn or within 1.4e-9 rad of one (no shortest way)."""
    a0, a1 = r0[..., :, 2], r1[..., :, 2]
    k = np.cross(a0, a1)
    c = np.einsum("...i,...i->...", a0, a1)
    zero = np.zeros_like(c)
    skew = np.stack([np.stack([zero, -k[..., 2], k[..., 1]], -1),
                     np.stack([k[..., 2], zero, -k[..., 0]], -1),
                     np.stack([-k[..., 1], k[..., 0], zero], -1)], -2)
    flip = 1.0 + c <= 1e-18
    with np.errstate(divide="ignore", invalid="ignore"):
        turn = np.eye(3) + skew + skew @ skew / np.where(flip, 1.0, 1.0 + c)[..., None, None]
    return np.where(flip[..., None, None], r1, turn @ r0)


def _excess(values: np.ndarray, scale: float) -> float:
    """How far the hull of a face at two poses leaves its sweep (m), its normal displacement
    ``values`` (times 1 / ``scale``) reaching both signs: A B / (A + B), else 0."""
    if not len(values) or not scale > _TURNED_OVER:
        return 0.0
    low, high = float(values.min()) / scale, float(values.max()) / scale
    if not low < 0.0 < high:
        return 0.0
    return -low * high / (high - low)


class SolidSplitter:
    """Cuts a rotating tool's turning sweeps into pieces where its tilt crosses its straight
    faces.

    Parameters
    ----------
    vertices : ndarray, shape (k, 3)
        The tool's vertices, tool frame (m).
    triangles : ndarray, shape (t, 3)
        Its outward triangles.
    """

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray) -> None:
        corner = vertices[triangles]
        normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        straight = np.abs(normal[:, 2]) <= _AXIAL_TOLERANCE  # the sides
        corner, normal = corner[straight], normal[straight]
        # the triangles of one face (a side's two) together: the face's displacement may
        # take both signs where no one triangle's does
        plane = np.round(np.concatenate(
            [normal, np.einsum("ij,ij->i", normal, corner[:, 0])[:, None] / _FACE_ROUND_M],
            axis=1) / _AXIAL_TOLERANCE)
        _, face = np.unique(plane, axis=0, return_inverse=True)
        order = np.argsort(face.reshape(-1), kind="stable")
        face = face.reshape(-1)[order]
        self.corners = corner[order]
        # (a tool with no straight side, a ball as high as its radius, has no face)
        self.starts = np.flatnonzero(np.r_[len(face) > 0, face[1:] != face[:-1]])
        self.normals = normal[order][self.starts]
        mesh = manifold3d.Mesh64(vert_properties=np.array(vertices, dtype=np.float64),
                                 tri_verts=np.array(triangles, dtype=np.uint64))
        self.body = manifold3d.Manifold(mesh)

    def crossing(self, rows, r0, r1, o0, o1, levels) -> np.ndarray:
        """Which of the sweeps ``rows`` may tilt across a side that comes below its clip
        height ``levels`` (world z, by row) at either pose (a quick test on the whole sides:
        `pieces` decides on their parts below it)."""
        rows = np.asarray(rows, dtype=np.int64)
        if not len(self.normals) or not len(rows):
            return np.zeros(len(rows), dtype=bool)
        a = r0[rows]
        b = tilt_only(a, r1[rows])
        total = a + b
        k = np.einsum("nji,njk->nik", b - a, total)  # (r1 - r0)^T (r0 + r1)
        shift = np.einsum("nji,nj->ni", total, o1[rows] - o0[rows])
        each = np.repeat(np.arange(len(self.starts)),
                         np.diff(np.r_[self.starts, len(self.corners)]))
        normals = self.normals[each]
        g = np.einsum("nij,tj->nti", k, normals)
        c = np.einsum("ti,ni->nt", normals, shift)
        f = np.einsum("tvi,nti->ntv", self.corners, g) + c[:, :, None]
        low = np.minimum.reduceat(f.min(axis=2), self.starts, axis=1)
        high = np.maximum.reduceat(f.max(axis=2), self.starts, axis=1)
        # sides wholly above the clip height at both poses (a ball's shank over a shallow
        # cut) cut nothing
        lowest = np.minimum(
            np.einsum("tvi,ni->ntv", self.corners, a[:, 2]).min(axis=2) + o0[rows, 2, None],
            np.einsum("tvi,ni->ntv", self.corners, b[:, 2]).min(axis=2) + o1[rows, 2, None])
        reaches = np.minimum.reduceat(lowest, self.starts, axis=1) <= levels[rows, None]
        scale = np.linalg.norm(np.einsum("nij,tj->nti", total, self.normals), axis=2)
        with np.errstate(divide="ignore", invalid="ignore"):
            excess = np.where((low < 0.0) & (high > 0.0), -low * high / (high - low), 0.0)
            excess = np.where(scale > _TURNED_OVER, excess / scale, 0.0)
        return ((excess > SPLIT_M) & reaches).any(axis=1)

    def planes(self, r0, o0, r1, o1, level: float) -> list[tuple[np.ndarray, float]]:
        """The planes (unit normal, offset: ``normal . p = offset``, tool frame) the tool is
        cut by for the sweep from (``r0``, ``o0``) to (``r1``, ``o1``), largest excess
        first: empty when no straight face's part below ``level`` (world z) at either pose
        leaves its sweep by more than `SPLIT_M`."""
        turned = tilt_only(r0, r1)
        total = r0 + turned
        k = (turned - r0).T @ total
        shift = total.T @ (o1 - o0)
        below = [(r0[2], level - o0[2]), (turned[2], level - o1[2])]
        pending = []
        ends = np.r_[self.starts[1:], len(self.corners)]
        for begin, end, normal in zip(self.starts, ends, self.normals, strict=True):
            parts = [clip_halfspace(corners, a, b) for corners in self.corners[begin:end]
                     for a, b in below]
            g = k @ normal
            c = float(normal @ shift)
            scale = float(np.linalg.norm(total @ normal))
            values = np.concatenate([part @ g for part in parts]) + c
            excess = _excess(values, scale)
            if excess > SPLIT_M:
                pending.append((excess, parts, g, c, scale))
        chosen = []
        # each plane is one face's own zero: none of that face's parts is left with an
        # excess, so there are at most as many planes as faces
        while pending:
            _, _, g, c, _ = max(pending, key=lambda item: item[0])
            size = float(np.linalg.norm(g))
            unit, offset = g / size, -c / size
            chosen.append((unit, offset))
            left = []
            for _, parts, g, c, scale in pending:
                for sign in (1.0, -1.0):
                    side = [clip_halfspace(part, sign * unit, sign * offset) if len(part) >= 3
                            else part[:0] for part in parts]
                    values = np.concatenate([part @ g for part in side]) + c
                    excess = _excess(values, scale)
                    if excess > SPLIT_M:
                        left.append((excess, side, g, c, scale))
            pending = left
        return chosen

    def pieces(self, r0, o0, r1, o1, level: float) -> list[np.ndarray] | None:
        """The point sets (world, m) whose hulls, united, are the sweep from pose (``r0``,
        ``o0``) to (``r1``, ``o1``), each piece cut to z <= ``level`` at each pose; None when
        no straight face is tilted across itself there (`planes`)."""
        planes = self.planes(r0, o0, r1, o1, level)
        if not planes:
            return None
        solids = [self.body]
        for unit, offset in planes:
            cut = []
            for solid in solids:
                above, under = solid.split_by_plane(tuple(unit), offset)
                cut.extend(part for part in (above, under) if not part.is_empty())
            solids = cut
        out = []
        for solid in solids:
            points = []
            for rotation, origin in ((r0, o0), (r1, o1)):
                kept = solid.trim_by_plane(tuple(-rotation[2]), -(level - origin[2]))
                if kept.is_empty():
                    continue
                local = np.asarray(kept.to_mesh64().vert_properties)[:, :3]
                points.append(local @ rotation.T + origin)
            if points:
                out.append(np.concatenate(points))
        return out
