"""Designed surfaces z(x, y) for slow-tool-servo turning (paper 004): the sine grid of its
eq 2, a sphere, a tilted plane, any callable, or a height map in memory or in a file.

`machinesim.cam.spiral` turns a design into cutting points, a tool path and a program, and
re-exports these names.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import RectBivariateSpline

from machinesim._io import check_readable_file
from machinesim.exceptions import FileError, InputError, check_length
from machinesim.metrology._arrays import as_number
from machinesim.units import M_PER_MM, M_PER_NM, M_PER_UM

__all__ = ["AMPLITUDE_M", "GRADIENT_STEP_M", "WAVELENGTH_M", "Design", "design_from_height_map",
           "radial_curvature",
           "read_design", "sine_grid", "sphere", "tilted_plane"]

#: Eq 2 and section 2.3: amplitude A = 50 nm and wavelength lambda = 100 um of the sine grid.
AMPLITUDE_M = 50 * M_PER_NM
WAVELENGTH_M = 100 * M_PER_UM
#: Central-difference step for the gradient of a callable design without one (m): on the
#: paper's sine grid the truncation h^2 |z'''| / 6 (|z'''| <= A (2 pi / lambda)^3) is 2e-10
#: of slope (the tip moves by R times that: 0.2 pm), the round-off eps |z| / h 2e-14 per um
#: of height.
GRADIENT_STEP_M = 10 * M_PER_NM


# --- designed surfaces -----------------------------------------------------------------------
@dataclass(frozen=True)
class Design:
    """A designed surface z(x, y) in the workpiece frame, m.

    Parameters
    ----------
    height : callable
        ``height(x, y) -> z``, vectorised over arrays of x and y (m).
    gradient : callable, optional
        ``gradient(x, y) -> (dz/dx, dz/dy)``; central differences (`GRADIENT_STEP_M`) when
        None.
    name : str
        For reports.

    A design is a value: `copy.copy` and `copy.deepcopy` give it back itself (its callables
    are shared as deepcopy shares functions). It pickles when its callables do: the designs
    made here (`sine_grid`, `sphere`, `tilted_plane`, `design_from_height_map`,
    `read_design`) do, their surfaces being module-level classes; a local function, an
    instance of a local class or a lambda is refused by name (`__getstate__`).
    """

    height: Callable
    gradient: Callable | None = None
    name: str = "design"

    def __copy__(self) -> Design:
        return self

    def __deepcopy__(self, memo) -> Design:
        return self

    def __getstate__(self) -> dict:
        # pickle's own words for a closure ("Can't pickle local object") name neither the
        # design nor the way out
        for role in ("height", "gradient"):
            function = getattr(self, role)
            # a callable object has no __qualname__ of its own: its class's names it (an
            # instance of a class defined in a function had passed, and pickle then said
            # "Can't pickle local object 'make.<locals>.Surface'")
            qualname = getattr(function, "__qualname__", None) or type(function).__qualname__
            if "<locals>" in qualname or "<lambda>" in qualname:
                raise InputError(f"design {self.name!r} cannot be pickled: its {role} is "
                                 f"{qualname}, a local function, class or lambda, which "
                                 "pickle cannot take; define it at a module's top level (or "
                                 "a method of a module-level class)", key="design")
        return dict(self.__dict__)

    def __call__(self, x, y) -> np.ndarray:
        return np.asarray(self.height(np.asarray(x, dtype=np.float64),
                                      np.asarray(y, dtype=np.float64)), dtype=np.float64)

    def slope(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """(dz/dx, dz/dy) at (x, y)."""
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        if self.gradient is not None:
            gx, gy = self.gradient(x, y)
            return np.asarray(gx, dtype=np.float64), np.asarray(gy, dtype=np.float64)
        h = GRADIENT_STEP_M
        return ((self(x + h, y) - self(x - h, y)) / (2.0 * h),
                (self(x, y + h) - self(x, y - h)) / (2.0 * h))


def sine_grid(amplitude: float = AMPLITUDE_M, wavelength: float = WAVELENGTH_M, *,
              amplitude_y: float | None = None, wavelength_y: float | None = None) -> Design:
    """Eq 2: z = A1 sin(2 pi x / lambda1) + A2 cos(2 pi y / lambda2), m.

    The second amplitude and wavelength default to the first (the paper: both 50 nm and
    100 um).
    """
    a1 = check_length(amplitude, "amplitude")
    l1 = _wavelength(wavelength, "wavelength")
    a2 = a1 if amplitude_y is None else check_length(amplitude_y, "amplitude_y")
    l2 = l1 if wavelength_y is None else _wavelength(wavelength_y, "wavelength_y")
    grid = _SineGrid(a1, 2.0 * math.pi / l1, a2, 2.0 * math.pi / l2)
    return Design(grid.height, grid.gradient, f"sine grid A {a1 / M_PER_NM:g} nm, lambda "
                                              f"{l1 / M_PER_UM:g} um")


@dataclass(frozen=True)
class _SineGrid:
    """`sine_grid`'s surface (a class, not closures, so that its design pickles): amplitudes,
    m, and wave numbers, rad/m."""

    a1: float
    k1: float
    a2: float
    k2: float

    def height(self, x, y):
        return self.a1 * np.sin(self.k1 * x) + self.a2 * np.cos(self.k2 * y)

    def gradient(self, x, y):
        return (self.a1 * self.k1 * np.cos(self.k1 * x),
                -self.a2 * self.k2 * np.sin(self.k2 * y) + 0.0 * x)


#: The shortest sine-grid wavelength taken, m: 1 nm, the NC writer's resolution. A path
#: over the grid is sampled along each wavelength, so 1e-300 m (accepted as positive) asked
#: for some 1e296 points a millimetre.
MIN_WAVELENGTH_M = 1e-9


def _wavelength(value, name: str) -> float:
    """``value`` as a wavelength, m: positive and at least `MIN_WAVELENGTH_M`."""
    length = check_length(value, name, positive=True)
    if length < MIN_WAVELENGTH_M:
        raise InputError(f"Expected {name} >= {MIN_WAVELENGTH_M:g} m (1 nm, "
                         f"machinesim.cam.designs.MIN_WAVELENGTH_M), got {length!r} m: a path "
                         "over the grid samples every wavelength", key=name)
    return length


def sphere(radius: float) -> Design:
    """A sphere cap with its pole at the origin: convex (z = sqrt(Rs^2 - rho^2) - Rs) for
    ``radius`` > 0, concave (z = |Rs| - sqrt(Rs^2 - rho^2)) for ``radius`` < 0, m.

    Defined for rho < |Rs|; NaN beyond.
    """
    rs = as_number(radius, "radius")  # True is no 1 m sphere, "2e-3" no number
    if rs == 0.0:
        raise InputError(f"Expected a finite, non-zero sphere radius (m), got {rs!r}",
                         key="radius")
    cap = _SphereCap(math.copysign(1.0, rs), abs(rs))
    return Design(cap.height, cap.gradient, f"sphere R {rs / M_PER_MM:g} mm")


@dataclass(frozen=True)
class _SphereCap:
    """`sphere`'s surface: ``sign`` +1 convex, -1 concave; ``size`` = |Rs|, m."""

    sign: float
    size: float

    def _root(self, x, y):
        with np.errstate(invalid="ignore"):
            return np.sqrt(self.size * self.size - (x * x + y * y))

    def height(self, x, y):
        return self.sign * (self._root(x, y) - self.size)

    def gradient(self, x, y):
        r = self._root(x, y)
        return -self.sign * x / r, -self.sign * y / r


def tilted_plane(slope_x: float, slope_y: float = 0.0) -> Design:
    """The plane z = slope_x x + slope_y y (a test surface: turned, its twist about the
    centre shows the tool's centre height with its sign)."""
    # True is no slope of 1, "0.02" no number (as_number refuses both, and NaN, by name)
    kx = as_number(slope_x, "slope_x", unit="m per m")
    ky = as_number(slope_y, "slope_y", unit="m per m")
    plane = _Plane(kx, ky)
    return Design(plane.height, plane.gradient, f"plane, slopes {kx:g}, {ky:g}")


@dataclass(frozen=True)
class _Plane:
    """`tilted_plane`'s surface: its slopes, m per m."""

    kx: float
    ky: float

    def height(self, x, y):
        return self.kx * x + self.ky * y

    def gradient(self, x, y):
        shape = np.broadcast(x, y).shape
        return np.full(shape, self.kx), np.full(shape, self.ky)


def design_from_height_map(x, y, z, *, name: str = "height map") -> Design:
    """A design from a height map: bicubic interpolating spline (scipy), m.

    Parameters
    ----------
    x : array-like, shape (nx,)
    y : array-like, shape (ny,)
        Strictly increasing grid axes, m, at least 4 each.
    z : array-like, shape (ny, nx)
        Heights, m, finite (``z[j, i]`` over ``(x[i], y[j])``, as `machinesim.metrology`).

    The design refuses points outside the map's box (InputError naming the first).
    """
    gx, gy = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    gz = np.asarray(z, dtype=np.float64)
    for axis, values in (("x", gx), ("y", gy)):
        if values.ndim != 1 or values.size < 4 or not np.isfinite(values).all() or (
                np.diff(values) <= 0.0).any():
            raise InputError(f"Expected {axis} as at least 4 finite, strictly increasing "
                             f"values (m), got shape {values.shape}", key=axis)
    if gz.shape != (gy.size, gx.size):
        raise InputError(f"Expected z of shape ({gy.size}, {gx.size}) (ny, nx), got "
                         f"{gz.shape}", key="z")
    if not np.isfinite(gz).all():
        raise InputError(f"Expected finite heights, {np.count_nonzero(~np.isfinite(gz))} are "
                         "not (fill the holes first)", key="z")
    spline = RectBivariateSpline(gx, gy, gz.T, kx=3, ky=3, s=0)
    surface = _HeightMap(spline, (gx[0], gx[-1], gy[0], gy[-1]), name)
    return Design(surface.height, surface.gradient, name)


@dataclass(frozen=True, eq=False)
class _HeightMap:
    """`design_from_height_map`'s surface: the spline, its box (x0, x1, y0, y1), m, and
    the design's name for the refusal of a point outside it."""

    spline: RectBivariateSpline
    box: tuple
    name: str

    def _check(self, px, py):
        box = self.box
        outside = (px < box[0]) | (px > box[1]) | (py < box[2]) | (py > box[3])
        if np.any(outside):
            i = int(np.flatnonzero(np.ravel(outside))[0])
            raise InputError(f"design {self.name!r}: point ({np.ravel(px)[i]!r}, "
                             f"{np.ravel(py)[i]!r}) m lies outside the height map "
                             f"[{box[0]!r}, {box[1]!r}] x [{box[2]!r}, {box[3]!r}] m",
                             key="design")

    def height(self, px, py):
        self._check(px, py)
        return self.spline.ev(px, py)

    def gradient(self, px, py):
        self._check(px, py)
        return self.spline.ev(px, py, dx=1), self.spline.ev(px, py, dy=1)


def read_design(path: str | os.PathLike) -> Design:
    """A design from a height-map file: ISO 25178-72 ``.x3p`` (as
    `machinesim.metrology.export_x3p` writes) or ``.npz`` with arrays ``x``, ``y``, ``z``
    in metres (``z`` of shape (ny, nx))."""
    file = check_readable_file(path, "height map")
    suffix = file.suffix.lower()
    if suffix == ".npz":
        try:
            with np.load(file, allow_pickle=False) as data:
                missing = [key for key in ("x", "y", "z") if key not in data]
                if missing:
                    raise InputError(f"missing array(s) {', '.join(missing)}; expected x, y, "
                                     "z in metres", source=str(file))
                x, y, z = data["x"], data["y"], data["z"]
        except (OSError, ValueError) as error:
            if isinstance(error, InputError):
                raise
            raise FileError(f"cannot read the height map: {error}", source=str(file)) from None
    elif suffix == ".x3p":
        x, y, z = _read_x3p(file)
    else:
        raise InputError(f"Expected a .x3p or .npz height map, got {suffix or 'no suffix'!r}",
                         source=str(file))
    return design_from_height_map(x, y, z, name=Path(file).name)


def _read_x3p(file: Path):
    import x3pio

    try:
        surface = x3pio.read(file)
    except (OSError, x3pio.X3pError) as error:
        raise FileError(f"cannot read the height map: {error}", source=str(file)) from None
    layer = surface.layers[0]
    rotation = np.asarray(surface.placement.rotation, dtype=np.float64)
    if not np.allclose(rotation, np.eye(3), rtol=0.0, atol=1e-12):
        raise InputError("Expected an x3p map without rotation in its placement",
                         source=str(file))
    offset = np.asarray(surface.placement.offset, dtype=np.float64)
    return (np.asarray(layer.x_values, dtype=np.float64) + offset[0],
            np.asarray(layer.y_values, dtype=np.float64) + offset[1],
            np.asarray(layer.z, dtype=np.float64) + offset[2])


def radial_curvature(design: Design, x, y) -> np.ndarray:
    """Curvature of ``design``'s profile in the radial plane through each point (x, y), 1/m:
    z_rr / (1 + z_r^2)^(3/2), z_r the slope along the outward radius (eq 13) and z_rr its
    derivative there; positive where the profile is concave seen from above (+Z, the side
    the tool comes from: a valley), negative on a crest. NaN where the design is not
    defined.

    z_rr is the one-sided second-order difference of the radial slope, at the point and
    `GRADIENT_STEP_M` and twice it towards the centre (the inner points lie on the part
    wherever the point does: a height map's edge is not crossed): exact for a quadratic
    profile; on the paper's sine grid its truncation h^2 |z''''| / 3 is 1.3e-7 relative.
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    rho = np.hypot(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.where(rho > 0.0, x / rho, 1.0)
        sin = np.where(rho > 0.0, y / rho, 0.0)
        h = GRADIENT_STEP_M
        slopes = []
        for step in (0.0, h, 2.0 * h):
            gx, gy = design.slope(x - step * cos, y - step * sin)
            slopes.append(cos * gx + sin * gy)
        second = (3.0 * slopes[0] - 4.0 * slopes[1] + slopes[2]) / (2.0 * h)
        return second / (1.0 + slopes[0] * slopes[0]) ** 1.5
