"""What every virtual instrument shares: a reading with a resolution and a seeded noise model.

An instrument turns an exact value (a height, a skip position, a displacement) into what it
would display: the exact value, plus Gaussian noise, rounded to the instrument's resolution,
in that order (the noise is physical, the rounding is the display). NaN stays NaN.

The instruments themselves live beside this module: `TouchProbe` (``probe_instrument``),
`Microscope` and `WhiteLightInterferometer` (``optical``), `LaserInterferometer`
(``interferometer``); all are exported by `machinesim.metrology`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_flag, as_number, shown

__all__ = ["OPTICAL_LIMIT", "READOUT_LIMIT", "Readout", "as_generator", "as_machine", "motion_of"]

#: Largest height noise ``sigma``, display ``resolution``, spot width, ``lateral_sigma`` and
#: ``stage_sigma`` an optical instrument (`Microscope`, `WhiteLightInterferometer`) takes, m.
#: 1 mm is the field of view of the widest objective modelled (the 10x's 1.35 mm x 1.01 mm,
#: `machinesim.realism.OBJECTIVE_10X`) and 10^5 times the coarsest height noise of the
#: objectives (0.18 um): a spot, a scatter or a noise larger than that reads nothing of the
#: surface in view (a unit slip, mm or um given as m), and a noise of 1e300 m would turn every
#: height to infinity.
OPTICAL_LIMIT = 1e-3
#: Largest noise ``sigma`` and display ``resolution`` of any reading (`Readout`): the laser
#: interferometer's, the touch probe's, the R-test's, each encoder's (m or rad). 1 mm (or
#: 1 mrad) is 10^5 times the noise the lab states of each (2 nm, 20 nm, 50 nm, 0.3 of a 1 nm
#: step); an instrument read to more measures nothing a procedure here identifies, so a
#: larger value is a unit slip (nm or um given as m), as `OPTICAL_LIMIT` bounds the optical
#: instruments'. Before, ``laser_interferometer(sigma=2)`` read with 2 m of noise.
READOUT_LIMIT = 1e-3


@dataclass(frozen=True)
class Readout:
    """Noise and quantisation of one kind of reading.

    Attributes
    ----------
    sigma : float
        Standard deviation of the Gaussian noise added to each reading, in the reading's
        unit (m for every instrument here); 0 adds none.
    resolution : float
        Quantisation step of the displayed reading (same unit); 0 leaves it unrounded.

    Notes
    -----
    With ``sigma`` well above ``resolution`` the displayed reading is unbiased and its
    standard deviation is ``sqrt(sigma**2 + resolution**2 / 12)`` (Sheppard's correction for
    rounding); `std` returns that value.
    """

    sigma: float
    resolution: float

    def __post_init__(self) -> None:
        for name in ("sigma", "resolution"):
            number = as_number(getattr(self, name), name, sign=">= 0")
            object.__setattr__(self, name, number)

    @classmethod
    def of(cls, sigma: float, resolution: float, noise: bool,
           limit: float | None = READOUT_LIMIT) -> Readout:
        """The readout of an instrument built with ``noise=False`` (sigma ignored) or True.

        ``sigma`` is checked either way, and ``noise`` must be a bool; both ``sigma`` and
        ``resolution`` at most ``limit`` (`READOUT_LIMIT`; None: no bound, for an encoder
        whose resolution is the machine's own)."""
        if limit is not None:
            for name, value in (("sigma", sigma), ("resolution", resolution)):
                within_readout_limit(value, name, limit)
        sigma = cls(sigma, resolution).sigma
        return cls(sigma if as_flag(noise, "noise") else 0.0, resolution)

    @property
    def std(self) -> float:
        """Standard deviation of the displayed reading, noise and rounding together (m)."""
        return math.sqrt(self.sigma**2 + self.resolution**2 / 12.0)

    def read(self, exact, rng: np.random.Generator) -> np.ndarray:
        """Display exact values: add the noise, then round to the resolution.

        Parameters
        ----------
        exact : array-like, any shape
            Exact values (m); NaN where there is nothing to read.
        rng : numpy.random.Generator
            Source of the noise; not drawn from when ``sigma`` is 0.

        Returns
        -------
        ndarray, the shape of ``exact``, float64
            Displayed values; NaN where ``exact`` is NaN.
        """
        values = np.array(exact, dtype=np.float64)
        if self.sigma > 0.0:
            values += self.sigma * rng.standard_normal(values.shape)
        if self.resolution > 0.0:
            values = np.round(values / self.resolution) * self.resolution
        return values


def within_readout_limit(value, name: str, limit: float = READOUT_LIMIT) -> float:
    """``value``, a reading's noise or step, as a float >= 0 and at most ``limit``, or an
    InputError naming ``name`` and the bound (`READOUT_LIMIT`)."""
    return as_number(value, name, sign=">= 0", unit="m or rad", limit=limit,
                     why=" (READOUT_LIMIT: 10^5 times the lab's instruments' noise; more is "
                         "a unit slip, e.g. nm given as m)")


def as_generator(rng) -> np.random.Generator:
    """The noise source of an instrument.

    Parameters
    ----------
    rng : numpy.random.Generator or int or None
        A generator (used as is, so several instruments may share one), a seed, or None for
        fresh entropy (readings then differ from run to run, as a real instrument's do).
    """
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or (isinstance(rng, int | np.integer) and not isinstance(rng, bool)
                       and rng >= 0):
        return np.random.default_rng(rng)
    raise InputError(f"Expected rng as a numpy Generator, a non-negative int seed or None, got "
                     f"{shown(rng)}", key="rng")


def as_machine(machine):
    """The machine an instrument stands on: a `machinesim.machines.Machine` as it is, or the
    name of a shipped one (or a URDF path) loaded with `machinesim.load_machine`.

    Raises
    ------
    ModelError
        For an unknown name or a bad URDF (from `load_machine`).
    InputError
        For anything else.
    """
    from pathlib import PurePath

    from machinesim.machines import Machine, load_machine

    if isinstance(machine, Machine):
        return machine
    if isinstance(machine, str | PurePath):
        return load_machine(machine)
    raise InputError(f"Expected machine as a Machine or the name of a shipped one (e.g. "
                     f"'robonano_a0ib'), got {shown(machine)}", key="machine")


def motion_of(machine, errors, frame: str | None = None):
    """The machine's actual motion, as an instrument on it sees it, with no door to ``errors``.

    Returns ``pose(frame, q) -> (..., 4, 4)``: the pose of ``frame`` in the workpiece frame at
    axis values ``q`` on the machine with ``errors``. An instrument keeps this function, not
    the errors: what it reads comes from where the machine really moves, and no attribute of
    the instrument returns the injected model (the honesty rule of DESIGN.md).

    ``frame``, when given, is the frame the instrument rides on: it must be on the machine.

    Raises
    ------
    ErrorModelError
        When ``errors`` does not fit ``machine``.
    InputError
        When ``frame`` is not a frame of ``machine``.
    """
    if frame is not None and frame not in machine.frames:
        # a touch probe asked of a machine without one named only 'probe_tip', an argument
        # its caller (`lab.touch_probe(part)`) had not given
        hint = ("; a touch probe rides on 'probe_tip', its ball centre, which a machine "
                "without a probe lacks: add one to its URDF, a link on a fixed joint of the "
                "tool side (docs/machines.md, robonano_a0ib's probe_body -> probe_tip)"
                if frame == "probe_tip" else "")
        raise InputError(f"Expected a frame of {machine.name} ({', '.join(machine.frames)}), "
                         f"got {frame!r}{hint}", key="frame")
    machine.check_errors(errors)

    def pose(frame: str, q) -> np.ndarray:
        return machine.frame_pose(frame, q, errors)

    return pose
