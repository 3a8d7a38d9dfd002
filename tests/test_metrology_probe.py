"""Touch-probe contact against closed forms (plane, V flanks, edge capsule, vertex sphere), a
tessellated sphere, and a brute-force bisection on the distance to the mesh."""

import manifold3d
import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.metrology import Contacts, MeshIndex, touch, touch_many
from machinesim.metrology import probe as probe_module
from machinesim.workpiece import Part

#: Travel agrees with the closed form to 0.001 nm: float64 round-off on a ~10 mm part is
#: ~1e-18 m, so 1e-12 m fails on any real error yet is 100x tighter than the brief's 0.1 nm.
TRAVEL_M = 1e-12
MM = 1e-3
R = 0.25 * MM  # the ruby ball of the alpha-0iB probe


def box(size, origin=(0.0, 0.0, 0.0)) -> manifold3d.Manifold:
    return manifold3d.Manifold.cube(size).translate(origin)


def v_groove_part(centre: float, bottom: float) -> Part:
    """10 x 4 x 3 mm block with a 90-degree V groove along y, lowest edge at (centre, bottom)."""
    side = 4 * MM
    diamond = manifold3d.Manifold.cube([side, 20 * MM, side], center=True)
    diamond = diamond.rotate([0.0, 45.0, 0.0]).translate([centre, 0.0, bottom + side / np.sqrt(2)])
    return Part(box([10 * MM, 4 * MM, 3 * MM]) - diamond)


def distance_to_mesh(points: np.ndarray, vertices: np.ndarray, triangles: np.ndarray):
    """Distance from each point (k, 3) to the closest point of any triangle, by closest points.

    Independent of the sweep: the distance to a triangle is the distance to its plane when
    the foot falls inside it, else the least distance to its three edge segments.
    """
    def dot(x, y):
        return np.sum(x * y, axis=-1)

    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    with np.errstate(invalid="ignore"):  # booleans leave a few zero-area slivers: edges only
        normal /= np.linalg.norm(normal, axis=1)[:, None]
    p = points[:, None, :]  # (k, 1, 3) against (m, 3) triangles
    height = dot(p - a, normal)
    foot = p - height[..., None] * normal
    inside = np.ones(height.shape, dtype=bool)
    edge = np.full(height.shape, np.inf)
    for s, e in ((a, b), (b, c), (c, a)):
        inside &= dot(np.cross(e - s, foot - s), normal) >= 0.0
        u = np.clip(dot(p - s, e - s) / dot(e - s, e - s), 0.0, 1.0)
        edge = np.minimum(edge, np.linalg.norm(p - s - u[..., None] * (e - s), axis=-1))
    return np.min(np.where(inside, np.abs(height), edge), axis=1)


def bisected_travel(mesh, centre, direction, radius, max_travel, steps=400):
    """First travel at which the distance to the mesh reaches the radius, by scan + bisection.

    Returns None when no scanned point comes within the radius. The scan step must be short
    enough not to step over a contact (aimed, non-grazing approaches in these tests).
    """
    direction = direction / np.linalg.norm(direction)
    t = np.linspace(0.0, max_travel, steps + 1)
    gap = distance_to_mesh(centre + t[:, None] * direction, *mesh) - radius
    assert gap[0] > 0.0
    hits = np.flatnonzero(gap <= 0.0)
    if hits.size == 0:
        return None
    lo, hi = t[hits[0] - 1], t[hits[0]]
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        if distance_to_mesh((centre + mid * direction)[None], *mesh)[0] > radius:
            lo = mid
        else:
            hi = mid
    return hi


def test_plane_contact_travels_the_gap():
    part = Part(box([10 * MM, 10 * MM, 3 * MM]))
    gap = 0.4 * MM
    contact = touch(part, [3 * MM, 4 * MM, 3 * MM + R + gap], [0, 0, -1], R, 1 * MM)
    assert contact.travel == pytest.approx(gap, rel=0, abs=TRAVEL_M)
    np.testing.assert_allclose(contact.point, [3 * MM, 4 * MM, 3 * MM], rtol=0, atol=TRAVEL_M)
    np.testing.assert_allclose(contact.centre, [3 * MM, 4 * MM, 3 * MM + R], rtol=0,
                               atol=TRAVEL_M)
    np.testing.assert_allclose(contact.normal, [0, 0, 1], rtol=0, atol=1e-9)
    angle = np.radians(30.0)
    slanted = touch(part, [3 * MM, 4 * MM, 3 * MM + R + gap],
                    [np.sin(angle), 0, -np.cos(angle)], R, 1 * MM)
    assert slanted.travel == pytest.approx(gap / np.cos(angle), rel=0, abs=TRAVEL_M)


def test_travel_limits_and_misses():
    part = Part(box([10 * MM, 10 * MM, 3 * MM]))
    start = [5 * MM, 5 * MM, 3.5 * MM + R]
    assert touch(part, start, [0, 0, -1], R, 0.4 * MM) is None  # stops short of the gap
    assert touch(part, start, [0, 0, 1], R, 5 * MM) is None  # moves away
    assert touch(part, start, [1, 0, 0], R, 50 * MM) is None  # passes over it
    at_limit = touch(part, start, [0, 0, -1], R, 0.5 * MM)  # contact right at the limit
    assert at_limit.travel == pytest.approx(0.5 * MM, rel=0, abs=TRAVEL_M)
    scaled = touch(part, start, [0, 0, -7], R, 1 * MM)  # directions are normalised
    assert scaled.travel == at_limit.travel


def test_v_flank_at_an_inclined_approach():
    part = v_groove_part(5 * MM, 2 * MM)
    normal = np.array([-1.0, 0.0, 1.0]) / np.sqrt(2)  # right flank, pointing into the groove
    on_flank = np.array([5 * MM, 0.0, 2 * MM])
    centre = np.array([5 * MM, 2 * MM, 3.5 * MM])
    angle = np.radians(20.0)
    d = np.array([np.sin(angle), 0.0, -np.cos(angle)])
    expected = (normal @ (centre - on_flank) - R) / -(normal @ d)
    contact = touch(part, centre, d, R, 3 * MM)
    assert contact.travel == pytest.approx(expected, rel=0, abs=TRAVEL_M)
    np.testing.assert_allclose(contact.point, centre + expected * d - R * normal, rtol=0,
                               atol=TRAVEL_M)
    np.testing.assert_allclose(contact.normal, normal, rtol=0, atol=1e-9)


def test_v_groove_seats_the_ball_on_both_flanks():
    part = v_groove_part(5 * MM, 2 * MM)
    contact = touch(part, [5 * MM, 2 * MM, 3.5 * MM], [0, 0, -1], R, 3 * MM)
    # Centre seated R * sqrt(2) above the lowest edge, touching each flank R / sqrt(2) aside.
    assert contact.travel == pytest.approx(1.5 * MM - R * np.sqrt(2), rel=0, abs=TRAVEL_M)
    assert abs(contact.point[0] - 5 * MM) == pytest.approx(R / np.sqrt(2), rel=0, abs=TRAVEL_M)
    assert contact.point[2] == pytest.approx(2 * MM + R / np.sqrt(2), rel=0, abs=TRAVEL_M)


def test_edge_contact_is_the_capsule_closed_form():
    part = Part(box([10 * MM, 4 * MM, 3 * MM]))
    a, b = 1 * MM, 0.1 * MM  # start 1 mm out from the edge, 0.1 mm above the top
    contact = touch(part, [10 * MM + a, 2 * MM, 3 * MM + b], [-1, 0, 0], R, 2 * MM)
    assert contact.travel == pytest.approx(a - np.sqrt(R**2 - b**2), rel=0, abs=TRAVEL_M)
    np.testing.assert_allclose(contact.point, [10 * MM, 2 * MM, 3 * MM], rtol=0, atol=TRAVEL_M)


def test_vertex_contact_is_the_sphere_closed_form():
    part = Part(box([10 * MM, 4 * MM, 3 * MM]))
    a, by, bz = 1 * MM, 0.1 * MM, 0.12 * MM
    contact = touch(part, [10 * MM + a, 4 * MM + by, 3 * MM + bz], [-1, 0, 0], R, 2 * MM)
    assert contact.travel == pytest.approx(a - np.sqrt(R**2 - by**2 - bz**2), rel=0,
                                           abs=TRAVEL_M)
    np.testing.assert_allclose(contact.point, [10 * MM, 4 * MM, 3 * MM], rtol=0, atol=TRAVEL_M)


def test_tessellated_sphere_against_bisection_and_the_true_sphere():
    radius = 2 * MM
    # A geodesic sphere from a refined octahedron: 32 segments round, 512 triangles.
    sphere = manifold3d.Manifold.sphere(radius, 32)
    part = Part(sphere)
    vertices, triangles = part.mesh()
    assert len(triangles) == 512
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    inner = np.min(np.abs(np.einsum("ij,ij->i", a, normal)) / np.linalg.norm(normal, axis=1))
    index = MeshIndex.from_surface(part)
    rng = np.random.default_rng(0)
    for _ in range(12):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        start = 5 * MM * u
        contact = touch(index, start, -u, R, 5 * MM)
        # The polyhedron lies between the sphere and the ball through its nearest face plane.
        assert 5 * MM - radius - R <= contact.travel <= 5 * MM - inner - R
        aimed = -u + 0.2 * rng.normal(size=3)
        contact = touch(index, start, aimed, R, 5 * MM)
        expected = bisected_travel((vertices, triangles), start, aimed, R, 5 * MM)
        if expected is None:
            assert contact is None
        else:
            assert contact.travel == pytest.approx(expected, rel=0, abs=TRAVEL_M)
            gap = distance_to_mesh(contact.centre[None], vertices, triangles)[0]
            assert gap == pytest.approx(R, rel=0, abs=TRAVEL_M)


def test_random_touches_match_bisection_on_a_pyramid_field(monkeypatch):
    # 12 x 12 pyramids of 0.25 mm pitch: the ball spans several, so the first contact is
    # rarely on the triangle nearest its path and the pruning of the second pass matters.
    pitch, depth, count = 0.25 * MM, 0.15 * MM, 12
    side = 1 * MM
    cuts = []
    for k in range(count + 1):
        diamond = manifold3d.Manifold.cube([side, 12 * MM, side], center=True)
        diamond = diamond.rotate([0.0, 45.0, 0.0]).translate(
            [k * pitch, 1.5 * MM, -depth + side / np.sqrt(2)])
        cuts += [diamond, diamond.rotate([0.0, 0.0, 90.0]).translate([3 * MM, 0.0, 0.0])]
    stock = box([3 * MM, 3 * MM, 1 * MM], [0.0, 0.0, -1 * MM])
    part = Part(manifold3d.Manifold.batch_boolean([stock, *cuts], manifold3d.OpType.Subtract))
    mesh = part.mesh()
    rng = np.random.default_rng(0)
    targets = rng.uniform([-0.3 * MM, -0.3 * MM, -0.3 * MM], [3.3 * MM, 3.3 * MM, 0.0], (24, 3))
    u = rng.normal(size=(24, 3))
    u[:, 2] = np.abs(u[:, 2]) + 1.0  # from above (start z > 0.9 mm: clear of the part)
    u /= np.linalg.norm(u, axis=1)[:, None]
    starts = targets + 2.5 * MM * u
    expected = [bisected_travel(mesh, starts[k], -u[k], R, 3 * MM, steps=150)
                for k in range(len(starts))]
    expected = np.array([np.nan if e is None else e for e in expected])
    assert np.isfinite(expected).sum() >= 18
    # ONE_PASS_PAIRS = 0 forces the pruned two-pass search on every block; the default solves
    # blocks this small in one pass. Both must match the brute force.
    for one_pass_pairs in (0, probe_module.ONE_PASS_PAIRS):
        monkeypatch.setattr(probe_module, "ONE_PASS_PAIRS", one_pass_pairs)
        contacts = touch_many(part, starts, -u, R, 3 * MM)
        assert isinstance(contacts, Contacts)
        np.testing.assert_array_equal(contacts.touched, np.isfinite(expected))
        np.testing.assert_allclose(contacts.travel, expected, rtol=0, atol=TRAVEL_M)
    single = [touch(part, starts[k], -u[k], R, 3 * MM) for k in range(len(starts))]
    np.testing.assert_array_equal(
        contacts.travel, [np.nan if s is None else s.travel for s in single])
    # Many plunges straight down onto apexes: the pruned search must agree with solving every
    # candidate (to round-off: a contact on a shared edge may be reported by either triangle).
    above = np.column_stack([rng.uniform(0.0, 3 * MM, (200, 2)), np.full(200, 0.5 * MM)])
    down = np.tile([0.0, 0.0, -1.0], (200, 1))
    results = []
    for one_pass_pairs in (0, 10**9):
        monkeypatch.setattr(probe_module, "ONE_PASS_PAIRS", one_pass_pairs)
        results.append(touch_many(part, above, down, R, 1 * MM))
    np.testing.assert_allclose(results[0].travel, results[1].travel, rtol=0, atol=TRAVEL_M)
    np.testing.assert_allclose(results[0].point, results[1].point, rtol=0, atol=TRAVEL_M)


def test_pruning_bound_never_exceeds_the_exact_travel():
    # The second pass skips a triangle whose lower bound exceeds a contact already found; a
    # bound above the triangle's true travel would lose contacts, so check it on every pair.
    part = Part(manifold3d.Manifold.sphere(2 * MM, 32) + box([3 * MM, 3 * MM, 1 * MM]))
    index = MeshIndex.from_surface(part)
    rng = np.random.default_rng(2)
    u = rng.normal(size=(40, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    starts = 6 * MM * u
    aims = -u + 0.3 * rng.normal(size=(40, 3))
    aims /= np.linalg.norm(aims, axis=1)[:, None]
    m = len(index.triangles)
    probe, tri = np.repeat(np.arange(40), m), np.tile(np.arange(m), 40)
    c, d = starts.T[:, probe], aims.T[:, probe]
    boxes, spheres = index.levels[-1]
    bound, _ = probe_module._lower_bound(boxes[:, tri], spheres[:, tri], c, d, R)
    travel, _, overlap = probe_module._sweep(c, d, R, probe_module._corners(index, tri))
    assert not overlap.any() and np.isfinite(travel).sum() > 100
    assert np.all(bound[np.isfinite(travel)] <= travel[np.isfinite(travel)])


def test_mesh_index_and_tuple_inputs_agree_with_the_part():
    part = v_groove_part(5 * MM, 2 * MM)
    args = ([4.5 * MM, 1 * MM, 3.6 * MM], [0.2, 0.1, -1], R, 2 * MM)
    reference = touch(part, *args)
    for surface in (MeshIndex.from_surface(part), part.mesh()):
        contact = touch(surface, *args)
        assert contact.travel == reference.travel
        np.testing.assert_array_equal(contact.point, reference.point)


def test_bad_probe_input_is_refused():
    part = Part(box([10 * MM, 10 * MM, 3 * MM]))
    with pytest.raises(InputError, match="start clear"):
        touch(part, [5 * MM, 5 * MM, 3.1 * MM], [0, 0, -1], R, 1 * MM)
    with pytest.raises(InputError, match="non-zero"):
        touch(part, [5 * MM, 5 * MM, 4 * MM], [0, 0, 0], R, 1 * MM)
    with pytest.raises(InputError, match="radius"):
        touch(part, [5 * MM, 5 * MM, 4 * MM], [0, 0, -1], 0.0, 1 * MM)
    with pytest.raises(InputError, match="max_travel"):
        touch(part, [5 * MM, 5 * MM, 4 * MM], [0, 0, -1], R, -1 * MM)
    with pytest.raises(InputError, match=r"shape \(3,\)"):
        touch(part, [5 * MM, 5 * MM], [0, 0, -1], R, 1 * MM)
    with pytest.raises(InputError, match="shape of centres"):
        touch_many(part, np.zeros((2, 3)), np.ones((3, 3)), R, 1 * MM)
