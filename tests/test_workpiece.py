"""Stock shapes against their analytic volumes and bounds, specs, mesh round trips, exports."""

import math
import os
import warnings

import numpy as np
import pytest

from machinesim.exceptions import InputError, MachineSimWarning
from machinesim.tool_specs import tool_from_spec
from machinesim.workpiece import (
    Part,
    block,
    block_with_spheres,
    cylinder,
    diamond_crown,
    mesh_volume,
    stock_from_spec,
)

#: Volumes of shapes with a few hundred float64 vertices at mm scale agree to ~1e-15 relative;
#: 1e-12 leaves room for the summation order of manifold3d's volume.
VOLUME_REL = 1e-12


def test_block_spec_occupies_the_stated_box():
    part = stock_from_spec("block:10x20x2")
    np.testing.assert_array_equal(part.bounds, [[0, 0, -2e-3], [10e-3, 20e-3, 0]])
    assert part.volume == pytest.approx(10e-3 * 20e-3 * 2e-3, rel=VOLUME_REL)


def test_placement_translates_the_stock():
    part = stock_from_spec("block:10x10x2@-5,-5,0.5")
    np.testing.assert_allclose(part.bounds, [[-5e-3, -5e-3, -1.5e-3], [5e-3, 5e-3, 0.5e-3]],
                               atol=1e-18)


def test_cylinder_is_the_inscribed_polygon_prism():
    part = stock_from_spec("cylinder:5x2")
    vertices, _ = part.mesh()
    radius, height = 5e-3, 2e-3
    np.testing.assert_allclose(np.hypot(vertices[:, 0], vertices[:, 1]), radius, rtol=1e-14)
    n = len(vertices) // 2
    # Inscribed n-gon: area n/2 r^2 sin(2 pi / n); its sagitta is within 1 nm of the circle.
    assert part.volume == pytest.approx(0.5 * n * radius**2 * math.sin(2 * math.pi / n)
                                        * height, rel=VOLUME_REL)
    assert radius * (1 - math.cos(math.pi / n)) <= 1e-9
    assert part.bounds[1, 2] == 0.0 and part.bounds[0, 2] == -height


def test_reference_spheres_add_three_hemispheres():
    radius = 1e-3
    part = block_with_spheres(10e-3, 10e-3, 2e-3, radius, chord_tol=1e-6)
    dimpled = block_with_spheres(10e-3, 10e-3, 2e-3, radius, chord_tol=1e-6, dimples=True)
    hemispheres = 3 * 2.0 / 3.0 * math.pi * radius**3
    base = 10e-3 * 10e-3 * 2e-3
    # The polygon lies between spheres of radius R - tol and R (vertices on the sphere).
    low = 3 * 2.0 / 3.0 * math.pi * (radius - 1e-6) ** 3
    assert low <= part.volume - base <= hemispheres
    assert low <= base - dimpled.volume <= hemispheres
    assert part.bounds[1, 2] == pytest.approx(radius, abs=1e-18)
    # Default centres: S1 -> S2 along +X and S1 -> S3 along +Y, 2 R in from the edges.
    vertices, _ = part.mesh()
    top = vertices[vertices[:, 2] > radius * (1 - 1e-12)]
    np.testing.assert_allclose(np.sort(top[:, 0]), [2e-3, 2e-3, 8e-3], atol=1e-15)


def test_crown_volume_matches_the_frustum_formula():
    across, height, base_size, base_height, slope = 4e-3, 0.2e-3, 10e-3, 3e-3, math.atan(0.2)

    def octagon(apothem):
        return 8 * apothem**2 * math.tan(math.pi / 8)

    for oversize in (0.0, 10e-6):
        part = diamond_crown(oversize)
        # Sides moved out by the oversize along their normals, top raised by it: at the new
        # top the apothem grows by oversize * (1 - cos(slope)) / sin(slope).
        a_top = across / 2 + oversize * math.tan(slope / 2)
        a_bottom = a_top + height / math.tan(slope)
        top, bottom = octagon(a_top), octagon(a_bottom)
        frustum = height / 3 * (top + bottom + math.sqrt(top * bottom))
        expected = base_size**2 * (base_height + oversize) + frustum
        assert part.volume == pytest.approx(expected, rel=VOLUME_REL)
        assert part.bounds[1, 2] == pytest.approx(oversize, abs=1e-18)
    assert stock_from_spec("crown").volume == pytest.approx(diamond_crown().volume, rel=1e-15)


def test_from_mesh_round_trip_is_exact():
    rng = np.random.default_rng(0)
    part = block(1e-3, 2e-3, 3e-3, origin=rng.normal(size=3) * 1e-3)
    vertices, triangles = part.mesh()
    again = Part.from_mesh(vertices, triangles)
    v2, t2 = again.mesh()
    np.testing.assert_array_equal(v2, vertices)
    np.testing.assert_array_equal(t2, triangles)


def test_from_mesh_rejects_an_open_mesh():
    vertices, triangles = block(1e-3, 1e-3, 1e-3).mesh()
    with pytest.raises(InputError, match="not a closed oriented 2-manifold"):
        Part.from_mesh(vertices, triangles[:-1])
    with pytest.raises(InputError, match=r"shape \(n, 3\)"):
        Part.from_mesh(vertices[:, :2], triangles)


def test_from_mesh_rejects_an_inside_out_mesh():
    # a mesh wound clockwise seen from outside (some exporters do) was accepted with a
    # negative volume, and every instrument then read its bottom as the top surface: a
    # 1 mm cube's height map read -1 mm everywhere instead of 0
    vertices, triangles = block(1e-3, 1e-3, 1e-3).mesh()
    with pytest.raises(InputError, match=r"inside out: it encloses -1e-09 m\^3"):
        Part.from_mesh(vertices, triangles[:, ::-1])


def test_from_mesh_refuses_what_is_no_mesh_naming_the_array():
    # a path for the vertices and an empty mesh had raised numpy's ValueError ("could not
    # convert string to float", "zero-size array to reduction"), and an index 1.5 was cast
    # to 1, a closed mesh of another shape
    vertices, triangles = block(1e-3, 1e-3, 1e-3).mesh()
    with pytest.raises(InputError, match=r"key 'vertices': Expected vertices as coordinates "
                                         r"\(m\), got 'part.ply'"):
        Part.from_mesh("part.ply", triangles)
    with pytest.raises(InputError, match=r"key 'triangles': expected triangles of shape "
                                         r"\(m, 3\), m >= 4 for a closed solid, got \(0, 3\)"):
        Part.from_mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=int))
    halves = triangles.astype(float)
    halves[0, 1] += 0.5
    with pytest.raises(InputError, match=r"key 'triangles': expected whole vertex indices"):
        Part.from_mesh(vertices, halves)
    whole = Part.from_mesh(vertices, triangles.astype(float))  # whole floats are indices
    assert whole.volume == pytest.approx(1e-9, rel=VOLUME_REL)


def test_a_part_is_made_from_a_manifold_only_naming_what_it_got():
    # Part(part) was taken and failed at its first use: AttributeError: 'Part' object has no
    # attribute 'bounding_box' (or 'to_mesh64')
    part = block(1e-3, 1e-3, 1e-3)
    with pytest.raises(InputError, match=r"key 'manifold': Expected the solid as a "
                       r"manifold3d.Manifold, got Part \(a part is never mutated"):
        Part(part)
    with pytest.raises(InputError, match=r"got tuple \(a mesh: Part.from_mesh"):
        Part(part.mesh())
    with pytest.raises(InputError, match="got NoneType"):
        Part(None)
    again = Part(part.manifold)  # what the refusal names
    assert again.volume == pytest.approx(1e-9, rel=VOLUME_REL)
    np.testing.assert_array_equal(again.bounds, part.bounds)


def _read_ply(path):
    """Independent binary PLY reader for the layout written by export_ply."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    nv = int(next(line for line in header if line.startswith("element vertex")).split()[-1])
    nf = int(next(line for line in header if line.startswith("element face")).split()[-1])
    assert "property double x" in header
    vertices = np.frombuffer(data, dtype="<f8", count=3 * nv, offset=end).reshape(nv, 3)
    faces = np.frombuffer(data, dtype=[("n", "u1"), ("i", "<i4", 3)], count=nf,
                          offset=end + 24 * nv)
    assert np.all(faces["n"] == 3)
    return vertices, faces["i"].astype(np.int64)


def test_mesh_volume_of_a_far_placed_cylinder_is_the_prism_formula():
    # Inscribed n-gon prism: (n / 2) r^2 sin(2 pi / n) h, 1 km from the origin, where a sum
    # of tetrahedra from the origin would lose ~12 digits to cancellation.
    part = cylinder(1e-3, 2e-3, origin=(1e3, -1e3, 5e2), chord_tol=1e-6)
    vertices, triangles = part.mesh()
    n = len(vertices) // 2
    expected = n / 2 * (1e-3) ** 2 * math.sin(2 * math.pi / n) * 2e-3
    assert mesh_volume(vertices, triangles) == pytest.approx(expected, rel=1e-9)


def test_a_meshed_part_builds_the_same_manifold_on_demand():
    source = diamond_crown()
    vertices, triangles = source.mesh()
    part = Part._closed(vertices, triangles)
    assert part.volume == pytest.approx(source.volume, rel=VOLUME_REL)
    np.testing.assert_array_equal(part.bounds, source.bounds)
    assert part.manifold.num_tri() == len(triangles)
    assert part.manifold.volume() == pytest.approx(source.volume, rel=VOLUME_REL)
    with pytest.raises(ValueError):
        part.mesh()[0][0, 0] = 1.0  # immutable: the arrays are read-only


def test_ply_round_trip_is_bit_exact(tmp_path):
    rng = np.random.default_rng(0)
    # Irrational coordinates: every mantissa bit matters.
    part = Part(stock_from_spec("cylinder:1x1").manifold.translate(tuple(rng.normal(size=3))))
    path = tmp_path / "part.ply"
    part.export_ply(path)
    vertices, triangles = _read_ply(path)
    expected_v, expected_t = part.mesh()
    assert vertices.tobytes() == expected_v.tobytes()
    np.testing.assert_array_equal(triangles, expected_t)
    assert [p.name for p in tmp_path.iterdir()] == ["part.ply"]  # no temp file left


def test_stl_and_glb_exports_are_readable(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    part = stock_from_spec("block:1x2x3")
    part.export_stl(tmp_path / "part.stl")
    part.export_glb(tmp_path / "part.glb")
    stl = trimesh.load(tmp_path / "part.stl")
    assert len(stl.faces) == 12
    assert stl.volume == pytest.approx(6.0, rel=1e-6)  # mm^3, float32 coordinates
    assert os.path.getsize(tmp_path / "part.stl") == 84 + 50 * 12
    glb = trimesh.load(tmp_path / "part.glb", force="mesh")
    assert glb.volume == pytest.approx(6.0, rel=1e-6)  # mm^3


def test_an_export_refuses_a_path_ending_in_another_format_naming_the_one_that_writes_it(
        tmp_path):
    # export_ply("part.stl") wrote the 'ply' header and float64 metres under an STL's name
    part = stock_from_spec("block:1x2x3")
    for export, name, words in [
            (part.export_ply, "part.stl", "Part.export_ply writes a PLY file (float64, "
             "metres: exact), and the path ends in .stl: expected a name ending in .ply; for "
             "a binary STL (float32, millimetres: display only) call Part.export_stl"),
            (part.export_stl, "part.ply", "the path ends in .ply: expected a name ending in "
             ".stl; for a PLY file (float64, metres: exact) call Part.export_ply"),
            (part.export_glb, "part.gltf", "the path ends in .gltf: expected a name ending "
             "in .glb"),
            (part.export_ply, "part", "the path has no ending: expected a name ending in .ply"),
    ]:
        with pytest.raises(InputError) as raised:
            export(str(tmp_path / name))
        assert raised.value.source == str(tmp_path / name) and raised.value.key == "path"
        assert words in str(raised.value), str(raised.value)
    assert list(tmp_path.iterdir()) == []  # nothing written
    # the ending in any case: a PLY under .PLY is the one under .ply, byte for byte
    part.export_ply(tmp_path / "upper.PLY")
    part.export_stl(tmp_path / "upper.Stl")
    assert (tmp_path / "upper.PLY").read_bytes() == part.encode("ply")
    assert (tmp_path / "upper.Stl").read_bytes() == part.encode("stl")


def test_a_ply_part_read_by_trimesh_as_the_readme_says_is_the_part(tmp_path):
    # 10 um V grooves on a block in metres: trimesh's default merge (1e-8, here 10 nm)
    # would fold their edges; read with process=False the mesh is the part, closed, and
    # its volume the part's to round-off (README, "Cutting a program")
    trimesh = pytest.importorskip("trimesh")
    from machinesim.cutting import cut
    from machinesim.nc import ProgramBuilder

    b = ProgramBuilder(1)
    for y in (2e-3, 2.004e-3):
        b.rapid(X=-1e-3, Y=y, Z=1e-4).rapid(Z=-1e-5).linear(X=6e-3, feed_mm_per_min=100.0)
        b.rapid(Z=1e-4)
    part, _ = cut(b.build(), "grooving_4axis", tool="v:90", stock="block:5x5x1")
    part.export_ply(tmp_path / "part.ply")
    mesh = trimesh.load(tmp_path / "part.ply", process=False)
    assert mesh.is_watertight
    assert len(mesh.vertices) == len(part.mesh()[0])
    assert mesh.volume == pytest.approx(part.volume, rel=1e-12)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("block:10x10", "'block:10x10'.*expected 3 numbers"),
        ("block:10x10x-2", "'block:10x10x-2'.*sizes '10x10x-2' must lie in 1e-06 .. 10000 mm"),
        ("cylinder:5", "'cylinder:5'.*expected 2 numbers"),
        ("block:10x10x2@1,2", "expected 3 numbers separated by ','"),
        # an empty placement (a shell's '@$POS' with POS unset) was read as none, the
        # stock standing at the origin with exit 0
        ("block:10x10x2@", "'block:10x10x2@'.*expected 3 numbers separated by ',' in ''"),
        ("cylinder:5x2@ ", "expected 3 numbers separated by ','"),
        # an overflowing size reads as inf; it was told 'expected 3 numbers', which it had
        ("block:1e400x10x2", "'1e400' in '1e400x10x2' is not a finite number of mm"),
        # float() reads '1_0' as 10 and full-width digits as ASCII ones
        ("block:1_0x10x2", "expected 3 numbers separated by 'x' in '1_0x10x2'"),
        ("block:\uff11\uff10x10x2", "expected 3 numbers separated by 'x'"),
        ("block:10x10x2@0,nan,0", "'nan' in '0,nan,0' is not a finite number of mm"),
        ("sphere:1", "'sphere:1'.*expected 'block:LxWxH'"),
        ("spheres:10x10x2:3", "radius must be positive and below"),
        ("spheres:10x10x2:1:bumps", "expected 'dimples'"),
    ],
)
def test_bad_stock_specs_raise_input_error(spec, message):
    with pytest.raises(InputError, match=message):
        stock_from_spec(spec)


def test_a_stock_spec_refusal_names_the_spec_once():
    # it read "key 'stock': stock spec 'block:10x10': ..."; the command line names --stock
    with pytest.raises(InputError) as caught:
        stock_from_spec("block:10x10x-2")
    assert str(caught.value) == ("stock spec 'block:10x10x-2': sizes '10x10x-2' must lie in "
                                 "1e-06 .. 10000 mm")
    assert caught.value.key is None
    with pytest.raises(InputError) as caught:
        stock_from_spec("spheres:10x10x2:1:bumps", name="--stock")
    assert str(caught.value) == "--stock 'spheres:10x10x2:1:bumps': expected 'dimples', got 'bumps'"


def test_spec_refusals_give_lengths_in_mm_first_and_clean():
    # specs are in mm, but the refusal read "... smaller side (0.0025 m), got
    # 0.009000000000000001 m": metres first, with the round-off of 9 * 1e-3
    with pytest.raises(InputError) as caught:
        stock_from_spec("spheres:10x10x2:9", name="--stock")
    assert str(caught.value) == ("--stock 'spheres:10x10x2:9': sphere radius must be positive "
                                 "and below a quarter of the block's smaller side, 2.5 mm "
                                 "(0.0025 m), got 9 mm (0.009 m)")
    with pytest.raises(InputError) as caught:
        stock_from_spec("crown:1.1")
    assert str(caught.value) == ("stock spec 'crown:1.1': crown oversize must lie in 0 .. 1 "
                                 "mm, got 1.1 mm (0.0011 m)")
    # the tool specs' lengths and angles alike: 'v:270' read "got 4.71238898038469 rad
    # (270.0 deg)"; 3 pi / 2 rad to 12 digits
    with pytest.raises(InputError) as caught:
        tool_from_spec("v:270", name="--tool")
    assert str(caught.value) == ("--tool 'v:270': included_angle must lie between 0 and 180 "
                                 "deg (0 and pi rad), got 270 deg (4.71238898038 rad)")


def test_cylinder_radius_error():
    with pytest.raises(InputError, match="radius must be positive"):
        cylinder(0.0, 1e-3)


def test_a_solid_refuses_a_size_that_is_no_number_naming_it():
    # cylinder("5", 2) ended in "TypeError: must be real number, not str", and True read as
    # a size of 1 m
    cases = [
        (lambda: cylinder("5", 2e-3), "radius", "cylinder radius must be a number in m, got "
         "'5' (str); a size written as text, in mm, is read by "
         "stock_from_spec('cylinder:RxH')"),
        (lambda: cylinder(1e-3, True), "height", "cylinder height must be a number in m, got "
         "True (bool)"),
        (lambda: block(1e-3, None, 1e-3), "width", "block width must be a number in m, got "
         "None (NoneType)"),
        (lambda: block_with_spheres(0.01, 0.01, 0.002, "1"), "radius", "sphere radius must be "
         "a number in m, got '1' (str)"),
    ]
    for make, key, message in cases:
        with pytest.raises(InputError) as raised:
            make()
        assert raised.value.key == key
        assert message in str(raised.value), str(raised.value)
    # numpy numbers are numbers: the cylinder as from floats, pi r^2 h to its chord polygon
    assert (cylinder(np.float64(1e-3), np.array(2e-3)).volume
            == cylinder(1e-3, 2e-3).volume == pytest.approx(math.pi * 2e-9, rel=1e-6))


def test_a_stock_spec_number_may_end_in_mm_as_a_tool_spec_size_may():
    # 'ball:0.5mm' is read; 'block:10x10x2mm' was refused ('expected 3 numbers')
    for spec, plain in [("block:10x10x2mm", "block:10x10x2"),
                        ("block:10mmx20 MMx2mm@-5mm,-5,0.5mm", "block:10x20x2@-5,-5,0.5"),
                        ("cylinder:5mmx2mm", "cylinder:5x2"), ("crown:0.01mm", "crown:0.01"),
                        ("spheres:20x20x3:2mm", "spheres:20x20x3:2")]:
        np.testing.assert_array_equal(stock_from_spec(spec).bounds,
                                      stock_from_spec(plain).bounds)
    assert stock_from_spec("block:10x10x2mm").volume == pytest.approx(200e-9, rel=VOLUME_REL)
    # another unit is refused as that unit, with its value in mm (it read 'expected 3 numbers')
    with pytest.raises(InputError, match=r"'2um' is not in mm: .*; 2 um is 0\.002 mm$"):
        stock_from_spec("block:10x10x2um")


def test_from_mesh_notes_a_part_in_millimetres_read_as_metres(tmp_path):
    # an STL (millimetres, as CAD tools read it) read back as it is was taken silently as a
    # part 1000 times too large: the 10 mm block a 10 m one, whose profiles read flat land
    trimesh = pytest.importorskip("trimesh")
    block(10e-3, 10e-3, 5e-3).export_stl(tmp_path / "part.stl")
    stl = trimesh.load(tmp_path / "part.stl", process=True)
    with pytest.warns(MachineSimWarning, match=r"measures 10 x 10 x 5 m, larger than any "
                      r"shipped machine's travel \(0.5 m at most\).*millimetres"):
        part = Part.from_mesh(stl.vertices, stl.faces)
    assert part.volume == pytest.approx(500.0, rel=1e-6)  # m^3: the noted part is still made
    # the largest shipped travel (X 500 mm on grooving_4axis) is a size no note is due for
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Part.from_mesh(*block(0.5, 0.5, 0.1).mesh())
