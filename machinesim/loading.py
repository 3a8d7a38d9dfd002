"""Robot loading: where an industrial robot really puts a workpiece (paper 002, section 2.1).

Paper 002 sets its roughly machined workpieces on the vacuum chuck of the C table with a
6-axis arm (FANUC LR Mate 200iD) whose catalogue repeatability is 30 um. The workpiece then
lands off its ideal place by a position error delta and rotation errors alpha, beta, gamma
(the paper's Fig. 3), which `machinesim.WorkpieceSetting` carries into the kinematics.

The model here draws them from the repeatability alone:

- **Position.** The repeatability RP (ISO 9283) is the mean distance of the attained
  positions from their barycentre plus three standard deviations of that distance. For an
  isotropic Gaussian scatter with standard deviation s per axis the distance follows a
  Maxwell law, mean ``2 s sqrt(2/pi)`` and standard deviation ``s sqrt(3 - 8/pi)``, so
  ``RP = (2 sqrt(2/pi) + 3 sqrt(3 - 8/pi)) s = 3.616 s``: 30 um gives s = 8.3 um per axis.
- **Attitude.** The gripper holds the part over a span (the ``lever``); two points of the
  part that far apart scatter independently by s each, which turns the part by s / lever
  (radians, per axis, small angles). The catalogue gives no orientation repeatability: the
  lever is the parameter that stands for it.

Draws are seeded (`numpy.random.Generator`); the same seed gives the same landing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.errors import WorkpieceSetting
from machinesim.exceptions import InputError, check_length

__all__ = ["LANDING_REACH", "RP_PER_SIGMA", "RobotLoader"]

#: RP / s for an isotropic 3-D Gaussian scatter (module docstring): mean plus three standard
#: deviations of the Maxwell-distributed distance, in units of the per-axis s.
RP_PER_SIGMA = 2.0 * math.sqrt(2.0 / math.pi) + 3.0 * math.sqrt(3.0 - 8.0 / math.pi)
#: Standard deviations of its scatter within which a robot's landing must be a setting that
#: `WorkpieceSetting` takes (`RobotLoader`): beyond it a campaign's landings were refused
#: one trial at a time (2 m, a unit slip, failed every trial).
LANDING_REACH = 3.0


@dataclass(frozen=True)
class RobotLoader:
    """An industrial robot that sets workpieces on the machine table.

    Parameters
    ----------
    repeatability : float
        Position repeatability RP (ISO 9283), m. Default 30 um (paper 002's LR Mate 200iD).
    lever : float
        Span over which the gripper holds the workpiece, m: the rotation scatter per axis is
        the position scatter over it. Default 20 mm, the size of seed 002's workpieces.
    """

    repeatability: float = 30e-6
    lever: float = 20e-3

    def __post_init__(self) -> None:
        for name in ("repeatability", "lever"):
            number = check_length(getattr(self, name), name, positive=name == "lever")
            object.__setattr__(self, name, number)
        self._check_reach()

    def _check_reach(self) -> None:
        """Refuse a robot whose landing `LANDING_REACH` standard deviations out on every
        axis is no setting `WorkpieceSetting` takes (its check, the one rule for how far a
        setting may be off: 1 m, 180 deg), so that the robot is refused once, here, rather
        than each landing drawn beyond it. Such a robot lands the part off by metres or
        turned by half a turn: repeatability 2 m (a unit slip for 2 mm) failed every trial
        of a campaign, each at its landing."""
        position = LANDING_REACH * self.position_sigma
        angle = LANDING_REACH * self.angle_sigma
        try:
            WorkpieceSetting(np.full(3, position), angle, angle, angle)
        except InputError as error:
            raise InputError(
                f"a robot of repeatability {self.repeatability:g} m and lever "
                f"{self.lever:g} m lands the part {LANDING_REACH:g} standard deviations out "
                f"({position:g} m, {angle:g} rad) beyond what a workpiece setting takes: "
                f"{getattr(error, 'message', error)}; expected a repeatability of at most "
                f"{self.largest_repeatability(self.lever):g} m for this lever",
                key="repeatability") from None

    @staticmethod
    def largest_repeatability(lever: float) -> float:
        """The largest repeatability, m, whose landing `LANDING_REACH` standard deviations
        out a `WorkpieceSetting` takes with the gripper's ``lever``, m."""
        from machinesim.errors._checks import LARGEST_ERROR

        sigma = min(LARGEST_ERROR["length"], LARGEST_ERROR["angle"] * lever) / LANDING_REACH
        return RP_PER_SIGMA * sigma

    @property
    def position_sigma(self) -> float:
        """Standard deviation of the position error per axis, m."""
        return self.repeatability / RP_PER_SIGMA

    @property
    def angle_sigma(self) -> float:
        """Standard deviation of each rotation error, rad."""
        return self.position_sigma / self.lever

    def land(self, rng=None) -> WorkpieceSetting:
        """Set one workpiece: its position and rotation errors, drawn.

        Parameters
        ----------
        rng : numpy.random.Generator or int or None
            Source of the draw, or its seed (a non-negative int, numpy's too).

        Returns
        -------
        WorkpieceSetting
            delta (3,) m with standard deviation `position_sigma` per axis; alpha, beta,
            gamma rad with standard deviation `angle_sigma` each.
        """
        from machinesim.metrology.instruments import as_generator

        # as every seeded draw of machinesim takes one: a numpy integer is a seed too
        # ("expected ... an int seed ..., got np.int64(3)"), and a negative one is refused
        # as an InputError (numpy's "ValueError: expected non-negative integer" had passed)
        rng = as_generator(rng)
        delta = self.position_sigma * rng.standard_normal(3)
        alpha, beta, gamma = self.angle_sigma * rng.standard_normal(3)
        return WorkpieceSetting(delta, float(alpha), float(beta), float(gamma))
