"""The check of each run's subtraction (machinesim.cutting.run_check) on sweeps that are the
union of convex pieces (a tool tilted across itself, `SweepSet._united`): the faces a
subtraction made are tested against each piece's planes, where the union's own hull would
hold material outside it."""

import math

import manifold3d
import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import HalfspaceIntersection
from test_cutting_run_check import (  # noqa: F401
    ROUND_OFF_M3,
    cut_exact_then_short,
    tetrahedron,
    union_short_of,
)
from tilted_cuts import swing

from machinesim.cutting import remove, run_check, sweepset
from machinesim.cutting.sweeps import ConvexPiece
from machinesim.end_mills import BallEndMill, FlatEndMill
from machinesim.workpiece import block

CUBE = manifold3d.Manifold.cube((10e-3, 10e-3, 10e-3))
#: Two boxes over two edges of the cube, across each other at its corner: their union, an L
#: seen from above, is not convex (its hull holds the corner x, y < 7 mm at z > 7 mm).
LOWS = [(7e-3, -1e-3, 7e-3), (-1e-3, 7e-3, 7e-3)]
HIGHS = [(11e-3, 11e-3, 11e-3), (11e-3, 11e-3, 11e-3)]


def box_piece(low, high) -> ConvexPiece:
    """The box [low, high] (m) as a ConvexPiece: its six outward planes, by hand."""
    low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    eye = np.eye(3)
    equations = np.concatenate([np.c_[eye, -high], np.c_[-eye, low]])
    return ConvexPiece(np.unique(equations, axis=0), low, high)


def l_union():
    boxes = [manifold3d.Manifold.cube(tuple(np.subtract(h, lo))).translate(lo)
             for lo, h in zip(LOWS, HIGHS, strict=True)]
    return boxes[0] + boxes[1], [box_piece(lo, h) for lo, h in zip(LOWS, HIGHS, strict=True)]


def test_a_face_left_inside_a_piece_of_a_union_is_found_at_its_depth():
    union, pieces = l_union()
    # the union, less a tetrahedron inside the first box (and the cube), subtracted: the
    # tetrahedron's faces y = 2 mm and x + y + z = 19 mm have their centroids 4/3 mm inside
    # the first box (from its faces x = 7 mm and z = 7 mm), by hand
    kept = CUBE - (union - tetrahedron((8e-3, 2e-3, 8e-3), 1e-3))
    kept.num_tri()
    assert run_check.deepest_inside(CUBE, kept, [union], [pieces]) == pytest.approx(
        4e-3 / 3, rel=1e-12, abs=0.0)
    # the union itself is not convex: without its pieces it is not tested
    assert run_check.deepest_inside(CUBE, kept, [union]) == 0.0


def test_a_union_with_nothing_left_inside_reports_no_depth():
    union, pieces = l_union()
    cut = CUBE - union
    # 3 x 10 x 3 mm under each box, the 3 x 3 x 3 mm corner counted once (by hand)
    assert cut.volume() == pytest.approx(10e-3 ** 3 - (2 * 90e-9 - 27e-9), rel=1e-12, abs=0.0)
    # the walls of the L's inner corner lie inside the union's hull, not inside a piece
    assert run_check.deepest_inside(CUBE, cut, [union], [pieces]) == 0.0
    assert run_check.subtract_run(CUBE, [union], [3], pieces=[pieces]).volume() == \
        pytest.approx(cut.volume(), rel=1e-12, abs=0.0)


def _chebyshev_centre(equations: np.ndarray) -> np.ndarray:
    """A point inside the polytope of the outward ``equations`` (p, 4): the centre of the
    largest ball in it."""
    norms = np.linalg.norm(equations[:, :3], axis=1)
    found = linprog([0.0, 0.0, 0.0, -1.0], A_ub=np.c_[equations[:, :3], norms],
                    b_ub=-equations[:, 3], bounds=[(None, None)] * 3 + [(0.0, None)])
    assert found.status == 0 and found.x[3] > 0.0
    return found.x[:3]


#: A 0.5 mm flat end mill swung +-1 deg in 4 sweeps about a Y line 50 um above its end face
#: and 50 um under the top of a 10 x 10 x 2 mm block, its tip at (5, 5) mm: its sides cross
#: that line, and every sweep is cut as two pieces (tests/test_cutting_tilted_solids.py).
RADIUS, ABOVE, UNDER_TOP = 0.5e-3, 50e-6, 50e-6


def _swung(pivot_height):
    tip = np.array([5e-3, 5e-3, -(pivot_height + UNDER_TOP)])
    return swing(4, tip, tip + np.array([0.0, 0.0, pivot_height]), math.radians(1.0))


@pytest.mark.parametrize("kind", ["flat", "ball"])
def test_a_split_sweep_keeps_the_planes_of_its_pieces(kind):
    """Each piece's kept planes and bounds bound the polytope (found by intersecting its
    half-spaces, a second method) whose union over the pieces is the sweep's solid."""
    if kind == "flat":
        tool, poses = FlatEndMill(RADIUS, chord_tol=1e-5), _swung(ABOVE)
    else:
        tool, poses = BallEndMill(RADIUS, chord_tol=1e-5), _swung(RADIUS + ABOVE)
    sweeps = sweepset.SweepSet(tool, [poses], 1e-9)
    hulls = sweeps.hulls(lambda low, high: np.ones(len(low), dtype=bool))[0]
    assert len(hulls) == 4
    for index in range(len(hulls)):
        pieces = hulls.pieces(index)
        assert pieces is not None and len(pieces) == 2
        polytopes = []
        for equations, lower, upper in pieces:
            corners = HalfspaceIntersection(equations, _chebyshev_centre(equations))
            points = corners.intersections
            assert (points >= lower - 1e-15).all() and (points <= upper + 1e-15).all()
            polytopes.append(manifold3d.Manifold.hull_points(points))
        united = manifold3d.Manifold.batch_boolean(polytopes, manifold3d.OpType.Add)
        assert united.volume() == pytest.approx(hulls[index].volume(), rel=1e-9, abs=0.0)
        assert (united ^ hulls[index]).volume() == pytest.approx(united.volume(), rel=1e-9, abs=0.0)


def test_remove_checks_the_runs_of_split_sweeps(union_short_of):  # noqa: F811
    stock, tool = block(10e-3, 10e-3, 2e-3), FlatEndMill(RADIUS, chord_tol=1e-5)
    paths = [_swung(ABOVE)]
    # 20 um above the end face at the middle pose, by the axis: inside the two sweeps that
    # end there, and the block
    exact, exact_report = cut_exact_then_short(stock, tool, paths, union_short_of,
                                               (5e-3, 5e-3, -80e-6))
    part, report = remove(stock, tool, paths, method="boolean")
    assert report.removed_volume == pytest.approx(exact_report.removed_volume, rel=1e-12,
                                                      abs=0.0)
    assert (part.manifold - exact.manifold).volume() <= ROUND_OFF_M3
