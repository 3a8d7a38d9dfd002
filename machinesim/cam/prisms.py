"""Test pieces of V grooves cut at set tool angles: paper 000's calibration ramps and its
angle-variable prism pattern, for a planer whose V tool turns about the A axis.

Each piece is a stock block and an NC program for the nominal arm radius r0 (the edge placed
by `machinesim.identification.tool_rotation_arm.nominal_axes`). They carry no measuring and no
identification: `machinesim.procedures.tool_rotation_arm` cuts and reads them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.identification.tool_rotation_arm import nominal_axes
from machinesim.metrology._arrays import as_floats, as_number, shown
from machinesim.nc import ProgramBuilder
from machinesim.nc.cycles import PECK_CLEARANCE_M
from machinesim.nc.program import Program
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = ["APPROACH_MARGIN_M", "CLEARANCE_MARGIN_M", "FLOOR_M", "SEARCH_MARGIN_M",
           "SPACING_MARGIN_M", "STATION_DITHER_M", "CalibrationPlan", "PrismPattern"]

#: Extra depth step between calibration stations (m): 1/9 of the microscope's 1 nm display
#: step, so the nine stations' apexes fall at nine places on that step and its rounding
#: averages out (with stations whole um apart, it repeats at every station when the noise
#: is off).
STATION_DITHER_M = 1e-9 / 9
#: Ramp depth kept beyond the capture range and the deepest station (m): two of the coarse
#: search's 10 um depth steps, so the walk down the ramp sees the groove start before it.
SEARCH_MARGIN_M = 20e-6
#: Ramp spacing kept beyond `CalibrationPlan.min_spacing`'s sum (m).
SPACING_MARGIN_M = 0.1 * M_PER_MM
#: Edge clearance over the ramps' top for rapids (m), beyond the search range.
CLEARANCE_MARGIN_M = 0.5 * M_PER_MM
#: Stock kept under the deepest cut of the calibration ramps (m), in the default thickness
#: of their block (`CalibrationPlan.height`).
FLOOR_M = 1.0 * M_PER_MM
#: Height (m) the edge keeps over the stock's top in every rapid, beyond the worst height
#: error of the edge a plan accepts (`CalibrationPlan.approach`; the pattern's
#: `machinesim.procedures.tool_rotation_arm.pattern_clearance`): 0.1 mm, the distance the
#: control's own G83 cycle stops a rapid short of the material (`machinesim.nc.cycles.
#: PECK_CLEARANCE_M`, FANUC parameter No. 5115). Closer to the stock the program feeds.
APPROACH_MARGIN_M = PECK_CLEARANCE_M


class _Derived(float):
    """A plan's length it derived itself (`CalibrationPlan`'s search, clearance, spacing and
    height, from its capture): `dataclasses.replace` hands every field back as given, so a
    copy with another capture would keep the old capture's values; given back as this, it
    is derived again. The same float otherwise (value, repr, arithmetic)."""

    __slots__ = ()


#: `CalibrationPlan`'s fields derived from the others when None.
_DERIVED_FIELDS = ("search", "clearance", "spacing", "height")


def _groove_program(r0: float, clearance: float, x_out: float, grooves, feed: float,
                    number: int, approach: float | None = None) -> Program:
    """Grooves along +X: ``grooves`` of (angle, edge points (x, y, z)), the first by rapids;
    with ``approach`` given, rapids keep the edge that high over the surface at least, and
    the program feeds between it and a path's ends."""
    b, current = ProgramBuilder(number), 0.0

    def axes(y, z, angle):
        Y, Z = nominal_axes(y, z, angle, r0)
        return {"Y": float(Y), "Z": float(Z), "A": float(angle)}

    for angle, path in grooves:
        # A turns only with the edge before the stock in x: turning A swings the edge by tens
        # of mm on its arm, far below a straight-line interpolation of Y and Z.
        b.rapid(Z=float(nominal_axes(0.0, clearance, current, r0)[1])).rapid(X=x_out)
        (x0, y0, z0), current = path[0], angle
        stop = z0 if approach is None else max(z0, approach)
        b.rapid(**axes(y0, clearance, angle)).rapid(X=x0).rapid(Z=axes(y0, stop, angle)["Z"])
        if stop > z0:
            b.linear(Z=axes(y0, z0, angle)["Z"], feed_mm_per_min=feed)
        for x, y, z in path[1:]:
            b.linear(X=x, **axes(y, z, angle), feed_mm_per_min=feed)
        (_, y1, z1) = path[-1]
        if approach is not None and z1 < approach:
            b.linear(Z=axes(y1, approach, angle)["Z"], feed_mm_per_min=feed)
        b.rapid(Z=axes(y1, clearance, angle)["Z"])
    return b.rapid(X=x_out).build()


def _number(value, name: str, *, sign: str = "> 0", unit: str = "m",
            refusal: str | None = None) -> float:
    """A plan's number field as a float (`as_number`: a bool, a str, None or a non-finite
    value is refused naming ``name``); ``refusal``, where given, is the message's text for
    a value that is no finite number, and the sign is then the caller's to check."""
    try:
        return as_number(value, name, sign="any" if refusal else sign, unit=unit)
    except InputError:
        if refusal is None:
            raise
        raise InputError(f"{refusal}, got {shown(value)}", key=name) from None


def _numbers(values, name: str, what: str, size: int | None = None) -> tuple[float, ...]:
    """A plan's tuple field as floats: a sequence of ``size`` (default one or more) finite
    numbers (`as_floats`: no str, no bool)."""
    if isinstance(values, list | tuple) and any(isinstance(v, bool | np.bool_) for v in values):
        # numpy reads (True, 0.1) as floats: as_floats sees no bool in it
        raise InputError(f"Expected {name} as {what}, got {shown(values)}", key=name)
    array = as_floats(values, name, what)
    count = "one or more" if size is None else str(size)
    if array.ndim != 1 or array.size == 0 or (size is not None and array.size != size):
        raise InputError(f"Expected {name} as a sequence of {count} {what}, got "
                         f"{shown(values)}", key=name)
    if not np.isfinite(array).all():
        raise InputError(f"Expected {name} as finite {what}, got {shown(values)}", key=name)
    return tuple(float(v) for v in array)


def _tool(plan) -> float:
    """Check the plan's ``tool_angle`` (between 0 and 180 deg) and ``feed_mm_per_min``
    (> 0), set them as floats; return the tool angle."""
    tool_angle = _number(plan.tool_angle, "tool_angle", unit="rad")
    if not tool_angle < math.pi:
        raise InputError(f"Expected tool_angle, the V tool's included angle, below pi rad "
                         f"(180 deg), got {tool_angle!r}", key="tool_angle")
    object.__setattr__(plan, "tool_angle", tool_angle)
    object.__setattr__(plan, "feed_mm_per_min",
                       _number(plan.feed_mm_per_min, "feed_mm_per_min", unit="mm/min"))
    return tool_angle


def _angles(angles, tool_angle: float, name: str) -> tuple[float, ...]:
    values = _numbers(angles, name, "tool angles (rad)")
    limit = (math.pi - tool_angle) / 2.0
    if not all(abs(a) < limit for a in values):
        raise InputError(f"Expected tool angles within +-{math.degrees(limit):g} deg (a flank "
                         f"of the {math.degrees(tool_angle):g}-deg tool turns flat there), got "
                         f"{[round(math.degrees(a), 6) for a in values]} deg", key=name)
    return values


@dataclass(frozen=True)
class CalibrationPlan:
    """Ramp grooves at the calibration angles (paper 000: 0, 10, 20, 30, 40 deg).

    Attributes
    ----------
    angles : tuple of float
        Tool angles (rad); 0 first for `touch_off`.
    capture : float
        The largest length ``sqrt(e_ys**2 + (r - r0)**2)`` of the edge's offset vector the
        ramps find (m). At any tool angle the edge's height error is the offset vector turned
        by that angle, so its z is never beyond this length. Default 1 mm: five times the
        paper's 0.18 mm, more than a tool set by hand under a tool-setting microscope is off.
    search : float, optional
        Half range of each ramp's programmed depth (m); default (None) derived from
        ``capture``: ``capture + the deepest station + SEARCH_MARGIN_M``, so that an edge
        anywhere within the capture range starts its groove on the ramp with every station
        still on it.
    slope : float
        Descent of the ramp per unit of x.
    spacing : float, optional
        Distance between the ramps' starts along Y (m); default (None) 3 mm, or more where
        the capture range needs it (`min_spacing`): a groove's search window across Y
        (`window`) must stay clear of the next ramp's groove, whose low flank (5 deg from
        the surface at 40 deg) spreads sideways 11 times as far as it is deep. The first
        ramp starts `lead` in from the block's low-y edge.
    station_depths : tuple of float
        Groove depths (m) at which the microscope reads each groove.
    origin : (float, float)
        Corner (x, y) of the stock (m), away from the workpiece origin where the edge starts.
    tool_angle, clearance, feed_mm_per_min : float
        Included angle of the V tool (rad), edge clearance over the surface for rapids (m;
        default None: ``search + CLEARANCE_MARGIN_M``, or `approach` where that is more; a
        given one at least `approach`, the capture and `APPROACH_MARGIN_M`), feed (the
        paper's 12,000 mm/min). Rapids keep the edge `approach` over the block at least;
        the program feeds down to a ramp and back up from it.
    height : float, optional
        Thickness of the calibration block (m); default (None) ``depth + FLOOR_M`` (3.036 mm
        for the default plan). Paper 000 gives no size of its workpiece, and the ramps are
        this plan's (the paper gives only the tool angles); a thickness not above `depth`
        is refused: the ramps would cut out through the block's bottom.

    A field left None (search, clearance, spacing, height) is derived again in a copy:
    ``dataclasses.replace(plan, capture=...)`` gets the new capture's, a field given keeps
    its value. A copy cannot tell a derived value handed back by ``replace`` from one
    passed by hand, so a value another plan derived, passed on as it is
    (``CalibrationPlan(capture=0.5e-3, height=plan.height)``), is derived again too: pass
    ``float(plan.height)`` to keep it.
    """

    angles: tuple[float, ...] = tuple(math.radians(a) for a in (0, 10, 20, 30, 40))
    capture: float = 1.0 * M_PER_MM
    search: float | None = None
    slope: float = 0.1
    spacing: float | None = None
    station_depths: tuple[float, ...] = tuple((8 + k) * M_PER_UM + k * STATION_DITHER_M
                                              for k in range(9))
    origin: tuple[float, float] = (1.0 * M_PER_MM, 1.0 * M_PER_MM)
    tool_angle: float = math.pi / 2
    clearance: float | None = None
    feed_mm_per_min: float = 12000.0
    height: float | None = None

    def __post_init__(self) -> None:
        tool_angle = _tool(self)
        object.__setattr__(self, "angles", _angles(self.angles, tool_angle, "angles"))
        object.__setattr__(self, "station_depths", _numbers(
            self.station_depths, "station_depths", "groove depths (m)"))
        if min(self.station_depths) <= 0.0:
            raise InputError(f"Expected station_depths > 0 (m, below the surface), got "
                             f"{shown(self.station_depths)}", key="station_depths")
        object.__setattr__(self, "origin", _numbers(self.origin, "origin", "lengths (x, y) (m)",
                                                    size=2))
        capture = _number(self.capture, "capture")
        object.__setattr__(self, "capture", capture)
        for name in _DERIVED_FIELDS:  # derived from the fields a copy was made from: again
            if isinstance(getattr(self, name), _Derived):
                object.__setattr__(self, name, None)

        def derived(name, value, **checks):
            given = getattr(self, name)
            value = _Derived(value()) if given is None else _number(given, name, **checks)
            object.__setattr__(self, name, value)
            return value

        search = derived("search", lambda: capture + max(self.station_depths)
                         + SEARCH_MARGIN_M)
        object.__setattr__(self, "slope", _number(self.slope, "slope", unit="m per m of x"))
        clearance = derived("clearance", lambda: max(search + CLEARANCE_MARGIN_M,
                                                     self.approach))
        derived("spacing", lambda: max(3.0 * M_PER_MM, self.min_spacing))
        if clearance <= search:
            raise InputError(f"Expected a clearance above the search range {search:g} m, "
                             f"got {clearance!r}", key="clearance")
        if clearance < self.approach:
            raise InputError(
                f"Expected a clearance at least {self.approach:g} m, the capture range "
                f"{capture:g} m and {APPROACH_MARGIN_M:g} m (an edge offset within the capture "
                f"sinks the edge by up to that much at any angle, and the rapids cross the "
                f"block at the clearance), got {clearance!r} m", key="clearance")
        height = derived("height", lambda: self.depth + FLOOR_M, refusal=(
            f"Expected height, the calibration block's thickness, as a finite number of m "
            f"(default None: {self.depth + FLOOR_M:g} m)"))
        if not height > self.depth:
            raise InputError(
                f"Expected the calibration block's thickness height above the ramps' deepest "
                f"cut {self.depth:g} m (the ramps end {self.search:g} m below its top, and an "
                f"edge offset within the capture range {capture:g} m cuts up to that much "
                f"lower), got {height!r} m: the ramps would cut out through the block's "
                "bottom", key="height")

    @property
    def depth(self) -> float:
        """Deepest (m) the ramps may cut below the block's top: their programmed end,
        ``search`` down, and ``capture`` lower again for an edge offset within the capture
        range (at any angle the edge's height error is the offset turned by it). 2.036 mm
        for the default plan."""
        return self.search + self.capture

    @property
    def approach(self) -> float:
        """Height (m) of the programmed edge over the block's top down to which a rapid
        comes over the block: ``capture + APPROACH_MARGIN_M``. An edge offset within the
        capture range sinks the edge by up to ``capture`` at any angle, so the real edge
        stays `APPROACH_MARGIN_M` over the top. A ramp starts lower (``search`` up: capture
        + 36 um by default, and its climb out ends there), so the program feeds between it
        and here: a rapid down to it, and the retract up from its end, came within 36 um of
        the top for an offset at the capture's edge, whatever the capture. 1.1 mm for the
        default plan."""
        return self.capture + APPROACH_MARGIN_M

    @property
    def window(self) -> float:
        """Half width (m) of the sections across Y that look for a ramp's groove: the search
        range (the groove's lateral offset is never beyond it) and 0.25 mm of land."""
        return self.search + 0.25 * M_PER_MM

    @property
    def min_spacing(self) -> float:
        """Least ramp spacing (m) that keeps each search window clear of the next groove.

        Where ramp k is searched and read (down to its deepest station), the next ramp's
        groove is deeper by at most the change of the edge's height between their angles,
        ``capture * 2 sin(dt / 2)`` (the offset vector turned by dt), plus the deepest
        station and `SEARCH_MARGIN_M`; its low flank, ``(pi - tool_angle) / 2 - t`` from the
        surface, spreads that depth sideways by 1 / tan of it. Add the window, the next
        groove's own lateral offset (up to ``capture``) and `SPACING_MARGIN_M`.
        """
        angles = sorted(self.angles)
        step = max((b - a for a, b in zip(angles[:-1], angles[1:], strict=True)), default=0.0)
        flank = (math.pi - self.tool_angle) / 2.0 - max(abs(a) for a in angles)
        depth = (2.0 * self.capture * math.sin(step / 2.0) + max(self.station_depths)
                 + SEARCH_MARGIN_M)
        return self.window + self.capture + depth / math.tan(flank) + SPACING_MARGIN_M

    def reach(self, k: int) -> tuple[float, float]:
        """How far (m) ramp ``k``'s groove may reach towards -y and towards +y of the ramp's
        start (its programmed edge's y there), for any edge offset within the capture range.

        The deepest cut is the ramp's end (deeper, a V spreads faster than the tool's axis
        moves aside): the programmed edge ``search`` below the top and ``2 search tan t``
        towards +y, the offset (dy, dz) of length up to ``capture`` moving the apex. A flank
        ``phi`` from the surface (``(pi - tool_angle) / 2 -+ t`` on the -y / +y side) spreads
        ``search + dz`` by ``1 / tan phi``; the most of ``-+dy + dz / tan phi`` over the
        offsets is ``capture / sin phi``. The V is drawn to any depth: a real tool's shank,
        parallel to its axis, is steeper than its flanks and reaches less. The default
        plan's 0 deg ramp: 1.036 + 1.414 = 2.450 mm either side.
        """
        t = self.angles[k]
        shift = 2.0 * self.search * math.tan(t)
        ends = []
        for sign in (-1.0, 1.0):
            phi = (math.pi - self.tool_angle) / 2.0 + sign * t
            spread = (self.search / math.tan(phi) + self.capture / math.sin(phi)
                      if phi < math.pi / 2.0 else self.capture)  # overhung: the apex
            ends.append(spread + sign * shift)
        return ends[0], ends[1]

    @property
    def lead(self) -> float:
        """Distance (m) of the first ramp's start from the block's low-y edge, at least 1 mm:
        its search window and `SPACING_MARGIN_M` of land, so that a groove moved towards -y
        by up to the capture range lies on the block with land beside it, and room for
        every ramp's deepest cut (`reach`) with that land: 2.55 mm for the default plan,
        its 0 deg ramp's 2.45 mm reach and 0.1 mm."""
        room = max(self.reach(k)[0] - k * self.spacing for k in range(len(self.angles)))
        return max(1.0 * M_PER_MM, self.window + SPACING_MARGIN_M, room + SPACING_MARGIN_M)

    @property
    def width(self) -> float:
        """Width of the calibration block along Y (m): `lead`, then `spacing` per ramp or
        more where a ramp's deepest cut (`reach`) needs it, with `SPACING_MARGIN_M` of land."""
        tail = max(k * self.spacing + self.reach(k)[1] + SPACING_MARGIN_M
                   for k in range(len(self.angles)))
        return self.lead + max(len(self.angles) * self.spacing, tail)

    @property
    def ramp(self) -> tuple[float, float]:
        """x (m) where the ramps start (edge ``search`` above the surface) and end (below)."""
        x_a = self.origin[0] + 0.5 * M_PER_MM
        return x_a, x_a + 2.0 * self.search / self.slope

    def edge(self, k: int, x):
        """Programmed edge (y, z) (m) of ramp ``k`` at ``x``: down the tool's own axis."""
        x_a = self.ramp[0]
        z = self.search - self.slope * (np.asarray(x) - x_a)
        # Descending along the tilted tool's axis keeps the move in the tool's X-Z plane: the
        # edge cuts forward, never dragged sideways.
        y = self.origin[1] + self.lead + k * self.spacing + (self.search - z) * math.tan(
            self.angles[k])
        return y, z

    @property
    def length(self) -> float:
        """Length of the calibration block along X (m): the ramps, their climb out, 1 mm."""
        return self.ramp[1] - self.origin[0] + 2.0 * self.search + 1.0 * M_PER_MM

    @property
    def stock(self) -> str:
        """Stock spec of the calibration block (mm)."""
        width = self.width / M_PER_MM
        return (f"block:{self.length / M_PER_MM:.6g}x{width:.6g}x{self.height / M_PER_MM:.12g}"
                f"@{self.origin[0] / M_PER_MM:.6g},{self.origin[1] / M_PER_MM:.6g},0")

    def program(self, r0: float, number: int = 1) -> Program:
        """The calibration program for the nominal arm radius ``r0`` (m)."""
        x_a, x_b = self.ramp
        # each ramp leaves the stock climbing the tool axis back at slope 1
        grooves = [(angle, [(x_a, *self.edge(k, x_a)), (x_b, *self.edge(k, x_b)),
                            (x_b + 2.0 * self.search, *self.edge(k, x_a))])
                   for k, angle in enumerate(self.angles)]
        return _groove_program(r0, self.clearance, self.origin[0] - 0.5 * M_PER_MM, grooves,
                               self.feed_mm_per_min, number, approach=self.approach)


@dataclass(frozen=True)
class PrismPattern:
    """The angle-variable prism pattern (paper 000: 0-20 deg by 1 deg, 10 um deep, 20 um pitch).

    Grooves along +X across the whole stock, one per angle, at increasing Y.

    Attributes
    ----------
    angles : tuple of float
        Tool angle of each groove (rad).
    depth, pitch : float
        Programmed apex depth below the surface and groove spacing (m).
    length, margin : float
        Stock length along X, and uncut land either side of the pattern along Y (m).
    origin : (float, float)
        Corner (x, y) of the stock (m).
    tool_angle, clearance, feed_mm_per_min : float
        As in `CalibrationPlan`.
    height : float
        Thickness of the pattern's block (m), 0.5 mm by default; a `depth` at or beyond it
        is refused (the grooves would cut through the block's bottom).
    """

    angles: tuple[float, ...] = tuple(math.radians(a) for a in range(21))
    depth: float = 10.0 * M_PER_UM
    pitch: float = 20.0 * M_PER_UM
    length: float = 1.0 * M_PER_MM
    margin: float = 0.3 * M_PER_MM
    origin: tuple[float, float] = (1.0 * M_PER_MM, 1.0 * M_PER_MM)
    tool_angle: float = math.pi / 2
    clearance: float = 1.0 * M_PER_MM
    feed_mm_per_min: float = 12000.0
    height: float = 0.5 * M_PER_MM

    def __post_init__(self) -> None:
        tool_angle = _tool(self)
        object.__setattr__(self, "angles", _angles(self.angles, tool_angle, "angles"))
        object.__setattr__(self, "origin", _numbers(self.origin, "origin", "lengths (x, y) (m)",
                                                    size=2))
        for name in ("depth", "pitch", "length", "margin", "height", "clearance"):
            object.__setattr__(self, name, _number(getattr(self, name), name))
        if self.depth >= self.height:
            raise InputError(
                f"Expected the pattern's depth below the thickness of its block, "
                f"height {self.height:g} m, got depth {self.depth:g} m: the grooves would cut "
                "through the block's bottom; give a shallower depth or a thicker "
                "PrismPattern(height=...)", key="depth")

    @property
    def centres(self) -> np.ndarray:
        """Programmed edge y of each groove (m), shape (n,)."""
        return self.origin[1] + self.margin + self.pitch * np.arange(len(self.angles))

    @property
    def width(self) -> float:
        """Stock width along Y (m)."""
        return 2.0 * self.margin + self.pitch * (len(self.angles) - 1)

    @property
    def stock(self) -> str:
        """Stock spec of the pattern block (mm)."""
        return (f"block:{self.length / M_PER_MM:.9g}x{self.width / M_PER_MM:.9g}"
                f"x{self.height / M_PER_MM:.12g}"
                f"@{self.origin[0] / M_PER_MM:.9g},{self.origin[1] / M_PER_MM:.9g},0")

    def program(self, r0: float, number: int = 2) -> Program:
        """The nominal pattern program for the arm radius ``r0`` (m), to be compensated
        (`machinesim.procedures.tool_rotation_arm.compensate_program`)."""
        x_in = self.origin[0] - 0.2 * M_PER_MM
        x_out = self.origin[0] + self.length + 0.2 * M_PER_MM
        grooves = [(angle, [(x_in, float(y), -self.depth), (x_out, float(y), -self.depth)])
                   for angle, y in zip(self.angles, self.centres, strict=True)]
        return _groove_program(r0, self.clearance, x_in, grooves, self.feed_mm_per_min, number)
