"""How far above the work a program's rapids (G00) pass: each rapid's edge over the stock's
top plane and its tool's vertical gap to the cut part, from the planned motion on the
erroneous machine. Shared by tests/test_tool_rotation_arm_clearance.py; not part of the
package (no test_ prefix: not collected).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim import motion
from machinesim.metrology.surface import grid_heights
from machinesim.nc import MOVE_KINDS

#: Largest step (m) of the edge between the samples a rapid is read at.
STEP_M = 20e-6
#: Largest step (m) between the points a tool profile is read at.
PROFILE_STEP_M = 10e-6


@dataclass(frozen=True)
class RapidClearance:
    """One rapid's clearance (m) over the stock (None where its edge never passes over the
    block's footprint) and its tool's least vertical gap to the part (None where no part of
    the tool passes over it)."""

    line: int
    over_top: float | None
    gap: float | None


def profile_points(tool) -> np.ndarray:
    """The tool's profile polygon (tool_tip frame, m) read every `PROFILE_STEP_M`."""
    vertices = np.asarray(tool.vertices(), dtype=float)
    points = []
    for a, b in zip(vertices[:-1], vertices[1:], strict=True):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / PROFILE_STEP_M)))
        points.append(a + (b - a) * np.linspace(0.0, 1.0, n + 1)[:-1, None])
    points.append(vertices[-1:])
    return np.vstack(points)


def _samples(q: np.ndarray, machine, errors) -> np.ndarray:
    """Axis values along one rapid's planned samples, subdivided so the edge steps at most
    `STEP_M` (axes linear between the planner's samples)."""
    edge = machine.tool_pose(q, errors)[:, :3, 3]
    rows = [q[:1]]
    for k in range(1, len(q)):
        n = max(1, int(np.ceil(np.linalg.norm(edge[k] - edge[k - 1]) / STEP_M)))
        s = np.linspace(0.0, 1.0, n + 1)[1:, None]
        rows.append(q[k - 1] + (q[k] - q[k - 1]) * s)
    return np.vstack(rows)


def rapid_clearances(program, machine, errors, tool, part, top: float,
                     footprint) -> list[RapidClearance]:
    """Per rapid of ``program`` on ``machine`` with ``errors``: the least height of the edge
    above ``top`` (the stock's top, m) where it is over ``footprint`` ((x0, x1), (y0, y1),
    m), and the least vertical distance from the tool's profile down to ``part``'s surface
    (heights read exactly from its mesh, `grid_heights`)."""
    trajectory = motion.plan(program, machine, errors, tool_points=tool.vertices())
    profile = np.c_[profile_points(tool), np.ones(len(profile_points(tool)))]
    (x0, x1), (y0, y1) = footprint
    vertices, triangles = part.mesh()
    out = []
    for i, kind in enumerate(trajectory.kinds):
        if MOVE_KINDS[kind] != "rapid":
            continue
        q = trajectory.q[trajectory.offsets[i]:trajectory.offsets[i + 1]]
        poses = machine.tool_pose(_samples(q, machine, errors), errors)
        edge = poses[:, :3, 3]
        over = (edge[:, 0] >= x0) & (edge[:, 0] <= x1) & (edge[:, 1] >= y0) & (edge[:, 1] <= y1)
        over_top = float((edge[over, 2] - top).min()) if over.any() else None
        gap = None
        for pose in poses:
            points = (profile @ pose.T)[:, :3]
            if points[:, 0].max() < x0 or points[:, 0].min() > x1:
                continue
            order = np.argsort(points[:, 1])
            ys, keep = np.unique(points[order, 1], return_index=True)
            z = points[order, 2][keep]
            x = np.array([points[:, 0].mean()])  # the profile stands across X
            heights = grid_heights((vertices, triangles), x, ys)[:, 0]
            below = ~np.isnan(heights)
            if below.any():
                least = float((z[below] - heights[below]).min())
                gap = least if gap is None else min(gap, least)
        out.append(RapidClearance(int(trajectory.lines[i]), over_top, gap))
    return out
