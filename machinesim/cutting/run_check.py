"""Each run's subtraction checked: no face of the part left inside the sweeps it removed.

manifold3d (3.5.4) does not always subtract exactly. On a flat end mill's rotary turn 10.1 mm
from the axis (docs/cutting.md, "A rotary turn inside the material"), the subtraction of one
run's union (`engine.remove`, step 3) left a wedge of 5.0e-18 m^3 inside that union, where
the part before it had no material: five of the faces it made, laid over the union's faces
and triangulated anew, lie 0.19 to 90 nm inside one of the run's sweeps. Every vertex of the
wedge lies on a sweep's surface (none deeper than 2e-16 m), so a test of the part's vertices
cannot see it; its faces' centroids can.

The check (`subtract_run`): after a run is subtracted, the centroid of each triangle of the
part that has a vertex the part before did not have (the faces the subtraction made; the
wedge's are among them) is tested against the plane equations of each of the run's sweeps
that is convex (Qhull's hull of its vertices has its volume, `CONVEX_REL`), and of each
convex piece of those that are not: a tool tilted across itself is cut as the union of
pieces' hulls (`SweepSet._united`, `tilted_profiles.halves`, `tilted_solids`), whose own hull
holds material outside it; the pieces' planes and bounds are kept with the union when it is
built (`sweeps.UnitedSolid`, `Solids.pieces`). A centroid deeper than
`tolerances.INSIDE_SWEEP_M` inside a solid or a piece is material the subtraction should have
removed (a point as deep inside a piece is at least as deep inside the union): the run is
subtracted again one sweep at a time (which leaves none on the case above) and checked again,
and if material is still there the cut is refused with `SubtractionError` rather than a wrong
part returned.

A piece's depth is the union's wherever the union's own surface is nearer than the faces
the pieces share; a face left nearer such a seam than its depth in the union is found no
deeper than its distance to the seam (0 on it). Before the pieces were kept, the unions
were left out whole: a tool swung across its sides (tests/test_cutting_run_check_pieces.py)
kept the material a run's union missed. What they cost, CPU of `deepest_inside` over the 3
runs of 20 sweeps swung +-1 deg about a Y line 50 um above the end face (a ball's equator),
every sweep split in two (medians of 3 on 2 shared cores; the cut itself 0.35-0.49 s for
flat:0.5, 1.4-1.8 s for ball:0.5): flat:0.5 7.3 ms before (Qhull of each union, then left
out), 7.5 ms now; v:90 swung +-2 deg 2.7, 2.9 ms; ball:0.5 23 ms before, 282 ms now, each of
its 9,990 new faces near every piece (the sweeps nearly coincide) and tested against the
578 planes of the pieces about the ball: the same sweeps cut unsplit, as convex hulls,
checked in 436 ms. The planes kept take 3.0, 0.4 and 19.9 kB a sweep (flat, V, ball), less
than the union's mesh as float64 arrays (4.7, 0.5, 24.4 kB) that its manifold holds more
than once over. Paper 002's crown before compensation (benchmarks/run_check.py's crown case,
cut once each way) splits no sweep and checks no run (its feed moves are cut as
translations): 120.4 s CPU before, 114.4 s now, the removed volume the same to the bit.
"""

from __future__ import annotations

from collections.abc import Sequence

import manifold3d
import numpy as np
from manifold3d import OpType
from scipy.spatial import ConvexHull

from machinesim.cutting.sweeps import ConvexPiece
from machinesim.exceptions import InputError, SubtractionError, brief
from machinesim.tolerances import INSIDE_SWEEP_M, SAME_ORIENTATION, TWIST_M

#: A sweep is convex when the volume of Qhull's hull of its vertices is its own within this
#: fraction (float64 round-off of the two sums, ~1e-15; a union of two pieces of a tilted
#: sweep differs from its hull by far more).
CONVEX_REL = 1e-9
#: Planes of a solid a centroid is tested against at once: those outside one of them are left
#: out before the next (`_deepest_in`).
PLANES_PER_PASS = 32
#: Distances computed at once, so that the block stays in cache (128 KB; all a run's planes
#: at once, 64 centroids against the 8 x 251 planes of a run took 12.8 ms for 7,453 centroids,
#: 186 ms in blocks of 8,192; 65,536 distances at once took as long as 16,384, 4,096 longer).
DISTANCES_PER_BLOCK = 16384
#: Sweeps whose tool vertices are turned at once when telling those that turn (a block of
#: 1,024 sweeps of a tool of 2,000 vertices: 49 MB).
SWEEPS_PER_BLOCK = 1024
#: Odd multipliers that mix a point's y and z bits into its key (`_unknown`): the golden
#: ratio's and xxHash's 64-bit primes, so that points a bit apart get keys far apart.
MIX = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xC2B2AE3D27D4EB4F))


#: `engine.remove`'s ``check_runs``: which runs are checked.
CHECKS = ("turning", "all", "off")


def check_runs_value(value) -> str:
    """``value`` if it is one of `CHECKS`, else an InputError naming ``check_runs``."""
    if not isinstance(value, str) or value not in CHECKS:
        raise InputError(f"Expected check_runs as one of {', '.join(map(repr, CHECKS))}, got "
                         f"{brief(repr(value))}", key="check_runs")
    return value


def checked_sweeps(check_runs: str, sweeps, owners) -> np.ndarray:
    """Which of the cut sweeps have their run checked (bool per sweep of ``owners``):
    every one ("all"), none ("off"), or those that turn the tool ("turning"), as
    `SweepSet.hulls` tells them: its orientation at the two poses differs by more than
    `SAME_ORIENTATION` and moves a vertex of the tool by more than `TWIST_M` (a sweep
    turned less is cut as a translation: the machine's angular motion errors turn every
    feed move of paper 002's crown by 1e-9 to 1e-7 rad, and checking those runs doubled
    its cut).

    Parameters
    ----------
    check_runs : {"turning", "all", "off"}
    sweeps : SweepSet
        Its ``poses``, ``pairs`` (each sweep's first pose) and ``vertices`` (the tool's).
    owners : sequence of int
        Each cut sweep's index over all paths (`SweepSet.hulls`).
    """
    owners = np.asarray(owners, dtype=np.int64)
    if check_runs != "turning":
        return np.full(len(owners), check_runs == "all")
    first = sweeps.pairs[owners]
    turn = sweeps.poses[first + 1, :3, :3] - sweeps.poses[first, :3, :3]
    turning = np.abs(turn).reshape(-1, 9).max(axis=1, initial=0.0) > SAME_ORIENTATION
    for begin in range(0, len(owners), SWEEPS_PER_BLOCK):
        rows = begin + np.flatnonzero(turning[begin:begin + SWEEPS_PER_BLOCK])
        # how far the turn alone moves each vertex, (R1 - R0) v
        moved = np.abs(sweeps.vertices @ turn[rows].transpose(0, 2, 1)).max(axis=(1, 2),
                                                                           initial=0.0)
        turning[rows] = moved > TWIST_M
    return turning


def _planes(solids: Sequence[manifold3d.Manifold],
            pieces: Sequence[Sequence[ConvexPiece] | None] | None = None
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The outward plane equations (p, 4) of the convex ``solids`` (Qhull's, of the hull of
    each one's vertices) and of the convex pieces of the others, the start of each solid's
    or piece's rows, and their bounds (c, 3) twice.

    A solid whose ``pieces`` are given (a union of split pieces, `SweepSet._united`) stands
    for its pieces' planes and bounds as they were kept when it was built (no hull here); a
    solid without is taken convex when Qhull's hull of its vertices has its volume
    (`CONVEX_REL`), and left out if not. Qhull's planes, not those of the solids' own
    triangles: those need a test of each solid's convexity against every plane (a ball
    sweep's thousands), which made a raster's check 4 times as slow."""
    equations, starts, lower, upper = [], [], [], []
    count = 0

    def add(rows, low, high):
        nonlocal count
        equations.append(rows)
        starts.append(count)
        count += len(rows)
        lower.append(low)
        upper.append(high)

    for index, solid in enumerate(solids):
        split = None if pieces is None else pieces[index]
        if split is not None:
            for piece in split:
                add(*piece)
            continue
        vertices = np.asarray(solid.to_mesh64().vert_properties)[:, :3]
        hull = ConvexHull(vertices)
        if not abs(hull.volume - solid.volume()) <= CONVEX_REL * hull.volume:
            continue
        # a facet's triangles share its equation
        add(np.unique(hull.equations, axis=0), vertices.min(axis=0), vertices.max(axis=0))
    if not equations:
        empty = np.zeros((0, 3))
        return np.zeros((0, 4)), np.zeros(0, dtype=np.int64), empty, empty
    return (np.concatenate(equations), np.array(starts, dtype=np.int64), np.array(lower),
            np.array(upper))


def _bits(points: np.ndarray) -> np.ndarray:
    """The bits of each coordinate of ``points`` (n, 3), as uint64 (n, 3)."""
    return np.ascontiguousarray(points, dtype=np.float64).view(np.uint64).reshape(-1, 3)


def _unknown(points: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Which of ``points`` (n, 3) are not among ``known`` (m, 3), bit for bit (bool, n).

    Each point's bits are mixed into one uint64 key; a point whose key no known point has
    is not known, one whose key matches is compared bit for bit with the known point that
    has that key (a point whose key two different known points share may be counted unknown:
    more faces tested, never fewer). Sorting the m keys costs a third of what np.isin over
    rows of 24 bytes did (30,000 points: 5.4 against 14.5 ms)."""
    point_bits, known_bits = _bits(points), _bits(known)
    if not len(known_bits):
        return np.ones(len(point_bits), dtype=bool)
    keys = _keys(known_bits)
    order = np.argsort(keys)
    keys = keys[order]
    wanted = _keys(point_bits)
    at = np.minimum(np.searchsorted(keys, wanted), len(keys) - 1)
    same = keys[at] == wanted
    same[same] = (point_bits[same] == known_bits[order[at[same]]]).all(axis=1)
    return ~same


def _keys(bits: np.ndarray) -> np.ndarray:
    """One uint64 of each row of ``bits`` (n, 3): the three mixed by odd multipliers."""
    return bits[:, 0] ^ (bits[:, 1] * MIX[0]) ^ (bits[:, 2] * MIX[1])


def _deepest_in(points: np.ndarray, equations: np.ndarray) -> float:
    """How deep (m) the deepest of ``points`` (n, 3) lies inside the convex solid of the
    outward planes ``equations`` (p, 4): the least distance inside its planes, -inf when
    every point is outside one. The planes are taken `PLANES_PER_PASS` at a time, spread over
    the list (Qhull's, sorted: neighbours face alike); a point outside one (distance > 0)
    lies inside by less than nothing and is left out of the next passes, so that the points
    on the solid's surface and inside it are the only ones tested against every plane. The
    depth of those is the maximum of the same distances as when every point meets every plane
    (to the bit on the four cases of benchmarks/run_check.py, every run checked)."""
    passes = max(1, len(equations) // PLANES_PER_PASS)
    farthest = np.full(len(points), -np.inf)  # each point's greatest distance outside so far
    for first in range(passes):
        if not len(points):
            return -np.inf
        normals = np.ascontiguousarray(equations[first::passes, :3].T)
        offsets = equations[first::passes, 3]
        rows = max(1, DISTANCES_PER_BLOCK // len(offsets))
        for start in range(0, len(points), rows):
            block = slice(start, start + rows)
            farthest[block] = np.maximum(
                farthest[block], (points[block] @ normals + offsets).max(axis=1))
        kept = farthest <= 0.0
        points, farthest = points[kept], farthest[kept]
    return float(-farthest.min()) if len(points) else -np.inf


def deepest_inside(before: manifold3d.Manifold, after: manifold3d.Manifold,
                   solids: Sequence[manifold3d.Manifold],
                   pieces: Sequence[Sequence[ConvexPiece] | None] | None = None) -> float:
    """How deep (m) the deepest face ``after`` made lies inside one of the convex ``solids``
    or one of the convex pieces of the others (0 when none lies inside).

    Parameters
    ----------
    before, after : manifold3d.Manifold
        The part before and after ``solids`` were subtracted; the faces tested are the
        triangles of ``after`` with a vertex that ``before`` does not have.
    solids : sequence of manifold3d.Manifold
        The sweeps subtracted; those that are not convex (`CONVEX_REL`) and have no
        ``pieces`` are not tested.
    pieces : sequence of (sequence of ConvexPiece or None), optional
        For each of ``solids``, the convex pieces it is the union of (`Solids.pieces`), or
        None where it is convex itself. A face as deep inside a piece is at least as deep
        inside the union.
    """
    equations, starts, lower, upper = _planes(solids, pieces)
    if not len(equations):
        return 0.0
    mesh = after.to_mesh64()
    vertices = np.asarray(mesh.vert_properties)[:, :3]
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64)
    new = _unknown(vertices, np.asarray(before.to_mesh64().vert_properties)[:, :3])
    centroids = vertices[triangles[new[triangles].any(axis=1)]].mean(axis=1)
    # each solid's planes against the centroids in its bounds only (outside them, outside it)
    near = ((centroids[:, None] >= lower[None]) & (centroids[:, None] <= upper[None])).all(axis=2)
    ends = np.append(starts[1:], len(equations))
    deepest = -np.inf
    for solid, (begin, end) in enumerate(zip(starts, ends, strict=True)):
        deepest = max(deepest, _deepest_in(centroids[near[:, solid]], equations[begin:end]))
    return max(deepest, 0.0) if np.isfinite(deepest) else 0.0


def one_at_a_time(piece: manifold3d.Manifold,
                  solids: Sequence[manifold3d.Manifold]) -> manifold3d.Manifold:
    """``piece`` less each of ``solids`` in turn, each subtraction evaluated before the next
    (left lazy, manifold3d flattens them into the one subtraction of their union)."""
    for solid in solids:
        piece = piece - solid
        piece.num_tri()
    return piece


def subtract_run(piece: manifold3d.Manifold, solids: Sequence[manifold3d.Manifold],
                 sweeps: Sequence[int], check: bool = True,
                 pieces: Sequence[Sequence[ConvexPiece] | None] | None = None
                 ) -> manifold3d.Manifold:
    """``piece`` less the union of ``solids`` (one `batch_boolean`), evaluated, and checked
    when ``check``: a face left deeper than `INSIDE_SWEEP_M` inside a convex solid, or a
    convex piece of one that is not (``pieces``), has the run subtracted again one solid at
    a time, and checked again.

    Parameters
    ----------
    piece : manifold3d.Manifold
        The part (or a tile of it).
    solids : sequence of manifold3d.Manifold
        The run's sweeps.
    sweeps : sequence of int
        The sweeps' indices over all paths, named by the error.
    check : bool
        Test the result (`deepest_inside`); False subtracts only.
    pieces : sequence of (sequence of ConvexPiece or None), optional
        Each solid's convex pieces where it is their union (`deepest_inside`).

    Raises
    ------
    SubtractionError
        When material is still left inside a sweep after the sweeps were subtracted one at
        a time.
    """
    after = piece - manifold3d.Manifold.batch_boolean(list(solids), OpType.Add)
    # Evaluate now: manifold3d is lazy and would flatten A - B - C into A - (B + C), the
    # union the runs exist to avoid.
    after.num_tri()
    if not check:
        return after
    depth = deepest_inside(piece, after, solids, pieces)
    if depth <= INSIDE_SWEEP_M:
        return after
    again = one_at_a_time(piece, solids)
    redone = deepest_inside(piece, again, solids, pieces)
    if redone <= INSIDE_SWEEP_M:
        return again
    raise SubtractionError(
        f"manifold3d's subtraction of sweeps {', '.join(map(str, sweeps))} left material "
        f"{redone * 1e9:.3g} nm inside them ({depth * 1e9:.3g} nm united, "
        f"{redone * 1e9:.3g} nm one at a time, more than {INSIDE_SWEEP_M * 1e9:g} nm): "
        "the part would be wrong there, so none is returned", sweeps=tuple(sweeps))
