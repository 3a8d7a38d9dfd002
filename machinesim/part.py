"""A machined or stock solid: `Part`, an immutable float64 manifold3d solid in the workpiece
frame (metres), its exact mesh and volume (`mesh_volume`), and its files (PLY exact in metres;
STL and glTF in mm for display). The stock it starts from is made in `machinesim.workpiece`.
"""

from __future__ import annotations

import os
import struct
import warnings

import manifold3d
import numpy as np

from machinesim._io import write_atomic
from machinesim.exceptions import InputError, MachineSimWarning
from machinesim.units import M_PER_MM

#: A part this large (m) in any direction is noted as perhaps in millimetres: meshes are read
#: as metres, and no shipped machine travels more than 0.5 m on an axis, so a part of a
#: millimetre or more written in millimetres (1000 times too large) measures 1 m or more.
#: A note, not a refusal: metre-class optics are diamond turned on machines of one's own.
UNIT_SLIP_SIZE_M = 1.0


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

        Warns
        -----
        MachineSimWarning
            If the part measures `UNIT_SLIP_SIZE_M` or more in x, y or z: perhaps a mesh in
            millimetres (STL's convention) read as metres.
        """
        from machinesim.metrology._arrays import as_floats, shown

        # manifold3d accepts only writeable C arrays: copy, which also detaches the caller's.
        # Numbers only: a path given for the vertices had raised numpy's ValueError.
        vertices = np.ascontiguousarray(as_floats(vertices, "vertices", "coordinates (m)"))
        triangles = np.array(as_floats(triangles, "triangles", "vertex indices"), order="C")
        if vertices.ndim != 2 or vertices.shape[1] != 3 or not np.all(np.isfinite(vertices)):
            raise InputError(f"expected finite vertices of shape (n, 3), got {vertices.shape}",
                             key="vertices")
        if triangles.ndim != 2 or triangles.shape[1] != 3 or not len(triangles):
            # none: an empty mesh had ended in numpy's "zero-size array to reduction"
            raise InputError(f"expected triangles of shape (m, 3), m >= 4 for a closed solid, "
                             f"got {triangles.shape}", key="triangles")
        if not np.all(np.isfinite(triangles) & (triangles == np.round(triangles))):
            raise InputError(f"expected whole vertex indices, got {shown(triangles.tolist())}",
                             key="triangles")  # 1.5 had been cast to index 1
        triangles = triangles.astype(np.int64)
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
        size = np.ptp(vertices, axis=0)
        if size.max() >= UNIT_SLIP_SIZE_M:
            warnings.warn(f"the mesh measures {size[0]:.6g} x {size[1]:.6g} x {size[2]:.6g} m, "
                          "larger than any shipped machine's travel (0.5 m at most): "
                          "vertices are read as metres; was it written in millimetres (as STL is)?",
                          MachineSimWarning, stacklevel=2)
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

__all__ = ["EXPORT_UNITS", "VOLUME_CHUNK", "Part", "mesh_volume"]
