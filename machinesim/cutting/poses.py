"""The poses `machinesim.cutting.engine.remove` takes: paths of rigid transforms, checked
before anything is cut (`_check_paths`: numbers of shape (N, 4, 4), rigid, within
`FARTHEST_M` of the workpiece origin; `_check_turns`: no step turning the tool by more than
`tolerances.MAX_STEP_TURN_RAD`), and how finely a rotary move is split for its sweeps'
chords to stay within a tolerance (`rotary_substeps`). Moved out of engine.py, which
re-exports `FARTHEST_M` and `rotary_substeps`."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from machinesim.exceptions import InputError, brief
from machinesim.rotations import not_rigid
from machinesim.tolerances import MAX_STEP_TURN_RAD, RIGID_TOL
from machinesim.tools import arc_segments

__all__ = ["FARTHEST_M", "rotary_substeps"]

#: Farthest the tool may go from the workpiece origin in a cut, m (any machine's travel is
#: well within): float64's spacing grows with distance, 1.2e-7 m at 1e9 m, where a sweep
#: across a 10 mm block came out as no cut at all. `remove` refuses a pose beyond it, as
#: `machinesim.cutting.cut` refuses a move: a flat end mill's slot from -1e9 to 1e9 m
#: through a 10 mm block removed nothing (an empty cut), from -1e7 to 1e7 m 1.5 % less; a
#: V groove from the block's middle to 1 km away removes 1.7e-6 less, to 40 m the same bits
#: as to 11 mm.
FARTHEST_M = 1000.0


def rotary_substeps(radius: float, angle: float, chord_tol: float = 1e-9) -> int:
    """Sub-steps that keep a point at ``radius`` from a rotation axis within ``chord_tol``.

    A point turning by ``step`` about an axis at distance r leaves its chord by the sagitta
    r (1 - cos(step / 2)); the count is the fewest equal steps over ``angle`` with a sagitta
    at most ``chord_tol``.

    Parameters
    ----------
    radius : float
        Largest distance of a tool point from the rotation axis, m.
    angle : float
        Rotation of the move, rad.
    chord_tol : float
        Largest chord error, m (default 1 nm, the axis resolution).
    """
    if radius <= 0.0 or angle == 0.0:
        return 1
    return arc_segments(radius, abs(angle), chord_tol)


def _check_paths(paths) -> list[np.ndarray]:
    """Paths as float64 arrays (N_i, 4, 4) of rigid transforms, else InputError naming one."""
    arrays = []
    if isinstance(paths, str | bytes) or not isinstance(paths, Iterable):
        raise InputError(f"Expected paths as a sequence of pose arrays (N, 4, 4), got "
                         f"{type(paths).__name__} {brief(repr(paths))}", key="paths")
    for index, path in enumerate(paths):
        try:
            poses = np.asarray(path, dtype=np.float64)
        except (TypeError, ValueError):  # text, None, ragged lists: no float array
            raise InputError(f"path {index}: expected poses of shape (N, 4, 4) as numbers, "
                             f"got {type(path).__name__} {brief(repr(path))}",
                             key="paths") from None
        if poses.ndim != 3 or poses.shape[1:] != (4, 4):
            raise InputError(
                f"path {index}: expected poses of shape (N, 4, 4), got {poses.shape}",
                key="paths",
            )
        arrays.append(poses)
    if not arrays:
        return arrays
    poses = np.concatenate(arrays)
    bad = not_rigid(poses, RIGID_TOL)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        path = int(np.searchsorted(np.cumsum([len(a) for a in arrays]), first, side="right"))
        raise InputError(
            f"path {path}: pose {first - sum(len(a) for a in arrays[:path])} is not a rigid "
            f"transform (finite, orthonormal rotation within {RIGID_TOL}, no mirror, last row "
            f"0 0 0 1): "
            f"{poses[first].tolist()}",
            key="paths",
        )
    # hypot, not norm: a tool 1e304 m out squared to inf ('inf m', 'spacing nan m'), and a
    # distance not finite is beyond too (NaN > FARTHEST_M is False)
    where = poses[:, :3, 3]
    distance = np.hypot(np.hypot(where[:, 0], where[:, 1]), where[:, 2])
    far = np.flatnonzero(~(distance <= FARTHEST_M))
    if far.size:
        first = int(far[0])
        path = int(np.searchsorted(np.cumsum([len(a) for a in arrays]), first, side="right"))
        raise InputError(
            f"path {path}: pose {first - sum(len(a) for a in arrays[:path])} lies "
            f"{float(distance[first]):.6g} m from the workpiece's origin "
            f"({poses[first, :3, 3].tolist()} m); expected within {FARTHEST_M:g} m, beyond "
            "any machine's travel, where float64 keeps no nanometre (its spacing there is "
            f"{np.spacing(distance[first]):.2g} m) and the part would come out wrong (poses "
            "are in m: were they given in mm or um?)",
            key="paths",
        )
    return arrays


def _check_turns(paths: list[np.ndarray], rotational: bool) -> None:
    """InputError naming the first pair of consecutive poses between which the tool turns
    by more than `MAX_STEP_TURN_RAD` (its axis, for a ``rotational`` tool)."""
    for index, poses in enumerate(paths):
        if len(poses) < 2:
            continue
        r0, r1 = poses[:-1, :3, :3], poses[1:, :3, :3]
        if rotational:
            a0, a1 = r0[:, :, 2], r1[:, :, 2]
            turn = np.arctan2(np.linalg.norm(np.cross(a0, a1), axis=1),
                              np.einsum("ni,ni->n", a0, a1))
            what = "the tool's axis tilts"
        else:
            # the angle of r1 r0^T, from its trace
            cosine = (np.einsum("nij,nij->n", r0, r1) - 1.0) / 2.0
            turn = np.arccos(np.clip(cosine, -1.0, 1.0))
            what = "the tool turns"
        far = np.flatnonzero(turn > MAX_STEP_TURN_RAD)
        if far.size:
            at = int(far[0])
            raise InputError(
                f"path {index}: {what} by {math.degrees(float(turn[at])):.6g} deg from pose "
                f"{at} to pose {at + 1} in one step, more than "
                f"{math.degrees(MAX_STEP_TURN_RAD):g} deg: a sweep is cut as the hull of its "
                "two poses, which stands for the tool's path only while each straight face "
                "looks the same way at both (its mean normal, by which a tilt is split, "
                "vanishes at a half turn); give the turn in sub-steps (the NC planner does, "
                "to its chord tolerance)",
                key="paths",
            )
