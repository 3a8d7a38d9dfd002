"""Scenes of machined parts: one part (with its cut report), or a scenario report folder.

A part is drawn as its colour-mapped top surface (`maps.surface_map`: deviation from a
nominal part, else height) and, in the part colour, the faces that do not face up (sides,
walls, bottom), decimated for display if large.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from machinesim._json import read_json
from machinesim.exceptions import InputError
from machinesim.part import UNIT_SLIP_SIZE_M
from machinesim.summary_schema import check_version
from machinesim.viewer.maps import (
    SurfaceMap,
    legend_for,
    map_mesh,
    map_title,
    mesh_of,
    surface_map,
)
from machinesim.viewer.meshes import (
    DISPLAY_TRIANGLES,
    decimate,
    ply_ascii,
    ply_single_precision,
    read_ply,
    triangle_normals,
)
from machinesim.viewer.scene import NoteTable, Scene

#: Colour of a part's faces that are not colour-mapped (sides, walls, bottom): pale copper,
#: the material of many diamond-turned parts.
PART_COLOUR = 0xD9A066
#: Parts of a report folder stand side by side, this fraction of the largest one apart.
GAP = 0.25
#: Lines of a report JSON shown in the overlay (the rest is left out, with a note).
MAX_NOTE_LINES = 14
#: Camera position in the world for a scene scaled to 1 (front right, above): the whole
#: scene fills about two thirds of the view of meshcat's 75-degree camera.
CAMERA_POSITION = np.array([0.55, -0.9, 0.65])


def add_part(scene: Scene, path: str, surface, nominal=None,
             max_triangles: int = DISPLAY_TRIANGLES, name: str = "the part") -> SurfaceMap:
    """Draw a part under ``path`` in its workpiece frame; return the surface map drawn.

    Parameters
    ----------
    scene : Scene
    path : str
        Scene node, e.g. ``"parts/part"``: the map goes to ``path/map``, the other faces to
        ``path/body``.
    surface : Part or tuple of (vertices, triangles)
        The part, exact float64 (measured before anything is thinned).
    nominal : Part or tuple, optional
        Colour by deviation from this part; else by height.
    max_triangles : int
        Display budget of each of the two meshes.
    name : str
        What a warning calls the part (a nominal that lies under none of its map is warned
        about in ``scene.warnings``).
    """
    vertices, triangles = mesh_of(surface)
    smap = surface_map((vertices, triangles), nominal, max_triangles)
    if not np.isfinite(smap.heights).any():
        # heights come from the faces that face up: an open surface wound the other way
        # (a scan with its normals down) has none, and the page showed an empty map
        scene.warnings.append(f"{name} has no face that faces up over its map, so the map "
                              "is empty: heights are read from upward-facing triangles "
                              "(counter-clockwise seen from above); is the surface wound "
                              "the other way?")
    elif smap.kind == "deviation" and not np.isfinite(smap.values).any():
        # else a grey map, a +-1 nm scale and 'P-V nan um', with no word why
        # the part's bounds, which the map covers (its outer nodes stand a hair inside)
        lo, hi = (np.array([vertices[:, k].min(), vertices[:, k].max()]) * 1e3 for k in (0, 1))
        scene.warnings.append(f"the nominal part lies under no point of {name}'s map (x "
                              f"{lo[0]:.6g} .. {lo[1]:.6g} mm, y {hi[0]:.6g} .. {hi[1]:.6g} "
                              "mm): no deviation to show; are both in the same workpiece "
                              "frame?")
    grid_v, grid_t, rgb = map_mesh(smap)
    scene.add_mesh(f"{path}/map", grid_v, grid_t, rgb=rgb)
    # the map covers every face that faces up; the rest keeps the part's silhouette
    body = triangles[triangle_normals(vertices, triangles)[:, 2] <= 0.0]
    if len(body):
        scene.add_mesh(f"{path}/body", *decimate(vertices, body, max_triangles),
                       colour=PART_COLOUR)
    return smap


def frame_scene(scene: Scene, lo, hi, root: str = "/meshcat") -> None:
    """Scale and shift ``root`` so the box [lo, hi] (m) is ~1 unit, centred at the origin,
    and aim the camera at it (meshcat's camera orbits the origin)."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    size = float(np.max(hi - lo)) or 1.0
    scale = 1.0 / size
    matrix = np.diag([scale, scale, scale, 1.0])
    matrix[:3, 3] = -0.5 * (lo + hi) * scale
    scene.set_transform(root, matrix)
    scene.set_camera(CAMERA_POSITION)


def part_scene(surface, nominal=None, report=None, title: str = "machined part",
               max_triangles: int = DISPLAY_TRIANGLES) -> Scene:
    """A scene of one part, colour-mapped, with its cut report's figures in the overlay.

    Parameters
    ----------
    surface : Part or tuple of (vertices, triangles) or path of a PLY file
    nominal : Part or tuple or path, optional
    report : dict or path of a JSON file, optional
        A cut report (`CutReport.to_dict`) or any JSON object: its entries become notes.
    title : str
    max_triangles : int
    """
    vertices, triangles = mesh_of(_load(surface))
    _check_extent(vertices, surface)
    scene = Scene(title)
    parts = {"the part": (surface, vertices)}
    if nominal is not None:
        path, nominal = nominal, _load(nominal)
        parts["the nominal part"] = (path, mesh_of(nominal)[0])
    scene.warnings += file_warnings(parts)
    smap = add_part(scene, "part", (vertices, triangles), nominal, max_triangles)
    scene.notes += _mesh_notes(len(triangles), max_triangles)
    if report is not None:
        data = read_json(Path(report), 'report') if isinstance(report, str | Path) else report
        scene.notes += report_notes(data)
        scene.warnings += cut_warnings(data)
    scene.legends.append(legend_for(smap))
    frame_scene(scene, vertices.min(axis=0), vertices.max(axis=0))
    return scene


def cut_warnings(report: dict) -> list[str]:
    """Lines for what a cut report says went wrong with the part itself, which its notes
    (the first `MAX_NOTE_LINES` keys) may leave out: a part in several pieces, where the
    stock was one (``part_pieces_count``, the last key `machinesim cut` writes), and a cut
    through the stock's bottom face (``bottom_cut_through_mm2``)."""
    lines = []
    pieces = report.get("part_pieces_count")
    if isinstance(pieces, int) and not isinstance(pieces, bool) and pieces > 1:
        lines.append(f"the report says the part is in {pieces} separate pieces, where the "
                     "stock was one: a cut went through it")
    through = report.get("bottom_cut_through_mm2")
    if (isinstance(through, int | float) and not isinstance(through, bool)
            and math.isfinite(through) and through > 0):
        lines.append(f"the report says the cut went through the bottom of the stock "
                     f"({through:.6g} mm^2 of its bottom face gone): the tool reached its "
                     "bottom face or went below it")
    return lines


def report_scene(folder, max_triangles: int = DISPLAY_TRIANGLES) -> Scene:
    """A scene of a scenario report folder: its part meshes side by side and its summary.

    The folder holds ``*.ply`` parts and ``summary.json``. The nominal part is the one that
    ``summary.json`` names under ``"nominal_ply"``, else ``nominal.ply`` if present; every
    other part is coloured by its deviation from it (without a nominal: by height).
    """
    folder = Path(folder)
    plys = sorted(folder.glob("*.ply"))
    summary_path = folder / "summary.json"
    if not plys:
        raise InputError(f"{folder}: no part meshes (*.ply) in this folder; a report folder "
                         "holds *.ply parts and summary.json")
    summary = read_json(summary_path, 'report summary') if summary_path.is_file() else {}
    if not isinstance(summary, dict):
        raise InputError(f"expected a JSON object, got {type(summary).__name__}",
                         source=str(summary_path))
    # a summary of another schema version (a newer machinesim's) was shown as this one's,
    # its keys read as this version's meaning
    check_version(summary, source=str(summary_path))
    nominal_path = folder / str(summary.get("nominal_ply", "nominal.ply"))
    shown = [p for p in plys if p != nominal_path] or plys
    # a folder holding only the nominal part shows it by height
    # a nominal among the folder's *.ply is read as a part is (a folder or a link to nothing
    # under its name is refused as one of the parts is; it had been passed over, and the parts
    # coloured by height without a word)
    nominal = read_ply(nominal_path) if nominal_path in plys and shown != plys else None
    scene = Scene(f"report {folder.name}")
    named = summary.get("nominal_ply")
    # a file outside the folder ('sub/nominal.ply', an absolute path) is no part of it: the
    # parts were coloured by height without a word
    if named is not None and not (isinstance(named, str) and nominal_path in plys):
        # the parts would be coloured by height, as if the summary named no nominal
        scene.warnings.append(f"{summary_path} names the nominal part {named!r} "
                              "(nominal_ply), which is not a file in the folder: each part "
                              "is coloured by its height, not by its deviation")
    if summary:
        table = figures_table(summary.get("figures"))
        if table is not None:  # a table, not the list of dicts as one note line
            scene.tables.append(table)
            summary = {k: v for k, v in summary.items() if k != "figures"}
        scene.notes += report_notes(summary)
    else:
        scene.notes.append("no summary.json in this folder")
    if nominal is not None:
        scene.notes.append(f"coloured by deviation from {nominal_path.name}")
    meshes = [read_ply(p) for p in shown]
    for p, (vertices, _) in zip(shown, meshes, strict=True):
        _check_extent(vertices, p)
    parts = {p.name: (p, mesh[0]) for p, mesh in zip(shown, meshes, strict=True)}
    if nominal is not None:
        parts[nominal_path.name] = (nominal_path, nominal[0])
    scene.warnings += file_warnings(parts)
    boxes = [(v.min(axis=0), v.max(axis=0)) for v, _ in meshes]
    step = (1.0 + GAP) * max(float(np.max(hi - lo)) for lo, hi in boxes)
    lo_all, hi_all = np.full(3, math.inf), np.full(3, -math.inf)
    for k, (p, mesh, (lo, hi)) in enumerate(zip(shown, meshes, boxes, strict=True)):
        # side by side along X: shift each part's box to start at k * step
        shift = np.array([k * step - lo[0], -0.5 * (lo[1] + hi[1]), 0.0])
        place = np.eye(4)
        place[:3, 3] = shift
        node = f"parts/{k}"
        scene.set_transform(node, place)
        smap = add_part(scene, node, mesh, nominal, max_triangles, name=p.name)
        scene.legends.append(legend_for(smap, title=f"{p.name}: {map_title(smap.kind)}",
                                        notes=_mesh_notes(len(mesh[1]), max_triangles)))
        lo_all, hi_all = np.minimum(lo_all, lo + shift), np.maximum(hi_all, hi + shift)
    frame_scene(scene, lo_all, hi_all)
    return scene


def file_warnings(parts: dict) -> list[str]:
    """`precision_warnings` and `size_warnings` of the parts ``name: (path, vertices)``:
    what a part file from elsewhere may hold that the page would show without a word."""
    return precision_warnings(parts) + size_warnings(
        {name: vertices for name, (_, vertices) in parts.items()})


def precision_warnings(parts: dict) -> list[str]:
    """A line for each named part, ``name: (path, vertices (n, 3) m)`` (a path that is not a
    str or Path skipped), whose PLY rounded its vertices before they were read: stored in
    single precision (by up to half a float32 step at the largest coordinate), or as text
    (as precise as they were printed: a writer's eight decimals of a metre round by up to
    5 nm), so the map's heights are exact for the rounded mesh only."""
    lines = []
    for name, (path, vertices) in parts.items():
        if not isinstance(path, str | Path):
            continue
        file = "" if name == Path(path).name else f" ({Path(path).name})"
        if ply_ascii(path):
            lines.append(f"{name}{file} stores its vertices as text: each as precise as it was "
                         "printed (eight decimals of a metre round by up to 5 nm), so its "
                         "heights are exact for the mesh as printed only; machinesim cut --out "
                         "part.ply writes float64")
        elif ply_single_precision(path):
            largest = float(np.abs(vertices).max())
            step = float(np.spacing(np.float32(largest))) / 2.0
            lines.append(f"{name}{file} stores its vertices as float32: each "
                         f"rounded by up to {step * 1e9:.2g} nm (half a float32 step at "
                         f"{largest * 1e3:.4g} mm from the origin) before it was read, so its "
                         "heights are exact for the rounded mesh only; machinesim cut --out "
                         "part.ply writes float64")
    return lines


def size_warnings(vertices_by_name: dict) -> list[str]:
    """A line for each named part (vertices (n, 3), m; None skipped) that measures at least
    `UNIT_SLIP_SIZE_M` in x, y or z: perhaps a file in millimetres read as metres."""
    lines = []
    for name, vertices in vertices_by_name.items():
        if vertices is None or not len(vertices):
            continue
        size = np.ptp(vertices, axis=0)
        if size.max() >= UNIT_SLIP_SIZE_M:
            lines.append(f"{name} measures {size[0]:.6g} x {size[1]:.6g} x {size[2]:.6g} m, "
                         "larger than any machine's travel: PLY coordinates are read as "
                         "metres; was the file written in millimetres?")
    return lines


def figures_table(figures) -> NoteTable | None:
    """A summary.json's ``figures`` (docs/reports.md: objects with ``name``, ``before``,
    ``after`` and ``unit``) as a table of those four, numbers to 4 significant digits and a
    null as n/a; None when ``figures`` is not such a list (its notes then show it as it is).
    The overlay had shown the list as one line of raw dicts: "figures: [{'name': ...}]"."""
    if not isinstance(figures, list) or not figures or not all(
            isinstance(f, dict) and isinstance(f.get("name"), str)
            and isinstance(f.get("unit"), str) for f in figures):
        return None

    def cell(value) -> str:
        if value is None:
            return "n/a"
        if isinstance(value, int | float) and not isinstance(value, bool):
            return f"{value:.4g}"
        return str(value)

    rows = tuple((f["name"], cell(f.get("before")), cell(f.get("after")), f["unit"])
                 for f in figures)
    return NoteTable("figures (before and after compensation)",
                     ("figure", "before", "after", "unit"), rows)


def report_notes(report) -> list[str]:
    """'key: value' lines of a report (a dict, or a JSON file's path), nested keys dotted."""
    data = read_json(Path(report), 'report') if isinstance(report, str | Path) else report
    if not isinstance(data, dict):
        raise InputError(f"expected a JSON object as report, got {type(data).__name__}")
    lines = []

    def walk(prefix: str, value) -> None:
        if isinstance(value, dict):
            for key, item in value.items():
                walk(f"{prefix}{key}.", item)
        elif isinstance(value, float):
            lines.append(f"{prefix[:-1]}: {value:.6g}")
        elif isinstance(value, list) and len(value) > 4:
            lines.append(f"{prefix[:-1]}: [{len(value)} entries]")
        else:
            lines.append(f"{prefix[:-1]}: {value}")

    walk("", data)
    if len(lines) > MAX_NOTE_LINES:
        lines = lines[:MAX_NOTE_LINES] + [f"... {len(lines) - MAX_NOTE_LINES} more entries"]
    return lines


def _mesh_notes(count: int, max_triangles: int) -> list[str]:
    if count <= max_triangles:
        return [f"{count:,} triangles"]
    return [f"{count:,} triangles, drawn decimated (display only; measured exact)"]


def _check_extent(vertices: np.ndarray, surface) -> None:
    """Refuse a part with no extent in x or y (a line or a flat sliver standing on edge),
    naming its file when it came from one: its top surface has no area to map."""
    if not len(vertices):
        return  # `surface_map` says so
    size = np.ptp(vertices, axis=0)
    if not np.all(size[:2] > 0.0):
        lo, hi = vertices.min(axis=0) * 1e3, vertices.max(axis=0) * 1e3
        raise InputError(
            f"the part spans x {lo[0]:.6g} .. {hi[0]:.6g} mm, y {lo[1]:.6g} .. {hi[1]:.6g} mm: "
            "expected an extent in both x and y, a top surface to map",
            source=str(surface) if isinstance(surface, str | Path) else None)


def _load(surface):
    if isinstance(surface, str | Path):
        return read_ply(surface)
    return surface


__all__ = ["PART_COLOUR", "UNIT_SLIP_SIZE_M", "add_part", "cut_warnings", "figures_table",
           "file_warnings", "frame_scene", "part_scene", "precision_warnings", "report_notes",
           "report_scene", "size_warnings"]
