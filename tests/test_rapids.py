"""The rapid check (`machinesim.cutting.rapids`) and its box grid (`cutting.boxgrid`), against
brute force: every box compared, and every earlier sweep subtracted."""

from __future__ import annotations

import manifold3d
import numpy as np
import pytest

from machinesim.cutting import cut, rapids
from machinesim.cutting.boxgrid import MAX_QUERY_CELLS, WIDE_CELLS, BoxGrid
from machinesim.nc import ProgramBuilder

MM, UM = 1e-3, 1e-6


def random_boxes(rng, n):
    """Small boxes over 10 mm, some of zero width, some long (wide) ones."""
    centre = rng.uniform(0.0, 10 * MM, (n, 3))
    half = rng.uniform(0.0, 0.2 * MM, (n, 3))
    half[rng.random(n) < 0.05] *= 40.0  # long moves across the part
    half[rng.random(n) < 0.05, :2] = 0.0  # a plunge of a zero-width box
    return centre - half, centre + half


def test_the_grid_lists_every_earlier_box_that_overlaps_or_holds_a_query():
    rng = np.random.default_rng(0)
    low, high = random_boxes(rng, 3000)
    grid = BoxGrid(low, high)
    assert len(grid.wide) and len(grid.wide) < 0.2 * len(low)
    for _ in range(400):
        k = int(rng.integers(0, len(low) + 1))
        q_low, q_high = random_boxes(rng, 1)
        every = np.flatnonzero(np.all(high[:k] >= q_low, axis=1)
                               & np.all(low[:k] <= q_high, axis=1))
        found = grid.candidates(q_low[0], q_high[0], k)
        assert np.all(np.diff(found) > 0) and np.all(found < k)
        assert set(every.tolist()) <= set(found.tolist())
        point = rng.uniform(0.0, 10 * MM, 3)
        holding = np.flatnonzero(np.all(low[:k] <= point, axis=1)
                                 & np.all(high[:k] >= point, axis=1))
        listed, wide = grid.at(point, k)
        assert set(holding.tolist()) <= set(listed.tolist()) | set(wide.tolist())


def test_a_query_in_a_field_of_small_boxes_reads_a_few_cells_not_every_box():
    # 2,500 boxes 0.1 mm wide on a 0.2 mm grid: the median box spans one cell, so a query
    # the size of one box reads at most four cells and the wide list
    x, y = np.meshgrid(np.arange(50) * 0.2 * MM, np.arange(50) * 0.2 * MM)
    centre = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    grid = BoxGrid(centre - 0.05 * MM, centre + 0.05 * MM)
    assert not len(grid.wide) and WIDE_CELLS < len(centre) and MAX_QUERY_CELLS < len(centre)
    found = grid.candidates(centre[1234] - 0.05 * MM, centre[1234] + 0.05 * MM, len(centre))
    assert 1234 in found and len(found) <= 4 * 4
    listed, _ = grid.at(centre[1234], len(centre))
    assert 1234 in listed and len(listed) <= 4


def brute_force_lines(stock, tool, poses, moves, reached, roi=None):
    """The rapids' lines by the definition alone: what each rapid that reached the stock met,
    less the union of every earlier sweep that reached it, holds material."""
    shape = rapids._Thick(tool)
    material = stock.manifold
    reached = np.sort(reached)
    found = []
    for sweep in reached[moves.sweep_rapid[reached]]:
        a = moves.sweep_start[sweep]
        solid = shape.solid(poses[a], poses[a + 1])
        if solid is None:
            continue
        earlier = [s for s in (shape.solid(poses[moves.sweep_start[k]],
                                           poses[moves.sweep_start[k] + 1])
                               for k in reached[reached < sweep]) if s is not None]
        hit = material ^ solid
        if earlier:
            hit = hit - manifold3d.Manifold.batch_boolean(earlier, manifold3d.OpType.Add)
        if rapids._material_left(hit):
            found.append(int(moves.sweep_line[sweep]))
    return tuple(dict.fromkeys(found))


def listed_both_ways(monkeypatch, program, tool: str, stock: str):
    """The rapids that cut of ``program`` cut on grooving_4axis: as the check lists them, as
    `brute_force_lines` (the definition) lists them, and as the report gives them."""
    seen = []
    real = rapids.rapids_that_cut

    def both(*args):
        seen.append((real(*args), brute_force_lines(*args)))
        return seen[-1][0]

    monkeypatch.setattr("machinesim.cutting.program.rapids_that_cut", both)
    _, report = cut(program, "grooving_4axis", tool=tool, stock=stock)
    assert len(seen) == 1
    return (*seen[0], report.rapids_that_cut)


def test_the_rapids_listed_are_those_brute_force_finds_in_a_random_program(monkeypatch):
    # short cuts 20 um deep at random places on a 5 mm block, joined by rapids: down to
    # 10 um above the top, or to a random depth (into the cut just made, or below it: a
    # crash), back up, and now and then along a random line 5 um deep (through fresh stock
    # or through cuts)
    rng = np.random.default_rng(7)
    b = ProgramBuilder(1).rapid(X=0.0, Y=0.0, Z=0.5 * MM)
    for _ in range(14):
        x, y = rng.uniform(0.5 * MM, 4.5 * MM, 2)
        b.rapid(X=x, Y=y).rapid(Z=10 * UM)
        b.linear(Z=-20 * UM, feed_mm_per_min=100.0)
        b.linear(X=x + rng.uniform(-0.4, 0.4) * MM, Y=y + rng.uniform(-0.4, 0.4) * MM)
        b.rapid(Z=-rng.uniform(0.0, 30.0) * UM)
        if rng.random() < 0.3:
            b.rapid(X=rng.uniform(0.5, 4.5) * MM, Y=rng.uniform(0.5, 4.5) * MM, Z=-5 * UM)
        b.rapid(Z=0.5 * MM)
    fast, slow, listed = listed_both_ways(monkeypatch, b.build(), "ball:0.1", "block:5x5x1")
    assert fast == slow == listed
    assert 3 <= len(fast) < 14 * 2  # some crash, some do not: the comparison means something


@pytest.mark.parametrize("holders", [0, 1, 16])
def test_the_holders_found_are_the_latest_that_hold_as_a_scan_of_every_box_finds(
        monkeypatch, holders):
    rng = np.random.default_rng(holders)
    low, high = random_boxes(rng, 2000)
    earlier = object.__new__(rapids._Earlier)
    earlier.low, earlier.high = low, high
    earlier.reached = np.arange(len(low)) * 2 + 1
    earlier.grid = BoxGrid(low, high)
    monkeypatch.setattr(rapids, "RAPID_HOLDERS", holders)
    counts = []
    for _ in range(300):
        k = int(rng.integers(0, len(low)))
        q_low, q_high = random_boxes(rng, 1)
        q_low, q_high = q_low[0] / 4, q_high[0] / 4  # small queries in a corner: many hold
        every = np.flatnonzero(np.all(low[:k] <= q_low, axis=1)
                               & np.all(high[:k] >= q_high, axis=1))[::-1][:holders]
        found = earlier._holding(int(earlier.reached[k]), q_low, q_high)
        assert found.tolist() == every.tolist()
        counts.append(len(every))
        # bounds the wrong way round (a box thinner than twice the tolerance): those that
        # reach below the first and above the second, which need not hold their middle
        every = np.flatnonzero(np.all(low[:k] <= q_high, axis=1)
                               & np.all(high[:k] >= q_low, axis=1))[::-1][:holders]
        found = earlier._holding(int(earlier.reached[k]), q_high, q_low)
        assert found.tolist() == every.tolist()
    assert holders == 0 or max(counts) == holders


@pytest.mark.parametrize("few", [False, True])
def test_the_rapids_listed_in_a_random_plunge_field_are_those_brute_force_finds(
        monkeypatch, few):
    # plunges 20 um deep with a flat end mill 0.1 mm across, at random places 50 um apart
    # or less, each begun by a rapid down to a random depth: above the top, into the cuts
    # already made around it (what they took, taken away one sweep at a time,
    # `_Earlier.subtract`) or below them (a crash). With ``few``, the recent sweeps taken
    # first and the count past which sweeps are sorted by meeting are made small, so the
    # rapids go through every branch
    if few:
        monkeypatch.setattr(rapids, "RAPID_RECENT_SWEEPS", 2)
        monkeypatch.setattr(rapids, "RAPID_EARLIER_UNION", 3)
    rng = np.random.default_rng(11)
    b = ProgramBuilder(1).rapid(X=1.0 * MM, Y=1.0 * MM, Z=50 * UM)
    for _ in range(24):
        x, y = rng.uniform(1.0 * MM, 1.15 * MM, 2)
        b.rapid(X=x, Y=y).rapid(Z=rng.choice([10.0, -15.0, -19.0, -25.0]) * UM)
        b.linear(Z=-20 * UM, feed_mm_per_min=100.0).rapid(Z=50 * UM)
    fast, slow, listed = listed_both_ways(monkeypatch, b.build(), "flat:0.05", "block:3x3x1")
    assert fast == slow == listed
    assert 2 <= len(fast) <= 20  # some crash, some do not
