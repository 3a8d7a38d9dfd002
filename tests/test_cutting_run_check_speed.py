"""The shortcuts of the check of each run's subtraction (machinesim.cutting.run_check): the
new vertices found by keys, the planes of a solid taken a few at a time. Each gives what
the plain computation gives."""

import numpy as np
from test_cutting_run_check import saved

from machinesim.cutting import run_check


def plain_deepest(before, after, solids):
    """`run_check.deepest_inside` the plain way: the new vertices by np.isin over rows of
    24 bytes, every centroid of the new faces against every plane of every convex solid."""
    equations, starts, _, _ = run_check._planes(solids)
    mesh = after.to_mesh64()
    vertices = np.asarray(mesh.vert_properties)[:, :3]
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64)
    rows = np.dtype((np.void, 24))
    new = ~np.isin(np.ascontiguousarray(vertices).view(rows).ravel(),
                   np.ascontiguousarray(np.asarray(before.to_mesh64().vert_properties)[:, :3])
                   .view(rows).ravel())
    centroids = vertices[triangles[new[triangles].any(axis=1)]].mean(axis=1)
    outside = centroids @ equations[:, :3].T + equations[:, 3]
    return max(float(-np.maximum.reduceat(outside, starts, axis=1).min()), 0.0)


def test_unknown_points_are_those_not_known_bit_for_bit():
    rng = np.random.default_rng(0)
    known = rng.normal(scale=1e-3, size=(5000, 3))
    known[0] = [0.0, 1e-3, 2e-3]
    fresh = rng.normal(scale=1e-3, size=(700, 3))
    # a known point with one coordinate one ulp away, and with 0 written -0: not known
    fresh[0] = known[1] + [0.0, 0.0, np.spacing(known[1, 2])]
    fresh[1] = [-0.0, 1e-3, 2e-3]
    points = np.concatenate([known[rng.permutation(5000)[:3000]], fresh])
    order = rng.permutation(len(points))
    expected = np.arange(len(points))[order] >= 3000
    assert np.array_equal(run_check._unknown(points[order], known), expected)
    assert run_check._unknown(points, np.zeros((0, 3))).all()


def test_a_point_whose_key_a_known_point_has_is_compared_bit_for_bit():
    known = np.array([[1e-3, 2e-3, 3e-3]])
    bits = run_check._bits(known)[0].copy()
    # y one bit up, x changed so that the key stays the same
    other = bits.copy()
    other[1] += np.uint64(1)
    other[0] ^= ((bits[1:2] * run_check.MIX[0]) ^ (other[1:2] * run_check.MIX[0]))[0]
    point = other.view(np.float64)[None]
    assert run_check._keys(other[None])[0] == run_check._keys(bits[None])[0]
    assert run_check._unknown(np.concatenate([known, point]), known).tolist() == [False, True]


def test_deepest_inside_the_saved_wedge_is_the_plain_computation():
    before = saved("before")
    sweeps = [saved(f"sweep{i}") for i in range(8)]
    united = run_check.subtract_run(before, sweeps, list(range(len(sweeps))), check=False)
    again = run_check.one_at_a_time(before, sweeps)
    # 168 nm inside a sweep united (the saved wedge); round-off once cut one at a time
    for after in (united, again):
        assert run_check.deepest_inside(before, after, sweeps) == plain_deepest(
            before, after, sweeps)
    assert plain_deepest(before, united, sweeps) > 1e-7
