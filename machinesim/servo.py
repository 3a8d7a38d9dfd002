"""Servo follow-up error: a sampled PID loop with feed-forward on a plant with mass and damping.

Each axis is modelled as

* plant ``P(s) = 1 / (m s^2 + c s)``: a mass ``m`` (kg; kg m^2 for a rotary axis) on a
  viscous guide of damping ``c`` (N s/m; N m s/rad), driven by a force (torque) ``u``;
* feedback ``C(s) = Kp + Ki / s + Kd s`` on the position error ``e = r - y``;
* acceleration feed-forward ``u_ff = acc_ff * m * a_ref`` passed through a first-order
  low-pass at the system bandwidth ``bandwidth_hz`` (``F(s) = 1 / (s / w_b + 1)``),

in the spirit of the PID + "ATC" (system bandwidth, mass, acceleration feed-forward) parameters
of paper 004 (Table 6). The controller and the feed-forward filter are discretised with the
Tustin rule, the plant with a zero-order hold (``control.sample_system``), the loop is closed in
discrete time (``control.feedback``) and driven by its transfer function's difference equation
(``scipy.signal.lfilter``, equal to ``control.forced_response`` and much faster: tested); no
integrator is written by hand. The sampled loop is checked for stability when the axis is built: a
closed-loop pole on or outside the unit circle raises `ServoDivergenceError` (the paper's
oscillation), so unstable gains never reach a part.

Units of Table 6. The paper prints the gains without units and no plant. The presets read
them per millimetre: Kp in N/mm, Ki in N/(mm s), Kd in N s/mm (linear axes; per mrad for C),
i.e. 1e3 times the printed numbers in SI; M in kg (x, z) and kg m^2 (c); ACCFF x 1000 as the
fraction of the inertial force fed forward; System BW in Hz. The guide damping is not in the
paper: one value for X and Z, `TABLE6_DAMPING`, is chosen so that the "before" preset leaves
the paper's 13 nm P-V of servo form error (Fig. 15(c)) on the program of Cases 1-2 (12.8 nm;
10.5 nm on the Case 3-4 program); the "after" preset's figure is then a prediction
(docs/procedures/sts_turning.md, "Units of Table 6").
The model itself takes SI gains and does not depend on this reading.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from machinesim.arrays import beyond_float64
from machinesim.exceptions import InputError, MachineSimError
from machinesim.servo_files import SERVO_KEYS, SERVO_OPTIONAL_KEYS, servo_from_toml

DEFAULT_SAMPLE_TIME_S = 1e-4  # 10 kHz servo loop
#: The servo loop periods an axis may have, s: a control's loop runs at 10 Hz .. 10 MHz. Far
#: outside, the sampled loop's coefficients underflow (1e-12 s gave no poles at all).
MIN_SAMPLE_TIME_S = 1e-7
MAX_SAMPLE_TIME_S = 0.1
#: Loop periods simulated at a time when a motion is followed: the work arrays of a piece
#: take about 20 MB, however long the motion (a 60000 s feed move at 10 kHz held 4.5 GB in
#: one piece).
FOLLOW_CHUNK = 1 << 18
#: Largest acceleration feed-forward fraction (``AxisServo.acc_ff``): 1 feeds the whole
#: inertial force forward; a control may over-feed a little, twice is beyond any tuning (an
#: ACCFF of 1e9, accepted, had fed a billion times the force forward without a word).
MAX_ACC_FF = 2.0
#: Most loop periods one motion is followed for: 1e9, 27.8 h of motion at 10 kHz, about 30 s
#: of computing per axis (1e8 periods took 3.2 s). A feed far too slow for its move (F0.0001
#: deg/min on a 9000 deg spiral: 5.4e9 s, 5.4e13 periods) had the loop simulated for days,
#: without a word.
MAX_FOLLOW_PERIODS = 10**9


#: `AxisServo`'s repr: the fields it names, and their units on a linear and a rotary axis.
_REPR_FIELDS = (("kp", "Kp"), ("ki", "Ki"), ("kd", "Kd"), ("mass", "mass"),
                ("damping", "damping"))
_LINEAR_UNITS = ("N/m", "N/(m s)", "N s/m", "kg", "N s/m")
_ROTARY_UNITS = ("N m/rad", "N m/(rad s)", "N m s/rad", "kg m^2", "N m s/rad")


class ServoDivergenceError(MachineSimError):
    """The sampled servo loop of an axis is unstable: the axis would oscillate and diverge."""


@dataclass(frozen=True)
class AxisServo:
    """Gains and plant of one axis, SI.

    Attributes
    ----------
    kp, ki, kd : float
        PID gains on the position error: N/m, N/(m s), N s/m (rotary: per rad).
    mass : float
        Moving mass, kg (rotary: inertia, kg m^2); also the feed-forward's mass estimate.
    damping : float
        Viscous damping of the guide, N s/m (rotary: N m s/rad).
    acc_ff : float
        Fraction of the inertial force ``mass * a_ref`` fed forward (0 = none, 1 = all).
    bandwidth_hz : float
        Cut-off of the feed-forward low-pass, Hz; ``inf`` for no filter.
    sample_time_s : float
        Servo loop period, s.
    name : str
        Axis name, used in messages.
    """

    kp: float
    ki: float
    kd: float
    mass: float
    damping: float = 0.0
    acc_ff: float = 0.0
    bandwidth_hz: float = float("inf")
    sample_time_s: float = DEFAULT_SAMPLE_TIME_S
    name: str = "axis"
    _loops: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for key in ("kp", "ki", "kd", "mass", "damping", "acc_ff", "bandwidth_hz",
                    "sample_time_s"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer,
                                                                 np.floating)):
                raise InputError(f"servo parameter {key} of axis {self.name} must be a number "
                                 f"(SI), got {value!r}", key=key)
            if (huge := beyond_float64(value)) is not None:
                raise InputError(f"servo parameter {key} of axis {self.name} must be a finite "
                                 f"number (SI), got {huge}", key=key)
        for key in ("kp", "ki", "kd", "damping", "acc_ff"):
            value = getattr(self, key)
            if not np.isfinite(value) or value < 0.0:
                raise InputError(f"servo gain of axis {self.name} must be finite and >= 0, "
                                 f"got {value!r}", key=key)
        if self.acc_ff > MAX_ACC_FF:
            raise InputError(f"servo parameter acc_ff of axis {self.name} is the fraction of "
                             f"the inertial force fed forward, 0 (none) to 1 (all), at most "
                             f"{MAX_ACC_FF:g}; got {self.acc_ff!r} (Table 6's ACCFF is read x "
                             "1000: 0.001 is 1)", key="acc_ff")
        for key in ("mass", "sample_time_s", "bandwidth_hz"):
            value = getattr(self, key)
            if not (value > 0.0) or np.isnan(value) or (key != "bandwidth_hz"
                                                        and not np.isfinite(value)):
                raise InputError(f"servo parameter of axis {self.name} must be > 0, "
                                 f"got {value!r}", key=key)
        if self.kp == 0.0 and self.ki == 0.0 and self.kd == 0.0:
            raise InputError(f"axis {self.name} has no feedback (Kp = Ki = Kd = 0)", key="kp")
        if not MIN_SAMPLE_TIME_S <= self.sample_time_s <= MAX_SAMPLE_TIME_S:
            raise InputError(f"servo loop period of axis {self.name} must lie in "
                             f"{MIN_SAMPLE_TIME_S:g} .. {MAX_SAMPLE_TIME_S:g} s (a control's "
                             f"servo loop runs at 10 Hz .. 10 MHz), got {self.sample_time_s!r}",
                             key="sample_time_s")
        import warnings

        from scipy.signal import BadCoefficients

        # np.errstate: such an overflow printed numpy's RuntimeWarning above the refusal
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("error", BadCoefficients)
            try:
                loops = self._build()
            # LinAlgError, or scipy's ValueError: the coefficients overflowed to inf (damping
            # = 1e300, mass = 1e-300: 1 / (m s^2 + c s) sampled; Kd = 1e300 alone), which
            # ended a --servo cut with status 1
            except (BadCoefficients, np.linalg.LinAlgError, ValueError):
                raise InputError(
                    f"servo loop of axis {self.name} cannot be formed in float64 (its transfer "
                    f"function's coefficients are badly conditioned) from Kp = {self.kp:g}, "
                    f"Ki = {self.ki:g}, Kd = {self.kd:g}, mass = {self.mass:g}, damping = "
                    f"{self.damping:g} at Ts = {self.sample_time_s:g} s: values far from a "
                    "machine axis' (SI: N/m, kg, N s/m)") from None  # no one key: all
        object.__setattr__(self, "_loops", loops)

    def _build(self):
        import control  # here: python-control and scipy.signal take 1.6 s to import

        ts = self.sample_time_s
        s = control.tf("s")
        plant = control.sample_system(1.0 / (self.mass * s**2 + self.damping * s), ts, "zoh")
        pid = self.kp + self.ki / s + self.kd * s / (ts / 2.0 * s + 1.0)  # proper derivative
        controller = control.sample_system(control.minreal(pid, verbose=False), ts, "tustin")
        # A gain without integral action can come out of the Tustin rule as (z - 1) / (z - 1):
        # cancelled, or the pair reads as a closed-loop pole on the unit circle.
        reduced = control.minreal(controller, verbose=False)
        if _order(reduced) < _order(controller):
            controller = reduced
        if np.isfinite(self.bandwidth_hz):
            ff = 1.0 / (s / (2.0 * np.pi * self.bandwidth_hz) + 1.0)
            ff_d = control.sample_system(ff, ts, "tustin")
        else:
            ff_d = control.tf([1.0], [1.0], ts)
        sensitivity_plant = control.feedback(plant, controller)      # a force -> y
        reference = control.feedback(controller * plant, 1)          # r -> y
        poles = control.poles(reference)
        radius = float(np.max(np.abs(poles))) if poles.size else 0.0
        if radius >= 1.0 - 1e-12:
            gains = (f"at Ts = {ts} s with Kp = {self.kp:g}, Ki = {self.ki:g}, "
                     f"Kd = {self.kd:g}, mass = {self.mass:g}, damping = {self.damping:g}")
            cause = self._continuous_cause()
            if radius > 1.0 + 1e-9:
                raise ServoDivergenceError(
                    f"servo loop of axis {self.name} is unstable (largest closed-loop pole "
                    f"|z| = {_pole(radius)} > 1) {gains}: the axis would oscillate; "
                    f"{cause or 'lower the gains'}")
            edge = ("from an integral gain too small to act against Kp (use Ki = 0 for none) "
                    "or from gains at the edge of stability")
            raise ServoDivergenceError(
                f"servo loop of axis {self.name} has a closed-loop pole on the unit circle "
                f"(|z| = {radius:.12f}) {gains}: a mode that never settles"
                f"{'; ' + cause if cause else ', ' + edge}")
        feed = control.minreal(ff_d * sensitivity_plant, verbose=False) * (self.acc_ff
                                                                           * self.mass)
        return reference, feed, radius

    def _continuous_cause(self) -> str | None:
        """Why the continuous loop, whatever its period, does not settle, or None when only
        the sampling makes it unstable (gains too high for the loop period). Its
        characteristic polynomial is m s^3 + (c + Kd) s^2 + Kp s + Ki, stable (Routh-Hurwitz)
        iff (c + Kd) Kp > m Ki with every coefficient > 0 (Ki = 0: m s^2 + (c + Kd) s + Kp)."""
        if self.kp == 0.0 and self.ki == 0.0:
            return ("there is no position feedback (Kp = Ki = 0): the position drifts "
                    "whatever Kd; give Kp > 0")
        left, right = (self.damping + self.kd) * self.kp, self.mass * self.ki
        if left > right:
            return None
        if self.ki == 0.0:
            return ("nothing damps it (damping = Kd = 0): a P loop on a mass oscillates at "
                    "any Kp; give Kd > 0 or a damping")
        lower = f", or lower Ki below (c + Kd) Kp / m = {left / self.mass:g}" if left else ""
        return (f"(damping + Kd) Kp = {left:g} <= mass Ki = {right:g}: unstable in continuous "
                "time already (Routh-Hurwitz on m s^3 + (c + Kd) s^2 + Kp s + Ki), so lower "
                f"gains alike or a shorter period do not help; raise Kp, Kd or the damping{lower}")

    def __repr__(self) -> str:
        return f"AxisServo({self.summary()})"

    def summary(self) -> str:
        """The axis in one line with its units: linear for an axis named X, Y or Z, rotary
        (per rad, kg m^2) for A, B or C, "SI" for any other name (the kind unknown)."""
        letter = self.name.upper()
        if len(letter) == 1 and letter in "XYZABC":
            units = _ROTARY_UNITS if letter in "ABC" else _LINEAR_UNITS
            gains = ", ".join(f"{label} {getattr(self, key):g} {unit}" for (key, label), unit
                              in zip(_REPR_FIELDS, units, strict=True))
        else:
            gains = "SI, per m or rad: " + ", ".join(f"{label} {getattr(self, key):g}"
                                                     for key, label in _REPR_FIELDS)
        if self.acc_ff:
            filtered = (f" through {self.bandwidth_hz:g} Hz" if np.isfinite(self.bandwidth_hz)
                        else "")
            forward = f"feed-forward {self.acc_ff:.4g} x the inertial force{filtered}"
        else:
            forward = "no feed-forward"
        return f"{self.name}: {gains}; {forward}; loop {self.sample_time_s * 1e3:g} ms"

    @property
    def pole_radius(self) -> float:
        """Largest |z| of the closed loop's poles (< 1: stable)."""
        return self._loops[2]

    def respond(self, t: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Position reached for the command ``r`` sampled at uniform times ``t`` (the loop's
        period), the axis at rest on ``r[0]`` at ``t[0]``."""
        r = np.asarray(r, dtype=np.float64)
        if r.size < 2:
            return r.copy()
        return np.concatenate([y for _, _, y in self._stream(r.size, lambda lo, hi: r[lo:hi])])

    def reach(self, t: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Position reached at the times ``t`` (non-decreasing, s) for the command ``r(t)``,
        linear between its samples, the axis at rest on ``r[0]`` at ``t[0]``.

        The command is resampled to the loop's period from ``t[0]``, simulated, and read back
        at ``t`` (linear interpolation), `FOLLOW_CHUNK` periods at a time: a motion of any
        length needs memory for one piece only.
        """
        t = np.asarray(t, dtype=np.float64)
        r = np.asarray(r, dtype=np.float64)
        if t.size < 2 or not t[-1] > t[0]:
            return r.copy()
        ts = self.sample_time_s
        periods = (t[-1] - t[0]) / ts
        if not periods <= MAX_FOLLOW_PERIODS:
            raise InputError(
                f"servo loop of axis {self.name}: a motion of {t[-1] - t[0]:.6g} s is "
                f"{periods:.3g} loop periods of {ts:g} s, more than the {MAX_FOLLOW_PERIODS:.0e} "
                f"one motion is followed for ({MAX_FOLLOW_PERIODS * ts / 3600.0:.3g} h; "
                "machinesim.servo.MAX_FOLLOW_PERIODS); expected motions of hours at most: is "
                "a feed far too slow (F in another unit), or a dwell that long?")
        n = int(np.ceil(periods)) + 1

        def command(lo, hi):
            return np.interp(t[0] + ts * np.arange(lo, hi), t, r)

        out = np.empty_like(r)
        done, last = 0, None  # samples of t read back; the last grid point and its value
        for a, b, y in self._stream(n, command):
            grid = t[0] + ts * np.arange(a, b)
            if last is not None:
                grid, y = np.concatenate([[last[0]], grid]), np.concatenate([[last[1]], y])
            stop = t.size if b == n else int(np.searchsorted(t, grid[-1], side="left"))
            out[done:stop] = np.interp(t[done:stop], grid, y)
            done, last = stop, (grid[-1], y[-1])
        return out

    def _stream(self, n: int, command):
        """The loop's output over ``n`` periods, ``(a, b, y[a:b])`` a piece at a time, for the
        command given on periods ``lo:hi`` by ``command(lo, hi)``; the filters' state carries
        from piece to piece (`scipy.signal.lfilter`'s ``zi``), so the pieces are the whole
        run's output (tested bit for bit)."""
        reference, feed, _ = self._loops
        ts = self.sample_time_s
        follow = _Filter(reference)
        forward = _Filter(feed) if self.acc_ff > 0.0 else None
        start = None
        for a in range(0, n, FOLLOW_CHUNK):
            b = min(n, a + FOLLOW_CHUNK)
            # two periods either side: the acceleration's central differences at a and b - 1
            # are then those of the whole run
            lo, hi = max(0, a - 2), min(n, b + 2)
            r = command(lo, hi)
            if start is None:
                start = r[0]
            y = follow(r[a - lo:b - lo] - start)
            if forward is not None:
                y = y + forward(np.gradient(np.gradient(r, ts), ts)[a - lo:b - lo])
            yield a, b, start + y


def _pole(radius: float) -> str:
    """A closed-loop pole's |z| for a message: to 9 decimals, which tell one just past the
    unit circle from it, or to 6 digits once it is 1000 or more (Kd = 1e200 put |z| =
    4.1e192 there as 193 digits and 9 decimals)."""
    return f"{radius:.9f}" if radius < 1e3 else f"{radius:.6g}"


def _order(system) -> int:
    """Degree of a SISO transfer function's denominator."""
    import control

    return len(np.trim_zeros(np.asarray(control.tfdata(system)[1][0][0]), "f")) - 1


class _Filter:
    """A discrete SISO system run from rest on an input given a piece at a time: the same as
    ``control.forced_response(system, U=u)`` on the whole input, by `scipy.signal.lfilter`
    on the transfer function's coefficients (compiled: 10^6-10^7 samples in seconds)."""

    def __init__(self, system) -> None:
        import control

        num, den = control.tfdata(system)
        num = np.asarray(num[0][0], dtype=np.float64)
        den = np.asarray(den[0][0], dtype=np.float64)
        # descending powers of z -> powers of z^-1: the numerator's end under the denominator's
        self.num = np.concatenate([np.zeros(den.size - num.size), num])
        self.den = den
        self.state = np.zeros(max(self.num.size, den.size) - 1)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        from scipy.signal import lfilter

        y, self.state = lfilter(self.num, self.den, u, zi=self.state)
        return y


@dataclass(frozen=True)
class PIDServo:
    """A `ServoModel` (``follow(t, q)``) made of one `AxisServo` per axis column; ``None`` for an
    axis that follows its command exactly. Commands are resampled to the loop period, simulated
    and read back at the requested times (linear interpolation)."""

    axes: tuple

    def __post_init__(self) -> None:
        # PIDServo((1, None, None, None)) had been made, and failed in its repr or at the
        # first cut ("'int' object has no attribute 'summary'"), naming no column
        if not isinstance(self.axes, tuple | list):
            raise InputError(f"Expected the axis columns as a tuple, one AxisServo or None per "
                             f"axis of the machine (machine.axes order), got "
                             f"{type(self.axes).__name__}", key="axes")
        for i, axis in enumerate(self.axes):
            if axis is not None and not isinstance(axis, AxisServo):
                raise InputError(f"column {i + 1}: expected an AxisServo or None (the axis "
                                 f"follows exactly), got {type(axis).__name__} {axis!r:.40}",
                                 key="axes")
        object.__setattr__(self, "axes", tuple(self.axes))

    def __repr__(self) -> str:
        parts = [f"column {i + 1} exact" if axis is None else axis.summary()
                 for i, axis in enumerate(self.axes)]
        return f"PIDServo({' | '.join(parts) or 'no axes'})"

    def follow(self, t: np.ndarray, q: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=np.float64)
        q = np.asarray(q, dtype=np.float64)
        if q.ndim != 2 or q.shape[1] != len(self.axes) or t.shape != (q.shape[0],):
            raise InputError(f"PIDServo with {len(self.axes)} axes needs t (N,) and q "
                             f"(N, {len(self.axes)}), got {t.shape} and {q.shape}")
        for name, values in (("t", t), ("q", q)):
            bad = np.flatnonzero(~np.isfinite(values).reshape(len(t), -1).all(axis=1))
            if bad.size:  # NaN had passed through the loops into every later sample
                raise InputError(
                    f"PIDServo.follow: {name} at sample {int(bad[0])} holds "
                    f"{values[bad[0]]!r} ({bad.size} samples not finite); expected finite "
                    f"{'times, s' if name == 't' else 'axis commands (m, rad)'}", key=name)
        out = q.copy()
        for i, axis in enumerate(self.axes):
            if axis is not None:
                out[:, i] = axis.reach(t, q[:, i])
        return out

    def following_error(self, t: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Commanded minus reached axis values, (N, n_axes)."""
        return np.asarray(q, dtype=np.float64) - self.follow(t, q)


# Paper 004, Table 6 (printed values; see the module docstring for the units read into them).
# "after" x System BW is printed 1.5; Table 3 (No. 2, the same tuned set) prints 15: a lost
# digit, and 15 is used. M as Table 6 prints it, where Table 3 No. 1 prints 1, 1, 0.115 and
# the text gives the tuned z's as 3.8 (docs/procedures/sts_turning.md, "Units of Table 6").
TABLE6 = {
    "before": {"x": (60, 7000, 0.9, 12, 4, 0), "z": (100, 7000, 1.2, 12, 4, 0.0009),
               "c": (70, 7000, 0.7, 10, 0.115, 0)},
    "after": {"x": (110, 10000, 1.1, 15, 4, 0.001), "z": (180, 10000, 1.5, 16, 4.8, 0.001),
              "c": (100, 10000, 1.5, 8, 0.3, 0)},
}


#: Guide damping, N s/m (x, z) and N m s/rad (c): not in the paper. 1600 N s/m makes the
#: "before" preset's servo form error over r 150-350 um at theta = 0 on the program of Cases
#: 1-2 (Table 4 "before") 12.8 nm P-V, the paper's 13 nm (Fig. 15(c)); on the Case 3-4
#: program it is 10.5 nm (docs/procedures/sts_turning.md, "Units of Table 6"). The C value
#: does not change it (< 0.01 nm).
TABLE6_DAMPING = {"x": 1600.0, "z": 1600.0, "c": 50.0}

#: SI per printed unit of Kp, Ki and Kd: the gains are read per mm (per mrad for C).
TABLE6_GAIN_SCALE = 1e3


def table6_axis(preset: str, axis: str, *, damping: float | None = None,
                sample_time_s: float = DEFAULT_SAMPLE_TIME_S) -> AxisServo:
    """The `AxisServo` of ``axis`` ("x", "z", "c") for Table 6's ``preset`` ("before", "after")."""
    # a name, not any key: a list or a dict is unhashable, and `in` raised TypeError on it
    if not isinstance(preset, str) or preset not in TABLE6:
        raise InputError(f"unknown servo preset {preset!r}; expected one of {sorted(TABLE6)}",
                         key="preset")
    if not isinstance(axis, str) or axis not in TABLE6[preset]:
        raise InputError(f"unknown axis {axis!r}; expected one of {sorted(TABLE6[preset])}",
                         key="axis")
    kp, ki, kd, bw, mass, accff = TABLE6[preset][axis]
    scale = TABLE6_GAIN_SCALE
    if damping is None:
        damping = TABLE6_DAMPING[axis]
    return AxisServo(kp=kp * scale, ki=ki * scale, kd=kd * scale, mass=mass,
                     damping=damping,
                     acc_ff=accff * 1e3, bandwidth_hz=bw, sample_time_s=sample_time_s,
                     name=axis)


def table6_servo(preset: str, axis_order: tuple = ("x", "z", "c"), **kwargs) -> PIDServo:
    """A `PIDServo` for Table 6's ``preset``, one column per name in ``axis_order`` (names in
    either case; a name not in the table, e.g. "y", follows exactly)."""
    if not isinstance(axis_order, tuple | list | str) or not all(isinstance(a, str)
                                                                 for a in axis_order):
        raise InputError(f"Expected axis_order as axis names, e.g. ('x', 'z', 'c'), got "
                         f"{axis_order!r}", key="axis_order")
    return PIDServo(tuple(table6_axis(preset, a.lower(), **kwargs)
                          if a.lower() in TABLE6["before"] else None for a in axis_order))


#: The axis letters an `AxisServo`'s ``name`` is checked against (`check_servo`).
_AXIS_LETTERS = frozenset("XYZABC")


def check_servo(machine, servo) -> None:
    """Refuse servo loops that do not fit ``machine``: no ``follow(t, q)``; a servo with
    ``axes`` (a `machinesim.servo.PIDServo`) whose column count is not the machine's axis
    count; a column whose ``name`` is an axis letter other than the machine's in that column.

    A ServoModel without ``axes`` cannot be checked before it is run. Names that are not a
    single axis letter (the default "axis", "spindle 1") are not checked.
    """
    if not callable(getattr(servo, "follow", None)):
        hint = (": a servo file is read with machinesim.servo.servo_from_toml(path, machine)"
                if isinstance(servo, str | os.PathLike) else "")
        raise InputError(f"Expected a servo with follow(t, q) (a ServoModel), got "
                         f"{type(servo).__name__}{hint}", key="servo")
    columns = getattr(servo, "axes", None)
    if not isinstance(columns, (tuple, list)):
        return
    axes = tuple(machine.axes)
    letters = ", ".join(axes)
    kind = type(servo).__name__
    if len(columns) != len(axes):
        if isinstance(servo, PIDServo):
            ones = ", ".join(a.lower() for a in axes)
            how = (f": build it with one column per axis in that order, e.g. "
                   f"table6_servo(\"before\", axis_order={axes!r}) or PIDServo(({ones})), "
                   "each an AxisServo(..., name=<its letter>) or None (the axis follows "
                   "exactly)")
        else:
            how = ": give one column per axis, in that order"
        raise InputError(f"a {kind} with {len(columns)} axis columns does not fit "
                         f"{machine.name}, whose {len(axes)} axes are {letters} (in this "
                         f"order){how}", key="servo")
    upper = [a.upper() for a in axes]
    for i, (axis, column) in enumerate(zip(axes, columns, strict=True)):
        name = getattr(column, "name", None)
        if not isinstance(name, str) or name.upper() not in _AXIS_LETTERS:
            continue
        other = name.upper()
        if other != axis.upper():
            fix = (f"put it in column {upper.index(other) + 1} ({other}) or name it {axis!r}"
                   if other in upper else
                   f"{machine.name} has no {other} axis: name it {axis!r} if it is {axis}'s")
            raise InputError(f"the {kind}'s column {i + 1} is {machine.name}'s {axis} axis "
                             f"(axes {letters}), but its {type(column).__name__} is named "
                             f"{name!r}: it would drive {axis} with the loop meant for "
                             f"{other}; {fix}", key="servo")


__all__ = ["DEFAULT_SAMPLE_TIME_S", "FOLLOW_CHUNK", "MAX_ACC_FF", "MAX_FOLLOW_PERIODS",
           "SERVO_KEYS", "SERVO_OPTIONAL_KEYS", "TABLE6", "TABLE6_DAMPING", "TABLE6_GAIN_SCALE",
           "AxisServo", "PIDServo", "ServoDivergenceError", "check_servo", "servo_from_toml",
           "table6_axis", "table6_servo"]
