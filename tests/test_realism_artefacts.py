"""Realism of the artefacts a lab makes (spheres in a stock): off, the design made
exactly; on, drawn per workpiece from the seed and cut where they are, part of the lab's
truth; the same workpiece handed back when asked for again."""

from __future__ import annotations

import numpy as np
import pytest
from realism_helpers import MM, UM

from machinesim import Lab
from machinesim.exceptions import InputError
from machinesim.metrology import fit_sphere
from machinesim.realism import ARTEFACT, Realism, SphereArtefacts
from machinesim.workpiece import Part, block_with_spheres


def _same_mesh(a: Part, b: Part) -> bool:
    """The same vertices, bit for bit, and the same triangles in any order (manifold3d's
    output order depends on which operands it had evaluated before)."""
    (va, ta), (vb, tb) = a.mesh(), b.mesh()

    def canonical(vertices, triangles):
        corners = [tuple(map(tuple, vertices[t])) for t in triangles]
        return sorted(min(c[k:] + c[:k] for k in range(3)) for c in corners)

    return canonical(va, ta) == canonical(vb, tb)


def test_artefacts_off_are_the_design_made_exactly(flat):
    design = SphereArtefacts(np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0], [1.2, 2.0, 0.0]]) * MM,
                             0.25 * MM, cavities=True)
    lab = Lab("robonano_a0ib", seed=1)
    made = lab.make_artefacts(flat, design, label="block")
    reference = block_with_spheres(5 * MM, 3 * MM, 1 * MM, 0.25 * MM,
                                   design.centres[:, :2], dimples=True)
    assert _same_mesh(made, reference)
    actual = lab.reveal_artefacts()["block"]
    assert np.array_equal(actual.centres, design.centres) and actual.radius == 0.25 * MM
    with pytest.raises(InputError, match="label"):
        lab.make_artefacts(flat, design, label=None)


def test_artefacts_are_made_in_a_stock_given_as_a_spec_as_cut_takes_it():
    """docs/lab.md's lab.make_artefacts(stock, design, label=) took a Part only: the spec
    lab.cut takes, "block:10x10x2", ended in TypeError: unsupported operand type(s) for -:
    'str' and 'Manifold' inside realism.make_spheres. Now it is read as cut reads it (mm),
    the same workpiece as the Part built by hand; anything else is refused naming 'stock'."""
    design = SphereArtefacts(np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0], [1.2, 2.0, 0.0]]) * MM,
                             0.25 * MM)
    made = Lab("robonano_a0ib", seed=1).make_artefacts("block:5x3x1", design, label="a")
    reference = block_with_spheres(5 * MM, 3 * MM, 1 * MM, 0.25 * MM,
                                   design.centres[:, :2], dimples=True)
    assert _same_mesh(made, reference)
    with pytest.raises(InputError, match=r"key 'stock': Expected stock as a spec such as "
                                         r"'block:10x10x2' or a Part, got NoneType"):
        Lab("robonano_a0ib").make_artefacts(None, design, label="a")


def test_a_sphere_design_in_mm_is_refused_before_its_polygon_is_built():
    """SphereArtefacts(centres, 1.0), a radius of 1 mm given as m, was taken, and
    make_artefacts then built a sphere polygon of some 12 million vertices per sphere at
    the default chord_tol (over 120 s, never finishing). Now refused at design, naming the
    radius, the polygon's size against MAX_TOOL_VERTICES and the unit; 1 mm is made."""
    centres = np.array([[2.0, 2.0, 0.0], [8.0, 2.0, 0.0], [5.0, 8.0, 0.0]])
    with pytest.raises(InputError, match=r"key 'radius': a sphere of radius 1 m at chord_tol "
                                         r"1e-07 m would be a polygon of some 12,348,196 "
                                         r"vertices, over MAX_TOOL_VERTICES \(200,000\): "
                                         r"expected the radius in m"):
        SphereArtefacts(centres, 1.0)
    assert SphereArtefacts(centres * MM, 1.0 * MM).radius == 1e-3


def test_artefacts_on_are_drawn_per_workpiece_and_cut_where_they_are(flat):
    centres = np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0], [1.2, 2.0, 0.0]]) * MM
    design = SphereArtefacts(centres, 0.4 * MM)

    def made(label, extra=False):
        lab = Lab("robonano_a0ib", seed=2, realism=Realism.with_only("artefact_errors"))
        if extra:
            lab.make_artefacts(flat, design, label="other")
            lab.microscope()
        part = lab.make_artefacts(flat, design, label=label)
        return part, lab.reveal_artefacts()[label]

    part, actual = made("crown")
    _, again = made("crown", extra=True)
    _, other = made("grooves")
    assert np.array_equal(actual.centres, again.centres) and actual.radius == again.radius
    assert not np.array_equal(actual.centres, other.centres)
    shift = actual.centres - centres
    assert 0.1 * UM < np.abs(shift).max() < 5 * ARTEFACT.position
    assert abs(actual.radius - 0.4 * MM) < 5 * ARTEFACT.radius
    # the cavity's vertices lie on the actual sphere: its radius plus the form there
    vertices, _ = part.mesh()
    for c, form in zip(actual.centres, actual.forms, strict=True):
        d = vertices - c
        r = np.linalg.norm(d, axis=1)
        near = np.flatnonzero((np.abs(r - actual.radius) < 3 * ARTEFACT.form)
                              & (vertices[:, 2] < -1 * UM))
        assert len(near) > 100
        np.testing.assert_allclose(r[near], actual.radius + form(d[near] / r[near, None]),
                                   rtol=0, atol=1e-12)
        fitted = fit_sphere(vertices[near])
        assert np.linalg.norm(fitted.centre - c) < ARTEFACT.form


def test_a_workpiece_asked_for_again_is_the_one_the_lab_made(flat):
    # A procedure asks the lab in measure and again in evaluate, keeping no lab between them
    # (RobotLoadedWorkpiece had kept every lab it met, and the workpiece, in _workpieces:
    # its identify could reach lab.reveal()). Made twice, a workpiece came back with its
    # triangles in another order (manifold3d), a stock its cuts' memo keys apart.
    centres = np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0], [1.2, 2.0, 0.0]]) * MM
    design = SphereArtefacts(centres, 0.4 * MM)
    lab = Lab("robonano_a0ib", seed=2, realism=Realism.with_only("artefact_errors"))
    first = lab.make_artefacts(flat, design, label="crown")
    actual = lab.reveal_artefacts()["crown"]
    again = lab.make_artefacts(Part(flat.manifold), design, label="crown")  # an equal stock
    assert again is first and lab.reveal_artefacts()["crown"] is actual
    # another design under the label is another workpiece, drawn from the label's stream
    bumps = SphereArtefacts(centres, 0.4 * MM, cavities=False)
    other = lab.make_artefacts(flat, bumps, label="crown")
    assert other is not first and other.volume > first.volume
    assert np.array_equal(lab.reveal_artefacts()["crown"].centres, actual.centres)



def test_a_labs_seed_and_realism_are_fixed_so_its_artefacts_stay_as_made(flat):
    """make_artefacts hands back the part it made for the same label, stock and design; the
    seed and the realism decide the spheres too. A lab whose seed or realism was set anew
    had handed back the part drawn under the old ones (then made them again, its instruments
    still from the old ones): both are now fixed for the lab's life, and another seed is
    another Lab."""
    from machinesim.exceptions import ReadOnlyError

    design = SphereArtefacts(np.array([[1.2, 1.0, 0.0], [3.8, 1.0, 0.0]]) * MM, 0.4 * MM)
    errors = Realism.with_only("artefact_errors")
    lab = Lab("robonano_a0ib", seed=2, realism=errors)
    first = lab.make_artefacts(flat, design, label="crown")
    assert lab.make_artefacts(flat, design, label="crown") is first  # asked again: the same
    centres = lab.reveal_artefacts()["crown"].centres
    with pytest.raises(ReadOnlyError, match=r"^Lab\.seed cannot be set \(to 3\)"):
        lab.seed = 3
    with pytest.raises(ReadOnlyError, match=r"^Lab\.realism cannot be set"):
        lab.realism = Realism.ideal()
    assert (lab.seed, lab.realism) == (2, errors)
    assert lab.make_artefacts(flat, design, label="crown") is first
    assert np.array_equal(lab.reveal_artefacts()["crown"].centres, centres)
    # another seed is another lab, its spheres drawn from its own streams
    fresh = Lab("robonano_a0ib", seed=3, realism=errors)
    fresh.make_artefacts(flat, design, label="crown")
    assert not np.array_equal(fresh.reveal_artefacts()["crown"].centres, centres)
