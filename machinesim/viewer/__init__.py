"""The browser viewer: machines moving along NC programs, machined parts and colour maps.

Scenes are built without a server (`Scene` records meshcat commands), then written as one
self-contained HTML file (`write_html`) or shown live by a meshcat server on 127.0.0.1
(`serve`). Parts are measured on their exact float64 meshes; only what is drawn is decimated
and converted to single precision for display.

>>> from machinesim.viewer import machine_scene, write_html
>>> write_html(machine_scene("robonano_a0ib"), "machine.html")  # doctest: +SKIP
"""

from __future__ import annotations

from machinesim.viewer.browser import Browser, find_chromium, screenshot
from machinesim.viewer.live import LiveSession, serve
from machinesim.viewer.machine import cut_by_block, machine_scene
from machinesim.viewer.maps import Legend, SurfaceMap, legend_for, surface_map
from machinesim.viewer.meshes import decimate, read_ply
from machinesim.viewer.scene import Scene, write_html
from machinesim.viewer.views import part_scene, report_scene

__all__ = [
    "Browser",
    "Legend",
    "LiveSession",
    "Scene",
    "SurfaceMap",
    "cut_by_block",
    "decimate",
    "find_chromium",
    "legend_for",
    "machine_scene",
    "part_scene",
    "read_ply",
    "report_scene",
    "screenshot",
    "serve",
    "surface_map",
    "write_html",
]
