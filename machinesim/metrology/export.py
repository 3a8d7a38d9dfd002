"""Measurements out: height maps to ISO 25178-72 x3p, profiles and height maps to PNG pictures.

Every file is written whole or not at all: it is built in memory or in a temporary file in
the destination folder and moved into place with `os.replace`. x3pio, matplotlib and its
Agg canvas are imported when a function runs, so importing `machinesim.metrology` stays cheap.

Pictures draw each axis in mm, um or nm, whichever its range reads best in; an axis far from
zero against its range (a face 2 mm deep with 100 nm of form) is drawn from a round offset
that its label names ("z + 2 mm (nm)").

x3p stores the heights as float64 ('D' data type) in metres, bit for bit, on a regular grid:
the x and y increments are the grid spacings and the offset of the view coordinate system
is the first sample (x[0], y[0], 0).
"""

from __future__ import annotations

import io

import numpy as np

from machinesim._io import check_ending, write_atomic
from machinesim.exceptions import InputError
from machinesim.metrology._arrays import map_arrays, profile_arrays, regular_step
from machinesim.units import LENGTH

__all__ = ["export_x3p", "length_unit", "plot_height_map", "plot_profile"]

#: Picture size (inches) and resolution: 1600 x 1000 pixels, readable in a report page.
FIGURE_INCHES = (8.0, 5.0)
DPI = 200
#: Axes whose extents differ by more than this ratio are drawn with free aspect; closer ones
#: keep x and y to the same scale, as a map of a part should be.
EQUAL_ASPECT_RATIO = 10.0
#: An axis whose values sit further from zero than this many times their range is drawn
#: relative to a round offset named in its label ("z + 2 mm (nm)"), not as -2000000 nm.
OFFSET_RATIO = 100.0
#: Units tried for an axis, largest first; the first in which the data range reaches 1 wins.
_UNITS = ("mm", "um", "nm")
_LABELS = {"mm": "mm", "um": "\N{MICRO SIGN}m", "nm": "nm"}


def length_unit(values) -> tuple[str, float]:
    """The unit (mm, um or nm) in which the range of ``values`` (m) reads as 1 or more.

    Returns the unit name and its factor to metres; NaN values are ignored, and a constant
    (or empty) set is sized by its magnitude instead of its range.
    """
    values = np.asarray(values, dtype=np.float64)
    finite = values[np.isfinite(values)]
    span = float(np.ptp(finite)) if finite.size else 0.0
    if span == 0.0:
        span = float(np.abs(finite).max()) if finite.size else 0.0
    for unit in _UNITS:
        if span >= LENGTH[unit]:
            return unit, LENGTH[unit]
    return _UNITS[-1], LENGTH[_UNITS[-1]]


def export_x3p(path, x, y, z, *, comment: str | None = None) -> None:
    """Write a height map to an ISO 25178-72 x3p file (float64 heights, metres).

    Parameters
    ----------
    path : str or os.PathLike
        Destination file, ending in ``.x3p`` (any case; another ending is refused).
    x : array-like, shape (nx,)
    y : array-like, shape (ny,)
        Regular grid axes, m (nx, ny >= 2).
    z : array-like, shape (ny, nx)
        Heights, m; NaN marks a sample with no surface (stored as x3p's missing point).
    comment : str, optional
        Free text stored in the file's metadata (Record2 comment).

    Raises
    ------
    InputError
        For a path not ending in ``.x3p``, malformed arrays or a grid that is not regular.
    """
    check_ending(path, "x3p", "export_x3p", "an ISO 25178-72 x3p height map")
    import x3pio

    from machinesim import __version__

    x, y, z = map_arrays(x, y, z)
    step_x = regular_step(x, "x")
    step_y = regular_step(y, "y")
    metadata = x3pio.Metadata.for_software("machinesim", __version__)
    metadata.comment = comment
    surface = x3pio.Surface.from_array(
        z, x_scale=step_x, y_scale=step_y, z_type=x3pio.DataType.FLOAT64, metadata=metadata,
        placement=x3pio.Placement.translation(float(x[0]), float(y[0]), 0.0),
        coordinate_system=x3pio.CoordinateSystem.VIEW,
    )
    write_atomic(path, surface.dumps())


def plot_profile(path, s, z, *, title: str | None = None, label: str = "s") -> None:
    """Draw a profile to a PNG file: heights against position, units chosen for the ranges.

    Parameters
    ----------
    path : str or os.PathLike
        Destination PNG file, ending in ``.png`` (any case; another ending is refused).
    s : array-like, shape (k,)
        Position along the profile, m, strictly increasing.
    z : array-like, shape (k,)
        Heights, m; NaN samples leave gaps.
    title : str, optional
        Title above the plot.
    label : str
        Name of the position axis.
    """
    check_ending(path, "png", "plot_profile", "a PNG picture")
    s_all = np.array(s, dtype=np.float64)
    z_all = np.array(z, dtype=np.float64)
    profile_arrays(s_all, z_all, 2)
    s_offset, s_factor, s_label = _axis(s_all, label)
    z_offset, z_factor, z_label = _axis(z_all, "z")
    figure, axes = _figure()
    axes.plot((s_all - s_offset) / s_factor, (z_all - z_offset) / z_factor, linewidth=0.8)
    axes.set_xlabel(s_label)
    axes.set_ylabel(z_label)
    axes.grid(True, linewidth=0.3)
    _finish(figure, axes, title, path)


def plot_height_map(path, x, y, z, *, title: str | None = None, cmap: str = "viridis") -> None:
    """Draw a height map to a PNG file: colour for height, with a colour bar in its unit.

    Parameters
    ----------
    path : str or os.PathLike
        Destination PNG file, ending in ``.png`` (any case; another ending is refused).
    x : array-like, shape (nx,)
    y : array-like, shape (ny,)
        Sample axes, m, strictly increasing (regular or not).
    z : array-like, shape (ny, nx)
        Heights, m; NaN samples are left blank.
    title : str, optional
        Title above the map.
    cmap : str
        A matplotlib colour map name.
    """
    check_ending(path, "png", "plot_height_map", "a PNG picture")
    x, y, z = map_arrays(x, y, z)
    if not np.isfinite(z).any():
        raise InputError("Expected at least one measured height to draw, got only NaN", key="z")
    span_x, span_y = float(np.ptp(x)), float(np.ptp(y))
    # x and y share a unit, so that a square reads as a square.
    xy_unit = length_unit([0.0, max(span_x, span_y)])[0]
    x_offset, xy_factor, x_label = _axis(x, "x", xy_unit)
    y_offset, _, y_label = _axis(y, "y", xy_unit)
    z_offset, z_factor, z_label = _axis(z, "z")
    x_drawn, y_drawn = (x - x_offset) / xy_factor, (y - y_offset) / xy_factor
    heights = np.ma.masked_invalid((z - z_offset) / z_factor)
    figure, axes = _figure()
    try:
        half_x = 0.5 * regular_step(x, "x") / xy_factor
        half_y = 0.5 * regular_step(y, "y") / xy_factor
        extent = (x_drawn[0] - half_x, x_drawn[-1] + half_x, y_drawn[0] - half_y,
                  y_drawn[-1] + half_y)
        image = axes.imshow(heights, origin="lower", extent=extent, cmap=cmap, aspect="auto",
                            interpolation="nearest")
    except InputError:
        image = axes.pcolormesh(x_drawn, y_drawn, heights, cmap=cmap, shading="nearest",
                                rasterized=True)
    if span_x > 0.0 and span_y > 0.0 and 1.0 / EQUAL_ASPECT_RATIO <= span_x / span_y \
            <= EQUAL_ASPECT_RATIO:
        axes.set_aspect("equal")
    axes.set_xlabel(x_label)
    axes.set_ylabel(y_label)
    bar = figure.colorbar(image, ax=axes)
    bar.set_label(z_label)
    _finish(figure, axes, title, path)


def _axis(values: np.ndarray, name: str, unit: str | None = None) -> tuple[float, float, str]:
    """Offset (m), unit factor (m) and label of an axis drawn in the unit of its range.

    Values far from zero against their range are drawn relative to their median, rounded to
    three decimals in its own unit, and the label names that offset.
    """
    finite = values[np.isfinite(values)]
    if unit is None:
        unit = length_unit(finite)[0]
    factor = LENGTH[unit]
    middle = float(np.median(finite))
    if abs(middle) <= OFFSET_RATIO * max(float(np.ptp(finite)), factor):
        return 0.0, factor, f"{name} ({_LABELS[unit]})"
    offset_unit, offset_factor = length_unit([middle])
    offset = round(middle / offset_factor, 3) * offset_factor
    sign = "+" if offset < 0.0 else "\N{MINUS SIGN}"
    return offset, factor, (f"{name} {sign} {abs(offset) / offset_factor:g} "
                            f"{_LABELS[offset_unit]} ({_LABELS[unit]})")


def _figure():
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    # A Figure on its own Agg canvas: no pyplot, no global state, no display needed.
    figure = Figure(figsize=FIGURE_INCHES, dpi=DPI, layout="constrained")
    FigureCanvasAgg(figure)
    return figure, figure.add_subplot()


def _finish(figure, axes, title, path) -> None:
    if title:
        axes.set_title(title)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    write_atomic(path, buffer.getvalue())

