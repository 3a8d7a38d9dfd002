"""Setting errors of a robot-loaded workpiece and the C-axis centre, from probe readings.

Paper 002 (Xu, Nakamoto, Takeuchi 2021). An industrial robot sets a roughly machined
workpiece on the C table of a 5-axis machine (X Y Z B C, `robonano_a0ib`); it lands off its
ideal place. The actual workpiece frame in the ideal one is
``W = T(d) Rx(alpha) Ry(beta) Rz(gamma)`` (`machinesim.WorkpieceSetting`; the ideal frame is
the machine's at C = 0, its origin on the C axis). Three reference spheres, ball-end-milled
into the workpiece at known places with S1 -> S2 along X and S1 -> S3 along Y, give W
(docs/procedures/workpiece_setting.md derives every formula).

This module sees the probe's readings only (the honesty rule of DESIGN.md); driving the
probe over the spheres is the procedure's (`machinesim.procedures.workpiece_setting`):

1. Each sphere is read with the on-machine touch probe: two orthogonal displacement scans
   whose ball centres lie on a sphere (`sphere_reading`: its centre's x, y and radius,
   Fig. 4b) and a touch along -Z at that x, y (Fig. 4c): the centre lies the sphere radius
   above the bottom point, the radius being the mean fitted radius of the three spheres.
2. Eqs 1-4 (derived; the printed eq 1 is garbled), `setting_from_centres`: with
   ez = ex x ey from the centres, ``alpha = atan2(-ez_y, ez_z)``, ``beta = asin(ez_x)``,
   ``gamma`` the angle of ``Ry(-beta) Rx(-alpha) ex`` from X, ``delta = S1 - S1_ideal``
   (the paper's position error) and ``d = S1 - R S1_ideal`` (the same setting about the
   ideal origin, what `ErrorModel` calls ``workpiece.x .. gamma``).
3. C-axis centre (Fig. 6), `c_axis_centre`: the midpoint of a sphere's bottom points before
   and after a 180-deg turn of C, averaged over the three spheres (``location.C.EX0C``,
   ``location.C.EY0C``).
4. Compensation, eqs 5-7 as a function of axis values (`eqs_5_to_7`, for
   `machinesim.compensation.map_program`): the program's (x, y, z, b, c) become
   ``B = b + beta`` (eq 5), ``C = c + gamma`` (eq 6) and, with the C centre ``c0``,
   ``(X, Y, Z) = c0 + Rz(-C) (d + R t - c0)`` (eq 7 derived), ``t = Rz(c) (x, y, z)``. Five
   axes cannot roll the tool about its cutting direction; for a round-nose tool the point
   put on the path may be the nose arc's lowest point (`nose_shift`) instead of the tip.
5. A cross-check by the generic fit (`fit_setting`, `machinesim.identification.fit`): the
   six probed sphere centres as displacements of the probe ball, the same parameters by
   weighted least squares.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from machinesim.arrays import frozen
from machinesim.errors import ErrorModel, WorkpieceSetting
from machinesim.exceptions import InputError
from machinesim.identification.fit import Estimate, fit, observations
from machinesim.metrology import fit_sphere, sphere_centre_from_touch
from machinesim.rotations import rot_y, rot_z, rotation_xyz

__all__ = [
    "AXES", "PARAMETERS", "Identification", "ReferenceSpheres", "SphereReading",
    "SphereReadings", "c_axis_centre", "check_machine", "eqs_5_to_7", "fit_setting",
    "identified_errors", "identify", "nose_shift", "parameters", "program_poses",
    "setting_from_centres", "sphere_reading",
]

#: The axes the procedure drives, in `Machine.axes` order.
AXES = ("X", "Y", "Z", "B", "C")
#: Two directions are "along X" (S1 -> S2) or "along Y" (S1 -> S3) within this angle (rad):
#: the formulas take the designed S1S2 and S1S3 as the workpiece X and Y axes.
LAYOUT_ANGLE = 1e-9
#: The error parameters the procedure identifies, as `Machine.parameter_names` spells them.
PARAMETERS = ("workpiece.x", "workpiece.y", "workpiece.z", "workpiece.alpha",
              "workpiece.beta", "workpiece.gamma", "location.C.EX0C", "location.C.EY0C")


@dataclass(frozen=True, eq=False)
class ReferenceSpheres:
    """The reference spheres of a workpiece as designed (paper 002, Fig. 4a).

    Parameters
    ----------
    centres : array-like, shape (3, 3)
        Designed centres of S1, S2, S3 in the workpiece frame, m, with S1 -> S2 along +X
        and S1 -> S3 along +Y (Fig. 5a).
    radius : float
        Designed radius, m: the ball end mill's (R2.0 in the paper). The procedure only plans
        its scans with it; the radius it uses is the one it measures.
    """

    centres: np.ndarray
    radius: float = 2e-3

    def __post_init__(self) -> None:
        centres = np.array(self.centres, dtype=np.float64)
        if centres.shape != (3, 3) or not np.isfinite(centres).all():
            raise InputError(f"Expected three sphere centres of shape (3, 3) (m), got "
                             f"{centres.shape}", key="centres")
        x, y = centres[1] - centres[0], centres[2] - centres[0]
        if (x[0] <= 0.0 or np.hypot(x[1], x[2]) > LAYOUT_ANGLE * x[0]
                or y[1] <= 0.0 or np.hypot(y[0], y[2]) > LAYOUT_ANGLE * y[1]):
            raise InputError(f"Expected S1 -> S2 along +X and S1 -> S3 along +Y, got "
                             f"{centres.tolist()} m", key="centres")
        radius = float(self.radius)
        if not math.isfinite(radius) or radius <= 0.0:
            raise InputError(f"Expected a radius > 0 (m), got {self.radius!r}", key="radius")
        object.__setattr__(self, "centres", frozen(centres))
        object.__setattr__(self, "radius", radius)


@dataclass(frozen=True, eq=False)
class SphereReading:
    """One sphere read by the probe, in machine coordinates (the ideal frame at C = 0), m.

    Built by `sphere_reading` from the scanned ball centres and the bottom touch.

    Attributes
    ----------
    xy : ndarray, shape (2,)
        Centre x, y of the least-squares sphere through the scanned ball centres.
    bottom : ndarray, shape (3,)
        Probe-ball centre at the bottom touch.
    radius : float
        Fitted radius of the sphere surface (ball-centre sphere plus the ball radius).
    residual_rms : float
        RMS distance of the scanned ball centres from their sphere.
    c_angle : float
        C axis value during the reading, rad.
    xy_gain : ndarray, shape (2,)
        Standard deviation of the fitted x, y per unit noise on the scanned points (first
        order, from the fit's Jacobian): times the probe's sigma, the centre's uncertainty.
    radius_gain : float
        The same for the fitted radius.
    points : ndarray, shape (N, 3), optional
        The scanned ball centres the fit went through (for the stated uncertainty).
    """

    xy: np.ndarray
    bottom: np.ndarray
    radius: float
    residual_rms: float
    c_angle: float = 0.0
    xy_gain: np.ndarray = None
    radius_gain: float = math.nan
    points: np.ndarray = None


def sphere_reading(points, bottom, ball_radius: float, c_angle: float = 0.0) -> SphereReading:
    """The sphere fit from the probe's readings (Fig. 4b, 4c).

    Parameters
    ----------
    points : array-like, shape (N, 3)
        Probe-ball centres of the two scans at contact, machine coordinates, m. They lie on a
        sphere of radius R - r about the cavity's centre (r the ball radius).
    bottom : array-like, shape (3,)
        Ball centre at the bottom touch, machine coordinates, m.
    ball_radius : float
        The probe ball's radius r, m.
    c_angle : float
        C axis value during the reading, rad.

    Returns
    -------
    SphereReading
        x, y of the fitted sphere, radius R = fitted + r, and the first-order gains of the
        fit (`SphereReading.xy_gain`).
    """
    points = np.asarray(points, dtype=np.float64)
    fitted = fit_sphere(points)
    # Jacobian of the radial residuals |p - c| - rho in (cx, cy, cz, rho): the covariance of
    # the fit per unit noise on the points is (J^T J)^-1.
    radial = points - fitted.centre
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    jacobian = np.column_stack([-radial, -np.ones(len(points))])
    gains = np.sqrt(np.diag(np.linalg.inv(jacobian.T @ jacobian)))
    return SphereReading(frozen(fitted.centre[:2]), frozen(bottom),
                         float(fitted.radius + ball_radius), float(fitted.residual_rms),
                         float(c_angle), frozen(gains[:2]), float(gains[3]), frozen(points))


@dataclass(frozen=True, eq=False)
class SphereReadings:
    """What the probe read on one loaded workpiece: the measurements `identify` takes.

    Attributes
    ----------
    spheres : ReferenceSpheres
        The spheres as designed.
    first : tuple of SphereReading
        S1, S2, S3 at C = 0.
    turned : tuple of SphereReading
        The same spheres after C turned 180 deg.
    ball_radius : float
        The probe ball's radius, m.
    sigma : float
        The probe's standard uncertainty per reading, m (its stated noise; its resolution
        when it reads without noise): weights of the fit cross-check only.
    lobing_amplitudes : Mapping[int, float]
        The probe's stated pre-travel, amplitude (m) per lobing order (none: not stated).
    sphericity : float
        The probe ball's stated peak-to-valley form, m.
    """

    spheres: ReferenceSpheres
    first: tuple[SphereReading, ...]
    turned: tuple[SphereReading, ...]
    ball_radius: float
    sigma: float
    lobing_amplitudes: Mapping[int, float] = field(default_factory=dict)
    sphericity: float = 0.0

    def __post_init__(self) -> None:
        for name in ("first", "turned"):
            readings = tuple(getattr(self, name))
            if len(readings) != 3 or not all(isinstance(r, SphereReading) for r in readings):
                raise InputError(f"Expected three SphereReading in {name}, got "
                                 f"{len(readings)}", key=name)
            object.__setattr__(self, name, readings)
        for name in ("ball_radius", "sigma"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value > 0.0):
                raise InputError(f"Expected {name} > 0 (m), got {value!r}", key=name)
            object.__setattr__(self, name, value)


@dataclass(frozen=True, eq=False)
class Identification:
    """What the probe found (all in the ideal frame, m and rad).

    Attributes
    ----------
    centres : ndarray, shape (3, 3)
        Centres of S1, S2, S3: x, y fitted, z the bottom point plus `radius`.
    radius : float
        Mean fitted radius of the three spheres.
    setting : WorkpieceSetting
        The setting errors about the ideal origin (the model's convention).
    delta : ndarray, shape (3,)
        Eq 4: S1 less its ideal place (the paper's position error).
    c_centre : ndarray, shape (2,)
        C-axis centre (Fig. 6), the mean over the spheres.
    c_centres : ndarray, shape (3, 2)
        The C-axis centre from each sphere.
    readings : tuple of SphereReading
        The spheres at C = 0, then at C = 180 deg.
    """

    centres: np.ndarray
    radius: float
    setting: WorkpieceSetting
    delta: np.ndarray
    c_centre: np.ndarray
    c_centres: np.ndarray
    readings: tuple[SphereReading, ...]


def check_machine(machine) -> None:
    """Refuse a machine other than a 5-axis XYZBC one with a probe (`robonano_a0ib`)."""
    if tuple(machine.axes) != AXES or "probe_tip" not in machine.frames:
        raise InputError(f"Expected a machine with axes {''.join(AXES)} and a probe_tip "
                         f"frame (robonano_a0ib), got {machine.name} with "
                         f"{''.join(machine.axes)}", key="machine")


def setting_from_centres(centres, designed) -> tuple[WorkpieceSetting, np.ndarray]:
    """Eqs 1-4 (paper 002): the setting errors from the measured sphere centres.

    Parameters
    ----------
    centres : array-like, shape (3, 3)
        Measured S1, S2, S3 in the ideal frame, m.
    designed : array-like, shape (3, 3)
        Their designed places in the workpiece frame, m (S1 -> S2 along X, S1 -> S3 along Y).

    Returns
    -------
    setting : WorkpieceSetting
        ``d = S1 - R S1_designed`` and alpha, beta, gamma, with R = Rx Ry Rz.
    delta : ndarray, shape (3,)
        Eq 4, ``S1 - S1_designed``.
    """
    centres = np.asarray(centres, dtype=np.float64)
    designed = ReferenceSpheres(designed).centres
    ex = centres[1] - centres[0]
    ey = centres[2] - centres[0]
    ex = ex / np.linalg.norm(ex)
    ez = np.cross(ex, ey)
    ez = ez / np.linalg.norm(ez)
    alpha = math.atan2(-ez[1], ez[2])                     # eq 1
    beta = math.asin(min(1.0, max(-1.0, ez[0])))          # eq 2
    back = rotation_xyz(0.0, -beta, 0.0) @ rotation_xyz(-alpha, 0.0, 0.0) @ ex
    gamma = math.atan2(back[1], back[0])                  # eq 3
    r = rotation_xyz(alpha, beta, gamma)
    d = centres[0] - r @ designed[0]
    return WorkpieceSetting(d, alpha, beta, gamma), frozen(centres[0] - designed[0])  # eq 4


def c_axis_centre(before, after) -> np.ndarray:
    """Fig. 6 (paper 002): the C-axis centre from bottom points before and after a 180-deg
    turn of C.

    Parameters
    ----------
    before, after : array-like, shape (..., 3) or (..., 2)
        Bottom points in machine coordinates, m.

    Returns
    -------
    ndarray, shape (..., 2)
        Their midpoints (x, y).
    """
    before, after = np.asarray(before, dtype=np.float64), np.asarray(after, dtype=np.float64)
    return 0.5 * (before[..., :2] + after[..., :2])


def _centres(readings, radius: float, ball_radius: float) -> np.ndarray:
    return np.array([sphere_centre_from_touch(r.xy, r.bottom[2], radius,
                                              probe_radius=ball_radius, concave=True)
                     for r in readings])


def identify(readings: SphereReadings) -> Identification:
    """Eqs 1-4 and Fig. 6 (paper 002) from the readings of the three spheres at C = 0 and
    180 deg.

    Parameters
    ----------
    readings : SphereReadings

    Returns
    -------
    Identification
    """
    radius = float(np.mean([r.radius for r in readings.first]))
    centres = _centres(readings.first, radius, readings.ball_radius)
    setting, delta = setting_from_centres(centres, readings.spheres.centres)
    each = c_axis_centre([r.bottom for r in readings.first],
                         [r.bottom for r in readings.turned])
    return Identification(frozen(centres), radius, setting, delta, frozen(each.mean(axis=0)),
                          frozen(each), readings.first + readings.turned)


def identified_errors(found: Identification) -> ErrorModel:
    """The identified machine state as an error model (model-based compensation).

    The C centre enters as the location errors EX0C, EY0C of the C axis: they move the C axis
    line to ``c_centre`` in the machine coordinates of C = 0, where the probe found it.
    """
    x, y = found.c_centre.tolist()
    return ErrorModel(workpiece=found.setting, location={"C": {"EX0C": x, "EY0C": y}})


def parameters(found: Identification) -> dict[str, float]:
    """The identified values by error parameter name (`PARAMETERS`), SI."""
    values = identified_errors(found).parameters()
    return {name: values[name] for name in PARAMETERS}


def fit_setting(machine, readings: SphereReadings, found: Identification | None = None
                ) -> Estimate:
    """The cross-check: the same parameters by the generic fit on the same readings.

    Each probed sphere centre (three at C = 0, three at C = 180 deg) is a point fixed on the
    workpiece at its designed place ``s``. The probe, at the axis values ``q`` that put the
    nominal ball on the measured centre, touches it: on the real machine the ball is at
    ``s`` in the workpiece frame, on the nominal machine at ``m(q)`` (`Machine.frame_pose` of
    ``probe_tip``). So the ball, a point fixed in the ``probe_tip`` frame, is seen displaced
    from its nominal place by ``s - m(q)``, relative to the workpiece: three observations
    (x, y, z of the workpiece frame) per centre, the form `machinesim.identification.fit`
    takes. The centre seen from the probe is displaced by the opposite, ``m(q) - s``.

    Weights: x, y carry the sphere fit's gain times the probe's sigma
    (`SphereReading.xy_gain`), z one touch and the mean radius.

    Parameters
    ----------
    machine : Machine
        The nominal machine the probe was moved on (`robonano_a0ib`), no errors.
    readings : SphereReadings
    found : Identification, optional
        `identify` of the same readings (computed when not given): its mean radius places
        the centres, as eqs 1-4 do.

    Returns
    -------
    Estimate
        Of `PARAMETERS`.
    """
    check_machine(machine)
    found = identify(readings) if found is None else found
    offset = machine.frame_pose("probe_tip", np.zeros(len(AXES)))[:3, 3]
    designed = readings.spheres.centres
    q, values, sigma, directions = [], [], [], []
    radius_gain = np.mean([r.radius_gain for r in readings.first]) / math.sqrt(3.0)
    for group in (readings.first, readings.turned):
        measured = _centres(group, found.radius, readings.ball_radius)
        for reading, centre, place in zip(group, measured, designed, strict=True):
            axes = np.r_[centre - offset, 0.0, reading.c_angle]
            seen = machine.frame_pose("probe_tip", axes)[:3, 3]
            xy_gain = reading.xy_gain if reading.xy_gain is not None else np.ones(2)
            gains = [*xy_gain, math.hypot(1.0, radius_gain)]
            for axis in range(3):
                q.append(axes)
                values.append(place[axis] - seen[axis])
                directions.append(np.eye(3)[axis])
                sigma.append(readings.sigma * gains[axis])
    return fit(machine, observations(np.array(q), directions=np.array(directions),
                                     values=np.array(values), sigma=np.array(sigma),
                                     frame="probe_tip"), list(PARAMETERS))


# ------------------------------------------------------------------------- compensation


def program_poses(q) -> tuple[np.ndarray, np.ndarray]:
    """Tool orientations (N, 3, 3) and tips (N, 3) a program asks for on the ideal part.

    Parameters
    ----------
    q : array-like, shape (N, 5)
        The program's axis values X Y Z B C, m and rad.
    """
    q = np.asarray(q, dtype=np.float64)
    orientation = rot_z(q[:, 4]) @ rot_y(q[:, 3])
    return orientation, np.einsum("nij,nj->ni", rot_z(q[:, 4]), q[:, :3])


def nose_shift(r_desired, r_actual, nose_radius: float) -> np.ndarray:
    """Where to put the tip so a round nose's lowest point lands where the program's tip would.

    The cutting edge is an arc of radius ``rho`` about ``(0, 0, rho)`` in the tool's Y-Z
    plane. A surface whose normal lies in the program's tool X-Z plane is generated by the
    arc point whose normal is that normal projected into the arc plane; for the program's
    tool axis ``z`` that point is ``centre - rho u``, ``u = unit((z.y') y' + (z.z') z')``
    with ``y', z'`` the actual tool axes. The tip goes to ``rho (u - z')`` from the
    program's tip: a pure pitch (about the tool's Y) needs nothing, a pure roll (about its
    X, which five axes cannot undo) puts the arc's centre where the program's is.

    Parameters
    ----------
    r_desired, r_actual : array-like, shape (N, 3, 3)
        Tool orientations wanted and reached, in one frame.
    nose_radius : float
        Nose radius, m; 0 gives no shift (the paper's tip).

    Returns
    -------
    ndarray, shape (N, 3)
        Shift of the tip, in that frame, m.
    """
    r_desired = np.asarray(r_desired, dtype=np.float64)
    r_actual = np.asarray(r_actual, dtype=np.float64)
    if nose_radius == 0.0:
        return np.zeros(r_desired.shape[:-2] + (3,))
    z, y_act, z_act = r_desired[..., :, 2], r_actual[..., :, 1], r_actual[..., :, 2]
    u = (np.einsum("...i,...i->...", z, y_act)[..., None] * y_act
         + np.einsum("...i,...i->...", z, z_act)[..., None] * z_act)
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    return nose_radius * (u - z_act)


def eqs_5_to_7(q, setting: WorkpieceSetting, c_centre, nose_radius: float = 0.0
               ) -> np.ndarray:
    """Eqs 5-7 (paper 002, eq 7 derived): compensated axis values for a program's.

    ``B = b + beta`` (5), ``C = c + gamma`` (6), ``(X, Y, Z) = c0 + Rz(-C) (d + R t - c0)``
    (7), ``t = Rz(c) (x, y, z)`` the program's tip on the ideal workpiece; with a nose radius
    ``t`` moves by `nose_shift` for the orientation reached, so that the nose arc's lowest
    point, not the tip, follows the path. Pass it to `machinesim.compensation.map_program`
    as ``lambda q: eqs_5_to_7(q, setting, c_centre, rho)``.

    Parameters
    ----------
    q : array-like, shape (N, 5)
        The program's axis values X Y Z B C (m, rad), written for the ideal workpiece on the
        nominal machine.
    setting : WorkpieceSetting
        The identified setting (about the ideal origin).
    c_centre : array-like, shape (2,)
        The identified C-axis centre, m.
    nose_radius : float
        m; 0 keeps the tip on the path, as the paper's eq 7.

    Returns
    -------
    ndarray, shape (N, 5)
    """
    q = np.asarray(q, dtype=np.float64)
    r = rotation_xyz(setting.alpha, setting.beta, setting.gamma)
    c0 = np.r_[np.asarray(c_centre, dtype=np.float64), 0.0]
    b_new, c_new = q[:, 3] + setting.beta, q[:, 4] + setting.gamma
    wanted, tip = program_poses(q)
    reached = r.T @ (rot_z(c_new) @ rot_y(b_new))
    tip = tip + nose_shift(wanted, reached, nose_radius)
    ideal = setting.delta + tip @ r.T
    xyz = c0 + np.einsum("nji,nj->ni", rot_z(c_new), ideal - c0)
    return np.column_stack([xyz, b_new, c_new])
