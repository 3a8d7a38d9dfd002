"""What the test files of generic identification (tests/test_identification_fit_*.py)
and tests/test_identification_held.py share (not collected: no test_ prefix): robonano_ui,
the sensors' sigma, readings made from a truth, a random truth, a plan along X and Y, and
the check that a fit recovered its truth."""

from __future__ import annotations

import numpy as np

from machinesim.errors import ErrorModel
from machinesim.machines import load_machine

DEG = np.pi / 180
UM = 1e-6
URAD = 1e-6
MACHINE = load_machine("robonano_ui")
SIGMA = 50e-9


def read(truth, q, directions, points, frame="tool_tip"):
    """What the sensors read: the point's displacement from its nominal place, along u."""
    points = np.broadcast_to(points, (len(q), 3))

    def place(errors):
        pose = MACHINE.frame_pose(frame, q, errors)
        return pose[:, :3, 3] + np.einsum("nij,nj->ni", pose[:, :3, :3], points)
    return np.einsum("ni,ni->n", directions, place(truth) - place(None))


def random_truth(rng, names, length=20 * UM, angle=50 * URAD, tool=200 * UM,
                 tool_angle=1e-3, workpiece=50 * UM, workpiece_angle=5e-3):
    """Errors on ``names`` only (normal, standard deviations by family), zero elsewhere."""
    values = {}
    for name in names:
        rotation = name.split(".")[-1] in ("rx", "ry", "rz", "alpha", "beta", "gamma") or (
            name.startswith("location") and name.split(".")[-1][1] in "ABC")
        if name.startswith("tool."):
            values[name] = rng.normal(0, tool_angle if rotation else tool)
        elif name.startswith("workpiece."):
            values[name] = rng.normal(0, workpiece_angle if rotation else workpiece)
        else:
            values[name] = rng.normal(0, angle if rotation else length)
    return ErrorModel().with_parameters(values)


def assert_recovered(estimate, truth, names):
    """1e-6 relative or 1e-12 (m or rad) absolute: far above the float64 floor of the fit
    (its steps bottom out at ~1e-16 m and ~1e-15 rad), far below anything a plan with 50 nm
    sensors resolves."""
    values = truth.parameters()
    for name in names:
        got = estimate.values[estimate.names.index(name)]
        want = values.get(name, 0.0)
        assert abs(got - want) <= max(1e-6 * abs(want), 1e-12), (name, got, want)


def xy_plan():
    """Tool vertical (A = B = 0), C at 10 angles, readings along workpiece X and Y only."""
    rng = np.random.default_rng(3)
    n = 10
    xyz = rng.uniform([-0.05, -0.03, -0.01], [0.05, 0.03, 0.05], (n, 3))
    q = np.column_stack([xyz, np.zeros((n, 2)), np.arange(n) * 36 * DEG])
    return np.repeat(q, 2, axis=0), np.tile(np.eye(3)[:2], (n, 1))
