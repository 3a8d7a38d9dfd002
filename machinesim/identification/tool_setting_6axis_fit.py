"""Paper 001's readings through the generic fit: a model-based cross-check of its formulas.

The same `GrooveReading`s the paper's formulas take
(`machinesim.identification.tool_setting_6axis`) become observations of the tool tip
(`fit_observations`) and go through `machinesim.identification.fit` on the machine's
kinematics (`fit_check`), which identifies the same five parameters with Pinocchio's error
Jacobians instead of the closed forms. docs/procedures/tool_setting_6axis.md gives the
figures.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from machinesim.exceptions import InputError
from machinesim.identification.tool_setting_6axis import PARAMETERS, GrooveReading
from machinesim.metrology.prisms import SIGMA_FLOOR_M

__all__ = ["fit_check", "fit_observations"]


def fit_observations(machine, a: Sequence[GrooveReading], c: Sequence[GrooveReading],
                     b: Sequence[GrooveReading]):
    """The plates' readings as observations of the tool tip for
    `machinesim.identification.fit`.

    A groove is the sweep of the edge along its cutting block: at the axis values of a
    profile's station (``q_start`` to ``q_end``, interpolated where the nominal edge passes
    the measured centre), the tip was seen displaced from its nominal place (the nominal
    machine at those axis values) by

    - across the groove: the measured centre minus the nominal edge (every groove);
    - along the groove: the measured end point minus the nominal end (the A sets: the end
      face is the edge profile at the end of the cut);
    - along +z: minus the measured depth minus the nominal edge height (the B grooves, the
      paper's source of dZ; the plate top is the workpiece's z = 0).

    Each with the reading's standard uncertainty (floored at `SIGMA_FLOOR_M`).

    Parameters
    ----------
    machine : Machine
        The nominal machine the plates were cut on (axes X Y Z A B C).
    a, c, b : sequence of GrooveReading

    Returns
    -------
    Observations
    """
    from machinesim.identification.fit import observations

    q, directions, values, sigma = [], [], [], []
    for group, depths in ((a, False), (c, False), (b, True)):
        for g in group:
            ends = machine.tool_pose(np.array([g.q_start, g.q_end]))[:, :3, 3]
            run = ends[1, :2] - ends[0, :2]
            length = float(np.hypot(*run))
            if not length > 0.0:
                raise InputError("Expected a groove whose cutting block moves in xy",
                                 key="q_end")
            along = np.r_[run / length, 0.0]
            across = np.array([-along[1], along[0], 0.0])
            t = (g.points - ends[0, :2]) @ along[:2] / length
            stations = g.q_start + t[:, None] * (g.q_end - g.q_start)
            nominal = machine.tool_pose(stations)[:, :3, 3]
            seen = np.column_stack([g.points, -g.depths])
            q.append(stations)
            directions.append(np.tile(across, (len(t), 1)))
            values.append((seen - nominal) @ across)
            sigma.append(np.maximum(g.point_sigma, SIGMA_FLOOR_M))
            if depths:
                q.append(stations)
                directions.append(np.tile((0.0, 0.0, 1.0), (len(t), 1)))
                values.append(seen[:, 2] - nominal[:, 2])
                sigma.append(np.maximum(g.depth_sigma, SIGMA_FLOOR_M))
            if g.end is not None:
                q.append(g.q_end[None, :])
                directions.append(along[None, :])
                values.append([(g.end - ends[1, :2]) @ along[:2]])
                sigma.append([max(g.end_sigma, SIGMA_FLOOR_M)])
    return observations(np.concatenate(q), directions=np.concatenate(directions),
                        values=np.concatenate(values), sigma=np.concatenate(sigma))


def fit_check(machine, a: Sequence[GrooveReading], c: Sequence[GrooveReading],
              b: Sequence[GrooveReading]):
    """Cross-check the paper's formulas: `PARAMETERS` by `machinesim.identification.fit` on
    the machine's kinematics, from the same readings (`fit_observations`).

    The paper reads each parameter from one stage (dx, dy from the A sets, e from the
    triangle, dZ from the B depths); the fit uses every reading at once, through Pinocchio's
    error Jacobians instead of the closed forms. Both are least squares on the same
    readings, so without noise they agree to the readings' resolution; with noise, within
    the uncertainties (docs/procedures/tool_setting_6axis.md gives the figures).

    Returns
    -------
    Estimate
    """
    from machinesim.identification.fit import fit

    return fit(machine, fit_observations(machine, a, c, b), list(PARAMETERS))
