"""Unions of upright prisms by their footprints: an end mill's level passes.

An upright flat end mill moved level (a pocket's zigzag, a contour's level) sweeps a prism:
its footprint, the tool's bottom ring swept along the move in XY, stood between the tool's
floor and the clip plane over the stock (`SweepSet._translated`). Prisms that share their
floor and their top unite into one prism, over the union of their footprints. That union is
a plane problem, which Clipper2 (through manifold3d's `CrossSection`) solves in a fraction
of the time the same union takes in three dimensions, where every pass's floor lies in one
plane with its neighbours' and the boolean resolves them face against face (a zigzag pocket
of 900 passes, 2 mm end mill at 10 um step-over: 31 s in 3-D, 2 s by footprints, the same
solid: `benchmarks/end_mill_passes.py`).

Clipper2 rounds to a grid of 1e-8 of its unit and holds coordinates up to about 4.6e10 units.
The footprints are scaled by the power of two that takes their farthest coordinate to 2**32
units (`REACH`): scaling is exact in float64, and the grid is then 2.3e-18 of that
coordinate, a hundredth of float64's spacing there. Corners the union keeps from a footprint
come back bit for bit where their coordinates are within about a hundredth of the farthest
(tested at a millimetre and at 0.7 m); smaller ones, and the corners the union makes where
two footprints' edges cross, within that grid (a corner at y = 0.1 mm on a pocket at x =
0.5 m moves by up to 5e-19 m).
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Sequence

import manifold3d
import numpy as np
from manifold3d import OpType

from machinesim.cutting.sweeps import manifold_from

__all__ = ["Footprint", "level_prisms", "united_in_plane"]

#: Where the footprints' farthest coordinate is scaled to, in Clipper2's units: a tenth of
#: the 4.6e10 it holds (2**62 over its 1e8 grid steps a unit).
REACH = 2.0 ** 32
#: Footprints united at once, up a tree. Clipper2 unites a batch in one sweep of all its
#: edges, so n footprints that overlap (a pocket's passes at a fine step-over) cross each
#: other about n^2 times: 2500 passes of a 1 mm end mill at 4 um took 30 s in one batch,
#: 0.11 s in a tree of fours (0.17 s of twos, 0.31 s of 32s).
BRANCHES = 4
#: Fewest prisms on one floor and top worth a plane union: below it, the 3-D union is as fast.
FEWEST = 4

#: One upright prism: its floor's and its top's heights (m) and its footprint's corners
#: (k, 2), m, any order (the footprint is their convex hull).
Footprint = tuple[float, float, np.ndarray]


def level_prisms(members: np.ndarray, footprints: Sequence[Footprint | None],
                 run_id: int) -> tuple[list[manifold3d.Manifold], np.ndarray]:
    """The prisms that stand for ``members`` with a footprint, one per floor and top.

    Parameters
    ----------
    members : ndarray of int
        Sweep indices into ``footprints``.
    footprints : sequence of Footprint or None
        For each sweep that is an upright prism over the convex hull of its corners: its
        floor, its top and its corners; None for every other.
    run_id : int
        The original id the prisms' faces carry (the sweeps', `SweepSet.run_id`).

    Returns
    -------
    prisms : list of manifold3d.Manifold
        Each the union of the sweeps of one floor and top (at least `FEWEST` of them).
    rest : ndarray of int
        The members none of ``prisms`` stands for, in their order.
    """
    groups: dict[tuple[float, float], list[int]] = defaultdict(list)
    for i in members.tolist():
        footprint = footprints[i]
        if footprint is not None:
            groups[footprint[0], footprint[1]].append(i)
    prisms, taken = [], set()
    for (floor, top), group in groups.items():
        if len(group) < FEWEST:
            continue
        prism = _prism(floor, top, [footprints[i][2] for i in group], run_id)
        if prism is not None:
            prisms.append(prism)
            taken.update(group)
    rest = np.array([i for i in members.tolist() if i not in taken], dtype=members.dtype)
    return prisms, rest


def united_in_plane(footprints: Sequence[Footprint | None]) -> np.ndarray:
    """Which sweeps have a footprint on a floor and top that at least `FEWEST` share, over
    the whole cut (bool, one per sweep): those `level_prisms` unites in the plane (where a
    tile holds fewer of them, they go the 3-D way there)."""
    keys = [None if f is None else (f[0], f[1]) for f in footprints]
    counts: dict[tuple[float, float], int] = defaultdict(int)
    for key in keys:
        if key is not None:
            counts[key] += 1
    return np.array([key is not None and counts[key] >= FEWEST for key in keys], dtype=bool)


def _prism(floor: float, top: float, corners: list[np.ndarray],
           run_id: int) -> manifold3d.Manifold | None:
    """The prism from ``floor`` to ``top`` over the union of the corners' convex hulls; None
    where Clipper2 cannot take them (the caller unites the solids instead)."""
    farthest = max(float(np.abs(c).max()) for c in corners)
    if not 0.0 < farthest < math.inf:
        return None
    scale = 2.0 ** math.floor(math.log2(REACH / farthest))
    try:
        shapes = [manifold3d.CrossSection.hull_points(np.ascontiguousarray(c) * scale)
                  for c in corners]
        while len(shapes) > 1:  # neighbours in program order first: small unions
            shapes = [manifold3d.CrossSection.batch_boolean(shapes[i:i + BRANCHES], OpType.Add)
                      for i in range(0, len(shapes), BRANCHES)]
        plane = shapes[0]
    except RuntimeError:  # "Values exceed permitted range": not expected below REACH
        return None
    if plane.is_empty():
        return None
    mesh = plane.extrude(1.0).to_mesh64()
    vertices = np.array(mesh.vert_properties[:, :3], dtype=np.float64)
    upper = vertices[:, 2] > 0.5
    vertices[:, :2] /= scale
    vertices[:, 2] = np.where(upper, top, floor)
    return manifold_from(vertices, np.asarray(mesh.tri_verts), run_id)
