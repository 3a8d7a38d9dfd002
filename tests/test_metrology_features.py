"""Feature fits against independent truth: analytic V grooves and groove sets, analytic lines,
exact and tessellated spheres, analytic planes and the diamond crown's faces, analytic steps and
a stepped part, a known added cosine, and Sa by its direct definition."""

import math

import manifold3d
import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.metrology import MeshIndex, height_map, profile, touch
from machinesim.metrology.fits import (
    fit_plane,
    fit_sphere,
    form_error,
    height_map_points,
    plane_angle,
    roughness_sa,
    sphere_centre_from_touch,
)
from machinesim.metrology.grooves import fit_v_groove, fit_v_grooves, groove_pitch
from machinesim.metrology.lines import (
    edge_distance,
    fit_line,
    fit_parallel_edges,
    fit_parallel_lines,
    groove_crossing,
    intersect_lines,
    profile_points,
    step_positions,
)
from machinesim.workpiece import Part, block_with_spheres, diamond_crown

MM = 1e-3
UM = 1e-6
NM = 1e-9
#: Lengths fitted from exact samples: coordinates of ~10 mm carry ~2e-18 m of round-off, the
#: line fits and intersections amplify it by ~100 at most; 1e-15 m (1 fm) fails on any real
#: error (a wrong sample in a fit moves a result by >1e-12 m) yet leaves that room.
EXACT_M = 1e-15
#: Angles from the same fits: slopes carry ~1e-18 m / 1e-6 m of round-off.
EXACT_RAD = 1e-10


def v_profile(s, centres, depth, half_angle, tilt=0.0, level=0.0):
    """Heights of V grooves (apex at each centre, flanks at half_angle from the vertical) cut
    into a reference line level + tilt * s."""
    z = level + tilt * s
    for centre in centres:
        z = np.minimum(z, level + tilt * s - depth + np.abs(s - centre) / math.tan(half_angle))
    return z


def line_angle(slope_a, slope_b):
    """Angle between two lines of the given slopes, from their direction vectors."""
    a = np.array([1.0, slope_a]) / math.hypot(1.0, slope_a)
    b = np.array([1.0, slope_b]) / math.hypot(1.0, slope_b)
    return math.acos(float(a @ b))


# ---------------------------------------------------------------- V grooves


def test_v_groove_exact_on_a_tilted_analytic_profile():
    s = 12.3 * MM + np.arange(2700) * 0.37 * UM  # the apex falls between samples
    depth, half = 3 * UM, math.radians(60.0)
    tilt, level = 1e-4, -1 * MM
    groove = fit_v_groove(s, v_profile(s, [12.8 * MM], depth, half, tilt, level))
    assert abs(groove.centre - 12.8 * MM) < EXACT_M
    assert abs(groove.depth - depth) < EXACT_M
    assert abs(groove.apex_height - (level + tilt * 12.8 * MM - depth)) < EXACT_M
    # The flanks meet the reference where |s - c| / tan(half) = depth.
    assert abs(groove.width - 2 * depth * math.tan(half)) < EXACT_M
    assert abs(groove.left_edge - (12.8 * MM - depth * math.tan(half))) < EXACT_M
    assert abs(groove.reference_slope - tilt) < EXACT_RAD
    cot = 1.0 / math.tan(half)
    assert abs(groove.left_flank_angle - line_angle(tilt - cot, tilt)) < EXACT_RAD
    assert abs(groove.right_flank_angle - line_angle(tilt + cot, tilt)) < EXACT_RAD


def test_v_groove_angles_of_a_level_120_degree_groove():
    s = np.arange(1000) * 0.5 * UM
    groove = fit_v_groove(s, v_profile(s, [0.2503 * MM], 1 * UM, math.radians(60.0)))
    assert abs(groove.left_flank_angle - math.radians(30.0)) < EXACT_RAD
    assert abs(groove.right_flank_angle - math.radians(30.0)) < EXACT_RAD
    assert abs(groove.included_angle - math.radians(120.0)) < EXACT_RAD


def depth_sigma(s, centre, depth, half_angle, band, noise, land_noise=None):
    """Standard deviation of the fitted depth of a level symmetric V, derived independently.

    To first order the apex height is the mean of the two flank lines' values at the apex
    (the slopes drop out at a symmetric V), and the depth is the reference line's value there
    minus it; each value of a fitted line at t has variance noise^2 (1/n + (t - mean)^2 / Sxx).
    ``land_noise`` (default ``noise``) is the reference line's.
    """
    def var_at(t, points):
        return 1.0 / points.size + (t - points.mean()) ** 2 / np.sum((points - points.mean())**2)

    run = depth * math.tan(half_angle)
    lo, hi = band
    land = s[np.abs(s - centre) > run]
    left = s[(s >= centre - run + lo * run) & (s <= centre - run + hi * run)]
    right = s[(s <= centre + run - lo * run) & (s >= centre + run - hi * run)]
    land_noise = noise if land_noise is None else land_noise
    variance = (land_noise**2 * var_at(centre, land)
                + 0.25 * noise**2 * (var_at(centre, left) + var_at(centre, right)))
    return math.sqrt(variance)


def test_v_groove_depth_on_noisy_profiles_within_the_derived_sigma():
    rng = np.random.default_rng(0)
    s = np.arange(3000) * 0.2 * UM
    centre, depth, half, noise = 0.3001 * MM, 2 * UM, math.radians(45.0), 5e-9
    clean = v_profile(s, [centre], depth, half)
    sigma = depth_sigma(s, centre, depth, half, (0.1, 0.9), noise)
    errors, reported = [], []
    for _ in range(100):
        groove = fit_v_groove(s, clean + rng.normal(0.0, noise, s.size))
        errors.append(groove.depth - depth)
        reported.append(groove.depth_sigma)
    errors = np.array(errors)
    # One profile: within 3 sigma (fails with probability 0.3 %, fixed by the seed).
    assert abs(errors[0]) < 3 * sigma
    # The spread over 100 profiles estimates sigma to ~7 % (1/sqrt(2n)): 20 % is ~3 of those.
    assert abs(errors.std() / sigma - 1.0) < 0.2
    # No bias: the mean error is within 3 standard errors of zero.
    assert abs(errors.mean()) < 3 * sigma / math.sqrt(errors.size)
    # The fit's own propagated sigma agrees with the derivation (its noise is estimated from
    # ~1000 residuals, so ~2 %; 10 % allows for the first-order derivation).
    assert abs(np.mean(reported) / sigma - 1.0) < 0.1


def test_v_groove_depth_sigma_holds_lateral_jitter_on_the_flanks_only():
    """Samples read a jittered place (lateral noise), reported at the asked one: on a 45 deg
    flank each height is off by the slope (1) times the jitter, on the land by nothing. The
    derived sigma (flanks with that noise, the land exact) explains the depths' scatter, and
    the fit states it; one noise pooled over land and flanks would state a sixth of it."""
    rng = np.random.default_rng(1)
    s = np.arange(3000) * 0.2 * UM
    centre, depth, half, jitter = 0.3001 * MM, 10 * UM, math.radians(45.0), 20e-9
    sigma = depth_sigma(s, centre, depth, half, (0.1, 0.9), jitter, land_noise=0.0)
    errors, reported = [], []
    for _ in range(100):
        seen = s + rng.normal(0.0, jitter, s.size)
        groove = fit_v_groove(s, v_profile(seen, [centre], depth, half))
        errors.append(groove.depth - depth)
        reported.append(groove.depth_sigma)
    errors = np.array(errors)
    # the spread over 100 profiles estimates sigma to ~7 %: 20 % is ~3 of those
    assert abs(errors.std() / sigma - 1.0) < 0.2
    # each flank's noise from its ~40 residuals: ~11 % per profile, ~1 % over 100
    assert abs(np.mean(reported) / sigma - 1.0) < 0.1


def test_groove_set_centres_and_pitch_with_partial_grooves_at_both_ends():
    s = np.arange(2703) * 0.37 * UM
    centres = np.array([12.3, 112.3, 187.3, 312.3, 437.3, 512.3, 687.3, 812.3]) * UM
    cut = [-50 * UM, *centres, s[-1] + 1.5 * UM]  # the outer two are cut by the profile's ends
    grooves = fit_v_grooves(s, v_profile(s, cut, 3 * UM, math.radians(45.0), tilt=2e-5))
    assert len(grooves) == centres.size
    found = np.array([g.centre for g in grooves])
    np.testing.assert_allclose(found, centres, rtol=0, atol=EXACT_M)
    np.testing.assert_allclose([g.depth for g in grooves], 3 * UM, rtol=0, atol=EXACT_M)
    pitch = groove_pitch(found)
    np.testing.assert_allclose(pitch.spacings, np.diff(centres), rtol=0, atol=2 * EXACT_M)
    assert abs(pitch.mean - (centres[-1] - centres[0]) / (centres.size - 1)) < EXACT_M
    assert not pitch.spacings.flags.writeable


def test_groove_fit_skips_unseen_samples():
    s = np.arange(2000) * 0.5 * UM
    z = v_profile(s, [0.4 * MM, 0.6 * MM], 1.5 * UM, math.radians(50.0))
    z[::7] = np.nan
    z[300:340] = np.nan
    grooves = fit_v_grooves(s, z)
    np.testing.assert_allclose([g.centre for g in grooves], [0.4 * MM, 0.6 * MM], rtol=0,
                               atol=EXACT_M)


def test_groove_in_a_machined_part_read_through_profile():
    # A 90-degree V prism (a cube turned 45 deg about y) cut 5 um deep into a block's top.
    side, centre, depth = 4 * MM, 2.0003 * MM, 5 * UM
    prism = manifold3d.Manifold.cube([side, 20 * MM, side], center=True)
    prism = prism.rotate([0.0, 45.0, 0.0]).translate([centre, 0.0, -depth + side / math.sqrt(2)])
    part = Part(manifold3d.Manifold.cube([4 * MM, 4 * MM, 1 * MM]).translate([0, 0, -MM]) - prism)
    s, z = profile(part, (1.9 * MM, 2 * MM), (2.1 * MM, 2 * MM), 0.1 * UM)
    groove = fit_v_groove(s, z)
    # manifold3d turns the prism by a rounded cos/sin of 45 deg (~1e-16 relative, ~1e-19 m on
    # its 4 mm vertices) and the booleans keep float64: 1e-14 m and 1e-12 rad leave room for
    # that and fail on any sample fitted to the wrong line.
    assert abs(1.9 * MM + groove.centre - centre) < 1e-14
    assert abs(groove.depth - depth) < 1e-14
    assert abs(groove.included_angle - math.pi / 2) < 1e-12


def test_groove_input_errors():
    s = np.arange(10000) * 0.1 * UM
    two = v_profile(s, [0.3 * MM, 0.6 * MM], 1 * UM, math.radians(45.0))
    with pytest.raises(InputError, match="Expected one whole V groove.*found 2"):
        fit_v_groove(s, two)
    with pytest.raises(InputError, match="found 0"):
        fit_v_groove(s, np.zeros_like(s))
    with pytest.raises(InputError, match="flank_band"):
        fit_v_grooves(s, two, flank_band=(0.9, 0.1))
    with pytest.raises(InputError, match="strictly increasing s"):
        fit_v_grooves(s[::-1], two)
    with pytest.raises(InputError, match="same shape"):
        fit_v_grooves(s, two[:-1])
    with pytest.raises(InputError, match="threshold"):
        fit_v_grooves(s, two, threshold=-1.0)
    # 2 um spacing leaves no sample inside 10-90 % of a 2 um wide groove's flank.
    coarse = np.arange(500) * 2 * UM
    with pytest.raises(InputError, match="at least two samples on the left flank"):
        fit_v_grooves(coarse, v_profile(coarse, [0.5 * MM], 1 * UM, math.radians(45.0)))
    with pytest.raises(InputError, match="strictly increasing centres"):
        groove_pitch([2.0, 1.0])


@pytest.mark.parametrize("shape", ["ridge", "bump", "wave"])
def test_profiles_without_a_v_below_level_land_are_refused(shape):
    # None of these holds a groove, which the old fit reported all the same: the ridge as
    # a groove 18.6 um deep (flanks 43.2 and 1.8 deg, the left land taken as a groove cut
    # by the profile's end), the 2 um bump as one 1.78 um deep, the 2 um wave as three 2.31 um
    # deep (deeper than its own peak to valley), each on its crests as "land"
    s = np.arange(0.0, 1 * MM, 0.3 * UM)
    z = {"ridge": np.maximum(0.0, 20 * UM - np.abs(s - 0.4 * MM)),
         "bump": 2 * UM * np.exp(-((s - 0.2 * MM) / (50 * UM)) ** 2),
         "wave": 1 * UM * np.sin(2 * math.pi * s / (0.3 * MM))}[shape]
    with pytest.raises(InputError, match="expected a V below level land, got a reference"):
        fit_v_grooves(s, z)
    with pytest.raises(InputError, match="no V groove"):
        fit_v_groove(s, z)


# ---------------------------------------------------------------- lines and crossings


def test_crossing_of_two_analytic_lines():
    point = np.array([3.2 * MM, -1.7 * MM])
    a = np.array([math.cos(0.3), math.sin(0.3)])
    b = np.array([math.cos(1.9), math.sin(1.9)])
    t = np.linspace(-2 * MM, 2 * MM, 7)[:, None]
    crossing = groove_crossing(point + t * a, point + (t + 0.5 * MM) * b)
    np.testing.assert_allclose(crossing.point, point, rtol=0, atol=EXACT_M)
    assert abs(crossing.angle - (math.pi - 1.6)) < EXACT_RAD
    assert crossing.first.residual_rms < EXACT_M


def test_crossing_of_two_grooves_from_centres_in_profiles():
    # Groove A along direction 20 deg through P, groove B along 115 deg through P; heights
    # of the surface along each profile line follow from the distance to the groove line.
    point = np.array([5.0 * MM, 4.0 * MM])
    depth, half = 2 * UM, math.radians(45.0)

    def heights(xy, through, angle):
        normal = np.array([-math.sin(angle), math.cos(angle)])
        distance = np.abs((xy - through) @ normal)
        return np.minimum(0.0, -depth + distance / math.tan(half))

    centres = []
    for angle in (math.radians(20.0), math.radians(115.0)):
        along = np.array([math.cos(angle), math.sin(angle)])
        across = np.array([-along[1], along[0]])
        found = []
        for offset in (-1.0 * MM, -0.6 * MM, 0.7 * MM, 1.2 * MM):
            start = point + offset * along - 50 * UM * across
            end = point + offset * along + 50 * UM * across
            s = np.arange(0.0, 100 * UM, 0.13 * UM)
            groove = fit_v_groove(s, heights(profile_points(start, end, s), point, angle))
            found.append(profile_points(start, end, [groove.centre])[0])
        centres.append(found)
    crossing = groove_crossing(*centres)
    # Profile points are start + s * unit direction: ~1e-18 m round-off at 5 mm, amplified by
    # the line fits and the intersection well below 1e-14 m.
    np.testing.assert_allclose(crossing.point, point, rtol=0, atol=1e-14)
    assert abs(crossing.angle - math.radians(85.0)) < EXACT_RAD


def test_line_input_errors():
    with pytest.raises(InputError, match="shape \\(k, 2\\)"):
        fit_line([[1.0, 2.0]])
    line = fit_line([[0.0, 0.0], [1.0, 0.0]])
    with pytest.raises(InputError, match="crossing lines"):
        intersect_lines(line, fit_line([[0.0, 1.0], [2.0, 1.0]]))


def test_step_positions_and_edge_distance_of_an_analytic_plateau():
    # Plateau at z = 0 from 1.0 to 3.0 mm, walls sloped 1:5 down to -10 um.
    s = np.arange(4000) * 1.003 * UM
    z = np.clip(np.minimum(0.2 * (s - 1.0 * MM), 0.2 * (3.0 * MM - s)), -10 * UM, 0.0)
    # The walls cross -5 um 25 um outside the plateau.
    steps = step_positions(s, z)
    np.testing.assert_allclose(steps, [0.975 * MM, 3.025 * MM], rtol=0, atol=EXACT_M)
    assert abs(edge_distance(s, z) - 2.05 * MM) < EXACT_M
    assert abs(edge_distance(s, z, level=-1 * UM) - 2.01 * MM) < EXACT_M
    with pytest.raises(InputError, match="crossing the level twice, got 0"):
        edge_distance(s, z, level=1 * UM)


def test_a_profile_touching_the_level_crosses_it_nowhere_from_either_side():
    # A peak touching the level from below counted 2 crossings (both at the peak), a valley
    # touching it from above none: a sample at the level was counted as above it.
    s = np.arange(9) * UM
    peak = np.array([-2.0, -1.0, 0.0, -1.0, -2.0, -1.0, 1.0, 2.0, 3.0]) * NM
    # the peak at 2 um touches; the rise crosses at 5.5 um
    np.testing.assert_array_equal(step_positions(s, peak, 0.0), [5.5 * UM])
    # upside down (a valley touching from above) and backwards: the same crossing
    np.testing.assert_array_equal(step_positions(s, -peak, 0.0), [5.5 * UM])
    np.testing.assert_array_equal(step_positions(-s[::-1], peak[::-1], 0.0), [-5.5 * UM])
    # a flat at the level touched, and a profile starting or ending at it: no crossing
    for z in ([-1, 0, 0, 0, -1, -2, -3, -2, -1], [0, 0, 1, 2, 3, 2, 1, 2, 3],
              [3, 2, 1, 2, 3, 2, 1, 0, 0]):
        for sign in (1.0, -1.0):
            assert step_positions(s, sign * np.array(z) * NM, 0.0).size == 0
    # a crossing through samples at the level lies at their middle, one sample at it
    for z, at in (([-2, -1, 0, 0, 0, 1, 2, 3, 4], 3.0), ([-2, -1, 0, 1, 2, 3, 4, 5, 6], 2.0)):
        for sign in (1.0, -1.0):
            np.testing.assert_array_equal(step_positions(s, sign * np.array(z) * NM, 0.0),
                                          [at * UM])
    # the analytic plateau's flat top at its own height is a touch: no edges there
    plateau_s = np.arange(4000) * 1.003 * UM
    plateau = np.clip(np.minimum(0.2 * (plateau_s - 1.0 * MM), 0.2 * (3.0 * MM - plateau_s)),
                      -10 * UM, 0.0)
    with pytest.raises(InputError, match="crossing the level twice, got 0"):
        edge_distance(plateau_s, plateau, level=0.0)


def test_edge_distance_of_a_stepped_part_with_walls_between_samples():
    # A 2 mm wide ridge 20 um high; samples every 10 um with both walls midway between two.
    base = manifold3d.Manifold.cube([6 * MM, 2 * MM, 1 * MM]).translate([0, 0, -MM])
    ridge = manifold3d.Manifold.cube([2 * MM, 2 * MM, 20 * UM]).translate([2.005 * MM, 0, 0])
    part = Part(base + ridge)
    s, z = profile(part, (0.0, 1 * MM), (6 * MM, 1 * MM), 10 * UM)
    # Midway samples make the crossing at mid-height fall exactly on the wall.
    assert abs(edge_distance(s, z) - 2 * MM) < 1e-12


def test_parallel_edges_of_a_rotated_analytic_strip():
    # A strip 1.2 mm wide between two walls at 30 deg to x, walls sloped 1:4 over 8 um.
    angle, width = math.radians(30.0), 1.2 * MM
    normal = np.array([-math.sin(angle), math.cos(angle)])
    x = np.arange(200) * 5 * UM
    y = np.arange(500) * 5 * UM
    grid_x, grid_y = np.meshgrid(x, y)
    across = (np.stack([grid_x, grid_y], axis=-1) - [0.5 * MM, 0.5 * MM]) @ normal
    z = np.clip(np.minimum(0.25 * across, 0.25 * (width - across)), -8 * UM, 0.0)
    # Each column (x) crosses the near wall at y in [0.21, 0.79] mm, the far one 1.39 mm on.
    edges = fit_parallel_edges(x, y, z, along="y")
    # At the mid level (-4 um) each wall is 16 um outside the strip.
    assert abs(edges.distance - (width + 32 * UM)) < 1e-14
    assert edges.parallelism < EXACT_RAD
    assert abs(abs(edges.first.direction @ [math.cos(angle), math.sin(angle)]) - 1) < 1e-15


def test_parallel_lines_of_two_turned_point_sets():
    """Two sets of points on parallel lines 0.3 mm apart, 8 mm along from each other, turned
    by 0.7 rad: one common direction, the offset across it, and each line through its own
    centroid; an even zig-zag about each line leaves the direction and offset exact."""
    turn = 0.7
    u, n = np.array([math.cos(turn), math.sin(turn)]), np.array([-math.sin(turn),
                                                                  math.cos(turn)])
    s = np.linspace(3e-3, 5e-3, 5)
    wiggle = np.array([1, -1, 0, 1, -1]) * 1e-7
    first = s[:, None] * u + wiggle[:, None] * n
    second = -s[:, None] * u + (0.3e-3 + wiggle)[:, None] * n
    one, two = fit_parallel_lines(first, second)
    np.testing.assert_allclose(one.direction, u, atol=1e-15)
    np.testing.assert_allclose(two.direction, u, atol=1e-15)
    assert (two.point - one.point) @ n == pytest.approx(0.3e-3, abs=1e-18)
    np.testing.assert_allclose(one.point, first.mean(axis=0), atol=1e-18)
    with pytest.raises(InputError, match="second with shape"):
        fit_parallel_lines(first, second[:1])
    with pytest.raises(InputError, match="each set's points equal"):
        fit_parallel_lines(np.zeros((3, 2)), np.ones((3, 2)))


def test_parallel_edges_input_errors():
    x = np.arange(50) * UM
    y = np.arange(4) * UM
    z = np.tile(np.where(np.arange(50) % 20 < 10, 0.0, -1 * UM), (4, 1))  # three steps a row
    with pytest.raises(InputError, match="two crossings.*got 4|two crossings.*got 3"):
        fit_parallel_edges(x, y, z)
    with pytest.raises(InputError, match="along"):
        fit_parallel_edges(x, y, z, along="z")


# ---------------------------------------------------------------- spheres


def two_scans(centre, radius, half_angle, count):
    """Points of two orthogonal scans across the top of a sphere (seed 002, Fig. 4b)."""
    t = np.linspace(-half_angle, half_angle, count)
    along_x = np.column_stack([radius * np.sin(t), np.zeros_like(t), radius * np.cos(t)])
    along_y = np.column_stack([np.zeros_like(t), radius * np.sin(t), radius * np.cos(t)])
    return centre + np.vstack([along_x, along_y])


def test_sphere_from_two_exact_scans():
    centre = np.array([10.3 * MM, 20.1 * MM, -1.5 * MM])
    points = two_scans(centre, 2 * MM, math.radians(50.0), 41)
    sphere = fit_sphere(points)
    # Points at ~20 mm carry ~4e-18 m round-off; 1e-12 m is the brief's bound.
    np.testing.assert_allclose(sphere.centre, centre, rtol=0, atol=1e-12)
    assert abs(sphere.radius - 2 * MM) < 1e-12
    assert sphere.residual_max < 1e-12
    held = fit_sphere(points, radius=2 * MM)
    np.testing.assert_allclose(held.centre, centre, rtol=0, atol=1e-12)


def test_sphere_from_a_tessellated_sphere_and_a_top_touch():
    radius, segments = 1 * MM, 512
    centre = np.array([0.2 * MM, -0.1 * MM, 0.05 * MM])
    sphere = manifold3d.Manifold.sphere(radius, segments)
    vertices = np.asarray(sphere.to_mesh64().vert_properties)[:, :3]
    # Facet depth: the vertices lie on the sphere, the facet planes up to this far inside.
    corner = vertices[np.asarray(sphere.to_mesh64().tri_verts)]
    normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    facet = radius - np.min(np.einsum("ij,ij->i", normal, corner[:, 0]))
    assert 1e-8 < facet < 1e-7  # ~50 nm at 512 segments
    part = Part(sphere.translate(tuple(centre)))
    x = centre[0] + np.linspace(-0.99, 0.99, 141) * MM + 0.3 * UM
    y = centre[1] + np.linspace(-0.99, 0.99, 141) * MM - 0.2 * UM
    fit = fit_sphere(height_map_points(x, y, height_map(part, x, y)))
    # The cap fit's xy is accurate: the facets are spread evenly round the top (measured
    # 0.08 nm); z and the radius trade off on a cap and carry the facet depth.
    np.testing.assert_allclose(fit.centre[:2], centre[:2], rtol=0, atol=1e-9)
    assert centre[2] - facet < fit.centre[2] < centre[2] + facet
    assert radius - facet < fit.radius < radius
    # Seed 002's remedy: z from a touch at the fitted xy, with the known radius. The top of
    # manifold3d's sphere is a vertex on the true sphere, so the touch is exact there and
    # the xy error (< 1 nm) changes the height only by xy^2 / 2R.
    top = height_map(part, [fit.centre[0]], [fit.centre[1]])[0, 0]
    touched = sphere_centre_from_touch(fit.centre[:2], top, radius, concave=False)
    np.testing.assert_allclose(touched, centre, rtol=0, atol=1e-9)


def test_bottom_touch_with_the_probe_ball_in_a_ball_end_milled_cavity():
    # Seed 002's reference spheres are cavities; the probe (r = 0.25 mm) touches the bottom.
    radius, probe_radius = 0.5 * MM, 0.25 * MM
    part = block_with_spheres(3 * MM, 3 * MM, 1 * MM, radius, dimples=True)
    truth = np.array([1 * MM, 1 * MM, 0.0])  # S1: 2 R in from the edges, on the top face
    x = truth[0] + np.linspace(-0.45, 0.45, 61) * MM
    y = truth[1] + np.linspace(-0.45, 0.45, 61) * MM
    points = height_map_points(x, y, height_map(part, x, y))
    # The grid's corners lie on the flat top face: keep the points inside the cavity's rim.
    points = points[np.hypot(*(points[:, :2] - truth[:2]).T) < 0.45 * MM]
    fit = fit_sphere(points)
    np.testing.assert_allclose(fit.centre[:2], truth[:2], rtol=0, atol=1e-9)
    start = [*fit.centre[:2], 0.5 * MM]
    contact = touch(MeshIndex.from_surface(part), start, [0, 0, -1], probe_radius, 2 * MM)
    centre = sphere_centre_from_touch(fit.centre[:2], contact.centre[2], radius,
                                      probe_radius=probe_radius)
    # The ball rests on the facets round the bottom vertex instead of the vertex itself:
    # their tilt theta ~ sqrt(8 delta / R) lifts it by r theta^2 / 2 ~ 4 r delta / R, delta
    # the facet depth (workpiece.SPHERE_CHORD_M = 0.1 um): at most 0.2 um here.
    assert abs(centre[2] - truth[2]) < 4 * probe_radius * 1e-7 / radius
    np.testing.assert_allclose(centre[:2], truth[:2], rtol=0, atol=1e-9)


def test_sphere_input_errors():
    with pytest.raises(InputError, match="at least 4 points"):
        fit_sphere(np.zeros((3, 3)))
    with pytest.raises(InputError, match="one plane"):
        fit_sphere([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]])
    with pytest.raises(InputError, match="shape \\(N, 3\\)"):
        fit_sphere(np.zeros((5, 2)))
    with pytest.raises(InputError, match="radius"):
        sphere_centre_from_touch([0, 0], 0.0, -1.0)


# ---------------------------------------------------------------- planes


def test_plane_inclination_and_angle_between_planes():
    rng = np.random.default_rng(0)
    tilt, azimuth = math.atan(0.2), math.radians(35.0)
    normal = np.array([math.sin(tilt) * math.cos(azimuth), math.sin(tilt) * math.sin(azimuth),
                       math.cos(tilt)])
    base = np.cross(normal, [0.0, 0.0, 1.0])
    base /= np.linalg.norm(base)
    other = np.cross(normal, base)
    uv = rng.uniform(-1 * MM, 1 * MM, (200, 2))
    points = [3 * MM, -2 * MM, 0.5 * MM] + uv[:, :1] * base + uv[:, 1:] * other
    plane = fit_plane(points)
    assert abs(plane.inclination - tilt) < 1e-12
    np.testing.assert_allclose(plane.normal, normal, rtol=0, atol=1e-12)
    assert plane.flatness < 1e-15
    level = fit_plane(np.column_stack([uv, np.full(200, 0.1 * MM)]))
    assert abs(plane_angle(plane, level) - tilt) < 1e-12
    assert level.inclination < 1e-15


def test_crown_side_face_inclination_from_a_height_map():
    # Seed 002's crown: side faces at atan(0.2) = 11.31 deg to the top face (Fig. 12b).
    crown = diamond_crown(oversize=0.0)
    x = np.linspace(2.2 * MM, 2.8 * MM, 31)  # on the side face that faces +x
    y = np.linspace(-0.4 * MM, 0.4 * MM, 41)
    side = fit_plane(height_map_points(x, y, height_map(crown, x, y)))
    xt = np.linspace(-1 * MM, 1 * MM, 21)
    top = fit_plane(height_map_points(xt, xt, height_map(crown, xt, xt)))
    # The crown's corners come from cos/sin in float64 (~1e-16 relative); 1e-12 rad is well
    # above that and far below any machining error the procedure looks for (~1e-4 rad).
    assert abs(side.inclination - math.atan(0.2)) < 1e-12
    assert abs(plane_angle(side, top) - math.atan(0.2)) < 1e-12
    assert side.flatness < 1e-15


def test_plane_input_errors():
    with pytest.raises(InputError, match="one line"):
        fit_plane([[0, 0, 0], [1, 1, 1], [2, 2, 2]])
    with pytest.raises(InputError, match="at least 3 points"):
        fit_plane([[0, 0, 0], [1, 1, 1], [np.nan, 0, 0]])


# ---------------------------------------------------------------- form error and Sa


def midpoint_grid(length, count):
    """Samples at the middle of count equal cells of [-length/2, length/2]: symmetric about 0."""
    return (np.arange(count) + 0.5) * (length / count) - length / 2


def cubic(x, y):
    """A nominal surface with third-order terms (so that a shift is not a tilt), m."""
    return 1e3 * (x**3 + 0.5 * y**3) + 2e-3 * x * y


def test_form_error_of_an_added_cosine_after_piston_and_tilt():
    x = midpoint_grid(2 * MM, 200)
    y = midpoint_grid(1.5 * MM, 120)
    grid_x, grid_y = np.meshgrid(x, y)
    amplitude = 50e-9
    # Whole periods on a grid symmetric about 0: the cosine is orthogonal to piston and tilt,
    # so the best fit leaves it whole.
    wave = amplitude * np.cos(2 * math.pi * 4 * grid_x / (2 * MM))
    z = cubic(grid_x, grid_y) + wave + 3 * UM + 1e-4 * grid_x - 2e-4 * grid_y
    form = form_error(x, y, z, cubic)
    # Residuals of ~1e-7 m heights computed from mm coordinates: round-off ~1e-22 m; the
    # plane removal adds ~1e-20 m. 1e-18 m fails on any missing or extra term.
    assert abs(form.pv - np.ptp(wave)) < 1e-18
    assert abs(form.rms - amplitude / math.sqrt(2)) < 1e-18
    assert abs(form.piston - 3 * UM) < 1e-18
    np.testing.assert_allclose(form.tilt, [1e-4, -2e-4], rtol=0, atol=1e-15)
    np.testing.assert_allclose(form.residual, wave, rtol=0, atol=1e-18)
    np.testing.assert_array_equal(form.shift, [0.0, 0.0])


def test_form_error_with_a_rigid_shift():
    x = midpoint_grid(2 * MM, 80)
    y = midpoint_grid(2 * MM, 60)
    grid_x, grid_y = np.meshgrid(x, y)
    shift = np.array([4.3 * UM, -2.1 * UM])
    z = cubic(grid_x - shift[0], grid_y - shift[1]) + 0.7 * UM + 3e-5 * grid_y
    z[5, 7] = np.nan
    form = form_error(x, y, z, cubic, shift=True)
    # Gauss-Newton converges on the exact shift whatever the accuracy of its gradient; the
    # residual heights' round-off (~1e-22 m) over gradients ~1e-3 bounds it far below 1e-15.
    np.testing.assert_allclose(form.shift, shift, rtol=0, atol=1e-15)
    assert form.pv < 1e-18
    assert np.isnan(form.residual[5, 7])
    # Without the shift the cubic's x^2 term, 3 * 1e3 * sx * x^2, stays in the residual.
    assert form_error(x, y, z, cubic).pv > 1e-9


def test_form_error_input_errors():
    x = np.arange(5) * UM
    z = np.zeros((5, 5))
    with pytest.raises(InputError, match="shift"):
        form_error(x, x, z, lambda a, b: a**2 + b**2, shift=True)
    with pytest.raises(InputError, match="nominal"):
        form_error(x, x, z, lambda a, b: np.zeros(3))
    with pytest.raises(InputError, match="z \\(ny, nx\\)"):
        form_error(x, x, z[:4], lambda a, b: a)


def test_sa_through_surfalize_equals_the_direct_definition():
    rng = np.random.default_rng(0)
    x = np.arange(120) * 0.5 * UM + 1 * MM
    y = np.arange(90) * 0.5 * UM - 2 * MM
    grid_x, grid_y = np.meshgrid(x, y)
    z = rng.normal(0.0, 8e-9, grid_x.shape) + 2e-9 * np.sin(grid_x / (3 * UM))
    z += 5 * UM + 2e-3 * (grid_x - 1 * MM) - 1e-3 * (grid_y + 2 * MM)
    z[10:14, 20:30] = np.nan

    def direct(x, y, z):
        # Sa = mean |z - least-squares plane| over the seen samples (ISO 25178-2, F-operator
        # a plane, no S- or L-filter).
        seen = ~np.isnan(z)
        design = np.column_stack([np.ones(seen.sum()), grid_x[seen], grid_y[seen]])
        plane = np.linalg.lstsq(design, z[seen], rcond=None)[0]
        return np.mean(np.abs(z[seen] - design @ plane))

    sa = roughness_sa(x, y, z)
    # Two float64 routes to the same ~7 nm mean: 1e-9 relative covers surfalize's um scaling
    # and its own centring of the coordinates, and fails on any different filter or plane.
    assert abs(sa - direct(x, y, z)) < 1e-9 * sa
    assert 5e-9 < sa < 8e-9  # ~0.8 sigma of the added noise
    with pytest.raises(InputError, match="regular grid along x"):
        roughness_sa(np.r_[x[:-1], x[-1] + 0.1 * UM], y, z)


def test_fit_parallel_edges_refuses_a_map_read_nowhere():
    # all NaN (off the part): nanmin warned, its level was NaN, and the refusal named lines
    x = y = np.linspace(0.0, 1e-3, 11)
    with pytest.raises(InputError, match="got all 121 samples NaN"):
        fit_parallel_edges(x, y, np.full((11, 11), np.nan))
