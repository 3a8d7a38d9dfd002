"""What the engine's test files (tests/test_cutting_engine.py, test_cutting_engine_reports.py,
test_cutting_engine_joins.py) share (not collected: no test_ prefix): the tolerances, both
engines, tool poses and straight V grooves along X and Y."""

import numpy as np
import pytest

#: Geometry read off the exact float64 mesh: vertices at mm scale carry ~1e-19 m round-off
#: per operation, so 0.01 nm (1e-11 m) leaves eight orders of margin and still catches any
#: real geometric error.
LENGTH_TOL = 1e-11

#: Volumes of exact meshes agree to float64 summation round-off (~1e-15 relative).
VOLUME_REL = 1e-12

#: Both engines, with the method each reports: the height-field mesher takes straight
#: grooves across a block when allowed, the boolean engine always can.
METHODS = pytest.mark.parametrize(("method", "used"), [("auto", "relief"),
                                                        ("boolean", "boolean")])

ALONG_Y = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def pose(position, rotation=None):
    matrix = np.eye(4)
    matrix[:3, :3] = np.eye(3) if rotation is None else rotation
    matrix[:3, 3] = position
    return matrix


def groove_x(y, depth, x0=-1e-3, x1=5e-3, dz=0.0):
    return np.array([pose((x0, y, -depth + dz)), pose((x1, y, -depth + dz))])


def groove_y(x, depth, y0=-1e-3, y1=5e-3):
    return np.array([pose((x, y0, -depth), ALONG_Y), pose((x, y1, -depth), ALONG_Y)])
