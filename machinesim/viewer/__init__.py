"""The browser viewer: machines moving along NC programs, machined parts and colour maps.

Scenes are built without a server (`Scene` records meshcat commands), then written as one
self-contained HTML file (`write_html`) or shown live by a meshcat server on 127.0.0.1
(`serve`). Parts are measured on their exact float64 meshes; only what is drawn is decimated
and converted to single precision for display.

>>> from machinesim.viewer import machine_scene, write_html
>>> write_html(machine_scene("robonano_a0ib"), "machine.html")  # doctest: +SKIP
"""

from __future__ import annotations

import importlib

from machinesim._submodules import submodule

#: Names imported on first use (PEP 562), so that the command line's parser (which imports
#: ``machinesim.viewer.cli``) does not load meshcat, trimesh and Pinocchio before it parses.
_LAZY = {
    "Browser": "browser", "find_chromium": "browser", "screenshot": "browser",
    "LiveSession": "live", "serve": "live",
    "cut_by_block": "machine", "machine_scene": "machine",
    "Legend": "maps", "SurfaceMap": "maps", "legend_for": "maps", "surface_map": "maps",
    "decimate": "meshes", "read_ply": "meshes",
    "Scene": "scene", "write_html": "scene",
    "part_scene": "views", "report_scene": "views",
}


def __getattr__(name: str):
    if name not in _LAZY:
        return submodule(__name__, name)  # machinesim.viewer.views, ...
    value = getattr(importlib.import_module(f"machinesim.viewer.{_LAZY[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


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
