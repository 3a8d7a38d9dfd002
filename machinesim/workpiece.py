"""Stock and machined parts: immutable float64 manifold3d solids in the workpiece frame.

Stock conventions (workpiece frame, metres): a block L x W x H occupies x in [0, L],
y in [0, W], z in [-H, 0]; a cylinder has its axis on Z through the origin and its top face
at z = 0. A placement translates either. Specs are in mm: ``"block:10x10x2"``,
``"cylinder:5x2"`` (radius x height), ``"block:10x10x2@-5,-5,0"``,
``"spheres:30x30x5:2"`` (block with three reference spheres of radius 2 mm, seed 002 Fig. 4)
and ``"crown"`` (seed 002's roughly machined diamond crown, 10 um oversize).
"""

from __future__ import annotations

import math
import numbers
import os
import struct

import manifold3d
import numpy as np

from machinesim._io import write_atomic
from machinesim.exceptions import InputError, brief
from machinesim.tolerances import CYLINDER_CHORD_M, SPHERE_CHORD_M
from machinesim.tools import arc_segments, sphere_polygon
from machinesim.units import M_PER_MM, M_PER_UM, length_text


class Part:
    """A solid in its workpiece frame (metres), exact float64 mesh behind a manifold3d value.

    Never mutated: every operation returns a new `Part`. A part is made from a
    `manifold3d.Manifold`, or by a mesher that closes its mesh by construction (the
    height-field cutter, `machinesim.cutting.relief`); the latter builds its manifold only
    when `manifold` is first read, since importing a mesh of millions of triangles into
    manifold3d costs about a second per million and measuring never needs it.

    Parameters
    ----------
    manifold : manifold3d.Manifold
        The solid. A `Part` is refused (a part is never mutated: use it as it is), and so is
        a mesh (`from_mesh` takes one).

    Raises
    ------
    InputError
        If ``manifold`` is not a `manifold3d.Manifold`.
    """

    __slots__ = ("_manifold", "_vertices", "_triangles", "_volume", "reliefs")

    def __init__(self, manifold: manifold3d.Manifold) -> None:
        if not isinstance(manifold, manifold3d.Manifold):
            hint = (" (a part is never mutated: use it as it is, or Part(part.manifold))"
                    if isinstance(manifold, Part) else
                    " (a mesh: Part.from_mesh(vertices, triangles))")
            raise InputError("Expected the solid as a manifold3d.Manifold, got "
                             f"{type(manifold).__name__}{hint}", key="manifold")
        self._manifold = manifold
        self._vertices = None
        self._triangles = None
        self._volume = None
        #: Height-field description of the part, when it has one (private to the cutter).
        self.reliefs = None

    @classmethod
    def _closed(cls, vertices: np.ndarray, triangles: np.ndarray, reliefs=None,
                volume: float | None = None) -> Part:
        """Part from a mesh that is closed and oriented by construction (not re-checked).

        ``volume`` (m^3), when the mesher knows it, spares summing over every triangle.
        """
        part = cls.__new__(cls)
        part._manifold = None
        part._volume = volume
        part._vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        part._triangles = np.ascontiguousarray(triangles, dtype=np.int64)
        part._vertices.flags.writeable = False
        part._triangles.flags.writeable = False
        part.reliefs = reliefs
        return part

    def __reduce__(self):
        """A part pickles as its exact float64 mesh (`mesh`; a manifold3d value does not
        pickle) and its volume, and comes back a meshed part of that volume, its manifold
        built when first read."""
        vertices, triangles = self.mesh()
        return _unpickle_part, (vertices, triangles, self.reliefs, self.volume)

    @property
    def manifold(self) -> manifold3d.Manifold:
        """The solid as a `manifold3d.Manifold` (built on first use for a meshed part)."""
        if self._manifold is None:
            mesh = manifold3d.Mesh64(
                vert_properties=np.array(self._vertices, order="C"),
                tri_verts=np.array(self._triangles, dtype=np.uint64, order="C"),
            )
            manifold = manifold3d.Manifold(mesh)
            if manifold.status() != manifold3d.Error.NoError:
                raise RuntimeError(f"meshed part is not a closed 2-manifold: {manifold.status()}")
            self._manifold = manifold
        return self._manifold

    @property
    def triangle_count(self) -> int:
        """How many triangles the part's mesh has."""
        return len(self._triangles) if self._manifold is None else self._manifold.num_tri()

    def __repr__(self) -> str:
        low, high = self.bounds
        return (f"Part({self.triangle_count} triangles, bounds {low.tolist()} .. "
                f"{high.tolist()} m, "
                f"volume {self.volume:.6g} m^3)")

    @classmethod
    def from_mesh(cls, vertices, triangles) -> Part:
        """Part from a closed, oriented triangle mesh.

        Parameters
        ----------
        vertices : array-like, shape (n, 3)
            Vertex positions (m), float64.
        triangles : array-like, shape (m, 3)
            Vertex indices, counter-clockwise seen from outside.

        Raises
        ------
        InputError
            If the arrays have the wrong shape, the mesh is not a closed 2-manifold, or it is
            inside out (wound clockwise seen from outside: a negative volume).
        """
        # manifold3d accepts only writeable C arrays: copy, which also detaches the caller's.
        vertices = np.array(vertices, dtype=np.float64, order="C")
        triangles = np.array(triangles, order="C")
        if vertices.ndim != 2 or vertices.shape[1] != 3 or not np.all(np.isfinite(vertices)):
            raise InputError(f"expected finite vertices of shape (n, 3), got {vertices.shape}")
        if triangles.ndim != 2 or triangles.shape[1] != 3:
            raise InputError(f"expected triangles of shape (m, 3), got {triangles.shape}")
        if triangles.size and (triangles.min() < 0 or triangles.max() >= len(vertices)):
            raise InputError(
                f"triangle indices must lie in [0, {len(vertices)}), got "
                f"[{triangles.min()}, {triangles.max()}]"
            )
        mesh = manifold3d.Mesh64(
            vert_properties=vertices,
            tri_verts=np.array(triangles, dtype=np.uint64, order="C"),
        )
        manifold = manifold3d.Manifold(mesh)
        if manifold.status() != manifold3d.Error.NoError:
            raise InputError(f"mesh is not a closed oriented 2-manifold: {manifold.status()}")
        # inside out, every instrument would read the bottom face as the top surface
        if manifold.volume() < 0.0:
            raise InputError(f"mesh is inside out: it encloses {manifold.volume():.6g} m^3; "
                             "expected triangles counter-clockwise seen from outside "
                             "(reverse each triangle's vertex order)")
        return cls(manifold)

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertices, shape (n, 3) float64 in m, and triangles, shape (m, 3) int64."""
        if self._vertices is not None:
            return self._vertices, self._triangles
        mesh = self.manifold.to_mesh64()
        vertices = np.ascontiguousarray(mesh.vert_properties[:, :3], dtype=np.float64)
        triangles = np.ascontiguousarray(mesh.tri_verts, dtype=np.int64)
        return vertices, triangles

    @property
    def volume(self) -> float:
        """Volume in m^3."""
        if self._volume is None:
            if self._manifold is None:
                self._volume = mesh_volume(self._vertices, self._triangles)
            else:
                self._volume = float(self._manifold.volume())
        return self._volume

    @property
    def bounds(self) -> np.ndarray:
        """Axis-aligned bounds, shape (2, 3) (m): row 0 the minimum corner, row 1 the maximum."""
        if self._manifold is None:
            box = np.stack([self._vertices.min(axis=0), self._vertices.max(axis=0)])
        else:
            box = np.array(self._manifold.bounding_box(), dtype=np.float64).reshape(2, 3)
        box.flags.writeable = False
        return box

    def encode(self, file_format: str) -> bytes:
        """The part as the bytes of a ``"ply"``, ``"stl"`` or ``"glb"`` file.

        PLY keeps the float64 vertices in metres, exact bit for bit. STL and GLB store
        float32 (display only) in millimetres, the unit CAD tools assume for STL; the
        coordinates are scaled in float64 and rounded to float32 once. Each file states its
        unit: the PLY and STL headers, the glTF ``asset.extras``. `EXPORT_UNITS` lists them.
        """
        encoders = {"ply": self._ply_bytes, "stl": self._stl_bytes, "glb": self._glb_bytes}
        key = str(file_format).lower().lstrip(".")
        if key not in encoders:
            raise InputError(f"unknown part file format {file_format!r}; expected one of "
                             f"{', '.join(encoders)}", key="format")
        return encoders[key]()

    def export_ply(self, path) -> None:
        """Write a binary little-endian PLY with float64 vertices in metres: exact, bit for bit.

        ``path`` ends in ``.ply`` (any case); one ending otherwise is refused (`_check_suffix`).
        """
        _check_suffix(path, "ply")
        write_atomic(path, self._ply_bytes())

    def export_stl(self, path) -> None:
        """Write a binary STL in millimetres. The format stores float32: for display only.

        ``path`` ends in ``.stl`` (any case).
        """
        _check_suffix(path, "stl")
        write_atomic(path, self._stl_bytes())

    def export_glb(self, path) -> None:
        """Write a binary glTF in millimetres (float32 inside, via trimesh): for display only.

        ``path`` ends in ``.glb`` (any case).
        """
        _check_suffix(path, "glb")
        write_atomic(path, self._glb_bytes())

    def _ply_bytes(self) -> bytes:
        vertices, triangles = self.mesh()
        header = (
            "ply\nformat binary_little_endian 1.0\ncomment machinesim part, metres\n"
            f"element vertex {len(vertices)}\n"
            "property double x\nproperty double y\nproperty double z\n"
            f"element face {len(triangles)}\n"
            "property list uchar int vertex_indices\nend_header\n"
        ).encode("ascii")
        faces = np.zeros(len(triangles), dtype=[("n", "u1"), ("i", "<i4", 3)])
        faces["n"] = 3
        faces["i"] = triangles
        return header + np.ascontiguousarray(vertices, dtype="<f8").tobytes() + faces.tobytes()

    def _stl_bytes(self) -> bytes:
        vertices, triangles = self.mesh()
        corner = (vertices / M_PER_MM)[triangles]
        normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
        length = np.linalg.norm(normal, axis=1, keepdims=True)
        normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
        record = np.zeros(len(triangles), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                                  ("a", "<u2")])
        record["n"] = normal
        record["v"] = corner
        return _STL_HEADER + struct.pack("<I", len(triangles)) + record.tobytes()

    def _glb_bytes(self) -> bytes:
        import trimesh

        vertices, triangles = self.mesh()

        def state_unit(tree: dict) -> None:
            tree.setdefault("asset", {})["extras"] = {"unit": "mm", "note": _GLB_NOTE}

        mesh = trimesh.Trimesh(vertices / M_PER_MM, triangles, process=False)
        return trimesh.exchange.gltf.export_glb(trimesh.Scene(mesh),
                                                tree_postprocessor=state_unit)


#: What each export format is, for a message (`_check_suffix`).
_FORMAT_TEXT = {"ply": "a PLY file (float64, metres: exact)",
                "stl": "a binary STL (float32, millimetres: display only)",
                "glb": "a binary glTF (float32, millimetres: display only)"}


def _check_suffix(path, file_format: str) -> None:
    """Refuse a ``path`` not ending in ``.<file_format>`` (any case): export_ply("part.stl")
    wrote PLY bytes under an STL's name without a word, which an STL reader then failed on or
    misread. The message names the export that writes what the ending asks, if one does."""
    if not isinstance(path, (str, os.PathLike)) or isinstance(os.fspath(path), bytes):
        return  # not a path: write_atomic says so
    name = os.fspath(path)
    suffix = os.path.splitext(name)[1].lower().lstrip(".")
    if suffix == file_format:
        return
    meant = (f"; for {_FORMAT_TEXT[suffix]} call Part.export_{suffix}" if suffix in _FORMAT_TEXT
             else "")
    ending = f"ends in .{os.path.splitext(name)[1][1:]}" if suffix else "has no ending"
    raise InputError(f"Part.export_{file_format} writes {_FORMAT_TEXT[file_format]}, and the "
                     f"path {ending}: expected a name ending in .{file_format}{meant}",
                     source=name, key="path")


#: Triangles summed at once by `mesh_volume`: its temporaries stay a few MB.
VOLUME_CHUNK = 65536
#: Unit of the coordinates each export format holds (`Part.encode`).
EXPORT_UNITS = {"ply": "m", "stl": "mm", "glb": "mm"}
_STL_HEADER = b"machinesim part, binary STL, units: mm (float32: display only)".ljust(80, b" ")
_GLB_NOTE = ("machinesim part in millimetres, as CAD tools read STL; float32: display only "
             "(the exact float64 part in metres is the PLY export)")


def _unpickle_part(vertices, triangles, reliefs, volume) -> Part:
    """A pickled `Part` (`Part.__reduce__`): its mesh, read-only again."""
    return Part._closed(vertices, triangles, reliefs, volume)


def mesh_volume(vertices: np.ndarray, triangles: np.ndarray,
                chunk: int = VOLUME_CHUNK) -> float:
    """Volume (m^3) enclosed by a closed triangle mesh (divergence theorem): negative when it
    is wound inside out (clockwise seen from outside).

    Tetrahedra are taken from the centre of the bounds, not the origin, so that a small part
    far from the origin does not lose digits to cancellation; they are summed ``chunk``
    triangles at a time, by components (a 3-million-triangle part in 0.3 s, where one pass
    through (m, 3, 3) temporaries and np.cross took 1 s). The bounds and the centring are
    taken on the coordinates' columns: numpy's min and max along the 3-wide rows of an
    (n, 3) array took 50 ms of a 1.5-million-triangle part's 160 ms, the columns 2 ms, for
    the same numbers bit for bit.
    """
    if len(triangles) == 0:
        return 0.0
    x, y, z = np.asarray(vertices, dtype=np.float64).T.copy()
    for column in (x, y, z):
        column -= (column.min() + column.max()) / 2.0
    total = 0.0
    for start in range(0, len(triangles), chunk):
        a, b, c = np.asarray(triangles[start:start + chunk]).T
        total += float(np.sum(x[a] * (y[b] * z[c] - z[b] * y[c])
                              + y[a] * (z[b] * x[c] - x[b] * z[c])
                              + z[a] * (x[b] * y[c] - y[b] * x[c])))
    return total / 6.0


def _sizes(kind: str, form: str, **sizes) -> list[float]:
    """A solid's sizes (m) as floats, refusing what is no number, naming it: cylinder("5", 2)
    ended in "TypeError: must be real number, not str", and True read as 1 m. ``form`` is the
    stock spec of the solid, which takes its sizes in mm as text."""
    values = []
    for name, value in sizes.items():
        if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
            value = value.item()
        if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
            spec = (f"; a size written as text, in mm, is read by stock_from_spec('{form}')"
                    if isinstance(value, str) else "")
            raise InputError(f"{kind} {name} must be a number in m, got {brief(repr(value))} "
                             f"({type(value).__name__}){spec}", key=name)
        values.append(float(value))
    return values


def block(length: float, width: float, height: float, origin=(0.0, 0.0, 0.0)) -> Part:
    """Block occupying [0, L] x [0, W] x [-H, 0] (m), translated by ``origin`` (m)."""
    length, width, height = _sizes("block", "block:LxWxH", length=length, width=width,
                                   height=height)
    for name, value in (("length", length), ("width", width), ("height", height)):
        if not math.isfinite(value) or value <= 0.0:
            raise InputError(f"block {name} must be positive, got {length_text(value)}",
                             key=name)
    solid = manifold3d.Manifold.cube((length, width, height)).translate((0.0, 0.0, -height))
    return Part(solid.translate(tuple(float(v) for v in origin)))


def cylinder(radius: float, height: float, origin=(0.0, 0.0, 0.0),
             chord_tol: float = CYLINDER_CHORD_M) -> Part:
    """Cylinder about Z through ``origin``, top face at z = origin z, radius and height in m.

    The circle is an inscribed polygon whose sagitta is at most ``chord_tol`` (m).
    """
    radius, height = _sizes("cylinder", "cylinder:RxH", radius=radius, height=height)
    for name, value in (("radius", radius), ("height", height)):
        if not math.isfinite(value) or value <= 0.0:
            raise InputError(f"cylinder {name} must be positive, got {length_text(value)}",
                             key=name)
    segments = arc_segments(radius, 2.0 * math.pi, chord_tol)
    solid = manifold3d.Manifold.cylinder(height, radius, radius, segments)
    return Part(solid.translate((float(origin[0]), float(origin[1]), float(origin[2]) - height)))


def block_with_spheres(length: float, width: float, height: float, radius: float,
                       centres=None, dimples: bool = False,
                       chord_tol: float = SPHERE_CHORD_M) -> Part:
    """Block with three reference spheres on its top face (seed 002, Fig. 4), all in m.

    Parameters
    ----------
    length, width, height : float
        Block size; the block occupies [0, L] x [0, W] x [-H, 0].
    radius : float
        Sphere radius.
    centres : array-like, shape (3, 2), optional
        (x, y) of the sphere centres S1, S2, S3 on the plane z = 0. Default: three corners,
        2 R in from the edges, so that S1->S2 runs along +X and S1->S3 along +Y (the
        workpiece axes of seed 002, Fig. 5a).
    dimples : bool
        False: hemispherical bumps above the top face. True: hemispherical cavities (seed
        002 cuts its spheres with a ball end mill and finds the centre above the bottom point,
        which fits a cavity).
    chord_tol : float
        Largest facet depth of the sphere polygon.
    """
    radius, = _sizes("sphere", "spheres:LxWxH:R", radius=radius)
    stock = block(length, width, height).manifold
    if radius <= 0.0 or 4.0 * radius >= min(length, width):
        raise InputError(
            f"sphere radius must be positive and below a quarter of the block's smaller side, "
            f"{length_text(min(length, width) / 4)}, got {length_text(radius)}",
            key="radius",
        )
    if centres is None:
        inset = 2.0 * radius
        centres = [(inset, inset), (length - inset, inset), (inset, width - inset)]
    centres = np.asarray(centres, dtype=np.float64)
    if centres.shape != (3, 2):
        raise InputError(f"expected three (x, y) sphere centres, got shape {centres.shape}")
    sphere = sphere_polygon(radius, chord_tol)
    spheres = manifold3d.Manifold.batch_boolean(
        [sphere.translate((float(x), float(y), 0.0)) for x, y in centres], manifold3d.OpType.Add
    )
    return Part(stock - spheres if dimples else stock + spheres)


def diamond_crown(oversize: float = 10.0 * M_PER_UM, top_across_flats: float = 4.0 * M_PER_MM,
                  crown_height: float = 0.2 * M_PER_MM, base_size: float = 10.0 * M_PER_MM,
                  base_height: float = 3.0 * M_PER_MM,
                  slope: float = math.atan(0.2)) -> Part:
    """Seed 002's diamond crown (section 3.2), roughly machined ``oversize`` larger (m, rad).

    Fig. 9 of the paper is missing; these dimensions follow its text: one top face and
    eight side faces sloped at 11.31 deg (tan = 0.2, ``slope``) facing C = 0, 45, ..., 315
    deg, opposite edges parallel in pairs (L1/L5 ... L4/L8). The target is a regular
    octagonal frustum, top face 4 mm across flats at z = 0, 0.2 mm high (so each side face
    runs 1 mm horizontally, one laser-microscope field), standing on a flat at z = -0.2 mm
    of a 10 x 10 mm base, 3 mm thick, centred on the C axis (x = y = 0). The rough part is
    that shape with every machined face (top, eight sides, flat) moved out by ``oversize``
    along its normal; the finishing cut then removes ``oversize`` (seed 002 Table 2: 10 um).
    """
    normal_xy = math.sin(slope)
    normal_z = math.cos(slope)
    top_z = oversize
    flat_z = -crown_height + oversize
    bottom_z = -crown_height - base_height
    # Side plane k: normal (sin(slope) u_k, cos(slope)) . p = apothem_top * sin(slope) + d.
    offset = 0.5 * top_across_flats * normal_xy + oversize

    def apothem(z: float) -> float:
        return (offset - z * normal_z) / normal_xy

    corners = []
    # The frustum reaches half its height into the base so the union meets it in clean lines.
    for z in (top_z, flat_z - 0.5 * crown_height):
        circum = apothem(z) / math.cos(math.pi / 8.0)
        for k in range(8):
            angle = (k + 0.5) * math.pi / 4.0
            corners.append((circum * math.cos(angle), circum * math.sin(angle), z))
    frustum = manifold3d.Manifold.hull_points(np.array(corners))
    base = manifold3d.Manifold.cube((base_size, base_size, flat_z - bottom_z), center=True)
    base = base.translate((0.0, 0.0, 0.5 * (flat_z + bottom_z)))
    return Part(base + frustum)


_STOCK_FORMS = (
    "'block:LxWxH', 'cylinder:RxH', 'spheres:LxWxH:R', 'spheres:LxWxH:R:dimples', "
    "'crown' or 'crown:OVERSIZE' (mm), each optionally followed by '@x,y,z' (mm); a number "
    "may end in 'mm' ('block:10x10x2mm')"
)


#: Range of a size in a stock spec (mm): from 1 nm (below it float64 squares of the size
#: underflow: a cylinder of radius 1e-200 mm has volume 0) to 10 m, twenty times the largest
#: machine travel (beyond it a 1 nm chord polygon needs billions of vertices). Placements
#: stay within +-10 m too: 1e300 + 1 == 1e300 would swallow the part's own size.
STOCK_SIZE_MM = (1e-6, 1e4)


def _numbers(where: str, text: str, count: int, separator: str,
             sizes: bool = True) -> list[float]:
    """``count`` numbers of ``text`` between ``separator``s; ``where`` (the spec as the
    caller names it) begins a refusal."""
    # a number may end in mm, as every size of a tool spec may ('block:10x10x2mm')
    fields = [f.strip()[:-2] if f.strip().lower().endswith("mm") else f
              for f in text.split(separator)]
    try:
        values = [float(field) for field in fields]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InputError(
            f"{where}: expected {count} numbers separated by {separator!r} in "
            f"{text!r}; forms: {_STOCK_FORMS}")
    low, high = STOCK_SIZE_MM
    if sizes and not all(low <= v <= high for v in values):
        raise InputError(f"{where}: sizes {text!r} must lie in {low:g} .. {high:g} mm")
    if not sizes and not all(abs(v) <= high for v in values):
        raise InputError(f"{where}: placement {text!r} must lie within +-{high:g} mm")
    return values


def stock_from_spec(spec: str, *, name: str = "stock spec") -> Part:
    """Build stock from a text spec in mm (see the module docstring for the forms).

    ``name`` is what a refusal calls the spec: ``"--stock"`` on the command line, so that
    it reads ``--stock 'block:10x10': expected 3 numbers ...``.

    Raises
    ------
    InputError
        Naming the spec once and the expected forms when it cannot be read.
    """
    where = f"{name} {brief(str(spec))!r}"
    text = str(spec).strip()
    body, at, placement = text.partition("@")
    # an '@' with nothing after it (a shell's '@$POS' with POS unset) is refused, not read
    # as no placement: the stock would stand at the origin where it was meant elsewhere
    origin = (
        [v * M_PER_MM for v in _numbers(where, placement, 3, ",", sizes=False)] if at
        else [0.0] * 3
    )
    fields = body.split(":")
    kind = fields[0].lower()
    try:
        if kind == "block" and len(fields) == 2:
            size = [v * M_PER_MM for v in _numbers(where, fields[1], 3, "x")]
            return block(*size, origin=origin)
        if kind == "cylinder" and len(fields) == 2:
            radius, height = (v * M_PER_MM for v in _numbers(where, fields[1], 2, "x"))
            return cylinder(radius, height, origin=origin)
        if kind == "spheres" and len(fields) in (3, 4):
            size = [v * M_PER_MM for v in _numbers(where, fields[1], 3, "x")]
            radius = _numbers(where, fields[2], 1, ",")[0] * M_PER_MM
            if len(fields) == 4 and fields[3].lower() != "dimples":
                raise InputError(f"{where}: expected 'dimples', got {fields[3]!r}")
            part = block_with_spheres(*size, radius, dimples=len(fields) == 4)
            return Part(part.manifold.translate(tuple(origin)))
        if kind == "crown" and len(fields) in (1, 2):
            oversize = (
                _numbers(where, fields[1], 1, ",", sizes=False)[0] * M_PER_MM
                if len(fields) == 2 else 10.0 * M_PER_UM
            )
            if not 0.0 <= oversize <= 1.0 * M_PER_MM:
                raise InputError(f"{where}: crown oversize must lie in 0 .. 1 mm, "
                                 f"got {length_text(oversize)}")
            return Part(diamond_crown(oversize).manifold.translate(tuple(origin)))
    except InputError as error:
        if error.message.startswith(where):
            raise
        # a size the solid refuses names itself (radius, ...): not again as a key
        raise InputError(f"{where}: {error.message}") from None
    raise InputError(f"{where}: expected {_STOCK_FORMS}")


__all__ = [
    "CYLINDER_CHORD_M",
    "EXPORT_UNITS",
    "STOCK_SIZE_MM",
    "SPHERE_CHORD_M",
    "Part",
    "block",
    "block_with_spheres",
    "cylinder",
    "diamond_crown",
    "stock_from_spec",
]
