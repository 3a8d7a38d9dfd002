"""Reading a workpiece's reference spheres with the on-machine touch probe (paper 002, Fig. 4).

Paper 002 (Xu, Nakamoto, Takeuchi 2021, section 2.3) finds a robot-loaded workpiece from
three ball-end-milled sphere cavities: each is scanned in two orthogonal lines, its centre's
x and y found by a least-squares sphere fit, and its z by a touch down the probe axis at the
fitted centre (Fig. 4b, 4c); all three are read at C = 0 and again at C = 180 deg for the C
centre (Fig. 6). `read_spheres` does that on a `machinesim.metrology.TouchProbe` and returns
the `SphereReadings` that `machinesim.identification.workpiece_setting.identify` turns into
the setting. The procedure (`machinesim.procedures.workpiece_setting`) calls it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.identification.workpiece_setting import (
    AXES,
    ReferenceSpheres,
    SphereReading,
    SphereReadings,
    check_machine,
    sphere_reading,
)
from machinesim.metrology import fit_sphere
from machinesim.metrology._arrays import as_count, as_number
from machinesim.metrology.probe_instrument import StylusOverTravel
from machinesim.rotations import rotation_xyz
from machinesim.units import M_PER_MM

__all__ = ["PROBE_PLAN", "ProbePlan", "probe_axes", "probing_miss", "read_sphere",
           "read_spheres"]

MM = M_PER_MM


#: How far (m) a reference sphere may sit off its designed place in x or y for the default
#: plan's scans to find it: measured through the lab (noise off, the grooves' block set
#: (dx, dy, 3 um)): dx 330 um and -330 um found, 340 and 350 um missed; (290, 290) um found,
#: (320, 320) missed. `probing_miss` refuses beyond it; within, a diagonal setting can still
#: be missed, and the probe says so.
SIDEWAYS_REACH = 0.34 * M_PER_MM
#: How far (m) a reference sphere may sit below its designed place for the default plan's
#: bottom touch to meet it: the touch starts ``lift`` over the designed centre and runs
#: ``lift`` + the sphere's radius down, and the ball meets the cavity's bottom its own
#: radius (0.25 mm) over it. Measured through the lab (either load set (0, 0, dz)): noise
#: off, -250 um found and -251 missed; with the lab's realism -240 found, -245 missed.
HEIGHT_REACH_BELOW = 0.25 * M_PER_MM
#: How far (m) a reference sphere may sit above its designed place: the scans and the
#: touch start ``lift`` (0.3 mm) over the designed centre, which lies in the part once the
#: sphere is more than its radius less the ball's, plus ``lift``, higher (2.05 mm), and the
#: probe refuses to start there. Measured: 2040 um found, 2060 refused, either load.
HEIGHT_REACH_ABOVE = 2.05 * M_PER_MM


@dataclass(frozen=True)
class ProbePlan:
    """How the spheres are probed (Fig. 4b, 4c).

    Attributes
    ----------
    half_width : float
        Each scan runs the ball centre this far either side of the centre, m. Default 1.2
        mm: on a R2 mm cavity read with a R0.25 mm ball the contact then stays 0.6 mm inside
        the rim; the scans find a sphere up to about 0.33 mm off (`SIDEWAYS_REACH`: farther,
        their ends run more than the stroke less the press into the rising wall).
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
        Readings of each sphere, the scans of each centred on the last one's result: the
        three spheres are then seen alike (docs/procedures/workpiece_setting.md).
    """

    half_width: float = 1.2 * MM
    points: int = 41
    press: float = 0.1 * MM
    stroke: float = 0.5 * MM
    lift: float = 0.3 * MM
    passes: int = 2

    def __post_init__(self) -> None:
        for name in ("half_width", "press", "stroke", "lift"):
            object.__setattr__(self, name, as_number(getattr(self, name), name, sign="> 0"))
        for name, least in (("points", 5), ("passes", 1)):
            object.__setattr__(self, name, as_count(getattr(self, name), name, least=least))


#: The default plan.
PROBE_PLAN = ProbePlan()


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
    check_machine(machine)
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
        On the machine with the workpiece (`machinesim.Lab.touch_probe`).
    centre : array-like, shape (3,)
        Where the sphere centre is expected, machine coordinates at ``c_angle``, m.
    plan : ProbePlan
    c_angle : float
        C axis value during the reading, rad.
    radius : float
        Designed sphere radius, m (plans the scan heights only).

    Returns
    -------
    SphereReading
        `machinesim.identification.workpiece_setting.sphere_reading` of the last pass's
        scans and the bottom touch.

    Raises
    ------
    InputError
        When a scan misses the sphere or the bottom touch finds nothing: the sphere lies
        farther from ``centre`` than the plan reaches (about ``half_width`` / 2 sideways).
        A first scan that misses or over-travels (the sphere more than ``press`` higher or
        lower than expected) is not yet an error: the bottom is touched first and the scans
        run again about the height found.
    """
    guess = np.array(centre, dtype=np.float64)
    inner = radius - probe.radius
    if plan.half_width >= inner:
        raise InputError(f"Expected a scan half width below the ball-centre sphere radius "
                         f"{inner} m, got {plan.half_width} m", key="half_width")
    s = np.linspace(-plan.half_width, plan.half_width, plan.points)
    located = False
    passes = 0
    while passes < plan.passes:
        points = _scans(probe, guess, s, inner, plan, c_angle)
        if points is None:
            if located:
                where = np.asarray(centre, dtype=np.float64).tolist()
                raise InputError(f"Expected the scans through {guess.tolist()} m (the height "
                                 f"of a bottom touch under {where} m) to touch the sphere "
                                 f"at {plan.points // 2} of {plan.points} points or more "
                                 f"within the stylus stroke, they did not: the sphere lies "
                                 "farther off its place than they reach (about "
                                 f"{SIDEWAYS_REACH / M_PER_MM:g} mm in x or y with the default "
                                 "plan)",
                                 key="centre")
            # The cavity is not at the expected height (a workpiece set much higher or
            # lower, or tilted): find its bottom first, as an operator would, and scan again.
            bottom = _bottom_touch(probe, guess, radius, plan, c_angle)
            guess = np.r_[guess[:2], bottom[2] + inner]
            located = True
            continue
        guess = np.r_[fit_sphere(points).centre[:2], guess[2]]
        passes += 1
    bottom = _bottom_touch(probe, guess, radius, plan, c_angle)
    return sphere_reading(points, bottom, probe.radius, c_angle)


def _scans(probe, guess, s, inner, plan, c_angle):
    """Contact points (N, 3) of the two orthogonal scans about ``guess``, or None when
    either touches the sphere at fewer than half its points or runs into it (over-travel)."""
    points = []
    for axis in (0, 1):
        path = np.tile(guess, (plan.points, 1))
        path[:, axis] += s
        path[:, 2] = guess[2] - np.sqrt(inner**2 - s**2) - plan.press
        try:
            scan = probe.scan(probe_axes(probe.machine, path, c_angle), stroke=plan.stroke)
        except StylusOverTravel:
            return None
        seen = ~np.isnan(scan.deflection)
        if np.count_nonzero(seen) < plan.points // 2:
            return None
        points.append(_machine_points(probe, scan.contact_q[seen]))
    return np.vstack(points)


def _bottom_touch(probe, guess, radius, plan, c_angle) -> np.ndarray:
    """The ball centre (3,) where a touch down the probe axis under ``guess`` meets the
    cavity, machine coordinates (Fig. 4c)."""
    start = probe_axes(probe.machine, [guess[0], guess[1], guess[2] + plan.lift], c_angle)
    contact = probe.touch(start, "-Z", plan.lift + radius)
    if contact is None:
        raise InputError(f"Expected the bottom touch under {guess[:2].tolist()} m to meet the "
                         f"sphere within {plan.lift + radius} m, it met nothing: the "
                         "workpiece sits farther from its drawing than the probing plan "
                         "searches (check the setting's size: position, rotations)",
                         key="centre")
    return _machine_points(probe, contact[None])[0]


def probing_miss(spheres: ReferenceSpheres, setting, plan: ProbePlan = ProbePlan()
                 ) -> str | None:
    """Whether a workpiece set by ``setting`` (a `WorkpieceSetting`: ``W = T(d) Rx Ry Rz``)
    puts a reference sphere farther off its designed place in x or y than `read_sphere`'s
    scans find it with the default plan (`SIDEWAYS_REACH`), or lower or higher than its
    bottom touch reaches (`HEIGHT_REACH_BELOW`, `HEIGHT_REACH_ABOVE`): what moves, or None
    (always None for another plan, whose reach is not measured). The scans are made about
    the designed centres; beyond that reach they run into the cavity's wall (over the
    stylus's stroke) or miss it, the bottom touch meets nothing, or the probe would start
    inside the part, and the reading is refused after the probe has run. The C centre's
    offset, micrometres across, is left out."""
    if plan != PROBE_PLAN:
        return None
    centres = spheres.centres
    rotation = rotation_xyz(setting.alpha, setting.beta, setting.gamma)
    landed = np.asarray(setting.delta, dtype=np.float64) + centres @ rotation.T
    side = np.abs(landed - centres)[:, :2]
    k, axis = np.unravel_index(int(np.argmax(side)), side.shape)
    if side[k, axis] > SIDEWAYS_REACH:
        x, y = centres[k, :2] / M_PER_MM
        return (f"it puts reference sphere S{k + 1} (designed at x {x:g}, y {y:g} mm) "
                f"{side[k, axis] / M_PER_MM:.4g} mm off its place in {'xy'[axis]}, where the "
                f"probe's scans find a sphere at most about {SIDEWAYS_REACH / M_PER_MM:g} mm "
                "off in x or y")
    height = landed[:, 2] - centres[:, 2]
    for k in (int(np.argmin(height)), int(np.argmax(height))):
        low = height[k] < -HEIGHT_REACH_BELOW
        if low or height[k] > HEIGHT_REACH_ABOVE:
            x, y = centres[k, :2] / M_PER_MM
            return (f"it puts reference sphere S{k + 1} (designed at x {x:g}, y {y:g} mm) "
                    f"{abs(height[k]) / M_PER_MM:.4g} mm {'lower' if low else 'higher'} than "
                    "its place, where the probe finds a sphere at most "
                    f"{HEIGHT_REACH_BELOW / M_PER_MM:g} mm lower (its bottom touch meets "
                    f"nothing below) and {HEIGHT_REACH_ABOVE / M_PER_MM:g} mm higher (it "
                    "would start inside the part above)")
    return None


def read_spheres(probe, spheres: ReferenceSpheres, plan: ProbePlan = ProbePlan()
                 ) -> SphereReadings:
    """The whole measurement (Fig. 4, Fig. 6): three spheres at C = 0, again at C = 180 deg.

    The spheres are looked for where the ideal setting puts them; after the turn, where the
    first readings put them turned by 180 deg about the nominal C axis (a table point p
    shows at -p in machine coordinates).
    """
    check_machine(probe.machine)
    ideal = spheres.centres
    first = [read_sphere(probe, c, plan, 0.0, spheres.radius) for c in ideal]
    turned = [read_sphere(probe, np.r_[-r.xy, c[2]], plan, math.pi, spheres.radius)
              for r, c in zip(first, ideal, strict=True)]
    return SphereReadings(spheres, tuple(first), tuple(turned), probe.radius,
                          probe.readout.std, probe.lobing_amplitudes, probe.sphericity)
