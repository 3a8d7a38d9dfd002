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
"""

from __future__ import annotations

import numpy as np

#: Sub-steps are raised by this share beyond the count the largest sampled tilt gives, for
#: a tilt rate that varies along the move (a C turn under a B-tilted tool is uniform; an
#: error table's tilt is not).
_MARGIN = 1.01
#: Samples whose poses are evaluated at once (128 bytes each, 16 MB).
_SAMPLES_PER_BLOCK = 1 << 17


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
