"""Cut in the tool's frame when the tool stands tilted in the workpiece frame.

A workpiece set on the machine with a tilt (a workpiece setting error alpha, beta), or a
tool set with a rotation error, leaves the tool's axis off the workpiece's Z by a fraction
of a milliradian. The sweeps are then the same exact solids as with an upright tool, turned;
but their faces that coincide in exact arithmetic (the flat end of an end mill on every
sweep of a level pass, which covers each point of the floor some twenty times) no longer
coincide in float64: each sweep's floor is turned with its own round-off, 1e-19 m apart.
manifold3d then cuts every floor against every other it overlaps, and the part's floor
breaks into an arrangement of slivers: a single circle of an end mill, 0.8 mm across, on a
block tilted 0.02 deg made 1.7 million triangles in about 3 minutes, and with a second
level outgrew 24 GB (`benchmarks/end_mill_passes.py --tilted`).

When the tool has a flat end and every pose of a cut shares one orientation (a 3-axis cut,
or any cut whose rotary axes stand still), the cut is exact in a frame turned with the
tool: the stock is turned into it, the poses become pure translations (their rotation
exactly the identity), the floors are level and coincide as they do on an upright machine,
and the part is turned back. The turns move the part's vertices by round-off, ~1e-19 m on
a part of millimetres; the poses' own spread of orientation, at most
`tolerances.SAME_ORIENTATION` (1e-12), is dropped, which moves a tool point 1 mm from the
tip by at most 1e-15 m. The holder's check and the rapids' are made in the same frame, for
the same reason (a retract up the tool, a holder's room in the slot the levels above cut).

Only a flat end is shared so widely: a ball's or a round nose's lowest point is a vertex,
and their passes' faces meet only along one path. For them the workpiece frame stays, where
passes laid along its axes (paper 002's crown faces, each cut turned by C) are cut faster
than turned off them by a tilt (the crown after compensation: 25 s there, 31 s in the
tool's frame, tilted 1.93 deg).
"""

from __future__ import annotations

import manifold3d
import numpy as np

from machinesim.tolerances import SAME_ORIENTATION
from machinesim.workpiece import Part

__all__ = ["flat_end", "into_frame", "out_of_frame", "tool_frame"]


def flat_end(tool) -> bool:
    """Whether the tool's lowest points span a face (an end mill's end), not one vertex."""
    vertices = np.asarray(tool.vertices(), dtype=np.float64)
    return int(np.count_nonzero(vertices[:, 2] == vertices[:, 2].min())) >= 3


def tool_frame(poses: np.ndarray, tool) -> np.ndarray | None:
    """The tool's common orientation (3, 3) when it tilts a flat-ended tool's Z, else None.

    None for a tool without a flat end (`flat_end`), when the poses' orientations differ by
    more than `SAME_ORIENTATION` (a cut that turns the tool), or when the tool's Z is the
    workpiece's Z exactly (an upright tool, turned about Z at most): there the floors
    already coincide.
    """
    if not len(poses) or not flat_end(tool):
        return None
    rotation = poses[:, :3, :3]
    first = rotation[0]
    if not (np.any(first[2, :2]) or np.any(first[:2, 2])):
        return None
    if float(np.abs(rotation - first).max()) > SAME_ORIENTATION:
        return None
    return first.copy()


def _turned(solid: manifold3d.Manifold, rotation: np.ndarray) -> manifold3d.Manifold:
    return solid.transform(np.hstack([rotation, np.zeros((3, 1))]))


def into_frame(stock: Part, paths: list[np.ndarray], frame: np.ndarray,
               windows=None) -> tuple[Part, list[np.ndarray]]:
    """The stock and the paths in the tool's frame ``frame`` (from `tool_frame`).

    ``windows`` (xmin, xmax, ymin, ymax), m, in the workpiece frame: the stock is cut down
    to them first, since a window is a box in the workpiece frame and not in the tool's
    (the part the engine returns is the stock inside the windows either way).
    """
    if windows is not None:
        from machinesim.cutting.windows import clip_to  # windows builds on the engine

        stock = clip_to(stock, windows)
    solid = stock.manifold
    turn = np.eye(4)
    turn[:3, :3] = frame.T
    turned = []
    for path in paths:
        poses = turn @ path
        poses[:, :3, :3] = np.eye(3)
        turned.append(poses)
    return Part(_turned(solid, frame.T)), turned


def out_of_frame(part: Part, frame: np.ndarray) -> Part:
    """A part cut in the tool's frame ``frame``, turned back into the workpiece frame."""
    return Part(_turned(part.manifold, frame))
