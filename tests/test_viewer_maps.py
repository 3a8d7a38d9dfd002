"""The viewer's surface maps without a browser: a deviation map is the exact plane
difference, its legend's P-V, RMS and ticks read as the grid gives them, the map mesh
covers the part and the colours interpolate their stops."""

from __future__ import annotations

import numpy as np
import pytest
from viewer_helpers import BUDGET, tilted_block

from machinesim.cutting import cut
from machinesim.metrology import height_map
from machinesim.nc import ProgramBuilder, parse_program
from machinesim.viewer import surface_map
from machinesim.viewer.maps import DIVERGING, NO_DATA, SurfaceMap, colours, legend_for, map_mesh
from machinesim.workpiece import block, stock_from_spec

UM, MM = 1e-6, 1e-3


def test_deviation_map_of_a_tilted_top_is_the_exact_plane_difference():
    slope = 1e-4  # 0.1 um per mm: +-100 nm over the 2 mm block
    smap = surface_map(tilted_block(slope), block(2 * MM, 1 * MM, 0.5 * MM), BUDGET)
    expected = slope * (smap.x - 1 * MM)[None, :] * np.ones((len(smap.y), 1))
    # float64 plane evaluations of ~1e-7 m values: round-off ~1e-22 m, far below 1e-18 m
    np.testing.assert_allclose(smap.values, expected, rtol=0, atol=1e-18)
    assert smap.kind == "deviation"
    assert smap.peak_to_valley == pytest.approx(200e-9, rel=1e-12)
    legend = legend_for(smap)
    assert [label for _, label in legend.ticks] == ["-100 nm", "-50 nm", "+0 nm", "+50 nm",
                                                    "+100 nm"]
    assert legend.notes[0].startswith("P-V 200 nm, RMS")


def test_a_legend_says_its_p_v_is_the_grid_nodes_and_how_far_apart_they_stand():
    # The README's part: four V grooves 20 um deep and 40 um wide across a 10 mm block. On
    # the default 317 x 317 nodes (31.65 um apart) no node lies on an apex, so the legend's
    # P-V read 13.67 um under "exact heights", which a user takes for the part's 20 um.
    program = ProgramBuilder(1)
    for i, y in enumerate((2, 4, 6, 8)):
        program.rapid(X=(-1 if i % 2 == 0 else 11) * MM, Y=y * MM, Z=0.1 * MM)
        program.rapid(Z=-20 * UM).linear(X=(11 if i % 2 == 0 else -1) * MM,
                                         feed_mm_per_min=100.0).rapid(Z=0.1 * MM)
    part, _ = cut(program.build(), "grooving_4axis", tool="v:90", stock="block:10x10x2")
    smap = surface_map(part)
    spacing = 10 * MM / (len(smap.x) - 1)
    assert len(smap.x) == len(smap.y) == 317 and spacing == pytest.approx(31.65 * UM, abs=5e-9)
    # an exact height map of the same part through the apexes reads the full depth
    assert np.nanmin(height_map(part, smap.x, np.array([2 * MM]))) == pytest.approx(-20 * UM,
                                                                                   abs=1e-15)
    assert smap.peak_to_valley == pytest.approx(13.67 * UM, abs=0.01 * UM)
    legend = legend_for(smap)
    assert legend.notes[0] == "P-V 13.67 um"
    assert legend.notes[1] == ("317 x 317 exact heights (metrology.height_map), 31.65 um "
                               "apart: the P-V and RMS of these nodes, which a narrower "
                               "groove or peak can fall between")


def test_a_map_reads_the_top_at_the_parts_rim_not_its_side_faces():
    # A flat end mill's G18 dip 0.15 mm deep run off the block's edge at x = 10 mm (a
    # new-user pass's trunnion part): the cut leaves the side face at x = 10 mm with vertices
    # 1.7e-18 m inside it, so the floor's triangles end short of a node on the bounds, which
    # read that leaning face's plane: -3.04 mm on a 5 mm block, the legend's P-V 3378 um
    # where the errors were 10 um. The dip bottoms at its 0.15 mm (less its 100 nm chords).
    program = parse_program("G21 G90\nG00 X5.5 Y3. Z1.\nG01 Z0. F100.\n"
                            "G18 G02 X9.5 Z0. R13.408333\nG00 Z1.\nM30\n",
                            chord_tolerance=1e-7)
    part, report = cut(program, "grooving_4axis", tool="flat:1.0",
                       stock="block:20x20x5@-10,-10,0")
    assert report.removed_volume_m3 > 0.0
    smap = surface_map(part)
    assert smap.x[-1] == pytest.approx(10 * MM, abs=1e-14)
    assert np.nanmin(smap.heights) >= -0.15 * MM - 1e-12
    assert np.nanmin(smap.heights[:, -1]) == pytest.approx(-65.67 * UM, abs=0.01 * UM)


def test_a_legend_tick_at_round_off_of_zero_reads_zero():
    # heights from -1 um to 1 um but for 1e-22 m: the middle tick read '+2.118e-13 nm'
    x = y = np.array([0.0, 1e-3])
    heights = np.array([[-999.8e-9, 0.0], [0.0, 999.8e-9 + 2e-22]])
    legend = legend_for(SurfaceMap(x, y, heights, heights, "height"))
    assert [label for _, label in legend.ticks] == ["-999.8 nm", "-499.9 nm", "+0 nm",
                                                    "+499.9 nm", "+999.8 nm"]


def test_a_legends_p_v_and_rms_below_a_picometre_read_zero():
    # a part and its nominal the same but for round-off (2.745e-18 m) read 'P-V 2.745e-09
    # nm': below 1 pm (tolerances.POSE_M, the geometry's resolution) a figure reads 0, and
    # from 1 pm up it is written as before, to 4 digits
    x = y = np.array([0.0, 1e-3])

    def stats(values):
        values = np.asarray(values, dtype=np.float64)
        return legend_for(SurfaceMap(x, y, values, values, "deviation")).notes[0]

    assert stats([[2.745e-18, 0.0], [0.0, 0.0]]) == "P-V 0 nm, RMS 0 nm"
    assert stats([[4e-13, -5e-13], [0.0, 0.0]]) == "P-V 0 nm, RMS 0 nm"  # 0.9 pm P-V
    # 4 pm P-V, RMS sqrt((2^2 + 2^2) / 4) = 1.414 pm
    assert stats([[2e-12, -2e-12], [0.0, 0.0]]) == "P-V 0.004 nm, RMS 0.001414 nm"
    # RMS sqrt(2^2 / 4) = 1 pm exactly: no longer below the cut-off, so written
    assert stats([[2e-12, 0.0], [0.0, 0.0]]) == "P-V 0.002 nm, RMS 0.001 nm"
    assert stats([[100e-9, -100e-9], [0.0, 0.0]]) == "P-V 200 nm, RMS 70.71 nm"
    heights = np.full((2, 2), 0.5e-3)  # a flat top: P-V 0 as before
    assert legend_for(SurfaceMap(x, y, heights, heights, "height")).notes[0] == "P-V 0 nm"


def test_map_mesh_faces_up_covers_the_part_and_leaves_out_cells_off_it():
    smap = surface_map(tilted_block(1e-4), block(2 * MM, 1 * MM, 0.5 * MM), BUDGET)
    vertices, triangles, rgb = map_mesh(smap)
    nx, ny = len(smap.x), len(smap.y)
    assert len(triangles) == 2 * (nx - 1) * (ny - 1) <= BUDGET
    corner = vertices[triangles]
    normal_z = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])[:, 2]
    assert np.all(normal_z > 0)
    # the scale is symmetric and the extremes are at x = 0 and x = L: the end colours
    np.testing.assert_allclose(rgb[0], DIVERGING[0], atol=1e-12)
    np.testing.assert_allclose(rgb[nx - 1], DIVERGING[-1], atol=1e-12)
    round_map = surface_map(stock_from_spec("cylinder:1x0.5"), max_triangles=BUDGET)
    _, round_tri, _ = map_mesh(round_map)
    assert 0 < len(round_tri) < 2 * (len(round_map.x) - 1) * (len(round_map.y) - 1)
    assert np.all(np.isfinite(round_map.heights.ravel()[np.unique(round_tri)]))


def test_colours_interpolate_the_stops_and_mark_missing_values():
    rgb = colours([-2.0, -1.0, 0.0, 0.5, 1.0, 3.0, np.nan], -1.0, 1.0, DIVERGING)
    np.testing.assert_allclose(rgb[0], DIVERGING[0])  # clipped below
    np.testing.assert_allclose(rgb[1], DIVERGING[0])
    np.testing.assert_allclose(rgb[2], DIVERGING[5])  # the middle of 11 stops
    np.testing.assert_allclose(rgb[3], 0.5 * (DIVERGING[7] + DIVERGING[8]))
    np.testing.assert_allclose(rgb[4], DIVERGING[-1])
    np.testing.assert_allclose(rgb[5], DIVERGING[-1])
    np.testing.assert_allclose(rgb[6], NO_DATA)
