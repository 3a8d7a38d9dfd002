"""A machine's visual geometry for the viewer, its STL meshes read by the browser only.

Loading a machine (`machinesim.machines.Machine`, ``machinesim cut``) builds its kinematics
from the URDF text and opens no mesh file. The view draws the visuals: Pinocchio's
`MeshcatVisualizer` sends an STL, OBJ or DAE mesh to the page as the file's own bytes, so
the triangles Pinocchio reads (through coal and assimp) and the collision tree it builds
of them are never used; for a CAD export's STL visuals that is most of the view's time (a
500,000-triangle STL: 8.5 s to build, 37 ms for trimesh to read). `machine_visuals` hands
Pinocchio a placeholder box for each STL mesh and puts the file's path and scale on the
geometry object it makes, which the visualizer then sends as before.
"""

from __future__ import annotations

import os
import re
import struct
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

try:
    import coal
except ImportError:  # Pinocchio before 3.4 is built on hpp-fcl, coal's former name
    import hppfcl as coal

from machinesim.urdf_reading import _URDF_NUMBER, _fields
from machinesim.viewer.scene import Scene

#: Mesh files whose geometry object keeps only the path (the visualizer sends the file
#: itself). OBJ and DAE meshes are sent as files too, but are read by Pinocchio as before:
#: a file that Pinocchio cannot read is then left out with a warning, and `_stl_readable`
#: is the check that stands in for that read for an STL.
DEFERRED_SUFFIXES = (".stl",)
#: Mesh files Pinocchio's `MeshcatVisualizer` sends to the page as the file's own bytes.
SENT_SUFFIXES = (".stl", ".obj", ".dae")


def machine_visuals(machine, scene: Scene) -> pin.GeometryModel:
    """The machine's visual geometry model. Mesh files the URDF names but that cannot be
    found or read (a ROS file's ``package://`` paths, resolved only inside ROS) are left out,
    with a warning naming their links, rather than ending the view: the axes need no
    drawing."""
    # a mesh's relative path is read from the URDF's folder, as its author (a CAD export's
    # meshes/base.STL) meant it, wherever the view starts; package://<package>/... from the
    # folders holding a ROS package's folder (<package>/urdf/machine.urdf)
    folder = Path(machine.path).resolve().parent
    dirs = [str(folder), str(folder.parent), str(folder.parent.parent)]
    root = ET.fromstring(machine.urdf_xml)
    deferred: dict[int, tuple[str, np.ndarray]] = {}  # id of a <visual>: its file, scale
    left_out = []
    for link in root.iter("link"):
        for visual in link.findall("visual"):
            mesh = visual.find("geometry/mesh")
            if mesh is not None and Path(mesh.get("filename")).suffix.lower() == ".obj":
                found = resource_path(mesh.get("filename"), dirs)
                if found is not None and _obj_not_finite(found):
                    link.remove(visual)
                    left_out.append(f"{link.get('name')} ({mesh.get('filename')}: a vertex "
                                    "that is not a finite number)")
                continue
            if mesh is None or Path(mesh.get("filename")).suffix.lower() not in \
                    DEFERRED_SUFFIXES or _scale(mesh) is None:
                continue
            found = resource_path(mesh.get("filename"), dirs)
            if found is None or not _stl_readable(found):
                link.remove(visual)
                why = (_not_found(mesh.get("filename"), dirs) if found is None
                       else "not an STL: binary, or text starting 'solid'")
                left_out.append(f"{link.get('name')} ({mesh.get('filename')}: {why})")
                continue
            deferred[id(visual)] = (found, _scale(mesh))
            geometry = visual.find("geometry")
            geometry.remove(mesh)
            ET.SubElement(geometry, "box", size="1 1 1")
    try:
        model = pin.buildGeomFromUrdfString(machine.model, ET.tostring(root, encoding="unicode"),
                                            pin.GeometryType.VISUAL, package_dirs=dirs)
    except ValueError:  # an OBJ or DAE mesh Pinocchio cannot find or read: every such mesh
        for link in root.iter("link"):  # is left out, as all meshes were before
            for visual in link.findall("visual"):
                mesh = visual.find("geometry/mesh")
                if mesh is not None:
                    link.remove(visual)
                    left_out.append(f"{link.get('name')} ({mesh.get('filename')}: "
                                    "not found, or not read by Pinocchio)")
        model = pin.buildGeomFromUrdfString(machine.model, ET.tostring(root, encoding="unicode"),
                                            pin.GeometryType.VISUAL, package_dirs=dirs)
    files = {}
    for link in root.iter("link"):  # Pinocchio names a link's visuals <link>_0, <link>_1, ...
        for index, visual in enumerate(link.findall("visual")):
            if id(visual) in deferred:
                files[f"{link.get('name')}_{index}"] = deferred[id(visual)]
    for g in model.geometryObjects:
        if g.name in files:
            g.geometry = coal.BVHModelOBBRSS()  # no primitive: drawn from its meshPath
            g.meshPath, g.meshScale = files[g.name]
        # every mesh file goes to the page as it is, an OBJ or DAE (read by Pinocchio) too:
        # no triangle budget makes it smaller (`Scene.to_html`'s refusal of a long page)
        if Path(g.meshPath).suffix.lower() in SENT_SUFFIXES and os.path.isfile(g.meshPath):
            scene.mesh_file_bytes += os.path.getsize(g.meshPath)
    if left_out:
        # where a file is looked up, only where one was not found: a FIFO or a text file
        # named .stl had been told to give the file's path too
        where = (f" (a relative path is looked up in {folder}, package://<package>/... there "
                 "and in the two folders above it; give the file's path)"
                 if any("not found" in entry for entry in left_out) else "")
        scene.warnings.append(
            f"{machine.path}: mesh files that could not be loaded, drawn without them: "
            f"{', '.join(left_out[:5])}"
            f"{f' and {len(left_out) - 5} more' if len(left_out) > 5 else ''}{where}")
    return model


def resource_path(filename: str, dirs: list[str]) -> str | None:
    """The file a URDF mesh's ``filename`` names, found as Pinocchio finds it (its
    ``retrieveResourcePath``): ``package://`` and ``model://`` paths, and relative ones, in
    the first of ``dirs`` holding them; ``file://`` and absolute paths as they are. None
    when there is no such file."""
    scheme, separator, rest = filename.partition("://")
    if separator:
        if scheme == "file":
            return rest if os.path.isfile(rest) else None
        if scheme not in ("package", "model"):
            return None
        filename = rest
    elif os.path.isabs(filename):
        return filename if os.path.isfile(filename) else None
    for folder in dirs:
        candidate = f"{folder}/{filename}"
        if os.path.exists(candidate):
            return candidate if os.path.isfile(candidate) else None
    return None


def _not_found(filename: str, dirs: list[str]) -> str:
    """Why `resource_path` found no file for ``filename``: there is none, or what is there
    is not a regular file (a folder, a FIFO, a device)."""
    scheme, separator, rest = filename.partition("://")
    if separator and scheme not in ("file", "package", "model"):
        return f"not found: {scheme}:// is not a path"
    name = rest if separator else filename
    places = [name] if (scheme == "file" or os.path.isabs(name)) else [
        f"{folder}/{name}" for folder in dirs]
    if any(os.path.exists(place) for place in places):
        return "not a regular file"
    return "not found"


#: An OBJ vertex line holding nan or inf: Pinocchio's reader (assimp) takes it, and its
#: bounding volume's eigen-solver printed "eigen: too many iterations in Jacobi transform."
#: on stderr from C++, the view going on with exit 0.
_OBJ_NOT_FINITE = re.compile(rb"(?im)^[ \t]*v[ \t][^\n]*?(?:nan|inf)")


def _obj_not_finite(path: str) -> bool:
    """Whether the OBJ file ``path`` has a vertex with a coordinate nan or inf (unreadable:
    left to Pinocchio, which names it)."""
    try:
        with open(path, "rb") as file:
            return _OBJ_NOT_FINITE.search(file.read()) is not None
    except OSError:
        return False


def _stl_readable(path: str) -> bool:
    """Whether ``path`` is an STL that Pinocchio's reader (assimp) takes, from its first
    bytes and its size: binary (84 bytes of header and count, 50 a triangle, at least one)
    or text (``solid`` after any blanks)."""
    try:
        size = os.path.getsize(path)
        with open(path, "rb") as file:
            head = file.read(84)
    except OSError:
        return False
    if len(head) == 84:
        (count,) = struct.unpack("<I", head[80:84])
        if count > 0 and size == 84 + 50 * count:
            return True
    return head.lstrip().lower().startswith(b"solid")


def _scale(mesh: ET.Element) -> np.ndarray | None:
    """A mesh's ``scale`` (1 1 1 when not given), or None when it is not three finite
    numbers as the URDF parser reads them (which a machine's load refuses): that parser
    drops such a visual, so it is left to Pinocchio, as before."""
    text = mesh.get("scale")
    if text is None:
        return np.ones(3)
    fields = _fields(text)
    if len(fields) != 3 or not all(_URDF_NUMBER.fullmatch(f) for f in fields):
        return None
    scale = np.array([float(f) for f in fields], dtype=np.float64)
    return scale if np.isfinite(scale).all() else None
