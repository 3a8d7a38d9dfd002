"""Colour maps of a part's top surface: deviation from a nominal part, or height.

The values are exact: `machinesim.metrology.height_map` evaluates the float64 meshes at the
grid nodes, and those nodes are the vertices of the coloured surface that is drawn. Only the
grid spacing (the display resolution) and the float32 buffers are display choices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology.surface import grid_heights
from machinesim.viewer.meshes import DISPLAY_TRIANGLES
from machinesim.workpiece import Part

#: ColorBrewer PRGn, 11 classes: purple below nominal (material missing), green above
#: (material left). Neither hue appears on the machines' URDF materials.
DIVERGING = np.array([
    (0x40, 0x00, 0x4B), (0x76, 0x2A, 0x83), (0x99, 0x70, 0xAB), (0xC2, 0xA5, 0xCF),
    (0xE7, 0xD4, 0xE8), (0xF7, 0xF7, 0xF7), (0xD9, 0xF0, 0xD3), (0xA6, 0xDB, 0xA0),
    (0x5A, 0xAE, 0x61), (0x1B, 0x78, 0x37), (0x00, 0x44, 0x1B)]) / 255.0
#: Viridis, sampled at 10 stops: heights, low (dark purple) to high (yellow).
SEQUENTIAL = np.array([
    (0x44, 0x01, 0x54), (0x48, 0x28, 0x78), (0x3E, 0x49, 0x89), (0x31, 0x68, 0x8E),
    (0x26, 0x82, 0x8E), (0x1F, 0x9E, 0x89), (0x35, 0xB7, 0x79), (0x6E, 0xCE, 0x58),
    (0xB5, 0xDE, 0x2B), (0xFD, 0xE7, 0x25)]) / 255.0
#: Colour of nodes where the nominal part has no surface (no deviation defined).
NO_DATA = np.array([0.5, 0.5, 0.5])
#: Half range (m) used when every deviation is zero, so the legend still has a scale: 1 nm,
#: the axis resolution of the machines.
MIN_HALF_RANGE_M = 1e-9
#: The grid's outer nodes stand this share of the part's largest coordinate (or of its
#: extent, when larger) inside its bounds (`grid_for`). On the bounds they lie on the
#: part's side faces, which a cut leaves a few ulps off vertical: a side face's vertex at
#: x = 10 mm - 1.7e-18 m ended the top's triangles short of the rim node, which read the
#: leaning face's plane instead, 3.04 mm down a 5 mm block beside a floor 0.15 mm deep (a
#: G18 dip run off the block's edge). 1e-13 is some 450 ulps of the coordinate: clear of
#: such a lean, and 2e-16 m on a 2 mm part, far below anything the map draws.
RIM_INSET = 1e-13


#: Where a legend's ticks stand along its colour bar, 0 (bottom) to 1 (top).
TICKS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: A tick within this fraction of the bar's span of zero is labelled zero: the labels show
#: 4 digits, so anything below 1e-6 of the span is round-off of the range's ends.
TICK_ZERO = 1e-6
#: A legend's figure (P-V, RMS) below this, m, reads 0: 1 pm, the resolution of machinesim's
#: geometry (`machinesim.tolerances.POSE_M`, a pose's position; the cut's sheets are trimmed
#: at 1 pm), below which two surfaces differ by round-off alone. A part and its nominal the
#: same but for that had read 'P-V 2.745e-09 nm', a figure of 2.7e-18 m.
FIGURE_ZERO_M = 1e-12


@dataclass(frozen=True)
class SurfaceMap:
    """Top-surface heights of a part on a grid, and the values it is coloured by.

    Attributes
    ----------
    x : ndarray, shape (nx,)
        Grid x coordinates, workpiece frame, m.
    y : ndarray, shape (ny,)
        Grid y coordinates, m.
    heights : ndarray, shape (ny, nx)
        Top surface of the part, m; NaN off the part.
    values : ndarray, shape (ny, nx)
        ``kind == "deviation"``: part minus nominal height, m (NaN where either is missing);
        ``kind == "height"``: the heights again.
    kind : {"deviation", "height"}
    """

    x: np.ndarray
    y: np.ndarray
    heights: np.ndarray
    values: np.ndarray
    kind: str

    @property
    def peak_to_valley(self) -> float:
        """Largest minus smallest value, m (NaN if there is none)."""
        v = self.values[np.isfinite(self.values)]
        return float(v.max() - v.min()) if v.size else math.nan

    @property
    def rms(self) -> float:
        """Root mean square of the values, m (NaN if there is none)."""
        v = self.values[np.isfinite(self.values)]
        return float(np.sqrt(np.mean(v * v))) if v.size else math.nan

    def value_range(self) -> tuple[float, float]:
        """The range the colour scale spans, m: symmetric about 0 for a deviation."""
        v = self.values[np.isfinite(self.values)]
        if self.kind == "deviation":
            half = max(float(np.abs(v).max()) if v.size else 0.0, MIN_HALF_RANGE_M)
            return -half, half
        lo, hi = (float(v.min()), float(v.max())) if v.size else (0.0, 0.0)
        if hi - lo < 2 * MIN_HALF_RANGE_M:
            mid = 0.5 * (lo + hi)
            return mid - MIN_HALF_RANGE_M, mid + MIN_HALF_RANGE_M
        return lo, hi


def mesh_of(surface) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 3) float64 m, triangles (m, 3) int64) of a Part or a mesh tuple."""
    if isinstance(surface, Part):
        return surface.mesh()
    try:
        vertices, triangles = surface
    except (TypeError, ValueError):
        raise InputError(f"expected a Part or a (vertices, triangles) tuple, got "
                         f"{type(surface).__name__}") from None
    return np.asarray(vertices, dtype=np.float64), np.asarray(triangles, dtype=np.int64)


def grid_for(bounds, max_triangles: int = DISPLAY_TRIANGLES) -> tuple[np.ndarray, np.ndarray]:
    """Square-celled grid over ``bounds`` ((2, 2) or (2, 3), m) with at most ``max_triangles``.

    The grid's outer nodes stand `RIM_INSET` inside the bounds' edges, so a rectangular part
    is covered to its rim and they read its top there, not its side faces.
    """
    lo, hi = np.asarray(bounds, dtype=np.float64)[:, :2]
    size = hi - lo
    if not np.all(size > 0.0):
        raise InputError(f"the part has no extent in x or y: bounds {lo.tolist()} .. "
                         f"{hi.tolist()} m")
    inset = RIM_INSET * np.maximum(np.maximum(np.abs(lo), np.abs(hi)), size)
    lo, hi = lo + inset, hi - inset
    size = hi - lo
    cells = max(max_triangles // 2, 1)
    spacing = math.sqrt(size[0] * size[1] / cells)
    nx, ny = (max(int(s / spacing), 1) for s in size)
    while nx * ny > cells:
        nx, ny = max(nx - 1, 1), max(ny - 1, 1)
    return np.linspace(lo[0], hi[0], nx + 1), np.linspace(lo[1], hi[1], ny + 1)


def surface_map(surface, nominal=None, max_triangles: int = DISPLAY_TRIANGLES) -> SurfaceMap:
    """Heights of ``surface`` on a display grid, and its deviation from ``nominal`` if given.

    Parameters
    ----------
    surface : Part or tuple of (array-like, array-like)
        The measured (machined) part, workpiece frame, m.
    nominal : Part or tuple, optional
        The part the program should have made, in the same frame.
    max_triangles : int
        The coloured grid has at most this many triangles (the display resolution).
    """
    vertices, triangles = mesh_of(surface)
    if len(vertices) == 0:
        raise InputError("the part has no vertices")
    bounds = np.array([vertices.min(axis=0), vertices.max(axis=0)])
    x, y = grid_for(bounds, max_triangles)
    # `height_map` refuses a map that reads nothing; the scene shows it, with a warning why
    heights = grid_heights((vertices, triangles), x, y)
    if nominal is None:
        return SurfaceMap(x, y, heights, heights, "height")
    values = heights - grid_heights(mesh_of(nominal), x, y)
    values.setflags(write=False)
    return SurfaceMap(x, y, heights, values, "deviation")


def colours(values, lo: float, hi: float, stops: np.ndarray) -> np.ndarray:
    """RGB in [0, 1], shape values.shape + (3,), by linear interpolation between ``stops``.

    Values outside [lo, hi] take the end colours; NaN takes `NO_DATA`.
    """
    values = np.asarray(values, dtype=np.float64)
    t = np.clip((values - lo) / (hi - lo), 0.0, 1.0)
    where = np.nan_to_num(t, nan=0.0) * (len(stops) - 1)
    k = np.minimum(where.astype(np.int64), len(stops) - 2)
    frac = (where - k)[..., None]
    rgb = stops[k] * (1.0 - frac) + stops[k + 1] * frac
    rgb[np.isnan(values)] = NO_DATA
    return rgb


def stops_for(kind: str) -> np.ndarray:
    """The colour stops of a map kind."""
    return DIVERGING if kind == "deviation" else SEQUENTIAL


def map_mesh(smap: SurfaceMap) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The coloured surface to draw: grid nodes at the part's heights, two triangles per cell.

    Returns
    -------
    vertices : ndarray, shape (nx * ny, 3), float64, m
    triangles : ndarray, shape (k, 3), int64, counter-clockwise seen from above; cells with
        a corner off the part are left out
    rgb : ndarray, shape (nx * ny, 3), colours in [0, 1]
    """
    gx, gy = np.meshgrid(smap.x, smap.y)
    z = smap.heights
    vertices = np.column_stack([gx.ravel(), gy.ravel(), np.nan_to_num(z).ravel()])
    nx = len(smap.x)
    j, i = np.mgrid[0:len(smap.y) - 1, 0:nx - 1]
    a = (j * nx + i).ravel()
    b, c, d = a + 1, a + nx + 1, a + nx
    finite = np.isfinite(z).ravel()
    keep = finite[a] & finite[b] & finite[c] & finite[d]
    a, b, c, d = a[keep], b[keep], c[keep], d[keep]
    triangles = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    lo, hi = smap.value_range()
    rgb = colours(smap.values.ravel(), lo, hi, stops_for(smap.kind))
    return vertices, triangles, rgb


@dataclass(frozen=True)
class Legend:
    """A colour bar and a few lines of text, drawn over the 3D view.

    Attributes
    ----------
    title : str
    stops : ndarray, shape (k, 3)
        Colours from the bottom (low) to the top (high) of the bar, in [0, 1].
    ticks : tuple of (float, str)
        Position along the bar (0 bottom, 1 top) and label, unit included.
    notes : tuple of str
    """

    title: str
    stops: np.ndarray
    ticks: tuple[tuple[float, str], ...]
    notes: tuple[str, ...] = ()


def length_unit(span: float) -> tuple[str, float]:
    """("nm", 1e-9) for spans under 1 um, else ("um", 1e-6): the unit a legend uses."""
    return ("nm", 1e-9) if span < 1e-6 else ("um", 1e-6)


def legend_for(smap: SurfaceMap, title: str | None = None, notes=()) -> Legend:
    """The colour bar of ``smap`` with five ticks in nm or um, its P-V (and a deviation's
    RMS)."""
    lo, hi = smap.value_range()
    name, factor = length_unit(max(abs(lo), abs(hi)))
    values = [lo + f * (hi - lo) for f in TICKS]
    # a height range symmetric but for round-off has its middle tick at ~1e-22 m, which
    # '+.4g' printed as '+2.118e-13 nm': a tick that small beside the span is zero
    values = [0.0 if abs(v) < TICK_ZERO * (hi - lo) else v for v in values]
    ticks = tuple((f, f"{v / factor:+.4g} {name}") for f, v in zip(TICKS, values, strict=True))
    pv_name, pv_factor = length_unit(smap.peak_to_valley)
    stats = f"P-V {figure_text(smap.peak_to_valley, pv_factor)} {pv_name}"
    if smap.kind == "deviation":
        stats += f", RMS {figure_text(smap.rms, pv_factor)} {pv_name}"
    # the figures are the nodes': a V groove narrower than their spacing falls between two
    # (the README's 20 um deep grooves across the 10 mm block read P-V 13.67 um on its
    # 317 x 317 nodes), so the legend says how far apart they stand, as a measurement would
    spacing = max(_spacing(smap.x), _spacing(smap.y))
    sp_name, sp_factor = length_unit(spacing)
    grid = (f"{len(smap.x)} x {len(smap.y)} exact heights (metrology.height_map), "
            f"{spacing / sp_factor:.4g} {sp_name} apart: the P-V and RMS of these nodes, "
            "which a narrower groove or peak can fall between")
    return Legend(title or map_title(smap.kind), stops_for(smap.kind), ticks,
                  (stats, grid, *notes))


def figure_text(value: float, factor: float) -> str:
    """``value`` (m) in the unit of ``factor`` (m per unit) to 4 significant digits, and
    ``0`` below `FIGURE_ZERO_M` (round-off, not a figure: 2.745e-18 m is no '2.745e-09 nm');
    a NaN reads nan."""
    if abs(value) < FIGURE_ZERO_M:
        return "0"
    return f"{value / factor:.4g}"


def _spacing(axis: np.ndarray) -> float:
    """The largest step between a grid axis's nodes, m (0 for a single node)."""
    return float(np.diff(axis).max()) if len(axis) > 1 else 0.0


def map_title(kind: str) -> str:
    """What a map of ``kind`` shows, as its legend says."""
    return ("deviation from nominal (height, part - nominal)" if kind == "deviation"
            else "height z (workpiece frame)")


__all__ = ["DIVERGING", "NO_DATA", "SEQUENTIAL", "Legend", "SurfaceMap", "colours",
           "figure_text", "grid_for", "legend_for", "length_unit", "map_mesh", "map_title",
           "mesh_of", "stops_for", "surface_map"]
