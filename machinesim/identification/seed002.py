"""Paper 002 (Xu, Nakamoto, Takeuchi 2021): setting errors of a robot-loaded workpiece.

An industrial robot sets a roughly machined workpiece on the C table of a 5-axis machine
(X Y Z B C, `robonano_a0ib`); it lands off its ideal place. The actual workpiece frame in
the ideal one is ``W = T(d) Rx(alpha) Ry(beta) Rz(gamma)`` (`machinesim.WorkpieceSetting`;
the ideal frame is the machine's at C = 0, its origin on the C axis). Three reference
spheres, ball-end-milled into the workpiece at known places with S1 -> S2 along X and
S1 -> S3 along Y, give W (docs/procedures/seed002.md derives every formula):

1. Each sphere, read with the on-machine touch probe on the B table (R0.25 ruby ball):
   two orthogonal displacement scans and a least-squares sphere give its centre's x, y
   (Fig. 4b); a touch along -Z at that x, y finds its bottom point, and the centre lies the
   sphere radius above it, the radius being the mean fitted radius of the three spheres
   (Fig. 4c). Each sphere is read twice: the second scans pass through the centre the
   first found, so that the three spheres are seen alike.
2. Eqs 1-4 (derived; the printed eq 1 is garbled): with ez = ex x ey from the centres,
   ``alpha = atan2(-ez_y, ez_z)``, ``beta = asin(ez_x)``, ``gamma`` the angle of
   ``Ry(-beta) Rx(-alpha) ex`` from X, ``delta = S1 - S1_ideal`` (the paper's position
   error) and ``d = S1 - R S1_ideal`` (the same setting about the ideal origin).
3. C-axis centre (Fig. 6): the midpoint of a sphere's bottom points before and after a
   180-deg turn of C, averaged over the three spheres.
4. Compensation: the NC program (x, y, z, b, c), written for the ideal workpiece, becomes
   ``B = b + beta`` (eq 5), ``C = c + gamma`` (eq 6) and, with the C centre ``c0``,
   ``(X, Y, Z) = c0 + Rz(-C) (d + R t - c0)`` (eq 7 derived), ``t`` the program's point
   ``Rz(c) (x, y, z)``; or model-based, `Machine.axis_values` on the identified model.
   Five axes cannot roll the tool about its cutting direction; for a round-nose tool
   (``nose_radius`` > 0) the point put on the path is the nose arc's lowest point, which a
   roll leaves in place only if the arc turns about its centre (`nose_shift`).

The procedure reads the probe only (the honesty rule of DESIGN.md): `identify` never sees
the injected errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from machinesim.errors import ErrorModel, WorkpieceSetting
from machinesim.exceptions import InputError
from machinesim.metrology import fit_sphere, sphere_centre_from_touch
from machinesim.nc import Program

__all__ = [
    "AXES", "Identification", "ProbePlan", "ReferenceSpheres", "SphereReading",
    "axis_targets", "c_axis_centre", "compensate", "compensate_model_based", "generating_points",
    "identified_errors", "identify", "nose_shift", "probe_axes", "read_sphere",
    "rotation", "setting_from_centres",
]

MM = 1e-3
#: The axes the procedure drives, in `Machine.axes` order.
AXES = ("X", "Y", "Z", "B", "C")
#: Two directions are "along X" (S1 -> S2) or "along Y" (S1 -> S3) within this angle (rad):
#: the formulas take the designed S1S2 and S1S3 as the workpiece X and Y axes.
LAYOUT_ANGLE = 1e-9


def rotation(alpha, beta, gamma) -> np.ndarray:
    """``Rx(alpha) Ry(beta) Rz(gamma)``, shape (3, 3), angles in rad."""
    ca, sa = math.cos(alpha), math.sin(alpha)
    cb, sb = math.cos(beta), math.sin(beta)
    cg, sg = math.cos(gamma), math.sin(gamma)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]])
    ry = np.array([[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]])
    rz = np.array([[cg, -sg, 0.0], [sg, cg, 0.0], [0.0, 0.0, 1.0]])
    return rx @ ry @ rz


def _rz(angles: np.ndarray) -> np.ndarray:
    """Rotations about Z, shape (N, 3, 3), for angles (N,) rad."""
    c, s = np.cos(angles), np.sin(angles)
    out = np.zeros(angles.shape + (3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 1, 0], out[..., 1, 1] = c, -s, s, c
    out[..., 2, 2] = 1.0
    return out


def _ry(angles: np.ndarray) -> np.ndarray:
    """Rotations about Y, shape (N, 3, 3), for angles (N,) rad."""
    c, s = np.cos(angles), np.sin(angles)
    out = np.zeros(angles.shape + (3, 3))
    out[..., 0, 0], out[..., 0, 2], out[..., 2, 0], out[..., 2, 2] = c, s, -s, c
    out[..., 1, 1] = 1.0
    return out


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
    radius: float = 2.0 * MM

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
        centres.flags.writeable = False
        object.__setattr__(self, "centres", centres)
        object.__setattr__(self, "radius", radius)


@dataclass(frozen=True)
class ProbePlan:
    """How the spheres are probed (Fig. 4b, 4c).

    Attributes
    ----------
    half_width : float
        Each scan runs the ball centre this far either side of the centre, m. Default 1.2
        mm: on a R2 mm cavity read with a R0.25 mm ball the contact then stays 0.6 mm inside
        the rim, room for a workpiece 0.5 mm off.
    points : int
        Points per scan line.
    press : float
        How far below the expected surface the free ball runs, m: the stylus stays pressed in
        for setting errors up to this. Default 0.1 mm.
    stroke : float
        Measuring range of the stylus, m.
    lift : float
        Height of the ball centre above the sphere centre where the bottom touch starts, m.
    passes : int
        Readings of each sphere, the scans of each centred on the last one's result.
    """

    half_width: float = 1.2 * MM
    points: int = 41
    press: float = 0.1 * MM
    stroke: float = 0.5 * MM
    lift: float = 0.3 * MM
    passes: int = 2

    def __post_init__(self) -> None:
        for name in ("half_width", "press", "stroke", "lift"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0.0):
                raise InputError(f"Expected {name} > 0 (m), got {value!r}", key=name)
        for name, least in (("points", 5), ("passes", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise InputError(f"Expected {name} an int >= {least}, got {value!r}", key=name)


@dataclass(frozen=True, eq=False)
class SphereReading:
    """One sphere read by the probe, in machine coordinates (the ideal frame at C = 0), m.

    Attributes
    ----------
    xy : ndarray, shape (2,)
        Centre x, y from the least-squares sphere of the last pass's two scans.
    bottom : ndarray, shape (3,)
        Probe-ball centre at the bottom touch.
    radius : float
        Fitted radius of the sphere surface (ball-centre sphere plus the ball radius).
    residual_rms : float
        RMS distance of the scanned ball centres from their sphere.
    """

    xy: np.ndarray
    bottom: np.ndarray
    radius: float
    residual_rms: float


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


def _check_machine(machine) -> None:
    if tuple(machine.axes) != AXES or "probe_tip" not in machine.frames:
        raise InputError(f"Expected a machine with axes {''.join(AXES)} and a probe_tip "
                         f"frame (robonano_a0ib), got {machine.name} with "
                         f"{''.join(machine.axes)}", key="machine")


def probe_axes(machine, ball, c_angle: float = 0.0) -> np.ndarray:
    """Axis values that put the nominal probe-ball centre at machine coordinates ``ball``.

    Parameters
    ----------
    machine : Machine
        `robonano_a0ib` (the ball sits on the B table, found from its ``probe_tip`` frame).
    ball : array-like, shape (N, 3) or (3,)
        Ball centres in machine coordinates (the ideal frame at C = 0), m.
    c_angle : float
        C axis value, rad (B stays 0).

    Returns
    -------
    ndarray, shape (N, 5) or (5,)
    """
    _check_machine(machine)
    ball = np.asarray(ball, dtype=np.float64)
    offset = machine.frame_pose("probe_tip", np.zeros(len(AXES)))[:3, 3]
    flat = ball.reshape(-1, 3)
    q = np.zeros((len(flat), len(AXES)))
    q[:, :3] = flat - offset
    q[:, 4] = c_angle
    return q.reshape(ball.shape[:-1] + (len(AXES),))


def _machine_points(probe, q: np.ndarray) -> np.ndarray:
    """Nominal ball centres (N, 3) in machine coordinates for recorded axis values (N, 5)."""
    at_zero = np.array(q, dtype=np.float64)
    at_zero[..., 3:] = 0.0
    return probe.nominal_centres(at_zero)


def read_sphere(probe, centre, plan: ProbePlan = ProbePlan(), c_angle: float = 0.0,
                radius: float = 2.0 * MM) -> SphereReading:
    """Read one sphere cavity: two orthogonal scans, a sphere fit, a bottom touch.

    Parameters
    ----------
    probe : TouchProbe
        On the machine with the workpiece (`machinesim.metrology.TouchProbe`).
    centre : array-like, shape (3,)
        Where the sphere centre is expected, machine coordinates at ``c_angle``, m.
    plan : ProbePlan
    c_angle : float
        C axis value during the reading, rad.
    radius : float
        Designed sphere radius, m (plans the scan heights only).

    Raises
    ------
    InputError
        When a scan misses the sphere or the bottom touch finds nothing: the sphere lies
        farther from ``centre`` than the plan reaches (about ``half_width`` / 2 sideways,
        ``press`` in height).
    """
    guess = np.array(centre, dtype=np.float64)
    ball_radius = probe.radius
    inner = radius - ball_radius
    if plan.half_width >= inner:
        raise InputError(f"Expected a scan half width below the ball-centre sphere radius "
                         f"{inner} m, got {plan.half_width} m", key="half_width")
    s = np.linspace(-plan.half_width, plan.half_width, plan.points)
    for _ in range(plan.passes):
        points = []
        for axis in (0, 1):
            path = np.tile(guess, (plan.points, 1))
            path[:, axis] += s
            path[:, 2] = guess[2] - np.sqrt(inner**2 - s**2) - plan.press
            scan = probe.scan(probe_axes(probe.machine, path, c_angle), stroke=plan.stroke)
            seen = ~np.isnan(scan.deflection)
            if np.count_nonzero(seen) < plan.points // 2:
                raise InputError(f"Expected the scan through {guess.tolist()} m to touch the "
                                 f"sphere at {plan.points // 2} of {plan.points} points or "
                                 f"more, got {np.count_nonzero(seen)}", key="centre")
            points.append(_machine_points(probe, scan.contact_q[seen]))
        fit = fit_sphere(np.vstack(points))
        guess = np.array([fit.centre[0], fit.centre[1], guess[2]])
    start = probe_axes(probe.machine, [guess[0], guess[1], guess[2] + plan.lift], c_angle)
    contact = probe.touch(start, "-Z", plan.lift + radius)
    if contact is None:
        raise InputError(f"Expected the bottom touch under {guess[:2].tolist()} m to meet the "
                         f"sphere within {plan.lift + radius} m, it met nothing", key="centre")
    bottom = _machine_points(probe, contact[None])[0]
    return SphereReading(_frozen(guess[:2]), _frozen(bottom), float(fit.radius + ball_radius),
                         float(fit.residual_rms))


def setting_from_centres(centres, designed) -> tuple[WorkpieceSetting, np.ndarray]:
    """Eqs 1-4: the setting errors from the measured sphere centres.

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
    alpha = math.atan2(-ez[1], ez[2])
    beta = math.asin(min(1.0, max(-1.0, ez[0])))
    back = rotation(0.0, -beta, 0.0) @ rotation(-alpha, 0.0, 0.0) @ ex
    gamma = math.atan2(back[1], back[0])
    r = rotation(alpha, beta, gamma)
    d = centres[0] - r @ designed[0]
    return WorkpieceSetting(d, alpha, beta, gamma), _frozen(centres[0] - designed[0])


def c_axis_centre(before, after) -> np.ndarray:
    """Fig. 6: the C-axis centre from bottom points before and after a 180-deg turn of C.

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


def identify(probe, spheres: ReferenceSpheres, plan: ProbePlan = ProbePlan()) -> Identification:
    """The whole measurement: three spheres at C = 0, again at C = 180 deg, eqs 1-4, Fig. 6.

    Parameters
    ----------
    probe : TouchProbe
        The probe on `robonano_a0ib`, touching the loaded workpiece.
    spheres : ReferenceSpheres
        The spheres as designed; they are looked for where the ideal setting puts them.
    plan : ProbePlan
    """
    _check_machine(probe.machine)
    ideal = spheres.centres
    first = [read_sphere(probe, c, plan, 0.0, spheres.radius) for c in ideal]
    # at C = 180 deg a table point p shows at -p in machine coordinates (C centre at 0)
    turned = [read_sphere(probe, np.r_[-r.xy, c[2]], plan, math.pi, spheres.radius)
              for r, c in zip(first, ideal, strict=True)]
    radius = float(np.mean([r.radius for r in first]))
    centres = np.array([sphere_centre_from_touch(r.xy, r.bottom[2], radius,
                                                 probe_radius=probe.radius, concave=True)
                        for r in first])
    setting, delta = setting_from_centres(centres, ideal)
    each = c_axis_centre([r.bottom for r in first], [r.bottom for r in turned])
    return Identification(_frozen(centres), radius, setting, delta,
                          _frozen(each.mean(axis=0)), _frozen(each), tuple(first + turned))


def identified_errors(found: Identification) -> ErrorModel:
    """The identified machine state as an error model (model-based compensation).

    The C centre enters as the location errors EX0C, EY0C of the C axis: they move the C axis
    line to ``c_centre`` in the machine coordinates of C = 0, where the probe found it.
    """
    x, y = found.c_centre.tolist()
    return ErrorModel(workpiece=found.setting, location={"C": {"EX0C": x, "EY0C": y}})


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


def axis_targets(program: Program) -> np.ndarray:
    """Axis targets (N, 5) of every move, X Y Z B C (m, rad); an axis not yet set is 0."""
    out = np.zeros((len(program.moves), len(AXES)))
    for n, move in enumerate(program.moves):
        for i, letter in enumerate(AXES):
            out[n, i] = move.target.get(letter, 0.0)
    extra = set(program.axes) - set(AXES)
    if extra:
        raise InputError(f"Expected a program on axes {''.join(AXES)}, got axes "
                         f"{''.join(sorted(extra))} as well", source=program.source)
    return out


def _program_poses(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tool orientations (N, 3, 3) and tips (N, 3) the program asks for on the ideal part."""
    orientation = _rz(q[:, 4]) @ _ry(q[:, 3])
    return orientation, np.einsum("nij,nj->ni", _rz(q[:, 4]), q[:, :3])


def _rewrite(program: Program, q: np.ndarray, how: str) -> Program:
    moves = []
    for n, move in enumerate(program.moves):
        # a dwell stays where the move before it ended (a program's modal rule)
        row = q[n - 1] if move.kind == "dwell" and n else q[n]
        target = {a: float(v) for a, v in zip(AXES, row, strict=True)}
        moves.append(replace(move, target=target))
    return Program(tuple(moves), program.number, f"{program.source} ({how})",
                   program.work_offsets)


def compensate(program: Program, found: Identification, nose_radius: float = 0.0) -> Program:
    """Rewrite an NC program by eqs 5-7 (derived), for the identified setting and C centre.

    Parameters
    ----------
    program : Program
        Written for the ideal workpiece on the nominal machine (axes X Y Z B C).
    found : Identification
    nose_radius : float
        Nose radius of a round-nose tool, m: the arc's lowest point is kept on the path
        (`nose_shift`); 0 keeps the tip on it, as the paper's eq 7.

    Returns
    -------
    Program
        The same moves with B = b + beta, C = c + gamma and X Y Z by eq 7; feeds unchanged.
    """
    q = axis_targets(program)
    s = found.setting
    r = rotation(s.alpha, s.beta, s.gamma)
    c0 = np.r_[found.c_centre, 0.0]
    b_new, c_new = q[:, 3] + s.beta, q[:, 4] + s.gamma
    wanted, tip = _program_poses(q)
    reached = r.T @ (_rz(c_new) @ _ry(b_new))
    tip = tip + nose_shift(wanted, reached, nose_radius)
    ideal = s.delta + tip @ r.T
    xyz = c0 + np.einsum("nji,nj->ni", _rz(c_new), ideal - c0)
    return _rewrite(program, np.column_stack([xyz, b_new, c_new]), "compensated, eqs 5-7")


def compensate_model_based(program: Program, machine, found: Identification,
                           nose_radius: float = 0.0, iterations: int = 3) -> Program:
    """Rewrite an NC program by inverse kinematics on the identified model.

    Each target becomes the axis values that put the tool, on the machine with the
    identified setting and C centre (`identified_errors`), at the pose the program asks for
    on the ideal workpiece (`Machine.axis_values`: position exact, orientation as far as
    five axes allow). With ``nose_radius`` the tip target is moved by `nose_shift` for the
    orientation reached, and solved again (``iterations`` times in all).

    Parameters
    ----------
    program : Program
    machine : Machine
        `robonano_a0ib`.
    found : Identification
    nose_radius : float
        m; see `compensate`.
    iterations : int
        Solves (1 without a nose radius).
    """
    _check_machine(machine)
    q = axis_targets(program)
    errors = identified_errors(found)
    wanted, tip = _program_poses(q)
    target = np.tile(np.eye(4), (len(q), 1, 1))
    target[:, :3, :3] = wanted
    target[:, :3, 3] = tip
    solution = q
    for _ in range(iterations if nose_radius else 1):
        solution = machine.axis_values(target, errors, q_start=solution).q
        reached = machine.tool_pose(solution, errors)[:, :3, :3]
        target[:, :3, 3] = tip + nose_shift(wanted, reached, nose_radius)
    return _rewrite(program, solution, "compensated, model-based")


def generating_points(machine, errors, program: Program, wanted,
                      nose_radius: float = 0.0) -> np.ndarray:
    """Where the nose arc's lowest point (or the tip) really goes, for checking a program.

    For each move's target: the point of the tool that generates a surface facing the
    wanted tool axis (`nose_shift`), written as the tip position that would put it there
    with the wanted orientation, in the workpiece frame of the machine with ``errors``.
    Verification only: the procedure never calls it.

    Parameters
    ----------
    machine : Machine
    errors : ErrorModel or None
    program : Program
    wanted : array-like, shape (N, 3, 3)
        The tool orientations the program is meant to give, one per move (the nominal
        program's on the nominal machine).
    nose_radius : float
        m; 0 gives the tip.

    Returns
    -------
    ndarray, shape (N, 3)
        m; compare with the nominal program's on the nominal machine.
    """
    poses = machine.tool_pose(axis_targets(program), errors)
    return poses[:, :3, 3] - nose_shift(wanted, poses[:, :3, :3], nose_radius)


def _frozen(values) -> np.ndarray:
    array = np.array(values, dtype=np.float64)
    array.flags.writeable = False
    return array
