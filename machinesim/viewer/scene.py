"""A scene: the meshcat commands that draw it, recorded once, then exported or served.

Building a scene needs no server: commands go to a recorder (a stand-in for meshcat's
`ViewerWindow`), in order. The same recording is written into one self-contained HTML file
(meshcat's three.js bundle inlined, the commands as base64 msgpack) or replayed to a live
meshcat server (`machinesim.viewer.live`). Both pages carry the same HTML overlay: the
scene's notes and its colour-bar legends.
"""

from __future__ import annotations

import base64
import html
from pathlib import Path
from typing import NamedTuple

import meshcat
import meshcat.geometry as mg
import numpy as np
import umsgpack
from scipy.spatial.transform import Rotation

from machinesim._io import write_atomic
from machinesim.exceptions import InputError
from machinesim.viewer.maps import Legend
from machinesim.viewer.meshes import display_buffers

#: meshcat's three.js viewer bundle, inlined into exported pages and served in live mode.
VIEWER_JS = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
#: The longest string Chromium's JavaScript engine holds on a 64-bit machine (V8's
#: ``String::kMaxLength``, v8.h: ``(1 << 29) - 24`` UTF-16 units): a script longer than this
#: (a page's scene inlined as base64, about 30 characters a triangle) does not run.
SCRIPT_CHARS_MOST = (1 << 29) - 24
#: Background gradient (top, bottom), RGB in [0, 1]: dark and neutral, so that neither the
#: machines' colours nor the colour maps' hues are lost against it.
BACKGROUND = ((0.23, 0.25, 0.28), (0.07, 0.08, 0.09))
#: Camera position (m, world) until a scene sets its own: meshcat's default.
DEFAULT_CAMERA = (3.0, 0.0, 1.0)
#: Overlay panels are at most this wide (CSS px), on the left edge of the page; the 3D view
#: to their right is never covered (the browser test measures colours there).
OVERLAY_WIDTH_PX = 300


class NoteTable(NamedTuple):
    """A small table in the overlay, above the notes: a scenario's figures (name, before,
    after, unit), each cell text as shown."""

    title: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


class _Recorder:
    """Receives meshcat commands like `meshcat.visualizer.ViewerWindow` and keeps them."""

    def __init__(self, frames: list[tuple[str, str, bytes]]) -> None:
        self.frames = frames

    def send(self, command) -> None:
        data = command.lower()
        self.frames.append((data["type"], data["path"], umsgpack.packb(data)))


class Scene:
    """Ordered meshcat commands plus an overlay (notes and legends).

    Parameters
    ----------
    title : str
        Page title and first overlay line.
    """

    def __init__(self, title: str = "machinesim") -> None:
        self.title = title
        self._frames: list[tuple[str, str, bytes]] = []
        self.legends: list[Legend] = []
        self.notes: list[str] = []
        self.tables: list[NoteTable] = []  # above the notes (`NoteTable`)
        self.warnings: list[str] = []  # shown in the overlay and printed by the command
        #: Bytes of the mesh files sent as they are (a machine's STL, OBJ and DAE visuals,
        #: `machinesim.viewer.visuals`): no triangle budget makes them smaller.
        self.mesh_file_bytes = 0
        self.vis = meshcat.Visualizer(window=_Recorder(self._frames))
        self.vis["/Background"].set_property("top_color", list(BACKGROUND[0]))
        self.vis["/Background"].set_property("bottom_color", list(BACKGROUND[1]))
        for helper in ("/Grid", "/Axes"):
            self.vis[helper].set_property("visible", False)
        # a live server replays nodes in the order they were first touched: touching the
        # camera now puts it before the (large) meshes
        self.set_camera(DEFAULT_CAMERA)

    @property
    def frames(self) -> tuple[tuple[str, str, bytes], ...]:
        """The commands in the order given, as meshcat's server takes them: (type, path,
        msgpack-encoded command)."""
        return tuple(self._frames)

    def send_raw(self, command: dict) -> None:
        """Record an already lowered meshcat command (a dict with 'type' and 'path')."""
        self._frames.append((command["type"], command["path"], umsgpack.packb(command)))

    def add_mesh(self, path: str, vertices, triangles, colour=0xB0B0B0, rgb=None,
                 opacity: float = 1.0) -> None:
        """A triangle mesh (float64 in, float32 buffers out: display only).

        Parameters
        ----------
        path : str
            Scene path, e.g. ``"part/surface"``.
        vertices : array-like, shape (n, 3), m
        triangles : array-like, shape (m, 3), int
        colour : int
            0xRRGGBB, used when ``rgb`` is None.
        rgb : array-like, shape (n, 3), optional
            Per-vertex colours in [0, 1].
        opacity : float
        """
        v32, t32 = display_buffers(vertices, triangles)
        geometry = mg.TriangularMeshGeometry(v32, t32, color=rgb)
        material = mg.MeshPhongMaterial(color=0xFFFFFF if rgb is not None else colour,
                                        vertexColors=rgb is not None, opacity=opacity,
                                        shininess=10)
        self.vis[path].set_object(geometry, material)

    def add_lines(self, path: str, points, colour: int) -> None:
        """A polyline through ``points`` (k, 3), m."""
        p32 = np.ascontiguousarray(np.asarray(points).T, dtype=np.float32)  # display only
        self.vis[path].set_object(mg.Line(mg.PointsGeometry(p32),
                                          mg.LineBasicMaterial(color=colour)))

    def set_transform(self, path: str, matrix) -> None:
        """Place the node at ``path`` by a 4x4 matrix (may include a uniform scale)."""
        self.vis[path].set_transform(np.asarray(matrix, dtype=np.float64))

    def set_camera(self, position) -> None:
        """Camera position in the world frame (Z up), m; it looks at the origin."""
        x, y, z = (float(v) for v in position)
        # meshcat's camera lives in a Y-up frame rotated from the Z-up world
        self.vis["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])

    def animate(self, tracks: dict[str, list[dict]], loop: bool = True) -> None:
        """Play ``tracks`` (path -> track dicts from `transform_tracks`, `visibility_track`).

        Times are in seconds (clips at 1 frame per second, so a key's frame is its time).
        """
        animations = [{"path": self.vis[path].path.lower(),
                       "clip": {"fps": 1, "name": "default", "tracks": list(track_list)}}
                      for path, track_list in tracks.items()]
        self.send_raw({"type": "set_animation", "path": "", "animations": animations,
                       "options": {"play": True, "repetitions": 1_000_000 if loop else 1}})

    def to_html(self) -> str:
        """The whole scene as one page: no server, no network (everything inlined).

        Raises
        ------
        InputError
            When the scene's script would be longer than a browser's JavaScript engine
            reads (`SCRIPT_CHARS_MOST`): the page would open blank.
        """
        payload = ",\n".join(f'"{base64.b64encode(data).decode("ascii")}"'
                              for _, _, data in self._frames)
        commands = (
            'var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));\n'
            f"var commands = [{payload}];\n"
            "for (const text of commands) {\n"
            "  const binary = atob(text);\n"
            "  const bytes = new Uint8Array(binary.length);\n"
            "  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);\n"
            "  viewer.handle_command_bytearray(bytes);\n"
            "}\n")
        if len(commands) > SCRIPT_CHARS_MOST:
            too_long = (f"the page's scene would be a script of {len(commands):,} characters, "
                        f"beyond the {SCRIPT_CHARS_MOST:,} a browser's JavaScript engine "
                        "reads (V8's String::kMaxLength): it would open blank; ")
            files = 4 * -(-self.mesh_file_bytes // 3)  # their characters, as base64
            if files >= SCRIPT_CHARS_MOST:
                raise InputError(
                    f"{too_long}the machine's mesh files (STL, OBJ, DAE visuals) alone are "
                    f"{self.mesh_file_bytes / 2**20:,.1f} MB ({files:,} characters), which "
                    f"no --max-triangles makes smaller: give it mesh files of at most "
                    f"{3 * SCRIPT_CHARS_MOST / 4 / 2**20:,.1f} MB in all (fewer triangles, "
                    "decimated in a mesh tool)")
            raise InputError(f"{too_long}show fewer triangles (--max-triangles at least "
                             f"{(len(commands) - files) / (SCRIPT_CHARS_MOST - files):.2g} "
                             "times lower)")
        script = (f"<script>{VIEWER_JS.read_text(encoding='utf-8')}</script>\n"
                  f"<script>\n{commands}</script>")
        return page(self.title, overlay_html(self), script)


def page(title: str, overlay: str, script: str) -> str:
    """An HTML page: meshcat's pane, the overlay, and the given viewer script.

    The overlay is a column on the left that scrolls (the wheel over it, or its scroll bar)
    when its panels are taller than the window: a report folder's seven legends, 1,860 px of
    them, had run off an 800 x 600 window with no way to reach all but the first (the
    overlay let no mouse event through to itself, and hid what overflowed it). The wheel
    over the 3D view still zooms it.
    """
    return f"""<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{html.escape(title)}</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
#machinesim-overlay {{ position: absolute; left: 8px; top: 8px;
  max-width: min({OVERLAY_WIDTH_PX}px, calc(100vw - 16px)); max-height: calc(100vh - 16px);
  overflow-x: hidden; overflow-y: auto; overscroll-behavior: contain;
  scrollbar-width: thin; scrollbar-color: rgba(255, 255, 255, 0.35) transparent;
  font: 12px/1.35 sans-serif; color: #e8e8e8; }}
.ms-panel {{ background: rgba(0, 0, 0, 0.55); border-radius: 4px; padding: 6px 8px;
  margin-bottom: 6px; }}
.ms-title {{ font-weight: bold; margin-bottom: 4px; }}
.ms-bar-row {{ position: relative; height: 160px; margin: 6px 0; }}
.ms-bar {{ position: absolute; left: 0; top: 0; width: 22px; height: 160px;
  border: 1px solid #999; }}
.ms-tick {{ position: absolute; left: 30px; transform: translateY(50%); white-space: nowrap; }}
.ms-table-title {{ margin-top: 4px; }}
.ms-table {{ border-collapse: collapse; margin: 2px 0 4px; }}
.ms-table th, .ms-table td {{ padding: 0 0 0 8px; text-align: right; white-space: nowrap; }}
.ms-table th:first-child, .ms-table td:first-child {{ padding-left: 0; text-align: left;
  white-space: normal; overflow-wrap: anywhere; }}
.ms-table th {{ font-weight: bold; border-bottom: 1px solid #999; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
{overlay}
{script}
</body>
</html>
"""


def overlay_html(scene: Scene) -> str:
    """The overlay: the title, tables and notes, then one panel per legend (colour bar with
    ticks)."""
    parts = ['<div id="machinesim-overlay">', '<div class="ms-panel">',
             f'<div class="ms-title">{html.escape(scene.title)}</div>']
    for table in scene.tables:  # a report's figures first, then its other entries
        parts += [f'<div class="ms-table-title">{html.escape(table.title)}</div>',
                  '<table class="ms-table">',
                  "<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in table.header)
                  + "</tr>"]
        # a long name ('edge_distance_planes_L1_L5') may break after an underscore
        parts += ["<tr>" + "".join(
            f"<td>{html.escape(c).replace('_', '_<wbr>') if k == 0 else html.escape(c)}</td>"
            for k, c in enumerate(row)) + "</tr>" for row in table.rows]
        parts.append("</table>")
    parts += [f"<div>{html.escape(line)}</div>" for line in scene.notes]
    parts += [f"<div><b>warning:</b> {html.escape(line)}</div>" for line in scene.warnings]
    parts.append("</div>")
    for legend in scene.legends:
        stops = ", ".join(f"{css_colour(c)} {100 * k / (len(legend.stops) - 1):.1f}%"
                          for k, c in enumerate(legend.stops))
        parts += ['<div class="ms-panel ms-legend">',
                  f'<div class="ms-title">{html.escape(legend.title)}</div>',
                  '<div class="ms-bar-row">',
                  f'<div class="ms-bar" style="background: linear-gradient(to top, {stops});">'
                  "</div>"]
        parts += [f'<div class="ms-tick" style="bottom: {160 * f:.1f}px">{html.escape(label)}'
                  "</div>" for f, label in legend.ticks]
        parts.append("</div>")
        parts += [f"<div>{html.escape(line)}</div>" for line in legend.notes]
        parts.append("</div>")
    parts.append("</div>")
    return "\n".join(parts)


def css_colour(rgb) -> str:
    """'#rrggbb' of an RGB triple in [0, 1]."""
    r, g, b = (int(round(255 * float(c))) for c in rgb)
    return f"#{r:02x}{g:02x}{b:02x}"


def transform_tracks(times, matrices) -> list[dict]:
    """Position and quaternion tracks of a node placed by ``matrices`` (k, 4, 4) at ``times``
    (k,), s. Rotations must be proper (no scale)."""
    times = [float(t) for t in times]
    matrices = np.asarray(matrices, dtype=np.float64)
    positions = matrices[:, :3, 3].tolist()
    quaternions = Rotation.from_matrix(matrices[:, :3, :3]).as_quat().tolist()  # x y z w
    return [
        {"name": ".position", "type": "vector3",
         "keys": [{"time": t, "value": p} for t, p in zip(times, positions, strict=True)]},
        {"name": ".quaternion", "type": "quaternion",
         "keys": [{"time": t, "value": q} for t, q in zip(times, quaternions, strict=True)]},
    ]


def visibility_track(times, visible) -> dict:
    """A track switching a node on and off at ``times`` (s)."""
    return {"name": ".visible", "type": "boolean",
            "keys": [{"time": float(t), "value": bool(v)}
                     for t, v in zip(times, visible, strict=True)]}


def write_html(scene: Scene, path) -> Path:
    """Write ``scene`` as one self-contained HTML file, whole or not at all; return the path."""
    write_atomic(path, scene.to_html())
    return Path(path)


__all__ = ["BACKGROUND", "OVERLAY_WIDTH_PX", "SCRIPT_CHARS_MOST", "VIEWER_JS", "NoteTable",
           "Scene",
           "css_colour", "overlay_html", "page", "transform_tracks", "visibility_track",
           "write_html"]
