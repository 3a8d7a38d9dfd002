"""Sub-steps that keep a flat face's tilt within the chord tolerance.

The engine cuts each sub-step of a move that turns the tool as the convex hull of the tool
at the sub-step's two poses. For points that rule is held by the chord tolerance (each
vertex's chord stays within it of the vertex's true path, `machinesim.motion.chords`), but
a flat face that tilts by an angle d between the two poses leaves its true sweep by more:
the hull joins one end of the face at the first pose to the other end at the second, and
that chord passes a * d / 2 inside the face's lowest position in between (a the face's
half-width across the tilt), to first order in d, where a point's chord leaves its arc by
r d**2 / 8. A flat end mill's end face is such a face (a its radius): on a 4th axis, a
turn of A under `flat:0.5` at the default 100 nm cut the floor 1.9 um too deep (its
vertices' chords, 10 mm up the tool, held 100 nm at 0.47 deg a sub-step), and a B swing on
robonano_a0ib 2.2 um. So such a move gets at least the sub-steps whose tilt d each keeps
a * d / 2 within the tolerance.

The tilt is that of the tool's axis (the face's normal), the great-circle angle between
its directions at consecutive sub-steps: a turn about the tool's own axis (C under an
upright end mill) tilts nothing and adds no sub-step.

A planar tool's profile (a V, a nose) has straight edges with the same first-order error
when it tilts while it moves (docs/cutting.md, "A tilt with a move"): `edge_substeps`
bounds each edge's waist, |D . n| / 4 (derived there), within the tolerance, read only
where a bound from the edge's length and the tool's turn could raise a count
(`_uncleared`). Moves that turn no rotary axis keep their count to the bit
(`profile_substeps`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Sub-steps are raised by this share beyond the count the largest sampled tilt gives, for
#: a tilt rate that varies along the move (a C turn under a B-tilted tool is uniform; an
#: error table's tilt is not).
_MARGIN = 1.01
#: Samples whose poses are evaluated at once (128 bytes each, 16 MB).
_SAMPLES_PER_BLOCK = 1 << 17
#: The share of its reach by which float64 may round a corner an edge's waist is taken
#: from, with room: a few times 2**-52 in each of its operations; `_uncleared`'s bound is
#: raised by it.
_ROUNDING = 1e-12


def face_substeps(machine, errors, starts: np.ndarray, delta: np.ndarray,
                  steps: np.ndarray, face_radius: float, tolerance: float) -> np.ndarray:
    """Sub-steps of each move (``steps`` raised where needed) so that the tool axis tilts by
    at most ``2 * tolerance / face_radius`` per sub-step.

    The tilt of each sub-step is measured at the ``steps`` the chord rule chose (the tool
    axis at every sub-step's end, from `Machine.tool_pose`), and the count raised to the
    largest tilt's share of the allowed one, times `_MARGIN`.

    Parameters
    ----------
    machine : machinesim.Machine
    errors : ErrorModel or None
    starts, delta : ndarray, shape (n, n_axes)
        Each move's start and change of axis values (m, rad).
    steps : ndarray, shape (n,)
        The chord rule's sub-steps of each move (at least 1).
    face_radius : float
        Half-width of the tool's widest flat face normal to its axis, m (a flat end mill's
        radius); 0: no such face, ``steps`` returned as they are.
    tolerance : float
        The chord tolerance, m.
    """
    steps = np.asarray(steps, dtype=np.int64)
    if face_radius <= 0.0 or not len(steps):
        return steps
    largest = np.zeros(len(steps))
    # moves in blocks of about _SAMPLES_PER_BLOCK samples: poses are 128 bytes each
    ends = np.cumsum(steps + 1)
    lo = 0
    while lo < len(steps):
        hi = max(lo + 1, int(np.searchsorted(ends, ends[lo] + _SAMPLES_PER_BLOCK)))
        largest[lo:hi] = _largest_tilt(machine, errors, starts[lo:hi], delta[lo:hi],
                                       steps[lo:hi])
        lo = hi
    allowed = 2.0 * tolerance / face_radius
    need = np.ceil(steps * largest / allowed * _MARGIN).astype(np.int64)
    return np.maximum(steps, need)


def _largest_tilt(machine, errors, starts, delta, steps) -> np.ndarray:
    """The largest tilt of the tool axis (rad) over one sub-step of each move."""
    counts = steps + 1
    move = np.repeat(np.arange(len(steps)), counts)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    fraction = (np.arange(int(counts.sum())) - first[move]) / steps[move]
    q = starts[move] + fraction[:, None] * delta[move]
    axis = machine.tool_pose(q, errors)[:, :3, 2]
    a, b = axis[:-1], axis[1:]
    tilt = np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))
    tilt[first[1:] - 1] = 0.0  # from one move's end to the next move's start: no sub-step
    return np.maximum.reduceat(np.append(tilt, 0.0), first)


@dataclass(frozen=True)
class ProfileEdges:
    """A planar tool's straight edges where they cut, for `edge_substeps`.

    Attributes
    ----------
    edges : ndarray, shape (k, 2, 3)
        Each edge's two ends in the ``tool_tip`` frame (m): a V's flanks, a nose's
        flanks and its arc's chords.
    top : float
        Height (m, workpiece frame) above which the engine clips the tool before it takes a
        sweep's hull: the stock's top. Only an edge's part below it is held; ``inf``: all.
    """

    edges: np.ndarray
    top: float = math.inf

    @classmethod
    def of(cls, setups, stock) -> ProfileEdges:
        """The edges a cut of ``stock`` (a Part: its top is read) holds, for `plan`'s
        ``profile``: those of the planar tools among ``setups``, each a pair (tool, length),
        the tool's edge that far (m) beyond ``tool_tip`` along the tool axis (0: at it), in
        the ``tool_tip`` frame. No planar tool: no edges."""
        edges = [np.asarray(tool.vertices(), dtype=np.float64)[tool.edges()]
                 - np.array([0.0, 0.0, length]) for tool, length in setups
                 if getattr(tool, "planar", False)]
        return cls(np.concatenate(edges) if edges else np.zeros((0, 2, 3)),
                   float(stock.bounds[1, 2]))


def edge_substeps(machine, errors, starts: np.ndarray, delta: np.ndarray,
                  steps: np.ndarray, profile: ProfileEdges | None,
                  tolerance: float) -> np.ndarray:
    """Sub-steps of each move (``steps`` raised where needed) so that the hull of each
    sub-step's two poses leaves no straight edge of a planar tool's profile's true sweep by
    more than ``tolerance`` (docs/cutting.md, "A tilt with a move").

    The bound, by hand. An edge from a to b (length L) at the sub-step's two poses has the
    corners a0, b0 and a1, b1. Its true sweep over the sub-step is, to first order in the
    sub-step (the chord rule holds the second), the bilinear patch
    S(t, s) = (1 - t) (a0 + s (b0 - a0)) + t (a1 + s (b1 - a1)), t, s in [0, 1], while the
    hull holds the tetrahedron of the four corners. With the twist
    D = (b1 - a1) - (b0 - a0) (L times the change of the edge's direction), the patch's
    centre S(1/2, 1/2) = (a0 + b1) / 2 - D / 4 = (b0 + a1) / 2 + D / 4 lies halfway between
    the tetrahedron's two opposite edges, the diagonals a0-b1 and b0-a1, which stand
    w = |D . n| / 2 apart (n the unit normal to both diagonals). The tetrahedron's faces
    through either diagonal pass the centre at w / 2 = |D . n| / 4, on either side of the
    patch: the hull reaches that far past the edge's sweep, first order in the sub-step
    (D and the diagonals' normal's share of it both scale with the sub-step's tilt times
    its move's direction), where a point's chord leaves its arc by second order. A tilt
    alone (a0 = a1, a turn about the edge point) makes the corners coplanar (w = 0); a
    move alone (D = 0) too. Hence for each sub-step the largest |D . n| / 4 over the
    edges, each cut at ``profile.top`` (its part below it at either pose, the same share
    of the edge at both), and the count raised to its share of ``tolerance`` times
    `_MARGIN`. For v:90 50 um deep swung to B10 while moving 0.1 mm along X in 196
    sub-steps (0.051 deg each) about its edge point, the flank (L = 70.7 um, its direction
    turning by d / sqrt(2) at 45 deg to the B axis) gives
    |D . n| / 4 = h d sin(B) / (4 sqrt(1 + cos(B)^2)) = 1.38 nm at the end (h = 50 um its
    depth; measured 1.16 nm past a reference cut in 8 times the sub-steps, which keeps
    1/8 of it: 1.21 nm predicted), and at B30 4.2 nm (measured 4.0 nm).

    That waist is taken only for the edges a cheap bound cannot clear (`_uncleared`: L
    times the change of the tool's rotation over a sub-step, over 4): an edge whose every
    waist in a piece of a move is too small to raise the move's count is skipped there,
    which keeps every count to the bit (a nose's arc of 556 chords of 2.8 um under a C
    turn at 1 nm: only its two flanks and its top are read).

    ``profile`` None or without edges: ``steps`` returned as they are.
    """
    steps = np.asarray(steps, dtype=np.int64)
    if profile is None or not len(profile.edges) or not len(steps):
        return steps
    edges = np.asarray(profile.edges, dtype=np.float64).reshape(-1, 2, 3)
    largest = _largest_waists(machine, errors, starts, delta, steps, edges,
                              float(profile.top), tolerance)
    need = np.ceil(steps * largest / tolerance * _MARGIN).astype(np.int64)
    return np.maximum(steps, need)


def _largest_waists(machine, errors, starts, delta, steps, edges, top, tolerance,
                    bounded: bool = True) -> np.ndarray:
    """The largest waist (m, `edge_substeps`) over each move's sub-steps and the edges
    `_uncleared` leaves (all of them if not ``bounded``), 0 where it leaves none."""
    largest = np.zeros(len(steps))
    # each move's samples in pieces of about `per`: a sample takes 24 bytes per edge in each
    # of a dozen arrays (a C turn of three turns under nose:1.0:90, 559 edges, 23,504
    # samples: 5 GB taken whole); the pieces posed in blocks of _SAMPLES_PER_BLOCK samples
    per = max(2, _SAMPLES_PER_BLOCK // len(edges))
    move, first, last = _pieces(steps, per - 1)
    length = np.linalg.norm(edges[:, 1] - edges[:, 0], axis=1)
    longest = np.argsort(-length, kind="stable")
    extent = float(np.linalg.norm(edges, axis=2).max())
    for block in _blocks(last - first + 1, _SAMPLES_PER_BLOCK):
        pieces = (move[block], first[block], last[block])
        q, head = _samples(steps, starts, delta, pieces)
        poses = machine.tool_pose(q, errors)
        if bounded:
            reach = float(np.linalg.norm(poses[:, :3, 3], axis=1).max()) + extent
            kept = _uncleared(steps[move[block]], _largest_turn(poses, head),
                              length[longest], reach, tolerance)
        else:
            kept = np.full(len(block), len(edges))
        counts = np.diff(np.append(head, len(q)))
        for k in np.unique(kept[kept > 0]):
            chosen = np.flatnonzero(kept == k)
            subset = edges[np.sort(longest[:k])]
            for part in _blocks(counts[chosen], max(2, _SAMPLES_PER_BLOCK // int(k))):
                at = chosen[part]
                rows = np.repeat(head[at] - np.cumsum(counts[at]) + counts[at], counts[at])
                rows += np.arange(len(rows))
                np.maximum.at(largest, move[block][at], _largest_waist(
                    poses[rows], np.cumsum(counts[at]) - counts[at], subset, top))
    return largest


def _blocks(counts, most: int):
    """Consecutive runs of ``counts`` (indices into it) each summing to at most ``most``,
    or a single item where that alone exceeds it."""
    ends = np.cumsum(counts)
    lo = 0
    while lo < len(counts):
        hi = max(lo + 1, int(np.searchsorted(ends, ends[lo] - counts[lo] + most,
                                             side="right")))
        yield np.arange(lo, hi)
        lo = hi


def _pieces(steps, most: int):
    """``(move, first, last)``: each move's samples (its sub-steps' ends, 0 to ``steps``) in
    pieces of at most ``most`` sub-steps, sample ``first`` to ``last`` of move ``move``;
    consecutive pieces of a move share their end sample."""
    count = np.maximum(-(-steps // most), 1)
    move = np.repeat(np.arange(len(steps)), count)
    first = (np.arange(len(move)) - np.repeat(np.cumsum(count) - count, count)) * most
    return move, first, np.minimum(first + most, steps[move])


def _samples(steps, starts, delta, pieces):
    """Axis values of the samples of each of ``pieces`` (`_pieces`), and each piece's first
    row."""
    move, first, last = pieces
    counts = last - first + 1
    piece = np.repeat(np.arange(len(move)), counts)
    head = np.concatenate([[0], np.cumsum(counts)[:-1]])
    at = move[piece]
    fraction = (np.arange(int(counts.sum())) - head[piece] + first[piece]) / steps[at]
    return starts[at] + fraction[:, None] * delta[at], head


def _largest_turn(poses, first) -> np.ndarray:
    """The largest ||R1 - R0|| (the largest singular value; 2 sin(theta / 2) for a turn by
    theta) over one sub-step of each piece whose samples' ``poses`` start at rows
    ``first``, R0 and R1 the tool's rotations at the sub-step's two ends."""
    change = poses[1:, :3, :3] - poses[:-1, :3, :3]
    square = np.linalg.eigvalsh(np.matmul(np.swapaxes(change, 1, 2), change))[:, -1]
    turn = np.sqrt(np.maximum(square, 0.0))
    turn[first[1:] - 1] = 0.0  # from one piece's end to the next one's start: no sub-step
    return np.maximum.reduceat(np.append(turn, 0.0), first)


def _uncleared(steps, turn, lengths, reach: float, tolerance: float) -> np.ndarray:
    """How many of the edges of ``lengths`` (m, longest first) a piece of a move of
    ``steps`` sub-steps and largest `_largest_turn` ``turn`` may need read.

    The bound, by hand. Over a sub-step an edge of length L (vector e in the tool's
    frame) at the tool's rotations R0, R1 has the twist D = s (R1 - R0) e (s <= 1 its
    share below the top), so its waist |D . n| / 4 (`edge_substeps`, n a unit vector) is
    at most |D| / 4 <= L ||R1 - R0|| / 4 <= L turn / 4 = U. If
    ceil(steps * U / tolerance * _MARGIN) <= steps (the count's own expression, in the
    same order, each of whose rounded operations is monotone in U), no waist of that edge
    in that piece can raise the move's count: whichever edge holds the move's largest
    waist, if it is cleared the count is ``steps`` and the largest over the edges read is
    no more, and if it is not it is read. So the count is the same to the bit as when
    every edge is read, given the same poses. The corners the waist is taken from are
    rounded by some 1e-16 of their ``reach`` (m, from the workpiece's origin) in each
    operation; U adds `_ROUNDING` of it, and of itself. Since U grows with L, the
    edges cleared are the shortest: the number left is found by bisection.
    """
    n = len(lengths)
    lo, hi = np.zeros(len(steps), dtype=np.int64), np.full(len(steps), n)
    while np.any(lo < hi):
        mid = (lo + hi) // 2
        bound = (lengths[np.minimum(mid, n - 1)] * turn / 4.0 * (1.0 + _ROUNDING)
                 + _ROUNDING * reach)
        raises = np.ceil(steps * bound / tolerance * _MARGIN) > steps
        open_ = lo < hi
        lo, hi = (np.where(open_ & raises, mid + 1, lo), np.where(open_ & ~raises, mid, hi))
    return lo


def _largest_waist(poses, first, edges, top) -> np.ndarray:
    """The largest |D . n| / 4 (m, `edge_substeps`) over one sub-step of each piece whose
    samples' ``poses`` start at rows ``first``, over ``edges``."""
    rotation, origin = poses[:, :3, :3], poses[:, :3, 3]
    # both ends of every edge at once, R p + o as rows p^T R^T: a third of the time of
    # an einsum for each end, to the same counts (not to the last bit of each waist)
    ends = np.matmul(edges.reshape(-1, 3), np.swapaxes(rotation, 1, 2)) + origin[:, None]
    a, b = ends[:, 0::2], ends[:, 1::2]
    # the share [lo, hi] of each edge (from a) below the top at each pose
    za, zb = a[..., 2], b[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = np.clip((top - za) / (zb - za), 0.0, 1.0)
    below_a, below_b = za <= top, zb <= top
    lo = np.where(below_a, 0.0, np.where(below_b, cross, 1.0))
    hi = np.where(below_b, 1.0, np.where(below_a, cross, 0.0))
    lo = np.minimum(lo[:-1], lo[1:])  # either pose's part: the same share at both
    hi = np.maximum(hi[:-1], hi[1:])
    span = np.maximum(hi - lo, 0.0)[..., None]
    e0, e1 = b[:-1] - a[:-1], b[1:] - a[1:]
    a0 = a[:-1] + lo[..., None] * e0
    a1 = a[1:] + lo[..., None] * e1
    b0, b1 = a0 + span * e0, a1 + span * e1
    twist = (b1 - a1) - (b0 - a0)
    normal = np.cross(b1 - a0, a1 - b0)
    size = np.linalg.norm(normal, axis=-1)
    dot = np.abs(np.einsum("nki,nki->nk", twist, normal))
    waist = np.where(size > 0.0, dot / np.where(size > 0.0, size, 1.0), 0.0) / 4.0
    waist = waist.max(axis=1)
    waist[first[1:] - 1] = 0.0  # from one piece's end to the next one's start: no sub-step
    return np.maximum.reduceat(np.append(waist, 0.0), first)


def profile_substeps(machine, errors, starts: np.ndarray, delta: np.ndarray,
                     found: np.ndarray, rotary: np.ndarray, profile: ProfileEdges | None,
                     tolerance: float) -> np.ndarray:
    """``found`` raised by `edge_substeps` for the moves that turn a rotary axis (``rotary``
    the machine's rotary axes); a profile that only moves, or bends by the errors of a
    linear axis, keeps its count, to the bit."""
    rotary = np.asarray(rotary, dtype=bool)
    tilting = np.flatnonzero(np.any(delta[:, rotary] != 0.0, axis=1))
    if profile is None or not tilting.size:
        return found
    found = np.array(found, dtype=np.int64)
    found[tilting] = edge_substeps(machine, errors, starts[tilting], delta[tilting],
                                   found[tilting], profile, tolerance)
    return found
