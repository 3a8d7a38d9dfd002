"""How real the lab is: one switch per source of imperfection, and the values a real lab has.

A `machinesim.Lab` reads exactly by default, but for its instruments' noise (today's
behaviour). `Realism` switches on, one by one, what a real laboratory adds:

=====================  ========================================================================
switch                 what it adds (the lab's defaults below, with their sources)
=====================  ========================================================================
instrument_noise       each instrument's height / trigger / displacement noise (its ``sigma``)
lateral_resolution     microscope and white-light interferometer average over a spot
lateral_noise          their sample positions jitter
registration           their frame sits off the workpiece's (offset, rotation, height, tilt);
                       the laser interferometer's beam is misaligned (cosine error)
probe_pretravel        the touch probe's pre-travel varies with the contact direction
probe_ball_form        the probe's ruby ball is not a perfect sphere
artefact_errors        reference spheres are off their designed place, size and form
background_errors      the machine's own residual geometric errors (a well-compensated machine)
stage_positioning      microscope and white-light interferometer: each reading is taken where
                       the stage put it, off its commanded place within the stage's accuracy
air_refraction         the laser interferometer counts in a wavelength its air compensation
                       misses: each set-up reads displacements on a scale off by a drawn ppm
=====================  ========================================================================

Each imperfection draws from its own stream (`machinesim.streams.stream` with the
instrument's kind and label and the switch's name), so turning one off never changes what
another draws: an error budget switches each off in turn (`Realism.without`) and reads the
change. With a switch off the reading is exactly what it was without the feature.

>>> Realism.lab().without("registration").on[:3]
('instrument_noise', 'lateral_resolution', 'lateral_noise')
>>> Realism.noise_only() == Realism.with_only("instrument_noise")
True
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from machinesim.arrays import frozen
from machinesim.background import add_errors, background_model, background_path
from machinesim.exceptions import InputError, check_length
from machinesim.metrology.imperfections import RegistrationScatter, Spot, ZonalForm
from machinesim.tolerances import SPHERE_CHORD_M
from machinesim.units import M_PER_NM, M_PER_UM

__all__ = [
    "ARTEFACT", "MICROSCOPE", "OBJECTIVE_10X", "PROBE", "WHITE_LIGHT", "ActualSpheres",
    "ArtefactScatter", "Objective", "OpticalDefaults", "ProbeDefaults", "Realism",
    "SphereArtefacts", "add_errors", "background_model", "background_path", "draw_spheres",
    "make_spheres",
]


@dataclass(frozen=True)
class Realism:
    """Which imperfections a lab has; each a bool (module docstring). ``Realism()`` has none.

    Presets: `ideal` (none), `noise_only` (today's `Lab` default), `lab` (all). `without`
    and `with_only` build the variants of an error budget.
    """

    instrument_noise: bool = False
    lateral_resolution: bool = False
    lateral_noise: bool = False
    registration: bool = False
    probe_pretravel: bool = False
    probe_ball_form: bool = False
    artefact_errors: bool = False
    background_errors: bool = False
    stage_positioning: bool = False
    air_refraction: bool = False

    def __post_init__(self) -> None:
        for f in fields(self):
            if not isinstance(getattr(self, f.name), bool):
                raise InputError(f"Expected {f.name} as True or False, got "
                                 f"{getattr(self, f.name)!r}", key=f.name)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """Every switch, in order."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def ideal(cls) -> Realism:
        """Nothing: every instrument reads the exact value (rounded to its resolution)."""
        return cls()

    @classmethod
    def noise_only(cls) -> Realism:
        """Instrument noise only: what `machinesim.Lab` does with ``noise=True``."""
        return cls(instrument_noise=True)

    @classmethod
    def lab(cls) -> Realism:
        """Everything a real lab has."""
        return cls(**dict.fromkeys(cls.names(), True))

    @classmethod
    def with_only(cls, *names: str) -> Realism:
        """Only the named switches on."""
        return cls(**dict.fromkeys(_check_names(names), True))

    def without(self, *names: str) -> Realism:
        """A copy with the named switches off."""
        return replace(self, **dict.fromkeys(_check_names(names), False))

    @property
    def on(self) -> tuple[str, ...]:
        """The switches that are on, in order."""
        return tuple(name for name in self.names() if getattr(self, name))

    def __repr__(self) -> str:
        """The preset, or the switches on, or the lab's without those off when fewer are
        (flags: no units): 'Realism(lab: all 10 on)', 'Realism(lateral_noise, registration
        on; 8 off)', 'Realism(lab without registration)'."""
        on, names = self.on, self.names()
        off = tuple(name for name in names if name not in on)
        if not on:
            return f"Realism(ideal: all {len(names)} off)"
        if not off:
            return f"Realism(lab: all {len(names)} on)"
        if len(off) < len(on):
            return f"Realism(lab without {', '.join(off)})"
        named = "noise_only: " if self == Realism.noise_only() else ""
        return f"Realism({named}{', '.join(on)} on; {len(off)} off)"

    def __str__(self) -> str:
        for preset in ("ideal", "noise_only", "lab"):
            if self == getattr(Realism, preset)():
                return preset
        return "+".join(self.on)


def _check_names(names) -> tuple[str, ...]:
    for name in names:
        if name not in Realism.names():
            raise InputError(f"Expected a realism switch in {', '.join(Realism.names())}, got "
                             f"{name!r}", key="realism")
    return tuple(names)


# ------------------------------------------------------------------ the lab's instruments


@dataclass(frozen=True)
class OpticalDefaults:
    """What `Realism` gives an optical instrument of the lab (keyword arguments of it)."""

    spot: Spot
    lateral_sigma: float
    registration: RegistrationScatter
    stage_sigma: float = 0.0


#: The laser confocal microscope (Keyence VK-X class; paper 002 names the VK-X50, paper 001
#: a laser confocal microscope). Spot: a Gaussian of 0.3 um FWHM, between the diffraction
#: limits 0.61 lambda / NA of a 50x / 0.95 objective at the 405-408 nm of the violet-laser
#: models (0.26 um) and at the 658 nm of the red-laser ones (0.42 um); no data sheet of the
#: VK-X50 was at hand: assumed from lambda / NA. Lateral noise: 20 nm per scan line and
#: column (assumed: scan-mirror position repeatability, well under the 0.1 um pixel).
#: Registration (all assumed; a microscope stage has no reference to the workpiece's origin
#: but what the operator sets on it): the origin set on a part edge or corner under the
#: objective to 5 um in x and y, the part's x turned on the stage by 1 mrad (an edge aligned
#: by eye over a ~1 mm field), the height zero anywhere within 10 um (the focus), the part
#: tilted by 0.2 mrad (levelled on the stage; procedures level their data anyway).
#: Stage positioning: 1 um per axis and reading (assumed from the accuracy class of the XY
#: stages of measuring microscopes, (2.2 + 0.02 L) um with L in mm, e.g. Mitutoyo's MF
#: series, read as a +-2 sigma band over the sub-millimetre moves between fields; a confocal
#: microscope's motorised stage is of that class or worse). Each profile or map is one
#: placement of the stage; a reading longer than one field is taken as one placement too.
MICROSCOPE = OpticalDefaults(Spot(0.3e-6, "gaussian"), 20 * M_PER_NM,
                             RegistrationScatter(5 * M_PER_UM, 10 * M_PER_UM, 1e-3, 0.2e-3),
                             1 * M_PER_UM)
@dataclass(frozen=True)
class Objective:
    """A microscope objective other than the lab's default 50x: what changes with it.

    Attributes
    ----------
    name : str
    spot : Spot
        The lateral resolution at it (with `Realism.lateral_resolution`).
    sigma : float
        Height noise per sample, m (with `Realism.instrument_noise`).
    pixel : float
        The image's pixel pitch, m: the sample spacing, and where an operator's cursor can
        sit (`machinesim.metrology.crown_image`).
    """

    name: str
    spot: Spot
    sigma: float
    pixel: float


#: The confocal microscope's 50x / 0.95 height noise (`machinesim.metrology.Microscope`).
_SIGMA_50X = 12 * M_PER_NM


def _axial_width(na: float) -> float:
    """A confocal microscope's axial response width on a mirror, relative units:
    lambda / (1 - cos alpha), alpha the objective's half angle (NA = sin alpha, in air)."""
    return 1.0 / (1.0 - np.sqrt(1.0 - na * na))


#: The confocal microscope at a 10x / 0.30 objective, as an operator reads a whole face of
#: paper 002's crown in one image (section 3.2.3: L from two points on an edge, S from the
#: face's height and length). Field (assumed, VK-X class at 10x): about 1.35 mm x 1.01 mm
#: on 1024 x 768 pixels, so one image holds a whole top edge (1.24 mm) and a face with the
#: top and the flat either side; pixel 1.32 um. Spot: 1.0 um FWHM, between 0.61 lambda / NA
#: at 408 nm (0.83 um) and at 658 nm (1.34 um). Height noise: the 50x's 12 nm scaled by the
#: confocal axial response width, lambda / (1 - cos alpha): 15.0 times wider at NA 0.30 than
#: at 0.95, so 0.18 um (assumed: the peak is found to the same fraction of its width).
OBJECTIVE_10X = Objective("10x / 0.30", Spot(1.0e-6, "gaussian"),
                          float(_SIGMA_50X * _axial_width(0.30) / _axial_width(0.95)),
                          1.35e-3 / 1024)

#: The white-light (coherence scanning) interferometer, 20x / 0.4 objective: spot 0.8 um
#: FWHM (0.61 lambda / NA at 0.55 um, the centre of its white light: 0.84 um); lateral noise
#: 10 nm (assumed: the camera's pixels are fixed, vibration moves the field between frames);
#: registration and stage positioning as the microscope's (the same stage practice).
WHITE_LIGHT = OpticalDefaults(Spot(0.8e-6, "gaussian"), 10 * M_PER_NM, MICROSCOPE.registration,
                              MICROSCOPE.stage_sigma)


@dataclass(frozen=True)
class ProbeDefaults:
    """What `Realism` gives the lab's touch probe and laser interferometer."""

    lobing: dict
    sphericity: float
    beam_alignment: float
    air_scale: float


#: The on-machine probe (paper 002's FANUC NANO CHECKER, an air-loaded displacement probe with
#: a R0.25 mm ruby ball; no data sheet of its lobing is published). Lobing: 3 lobes of 0.10 um
#: and a first-order residual of 0.02 um (assumed: below the 2-D lobing of +-0.25 um that
#: strain-gauge machine-tool probes of the Renishaw OMP400 class state, since the NANO
#: CHECKER reads a displacement at a low, air-set force; the first order is what a centre
#: calibration on a reference sphere leaves, one fifth of the lobing). Ball form: 0.13 um
#: peak to valley, the sphericity of an ISO 3290 grade 5 ball, the standard grade of ruby
#: styli (grade 3, 0.08 um, on request). Laser interferometer beam alignment: 0.1 mrad per
#: axis (assumed: the return beam kept centred on its target to ~0.03 mm over a 300 mm
#: travel), a cosine error of 5e-9 of the travel. Laser interferometer air compensation:
#: 0.5 ppm per set-up (standard deviation of the scale its displacements are read on). The
#: wavelength in air moves 1 ppm for 1 deg C of air temperature, 2.5 mmHg of pressure or 80 %
#: of humidity (HP 5528A laser measurement system manual, "Velocity-of-light compensation";
#: -0.95 ppm/K and +0.27 ppm/hPa by the Boensch-Potulski equation, Int. J. Metrol. Qual.
#: Eng. 2023, Table 1); the compensation reads the air at its sensor, and the air along the
#: beam differs from set-up to set-up: 0.5 ppm is 0.5 K of it unseen (assumed, a round value
#: of the order that gives paper 003's map after compensation; its text gives none).
PROBE = ProbeDefaults({1: 0.02 * M_PER_UM, 3: 0.10 * M_PER_UM}, 0.13 * M_PER_UM, 0.1e-3,
                      0.5e-6)


# ------------------------------------------------------------------------------ artefacts


@dataclass(frozen=True)
class ArtefactScatter:
    """How far actual reference spheres stray from their design.

    Attributes
    ----------
    position : float
        m, standard deviation of each coordinate of each centre.
    radius : float
        m, standard deviation of the radius error, common to the spheres of one workpiece
        (one ball end mill cut them all).
    form : float
        m, peak to valley of each sphere's form error (a drawn `ZonalForm`).
    """

    position: float
    radius: float
    form: float

    def __post_init__(self) -> None:
        for name in ("position", "radius", "form"):
            object.__setattr__(self, name, check_length(getattr(self, name), name))


#: Paper 002's reference spheres, ball-end-milled by an ordinary machining centre (1 um
#: resolution) with the rough shape (section 3.2.1). Position: 1 um per coordinate, so that
#: the workpiece position found from three spheres is off by ~1.7 um (1 um times sqrt 3) and
#: its inclination by ~0.007 deg (1 um times sqrt 2 over the 12 mm between spheres): the
#: paper's "less than 1-2 um ... in accordance with the errors obtained in the machining
#: tests" (section 2.3). That inclination, 0.12 mrad, leaves about 0.2 um between opposite
#: groove ends 1.9 mm apart: over seeds 0-15 the grooves after spread 127-709 nm (median
#: 248 nm), where the paper's came within about 100 nm of each other (Fig. 8b), the low
#: tenth of that spread (docs/procedures/workpiece_setting.md); the scatter is not narrowed
#: to land on it.
#: The paper's "5 um and 0.02 degree" is its estimate of what a sphere shift could do, which
#: its tests did not show; with 3 um per coordinate (that estimate) the grooves after came out
#: 0.87 um apart. Radius: 3 um (assumed: the radius tolerance of a precision R2 ball end mill,
#: +-5 um class; the paper takes the mean measured radius because "the machined sphere radius
#: is a little different from the targeted one"). Form: 2 um peak to valley (assumed, so that
#: its effect on the workpiece position is of the paper's "less than 1-2 um").
ARTEFACT = ArtefactScatter(1 * M_PER_UM, 3 * M_PER_UM, 2 * M_PER_UM)

#: Resolution of the tool holder's adjuster (m): an operator's move of the tool lands within
#: +-half of it (`machinesim.Lab.adjust_tool`). Chosen from paper 004, Table 5: its
#: tool-workpiece alignment left dx and dy at 0.25 um, half of a 0.5 um step.
TOOL_ADJUSTER_RESOLUTION_M = 0.5 * M_PER_UM
#: Stroke of the adjuster (m): a move of more than this along any axis is refused, judged on
#: the move alone (assumed: a micrometre-screw tool holder of +-5 mm; resetting a tool
#: further is a new tool setting, `ErrorModel`'s tool offset, not an adjustment).
TOOL_ADJUSTER_STROKE_M = 5e-3


@dataclass(frozen=True, eq=False)
class SphereArtefacts:
    """Reference spheres as designed, cut into (cavities) or onto (bumps) a stock.

    Parameters
    ----------
    centres : array-like, shape (N, 3)
        Designed centres, workpiece frame, m.
    radius : float
        Designed radius, m.
    cavities : bool
        True: the stock minus the spheres (paper 002's ball-end-milled cavities). False: plus.
    chord_tol : float
        Largest facet depth of each sphere polygon, m (`machinesim.tools.sphere_polygon`).
    """

    centres: np.ndarray
    radius: float
    cavities: bool = True
    chord_tol: float = SPHERE_CHORD_M

    def __post_init__(self) -> None:
        centres = np.array(self.centres, dtype=np.float64)
        if centres.ndim != 2 or centres.shape[1] != 3 or not len(centres) \
                or not np.isfinite(centres).all():
            raise InputError(f"Expected sphere centres of shape (N, 3) (m), got "
                             f"{centres.shape}", key="centres")
        object.__setattr__(self, "centres", frozen(centres))
        object.__setattr__(self, "radius", check_length(self.radius, "radius", positive=True))
        object.__setattr__(self, "chord_tol", check_length(self.chord_tol, "chord_tol",
                                                           positive=True))
        _check_sphere_polygon(self.radius, self.chord_tol)
        if not isinstance(self.cavities, bool):
            raise InputError(f"Expected cavities as True or False, got {self.cavities!r}",
                             key="cavities")


def _check_sphere_polygon(radius: float, chord_tol: float) -> None:
    """Refuse a sphere whose polygon (`machinesim.tools.sphere_polygon`, about segments^2 / 4
    vertices) would exceed `MAX_TOOL_VERTICES`: a radius of 1 (mm given as m) at the
    default chord_tol is 12 million vertices a sphere, which were built without end."""
    import math

    from machinesim.tool_sizes import MAX_TOOL_VERTICES
    from machinesim.tools import arc_segments

    segments = 4 * math.ceil(arc_segments(radius, 2.0 * math.pi, chord_tol) / 4)
    if segments ** 2 // 4 > MAX_TOOL_VERTICES:
        raise InputError(f"a sphere of radius {radius:.6g} m at chord_tol {chord_tol:.3g} m "
                         f"would be a polygon of some {segments ** 2 // 4:,} vertices, over "
                         f"MAX_TOOL_VERTICES ({MAX_TOOL_VERTICES:,}): expected the radius in "
                         "m (1 mm is 0.001), or a larger chord_tol", key="radius")


@dataclass(frozen=True, eq=False)
class ActualSpheres:
    """Reference spheres as a lab made them: part of the lab's truth (`Lab.reveal_artefacts`).

    Attributes
    ----------
    centres : ndarray, shape (N, 3), m
    radius : float, m
    forms : tuple of ZonalForm or None
        Each sphere's form error about its centre (None: perfect).
    """

    centres: np.ndarray
    radius: float
    forms: tuple


def draw_spheres(design: SphereArtefacts, scatter: ArtefactScatter | None,
                 rng_position: np.random.Generator | None = None,
                 rng_radius: np.random.Generator | None = None,
                 rng_form: np.random.Generator | None = None) -> ActualSpheres:
    """Actual spheres for a design; ``scatter`` None gives the design itself."""
    if scatter is None:
        return ActualSpheres(design.centres, design.radius, (None,) * len(design.centres))
    n = len(design.centres)
    centres = design.centres + scatter.position * rng_position.standard_normal((n, 3))
    radius = design.radius + scatter.radius * float(rng_radius.standard_normal())
    if radius <= 0.0:
        raise InputError(f"Expected a drawn sphere radius > 0, got {radius} m: the radius "
                         f"scatter {scatter.radius} m is too large for {design.radius} m",
                         key="radius")
    forms = tuple(ZonalForm.draw(rng_form, scatter.form) if scatter.form > 0.0 else None
                  for _ in range(n))
    return ActualSpheres(frozen(centres), radius, forms)


def make_spheres(stock, design: SphereArtefacts, actual: ActualSpheres):
    """The stock with the actual spheres cut into it (or added): a `Part`.

    With the design's own values (no scatter) this is the design made exactly: one sphere
    polygon translated to each centre, unioned in one batch, subtracted (or added) once, as
    `machinesim.cam.crown.crown_stock` and `machinesim.workpiece.block_with_spheres` do (the
    same vertices bit for bit; manifold3d may list the triangles in another order). With a
    form, each vertex of the polygon is moved along its radius onto the actual sphere.
    """
    import manifold3d

    from machinesim.tools import sphere_polygon
    from machinesim.workpiece import Part

    solid = stock.manifold if hasattr(stock, "manifold") else stock
    base = sphere_polygon(actual.radius, design.chord_tol)
    spheres = []
    for centre, form in zip(actual.centres, actual.forms, strict=True):
        sphere = base
        if form is not None:
            def warp(points, form=form, radius=actual.radius):
                points = np.asarray(points, dtype=np.float64)
                r = np.linalg.norm(points, axis=1, keepdims=True)
                return points * ((radius + form(points / r)[:, None]) / r)
            sphere = base.warp_batch(warp)
        spheres.append(sphere.translate(tuple(float(v) for v in centre)))
    union = manifold3d.Manifold.batch_boolean(spheres, manifold3d.OpType.Add)
    return Part(solid - union if design.cavities else solid + union)
