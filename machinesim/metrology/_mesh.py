"""The one way instruments read a surface: float64 vertices and int64 triangles, checked."""

from __future__ import annotations

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_floats, as_number, shown


def mesh_arrays(surface) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of whatever an instrument was pointed at.

    Parameters
    ----------
    surface : Part or MeshIndex or tuple of (array-like, array-like)
        Anything with a ``mesh()`` method returning ``(vertices, triangles)`` (a machined
        `machinesim.workpiece.Part`, a `machinesim.metrology.MeshIndex`), or the pair itself.

    Returns
    -------
    vertices : ndarray, shape (n, 3), float64
        Vertex positions in the workpiece frame, m. Finite.
    triangles : ndarray, shape (m, 3), int64
        Vertex indices, counter-clockwise seen from outside the solid.

    Raises
    ------
    InputError
        When the input is neither, or the arrays have the wrong shape, type or range.
    """
    if hasattr(surface, "mesh"):
        vertices, triangles = surface.mesh()
    elif isinstance(surface, tuple) and len(surface) == 2:
        vertices, triangles = surface
    else:
        raise InputError(
            "Expected a Part, a MeshIndex or a (vertices, triangles) tuple, "
            f"got {type(surface).__name__}"
        )
    try:
        vertices = np.asarray(vertices)
        triangles = np.asarray(triangles)
    except (TypeError, ValueError) as error:  # ragged nesting
        raise InputError(f"Expected vertices (n, 3) and triangles (m, 3) as regular arrays, "
                         f"got {shown(vertices)} and {shown(triangles)}") from error
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InputError(f"Expected vertices with shape (n, 3), got {vertices.shape}")
    if vertices.dtype != np.float64:
        # single precision would have rounded the measured geometry already: refuse, not widen
        raise InputError(f"Expected float64 vertices, got {vertices.dtype}")
    if not np.isfinite(vertices).all():
        raise InputError("Expected finite vertices, got NaN or infinity")
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        raise InputError(f"Expected triangles with shape (m, 3), got {triangles.shape}")
    if not np.issubdtype(triangles.dtype, np.integer):
        raise InputError(f"Expected integer triangle indices, got {triangles.dtype}")
    triangles = triangles.astype(np.int64, copy=False)
    if triangles.size and (triangles.min() < 0 or triangles.max() >= len(vertices)):
        raise InputError(
            f"Expected triangle indices in [0, {len(vertices) - 1}], "
            f"got [{triangles.min()}, {triangles.max()}]"
        )
    return vertices, triangles


def as_vector(value, length: int, name: str) -> np.ndarray:
    """A finite float64 copy of ``value`` with shape (``length``,), or an InputError naming it."""
    array = as_floats(value, name, f"{length} numbers")
    if array.shape != (length,):
        raise InputError(f"Expected {name} with shape ({length},), got {array.shape}", key=name)
    if not np.isfinite(array).all():
        raise InputError(f"Expected finite {name}, got {array}", key=name)
    return array


def as_positive(value, name: str) -> float:
    """``value`` as a float when finite and > 0, else an InputError naming it."""
    return as_number(value, name, sign="> 0")
