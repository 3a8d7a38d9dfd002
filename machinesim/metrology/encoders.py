"""The machine's own axis encoders, as its control records them: the follow-up error.

A control samples every axis' scale (its linear or rotary encoder) each servo period and can
record the commanded and the measured position side by side (FANUC's servo guide, Heidenhain's
oscilloscope). Their difference, command minus position, is the follow-up (following) error
paper 004 tunes its servo loops against (section 3.3, Table 6, Fig. 14).

`Encoders` plans a program's commanded trajectory (`machinesim.motion.plan` on the nominal
machine: the control interpolates without knowing the machine's errors), runs it through the
lab's servo loops as `Lab.cut` does (the planner's ``servo`` slot: each run of feed moves
one continuous motion), and reads the positions reached through the readout of each axis:
Gaussian noise, then rounding to the axis' resolution (the machine's URDF ``resolution``).
What it records is the motion the lab cuts with. Like every instrument it keeps a function
(``follow``), not the servo model, so nothing it returns exposes the loops' gains (the
honesty rule).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from machinesim.arrays import frozen
from machinesim.exceptions import AxisLimitError, InputError
from machinesim.metrology._arrays import as_flag, as_floats, as_number
from machinesim.metrology.instruments import Readout, as_generator, within_readout_limit

__all__ = ["ENCODER_SIGMA_OF_RESOLUTION", "MAX_RECORDED_SAMPLES", "EncoderReading", "Encoders"]

#: Noise of an encoder reading, as a fraction of the axis' resolution (assumed: the
#: interpolation jitter of a scale interpolated down to its resolution stays below one step).
ENCODER_SIGMA_OF_RESOLUTION = 0.3
#: Most samples `Encoders.record` takes with a ``period_s`` (about 1 GB of arrays).
MAX_RECORDED_SAMPLES = 20_000_000


@dataclass(frozen=True, eq=False)
class EncoderReading:
    """A recorded run: times, commanded and measured axis values (SI: m, rad).

    Attributes
    ----------
    axes : tuple of str
        Axis letters, the columns of ``commanded`` and ``position``.
    t : ndarray (N,)
        Times, s.
    commanded : ndarray (N, n_axes)
        The control's commands.
    position : ndarray (N, n_axes)
        What the encoders read.
    machine : str or None
        The name of the machine recorded (None when not known).
    """

    axes: tuple
    t: np.ndarray
    commanded: np.ndarray
    position: np.ndarray
    machine: str | None = None

    def check_machine(self, machine) -> None:
        """Refuse a recording of a machine other than ``machine`` (a `Machine`): its columns
        are that machine's axes, even when as many and named alike."""
        if ((self.machine is not None and self.machine != machine.name)
                or tuple(self.axes) != tuple(machine.axes)):
            raise InputError(f"the recording is of {self.machine or 'an unnamed machine'} "
                             f"(axes {''.join(self.axes)}), not of {machine.name} (axes "
                             f"{''.join(machine.axes)}); expected the encoders' recording of "
                             f"the program on {machine.name}", key="recording")

    @property
    def following_error(self) -> np.ndarray:
        """Command minus measured position, (N, n_axes), m or rad."""
        return self.commanded - self.position

    def peak(self, axis: str) -> float:
        """Largest |following error| of one axis, m or rad."""
        if axis not in self.axes:
            raise InputError(f"unknown axis {axis!r}; the reading has {''.join(self.axes)}",
                             key="axis")
        return float(np.max(np.abs(self.following_error[:, self.axes.index(axis)])))

    def __repr__(self) -> str:
        span = f"{self.t[0]:.6g} .. {self.t[-1]:.6g} s" if len(self.t) else "no time"
        peaks = ", ".join(f"{a} {self.peak(a) * 1e6:.6g} {_micro(a)}" for a in self.axes
                          ) if len(self.t) else "none"
        return (f"EncoderReading({len(self.t)} samples of {''.join(self.axes)} over {span}; "
                f"peak following error {peaks})")


def _micro(axis: str) -> str:
    """um for a linear axis, urad for a rotary one (A, B, C)."""
    return "urad" if axis.upper() in "ABC" else "um"


class Encoders:
    """The control's recording of its axis encoders (module docstring).

    Parameters
    ----------
    machine : Machine
    follow : callable(t, q) -> q
        The axes' response to commands (the lab's servo loops; identity for ideal axes).
    noise : bool
        Encoder noise on or off (rounding to the resolution stays).
    rng : numpy Generator or seed
    sigma : sequence of float, optional
        Noise per axis, m or rad; default `ENCODER_SIGMA_OF_RESOLUTION` x the resolution.
    """

    def __init__(self, machine, follow: Callable, *, noise: bool = True, rng=None,
                 sigma=None) -> None:
        given = sigma
        resolution = np.asarray(machine.resolution, dtype=np.float64)
        sigma = (ENCODER_SIGMA_OF_RESOLUTION * resolution if sigma is None
                 else as_floats(sigma, "sigma", "one noise std per axis (m or rad)"))
        if sigma.shape != resolution.shape:
            raise InputError(f"Expected one sigma per axis ({len(resolution)}), got "
                             f"{sigma.shape}", key="sigma")
        if given is not None:  # the resolution is the machine's: only a given sigma bounded
            for s in sigma:
                within_readout_limit(float(s), "sigma")
        self.machine = machine
        self.readouts = tuple(Readout.of(float(s), float(r), noise, limit=None)
                              for s, r in zip(sigma, resolution, strict=True))
        self._follow = follow
        self._rng = as_generator(rng)

    def __repr__(self) -> str:
        each = ", ".join(f"{a} {r.resolution:.6g} {'rad' if a.upper() in 'ABC' else 'm'}"
                         for a, r in zip(self.machine.axes, self.readouts, strict=True))
        return f"Encoders({self.machine.name}, resolution {each})"

    def record(self, program, *, start=None, period_s: float | None = None,
               allow_overtravel: bool = False) -> EncoderReading:
        """Run ``program`` (an NC program) and record commands and encoder positions.

        By default at the planned samples: each move's start and end, and every sub-step of a
        rotary move. With ``period_s`` (s), as a control's servo trace records them: every
        ``period_s`` from the program's start as well (the command linear between the
        planned samples, as it is), so what happens inside a move (a loop settling after a
        corner, a ramp's error building up) is seen. At most `MAX_RECORDED_SAMPLES` samples.

        A program whose commanded path takes an axis outside its travel is refused
        (`AxisLimitError` naming the axis, the value, its line and the travel), as `Lab.cut`
        refuses the same path; ``allow_overtravel=True`` records it anyway.
        """
        from machinesim import motion
        from machinesim.cutting.tool_runs import _Moves
        from machinesim.motion.following import follow_runs

        allow_overtravel = as_flag(allow_overtravel, "allow_overtravel")
        trajectory = motion.plan(program, self.machine, None, start=start)
        self._check_travel(_Moves(trajectory, len(self.machine.axes)), program,
                           allow_overtravel)
        t = np.asarray(trajectory.t, dtype=np.float64)
        commanded = np.asarray(trajectory.q, dtype=np.float64)
        offsets = np.asarray(trajectory.offsets, dtype=np.int64)
        if period_s is not None:
            t, commanded, offsets = _at_period(t, commanded, offsets, period_s)
        reached = commanded.copy()
        follow_runs(_Follow(self._follow), reached, t, offsets,
                    np.asarray(trajectory.kinds), getattr(program, "exact_stops", ()))
        position = np.column_stack([readout.read(reached[:, i], self._rng)
                                    for i, readout in enumerate(self.readouts)])
        return EncoderReading(tuple(self.machine.axes), frozen(t), frozen(commanded),
                              frozen(position.reshape(commanded.shape)),
                              machine=self.machine.name)

    def record_turning(self, program, *, allow_overtravel: bool = False) -> EncoderReading:
        """Record a turning program (`machinesim.cutting.lathe`): each run of feed moves
        that turn C as the one continuous motion the control runs it as (not move by move
        from rest), sampled at the program's points; the runs one after the other. A
        machine that is no lathe (`machinesim.cutting.lathe.check_lathe`: a mill's C table,
        an axis beyond X, Z and C) is refused, as `Lab.turn` refuses it: its motion is no
        turning run. So is a program whose command takes an axis outside its travel
        (`AxisLimitError`, as `Lab.turn` refuses it), unless ``allow_overtravel``."""
        from machinesim.cutting.lathe import _program_moves, check_lathe, followed, turning_runs

        check_lathe(self.machine)
        allow_overtravel = as_flag(allow_overtravel, "allow_overtravel")
        self._check_travel(_program_moves(program, self.machine), program, allow_overtravel)

        ts, commands, positions, offset = [], [], [], 0.0
        for t, points in turning_runs(program, self.machine):
            reached = followed(self._follow, t, points)
            ts.append(t + offset)
            offset = float(ts[-1][-1])
            commands.append(points)
            positions.append(np.column_stack([readout.read(reached[:, i], self._rng)
                                              for i, readout in enumerate(self.readouts)]))
        return EncoderReading(tuple(self.machine.axes), frozen(np.concatenate(ts)),
                              frozen(np.concatenate(commands)),
                              frozen(np.concatenate(positions)), machine=self.machine.name)

    def _check_travel(self, moves, program, allow: bool) -> None:
        """Raise AxisLimitError where ``moves`` (commanded axis values and their lines, as
        `machinesim.cutting.program._overtravel` reads them) leave an axis' travel, unless
        ``allow``: the descriptions and lines are the cut's."""
        from machinesim.cutting.refusals import _overtravel

        found = _overtravel(self.machine, moves, program, True)
        if found and not allow:
            source = getattr(program, "source", None)
            where = f"{source}: " if source else ""
            raise AxisLimitError(f"{where}{'; '.join(found)}; nothing was recorded "
                                 "(allow_overtravel=True records it anyway)")


def _at_period(t: np.ndarray, q: np.ndarray, offsets: np.ndarray, period: float):
    """The planned samples with, inside each move, every multiple of ``period`` from the
    program's start; the command linear between the planned samples."""
    period = as_number(period, "period_s", sign="> 0", unit="s")
    duration = float(t[-1] - t[0]) if len(t) else 0.0
    if duration / period + len(t) > MAX_RECORDED_SAMPLES:
        raise InputError(f"recording {duration:g} s every {period:g} s takes "
                         f"{duration / period:.3g} samples, more than {MAX_RECORDED_SAMPLES:g}:"
                         " give a longer period_s or record part of the program",
                         key="period_s")
    times, values, bounds = [], [], [0]
    for a, b in zip(offsets[:-1].tolist(), offsets[1:].tolist(), strict=True):
        tm = t[a:b]
        first = math.floor((tm[0] - t[0]) / period) + 1
        last = math.ceil((tm[-1] - t[0]) / period)
        grid = t[0] + period * np.arange(first, last, dtype=np.float64)
        grid = grid[(grid > tm[0]) & (grid < tm[-1])]
        at = np.sort(np.concatenate([tm, grid]), kind="stable")
        times.append(at)
        values.append(np.column_stack([np.interp(at, tm, tm_q) for tm_q in q[a:b].T])
                      if len(grid) else q[a:b])
        bounds.append(bounds[-1] + len(at))
    return (np.concatenate(times), np.concatenate(values).reshape(-1, q.shape[1]),
            np.asarray(bounds, dtype=np.int64))


class _Follow:
    """A follow function as the planner's `machinesim.motion.ServoModel`."""

    def __init__(self, follow: Callable) -> None:
        self.follow = follow
