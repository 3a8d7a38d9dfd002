"""An end mill's level passes united by their footprints (`machinesim.cutting.footprints`)."""

import manifold3d
import numpy as np
import pytest

import machinesim.cutting.footprints as footprints
from machinesim.cutting import remove
from machinesim.cutting.footprints import level_prisms
from machinesim.tools import FlatEndMill
from machinesim.workpiece import block

#: Volumes of exact meshes agree to float64 summation round-off (~1e-15 relative).
VOLUME_REL = 1e-12


def _square(centre, half):
    x, y = centre
    return np.array([[x - half, y - half], [x + half, y - half], [x + half, y + half],
                     [x - half, y + half]])


def _pose(x, y, z):
    matrix = np.eye(4)
    matrix[:3, 3] = (x, y, z)
    return matrix


def test_four_passes_round_a_square_unite_into_the_analytic_frame():
    """A square tool of half-width h round a square of side a: the union of the four sweeps
    is the frame between the squares of side a + 2h and a - 2h, area 8 a h, over the
    passes' common floor and top; corners the footprints hold come back bit for bit."""
    a, h, floor, top = 3e-3, 0.4e-3, -0.25e-3, 1e-9
    corners = [(-a / 2, -a / 2), (a / 2, -a / 2), (a / 2, a / 2), (-a / 2, a / 2)]
    prints = [(floor, top, np.concatenate([_square(p, h), _square(q, h)]))
              for p, q in zip(corners, corners[1:] + corners[:1], strict=True)]
    run_id = manifold3d.Manifold.reserve_ids(1)
    prisms, rest = level_prisms(np.arange(4), prints, run_id)
    assert len(prisms) == 1 and not len(rest)
    solid = prisms[0]
    assert solid.volume() == pytest.approx(8 * a * h * (top - floor), rel=VOLUME_REL)
    mesh = solid.to_mesh64()
    assert set(np.asarray(mesh.run_original_id).tolist()) == {run_id}
    vertices = np.asarray(mesh.vert_properties)[:, :3]
    assert set(vertices[:, 2].tolist()) == {floor, top}
    outer = a / 2 + h
    for corner in ((outer, outer), (-outer, outer), (outer, -outer), (-outer, -outer)):
        assert (vertices[:, :2] == corner).all(axis=1).any()


def test_fewer_than_fewest_prisms_on_a_floor_and_other_sweeps_are_left_to_the_solids():
    """Prisms are made per floor and top, of at least `FEWEST` sweeps; the rest keep their
    order."""
    run_id = manifold3d.Manifold.reserve_ids(1)
    square = _square((0.0, 0.0), 1e-3)
    prints = [None, (0.0, 1e-3, square), (-1e-3, 1e-3, square)] + [(0.0, 1e-3, square)] * 3
    prisms, rest = level_prisms(np.array([5, 4, 3, 2, 1, 0]), prints, run_id)
    assert len(prisms) == 1 and prisms[0].volume() == pytest.approx(4e-9, rel=VOLUME_REL)
    assert rest.tolist() == [2, 0]


def _zigzag(rows, step, depth):
    """A pocket's zigzag at one depth: passes along X, stepped along Y (m)."""
    points = []
    for row in range(rows):
        x0, x1 = (0.8e-3, 3.2e-3) if row % 2 == 0 else (3.2e-3, 0.8e-3)
        y = 1e-3 + row * step
        points += [(x0, y), (x1, y)]
    return [np.array([_pose(x, y, -depth) for x, y in points])]


def test_a_zigzag_pocket_is_the_pocket_united_in_three_dimensions(monkeypatch):
    """A zigzag pocket, 40 passes at 20 um step-over with a 1 mm end mill: the part cut by
    footprints is the part cut by the 3-D union of the same sweeps (the second method),
    and the footprints were used."""
    tool = FlatEndMill(0.5e-3, chord_tol=1e-6, height=5e-3)
    paths = _zigzag(40, 20e-6, 0.1e-3)
    stock = block(4e-3, 4e-3, 1e-3)
    made = []
    original = footprints._prism

    def record(*args):
        made.append(original(*args))
        return made[-1]

    monkeypatch.setattr(footprints, "_prism", record)
    part, report = remove(stock, tool, paths, method="boolean")
    assert made and all(prism is not None for prism in made)
    monkeypatch.setattr(footprints, "FEWEST", 10 ** 9)
    solid, solid_report = remove(stock, tool, paths, method="boolean")
    assert report.removed_volume == pytest.approx(solid_report.removed_volume, rel=VOLUME_REL)
    apart = (part.manifold - solid.manifold).volume() + (solid.manifold - part.manifold).volume()
    assert apart <= VOLUME_REL * report.removed_volume
