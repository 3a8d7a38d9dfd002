"""Optical areal instruments: a laser confocal microscope and a white-light interferometer.

Both read the top surface of a part from above: exact heights from the float64 mesh
(`machinesim.metrology.height_map` / `profile`), then Gaussian height noise, then rounding to
the vertical resolution. They differ only in their defaults (justified in each class).

By default the lateral sampling is ideal: heights exactly at the sample points, in the
workpiece frame. Three imperfections of a real instrument can be given (all off by default;
`machinesim.Lab` gives the lab's values, `machinesim.realism.MICROSCOPE` and ``WHITE_LIGHT``,
when `machinesim.realism.Realism` turns them on):

- ``spot`` (`machinesim.metrology.imperfections.Spot`): each reading is the mean of the exact
  heights over a Gaussian spot or a top-hat pixel, not the height at a point;
- ``lateral_sigma``: the sample positions jitter (lateral noise): on a height map each
  column sits off in x and each row (scan line) in y by its own normal deviate; on a profile
  each sample sits off along the line by its own and the whole line across it by one;
- ``registration`` (`machinesim.metrology.imperfections.Registration`): the instrument's own
  frame, in which it takes and reports every coordinate and height, sits off the
  workpiece's. The instrument keeps it to itself, as a real stage does not know it.
- ``stage_sigma``: the stage positions each reading within its accuracy: a profile or a map
  is read a fresh (dx, dy) away from where it was asked for, and reported where it was
  asked for (two readings of one feature disagree by the stage's scatter); readings inside
  ``with instrument.placement():`` share one placement (one field of view).

A part may also be a height field (anything with ``heights_at(px, py)``, e.g. the
`machinesim.cutting.lathe.TurnedPart` a turn leaves): it is read at the sample points
exactly, with lateral and height noise; spot and registration are modelled for meshes only
and refused there.

The slope limit of a real objective (no light back from steep flanks) is not modelled.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from machinesim._keywords import keywords_checked
from machinesim.arrays import frozen
from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_number
from machinesim.metrology._mesh import as_positive, as_vector, mesh_arrays
from machinesim.metrology.imperfections import (
    Registration,
    RegistrationScatter,
    Spot,
    line_heights,
    spot_heights,
)
from machinesim.metrology.instruments import OPTICAL_LIMIT, Readout, as_generator
from machinesim.metrology.surface import (
    END_SLACK,
    check_read,
    check_samples,
    grid_heights,
    line_count,
    profile,
)
from machinesim.units import M_PER_MM

__all__ = ["HeightMap", "Microscope", "Profile", "WhiteLightInterferometer"]


def _span(z: np.ndarray) -> str:
    """The heights read, for a repr: missing count and range, um."""
    read = z[~np.isnan(z)]
    heights = (f"z {read.min() * 1e6:.6g} .. {read.max() * 1e6:.6g} um" if read.size
               else "nothing read")
    return f"{z.size - read.size} missing, {heights}"


@dataclass(frozen=True, eq=False, repr=False)
class Profile:
    """Heights read along a straight line in xy.

    Attributes
    ----------
    s : ndarray, shape (k,), float64, read-only
        Distance of each sample from `start` along the line, m.
    z : ndarray, shape (k,), float64, read-only
        Displayed height at each sample, workpiece frame, m; NaN where the sample is off the
        part and read nothing (`missing`).
    start, end : ndarray, shape (2,), float64, read-only
        End points (x, y) of the line, m.

    A profile partly off the part keeps its samples there as missing, as a profilometer's
    data marks its non-measured points (x3p: invalid); the fits leave them out. A profile
    wholly off the part is refused (`machinesim.metrology.surface.check_read`).
    """

    s: np.ndarray
    z: np.ndarray
    start: np.ndarray
    end: np.ndarray

    @property
    def missing(self) -> np.ndarray:
        """Shape (k,), bool: True where the sample read nothing (off the part; ``z`` NaN)."""
        return _flags(np.isnan(self.z))

    @property
    def xy(self) -> np.ndarray:
        """Shape (k, 2): the (x, y) of each sample, m."""
        direction = (self.end - self.start) / np.hypot(*(self.end - self.start))
        return self.start + self.s[:, None] * direction

    def __repr__(self) -> str:
        (x0, y0), (x1, y1) = self.start * 1e3, self.end * 1e3
        return (f"Profile({self.s.size} samples from ({x0:.6g}, {y0:.6g}) mm to ({x1:.6g}, "
                f"{y1:.6g}) mm, {_span(self.z)})")


@dataclass(frozen=True, eq=False, repr=False)
class HeightMap:
    """Heights read over a rectangular grid.

    Attributes
    ----------
    x : ndarray, shape (nx,), float64, read-only
        Sample x coordinates, workpiece frame, m.
    y : ndarray, shape (ny,), float64, read-only
        Sample y coordinates, m.
    z : ndarray, shape (ny, nx), float64, read-only
        ``z[j, i]`` is the displayed height at ``(x[i], y[j])``, m; NaN where the sample is
        off the part and read nothing (`missing`; as `Profile`'s).
    """

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray

    @property
    def missing(self) -> np.ndarray:
        """Shape (ny, nx), bool: True where the sample read nothing (off the part; ``z``
        NaN)."""
        return _flags(np.isnan(self.z))

    def __repr__(self) -> str:
        x, y = self.x * 1e3, self.y * 1e3
        return (f"HeightMap({y.size} x {x.size} samples over x {x.min():.6g} .. "
                f"{x.max():.6g} mm, y {y.min():.6g} .. {y.max():.6g} mm, {_span(self.z)})")


class _Profiler:
    """A height-reading instrument: its readout, its lateral spacing and its noise source,
    and the lateral imperfections it was given (module docstring)."""

    def __init__(self, sigma: float, resolution: float, lateral_spacing: float, noise: bool,
                 rng, spot: Spot | None = None, lateral_sigma: float = 0.0,
                 lateral_rng=None, registration: Registration | None = None,
                 stage_sigma: float = 0.0, stage_rng=None,
                 registration_scatter: RegistrationScatter | None = None) -> None:
        sigma, resolution = _setting(sigma, "sigma"), _setting(resolution, "resolution")
        self.readout = Readout.of(sigma, resolution, noise)
        self.stage_sigma = _setting(stage_sigma, "stage_sigma")
        self._stage_rng = as_generator(stage_rng) if self.stage_sigma > 0.0 else None
        self._held = None  # the placement `placement` holds
        self.lateral_spacing = as_positive(lateral_spacing, "lateral_spacing")
        _setting(self.lateral_spacing, "lateral_spacing")  # a pixel within the field of view
        self._rng = as_generator(rng)
        if spot is not None and not isinstance(spot, Spot):
            raise InputError(f"Expected spot as a Spot or None, got {spot!r}", key="spot")
        if registration is not None and not isinstance(registration, Registration):
            raise InputError(f"Expected registration as a Registration or None, got "
                             f"{type(registration).__name__}", key="registration")
        self.spot = spot
        self.lateral_sigma = _setting(lateral_sigma, "lateral_sigma")
        self._lateral_rng = as_generator(lateral_rng) if self.lateral_sigma > 0.0 else None
        if registration_scatter is not None and not isinstance(registration_scatter,
                                                               RegistrationScatter):
            raise InputError(f"Expected registration_scatter as a RegistrationScatter or "
                             f"None, got {registration_scatter!r}", key="registration_scatter")
        self._registration = registration
        self.registration_scatter = registration_scatter
        self._seen = None  # (part, its vertices in the instrument frame, triangles)

    def __repr__(self) -> str:
        r = self.readout
        extra = "" if self.spot is None else (f", spot={self.spot.shape}:{self.spot.width:g} m"
                                              + (" exact" if self.spot.exact else ""))
        if self.lateral_sigma > 0.0:
            extra += f", lateral_sigma={self.lateral_sigma:g} m"
        if self.stage_sigma > 0.0:
            extra += f", stage_sigma={self.stage_sigma:g} m"
        return (f"{type(self).__name__}(sigma={r.sigma:g} m, resolution={r.resolution:g} m, "
                f"lateral_spacing={self.lateral_spacing:g} m{extra})")

    @keywords_checked
    def profile(self, part, start, end, spacing: float | None = None) -> Profile:
        """Read the heights along a line.

        Parameters
        ----------
        part : Part or MeshIndex or tuple of (array-like, array-like) or TurnedPart
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
        spacing = _pitch(self.lateral_spacing if spacing is None else spacing)
        nominal = as_vector(start, 2, "start"), as_vector(end, 2, "end")
        if not _is_field(part):
            self._check_on_part(part, *nominal, spacing=spacing)
        shift = self._stage_offset()  # where the stage really put this reading
        a, b = nominal[0] + shift, nominal[1] + shift
        if _is_field(part):
            s = _line_samples(a, b, as_positive(spacing, "spacing"), 1)
            ds, across = self._jitter(len(s)), self._jitter(1)[0]
            along = (b - a) / np.hypot(*(b - a))
            points = a + (s + ds)[:, None] * along + across * np.array([-along[1], along[0]])
            z = self._field(part, points[:, 0], points[:, 1])
            return Profile(frozen(s, copy=False), self._display(z), frozen(nominal[0]),
                           frozen(nominal[1]))
        surface = self._surface(part)
        if self.spot is None and self.lateral_sigma == 0.0:
            s, z = profile(surface, a, b, spacing, refuse=False)
        else:
            per_sample = 1 if self.spot is None or self.spot.exact else self.spot.samples**2
            s = _line_samples(a, b, as_positive(spacing, "spacing"), per_sample)
            ds, across = np.zeros(len(s)), 0.0
            if self._lateral_rng is not None:
                ds = self.lateral_sigma * self._lateral_rng.standard_normal(len(s))
                across = self.lateral_sigma * float(self._lateral_rng.standard_normal())
            vertices, triangles = mesh_arrays(surface)
            z = line_heights(vertices, triangles, a, (b - a) / np.hypot(*(b - a)), s, ds,
                             across, self.spot)
            s = frozen(s, copy=False)
        # named as asked, over the part as given: where the stage and the registration
        # really put them is the lab's (the stage's offset had read here to 10 nm)
        check_read(z, mesh_arrays(part)[0], f"{type(self).__name__}: the profile from "
                   f"({nominal[0][0]:g}, {nominal[0][1]:g}) to ({nominal[1][0]:g}, "
                   f"{nominal[1][1]:g}) m", "start")
        return Profile(s, self._display(z), frozen(nominal[0]), frozen(nominal[1]))

    @keywords_checked
    def height_map(self, part, x0: float, x1: float, y0: float, y1: float,
                   spacing: float | None = None) -> HeightMap:
        """Read the heights over the rectangle [x0, x1] x [y0, y1].

        Parameters
        ----------
        part : Part or MeshIndex or tuple of (array-like, array-like) or TurnedPart
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
        spacing = _pitch(self.lateral_spacing if spacing is None else spacing)
        (x0, x1), (y0, y1) = _limits(x0, x1, "x"), _limits(y0, y1, "y")
        if not _is_field(part):
            self._check_on_part(part, np.array([x0, y0]), np.array([x1, y1]), spacing,
                                window=True)
        nx, ny = line_count(x1 - x0, spacing), line_count(y1 - y0, spacing)
        check_samples(nx * ny, spacing, f"{x1 - x0:g} m x {y1 - y0:g} m ({nx:.4g} x {ny:.4g})")
        x = _axis(x0, x1, spacing)
        y = _axis(y0, y1, spacing)
        shift = self._stage_offset()  # where the stage really put this reading
        rx, ry = x + shift[0], y + shift[1]  # what is read; reported at x, y
        if _is_field(part):
            px, py = np.meshgrid(rx + self._jitter(len(x)), ry + self._jitter(len(y)))
            z = self._field(part, px.ravel(), py.ravel()).reshape(len(y), len(x))
            return HeightMap(x, y, self._display(z))
        surface = self._surface(part)
        if self.spot is None and self.lateral_sigma == 0.0:
            z = grid_heights(surface, rx, ry)
        else:
            dx, dy = np.zeros(len(x)), np.zeros(len(y))
            if self._lateral_rng is not None:
                dx = self.lateral_sigma * self._lateral_rng.standard_normal(len(x))
                dy = self.lateral_sigma * self._lateral_rng.standard_normal(len(y))
            vertices, triangles = mesh_arrays(surface)
            z = spot_heights(vertices, triangles, rx, ry, dx, dy, self.spot)
        check_read(z, mesh_arrays(part)[0], f"{type(self).__name__}: the height map over x "
                   f"{x[0]:g} .. {x[-1]:g} m, y {y[0]:g} .. {y[-1]:g} m", "x0")  # as asked
        return HeightMap(x, y, self._display(z))

    def _check_on_part(self, part, a: np.ndarray, b: np.ndarray, spacing: float,
                       window: bool = False) -> None:
        """Refuse a profile from ``a`` to ``b`` (a map over the rectangle of corners ``a``,
        ``b``), as asked, that misses the part's xy extent or of which less than
        `ON_PART_SHARE` lies over it: a unit slip, mm given as m. Given (1, 5) and (9, 5)
        for a line across a 10 mm block, the microscope read 26.7 million samples (9 s), all
        NaN, and fit_v_groove then said 'Expected at least 5 finite samples, got 0'. A part
        given as a height field (a turned face) has heights everywhere.

        Judged on the part as the instrument sees it (in its frame when it has a
        registration): "every sample would read NaN" is then what the reading would do. A
        line over the part as really placed reads, as on a real stage, where one judged on
        the part as given was refused: paper 003's profiles put on ridges found in the
        instrument's frame lie up to tens of um off the given corner window under the
        registration's 1 mrad at 190 mm. Whether a line reads is a measurement a real
        instrument gives too (an edge found by reading across it); the message names the
        part's extent as given, in the workpiece frame, not where the hidden registration put
        it (which it had printed to 0.1 um)."""
        seen, _ = mesh_arrays(self._surface(part))
        if len(seen) == 0:
            return
        lo, hi = seen[:, :2].min(axis=0), seen[:, :2].max(axis=0)
        if window:
            size = b - a
            over = np.clip(np.minimum(b, hi) - np.maximum(a, lo), 0.0, None)
            share = float(np.prod(over) / np.prod(size))
            missed = bool(np.any(np.minimum(b, hi) < np.maximum(a, lo)))
            count = line_count(size[0], spacing) * line_count(size[1], spacing)
            what = (f"the map over x {a[0]:g} .. {b[0]:g} m, y {a[1]:g} .. {b[1]:g} m "
                    f"({size[0]:g} m x {size[1]:g} m, {count:.3g} samples at {spacing:g} m)")
            arguments, of = "x0, x1, y0, y1", "of its area"
        else:
            length = float(np.hypot(*(b - a)))
            if length == 0.0:
                return  # refused as such by the reading
            inside = _clipped(a, b, lo, hi)
            missed = inside is None
            share = 0.0 if missed else inside / length
            what = (f"the profile from ({a[0]:g}, {a[1]:g}) to ({b[0]:g}, {b[1]:g}) m "
                    f"({length:g} m long, {line_count(length, spacing):.3g} samples at "
                    f"{spacing:g} m)")
            arguments, of = "start and end", "of it"
        if not missed and share >= ON_PART_SHARE:
            return
        given = mesh_arrays(part)[0]
        lo, hi = given[:, :2].min(axis=0), given[:, :2].max(axis=0)
        mm = (lo / M_PER_MM).tolist(), (hi / M_PER_MM).tolist()
        spans = (f"the part spans x {mm[0][0]:.6g} .. {mm[1][0]:.6g} mm, y {mm[0][1]:.6g} .. "
                 f"{mm[1][1]:.6g} mm (in m: x {lo[0]:.6g} .. {hi[0]:.6g}, y {lo[1]:.6g} .. "
                 f"{hi[1]:.6g})")
        found = ("misses the part: every sample would read NaN (no surface)" if missed else
                 f"lies over the part for {share:.2%} {of}: the rest would read NaN")
        raise InputError(f"{type(self).__name__}: {what} {found}; {spans}. Expected "
                         f"{arguments} in m (SI: 5 mm is 0.005)",
                         key="start" if not window else "x0")

    @contextmanager
    def placement(self):
        """Readings inside share one placement of the stage: one field of view (a profile
        zoomed into, several profiles of one image). Outside, each reading is its own.

        >>> with microscope.placement():  # doctest: +SKIP
        ...     coarse = microscope.profile(part, a, b)
        ...     fine = microscope.profile(part, c, d, spacing=1e-9)

        One placed inside another is the same placement (the stage does not move), and the
        outer one holds on after it.
        """
        outer = self._held
        self._held = self._stage_offset()  # the outer placement's, if one is held
        try:
            yield self
        finally:
            self._held = outer

    def _stage_offset(self) -> np.ndarray:
        """Where the stage puts this reading off its commanded place (x, y, m): the held
        placement's, else a fresh draw per reading with stage positioning, zeros without."""
        if self._held is not None:
            return self._held
        if self._stage_rng is None:
            return np.zeros(2)
        return self.stage_sigma * self._stage_rng.standard_normal(2)

    def _jitter(self, n: int) -> np.ndarray:
        """Lateral noise of ``n`` sample positions (zeros without it), m."""
        if self._lateral_rng is None:
            return np.zeros(n)
        return self.lateral_sigma * self._lateral_rng.standard_normal(n)

    def _field(self, part, px: np.ndarray, py: np.ndarray) -> np.ndarray:
        """Exact heights of a height-field part (a `TurnedPart`) at the sample points."""
        if self.spot is not None or self._registration is not None:
            raise InputError(f"{type(self).__name__}: a turned part (a height field) is read "
                             "without spot and registration, which are modelled for mesh "
                             "parts only; give the instrument spot=None and no registration "
                             "(Realism: lateral_resolution and registration off)", key="part")
        return np.asarray(part.heights_at(px, py), dtype=np.float64)

    def _display(self, exact: np.ndarray) -> np.ndarray:
        return frozen(self.readout.read(exact, self._rng), copy=False)

    def _surface(self, part):
        """The part as this instrument sees it: itself, or its mesh in the instrument frame
        (kept for the last part read, as a stage keeps a part until the next is put on)."""
        if self._registration is None:
            return part
        if self._seen is None or self._seen[0] is not part:
            vertices, triangles = mesh_arrays(part)
            self._seen = (part, self._registration.to_instrument(vertices), triangles)
        return self._seen[1], self._seen[2]


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
    spot : Spot, optional
        Lateral resolution: the spot each reading averages over. Default none (heights at
        points). The lab's: a Gaussian of 0.3 um FWHM (`machinesim.realism.MICROSCOPE`,
        from lambda / NA of a 50x / 0.95 objective).
    lateral_sigma : float
        Lateral noise, m (module docstring). Default 0; the lab's 20 nm (assumed).
    lateral_rng : numpy.random.Generator or int or None
        Source of the lateral noise, apart from the height noise's.
    registration : Registration, optional
        Where the instrument's frame sits on the workpiece; default exactly on it. The lab
        draws one per instrument (5 um, 1 mrad, 10 um, 0.2 mrad scatter, assumed).
    stage_sigma : float
        Stage positioning, m: each reading (`profile`, `height_map`) is taken where the
        stage put it, off its commanded place by a fresh normal draw of this deviation in x
        and y, and reported at the commanded place. Default 0; the lab's 1 um
        (`machinesim.realism.MICROSCOPE`).
    stage_rng : numpy.random.Generator or int or None
        Source of the stage's draws.
    registration_scatter : RegistrationScatter, optional
        What the lab states of its registration practice: the scatter its registrations are
        drawn from, public (`registration_scatter`) for the uncertainty a procedure states;
        the drawn ``registration`` stays hidden. The lab gives it with its registration.
    """

    def __init__(self, sigma: float = 12e-9, resolution: float = 1e-9,
                 lateral_spacing: float = 0.3e-6, *, noise: bool = True, rng=None,
                 spot: Spot | None = None, lateral_sigma: float = 0.0, lateral_rng=None,
                 registration: Registration | None = None, stage_sigma: float = 0.0,
                 stage_rng=None, registration_scatter: RegistrationScatter | None = None
                 ) -> None:
        super().__init__(sigma, resolution, lateral_spacing, noise, rng, spot, lateral_sigma,
                         lateral_rng, registration, stage_sigma, stage_rng,
                         registration_scatter)


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
    spot, lateral_sigma, lateral_rng, registration, stage_sigma, stage_rng, registration_scatter
        As the `Microscope`'s, all off by default. The lab's: a Gaussian spot of 0.8 um FWHM
        (0.61 lambda / NA of a 20x / 0.4 objective at 0.55 um), 10 nm lateral noise
        (assumed), the microscope's registration scatter (`machinesim.realism.WHITE_LIGHT`).
    """

    def __init__(self, sigma: float = 0.5e-9, resolution: float = 0.1e-9,
                 lateral_spacing: float = 0.5e-6, *, noise: bool = True, rng=None,
                 spot: Spot | None = None, lateral_sigma: float = 0.0, lateral_rng=None,
                 registration: Registration | None = None, stage_sigma: float = 0.0,
                 stage_rng=None, registration_scatter: RegistrationScatter | None = None
                 ) -> None:
        super().__init__(sigma, resolution, lateral_spacing, noise, rng, spot, lateral_sigma,
                         lateral_rng, registration, stage_sigma, stage_rng,
                         registration_scatter)


#: Least share of a profile's length (of a map's area) that must lie over the part's xy
#: extent: below it at least 999 samples in 1000 read NaN. A line across a 10 mm block given
#: in mm where m are asked for is over it for 0.08 % ((-1, 5) to (11, 5): 12 m, 10 mm of
#: it over the block) or misses it; a generous line or map around a small part is far above.
ON_PART_SHARE = 1e-3


def _clipped(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float | None:
    """Length of the segment a-b inside the closed box [lo, hi] (Liang-Barsky), None when it
    misses the box."""
    t0, t1 = 0.0, 1.0
    d = b - a
    for k in range(2):
        if d[k] == 0.0:
            if not lo[k] <= a[k] <= hi[k]:
                return None
            continue
        u, v = (lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]
        t0, t1 = max(t0, min(u, v)), min(t1, max(u, v))
    if t0 > t1:
        return None
    return (t1 - t0) * float(np.hypot(*d))


def _flags(mask: np.ndarray) -> np.ndarray:
    """``mask`` (bool), read-only."""
    mask.flags.writeable = False
    return mask


def _is_field(part) -> bool:
    """True for a part given as a height field (``heights_at``), e.g. a turned face."""
    return callable(getattr(part, "heights_at", None))


def _setting(value, name: str) -> float:
    """An optical instrument's noise, step or scatter: >= 0 and at most `OPTICAL_LIMIT`."""
    return as_number(value, name, sign=">= 0", limit=OPTICAL_LIMIT,
                     why=" (OPTICAL_LIMIT: the widest field of view modelled; more is a unit "
                         "slip, e.g. mm given as m)")


def _pitch(spacing) -> float:
    """A reading's ``spacing``: > 0 and, as `lateral_spacing`, at most `OPTICAL_LIMIT`, a
    pixel within the field of view (``spacing=0.3``, um meant, had read a 2 mm profile as
    one sample and a height map as one pixel)."""
    return _setting(as_positive(spacing, "spacing"), "spacing")


def _line_samples(start: np.ndarray, end: np.ndarray, spacing: float,
                  per_sample: int) -> np.ndarray:
    """Distances along a profile, as `machinesim.metrology.profile` takes them, refused
    beyond `machinesim.metrology.surface.MAX_SAMPLES` (``per_sample`` points read for each)."""
    length = float(np.hypot(*(end - start)))
    if length == 0.0:
        raise InputError(f"Expected a profile of non-zero length, got start = end = {start}")
    count = line_count(length, spacing)
    check_samples(count, spacing, f"a {length:g} m line", per_sample)
    s = np.arange(int(count)) * spacing
    if abs(s[-1] - length) <= END_SLACK * spacing:
        s[-1] = length
    return s


def _limits(lo, hi, name: str) -> tuple[float, float]:
    """A map's limits along ``name`` as finite floats with lo < hi."""
    lo, hi = as_number(lo, f"{name}0"), as_number(hi, f"{name}1")
    if not lo < hi:
        raise InputError(f"Expected {name}0 < {name}1 (m), got {lo} and {hi}", key=name)
    return lo, hi


def _axis(lo: float, hi: float, spacing: float) -> np.ndarray:
    """lo, lo + spacing, ... up to the last whole step not beyond hi (hi itself when whole)."""
    axis = lo + np.arange(int(line_count(hi - lo, spacing))) * spacing
    if abs(axis[-1] - hi) <= END_SLACK * spacing:
        axis[-1] = hi
    return frozen(axis, copy=False)
