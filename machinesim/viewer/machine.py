"""A machine in the browser: its URDF visuals moving along an NC program, with errors.

The machine is drawn by Pinocchio's `MeshcatVisualizer` from the visual geometry of the
error-augmented URDF, so the bodies move as the erroneous kinematics says. Along a program
the scene shows the tool, the nominal tool path (machine without errors) and the actual one
(with errors) in the workpiece frame, and the part as it is cut: the engine cuts the stock
block by block and each stage is switched on while the next block runs. Beside the machine
stands an enlarged copy of the finished part, coloured by its deviation from the part the
nominal machine cuts.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from machinesim import motion
from machinesim.cutting import cut, remove
from machinesim.cutting.report import arc_chord_note, nothing_left_note
from machinesim.errors import as_error_model
from machinesim.exceptions import InputError
from machinesim.machines import travel_text
from machinesim.motion.faces import ProfileEdges
from machinesim.tool_specs import tool_from_spec
from machinesim.tools import check_path_chord, flat_face_radius, path_chord_tolerance
from machinesim.viewer.maps import legend_for
from machinesim.viewer.meshes import DISPLAY_TRIANGLES, decimate, tool_mesh
from machinesim.viewer.scene import Scene, transform_tracks, visibility_track
from machinesim.viewer.views import PART_COLOUR, add_part, frame_scene
from machinesim.viewer.visuals import machine_visuals
from machinesim.workpiece import stock_from_spec

#: Longest animation (s) before the program's time is compressed to fit: a minute-long
#: program plays in 20 s, a 5 s program in real time.
DURATION_S = 20.0
#: Key frames per second of animation: enough for smooth rotary moves between keys (three.js
#: interpolates positions linearly and rotations by slerp between them).
KEY_RATE = 20.0
#: Block starts and ends become key frames (so a short block is not skipped) for programs of
#: up to this many blocks; longer programs use the uniform rate only, to bound the page size.
MAX_BLOCK_KEYS = 2000
#: Most part stages (meshes) in a scene: up to this many feed blocks, one stage per block;
#: beyond, consecutive blocks share a stage, so the page stays a few MB.
MAX_STAGES = 60
#: Display budget of each stage mesh (triangles).
STAGE_TRIANGLES = 20_000
#: Most points of a drawn tool path; longer paths are thinned (display only).
PATH_POINTS = 20_000
#: The finished part's copy beside the machine is this fraction of the machine's size.
INSPECTION_SIZE = 0.3
#: Colours: nominal path cyan, actual path red, tool bright white.
NOMINAL_COLOUR, ACTUAL_COLOUR, TOOL_COLOUR = 0x00E5FF, 0xFF3030, 0xF0F0FF


def machine_scene(machine, program=None, *, tool="v:90", stock="block:10x10x2", errors=None,
                  start=None, duration_s: float = DURATION_S, max_stages: int = MAX_STAGES,
                  max_triangles: int = DISPLAY_TRIANGLES,
                  chord_tolerance: float | None = None, progress=None) -> Scene:
    """A scene of ``machine``, and of it running ``program`` if one is given.

    Parameters
    ----------
    machine : machinesim.Machine or str
    program : machinesim.nc.Program, optional
    tool : str or tool
        Tool spec (``"v:90"``, ``"nose:2.0:90"``, ``"ball:2.0"``, mm and deg) or object.
    stock : str or Part
        Stock spec (``"block:10x10x2"``, mm) or Part, workpiece frame.
    errors : ErrorModel, optional
        The machine's errors; None for the nominal machine.
    start : array-like, shape (n_axes,), optional
        Axis values before the first block (m, rad); default the machine's home
        (`Machine.home`), where ``machinesim cut`` starts a program.
    duration_s : float
        Longest animation, s: a longer program plays faster.
    max_stages : int
        Most part stages; a program with more feed blocks groups them.
    max_triangles : int
        Display budget of the deviation map.
    chord_tolerance : float, optional
        Rotary moves are split within this distance of their path (m), as `cut` splits
        them; default `machinesim.tools.path_chord_tolerance` of ``tool``.
    progress : callable, optional
        ``progress(done, total)`` after each cut of a program's view: its part stages, then
        the part on the machine without errors (``total`` = stages + 1). A long program's
        view cuts it about twice (a spiral of 8,002 moves: 14.1 s of CPU against 3.8 s for
        ``machinesim cut``), and ``machinesim view`` prints these as lines.
    """
    from machinesim.machines import Machine, load_machine

    if chord_tolerance is not None:  # as `cut` and --chord-nm take it, before any work
        chord_tolerance = check_path_chord(chord_tolerance)
    machine = machine if isinstance(machine, Machine) else load_machine(machine)
    machine.check_errors(errors)
    scene = Scene(f"{machine.name} ({''.join(machine.axes)})")
    model = machine.model
    geometry = machine_visuals(machine, scene)
    visualizer = MeshcatVisualizer(model, visual_model=geometry)
    visualizer.initViewer(viewer=scene.vis)
    visualizer.loadViewerModel(rootNodeName="machine")
    binding = machine.binding(errors)
    q0 = machine.home if start is None else np.asarray(start, dtype=np.float64)
    visualizer.display(machine.kin.full_q(q0, binding))
    lo, hi = _machine_box(visualizer)
    # the rotary axes' travel too, as `machinesim machines` gives it: "A rotary" had hidden
    # a trunnion's -110..110 deg tilt
    scene.notes.append("travel: " + travel_text(machine))
    if program is not None:
        lo, hi = _run(scene, visualizer, machine, program, tool, stock, errors, q0, lo, hi,
                      duration_s, max_stages, max_triangles, chord_tolerance, progress)
    if lo is None:  # no visual bodies and no program: the origin
        lo = hi = np.zeros(3)
    frame_scene(scene, lo, hi)
    return scene


def _run(scene, visualizer, machine, program, tool, stock, errors, q0, lo, hi, duration_s,
         max_stages, max_triangles, chord_tolerance, progress=None):
    """Animate the program; return the box (m) of everything drawn."""
    if duration_s <= 0.0 or max_stages < 1:
        raise InputError(f"duration_s and max_stages must be positive, got {duration_s} and "
                         f"{max_stages}")
    from machinesim.cutting.refusals import _refuse_turning

    # a turning program is refused as cut refuses it, before any stage is cut: the refusal
    # had come from the part without errors, cut last (a 4-line turn on sts_lathe, after
    # 384 s of stages)
    _refuse_turning(program, machine, q0)
    tool = tool_from_spec(tool) if isinstance(tool, str) else tool
    stock = stock_from_spec(stock) if isinstance(stock, str) else stock
    # the stock where it stands: a machine without visual bodies has only it to frame (its
    # box was a point, and the enlarged part beside it came out of size zero)
    lo, hi = _with_stock(visualizer, machine, errors, q0, stock, lo, hi)
    if chord_tolerance is None:
        chord_tolerance = path_chord_tolerance([tool])
    # sub-steps as cut() takes them (a flat end mill's tilted face, a planar profile tilting
    # while it moves: `motion.faces`), so that the last stage is the part cut() gives and
    # its colours compare like with like
    trajectory = motion.plan(program, machine, errors, start=q0, tool_points=tool.vertices(),
                             chord_tolerance=chord_tolerance,
                             face_radius=flat_face_radius([tool]),
                             profile=ProfileEdges.of([(tool, 0.0)], stock))
    times, qs = _samples(trajectory, q0)
    speed = max(1.0, trajectory.duration / duration_s)
    keys = _key_times(trajectory, times[-1], speed)
    key_q = np.column_stack([np.interp(keys, times, qs[:, i]) for i in range(qs.shape[1])])

    # tool paths in the workpiece frame: commanded axis values on both machines
    moving = [s for s in trajectory.segments if s.kind != "dwell"]
    path_q = np.vstack([s.q for s in moving]) if moving else q0[None]
    step = max(1, len(path_q) // PATH_POINTS)
    path_q = path_q[np.unique(np.append(np.arange(0, len(path_q), step), len(path_q) - 1))]
    scene.add_lines("workpiece/paths/nominal", machine.tool_pose(path_q, None)[:, :3, 3],
                    NOMINAL_COLOUR)
    scene.add_lines("workpiece/paths/actual", machine.tool_pose(path_q, errors)[:, :3, 3],
                    ACTUAL_COLOUR)
    scene.add_mesh("tool", *tool_mesh(tool), colour=TOOL_COLOUR)

    stage_times, parts, empty, removed = _stages(trajectory, machine, tool, stock, errors,
                                                 max_stages, progress)
    if empty and not moving:  # as machinesim cut says it: the stock is not what to move
        scene.warnings.append("the program has no moves (no G00/G01/G02/G03 block that "
                              "runs), so nothing was removed")
    elif empty:
        scene.warnings.append("the program removed no material (does it reach the stock? "
                              "the stock is placed in the workpiece frame: --stock "
                              "block:LxWxH@x,y,z, mm)")
    for k, part in enumerate(parts):
        scene.add_mesh(f"workpiece/stages/{k}", *decimate(*part.mesh(), STAGE_TRIANGLES),
                       colour=PART_COLOUR)
    tracks = _body_tracks(visualizer, machine, errors, keys / speed, key_q)
    for k in range(len(parts)):
        on = [t / speed for t in stage_times[k:k + 2]]
        switch = sorted({0.0, *on})
        tracks[f"workpiece/stages/{k}"] = [visibility_track(
            switch, [on[0] <= t < (on[1] if len(on) > 1 else np.inf) for t in switch])]
    scene.animate(tracks)

    left = nothing_left_note(parts[-1], removed)  # cut()'s rule and words
    if left:  # bounds of nothing are NaN: no finished part to draw
        scene.warnings.append(f"{left}; no finished part is drawn")
        scene.notes += _program_notes(program, trajectory, keys, speed, parts, errors,
                                      chord_tolerance)
        if progress is not None:
            progress(len(parts), len(parts))
        return lo, hi
    nominal, _ = cut(program, machine, tool=tool, stock=stock, errors=None, start=q0,
                     chord_tolerance=chord_tolerance)
    if progress is not None:
        progress(len(parts), len(parts))
    part_lo, part_hi = parts[-1].bounds
    size = float(np.max(hi - lo))
    # at least the part's own size: beside a machine drawn as its stock alone (no visual
    # bodies) a fraction of the box would be smaller than the part
    scale = max(1.0, INSPECTION_SIZE * size / float(np.max(part_hi - part_lo)))
    place = np.diag([scale, scale, scale, 1.0])
    anchor = np.array([hi[0] + 0.1 * size, 0.5 * (lo[1] + hi[1]), lo[2]])
    place[:3, 3] = anchor - scale * np.array([part_lo[0], 0.5 * (part_lo[1] + part_hi[1]),
                                              part_lo[2]])
    scene.set_transform("inspection", place)
    smap = add_part(scene, "inspection/part", parts[-1], nominal, max_triangles)
    scene.legends.append(legend_for(smap, notes=(
        "finished part (enlarged, right of the machine) vs the nominal machine's",)))
    scene.notes += _program_notes(program, trajectory, keys, speed, parts, errors,
                                  chord_tolerance)
    extent = scale * (part_hi - part_lo)
    return lo, np.maximum(hi, anchor + extent * [1.0, 0.5, 1.0])


def _program_notes(program, trajectory, keys, speed, parts, errors, chord_tolerance):
    """The overlay's lines on the program, its animation, the part's stages and paths."""
    feeds = _feed_count(trajectory)
    notes = [
        f"program: {len(program.moves)} blocks, {trajectory.duration:.3g} s machining",
        f"animation: {keys[-1] / speed:.3g} s ({speed:.3g}x real time)",
        f"part stages: {len(parts) - 1} (stock, then after "
        + ("its rapids: it has no feed block)" if not feeds else
           "each feed block)" if len(parts) - 1 == feeds else "groups of feed blocks)"),
        path_note(errors),
    ]
    chords = arc_chord_note(program, chord_tolerance, takes_path=False)
    if chords:  # as cut() notes it: the stages and the part follow the program's own chords
        notes.append(chords)
    return notes


def path_note(errors) -> str:
    """The overlay's line on the two tool paths: red is the path on the machine with
    ``errors``, which without errors (None, or a model whose every parameter is zero) is the
    cyan nominal path itself, drawn over it; the line had said 'red actual (with errors)'
    of a view given none."""
    if errors is None:
        return ("tool path: cyan nominal; no errors given (--errors), so the red actual path "
                "is the nominal one, drawn over it")
    if as_error_model(errors).is_zero:
        return ("tool path: cyan nominal; the errors given are all zero, so the red actual "
                "path is the nominal one, drawn over it")
    return "tool path: cyan nominal, red actual (with errors)"


def cut_by_block(trajectory, machine, tool, stock, errors=None, max_stages: int = MAX_STAGES):
    """The part after each feed block (or group of blocks), cut one after the other, each
    with the rapids before it (the last with those after it too), as `cut` cuts them.

    Parameters
    ----------
    trajectory : machinesim.motion.Trajectory
    machine : machinesim.Machine
    tool : tool object
    stock : Part
    errors : ErrorModel, optional
    max_stages : int
        At most this many cuts: feed blocks are grouped evenly when there are more.

    Returns
    -------
    times : list of float
        Program time (s) from which each stage is the current part: 0 for the stock, then the
        end of each block or group.
    parts : list of Part
        The stock, then the part after each block or group (same length as ``times``).
    """
    times, parts, _, _ = _stages(trajectory, machine, tool, stock, errors, max_stages)
    return times, parts


def _stages(trajectory, machine, tool, stock, errors, max_stages, progress=None):
    """`cut_by_block`'s times and parts, whether no stage removed any material, and the
    volume (m^3) all stages removed; ``progress(done, stages + 1)`` after each stage (the
    one more: the nominal part).

    A stage is a feed block or a group of them, each cut with the rapids before it (the
    last with those after it too), as `cut` cuts every move: the stages had cut the feeds
    alone, so a rapid through the stock was missing from the finished part, which the map
    then coloured as the machine's error against the nominal part `cut` made (rapids
    included), and a program of rapids alone was said to remove nothing."""
    moving = [s for s in trajectory.segments if s.kind != "dwell" and len(s.q) > 1]
    feeds = [i for i, s in enumerate(moving) if s.kind == "linear"]
    if feeds:
        groups = np.array_split(np.array(feeds), min(len(feeds), max_stages))
        ends = [int(group[-1]) for group in groups]
    else:  # rapids alone: one stage, as they cut too
        ends = [len(moving) - 1] if moving else []
    times, parts, empty, removed = [0.0], [stock], True, 0.0
    for k, end in enumerate(ends):
        begin = ends[k - 1] + 1 if k else 0
        members = moving[begin:end + 1] if k < len(ends) - 1 else moving[begin:]
        paths = [machine.tool_pose(s.q, errors) for s in members]
        part, report = remove(parts[-1], tool, paths)
        if progress is not None:
            progress(k + 1, len(ends) + 1)
        empty = empty and bool(report.empty_cut)
        removed += float(report.removed_volume)
        times.append(float(moving[end].t[-1]))
        parts.append(part)
    return times, parts, empty, removed


def _feed_count(trajectory) -> int:
    return sum(1 for s in trajectory.segments if s.kind == "linear" and len(s.q) > 1)


def _samples(trajectory, q0):
    """All samples as (times (k,), axis values (k, n)), one sample per distinct time."""
    if not trajectory.segments:
        return np.array([0.0, 1.0]), np.vstack([q0, q0])
    times = np.concatenate([s.t for s in trajectory.segments])
    qs = np.vstack([s.q for s in trajectory.segments])
    # at a block boundary the later sample holds: keep the last of equal times
    last = np.append(np.diff(times) > 0.0, True)
    times, qs = times[last], qs[last]
    if len(times) == 1:
        return np.array([0.0, 1.0]), np.vstack([qs[0], qs[0]])
    return times, qs


def _key_times(trajectory, end: float, speed: float) -> np.ndarray:
    """Program times of the key frames: a uniform rate plus every block's start and end."""
    count = max(int(np.ceil(end / speed * KEY_RATE)), 1)
    segments = trajectory.segments if len(trajectory.segments) <= MAX_BLOCK_KEYS else ()
    bounds = [s.t[0] for s in segments] + [s.t[-1] for s in segments]
    keys = np.unique(np.concatenate([np.linspace(0.0, end, count + 1), bounds]))
    return keys[(keys >= 0.0) & (keys <= end)]


def _body_tracks(visualizer, machine, errors, times, key_q) -> dict:
    """Tracks of every visual body, the workpiece node and the tool: at animation ``times``
    (k,), s, the machine stands at axis values ``key_q`` (k, n)."""
    model, data = visualizer.model, visualizer.data
    geometry, gdata = visualizer.visual_model, visualizer.visual_data
    binding = machine.binding(errors)
    frames = {name: machine.kin.frame_id[name] for name in ("workpiece", "tool_tip")}
    bodies = {g.name: [] for g in geometry.geometryObjects}
    placed = {name: [] for name in frames}
    for q in key_q:
        full = machine.kin.full_q(q, binding)
        pin.forwardKinematics(model, data, full)
        pin.updateFramePlacements(model, data)
        pin.updateGeometryPlacements(model, data, geometry, gdata)
        for g_id, g in enumerate(geometry.geometryObjects):
            bodies[g.name].append(gdata.oMg[g_id].homogeneous)
        for name, f_id in frames.items():
            placed[name].append(data.oMf[f_id].homogeneous)
    tracks = {visualizer.getViewerNodeName(g, pin.GeometryType.VISUAL):
              transform_tracks(times, bodies[g.name]) for g in geometry.geometryObjects}
    tracks["workpiece"] = transform_tracks(times, placed["workpiece"])
    tracks["tool"] = transform_tracks(times, placed["tool_tip"])
    return tracks


def _with_stock(visualizer, machine, errors, q0, stock, lo, hi):
    """The world box (m) ``lo``, ``hi`` (None: nothing drawn yet) grown by the stock's, the
    workpiece frame placed at axis values ``q0``."""
    model, data = visualizer.model, visualizer.data
    pin.framesForwardKinematics(model, data, machine.kin.full_q(q0, machine.binding(errors)))
    pose = data.oMf[machine.kin.frame_id["workpiece"]]
    box = np.array(np.meshgrid(*stock.bounds.T)).reshape(3, -1).T
    corners = box @ pose.rotation.T + pose.translation
    if lo is None:
        return corners.min(axis=0), corners.max(axis=0)
    return np.minimum(lo, corners.min(axis=0)), np.maximum(hi, corners.max(axis=0))


def _machine_box(visualizer) -> tuple[np.ndarray | None, np.ndarray | None]:
    """World box (m) of the visual bodies where they stand now; (None, None) without any."""
    corners = []
    for g_id, g in enumerate(visualizer.visual_model.geometryObjects):
        shape = g.geometry
        if hasattr(shape, "halfSide"):
            half = np.asarray(shape.halfSide, dtype=np.float64)
        elif hasattr(shape, "radius") and hasattr(shape, "halfLength"):
            half = np.array([shape.radius, shape.radius, shape.halfLength])
        else:
            continue
        box = np.array(np.meshgrid(*[(-h, h) for h in half])).reshape(3, -1).T
        pose = visualizer.visual_data.oMg[g_id]
        corners.append(box @ pose.rotation.T + pose.translation)
    if not corners:
        return None, None
    points = np.vstack(corners)
    return points.min(axis=0), points.max(axis=0)


__all__ = ["DURATION_S", "MAX_STAGES", "cut_by_block", "machine_scene"]
