"""On-machine touch probe (paper 002): a ruby ball moved by the machine's own axes.

The probe of paper 002 (FANUC NANO CHECKER) stands on the B table of the ROBOnano
alpha-0iB beside the tool and moves through the same, erroneous, kinematics; the NC system
records the axis values. So the probe here is commanded in axis values and returns axis
values: where the ball centre is comes from the machine (`Machine.frame_pose` of
``probe_tip`` with the injected errors), where it touches from the part's exact mesh
(`machinesim.metrology.touch_many`). The errors themselves are never read.

The path of the ball. A move q(t) = q_start + t u in axis space carries the ball centre along
c(t) in the workpiece frame. Errors that do not depend on the axis positions (location and
setting errors) turn and shift the linear axes' directions but keep each a translation, so
c(t) is then an exact straight line traversed at constant speed. Position-dependent
(component) errors and rotary axes bend it. So c(t) is sampled and replaced by a polyline,
split until every sampled point lies within `PROBE_CHORD_M` of its chord (checked against the
constant-speed interpolation, so the travel maps back to t linearly); the ball is swept
along the pieces in order and the first contact wins. A straight path stays one piece.

Pre-travel and ball form (off by default; `machinesim.Lab` gives the lab's when
`machinesim.realism.Realism` turns them on). Both move the recorded contact along the
contact normal ``n`` (unit, from the surface to the ball centre, seen in the probe's frame):
the probe reads the contact of the exact ball when it has pressed a further
``p(n) - f(-n)`` into the surface, ``p`` the pre-travel (`Lobing`) and ``f`` the ball's
radial form error where it touches (`ZonalForm`; a larger ball touches earlier). Moving at
unit velocity ``v`` the ball gets there after a further travel of
``(p(n) - f(-n)) / (-v . n)``: that is added to the exact contact travel before the trigger
noise. It is the first-order effect of an effective ball radius ``r - p(n) + f(-n)``:
exact for the touch of a plane, and within (p - f)**2 / r of it elsewhere (below 0.1 nm
for sub-micrometre departures on a 0.25 mm ball).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import AxisLimitError, InputError
from machinesim.metrology._arrays import as_floats, as_number, shown
from machinesim.metrology._mesh import as_positive
from machinesim.metrology.imperfections import Lobing, ZonalForm
from machinesim.metrology.instruments import Readout, as_generator, as_machine, motion_of
from machinesim.metrology.meshindex import MeshIndex
from machinesim.metrology.probe import touch_many
from machinesim.tolerances import PROBE_CHORD_M
from machinesim.units import length_text

__all__ = ["BALL_RADIUS_LIMIT", "DEPARTURE_SHARE", "ScanReading", "StylusOverTravel",
           "TouchProbe"]

#: Largest ball ``radius`` a `TouchProbe` takes, m: 10 mm, 40 times paper 002's R0.25 mm ruby
#: ball and above the balls of machine-tool probe styli (a few mm across). Any real ball's
#: radius given in mm as m lies above it (the smallest balls, 0.1 mm across, would read
#: 0.05 m), as would one in um: a unit slip, refused when the probe is built, as the
#: readings' `READOUT_LIMIT` refuses a noise in nm given as m. Before, ``radius=0.25``
#: (mm meant) was refused only at the first touch, as a ball overlapping the part.
BALL_RADIUS_LIMIT = 10e-3


class StylusOverTravel(InputError):
    """A scan met the surface more than the stylus's stroke above its path: a real probe
    would stop the machine there."""

#: Largest departure of the probed ball from its radius that pre-travel and ball form may
#: add together (the sum of their amplitudes, each term's largest value), as a fraction of
#: the ball radius: 1 %, 2.5 um on paper 002's R0.25 mm ball, 10 times the +-0.25 um lobing
#: of strain-gauge probes and 20 times the lab's (0.10 + 0.02 um of lobing, 0.13 um of form
#: P-V). The model is the first-order effect of an effective radius, within (p - f)**2 / r of
#: the exact touch: at the bound 1 % of the departure. Beyond, a unit slip (0.1 um given as
#: 0.1) read a touch 0.1 m early, or a ball form 50 mm inside the part.
DEPARTURE_SHARE = 0.01

#: Interior points tested on each piece: a smooth path's largest departure from a chord is
#: near its middle, and a kink anywhere inside a piece moves every interior point.
CHORD_SAMPLES = 7
#: Halvings of a piece before it is accepted whatever its departure: 2^-40 of the travel is
#: below float64 resolution of t on any travel, so a deeper split could not change anything.
MAX_SPLITS = 40
#: Least cosine between the ball's motion and the contact normal by which a pre-travel or
#: form departure is divided: a contact grazed at over 89.9 deg would otherwise amplify it
#: without bound, where the effective-ball model no longer holds anyway.
GRAZING_COSINE = 2e-3


@dataclass(frozen=True, eq=False)
class ScanReading:
    """Displacement scan: machine axis values and the probe's deflection at each point.

    Attributes
    ----------
    q : ndarray, shape (N, n_axes), float64, read-only
        Axis values of the path points, m and rad, rounded as the controller records them.
    deflection : ndarray, shape (N,), float64, read-only
        How far the surface pushed the ball back along +Z (axis space) from its free
        position at ``q``, m, with noise and rounded to the probe's resolution; NaN where the
        ball hung free (the surface below its free position).
    contact_q : ndarray, shape (N, n_axes), float64, read-only
        ``q`` with ``deflection`` added to Z: the axis values at which the free ball would
        touch the surface (NaN rows where it hung free). `TouchProbe.nominal_centres` turns
        them into measured points (NaN rows staying NaN: drop them, or fit with a function
        that leaves NaN rows out, as `machinesim.metrology.fit_sphere` does).
    machine : str or None
        The name of the machine the scan was taken on (None when not known: a reading
        pickled before it was recorded).
    axes : tuple of str or None
        That machine's axis letters, the columns of ``q`` and ``contact_q``.
    """

    q: np.ndarray
    deflection: np.ndarray
    contact_q: np.ndarray
    machine: str | None = None
    axes: tuple[str, ...] | None = None


class TouchProbe:
    """A touch probe on a machine, touching one part.

    Parameters
    ----------
    machine : Machine or str
        The machine carrying the probe, or the name of a shipped one
        (`machinesim.load_machine`); it must have the frame ``frame``.
    errors : ErrorModel or None
        The machine's injected errors: they move the ball as they move the tool. Only the
        machine's kinematics reads them; the probe keeps no attribute that returns them
        (`machinesim.Lab.touch_probe` builds one without handing them out).
    part : Part or MeshIndex or tuple of (array-like, array-like)
        The part on the machine, in its workpiece frame (m). Indexed once, here.
    radius : float
        Ball radius, m. Default 0.25 mm (paper 002's R0.25 ruby ball); > 0 and at most
        `BALL_RADIUS_LIMIT` (10 mm: more is a unit slip).
    sigma : float
        Standard deviation of the trigger (and deflection) noise, m, along the direction of
        motion of the ball. Default 20 nm: paper 002 gives the probe's 1 nm resolution but no
        repeatability; 20 nm is the order of low-force on-machine contact probes of this
        class, and keeps the probe well inside the paper's error budget (workpiece position
        found to 1-2 um, limited by sphere form error; groove depths equal to ~100 nm).
    resolution : float
        Rounding of the recorded linear axis values and deflections, m. Default 1 nm (paper
        002). Rotary axis values are rounded to the machine's own axis resolution.
    noise : bool
        False turns the noise off exactly (``sigma`` ignored); rounding stays (resolution 0
        turns it off).
    rng : numpy.random.Generator or int or None
        Noise source, or its seed.
    frame : str
        The machine frame at the ball centre. Default ``"probe_tip"``.
    pretravel : Lobing, optional
        Pre-travel variation with the contact direction (module docstring); default none.
        Its amplitudes and the ball form's sum to at most `DEPARTURE_SHARE` (1 %) of
        ``radius``.
        The lab's: 3 lobes of 0.10 um and a first order of 0.02 um, phases drawn per probe
        (`machinesim.realism.PROBE`, assumed below the +-0.25 um 2-D lobing of strain-gauge
        machine-tool probes).
    ball_form : ZonalForm, optional
        Form error of the ball, in the probe's frame; default a perfect sphere. The lab's:
        0.13 um peak to valley (ISO 3290 grade 5 sphericity, the standard ruby stylus ball).
    lobing_amplitudes : mapping of int to float, optional
        What the probe's maker states of its pre-travel: amplitude (m) per lobing order,
        phases unknown. Public (`lobing_amplitudes`), for the uncertainty a procedure
        states; the drawn ``pretravel`` stays hidden. The lab gives it with its pre-travel.
    sphericity : float
        What is stated of the ball's form: its peak to valley (m), the same way. Default 0.
    """

    def __init__(self, machine, errors, part, radius: float = 0.25e-3, sigma: float = 20e-9,
                 resolution: float = 1e-9, *, noise: bool = True, rng=None,
                 frame: str = "probe_tip", pretravel: Lobing | None = None,
                 ball_form: ZonalForm | None = None, lobing_amplitudes=None,
                 sphericity: float = 0.0) -> None:
        self.machine = machine = as_machine(machine)
        self._pose = motion_of(machine, errors, frame)
        self.frame = frame
        self.index = MeshIndex.from_surface(part)
        self.radius = as_positive(radius, "radius")
        if self.radius > BALL_RADIUS_LIMIT:
            raise InputError(f"Expected the ball radius <= {length_text(BALL_RADIUS_LIMIT)} "
                             "(BALL_RADIUS_LIMIT: 40 times paper 002's R0.25 mm ball, above "
                             "any probe stylus's; radius is in m: more is a unit slip, e.g. mm "
                             f"given as m), got {length_text(self.radius)}", key="radius")
        self.readout = Readout.of(sigma, resolution, noise)
        self._rng = as_generator(rng)
        for name, value, kind in (("pretravel", pretravel, Lobing),
                                  ("ball_form", ball_form, ZonalForm)):
            if value is not None and not isinstance(value, kind):
                raise InputError(f"Expected {name} as a {kind.__name__} or None, got "
                                 f"{type(value).__name__}", key=name)
        departure = ((0.0 if pretravel is None else sum(abs(a) for _, a, _ in
                                                        pretravel.harmonics))
                     + (0.0 if ball_form is None else float(np.abs(ball_form.amplitudes).sum())))
        if departure > DEPARTURE_SHARE * self.radius:
            raise InputError(f"Expected the pre-travel and ball form amplitudes to sum to at "
                             f"most {length_text(DEPARTURE_SHARE * self.radius)} "
                             f"(DEPARTURE_SHARE: {DEPARTURE_SHARE:g} of the ball radius "
                             f"{length_text(self.radius)}, where the model holds; amplitudes "
                             f"are in m: more is a unit slip, e.g. um given as m), got "
                             f"{length_text(departure)}", key="pretravel" if ball_form is None
                             else "ball_form")
        self._pretravel = pretravel
        self._ball_form = ball_form
        if lobing_amplitudes is not None and not isinstance(lobing_amplitudes, Mapping):
            raise InputError(f"Expected lobing_amplitudes as a mapping of lobing order to "
                             f"amplitude (m), e.g. {{3: 1e-7}}, or None, got "
                             f"{shown(lobing_amplitudes)}", key="lobing_amplitudes")
        stated = dict(lobing_amplitudes or {})
        for order, amplitude in stated.items():
            as_number(amplitude, f"lobing_amplitudes[{order!r}]", sign=">= 0")
        Lobing(tuple((k, a, 0.0) for k, a in stated.items()))  # the same checks as a lobing
        self.lobing_amplitudes = {int(k): float(a) for k, a in stated.items()}
        self.sphericity = as_number(sphericity, "sphericity", sign=">= 0")
        # The controller records linear axes at the probe's resolution, rotary ones at theirs.
        self._axis_rounding = [Readout(0.0, float(r) if rotary else self.readout.resolution)
                               for r, rotary in zip(machine.resolution, machine.rotary,
                                                    strict=True)]

    def __repr__(self) -> str:
        return (f"TouchProbe({self.machine.name}, frame={self.frame!r}, radius={self.radius:g} "
                f"m, sigma={self.readout.sigma:g} m, resolution={self.readout.resolution:g} m)")

    # ------------------------------------------------------------------------------ reading

    def touch(self, q_start, direction, max_travel: float) -> np.ndarray | None:
        """Move the axes from ``q_start`` along ``direction`` until the ball touches the part.

        Parameters
        ----------
        q_start : array-like, shape (n_axes,)
            Axis values at the start, m and rad (`Machine.axes` order). The ball must start
            clear of the part: one that overlaps it is refused; one wholly inside it is not
            detected (it may then report a contact from inside).
        direction : str or array-like, shape (n_axes,)
            Direction of the move in axis space: ``"-Z"``, ``"+X"`` ..., or a vector
            (normalised here). Travel t then moves the axes by t times the unit vector:
            metres for a move of linear axes.
        max_travel : float
            Longest travel to search, > 0 (m for a move of linear axes). The search must
            end within every axis's travel, as a control alarms on a skip move whose end
            lies beyond a soft limit: 5 given for 5 mm is refused, not searched in vain.

        Returns
        -------
        ndarray, shape (n_axes,), read-only, or None
            The axis values at contact as the controller records them (the skip position):
            with the trigger noise along the move and rounded to the resolution. None when the
            ball touches nothing within ``max_travel``.

        Raises
        ------
        InputError
            For bad arguments or a ball that overlaps the part at ``q_start``.
        AxisLimitError
            When the start, the end of the search or the contact lies outside an axis
            travel.
        """
        q_start = self._q(q_start, "q_start")[None]
        u = self._direction(direction)
        travel = as_positive(max_travel, "max_travel")
        # a search past the travel (5 m given for 5 mm) had run on and returned None
        beyond = self.machine.limit_violations(q_start + travel * u)
        if beyond:
            along = direction if isinstance(direction, str) else shown(u.tolist())
            raise AxisLimitError(f"{self.machine.name}: a search of max_travel {travel:g} "
                                 f"along {along} from q_start ends at {'; '.join(beyond)}; "
                                 "expected it within the travel (max_travel is in m for a "
                                 "move of linear axes: 5 mm is 0.005)")
        t, speed, normal, velocity = self._sweep(q_start, u, travel, "q_start")
        if np.isnan(t[0]):
            return None
        t = t + self._departure(q_start + t[:, None] * u, normal, velocity) / speed
        if self.readout.sigma > 0.0:
            t = t + self.readout.sigma * self._rng.standard_normal(1) / speed
        contact = q_start + t[:, None] * u
        self._check_limits(contact, "the contact")
        return self._record(contact)[0]

    def scan(self, q_path, stroke: float = 0.5e-3) -> ScanReading:
        """Displacement scanning along a path (paper 002 Fig. 4b).

        Modelled as one touch along -Z (axis space) per path point: the ball comes down from
        above the part until it touches; its deflection is how far above the point's Z that
        contact is. A real scan follows the surface continuously with the stylus pressed in;
        sampled at the same points it records the same deflections (the probe's dynamics and
        contact force are not modelled).

        Parameters
        ----------
        q_path : array-like, shape (N, n_axes)
            Axis values of the path points, m and rad; Z is where the free (undeflected) ball
            would be, below the surface so that the stylus is pressed in.
        stroke : float
            Measuring range of the stylus deflection, m, > 0. Default 0.5 mm.

        Returns
        -------
        ScanReading
            NaN deflection where the surface lies below the free ball.

        Raises
        ------
        InputError
            For a bad path, or points where the surface stands more than ``stroke`` above
            the free ball (over-travel of the stylus).
        """
        q = self._q(q_path, "q_path", batch=True)
        stroke = as_positive(stroke, "stroke")
        u = self._direction("-Z")
        # Start every ball above the whole part (2 radii of clearance against the errors'
        # small departure of the ball's height from Z), so that it meets the surface as a
        # stylus coming down from above does, whatever the path's Z.
        top = self.index.vertices[:, 2].max()
        lift = max(stroke, top - self._centres(q)[:, 2].min() + 2.0 * self.radius)
        t, speed, normal, velocity = self._sweep(q - lift * u, u, lift, "q_path")
        touched = ~np.isnan(t)
        if touched.any():
            at = (q - lift * u)[touched] + t[touched, None] * u
            t[touched] += (self._departure(at, normal[touched], velocity[touched])
                           / speed[touched])
        exact = lift - t
        over = np.flatnonzero(exact > stroke)
        if over.size:
            # the amount to 2 digits, as an alarm says it: given exactly, it was a reading
            # without noise or rounding (a workpiece 3.21 um high read 0.000553209999999951)
            raise StylusOverTravel(f"Expected the surface within the stylus stroke ({stroke} "
                                   f"m) above the path, got it about {exact[over].max():.2g} m "
                                   f"above at points {over.tolist()[:10]} (over-travel)",
                                   key="q_path")
        deflection = self.readout.read(exact, self._rng)
        recorded = self._record(q)
        contact = recorded - deflection[:, None] * u
        contact[np.isnan(deflection)] = np.nan
        for array in (deflection, contact):
            array.setflags(write=False)
        return ScanReading(recorded, deflection, contact, self.machine.name,
                           tuple(self.machine.axes))

    def nominal_centres(self, q) -> np.ndarray:
        """Ball centres the nominal machine puts at recorded axis values (what a lab computes).

        Parameters
        ----------
        q : array-like, shape (n_axes,) or (N, n_axes)
            Recorded axis values, m and rad.

        Returns
        -------
        ndarray, shape (3,) or (N, 3)
            Ball centre in the workpiece frame of the error-free machine, m. A row of ``q``
            that holds NaN (a `ScanReading.contact_q` row where the ball hung free) gives a
            NaN row, so ``nominal_centres(probe.scan(path).contact_q)`` keeps one row per
            path point.
        """
        n = len(self.machine.axes)
        array = as_floats(q, "q", "axis values (m, rad)")
        if array.shape != (n,) and not (array.ndim == 2 and array.shape[1] == n):
            raise InputError(f"Expected q with shape ({n},) or (N, {n}) (axes "
                             f"{''.join(self.machine.axes)}), got {array.shape}", key="q")
        if np.isinf(array).any():
            raise InputError("Expected finite q or NaN rows, got infinity", key="q")
        rows = array.reshape(-1, n)
        seen = ~np.isnan(rows).any(axis=1)
        centres = np.full((len(rows), 3), np.nan)
        if seen.any():
            centres[seen] = self.machine.frame_pose(self.frame, rows[seen])[..., :3, 3]
        return centres.reshape(array.shape[:-1] + (3,))

    # ---------------------------------------------------------------------------- internals

    def _q(self, q, name: str, batch: bool = False) -> np.ndarray:
        n = len(self.machine.axes)
        array = as_floats(q, name, "axis values (m, rad)")
        shape = (array.ndim == 2 and array.shape[1] == n and len(array) > 0) if batch else (
            array.shape == (n,))
        if not shape:
            want = f"(N, {n})" if batch else f"({n},)"
            raise InputError(f"Expected {name} with shape {want} (axes "
                             f"{''.join(self.machine.axes)}), got {array.shape}", key=name)
        if not np.isfinite(array).all():
            raise InputError(f"Expected finite {name}, got NaN or infinity", key=name)
        self._check_limits(array, name)
        return array

    def _check_limits(self, q: np.ndarray, what: str) -> None:
        bad = self.machine.limit_violations(q)
        if bad:
            raise AxisLimitError(f"{self.machine.name}: {what} needs " + "; ".join(bad))

    def _direction(self, direction) -> np.ndarray:
        axes = self.machine.axes
        if isinstance(direction, str):
            sign, letter = direction[:1], direction[1:]
            if sign not in "+-" or not sign or letter not in axes:
                raise InputError(f"Expected a direction like '-Z' or '+X' on axes "
                                 f"{''.join(axes)}, got {direction!r}", key="direction")
            u = np.zeros(len(axes))
            u[axes.index(letter)] = 1.0 if sign == "+" else -1.0
            return u
        u = as_floats(direction, "direction", "a string or numbers")
        norm = np.linalg.norm(u) if u.shape == (len(axes),) else np.nan
        if not (np.isfinite(norm) and norm > 0.0):
            raise InputError(f"Expected a finite non-zero direction of shape ({len(axes)},), "
                             f"got {direction!r}", key="direction")
        return u / norm

    def _centres(self, q: np.ndarray) -> np.ndarray:
        """Ball centres (..., 3) of the erroneous machine at axis values q (..., n_axes)."""
        flat = q.reshape(-1, q.shape[-1])
        poses = self._pose(self.frame, flat)
        return poses[:, :3, 3].reshape(q.shape[:-1] + (3,))

    def _polyline(self, q0: np.ndarray, u: np.ndarray, travel: float) -> np.ndarray:
        """Knots 0 = t_0 < ... < t_S = travel of pieces along which every path is straight."""
        fractions = np.arange(CHORD_SAMPLES + 2) / (CHORD_SAMPLES + 1)
        pending = np.array([[0.0, travel]])
        knots = [travel]
        for split in range(MAX_SPLITS + 1):
            t = pending[:, :1] + fractions * (pending[:, 1:] - pending[:, :1])  # (P, F)
            c = self._centres(q0[:, None, None, :] + t[None, :, :, None] * u)  # (K, P, F, 3)
            chord = c[:, :, :1] + fractions[:, None] * (c[:, :, -1:] - c[:, :, :1])
            departure = np.linalg.norm(c - chord, axis=-1).max(axis=(0, 2))
            straight = (departure <= PROBE_CHORD_M) | (split == MAX_SPLITS)
            knots += pending[straight, 0].tolist()
            halves = pending[~straight].mean(axis=1)
            pending = np.concatenate([np.stack([pending[~straight, 0], halves], axis=1),
                                      np.stack([halves, pending[~straight, 1]], axis=1)])
            if pending.size == 0:
                break
        return np.unique(knots)

    def _sweep(self, q0: np.ndarray, u: np.ndarray, travel: float, name: str):
        """First contact of each ball moved from axis values q0 (K, n) along u up to travel.

        Returns
        -------
        t : ndarray, shape (K,)
            Travel at contact (axis-space units); NaN where nothing is touched.
        speed : ndarray, shape (K,)
            Ball speed along its path at contact, m per unit of t; NaN where no contact.
        normal : ndarray, shape (K, 3)
            Contact normal (surface to ball centre), workpiece frame; NaN where no contact.
        velocity : ndarray, shape (K, 3)
            Unit direction of the ball's motion at contact, workpiece frame; NaN likewise.
        """
        knots = self._polyline(q0, u, travel)
        centres = self._centres(q0[:, None, :] + knots[None, :, None] * u)  # (K, S + 1, 3)
        k = len(q0)
        t = np.full(k, np.nan)
        speed = np.full(k, np.nan)
        normal = np.full((k, 3), np.nan)
        velocity = np.full((k, 3), np.nan)
        for s in range(len(knots) - 1):
            step = centres[:, s + 1] - centres[:, s]
            length = np.linalg.norm(step, axis=1)
            if not np.isnan(t).any():
                break
            active = np.flatnonzero(np.isnan(t) & (length > 0.0))
            if active.size == 0:
                continue
            try:
                hit = touch_many(self.index, centres[active, s], step[active], self.radius,
                                 length[active])
            except InputError as error:
                raise InputError(f"Expected the probe ball (radius {self.radius} m) to start "
                                 f"clear of the part; it overlaps it ({error})",
                                 key=name) from error
            touched = active[hit.touched]
            dt = knots[s + 1] - knots[s]
            speed[touched] = length[touched] / dt
            t[touched] = knots[s] + hit.travel[hit.touched] / speed[touched]
            normal[touched] = hit.normal[hit.touched]
            velocity[touched] = step[touched] / length[touched, None]
        return t, speed, normal, velocity

    def _departure(self, q: np.ndarray, normal: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        """Further travel (m along the ball's path) before the probe reads each contact: the
        pre-travel less the ball's form where it touches, over the approach cosine."""
        if self._pretravel is None and self._ball_form is None:
            return np.zeros(len(q))
        rotation = self._pose(self.frame, q)[:, :3, :3]
        local = np.einsum("nji,nj->ni", rotation, normal)  # the normal in the probe's frame
        press = np.zeros(len(q))
        if self._pretravel is not None:
            press += self._pretravel(local)
        if self._ball_form is not None:
            press -= self._ball_form(-local)
        cosine = np.maximum(-np.einsum("ni,ni->n", velocity, normal), GRAZING_COSINE)
        return press / cosine

    def _record(self, q: np.ndarray) -> np.ndarray:
        """Axis values (N, n_axes) rounded as the controller records them, read-only."""
        out = np.column_stack([r.read(q[:, i], self._rng)
                               for i, r in enumerate(self._axis_rounding)])
        out.setflags(write=False)
        return out
