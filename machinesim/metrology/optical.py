"""Optical areal instruments: a laser confocal microscope and a white-light interferometer.

Both read the top surface of a part from above: exact heights from the float64 mesh
(`machinesim.metrology.height_map` / `profile`), then Gaussian height noise, then rounding to
the vertical resolution. They differ only in their defaults (justified in each class). The
lateral sampling is ideal (heights at the sample points, no optical transfer function): the
spot and the slope limit of a real objective are not modelled.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.arrays import frozen
from machinesim.exceptions import InputError
from machinesim.metrology._mesh import as_positive, as_vector
from machinesim.metrology.instruments import Readout, as_generator
from machinesim.metrology.surface import END_SLACK, height_map, profile

__all__ = ["HeightMap", "Microscope", "Profile", "WhiteLightInterferometer"]


@dataclass(frozen=True, eq=False)
class Profile:
    """Heights read along a straight line in xy.

    Attributes
    ----------
    s : ndarray, shape (k,), float64, read-only
        Distance of each sample from `start` along the line, m.
    z : ndarray, shape (k,), float64, read-only
        Displayed height at each sample, workpiece frame, m; NaN where no surface lies below.
    start, end : ndarray, shape (2,), float64, read-only
        End points (x, y) of the line, m.
    """

    s: np.ndarray
    z: np.ndarray
    start: np.ndarray
    end: np.ndarray

    @property
    def xy(self) -> np.ndarray:
        """Shape (k, 2): the (x, y) of each sample, m."""
        direction = (self.end - self.start) / np.hypot(*(self.end - self.start))
        return self.start + self.s[:, None] * direction


@dataclass(frozen=True, eq=False)
class HeightMap:
    """Heights read over a rectangular grid.

    Attributes
    ----------
    x : ndarray, shape (nx,), float64, read-only
        Sample x coordinates, workpiece frame, m.
    y : ndarray, shape (ny,), float64, read-only
        Sample y coordinates, m.
    z : ndarray, shape (ny, nx), float64, read-only
        ``z[j, i]`` is the displayed height at ``(x[i], y[j])``, m; NaN where no surface.
    """

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray


class _Profiler:
    """A height-reading instrument: its readout, its lateral spacing and its noise source."""

    def __init__(self, sigma: float, resolution: float, lateral_spacing: float, noise: bool,
                 rng) -> None:
        self.readout = Readout.of(sigma, resolution, noise)
        self.lateral_spacing = as_positive(lateral_spacing, "lateral_spacing")
        self.rng = as_generator(rng)

    def __repr__(self) -> str:
        r = self.readout
        return (f"{type(self).__name__}(sigma={r.sigma:g} m, resolution={r.resolution:g} m, "
                f"lateral_spacing={self.lateral_spacing:g} m)")

    def profile(self, part, start, end, spacing: float | None = None) -> Profile:
        """Read the heights along a line.

        Parameters
        ----------
        part : Part or MeshIndex or tuple of (array-like, array-like)
            The measured solid (workpiece frame, m).
        start, end : array-like, shape (2,)
            End points (x, y) of the line, m.
        spacing : float, optional
            Distance between samples, m (default: the instrument's `lateral_spacing`). The
            first sample is at ``start``, the last the last whole spacing not beyond ``end``.

        Returns
        -------
        Profile
        """
        spacing = self.lateral_spacing if spacing is None else spacing
        s, z = profile(part, start, end, spacing)
        return Profile(s, self._display(z), frozen(as_vector(start, 2, "start")),
                       frozen(as_vector(end, 2, "end")))

    def height_map(self, part, x0: float, x1: float, y0: float, y1: float,
                   spacing: float | None = None) -> HeightMap:
        """Read the heights over the rectangle [x0, x1] x [y0, y1].

        Parameters
        ----------
        part : Part or MeshIndex or tuple of (array-like, array-like)
            The measured solid (workpiece frame, m).
        x0, x1, y0, y1 : float
            The rectangle, m, with ``x0 < x1`` and ``y0 < y1``.
        spacing : float, optional
            Grid step along x and y, m (default: the instrument's `lateral_spacing`). Samples
            start at (x0, y0); the last of each axis is the last whole step not beyond x1, y1.

        Returns
        -------
        HeightMap
        """
        spacing = as_positive(self.lateral_spacing if spacing is None else spacing, "spacing")
        x = _axis(x0, x1, spacing, "x")
        y = _axis(y0, y1, spacing, "y")
        return HeightMap(x, y, self._display(height_map(part, x, y)))

    def _display(self, exact: np.ndarray) -> np.ndarray:
        return frozen(self.readout.read(exact, self.rng), copy=False)


class Microscope(_Profiler):
    """Laser scanning confocal microscope (the Keyence VK-X50 of paper 002, VK-X class).

    Parameters
    ----------
    sigma : float
        Height noise per sample, m. Default 12 nm: VK-X class instruments state a height
        repeatability of the order of 10 nm (sigma, high-magnification objective); paper 002
        reads groove depths with it to resolve differences of ~100 nm after three repeats.
    resolution : float
        Vertical display resolution, m. Default 1 nm: the order of the height display
        resolution of this class (0.5-1 nm), and the 1 nm step the machines move in.
    lateral_spacing : float
        Default sample spacing in x and y, m. Default 0.3 um, a 50x objective's pixel pitch in
        this class (0.1-0.7 um over the usual objectives).
    noise : bool
        False turns the noise off exactly (``sigma`` ignored); rounding stays.
    rng : numpy.random.Generator or int or None
        Noise source, or its seed (see `machinesim.metrology.instruments.as_generator`).
    """

    def __init__(self, sigma: float = 12e-9, resolution: float = 1e-9,
                 lateral_spacing: float = 0.3e-6, *, noise: bool = True, rng=None) -> None:
        super().__init__(sigma, resolution, lateral_spacing, noise, rng)


class WhiteLightInterferometer(_Profiler):
    """White-light (coherence scanning) interferometer (paper 002's reference [11]).

    Parameters
    ----------
    sigma : float
        Height noise per sample, m. Default 0.5 nm: coherence scanning interferometers reach
        ~0.1 nm RMS in phase mode on smooth surfaces and ~1 nm in scanning mode on machined
        ones; 0.5 nm sits between, far below the confocal microscope.
    resolution : float
        Vertical display resolution, m. Default 0.1 nm.
    lateral_spacing : float
        Default sample spacing in x and y, m. Default 0.5 um (a 20x objective's pixel pitch).
    noise : bool
        False turns the noise off exactly (``sigma`` ignored); rounding stays.
    rng : numpy.random.Generator or int or None
        Noise source, or its seed.
    """

    def __init__(self, sigma: float = 0.5e-9, resolution: float = 0.1e-9,
                 lateral_spacing: float = 0.5e-6, *, noise: bool = True, rng=None) -> None:
        super().__init__(sigma, resolution, lateral_spacing, noise, rng)


def _axis(lo: float, hi: float, spacing: float, name: str) -> np.ndarray:
    """lo, lo + spacing, ... up to the last whole step not beyond hi (hi itself when whole)."""
    try:
        lo, hi = float(lo), float(hi)
    except (TypeError, ValueError) as error:
        raise InputError(f"Expected {name} limits as numbers (m), got {lo!r}, {hi!r}",
                         key=name) from error
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise InputError(f"Expected finite {name}0 < {name}1 (m), got {lo} and {hi}", key=name)
    count = int(np.floor((hi - lo) / spacing + END_SLACK)) + 1
    axis = lo + np.arange(count) * spacing
    if abs(axis[-1] - hi) <= END_SLACK * spacing:
        axis[-1] = hi
    return frozen(axis, copy=False)
