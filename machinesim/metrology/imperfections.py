"""What makes a real instrument read other than the exact value: the models, as plain values.

Each class here is one imperfection of one kind of instrument, frozen, with a ``draw``
classmethod that makes one at random from a stated scatter (`machinesim.Lab` draws them from
the instrument's own streams when `machinesim.realism.Realism` turns them on; a test builds
known ones directly):

- `Spot`: the lateral resolution of an optical instrument, a Gaussian spot or a square
  top-hat (a camera pixel) over which the exact heights are averaged;
- `Registration`: where the optical instrument's own frame sits on the workpiece (an offset
  and a rotation in xy, a height offset and a tilt);
- `Lobing`: the pre-travel variation of a touch probe with the direction of contact;
- `ZonalForm`: the form error of a ball (the probe's ruby, a reference sphere) as a few
  low-order spherical harmonics.

The optical instruments sample through `spot_heights` and `line_heights` here, which read the
exact top surface (`machinesim.metrology.surface`) at many points and average them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import hermite, legendre

from machinesim.arrays import frozen
from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_floats, as_number, shown
from machinesim.metrology.blur import gaussian_blur
from machinesim.metrology.instruments import OPTICAL_LIMIT
from machinesim.metrology.surface import _finish, _Line, _zbuffer, grid_heights
from machinesim.tolerances import LINE_MARGIN

__all__ = ["Lobing", "Registration", "RegistrationScatter", "Spot", "ZonalForm",
           "line_heights", "spot_heights"]

SPOT_SHAPES = ("gaussian", "tophat")
#: Largest slope of a `Registration`'s tilt (each of its two), rad: 10 mrad, 50 times the
#: lab's 0.2 mrad scatter (a part levelled on the stage). The tilt is applied as a shear of
#: heights, leaving out the sideways move of tilt x height, which at 10 mrad is already 1 %
#: of every height; a part that leans more is no levelled part. A tilt in mrad given as rad
#: lies above it: tilt=(0.2, 0), 0.2 mrad meant, had sheared the part by 0.2 (11 deg).
TILT_LIMIT = 1e-2
#: Samples of a sub-grid read per call of the height map (rows are read in blocks): keeps a
#: block's arrays at ~100 MB whatever the map's size.
BLOCK_SAMPLES = 4_000_000
#: Least share of a spot's weight that must lie on the part for a sample to read: below it
#: the sample reads nothing (NaN), as a sample off the part does without a spot. Half puts
#: the edge of a part or of a hole read through a symmetric spot where the spot's centre
#: crosses it, as without one, whatever the spot's ``samples``; averaging whatever points hit
#: the part had moved the edge out to the spot's outermost node (a 3 um FWHM Gaussian: 3.6 um
#: at 5 samples, 10 um at 25), reading a hole smaller the finer the spot was sampled. The
#: slack takes the round-off of weights that sum to exactly half on an edge. A spot of an even
#: ``samples`` has no node at its centre, and its weight on the part is exactly half wherever
#: its centre lies within its innermost node's offset of a straight edge, on either side (a
#: 3 um Gaussian of 2 samples: 1.27 um): there the spot's centre decides, as a point sample
#: (`SPOT_TIE`).
SPOT_COVER = 0.5 - 1e-12
#: Weights within this of half on the part are a tie, read only where the spot's centre, as a
#: point sample, is on the part (it reads NaN otherwise): else an even spot read up to its
#: innermost node's offset into a hole (a 10 um hole through a 3 um Gaussian of 2 samples
#: read 2.5 um narrower), the edge again set by the quadrature, not by the spot.
SPOT_TIE = 1e-12
#: Unit vectors on which a drawn form is scaled to its stated peak-to-valley: a Fibonacci
#: sphere this dense puts every point within ~0.04 rad of a sample, where a degree-4 term
#: moves by under 1 % of its amplitude.
FORM_POINTS = 4000


def _fwhm_sigma(fwhm: float) -> float:
    return fwhm / (2.0 * math.sqrt(2.0 * math.log(2.0)))


@dataclass(frozen=True)
class Spot:
    """The area over which an optical instrument averages the surface at one sample.

    Parameters
    ----------
    width : float
        m, > 0 and at most `machinesim.metrology.instruments.OPTICAL_LIMIT` (1 mm): the full
        width at half maximum of a ``"gaussian"`` spot (round), or the side of a ``"tophat"``
        (a square pixel aligned with the instrument's x and y).
    shape : {"gaussian", "tophat"}
    samples : int
        Points per axis of the sub-grid that stands for the spot (>= 1); the reading is the
        weighted mean of the exact heights at ``samples**2`` points. A Gaussian uses the
        Gauss-Hermite nodes and weights (exact for heights that are polynomials of degree
        up to ``2 samples - 1``), a top-hat equally weighted points at the centres of
        ``samples`` equal cells: a step edge read across then rises in ``samples`` equal
        steps over the width, the top-hat's ramp in the limit.
    exact : bool
        False (default): the sub-grid above. True (a ``"gaussian"`` spot only): the exact
        Gaussian blur of the mesh's top surface, integrated in closed form over each of its
        planes (`machinesim.metrology.blur`), ``samples`` unused: a wall or a kink reads the
        blur of a true Gaussian spot wherever it lies, not a staircase where the nodes cross
        it. Its weight on the part decides as the sub-grid's (`SPOT_COVER`, `SPOT_TIE`). A
        part read as a height field has no planes: refused there as every spot is.

    Notes
    -----
    A plane reads unchanged through either spot: the offsets are symmetric and the weights
    sum to one. A sample whose sub-grid partly misses the part (an edge, a through hole)
    averages the points that hit it when they carry at least half the spot's weight
    (`SPOT_COVER`), else reads nothing (NaN): the edge reads where the spot's centre crosses
    it, as without a spot, whatever ``samples``.
    """

    width: float
    shape: str = "gaussian"
    samples: int = 5
    exact: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "width", as_number(
            self.width, "width", sign="> 0", limit=OPTICAL_LIMIT,
            why=" (OPTICAL_LIMIT: the widest field of view modelled)"))
        if self.shape not in SPOT_SHAPES:
            raise InputError(f"Expected a spot shape in {SPOT_SHAPES}, got {self.shape!r}",
                             key="shape")
        if isinstance(self.samples, bool) or not isinstance(self.samples, int | np.integer) \
                or self.samples < 1:
            raise InputError(f"Expected samples an int >= 1, got {self.samples!r}",
                             key="samples")
        object.__setattr__(self, "samples", int(self.samples))
        if not isinstance(self.exact, bool | np.bool_):  # "no" is no True
            raise InputError(f"Expected exact as True or False, got {self.exact!r:.60}",
                             key="exact")
        if self.exact and self.shape != "gaussian":
            raise InputError(f"Expected exact=True with a 'gaussian' spot (the closed form "
                             f"is the Gaussian's), got shape {self.shape!r}", key="exact")
        object.__setattr__(self, "exact", bool(self.exact))

    def axis(self) -> tuple[np.ndarray, np.ndarray]:
        """Offsets (m) and weights along one axis, each shape (samples,); weights sum to 1."""
        n = self.samples
        if self.shape == "tophat":
            offsets = ((np.arange(n) + 0.5) / n - 0.5) * self.width
            return offsets, np.full(n, 1.0 / n)
        nodes, weights = hermite.hermgauss(n)
        # integral of f(x) exp(-x**2 / (2 s**2)) / (s sqrt(2 pi)) = sum w_i f(sqrt(2) s x_i)
        return math.sqrt(2.0) * _fwhm_sigma(self.width) * nodes, weights / math.sqrt(math.pi)


@dataclass(frozen=True)
class RegistrationScatter:
    """How far a drawn `Registration` strays (standard deviations).

    Attributes
    ----------
    offset_xy : float
        m, of each of the instrument origin's x and y on the workpiece.
    offset_z : float
        m, of the height zero.
    rotation : float
        rad, of the instrument's x axis about z.
    tilt : float
        rad, of each of the two slopes.
    """

    offset_xy: float
    offset_z: float
    rotation: float
    tilt: float

    def __post_init__(self) -> None:
        for name, unit in (("offset_xy", "m"), ("offset_z", "m"), ("rotation", "rad"),
                           ("tilt", "rad")):
            object.__setattr__(self, name, as_number(getattr(self, name), name, sign=">= 0",
                                                     unit=unit))


@dataclass(frozen=True, eq=False)
class Registration:
    """Where an optical instrument's frame sits on the workpiece.

    The instrument reads the surface in its own frame: its point ``(xi, yi)`` is the
    workpiece's ``R(rotation) (xi, yi) + offset[:2]``, and the height it shows there is the
    workpiece's plus ``offset[2] + tilt[0] xi + tilt[1] yi``. The tilt is applied as a shear
    of heights (x and y stay): a true rotation would also move each point sideways by the
    tilt times its height (1 um at 1 mrad and 1 mm of height; 40 nm between paper 002's
    crown top and its flat 0.2 mm below at the lab's 0.2 mrad), and lower it by tilt^2 x / 2
    (under 1 nm for tilts below 1 mrad over 1 mm): the shear leaves the sideways part out.

    What the shear does that a tilt would not: it changes the angle between two faces. A
    rotation turns every face by one angle; the shear turns a face of slope ``a`` along the
    tilt ``t`` (its angle ``alpha = atan a``) by ``atan(a + t) - atan(a) ~ t cos^2 alpha``,
    so the angle between faces at ``alpha1`` and ``alpha2`` changes by about ``t (cos^2
    alpha1 - cos^2 alpha2)``, against the flat by ``-t sin^2 alpha``: -0.038 t for paper
    002's crown faces (slope 0.2), 7.7 urad (0.00044 deg) at the lab's 0.2 mrad. In general,
    faces of upward unit normals ``n1``, ``n2`` at the angle ``beta``, ``h1``, ``h2`` their
    x-y parts, under the tilt vector ``t``: ``((t.h1)(n2z - n1z cos beta) + (t.h2)(n1z - n2z
    cos beta)) / sin beta`` to first order (tests/test_registration_shear.py checks both
    against a rotated part).

    Parameters
    ----------
    offset : array-like, shape (3,)
        m: the instrument origin in the workpiece's x, y; the height offset.
    rotation : float
        rad: the instrument's x axis turned about z from the workpiece's.
    tilt : array-like, shape (2,)
        The slopes dz/dx and dz/dy the part shows in the instrument frame (rad), each at
        most `TILT_LIMIT` (10 mrad) in size.
    """

    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: float = 0.0
    tilt: np.ndarray = field(default_factory=lambda: np.zeros(2))

    def __post_init__(self) -> None:
        object.__setattr__(self, "offset", _finite(self.offset, (3,), "offset"))
        object.__setattr__(self, "tilt", _finite(self.tilt, (2,), "tilt"))
        if np.abs(self.tilt).max() > TILT_LIMIT:
            raise InputError(f"Expected tilt slopes within {TILT_LIMIT:g} rad in size "
                             "(TILT_LIMIT: a levelled part, where the shear of heights "
                             "holds; the slopes are in rad, not mrad), got "
                             f"{self.tilt.tolist()}", key="tilt")
        object.__setattr__(self, "rotation", float(_finite(self.rotation, (), "rotation")))

    @classmethod
    def draw(cls, rng: np.random.Generator, scatter: RegistrationScatter) -> Registration:
        """One registration: independent normal deviates, in the order x, y, z, rotation,
        tilt x, tilt y."""
        d = rng.standard_normal(6)
        return cls(d[:3] * [scatter.offset_xy, scatter.offset_xy, scatter.offset_z],
                   d[3] * scatter.rotation, d[4:] * scatter.tilt)

    def to_workpiece(self, xy) -> np.ndarray:
        """Workpiece (x, y) of instrument points ``xy`` (..., 2), m."""
        xy = np.asarray(xy, dtype=np.float64)
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        return np.stack([c * xy[..., 0] - s * xy[..., 1] + self.offset[0],
                         s * xy[..., 0] + c * xy[..., 1] + self.offset[1]], axis=-1)

    def to_instrument(self, vertices: np.ndarray) -> np.ndarray:
        """The part's vertices (n, 3) as the instrument sees them (its x, y; its heights)."""
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        dx = vertices[:, 0] - self.offset[0]
        dy = vertices[:, 1] - self.offset[1]
        xi = c * dx + s * dy
        yi = c * dy - s * dx
        zi = vertices[:, 2] + self.offset[2] + self.tilt[0] * xi + self.tilt[1] * yi
        return np.column_stack([xi, yi, zi])

    def __repr__(self) -> str:
        return (f"Registration(offset={self.offset.tolist()} m, rotation={self.rotation:g} "
                f"rad, tilt={self.tilt.tolist()})")


@dataclass(frozen=True, eq=False)
class Lobing:
    """Pre-travel variation of a touch probe with the direction of contact (lobing).

    The probe triggers, or its reading settles, when the ball has pressed ``p`` into the
    surface along the contact normal, ``p`` depending on the normal's direction in the
    probe's frame: with ``n`` the unit contact normal (surface to ball centre) there,
    ``h = hypot(n_x, n_y)`` and ``phi = atan2(n_y, n_x)``::

        p(n) = h * sum_k a_k cos(k (phi - phi_k))

    The constant part of a real probe's pre-travel is calibrated into its effective ball
    radius and left out; contacts along the probe axis (``h = 0``) see none. The three lobes
    of a kinematic seat are ``k = 3``; ``k = 1`` is what the centre calibration leaves (it
    shifts every fitted centre by ``-a_1`` towards ``phi_1``, see the tests).

    Parameters
    ----------
    harmonics : sequence of (int, float, float)
        ``(k, a_k, phi_k)``: order >= 1, amplitude m, phase rad.
    """

    harmonics: tuple = ()

    def __post_init__(self) -> None:
        terms = []
        for term in self.harmonics:
            try:
                k, a, phi = term
            except (TypeError, ValueError) as error:
                raise InputError(f"Expected harmonics as (k, amplitude, phase), got {term!r}",
                                 key="harmonics") from error
            if isinstance(k, bool) or not isinstance(k, int | np.integer) or k < 1:
                raise InputError(f"Expected a lobing order k >= 1, got {k!r}", key="harmonics")
            a = float(_finite(a, (), "amplitude"))
            terms.append((int(k), a, float(_finite(phi, (), "phase"))))
        object.__setattr__(self, "harmonics", tuple(terms))

    @classmethod
    def draw(cls, rng: np.random.Generator, amplitudes: dict[int, float]) -> Lobing:
        """A probe with the given amplitude per order (m) and uniformly drawn phases."""
        orders = sorted(amplitudes)
        phases = rng.uniform(0.0, 2.0 * math.pi, len(orders))
        return cls(tuple((k, amplitudes[k], float(p)) for k, p in zip(orders, phases,
                                                                    strict=True)))

    def __call__(self, normal) -> np.ndarray:
        """Pre-travel (m) for unit contact normals (..., 3) in the probe's frame."""
        n = np.asarray(normal, dtype=np.float64)
        h = np.hypot(n[..., 0], n[..., 1])
        phi = np.arctan2(n[..., 1], n[..., 0])
        total = np.zeros(n.shape[:-1])
        for k, a, p in self.harmonics:
            total += a * np.cos(k * (phi - p))
        return h * total


@dataclass(frozen=True, eq=False)
class ZonalForm:
    """Form error of a ball: radial departures as a sum of zonal spherical harmonics.

    The surface of the ball in direction ``v`` (unit, from its centre, in the ball's own
    frame) lies at ``R + sum_i a_i P_{l_i}(v . w_i)``: each term a Legendre polynomial of
    degree ``l_i`` about its own axis ``w_i``, which is a spherical harmonic of that degree.
    Degrees 0 and 1 (a size error and a shift) are left out: a calibration takes them up.

    Parameters
    ----------
    degrees : sequence of int
        Each >= 2.
    amplitudes : array-like, shape (k,)
        m.
    axes : array-like, shape (k, 3)
        Normalised here.
    """

    degrees: tuple = ()
    amplitudes: np.ndarray = field(default_factory=lambda: np.zeros(0))
    axes: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def __post_init__(self) -> None:
        try:  # whole numbers: int() had read 2.7 as degree 2 and "3" as 3
            given = None if isinstance(self.degrees, str | bytes) else tuple(self.degrees)
        except TypeError:
            given = None
        if given is None or any(isinstance(d, bool | np.bool_)
                                or not isinstance(d, int | np.integer) or d < 2
                                for d in given):
            raise InputError(f"Expected form degrees as whole numbers >= 2, got "
                             f"{shown(self.degrees)}", key="degrees")
        degrees = tuple(int(d) for d in given)
        k = len(degrees)
        amplitudes = _finite(self.amplitudes, (k,), "amplitudes")
        axes = np.array(_finite(self.axes, (k, 3), "axes"))
        norms = np.linalg.norm(axes, axis=1)
        if np.any(norms == 0.0):
            raise InputError("Expected non-zero form axes", key="axes")
        object.__setattr__(self, "degrees", degrees)
        object.__setattr__(self, "amplitudes", amplitudes)
        object.__setattr__(self, "axes", frozen(axes / norms[:, None]))

    @classmethod
    def draw(cls, rng: np.random.Generator, peak_to_valley: float,
             degrees=(2, 3, 4)) -> ZonalForm:
        """A form of the given degrees, axes uniform on the sphere, normal amplitudes scaled
        so that its peak-to-valley over `FORM_POINTS` directions is ``peak_to_valley`` (m)."""
        axes = rng.standard_normal((len(degrees), 3))
        raw = cls(tuple(degrees), rng.standard_normal(len(degrees)), axes)
        values = raw(fibonacci_sphere(FORM_POINTS))
        scale = peak_to_valley / np.ptp(values)
        return cls(raw.degrees, raw.amplitudes * scale, raw.axes)

    def __call__(self, directions) -> np.ndarray:
        """Radial departure (m) of the ball's surface in unit directions (..., 3)."""
        v = np.asarray(directions, dtype=np.float64)
        total = np.zeros(v.shape[:-1])
        for degree, a, w in zip(self.degrees, self.amplitudes, self.axes, strict=True):
            total += a * legendre.legval(v @ w, np.eye(degree + 1)[degree])
        return total


def fibonacci_sphere(count: int) -> np.ndarray:
    """``count`` unit vectors (count, 3) spread evenly over the sphere (golden spiral)."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    r = np.sqrt(1.0 - z * z)
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


# ------------------------------------------------------------------------------- sampling


def spot_heights(vertices, triangles, x, y, dx, dy, spot: Spot | None) -> np.ndarray:
    """Heights over the grid ``(x[i] + dx[i], y[j] + dy[j])`` through a spot, (ny, nx).

    ``x``, ``y`` are the nominal sample axes and ``dx``, ``dy`` how far each column and row
    really sits off (lateral noise; zeros for none), all m. Without a spot each value is the
    exact height there; with one, the spot's weighted mean of the exact heights around it
    (its sub-grid's, or with ``exact`` the spot's blur in closed form).
    """
    if spot is not None and spot.exact:
        shape = (len(y), len(x))
        px = np.broadcast_to((x + dx)[None, :], shape).ravel()
        py = np.broadcast_to((y + dy)[:, None], shape).ravel()
        out, tie = _blurred(vertices, triangles, px, py, spot)
        if tie.any():  # the spot's centre decides (`SPOT_TIE`): read those samples bare
            cx, jx = np.unique(px[tie], return_inverse=True)
            cy, jy = np.unique(py[tie], return_inverse=True)
            centre = grid_heights((vertices, triangles), cx, cy)[jy, jx]
            out[np.flatnonzero(tie)[~np.isfinite(centre)]] = np.nan
        return out.reshape(shape)
    ox, wx = (np.zeros(1), np.ones(1)) if spot is None else spot.axis()
    xs, ix = np.unique(((x + dx)[:, None] + ox[None, :]).ravel(), return_inverse=True)
    ys, iy = np.unique(((y + dy)[:, None] + ox[None, :]).ravel(), return_inverse=True)
    ix = ix.reshape(len(x), len(ox))
    iy = iy.reshape(len(y), len(ox))
    out = np.empty((len(y), len(x)))
    rows = max(1, BLOCK_SAMPLES // (len(xs) * len(ox)))
    for j0 in range(0, len(y), rows):
        block = iy[j0:j0 + rows]
        lo, hi = int(block.min()), int(block.max()) + 1
        h = grid_heights((vertices, triangles), xs, ys[lo:hi])
        # (rows, n_y offsets, nx, n_x offsets) heights of every sub-sample of the block
        sub = h[(block - lo)[:, :, None, None], ix[None, None, :, :]]
        weights = wx[None, :, None, None] * wx[None, None, None, :]
        out[j0:j0 + rows], tie = _weighted(sub, weights, axes=(1, 3))
        if tie.any():  # the spot's centre decides (`SPOT_TIE`): read those rows bare
            cx, jx = np.unique(x + dx, return_inverse=True)
            cy, jy = np.unique((y + dy)[j0:j0 + rows], return_inverse=True)
            centre = grid_heights((vertices, triangles), cx, cy)[jy[:, None], jx[None, :]]
            out[j0:j0 + rows][tie & ~np.isfinite(centre)] = np.nan
    return out


def line_heights(vertices, triangles, start, direction, s, ds, across: float,
                 spot: Spot | None) -> np.ndarray:
    """Heights along the line ``start + (s + ds) u + across n`` through a spot, shape (k,).

    ``u`` is the unit ``direction``, ``n`` its left normal; ``ds`` (k,) and ``across`` are the
    lateral noise along and across the line (m). One exact line is read per distinct across
    offset of the spot's sub-grid. A round (Gaussian) spot lays its sub-grid along ``u`` and
    ``n``: its weight is the same in every frame, and the rotated Gauss-Hermite grid is exact
    for the same polynomials, so a line in any direction reads ``samples`` lines. A top-hat
    is a pixel square to the instrument's x and y: its offsets are split into their parts
    along and across the line, up to ``samples**2`` lines for a slanted one. An ``exact``
    spot reads the blur at each sample in closed form, no lines.
    """
    ox, w = (np.zeros(1), np.ones(1)) if spot is None else spot.axis()
    u = np.asarray(direction, dtype=np.float64)
    normal = np.array([-u[1], u[0]])
    if spot is not None and spot.exact:
        origin = np.asarray(start, dtype=np.float64) + across * normal
        points = origin + (s + ds)[:, None] * u
        out, tie = _blurred(vertices, triangles, points[:, 0], points[:, 1], spot)
        if tie.any():  # the spot's centre decides (`SPOT_TIE`): read the line bare there
            centre, inverse = np.unique((s + ds)[tie], return_inverse=True)
            z = _finish(_zbuffer(vertices, triangles,
                                 _LineSamples(origin, u, centre, vertices)))
            out[np.flatnonzero(tie)[~np.isfinite(z[inverse])]] = np.nan
        return out
    offsets = np.stack(np.meshgrid(ox, ox, indexing="ij"), axis=-1).reshape(-1, 2)
    weights = np.outer(w, w).ravel()
    if spot is not None and spot.shape == "gaussian":
        along, side = offsets[:, 0], offsets[:, 1]
    else:
        along, side = offsets @ u, offsets @ normal
    heights = np.empty((len(s), len(offsets)))
    for value in np.unique(side):
        pick = np.flatnonzero(side == value)
        points, inverse = np.unique(((s + ds)[:, None] + along[pick][None, :]).ravel(),
                                    return_inverse=True)
        origin = np.asarray(start, dtype=np.float64) + (across + value) * normal
        line = _LineSamples(origin, u, points, vertices)
        z = _finish(_zbuffer(vertices, triangles, line))
        heights[:, pick] = z[inverse.reshape(len(s), len(pick))]
    out, tie = _weighted(heights, weights[None, :], axes=(1,))
    if tie.any():  # the spot's centre decides (`SPOT_TIE`): read the line bare there
        points, inverse = np.unique((s + ds)[tie], return_inverse=True)
        origin = np.asarray(start, dtype=np.float64) + across * normal
        centre = _finish(_zbuffer(vertices, triangles,
                                  _LineSamples(origin, u, points, vertices)))
        out[np.flatnonzero(tie)[~np.isfinite(centre[inverse])]] = np.nan
    return out


def _blurred(vertices, triangles, px, py, spot: Spot) -> tuple[np.ndarray, np.ndarray]:
    """An ``exact`` spot's reading at the points ``(px, py)`` and its ties, as `_weighted`:
    the blur's mean where its weight on the part is at least `SPOT_COVER`, else NaN."""
    total, weight = gaussian_blur(vertices, triangles, px, py, _fwhm_sigma(spot.width))
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = total / weight
    mean[~(weight >= SPOT_COVER)] = np.nan
    return mean, np.abs(weight - 0.5) <= SPOT_TIE


def _weighted(values: np.ndarray, weights: np.ndarray, axes: tuple
              ) -> tuple[np.ndarray, np.ndarray]:
    """Weighted mean over ``axes`` of the finite values (``weights`` sum to 1 over them); NaN
    where the finite ones weigh less than `SPOT_COVER` (the spot mostly off the part). And
    where they weigh half, to `SPOT_TIE`: a tie, which the caller decides by the spot's
    centre (boolean, the mean's shape)."""
    seen = np.isfinite(values)
    w = np.where(seen, weights, 0.0)
    total = np.sum(w, axis=axes)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.sum(np.where(seen, values, 0.0) * w, axis=axes) / total
    mean[~(total >= SPOT_COVER)] = np.nan
    return mean, np.abs(total - 0.5) <= SPOT_TIE


class _LineSamples(_Line):
    """Samples ``origin + s[i] u`` at sorted ``s`` (any sign), for the exact rasteriser.

    The sample set of `machinesim.metrology.surface` for a profile, at given distances: along
    the axis the line runs most along, the sample coordinate is monotonic in i, so a
    triangle's box maps to one index range.
    """

    def __init__(self, origin, u, s, vertices) -> None:
        self.start = origin
        self.direction = u
        self.px = origin[0] + s * u[0]
        self.py = origin[1] + s * u[1]
        self.size = s.size
        scale = max(np.abs(vertices).max(initial=0.0), np.abs(origin).max(),
                    np.abs(self.px).max(), np.abs(self.py).max())
        self.margin = LINE_MARGIN * scale
        self.axis = 0 if abs(u[0]) >= abs(u[1]) else 1
        self.sign = 1.0 if u[self.axis] > 0 else -1.0
        self.key = self.sign * (self.px if self.axis == 0 else self.py)


def _finite(value, shape: tuple, name: str) -> np.ndarray:
    array = as_floats(value, name, "numbers")
    if array.shape != shape or not np.isfinite(array).all():
        raise InputError(f"Expected {name} as finite numbers of shape {shape}, got "
                         f"{shown(value)}", key=name)
    return frozen(array)
