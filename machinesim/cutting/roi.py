"""Measuring windows (``roi``): the parts of the stock a cut is made in, checked once for
`machinesim.cutting.cut`, `cut_turned` and the command line's ``--roi``."""

from __future__ import annotations

import numpy as np

from machinesim.exceptions import InputError, brief


def roi_cells(roi, bounds: np.ndarray) -> list[tuple[float, float, float, float]]:
    """The windows ``roi`` (xmin, xmax, ymin, ymax), m, each cut to the stock's ``bounds``
    (shape (2, 3), m) in x and y; those that hold none of it are left out.

    Raises
    ------
    InputError
        When ``roi`` is not an (n, 4) array of finite numbers with xmin < xmax, ymin < ymax.
    """
    from machinesim.metrology._arrays import as_floats, shown

    # numbers only: roi="x" had raised numpy's ValueError, naming nothing
    windows = as_floats(roi, "roi", "windows (xmin, xmax, ymin, ymax), m")
    if windows.ndim != 2 or windows.shape[1] != 4:
        one = " (one window is [(xmin, xmax, ymin, ymax)])" if windows.shape == (4,) else ""
        raise InputError(
            f"roi: expected windows (xmin, xmax, ymin, ymax) of shape (n, 4), got "
            f"{windows.shape}{one}",
            key="roi",
        )
    if not np.all(np.isfinite(windows)):  # had been told as the shape, which was right
        raise InputError(f"roi: expected finite windows (m), got {shown(windows.tolist())}",
                         key="roi")
    if np.any(windows[:, 1] <= windows[:, 0]) or np.any(windows[:, 3] <= windows[:, 2]):
        raise InputError("roi: each window needs xmin < xmax and ymin < ymax", key="roi")
    cells = []
    for xmin, xmax, ymin, ymax in windows:
        box = (max(xmin, bounds[0, 0]), min(xmax, bounds[1, 0]),
               max(ymin, bounds[0, 1]), min(ymax, bounds[1, 1]))
        if box[0] < box[1] and box[2] < box[3]:
            cells.append(box)
    return cells


def check_roi_meets(roi, stock, *, given: str | None = None, unit: str = "m") -> None:
    """Refuse windows ``roi`` (m, as `roi_cells` takes them) of which none overlaps
    ``stock`` (a `machinesim.workpiece.Part`) in x and y.

    The cut returns the stock clipped to the windows, so it was empty: the command line
    wrote a part of 0 vertices, exit 0, with "does it reach the stock?", and ``cut()`` gave
    it back without a word. ``given`` names the windows in the message (the command line's
    ``--roi`` texts; by default ``roi`` and the windows in m) and ``unit`` ("m" or "mm")
    the unit of the stock's extent there.
    """
    if roi is None:
        return
    bounds = stock.bounds
    if roi_cells(roi, bounds):
        return
    scale = {"m": 1.0, "mm": 1e3}[unit]
    if given is None:
        shown = ", ".join(f"({', '.join(f'{v:g}' for v in window)})"
                          for window in np.asarray(roi, dtype=np.float64).tolist())
        given = f"roi [{brief(shown)}] m"
    (x0, y0, _), (x1, y1, _) = bounds * scale
    raise InputError(f"{given}: no window overlaps the stock, which spans x {x0:g} .. {x1:g} "
                     f"{unit} and y {y0:g} .. {y1:g} {unit} (workpiece frame): the part, the "
                     "stock within the windows, would be empty; expected a window over the "
                     "stock")


__all__ = ["check_roi_meets", "roi_cells"]
