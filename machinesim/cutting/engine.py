"""Exact material removal: stock minus the convex sweeps of a tool along pose sequences.

A sweep is the convex hull of the tool at two consecutive poses of a path, built exactly in
float64 (`machinesim.cutting.sweeps`: the prism of a profile for a translation, Qhull for a
solid or a move that rotates; never manifold3d's QuickHull, which drops points near flat
sets and mis-builds hulls of coplanar rings). For a move at fixed orientation this is the
exact volume swept by the tool; a move that rotates must arrive already split into sub-steps
whose chord error is within tolerance (`rotary_substeps`).

Straight grooves right across a block, in at most two directions in XY (along the block's
axes or slanted), are first offered to `machinesim.cutting.relief`, which meshes their height
field exactly without any boolean; everything else is subtracted here. Speed comes from
never touching the part mesh once per sweep:

1. Tool points for all poses are transformed at once (numpy).
2. Each sweep is clipped to the half-space a hair above the top of the stock
   (`CLIP_MARGIN_REL`; a translated profile at that height plus its Z travel, `_prism`). The
   part is unchanged (nothing above the stock is material), but tall tool bodies no longer
   overlap their neighbours, so parallel sweeps stay (almost) disjoint and their union is
   nearly free.
3. Sweeps are grouped by their direction of travel in XY. Parallel sweeps are unioned in
   one `batch_boolean` when they lie side by side, and in runs of a few overlapping pairs
   when they overlap each other (passes stacked down a face: `tiling.union_runs`), since
   a union's cost grows with its overlapping pairs; groups that cross each other are
   subtracted one after the other, each evaluated before the next, because the union of
   crossing sweeps costs as much as cutting them (and manifold3d, left lazy, would form
   exactly that union). A run of a tool that turns is checked for material manifold3d
   left inside its sweeps, and cut again one sweep at a time where there is any
   (`machinesim.cutting.run_check`). An upright flat end mill's level passes are taken
   first: those on one floor are one prism, over the union of their footprints in the plane
   (`machinesim.cutting.footprints`); a ball end mill's level moves exactly in line are
   one sweep of the joined move (`machinesim.cutting.collinear`).
4. The region is split into cells (ROI windows, and a grid of tiles inside each): a tile is
   cut with only the sweeps that touch it, which keeps manifold3d's faster-than-linear
   boolean cost down, and the tiles of a cell are joined by `stitch` (a mesh merge along
   the walls, with a boolean union as the fallback), the cells by one union.

An end mill that stands tilted in the workpiece frame and does not turn (a workpiece set
with a tilt, a 3-axis program) is cut in its own frame (`machinesim.cutting.frame`): there its
sweeps' shared faces, an end mill's floor above all, coincide exactly as on an upright
machine, where in the workpiece frame they coincide only to round-off and break into slivers.

Subtraction commutes, so the part does not depend on how the sweeps are batched or ordered:
removing a set of sweeps at once or one by one gives the same solid (to manifold3d's
round-off, tested on paper 002's groove programs). Where sweeps' faces coincide exactly,
round-off can keep a sheet of stock under a picometre thick between them; such sheets are
cut away after the last union (`machinesim.cutting.sheets`). The removed volume is
integrated over the cut itself (`removed_volume`, `machinesim.cutting.cut_volume`), not
taken as the difference of two large volumes.
"""

from __future__ import annotations

import functools
import inspect
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import manifold3d
import numpy as np
from manifold3d import OpType

from machinesim.cutting.collinear import joined_ball_sweeps
from machinesim.cutting.containment import CONTAINED_REL, contained_sweeps
from machinesim.cutting.cut_volume import (  # noqa: F401  (re-exported: the names engine had)
    FACE_KEY,
    FACE_ROUND_REL,
    removed_volume,
)
from machinesim.cutting.footprints import level_prisms, united_in_plane
from machinesim.cutting.frame import into_frame, out_of_frame, tool_frame
from machinesim.cutting.holder import judge_holder
from machinesim.cutting.holder_allowance import turned_lent
from machinesim.cutting.poses import (  # noqa: F401  (re-exported: the names engine had)
    FARTHEST_M,
    _check_paths,
    _check_turns,
    rotary_substeps,
)
from machinesim.cutting.relief import cut_reliefs
from machinesim.cutting.roi import roi_cells
from machinesim.cutting.run_check import check_runs_value, checked_sweeps, subtract_run
from machinesim.cutting.sheets import SheetReport, remove_sheets
from machinesim.cutting.sideways import dragged
from machinesim.cutting.stitch import exact_box, snapped_union, stitch
from machinesim.cutting.sweepset import SweepSet
from machinesim.cutting.tiling import (
    SWEEPS_PER_TILE,
    grid_tiles,
    members_in,
    overlapping,
    tile_box,
    union_runs,
)
from machinesim.exceptions import InputError, brief
from machinesim.metrology._arrays import as_number
from machinesim.tolerances import CLIP_MARGIN_REL, PLANAR_TRAVEL_REL
from machinesim.tools import Tool
from machinesim.workpiece import Part

#: Sweeps travelling within this angle (rad) in XY are cut together as one parallel group.
DIRECTION_BIN_RAD = math.radians(5.0)
#: A cut is empty when it removes at most this fraction of the volume its sweeps could
#: remove (the clipped sweeps' own volume), not of the stock's: the removed volume is
#: integrated over the cut faces, so its round-off is ~1e-15 of the cut's size, and a cut
#: that removes nothing integrates to exactly 0. A 10 nm deep groove on a 100 mm block is
#: 1e-2 of its clipped sweep, ten orders above this.
EMPTY_SWEPT_REL = 1e-12


@dataclass(frozen=True)
class EngineReport:
    """What a call to `remove` did.

    Attributes
    ----------
    removed_volume : float
        Volume removed from the stock (clipped to the ROI), m^3, integrated over the cut
        (exact to float64 round-off of the cut's own size, whatever the stock's).
    n_sweeps : int
        Sweeps in the input (consecutive pose pairs over all paths; one for a path of one
        pose).
    n_sweeps_cut : int
        Sweeps that reach the stock region and were subtracted.
    n_degenerate : int
        Sweeps with no volume (a zero-thickness profile moved within its own plane or not
        at all); they remove nothing.
    empty_cut : bool
        True when nothing was removed, judged against ``swept_volume`` (`EMPTY_SWEPT_REL`):
        flagged, never silent.
    sideways : tuple of int
        Indices (over all paths, in order) of sweeps that reach the stock and drag a
        non-rotational tool sideways (`SIDEWAYS_REL`).
    n_cells : int
        Cells (ROI windows times tiles) the region was cut in; 1 per window by relief.
    method : str
        "relief" when the cut was meshed as a height field (straight grooves across a block
        in at most two XY directions, `machinesim.cutting.relief`), "boolean" when the
        sweeps were subtracted.
    elapsed_s : float
        Wall time of the call, s.
    swept_volume : float
        Volume of the sweeps that reach the stock, clipped just above it, m^3 (the relief
        engine: the profiles' area below the top times the groove lengths).
    holder_contact : tuple of int
        Indices (over all paths) of sweeps in which the top of the tool's body, where its
        holder begins (`tools`), comes below the top of the stock within its box: the
        holder, not modelled, may touch the part. With ``on_holder_contact``, only those
        whose holder's room holds material (none when it was called: it refuses).
    reached : ndarray of int
        Indices (over all paths) of the sweeps that reach the stock region (those cut, and
        those with no volume); `machinesim.cutting.cut` checks its rapids among them.
    sheets : SheetReport
        Sheets of stock under `tolerances.SHEET_M` thick that round-off left between
        sweeps whose faces coincide, and which were cut away (`machinesim.cutting.sheets`).
    """

    removed_volume: float
    n_sweeps: int
    n_sweeps_cut: int
    n_degenerate: int
    empty_cut: bool
    sideways: tuple[int, ...]
    n_cells: int
    method: str
    elapsed_s: float
    swept_volume: float = 0.0
    holder_contact: tuple[int, ...] = ()
    reached: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    sheets: SheetReport = SheetReport()




def _direction_keys(direction: np.ndarray) -> np.ndarray:
    """Group key per sweep: its XY travel direction modulo pi, in bins; -1 for no XY travel."""
    planar = np.hypot(direction[:, 0], direction[:, 1])
    angle = np.mod(np.arctan2(direction[:, 1], direction[:, 0]), math.pi)
    bins = int(round(math.pi / DIRECTION_BIN_RAD))
    key = np.mod(np.rint(angle / DIRECTION_BIN_RAD).astype(np.int64), bins)
    return np.where(planar > PLANAR_TRAVEL_REL * np.linalg.norm(direction, axis=1), key, -1)


def _holder_sweeps(sweeps: SweepSet, tool, paths, z_high: float,
                   holder_stock: Part | None) -> SweepSet:
    """The sweeps the holder is judged with: ``sweeps``, or, when ``holder_stock`` rises
    above the stock they are clipped to (a part clipped to windows cut down to below the
    top elsewhere), the same clipped over it, so that they cut all its material."""
    if holder_stock is None:
        return sweeps
    bounds = holder_stock.bounds
    top = bounds[1, 2] + CLIP_MARGIN_REL * (float(np.abs(bounds).max()) or 1.0)
    return sweeps if top <= z_high else SweepSet(tool, paths, top)


def _building(progress):
    """``progress`` told the stage "building", when it takes a ``stage`` keyword, else None:
    a callable of (done, total) alone, as `remove` was documented to call, is left as it
    was (its counts would run twice, from 0 to the sweeps and again)."""
    if progress is None:
        return None
    try:
        inspect.signature(progress).bind(0, 0, stage="building")
    except (TypeError, ValueError):
        return None
    return functools.partial(progress, stage="building")


def _holder_tolerance(value, paths: list) -> float | np.ndarray:
    """``value`` (`remove`'s ``holder_tolerance``) as a length >= 0 (m), or as one per sweep
    of ``paths`` (a path of one pose is one sweep, a path of none none), or an InputError
    naming it."""
    if np.ndim(value) == 0 or isinstance(value, str | bytes):
        return as_number(value, "holder_tolerance", sign=">= 0")
    count = sum(max(len(poses) - 1, 1) for poses in paths if len(poses))
    try:
        each = np.asarray(value)
    except (TypeError, ValueError):  # ragged
        each = None
    if each is not None and each.dtype.kind in "iuf":  # not "1e-6", not True
        each = each.astype(np.float64)
    else:
        each = None
    if each is None or each.shape != (count,) or not (np.isfinite(each) & (each >= 0.0)).all():
        raise InputError(f"Expected holder_tolerance as a length >= 0 (m) or {count} of them, "
                         f"one per sweep of paths, got {brief(repr(value))}",
                         key="holder_tolerance")
    return each


def remove(
    stock: Part,
    tool,
    paths: Sequence,
    *,
    roi=None,
    progress: Callable[[int, int], None] | None = None,
    sweeps_per_tile: int = SWEEPS_PER_TILE,
    method: str = "auto",
    sheets: bool = True,
    on_holder_contact: Callable[[tuple[int, ...]], None] | None = None,
    holder_stock: Part | None = None,
    holder_tolerance=0.0,
    holder_lent=None,
    check_runs: str = "turning",
) -> tuple[Part, EngineReport]:
    """Cut ``stock`` with ``tool`` moved along ``paths``.

    Parameters
    ----------
    stock : Part
        The stock, workpiece frame, m.
    tool : VTool or RoundNoseTool or BallEndMill
        The tool (machinesim.tools), in its tool_tip frame.
    paths : sequence of array-like, each shape (N_i, 4, 4)
        wMt poses of the tool_tip frame in the workpiece frame (m). Consecutive poses of a
        path form sweeps; a path of one pose is one sweep, the tool standing there (its
        own volume, as that pose given twice); nothing joins one path to the next.
    roi : array-like, shape (n, 4), optional
        Windows (xmin, xmax, ymin, ymax), m. Only sweeps touching a window are cut and the
        result is the stock clipped to the windows.
    progress : callable(done, total), optional
        Called as tiles are cut, in sweeps (`EngineReport.n_sweeps_cut` in all), each
        counted once, when the first tile it reaches is cut. A callable that also takes a
        keyword ``stage`` is told the building of the sweeps before that, as
        ``progress(done, total, stage="building")`` over all `EngineReport.n_sweeps`: for a
        ball end mill the longer wait before the first tile (`SweepSet.hulls`).
    sweeps_per_tile : int
        Cells are split into a grid of tiles until each has at most this many sweeps (or
        splitting stops paying, see `SPLIT_GAIN`); a huge value disables tiling.
    method : {"auto", "boolean"}
        "auto" meshes the cut as a height field when every sweep that reaches the stock is
        a straight level groove right across a block (or a part cut that way before), in at
        most two directions in XY, `machinesim.cutting.relief`, and subtracts sweeps
        otherwise; "boolean" always subtracts. Both are exact; the height field is 10-100
        times faster on groove patterns.
    sheets : bool
        Cut away the sheets under `tolerances.SHEET_M` thick that round-off leaves where
        sweeps' faces coincide (`machinesim.cutting.sheets`), after the last union. A caller
        that cuts one part in several calls (`machinesim.cutting.cut`, `cut_turned`) does
        it once, at the end: a sheet one call leaves, the next may cut away.
    on_holder_contact : callable(sweeps), optional
        Called before anything is cut with the sweeps in which the holder meets the stock,
        when there are any: those whose body top comes below the stock's top within its box
        (`holder.holder_contact`) and whose holder's room then holds material that the
        earlier sweeps of ``paths`` left (`holder.holder_in_material`). A caller that
        refuses such a cut raises there and wastes no cutting. The holder is judged over
        the whole stock, windows or not (`holder.judge_holder`).
    holder_stock : Part, optional
        The material the holder is judged against, when ``stock`` is not all of it: a
        caller that cuts a part already clipped to windows gives the part as it is outside
        them (`machinesim.cutting.cut`'s later tools). Default: ``stock``.
    holder_tolerance : float or array_like, shape (n_sweeps,)
        How far the holder may enter the material, m, one value or one per sweep (in the
        order of ``paths``; a path of one pose is one sweep): one chord of the sweep's move,
        or of the chorded moves that cut the walls about its holder before
        (`holder.holder_in_material`, `machinesim.cutting.holder_allowance`). Default 0.
    holder_lent : dict, optional
        Where a sweep whose ``holder_tolerance`` is borrowed from chorded sweeps may use it
        (`holder_allowance.Lent`, workpiece frame): inside their boxes; elsewhere its own.
    check_runs : {"turning", "all", "off"}
        Which runs of step 3 have their subtraction checked for material left inside their
        sweeps, subtracted again one sweep at a time where there is, and refused with
        `SubtractionError` where that leaves it too (`machinesim.cutting.run_check`): runs
        with a sweep that turns the tool (the default; where manifold3d was seen to leave
        such material, a rotary turn), every run, or none. Checking every run costs a
        plain milling cut 16-26 % more CPU (docs/cutting.md).

    Returns
    -------
    part : Part
        The machined part (clipped to ``roi`` if given).
    report : EngineReport
    """
    start = time.perf_counter()
    if not isinstance(tool, Tool):  # a spec or None read .rotational: an AttributeError
        raise InputError(f"Expected tool as a tool object (machinesim.tools: VTool, "
                         f"RoundNoseTool, BallEndMill, FlatEndMill), got "
                         f"{type(tool).__name__} {brief(repr(tool))}; a spec such as 'v:90' "
                         "is made one by machinesim.tool_specs.tool_from_spec", key="tool")
    if not isinstance(stock, Part):  # None read .bounds: an AttributeError
        raise InputError(f"Expected stock as a machinesim.workpiece.Part, got "
                         f"{type(stock).__name__} {brief(repr(stock))}; a spec such as "
                         "'block:10x10x2' is made one by machinesim.workpiece.stock_from_spec",
                         key="stock")
    paths = _check_paths(paths)
    holder_tolerance = _holder_tolerance(holder_tolerance, paths)
    # A path of one pose is the tool standing there, and the volume it sweeps, the hull of
    # that pose and itself, is the tool: one sweep, as the same pose given twice (it had
    # formed no sweep and was passed over without a word).
    paths = [np.concatenate([poses, poses]) if len(poses) == 1 else poses for poses in paths]
    _check_turns(paths, bool(tool.rotational))
    if method not in ("auto", "boolean"):
        raise InputError(f"method must be 'auto' or 'boolean', got {method!r}", key="method")
    check_runs = check_runs_value(check_runs)
    bounds = stock.bounds
    scale = float(np.abs(bounds).max()) or 1.0
    margin = CLIP_MARGIN_REL * scale
    if roi is None:
        cells = [(bounds[0, 0] - margin, bounds[1, 0] + margin,
                  bounds[0, 1] - margin, bounds[1, 1] + margin)]
    else:
        cells = roi_cells(roi, bounds)
    cell_array = np.array(cells).reshape(-1, 4)
    z_low, z_high = bounds[0, 2] - margin, bounds[1, 2] + margin

    def touches(low: np.ndarray, high: np.ndarray) -> np.ndarray:
        inside = (low[:, 2] <= z_high) & (high[:, 2] >= z_low)
        hit = ((low[:, None, 0] <= cell_array[None, :, 1] + margin)
               & (high[:, None, 0] >= cell_array[None, :, 0] - margin)
               & (low[:, None, 1] <= cell_array[None, :, 3] + margin)
               & (high[:, None, 1] >= cell_array[None, :, 2] - margin))
        return inside & hit.any(axis=1)

    sweeps = SweepSet(tool, paths, z_high)
    frame = tool_frame(sweeps.poses, tool) if sweeps.count else None
    if frame is not None and (roi is None or cells):
        # A tilted end mill: cut, and its holder judged, where it stands upright, so that
        # its coinciding faces coincide (a height field needs a level block: none here).
        # The stock is cut down to the windows first; the holder is judged over all of it.
        framed, framed_paths = into_frame(stock, paths, frame, None if roi is None else cells)
        framed_holder = None if roi is None and holder_stock is None else into_frame(
            stock if holder_stock is None else holder_stock, [], frame)[0]
        part, report = remove(framed, tool, framed_paths, progress=progress,
                              sweeps_per_tile=sweeps_per_tile, method="boolean", sheets=sheets,
                              on_holder_contact=on_holder_contact, holder_stock=framed_holder,
                              holder_tolerance=holder_tolerance,
                              holder_lent=turned_lent(holder_lent, frame.T),
                              check_runs=check_runs)
        return out_of_frame(part, frame), replace(report,
                                                  elapsed_s=time.perf_counter() - start)
    holder = judge_holder(_holder_sweeps(sweeps, tool, paths, z_high, holder_stock),
                          stock if holder_stock is None else holder_stock, on_holder_contact,
                          holder_tolerance, holder_lent)
    if method == "auto" and sweeps.count:
        relief = cut_reliefs(stock, sweeps.vertices, sweeps.poses, sweeps.pairs,
                             None if roi is None else cells, sweeps.pose_bounds)
        if relief is not None:
            if progress is not None:
                progress(0, relief.n_sweeps_cut)
                progress(relief.n_sweeps_cut, relief.n_sweeps_cut)
            sideways = []
            if not sweeps.rotational:
                first = sweeps.pairs[relief.reached]
                move = sweeps.poses[first + 1, :3, 3] - sweeps.poses[first, :3, 3]
                drag = dragged(sweeps.poses[first, :3, :3], move)
                sideways = relief.reached[drag].tolist()
            report = EngineReport(
                removed_volume=relief.removed_volume,
                n_sweeps=sweeps.count,
                n_sweeps_cut=relief.n_sweeps_cut,
                n_degenerate=relief.n_degenerate,
                empty_cut=not relief.removed_volume > EMPTY_SWEPT_REL * relief.swept_volume,
                sideways=tuple(sideways),
                n_cells=len(relief.part.reliefs),
                method="relief",
                elapsed_s=time.perf_counter() - start,
                swept_volume=relief.swept_volume,
                holder_contact=holder,
                reached=relief.reached,
            )
            return relief.part, report
    (hulls, lower, upper, direction, n_degenerate, sideways, swept, reached, footprints,
     owners) = sweeps.hulls(touches, progress=_building(progress))
    keys = _direction_keys(direction)

    def planned(cut: np.ndarray):
        tiled = []
        for cell in cells:
            members = members_in(lower, upper, cell, margin)
            tiled.append((cell, grid_tiles(cell, members[cut[members]], lower, upper, margin,
                                           sweeps_per_tile)))
        return tiled

    plan = planned(np.ones(len(hulls), dtype=bool))
    # Sweeps inside another sweep remove nothing more: drop them, then tile what is left.
    # Level passes of a floor with enough of them are left out: their footprints are united
    # in the plane, where one inside another costs nothing, and testing them would make
    # each one's solid (`DeferredSolid`).
    level = united_in_plane(footprints)
    inside = contained_sweeps(hulls, lower, upper,
                              [(box, members[~level[members]])
                               for _, tiles in plan for box, members in tiles],
                              CONTAINED_REL * scale)
    if inside.any():
        plan = planned(~inside)
    # progress in sweeps, each counted once (at its first tile), as the report counts them: a
    # sweep across ten tiles had counted ten times, 96,376 "sweeps" of a cut of 36,902;
    # those inside another are done from the start
    counted = inside.copy()
    total = len(hulls)
    done = int(np.count_nonzero(counted))
    if progress is not None:
        progress(done, total)

    # Ball sweeps along one straight line are cut as the one sweep of the line they make.
    head, joined = joined_ball_sweeps(sweeps, hulls, owners)
    checked = checked_sweeps(check_runs, sweeps, owners)
    base = stock.manifold
    top = float(bounds[1, 2])
    stock_pieces, cell_parts = [], []
    removed = 0.0
    for cell, tiles in plan:
        pieces = []
        for (xmin, xmax, ymin, ymax), members in tiles:
            if roi is None and len(tiles) == 1:
                piece = base
            else:
                piece = base ^ exact_box(*tile_box((xmin, xmax, ymin, ymax), cell, roi is None,
                                                    bounds, scale))
            stock_pieces.append(piece)
            uncut = piece
            prisms, rest = level_prisms(members, footprints, sweeps.run_id)
            if head is not None:
                rest = np.unique(head[rest])
            for prism in prisms:  # level passes, each floor's united in the plane
                piece = piece - prism
                piece.num_tri()
            for key in np.unique(keys[rest]):
                for run in union_runs(rest[keys[rest] == key], lower, upper):
                    piece = subtract_run(piece, [joined[i] for i in run],
                                         [owners[i] for i in run], checked[run].any(),
                                         pieces=[joined.pieces(i) for i in run])
            if len(members):
                removed += removed_volume(uncut, piece, sweeps.run_id, top)
            pieces.append(piece)
            new = members[~counted[members]]
            counted[new] = True
            done += len(new)
            if progress is not None:
                progress(done, total)
        if len(pieces) > 1:
            boxes = [box for box, _ in tiles]
            stitched = stitch(pieces, boxes, cell, scale)
            # the walls put on their planes first: else the union leaves a crack of no width
            cell_parts.append(stitched if stitched is not None
                              else snapped_union(pieces, boxes, cell, scale))
        else:
            cell_parts.append(manifold3d.Manifold.batch_boolean(pieces, OpType.Add))
    result = (manifold3d.Manifold.batch_boolean(cell_parts, OpType.Add) if cell_parts
              else manifold3d.Manifold())
    if overlapping(cell_array):
        # Windows that overlap cut their common part twice: count it once, by difference.
        stock_volume = manifold3d.Manifold.batch_boolean(stock_pieces, OpType.Add).volume()
        removed = stock_volume - result.volume()
    sheets_found = SheetReport()
    if sheets:
        result, sheets_found = remove_sheets(result)
        removed += sheets_found.volume
    report = EngineReport(
        removed_volume=removed,
        n_sweeps=sweeps.count,
        n_sweeps_cut=len(hulls),
        n_degenerate=n_degenerate,
        empty_cut=not removed > EMPTY_SWEPT_REL * swept,
        sideways=tuple(int(i) for i in sideways),
        n_cells=sum(len(tiles) for _, tiles in plan),
        method="boolean",
        elapsed_s=time.perf_counter() - start,
        swept_volume=swept,
        holder_contact=holder,
        reached=np.array(reached, dtype=np.int64),
        sheets=sheets_found,
    )
    return Part(result), report
