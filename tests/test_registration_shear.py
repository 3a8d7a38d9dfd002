"""The registration's tilt is a shear of heights, not a rotation: it changes the angle between
two faces, by the amount `Registration`'s docstring derives."""

from __future__ import annotations

import math

import numpy as np
import pytest

from machinesim.cam import crown as cam
from machinesim.metrology.imperfections import Registration

MM = 1e-3


def _two_faces(g1, g2):
    """Points (n, 3) on two planes through the origin's neighbourhood, of gradients (dz/dx,
    dz/dy) g1 (on x < 0) and g2 (on x > 0), 1 mm square each; and the face of each point."""
    u = np.linspace(0.05, 1.0, 12) * MM
    x, y = np.meshgrid(u, u - 0.5 * MM)
    left = np.column_stack([-x.ravel(), y.ravel()])
    right = np.column_stack([x.ravel(), y.ravel()])
    points = np.vstack([np.column_stack([left, left @ g1]),
                        np.column_stack([right, right @ g2])])
    return points, np.repeat([0, 1], len(left))


def _fitted_normals(points, face):
    """Upward unit normals of the planes z = c + gx x + gy y fitted to each face."""
    normals = []
    for k in (0, 1):
        p = points[face == k]
        a = np.column_stack([np.ones(len(p)), p[:, 0], p[:, 1]])
        _, gx, gy = np.linalg.lstsq(a, p[:, 2], rcond=None)[0]
        n = np.array([-gx, -gy, 1.0])
        normals.append(n / np.linalg.norm(n))
    return normals


def _angle(n1, n2):
    return math.atan2(np.linalg.norm(np.cross(n1, n2)), n1 @ n2)


def _rotation_showing(tilt):
    """The rotation that turns the flat's normal z to the normal of slopes ``tilt``
    (Rodrigues, about z x n)."""
    n = np.array([-tilt[0], -tilt[1], 1.0])
    n /= np.linalg.norm(n)
    axis = np.cross([0.0, 0.0, 1.0], n)
    s, c = np.linalg.norm(axis), n[2]
    k = axis / s
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * kx + (1 - c) * kx @ kx


@pytest.mark.parametrize("tilt", [(2e-4, 0.0), (-2e-4, 0.0), (1e-2, 0.0)])
def test_the_shear_turns_a_face_of_slope_a_by_atan_a_plus_t_minus_atan_a(tilt):
    """Faces whose slopes lie along the tilt (a crown face and the flat, as paper 002 reads
    them): the shear turns each by atan(a + t) - atan(a), a rotation every face by atan(t), so
    the angle between them changes by the difference, ~ -t sin^2(alpha) = -t a^2 / (1 + a^2)
    against the flat."""
    a = math.tan(cam.CROWN.slope)
    t = tilt[0]
    points, face = _two_faces(np.array([a, 0.0]), np.zeros(2))  # a crown's top, side face
    before = _angle(*_fitted_normals(points, face))
    assert before == pytest.approx(cam.CROWN.slope, abs=1e-12)
    turned = points @ _rotation_showing(tilt).T
    sheared = Registration(tilt=tilt).to_instrument(points)
    # both show the flat at the slope t
    for seen in (turned, sheared):
        assert -_fitted_normals(seen, face)[1][0] / _fitted_normals(seen, face)[1][2] \
            == pytest.approx(t, rel=1e-9)
    assert _angle(*_fitted_normals(turned, face)) == pytest.approx(before, abs=1e-13)
    change = _angle(*_fitted_normals(sheared, face)) - before
    exact = (math.atan(a + t) - math.atan(a)) - math.atan(t)
    assert change == pytest.approx(exact, rel=1e-7)
    # to first order -t sin^2(alpha), alpha = atan(a); the remainder, t^2 a / (1 + a^2)^2,
    # is about t / a of it
    first = -t * math.sin(cam.CROWN.slope) ** 2
    assert change == pytest.approx(first, rel=2 * abs(t) / a)
    if t == 2e-4:  # the lab's 0.2 mrad on a crown face: 0.00044 deg
        assert abs(math.degrees(change)) == pytest.approx(4.4e-4, abs=0.5e-5)


def test_the_shear_changes_the_angle_between_any_two_faces_as_derived():
    """In general, faces of upward unit normals n1, n2 at the angle beta, h_i the normals' x-y
    parts, under the tilt vector t: the angle changes by ((t.h1)(n2z - n1z cos beta) +
    (t.h2)(n1z - n2z cos beta)) / sin beta to first order, exactly by the angle between the
    sheared gradients' normals (-(g + t), 1); a rotation changes it by nothing."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        g1, g2 = rng.normal(scale=0.3, size=(2, 2))
        t = rng.normal(scale=2e-4, size=2)
        points, face = _two_faces(g1, g2)
        n1, n2 = _fitted_normals(points, face)
        beta = _angle(n1, n2)
        turned = points @ _rotation_showing(t).T
        assert _angle(*_fitted_normals(turned, face)) == pytest.approx(beta, abs=1e-13)
        change = _angle(*_fitted_normals(Registration(tilt=t).to_instrument(points),
                                         face)) - beta

        def up(g):
            n = np.array([-g[0], -g[1], 1.0])
            return n / np.linalg.norm(n)

        assert change == pytest.approx(_angle(up(g1 + t), up(g2 + t)) - beta, rel=1e-6,
                                       abs=1e-14)
        c = math.cos(beta)
        first = ((t @ n1[:2]) * (n2[2] - n1[2] * c)
                 + (t @ n2[:2]) * (n1[2] - n2[2] * c)) / math.sin(beta)
        # second-order remainder: of the order of t / beta of the change
        assert change == pytest.approx(first, rel=0.05, abs=np.linalg.norm(t) ** 2 / beta)
