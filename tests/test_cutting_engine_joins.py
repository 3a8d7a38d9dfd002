"""How the boolean engine joins: tiles stitched at their walls, sweeps united in runs, passes
inside deeper ones dropped, a ball's moves in line cut as one sweep; each against the
analytic part or the part cut without the join."""

import math

import manifold3d
import numpy as np
import pytest
from cutting_engine_helpers import LENGTH_TOL, VOLUME_REL, groove_x, pose

from machinesim.cutting import remove
from machinesim.cutting.stitch import exact_box, stitch
from machinesim.tools import BallEndMill, VTool
from machinesim.workpiece import block


def _tile_pieces(walls_x, walls_y, hull):
    boxes, pieces = [], []
    for x0, x1 in zip(walls_x[:-1], walls_x[1:], strict=True):
        for y0, y1 in zip(walls_y[:-1], walls_y[1:], strict=True):
            boxes.append((x0, x1, y0, y1))
            pieces.append(exact_box(x0, x1, y0, y1, -1e-3, 0.0) - hull)
    return boxes, pieces


def test_stitched_tiles_are_the_union_of_the_tiles():
    # A groove running diagonally across four tiles: its flanks cross every wall.
    tool = VTool(math.pi / 2).vertices()
    rotation = np.array([[math.cos(0.3), -math.sin(0.3), 0], [math.sin(0.3), math.cos(0.3), 0],
                         [0, 0, 1.0]])
    ends = [tool @ rotation.T + p for p in ([-0.2e-3, 0.1e-3, -20e-6], [1.2e-3, 0.6e-3, -20e-6])]
    hull = manifold3d.Manifold.hull_points(np.vstack(ends))
    walls = [0.0, 0.4123e-3, 1e-3]
    boxes, pieces = _tile_pieces(walls, walls, hull)
    joined = stitch(pieces, boxes, (0.0, 1e-3, 0.0, 1e-3), 1e-3)
    union = manifold3d.Manifold.batch_boolean(pieces, manifold3d.OpType.Add)
    assert joined is not None
    assert joined.volume() == pytest.approx(union.volume(), rel=VOLUME_REL)
    assert joined.num_tri() <= union.num_tri() + 8  # no wall faces left inside
    v_joined = np.unique(np.asarray(joined.to_mesh64().vert_properties), axis=0)
    v_union = np.unique(np.asarray(union.to_mesh64().vert_properties), axis=0)
    assert len(v_joined) == len(v_union)
    np.testing.assert_allclose(v_joined, v_union, atol=1e-18)


def test_stitch_refuses_tiles_whose_walls_do_not_match():
    hull = manifold3d.Manifold.hull_points(np.vstack(
        [VTool(math.pi / 2).vertices() + p for p in ([-1e-4, 0.5e-3, -2e-5],
                                                       [1.1e-3, 0.5e-3, -2e-5])]))
    boxes, pieces = _tile_pieces([0.0, 0.5e-3, 1e-3], [0.0, 1e-3], hull)
    # The right tile's groove 1 nm off: its wall section no longer matches the left one's.
    pieces[1] = exact_box(*boxes[1], -1e-3, 0.0) - hull.translate((0.0, 1e-9, 0.0))
    assert stitch(pieces, boxes, (0.0, 1e-3, 0.0, 1e-3), 1e-3) is None


def test_stitch_keeps_the_wall_of_an_empty_neighbour():
    hull = manifold3d.Manifold.hull_points(np.vstack(
        [VTool(math.pi / 2).vertices() + p for p in ([-1e-4, 0.5e-3, -2e-5],
                                                       [1.1e-3, 0.5e-3, -2e-5])]))
    boxes, pieces = _tile_pieces([0.0, 0.5e-3, 1e-3], [0.0, 1e-3], hull)
    pieces[1] = manifold3d.Manifold()  # all material of the right tile is gone
    joined = stitch(pieces, boxes, (0.0, 1e-3, 0.0, 1e-3), 1e-3)
    assert joined is not None
    assert joined.volume() == pytest.approx(pieces[0].volume(), rel=VOLUME_REL)


def test_union_runs_cap_the_overlapping_pairs_and_keep_side_by_side_sweeps_together():
    from machinesim.cutting.tiling import PAIRS_PER_UNION, union_runs

    # Boxes that all overlap: a run of n holds n (n - 1) / 2 pairs, so runs of 8 (28 pairs).
    count = 100
    lower = np.zeros((count, 3)) + 1e-9 * np.arange(count)[:, None]
    upper = lower + 1e-6
    runs = union_runs(np.arange(count), lower, upper)
    longest = max(n for n in range(2, count) if n * (n - 1) // 2 <= PAIRS_PER_UNION)
    assert [len(r) for r in runs] == [longest] * (count // longest) + [count % longest]
    np.testing.assert_array_equal(np.concatenate(runs), np.arange(count))
    # Grooves at their own width's pitch only touch: one union, as before the runs.
    pitch = 20e-6
    lower = np.stack([np.zeros(count), pitch * np.arange(count), np.zeros(count)], axis=1)
    upper = lower + [1e-3, pitch, 10e-6]
    assert [len(r) for r in union_runs(np.arange(count), lower, upper)] == [count]
    assert union_runs(np.arange(0), lower, upper) == []


def test_passes_stacked_down_a_slope_cut_the_analytic_staircase(monkeypatch):
    from machinesim.cutting import engine
    from machinesim.cutting.tiling import union_runs
    from machinesim.metrology.surface import height_map

    runs = []

    def recorded(*args):
        found = union_runs(*args)
        runs.extend(found)
        return found

    monkeypatch.setattr(engine, "union_runs", recorded)
    # Finishing passes down an inclined face: each 90-deg V pass is 0.2 um from the last
    # sideways and 0.1 um deeper, so its tool body overlaps the passes above it and the
    # engine cuts them in runs (`union_runs`). The top is the lowest of the V's:
    # z(y) = min_k (|y - y_k| - d_k), exact at every sample.
    count, step, drop, top_depth = 120, 0.2e-6, 0.1e-6, 1e-6
    stock = block(2e-3, 1e-3, 0.5e-3)
    ys = 0.45e-3 + step * np.arange(count)
    depths = top_depth + drop * np.arange(count)
    paths = [groove_x(y, d, x0=-0.5e-3, x1=2.5e-3) for y, d in zip(ys, depths, strict=True)]
    part, report = remove(stock, VTool(math.radians(90.0)), paths, method="boolean")
    assert report.method == "boolean" and report.n_sweeps_cut == count
    assert len(runs) > 10
    np.testing.assert_array_equal(np.concatenate(runs), np.arange(count))
    y = np.linspace(0.44e-3, 0.48e-3, 801)
    heights = height_map(part, np.array([0.3e-3, 1.7e-3]), y)
    expected = np.minimum(np.min(np.abs(y[:, None] - ys) - depths, axis=1), 0.0)
    np.testing.assert_allclose(heights, np.repeat(expected[:, None], 2, axis=1), rtol=0,
                               atol=LENGTH_TOL)


def _helix_levels(radius, depths, steps=48, rise=0.0):
    """A flat end mill's circle of chords at each depth, one path per level (m); with
    ``rise``, each a helix's turn going that much down (a level chord is a footprint
    prism, united in the plane, `machinesim.cutting.footprints`)."""
    angle = np.linspace(0.0, 2.0 * math.pi, steps + 1)
    return [np.array([pose((2e-3 + radius * math.cos(a), 2e-3 + radius * math.sin(a),
                            -depth - rise * a / (2.0 * math.pi))) for a in angle])
            for depth in depths]


def _recorded_containment(monkeypatch) -> list:
    """The list each call of `engine.contained_sweeps` appends its answer to."""
    import machinesim.cutting.engine as engine

    found, original = [], engine.contained_sweeps

    def record(*args):
        found.append(original(*args))
        return found[-1]

    monkeypatch.setattr(engine, "contained_sweeps", record)
    return found


def test_passes_repeated_deeper_are_dropped_and_the_part_is_the_same(monkeypatch):
    """A pass repeated over the same path deeper holds the shallower one: those sweeps are
    dropped (`contained_sweeps`) and the part is the one cut with all of them. (The turns
    of a helix, 50 um down a turn: level passes would be united in the plane instead, and
    are not tested.)"""
    import machinesim.cutting.engine as engine
    from machinesim.tools import FlatEndMill

    tool = FlatEndMill(0.5e-3, chord_tol=1e-6, height=5e-3)
    paths = _helix_levels(0.6e-3, [0.2e-3, 0.4e-3, 0.6e-3], rise=50e-6)
    stock = block(4e-3, 4e-3, 1e-3)
    found = _recorded_containment(monkeypatch)
    part, report = remove(stock, tool, paths, method="boolean")
    assert int(found[0].sum()) == 2 * 48  # the two upper levels, all inside the lowest
    monkeypatch.setattr(engine, "contained_sweeps",
                        lambda hulls, *rest: np.zeros(len(hulls), dtype=bool))
    every, every_report = remove(stock, tool, paths, method="boolean")
    assert report.n_sweeps_cut == every_report.n_sweeps_cut == 3 * 48
    assert report.removed_volume == pytest.approx(every_report.removed_volume, rel=VOLUME_REL)
    apart = (part.manifold - every.manifold).volume() + (every.manifold - part.manifold).volume()
    assert apart <= VOLUME_REL * report.removed_volume


def test_a_sweep_poking_out_of_another_is_kept(monkeypatch):
    """Containment is read off the vertices: a pass 1 nm outside the deeper one is cut."""
    from machinesim.tools import FlatEndMill

    tool = FlatEndMill(0.5e-3, chord_tol=1e-6, height=5e-3)
    deep = groove_x(2e-3, 0.4e-3)
    shallow = groove_x(2e-3 + 1e-9, 0.2e-3)
    stock = block(4e-3, 4e-3, 1e-3)
    found = _recorded_containment(monkeypatch)
    remove(stock, tool, [deep, shallow], method="boolean")
    assert not found[0].any()
    # at the same place the shallow pass lies inside the deep one: dropped
    remove(stock, tool, [deep, groove_x(2e-3, 0.2e-3)], method="boolean")
    assert found[1].tolist() == [False, True]


def test_a_ball_line_in_short_moves_is_cut_as_one_move(monkeypatch):
    # A level ball groove from x = 0.5 to 3.5 mm in 60 moves of 50 um, exactly in line:
    # joined into one sweep (`machinesim.cutting.collinear`), the part is the one-move
    # cut's, volume and removed volume to 1e-12; a turn of 1e-6 rad at one point keeps the
    # two lines apart, and their part stays the one of two moves (to 1e-12).
    from machinesim.cutting import collinear, engine

    chains = []

    def recorded(*args):
        head, solids = collinear.joined_ball_sweeps(*args)
        chains.append(None if head is None else len(np.unique(head)))
        return head, solids

    stock, tool = block(4e-3, 4e-3, 1e-3), BallEndMill(0.25e-3)
    xs = 0.5e-3 + 50e-6 * np.arange(61)
    short = np.array([pose((x, 2e-3, -40e-6)) for x in xs])
    one, report_one = remove(stock, tool, [short[[0, -1]]], method="boolean")
    monkeypatch.setattr(engine, "joined_ball_sweeps", recorded)
    many, report_many = remove(stock, tool, [short], method="boolean")
    bent = short.copy()
    bent[30:, 1, 3] += (bent[30:, 0, 3] - bent[30, 0, 3]) * 1e-6
    turned, _ = remove(stock, tool, [bent], method="boolean")
    assert report_many.n_sweeps_cut == 60
    # the first line is one chain; the bent line's moves, rounded, join where in line
    assert chains[0] == 1 and 2 <= chains[1] <= 31
    assert many.manifold.volume() == pytest.approx(one.manifold.volume(), rel=VOLUME_REL)
    assert report_many.removed_volume == pytest.approx(report_one.removed_volume,
                                                       rel=VOLUME_REL, abs=0.0)
    two, _ = remove(stock, tool, [bent[[0, 30, -1]]], method="boolean")
    assert turned.manifold.volume() == pytest.approx(two.manifold.volume(), rel=VOLUME_REL)


def test_windows_after_one_cut_in_tiles_are_cut():
    # Two windows, the first cut in a grid of tiles stitched at their walls: the second is
    # cut too (the stitched cell once took the name of the sweeps' solids, and the next
    # window read a sweep from it: TypeError 'Manifold' object is not subscriptable).
    # 90 deg V grooves d deep remove d^2 per length; two crossing remove 4 d^3 / 3 twice.
    from cutting_engine_helpers import groove_y

    depth = 6e-6
    stock = block(4e-3, 4e-3, 1e-3)
    paths = [groove_x(y, depth) for y in (0.5e-3, 1.2e-3, 1.5e-3, 1.8e-3, 2.5e-3, 3.5e-3)]
    paths += [groove_y(x, depth) for x in (1.2e-3, 1.6e-3, 3.2e-3)]
    windows = [(1e-3, 2e-3, 1e-3, 2e-3), (3e-3, 3.5e-3, 3e-3, 4e-3)]
    # window 1: three grooves along X and two along Y, 1 mm each, six crossings;
    # window 2: one along X 0.5 mm, one along Y 1 mm, one crossing
    removed = depth ** 2 * (3e-3 + 2e-3 + 0.5e-3 + 1e-3) - 7 * 4 * depth ** 3 / 3
    for per_tile in (1000, 2):
        part, report = remove(stock, VTool(math.pi / 2), paths, roi=windows,
                              method="boolean", sweeps_per_tile=per_tile)
        assert report.n_cells > 2 or per_tile == 1000
        assert report.removed_volume == pytest.approx(removed, rel=1e-9, abs=0.0)
        assert part.volume == pytest.approx(1.5e-3 * 1e-3 * 1e-3 - removed, rel=VOLUME_REL)
