"""The observation model of `machinesim.identification.fit`: model readings and their Jacobian.

`_Plan` binds displacement readings (`Observations`) to a machine and a list of error
parameters: what each reading would show on the machine with given errors, and its
derivative with respect to the parameters (`Machine.frame_pose` and
`Machine.error_jacobian`, the batched evaluator over every pose at once).
docs/identification.md gives the model.
"""

from __future__ import annotations

import numpy as np

from machinesim.exceptions import AxisLimitError, InputError
from machinesim.identification.observations import Observations
from machinesim.metrology.rtest import refuse_far_points


class _Plan:
    """The readings bound to a machine and a parameter list: model readings and Jacobian."""

    def __init__(self, machine, obs: Observations, names: tuple[str, ...]) -> None:
        # an R-test read on planer_4axis (XYZA) had been fitted on grooving_4axis (XYZC)
        obs.check_machine(machine)
        if obs.q.shape[1] != len(machine.axes):
            raise InputError(
                f"{machine.name} has axes {''.join(machine.axes)}: expected axis values of "
                f"shape (N, {len(machine.axes)}), got {obs.q.shape}", key="q")
        unknown = sorted(set(obs.frames) - set(machine.frames))
        if unknown:
            raise InputError(f"frame {unknown[0]!r} is not on {machine.name}; it has "
                             f"{', '.join(machine.frames)}", key="frames")
        # a point 40 m up the tool (40 mm meant) levers every angle 1000-fold, fitted
        # without a note
        refuse_far_points(machine, obs.points, obs.frames, key="points",
                          what="a point on the tool or a probe")
        outside = machine.limit_violations(obs.q)
        if outside:
            raise AxisLimitError(f"{machine.name}: readings at axis values the machine cannot "
                                 f"take: {'; '.join(outside)} (axis values in m and rad)")
        self.machine = machine
        self.obs = obs
        self.names = names
        frames = np.asarray(obs.frames)
        self.groups = []
        for frame in dict.fromkeys(obs.frames):
            rows = np.flatnonzero(frames == frame)
            unique, inverse = np.unique(obs.q[rows], axis=0, return_inverse=True)
            self.groups.append((frame, rows, unique, inverse.ravel()))
        self.nominal = self._positions(None)
        # readings of sensors set to zero at a pose: less the same reading there
        self.zeroed = np.flatnonzero(obs.zeroed)
        self.zero = None if not self.zeroed.size else _Plan(machine, Observations(
            obs.zero_at[self.zeroed], values=0.0, directions=obs.directions[self.zeroed],
            sigma=obs.sigma[self.zeroed],
            frames=tuple(np.asarray(obs.frames)[self.zeroed].tolist()),
            points=obs.points[self.zeroed]), names)

    def _positions(self, errors) -> np.ndarray:
        """Positions (N, 3) of the observed points in the workpiece frame, m.

        Every distinct pose of a frame at once (a plan reads several points and directions
        per pose) by the batched evaluator (`Machine.frame_pose`), under 1 us a pose on
        robonano_a0ib. It had been one Pinocchio pass a pose (`Machine.pinocchio_pose`,
        15-26 us), most of a fit's time once the Jacobian was batched; the readings of the
        two agree to 2.4e-16 m (tests/test_identification_fit_jacobian.py holds them).
        """
        out = np.empty((len(self.obs), 3))
        for frame, rows, unique, inverse in self.groups:
            poses = self.machine.frame_pose(frame, unique, errors)[inverse]
            out[rows] = poses[:, :3, 3] + np.einsum("nij,nj->ni", poses[:, :3, :3],
                                                    self.obs.points[rows])
        return out

    def readings(self, errors) -> np.ndarray:
        """Model readings (N,), m: u . (x(errors) - x(nominal)), less the same at
        ``zero_at`` for a zeroed reading."""
        out = np.einsum("ni,ni->n", self.obs.directions, self._positions(errors) - self.nominal)
        if self.zero is not None:
            out[self.zeroed] -= self.zero.readings(errors)
        return out

    def jacobian(self, errors) -> np.ndarray:
        """d readings / d parameters (N, k), m per m or per rad."""
        out = np.empty((len(self.obs), len(self.names)))
        for frame, rows, _, _ in self.groups:
            jac = self.machine.error_jacobian(self.obs.q[rows], errors, self.names, frame=frame,
                                              point=self.obs.points[rows])
            out[rows] = np.einsum("ni,nik->nk", self.obs.directions[rows], jac[:, :3, :])
        if self.zero is not None:
            out[self.zeroed] -= self.zero.jacobian(errors)
        return out
