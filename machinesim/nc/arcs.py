"""Circular interpolation (G02/G03): an arc as the straight moves that follow it within the
chord tolerance.

Plane coordinates (u, v) are the plane's axes in the order that makes the plane's normal
their cross product: G17 (X, Y) about +Z, G18 (Z, X) about +Y, G19 (Y, Z) about +X. G03
turns counter-clockwise seen from the normal's tip (positive rotation about it), G02
clockwise. The centre is given either as I J K (its offset from the start, always
incremental, as FANUC) or as a signed radius R (R > 0: the arc of at most 180 deg, R < 0:
the one over 180 deg).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from machinesim.exceptions import NCProgramError
from machinesim.tolerances import CHORD_TOLERANCE_M, POSE_M

#: (u, v, normal) axes and (u, v) centre words of each plane.
PLANES = {
    "G17": (("X", "Y", "Z"), ("I", "J")),
    "G18": (("Z", "X", "Y"), ("K", "I")),
    "G19": (("Y", "Z", "X"), ("J", "K")),
}
#: Default chord tolerance of an arc, m: the 1 nm of motion's rotary moves
#: (`machinesim.tolerances.CHORD_TOLERANCE_M`), the axis resolution of the machines, for the
#: same reason: the polygon never shows in a cut at the machine's resolution.
ARC_CHORD_M = CHORD_TOLERANCE_M
#: Largest difference between the radius at the start (|I J K|) and at the end of an arc
#: given by its centre, m. A CAM post rounds the start, the end and the centre offset to its
#: output increment; with the 0.001 mm of FANUC's usual IS-B input the radius at the end can
#: then differ from the one at the start by |end error| + |start error| + 2 |centre error|
#: <= 4 x 0.5 um x sqrt(2) = 2.83 um. 3 um accepts every such arc and still refuses a
#: centre wrong by one digit in the hundredths of a millimetre (10 um). Within it, the
#: radius goes linearly from start to end along the arc (a spiral, as FANUC does it), so the
#: path joins both programmed points.
ARC_RADIUS_TOLERANCE_M = 3e-6
#: The same for an inch program (G20): its output increment, 0.0001 in, allows 4 x 0.5 x
#: 2.54 um x sqrt(2) = 7.18 um; 7.5 um accepts every such arc and still refuses a centre
#: wrong by one digit in the thousandths of an inch (25.4 um).
ARC_RADIUS_TOLERANCE_INCH_M = 7.5e-6
#: End and start closer than this are one point: a full circle (I J K form). POSE_M: the
#: agreement of two float64 positions on a ~1 m machine.
FULL_CIRCLE_M = POSE_M
#: The angular step never exceeds this: at least four segments a turn even for an arc far
#: smaller than the tolerance, so that its moves still go round the centre.
MAX_STEP_RAD = math.pi / 2
#: The step is taken for the tolerance times this, so that float64 rounding of the angles
#: (~1e-16 relative) never puts a chord's sagitta over the tolerance itself.
_SAFETY = 1.0 - 1e-9
#: An arc's points, centre + r (cos a, sin a), carry round-off of about 4 ulp of its radius r
#: (the centre's, the angle's, up to 2 ulp of r at a = pi, and the sum's): r times this. An
#: arc whose r times it passes the chord tolerance is refused (`arc_points`): float64 cannot
#: place its points within the tolerance (at 1 nm, radii beyond 1.1e6 m, 1,100 km; a lens or
#: mirror of 20 m radius is far inside), and a radius of 1e300 mm had overflowed r^2 to inf
#: and crashed the reader with ZeroDivisionError.
RADIUS_ROUND_OFF = 2.0**-50
#: An arc by R whose half chord comes within this many ulp of the largest coordinate of
#: its radius is a half circle: the end points' decimal-to-binary rounding (half an ulp
#: each), the subtraction and the hypot of the chord leave its length uncertain by a few
#: ulp of the coordinates (`_centre_from_radius`).
_HALF_CIRCLE_ULPS = 8.0


#: Arcs a warning lists by line; the rest are counted.
NEAR_CIRCLES_LISTED = 5


class NearCircle(NamedTuple):
    """An I J K arc whose end lies within ``tolerance`` (the radius tolerance, m) of its
    start but not on it, read as the short arc it writes (``sweep`` < 180 deg)."""

    code: str  # G02 or G03
    length: float  # m, along the moves the reader made of it
    sweep: float  # rad
    gap: float  # m, from its start to its end
    tolerance: float  # m


def near_circle_warning(arcs: dict[int, NearCircle], source: str) -> str:
    """The warning for ``arcs`` (line -> `NearCircle`): each is read as written, a short
    arc, where a full circle was most likely meant. An end that close to the start is within
    what a post's rounding leaves on an arc, where a full circle's end is its start exactly;
    no FANUC rule for such an end was found (the docs/pages search for parameter 3410 and
    alarm PS0020 found the radius check only: Series 15i-MA B-63324EN/01 4.4 runs an end
    off the circle within it as a spiral), so the reader warns and does not refuse: a short
    arc, as written, is also a path an arc-fitting post may write."""
    listed = [f"{arc.code} at line {line}: {arc.length * 1e6:.4g} um long "
              f"({math.degrees(arc.sweep):.3g} deg), its end {arc.gap * 1e6:.4g} um from its "
              "start" for line, arc in list(arcs.items())[:NEAR_CIRCLES_LISTED]]
    more = len(arcs) - len(listed)
    tolerance = next(iter(arcs.values())).tolerance
    return (f"{source}: {len(arcs)} arc{'s' if len(arcs) > 1 else ''} with I J K whose end "
            f"is within {tolerance * 1e6:g} um of its start but not on it (within the "
            "rounding a post leaves on an arc's radius), read as written, a short arc, where "
            f"a full circle was most likely meant: {'; '.join(listed)}"
            + (f"; and {more} more" if more > 0 else "")
            + ". For a full circle write the end as the start (or leave out its axis words)")


def arc_points(
    start: tuple[float, float],
    end: tuple[float, float],
    *,
    clockwise: bool,
    centre: tuple[float, float] | None = None,
    radius: float | None = None,
    chord_tolerance: float = ARC_CHORD_M,
    radius_tolerance: float = ARC_RADIUS_TOLERANCE_M,
    max_segments: int | None = None,
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The points that replace an arc from ``start`` to ``end`` in its plane.

    Parameters
    ----------
    start, end : (u, v), m
        Plane coordinates of the arc's ends.
    clockwise : bool
        True for G02.
    centre : (u, v), m, optional
        The centre (start + I J K); exactly one of ``centre`` and ``radius``.
    radius : float, m, optional
        The signed radius R.
    chord_tolerance : float, m
        Largest distance between a segment and the arc.
    radius_tolerance : float, m
        Largest difference of the start and end radii (centre form), or of half the chord
        beyond |R| (radius form).
    max_segments : int, optional
        Refuse an arc that needs more segments than this.

    Returns
    -------
    fractions : ndarray, shape (n,)
        Fraction of the swept angle at each point, in (0, 1], the last 1.0 (for helical and
        other axes that move with the arc).
    points : ndarray, shape (n, 2)
        The points after the start, m; the last is ``end`` exactly.
    radius : float
        The radius at the start, m.
    sweep : float
        The signed swept angle, rad (negative clockwise).

    Raises
    ------
    NCProgramError
        Without location (the reader adds it): an end off the circle beyond the tolerance,
        a zero radius, R with end = start, an arc needing more than ``max_segments``.
    """
    s = np.array(start, dtype=np.float64)
    e = np.array(end, dtype=np.float64)
    chord = float(np.hypot(*(e - s)))
    if radius is not None:
        _check_radius(abs(radius), chord_tolerance)
        c = _centre_from_radius(s, e, chord, radius, clockwise, radius_tolerance)
    else:
        c = np.array(centre, dtype=np.float64)
    r0 = float(np.hypot(*(s - c)))
    r1 = float(np.hypot(*(e - c)))
    if r0 == 0.0:
        raise NCProgramError("the arc's centre is its start point (zero radius); give I J K "
                             "from the start to the centre")
    _check_radius(max(r0, r1), chord_tolerance)
    if radius is None and abs(r1 - r0) > radius_tolerance:
        raise NCProgramError(
            f"the end point is off the arc: radius {r0 * 1e3:.6f} mm at the start (from I J K) "
            f"but {r1 * 1e3:.6f} mm at the end, {abs(r1 - r0) * 1e6:.3f} um apart; expected "
            f"at most {radius_tolerance * 1e6:g} um"
        )
    a0 = math.atan2(s[1] - c[1], s[0] - c[0])
    a1 = math.atan2(e[1] - c[1], e[0] - c[0])
    if chord <= FULL_CIRCLE_M:
        sweep = 2.0 * math.pi
    else:
        sweep = (a0 - a1) % (2.0 * math.pi) if clockwise else (a1 - a0) % (2.0 * math.pi)
    rmax = max(r0, r1)
    # sagitta r (1 - cos(step / 2)) = 2 r sin^2(step / 4), solved without cancellation
    q = math.sqrt(chord_tolerance * _SAFETY / (2.0 * rmax))
    step = MAX_STEP_RAD if q >= math.sin(MAX_STEP_RAD / 4) else 4.0 * math.asin(q)
    n = max(1, math.ceil(sweep / step))
    if max_segments is not None and n > max_segments:
        raise NCProgramError(
            f"the arc (radius {r0 * 1e3:.6g} mm, {math.degrees(sweep):.6g} deg) needs {n} "
            f"segments to stay within the chord tolerance {chord_tolerance * 1e9:g} nm, more "
            f"than the {max_segments} moves left of the most a program may expand to; raise "
            "the chord tolerance, or, where the moves before it are many (a subprogram's "
            "repeats), make the program shorter"
        )
    signed = -sweep if clockwise else sweep
    fractions = np.arange(1, n + 1, dtype=np.float64) / n
    angle = a0 + signed * fractions
    r = r0 + (r1 - r0) * fractions
    points = np.empty((n, 2))
    points[:, 0] = c[0] + r * np.cos(angle)
    points[:, 1] = c[1] + r * np.sin(angle)
    fractions[-1] = 1.0
    points[-1] = e
    return fractions, points, r0, signed


def _check_radius(radius: float, chord_tolerance: float) -> None:
    """Refuse a ``radius`` (m) whose points float64 cannot place within ``chord_tolerance``
    (m) of the circle (`RADIUS_ROUND_OFF`)."""
    if not radius * RADIUS_ROUND_OFF <= chord_tolerance:
        raise NCProgramError(
            f"the arc's radius of {radius * 1e3:.6g} mm is too large: float64 places its "
            f"points only within about {radius * RADIUS_ROUND_OFF * 1e9:.3g} nm (4 ulp of the "
            f"radius) of the circle, more than the chord tolerance "
            f"{chord_tolerance * 1e9:g} nm, so radii beyond "
            f"{chord_tolerance / RADIUS_ROUND_OFF * 1e3:.6g} mm are not read; is the radius "
            "(R, or the centre I J K) in the unit meant? An arc this flat is its chord: G01")


def _centre_from_radius(s: np.ndarray, e: np.ndarray, chord: float, radius: float,
                        clockwise: bool, tolerance: float) -> np.ndarray:
    if radius == 0.0:
        raise NCProgramError("R0 is no arc; expected a radius R > 0 (up to 180 deg) or R < 0 "
                             "(over 180 deg)")
    if chord <= FULL_CIRCLE_M:
        raise NCProgramError("an arc given by R cannot be a full circle (its end is its "
                             "start); give the centre with I J K")
    half = chord / 2.0
    r = abs(radius)
    if half > r + tolerance:
        raise NCProgramError(
            f"the end point is {chord * 1e3:.6f} mm from the start, more than the diameter "
            f"2|R| = {2 * r * 1e3:.6f} mm (beyond the {tolerance * 1e6:g} um tolerance)"
        )
    # The centre's distance from the chord, sqrt(r^2 - half^2), is ill-conditioned at a half
    # circle: the chord carries the round-off of its end points (a few ulp of the largest
    # coordinate), and sqrt turns an error e of r - half into one of sqrt(2 r e), 0.3 nm for
    # an inch half circle of R0.5 at X2. .. X3. and 1.7 nm at 500 mm. Within that round-off
    # the arc is the half circle, its centre the chord's midpoint.
    slack = _HALF_CIRCLE_ULPS * math.ulp(max(float(np.max(np.abs(s))), float(np.max(np.abs(e))), r))
    h = 0.0 if r - half <= slack else math.sqrt((r - half) * (r + half))
    mid = (s + e) / 2.0
    left = np.array([s[1] - e[1], e[0] - s[0]]) / chord  # the chord turned +90 deg
    # counter-clockwise along the shorter arc keeps the centre on the chord's left
    side = 1.0 if (radius > 0.0) != clockwise else -1.0
    return mid + side * h * left
