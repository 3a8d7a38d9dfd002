"""Meshes for display: PLY reading (exact), decimation and float32 buffers (display only).

Measurements never go through this module's decimated output for display: the viewer
measures on the exact float64 mesh (`machinesim.metrology`) and only then thins and converts what it
draws.
"""

from __future__ import annotations

import re
from pathlib import Path

import manifold3d
import numpy as np

from machinesim._io import check_path, not_a_regular_file
from machinesim.exceptions import FileError, InputError
from machinesim.workpiece import mesh_volume

#: Triangles of one displayed mesh above which it is decimated: ~200k triangles keep a scene
#: interactive in a browser without a GPU (swiftshader) and the HTML file under ~10 MB.
DISPLAY_TRIANGLES = 200_000
#: How much of a PLY file `ply_single_precision` reads at a time for its header (a part's
#: is ~250 B).
HEADER_BYTES = 65536
#: Each decimation pass shrinks the clustering cell by this factor beyond the estimate when
#: the estimate left too many triangles (a few passes at most).
CELL_GROWTH = 1.25

#: The PLY formats read, with their byte order (ASCII has none).
_PLY_FORMATS = {"format binary_little_endian 1.0": "<", "format binary_big_endian 1.0": ">",
                "format ascii 1.0": ""}
_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    # PLY property types; single-precision files are for display only
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def read_ply(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a triangle mesh from a PLY file: binary (either byte order, as `Part.export_ply`
    and most mesh tools write it) or ASCII, its header's lines ended by LF or CRLF.

    Vertices stored as double come back bit for bit (ASCII ones as their decimal text rounds
    to float64); float ones are widened to float64. Faces may carry other properties beside
    their vertex list (a colour, flags), which are skipped.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    vertices : ndarray, shape (n, 3), float64, m
    triangles : ndarray, shape (m, 3), int64

    Raises
    ------
    InputError
        When ``path`` is no file name (None, bytes: key 'path'), the file is missing, not a
        PLY, shorter than its header says (truncated) or longer (elements it does not
        count), has non-triangle faces, no faces, or a vertex that is not finite, or is a
        closed mesh inside out (wound clockwise seen from outside).
    """
    path = Path(check_path(path, "reading the PLY part"))  # None, bytes: no file name
    if path.is_dir():  # a folder named *.ply in a report folder: 'cannot read (Is a directory)'
        raise InputError("is a folder; expected a PLY part file", source=str(path))
    if path.exists() and not path.is_file():
        # a named pipe would block the read for ever, a device (/dev/zero) never end it
        raise FileError(f"{not_a_regular_file(path)}; expected a PLY part file",
                        source=str(path))
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read the PLY file ({exc.strerror})", source=str(path)) from None
    if not data.strip():  # 'not a PLY file: expected 'ply' and 'end_header' lines' had said
        raise InputError(f"the file is empty ({len(data)} bytes"
                         f"{', all white space' if data else ''}); expected a PLY part "
                         "(a 'ply' line, its header and its elements)", source=str(path))
    found = re.search(rb"end_header\r?\n", data)
    if not re.match(rb"ply\r?\n", data) or found is None:
        raise InputError("not a PLY file: expected 'ply' and 'end_header' lines",
                         source=str(path))
    header = data[:found.start()].decode("ascii", errors="replace").splitlines()
    fmt = next((h.strip() for h in header if h.startswith("format")), "no format line")
    if fmt not in _PLY_FORMATS:
        raise InputError(f"{fmt!r}: expected 'format binary_little_endian 1.0', "
                         "'format binary_big_endian 1.0' or 'format ascii 1.0'",
                         source=str(path))
    elements = _ply_elements(header, path)
    if fmt == "format ascii 1.0":
        vertices, triangles = _ascii_elements(data, found.end(), elements, path)
    else:
        vertices, triangles = _binary_elements(data, found.end(), elements,
                                               _PLY_FORMATS[fmt], path)
    if vertices is None or triangles is None:
        raise InputError("expected 'vertex' and 'face' elements", source=str(path))
    if not len(triangles):
        raise InputError(f"no faces ({len(vertices)} vertices): expected a part's surface as "
                         "triangles", source=str(path))
    # the flat tests first (1 ms of a 1.5-million-triangle part, where the rows' took 25 ms);
    # the rows only to name the first offender
    if not np.isfinite(vertices).all():
        finite = np.isfinite(vertices).all(axis=1)
        first = int(np.flatnonzero(~finite)[0])
        raise InputError(f"vertex {first} is {vertices[first].tolist()} ({np.sum(~finite)} of "
                         f"{len(vertices)} not finite): expected finite coordinates",
                         source=str(path))
    if triangles.min() < 0 or triangles.max() >= len(vertices):
        outside = (triangles < 0) | (triangles >= len(vertices))
        face = int(np.flatnonzero(outside.any(axis=1))[0])
        raise InputError(f"face {face} is {triangles[face].tolist()} ({np.sum(outside)} of "
                         f"{outside.size} indices outside): expected vertex indices 0 .. "
                         f"{len(vertices) - 1} (the file has {len(vertices)} vertices)",
                         source=str(path))
    volume = mesh_volume(vertices, triangles)
    # an open mesh's signed volume means nothing: only a closed one is known inside out
    if volume < 0.0 and closed_and_oriented(triangles):
        raise InputError(f"the part is inside out: it encloses {volume * 1e9:.6g} mm^3, its "
                         "triangles clockwise seen from outside, so its bottom would read as "
                         "its top surface; expected counter-clockwise (reverse each face's "
                         "vertex order)", source=str(path))
    return vertices, triangles


def closed_and_oriented(triangles: np.ndarray) -> bool:
    """Whether every edge of ``triangles`` (m, 3) is shared by exactly two of them, run in
    opposite directions (a closed, consistently wound mesh; vertices shared by index).

    Each directed edge (i, j) is found run back as (j, i) when the edges are distinct and
    the reversed ones, as many and as distinct, are the same set: both sorted, equal. (With
    a search of each reversed edge among the sorted ones the check of a
    1.5-million-triangle part took 0.54 s, with the second sort 0.19 s.)
    """
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    count = int(triangles.max()) + 1
    key = np.sort(edges[:, 0] * count + edges[:, 1])
    if np.any(key[1:] == key[:-1]):
        return False
    return bool(np.array_equal(key, np.sort(edges[:, 1] * count + edges[:, 0])))


def ply_single_precision(path) -> bool:
    """Whether a PLY part (read by `read_ply`, which widens them) stores any of its vertex
    coordinates in single precision, as trimesh and most mesh tools write PLY: rounded to
    float32 before machinesim reads them, so its heights are exact only for the rounded mesh.
    """
    return any(_PLY_TYPES[kind] == "f4" for kind in _vertex_kinds(_ply_header(path), path))


def ply_ascii(path) -> bool:
    """Whether a PLY part stores its numbers as text (``format ascii 1.0``)."""
    return any(line.strip() == "format ascii 1.0" for line in _ply_header(path))


def _ply_header(path) -> list[str]:
    path = Path(path)
    head = b""
    with path.open("rb") as file:
        # read on until the header ends: a header of many comments, longer than one read,
        # lost its element lines, and with them the float32 warning
        end = -1
        while end < 0:
            chunk = file.read(HEADER_BYTES)
            if not chunk:
                break
            head += chunk
            # only the new bytes and the tail before them can hold it
            end = head.find(b"end_header", max(len(head) - len(chunk) - 10, 0))
    return head[:end if end >= 0 else len(head)].decode("ascii", errors="replace").splitlines()


def _vertex_kinds(header: list[str], path) -> list[str]:
    for name, _, props in _ply_elements(header, Path(path)):
        if name == "vertex":
            return [kind for prop, kind, _ in props if prop in ("x", "y", "z")]
    return []


def _ply_elements(header: list[str], path: Path):
    elements = []
    for line in header:
        words = line.split()
        if not words:
            continue
        if words[0] == "element":
            if len(words) != 3 or not words[2].isdigit():
                raise InputError(f"malformed element line {line!r}: expected 'element NAME "
                                 "COUNT', COUNT a whole number", source=str(path))
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            if not elements:
                raise InputError("property before any element", source=str(path))
            if words[1] == "list":
                if len(words) != 5 or words[2] not in _PLY_TYPES or words[3] not in _PLY_TYPES:
                    raise InputError(f"malformed list property {line!r}", source=str(path))
                elements[-1][2].append((words[4], "list", (words[2], words[3])))
            elif len(words) == 3 and words[1] in _PLY_TYPES:
                elements[-1][2].append((words[2], words[1], None))
            else:
                raise InputError(f"unknown property {line!r}", source=str(path))
    for name, _, props in elements:
        lists = sum(kind == "list" for _, kind, _ in props)
        if lists and (name != "face" or lists != 1):
            raise InputError(f"element {name!r} has list properties; only 'face' may, one "
                             "(its vertex indices)", source=str(path))
    return elements


def _binary_elements(data: bytes, offset: int, elements, order: str, path: Path):
    """The vertices and triangles of a binary PLY body from ``offset`` (byte ``order`` '<'
    or '>'): each element a record array; a face's vertex list read as three indices after
    checking every face has three (a face of another size would misplace those after it,
    so the first such is where reading stops)."""
    vertices = triangles = None
    for name, count, props in elements:
        lists = any(kind == "list" for _, kind, _ in props)  # a face's (`_ply_elements`)
        fields = []
        for prop, kind, types in props:
            if kind == "list":
                fields += [("#n", order + _PLY_TYPES[types[0]]),
                           ("#i", order + _PLY_TYPES[types[1]], 3)]
            else:
                fields.append((prop, order + _PLY_TYPES[kind]))
        dtype = np.dtype(fields)
        _check_length(data, offset, dtype.itemsize * count, name, count, path)
        block = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
        offset += dtype.itemsize * count
        if name == "vertex":
            vertices = _vertex_columns(block, path)
        elif name == "face":
            triangles = _face_indices(block["#n"] if lists else None,
                                      block["#i"] if lists else None, path)
    if data[offset:].strip(b" \t\r\n"):
        # elements the header does not count (a count left too small) would be dropped; a
        # line end or blanks some writers leave after the data are no element
        raise InputError(f"the file goes on for {len(data) - offset} bytes after its "
                         f"elements end at byte {offset}: expected as many elements as the "
                         f"header counts ({_counts(elements)})", source=str(path))
    return vertices, triangles


def _ascii_elements(data: bytes, offset: int, elements, path: Path):
    """The vertices and triangles of an ASCII PLY body: whitespace-separated numbers, one
    element record after another (a face's list: its size, then that many indices)."""
    words = data[offset:].split()
    at = 0
    vertices = triangles = None
    for name, count, props in elements:
        lists = any(kind == "list" for _, kind, _ in props)  # a face's (`_ply_elements`)
        width = len(props) + (3 if lists else 0)  # a list: its size and three indices
        if at + width * count > len(words):
            raise InputError(f"the file ends after {len(words)} numbers, where its {count} "
                             f"{name!r} elements need {width * count} from number {at}: "
                             "truncated?", source=str(path))
        try:
            table = np.array(words[at:at + width * count], dtype=np.float64).reshape(count,
                                                                                      width)
        except ValueError:
            raise InputError(f"the {name!r} elements hold a word that is not a number",
                             source=str(path)) from None
        at += width * count
        columns, column = {}, 0
        for prop, kind, _ in props:
            if kind == "list":
                columns["#n"], columns["#i"] = table[:, column], table[:, column + 1:column + 4]
                column += 4
            else:
                columns[prop] = table[:, column]
                column += 1
        if name == "vertex":
            vertices = _vertex_columns(columns, path)
        elif name == "face":
            triangles = _face_indices(columns.get("#n"), columns.get("#i"), path)
    if at < len(words):
        # elements the header does not count (a count left too small) would be dropped
        raise InputError(f"the file goes on for {len(words) - at} numbers after its "
                         f"elements end at number {at}: expected as many elements as the "
                         f"header counts ({_counts(elements)})", source=str(path))
    return vertices, triangles


def _counts(elements) -> str:
    """'3 vertex, 1 face': the elements a PLY header counts."""
    return ", ".join(f"{count} {name}" for name, count, _ in elements)


def _vertex_columns(block, path: Path) -> np.ndarray:
    if not {"x", "y", "z"} <= set(block.dtype.names if hasattr(block, "dtype") else block):
        raise InputError("vertex element lacks x, y, z", source=str(path))
    return np.column_stack([np.asarray(block[c], dtype=np.float64) for c in "xyz"])


def _face_indices(sizes, indices, path: Path) -> np.ndarray:
    if sizes is None:
        raise InputError("expected faces with a list property (vertex_indices)",
                         source=str(path))
    if np.any(sizes != 3):
        first = int(np.flatnonzero(sizes != 3)[0])
        raise InputError(f"face {first} has {sizes[first]:g} vertices: only triangle faces "
                         "are supported (every face with 3 indices)", source=str(path))
    # an ASCII file's indices arrive as float64: one past int64 (1e30, inf) became
    # -9223372036854775808 when cast, and was named so. A binary file's integers (at most 32
    # bits, `_PLY_TYPES`) are whole and within it: not rounded to see (90 ms of a
    # 1.5-million-triangle part's 0.3 s)
    bad = (None if indices.dtype.kind in "iu" else
           (indices != np.round(indices)) | ~(np.abs(indices) < 2.0**62))
    if bad is not None and np.any(bad):
        first = int(np.flatnonzero(bad.any(axis=1))[0])
        shown = ", ".join(f"{value:g}" for value in indices[first])
        raise InputError(f"face {first} is [{shown}]: expected whole-number vertex indices",
                         source=str(path))
    return np.asarray(indices, dtype=np.int64).reshape(-1, 3)


def _check_length(data: bytes, offset: int, size: int, name: str, count: int,
                  path: Path) -> None:
    """Refuse a file that ends before the ``size`` bytes of its element ``name`` (a file cut
    short in a copy or a download)."""
    if offset + size > len(data):
        raise InputError(f"the file ends at byte {len(data)}, where its {count} {name!r} "
                         f"elements need bytes {offset} .. {offset + size}: truncated?",
                         source=str(path))


def triangle_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unnormalised outward normals (m^2, twice the area), shape (m, 3) float64."""
    corner = vertices[triangles]
    return np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])


def decimate(vertices, triangles, max_triangles: int = DISPLAY_TRIANGLES):
    """Fewer triangles for display by vertex clustering (display only: never measure on it).

    Vertices are merged per cubic cell (their mean), triangles whose corners fall in fewer than
    three cells vanish, duplicates are dropped. The cell is chosen from the surface area so
    that the result has at most ``max_triangles``; meshes already small enough come back
    unchanged but for the vertices no triangle uses. The result need not be manifold.

    Parameters
    ----------
    vertices : array-like, shape (n, 3), m
    triangles : array-like, shape (m, 3), int
    max_triangles : int

    Returns
    -------
    vertices : ndarray, shape (n', 3), float64
    triangles : ndarray, shape (m', 3), int64, m' <= max_triangles
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    if max_triangles < 1:
        raise InputError(f"max_triangles must be at least 1, got {max_triangles}")
    if len(triangles) <= max_triangles:
        return compact(vertices, triangles)
    area = 0.5 * np.linalg.norm(triangle_normals(vertices, triangles), axis=1).sum()
    lo = vertices.min(axis=0)
    # A clustered closed surface has about 2 triangles per occupied cell, A / h^2 cells.
    # (A mesh of zero area starts from its extent instead.)
    cell = np.sqrt(2.0 * area / max_triangles) or float(np.ptp(vertices, axis=0).max()) or 1.0
    while True:
        out_v, out_t = _cluster(vertices, triangles, lo, cell)
        if len(out_t) <= max_triangles:
            return out_v, out_t
        cell *= max(CELL_GROWTH, np.sqrt(len(out_t) / max_triangles))


def _cluster(vertices, triangles, lo, cell):
    cells = np.floor((vertices - lo) / cell).astype(np.int64)
    span = cells.max(axis=0) + 1
    key = (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]
    _, group = np.unique(key, return_inverse=True)
    counts = np.bincount(group).astype(np.float64)
    merged = np.column_stack(
        [np.bincount(group, weights=vertices[:, k]) / counts for k in range(3)])
    tri = group[triangles]
    keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])
    tri = tri[keep]
    # rotate each triangle to start at its smallest index, keeping its orientation
    start = np.argmin(tri, axis=1)
    rows = np.arange(len(tri))[:, None]
    tri = tri[rows, (start[:, None] + np.arange(3)) % 3]
    return compact(merged, np.unique(tri, axis=0))


def compact(vertices: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The same triangles over only the vertices they use (in their original order)."""
    used = np.zeros(len(vertices), dtype=bool)
    used[triangles.ravel()] = True
    remap = np.cumsum(used) - 1
    return vertices[used], remap[triangles]


def display_buffers(vertices, triangles) -> tuple[np.ndarray, np.ndarray]:
    """float32 positions and uint32 indices for WebGL: display only, after measuring."""
    return (np.ascontiguousarray(vertices, dtype=np.float32),  # display only
            np.ascontiguousarray(triangles, dtype=np.uint32))


def tool_mesh(tool) -> tuple[np.ndarray, np.ndarray]:
    """A solid to draw for a tool (tool_tip frame, m): the hull of its points.

    A V or round-nose profile has zero thickness; it is drawn 1/10 of its height thick along
    the cutting direction X, for display only.
    """
    points = np.asarray(tool.vertices(), dtype=np.float64)
    extent = np.ptp(points, axis=0)
    if extent[0] == 0.0:
        half = 0.05 * max(float(extent.max()), 1e-9)
        points = np.vstack([points + [half, 0.0, 0.0], points - [half, 0.0, 0.0]])
    mesh = manifold3d.Manifold.hull_points(points).to_mesh64()
    return (np.asarray(mesh.vert_properties[:, :3], dtype=np.float64),
            np.asarray(mesh.tri_verts, dtype=np.int64))


__all__ = ["DISPLAY_TRIANGLES", "closed_and_oriented", "compact", "decimate", "display_buffers",
           "ply_ascii", "ply_single_precision", "read_ply", "tool_mesh",
           "triangle_normals"]
