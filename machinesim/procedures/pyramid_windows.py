"""Pyramids cut in measuring windows across the plate and read with the white-light
interferometer (paper 003 section IV; issue 14 item 5).

Each window (1 x 1 mm; the plate's centre and four corners) gets the two groove sets of
`machinesim.cam.pyramids`. The white-light interferometer reads profiles across each set
along the other set's ridges; each groove's two flanks are fitted by straight lines on their
lower part (away from the ridges, where the other set may clip them), which gives:

- the groove's bottom (the flanks' intersection) and its position across the set;
- each ridge's height: the intersection of the facing flanks of neighbouring grooves (for
  flanks at +-45 deg and bottoms z1, z2 at positions c1, c2 it is (z1 + z2 + c2 - c1) / 2);
- a pyramid's apex: the lower of the two ridges that cross there, ``min(r1_i, r2_j)``;
- the pitch: the mean spacing of the groove positions;
- the angle between the sets: each set's direction from its groove positions on two
  profiles 0.6 mm apart, slopes m1 (set 1, dy/dx) and m2 (set 2, dx/dy); to first order
  the angle between the sets is 90 deg - (m1 + m2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.cam.pyramids import PAPER_PLAN, PyramidPlan, pyramid_program, workpiece_axes
from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_number

__all__ = ["PLATE_TOP", "UNCUT_BAND", "UNCUT_BAND_REGISTERED", "WINDOWS", "PyramidWindow",
           "capture", "cut_and_read", "path_errors", "rapid_reach", "read_window", "uncut_note",
           "v_flanks"]

WINDOWS = ((0.0, 0.0), (-0.19, -0.19), (0.19, -0.19), (0.19, 0.19), (-0.19, 0.19))
"""Window centres on the 400 mm plate (workpiece frame, m): centre and four corners."""
STOCK = "block:400x400x5@-200,-200,0"
"""The 400 x 400 mm plate, top at z = 0, centred on the C axis."""
STOCK_XY = (-0.2, 0.2)
"""`STOCK`'s extent in x and in y, m: a window's square must lie within it."""
SPACING = 0.1e-6
"""Profile sample spacing, m."""
PLATE_TOP = 0.0
"""`STOCK`'s top, m: the plan's grooves are half their pitch deep, so the ridges of a pattern
cut as programmed meet at it."""
UNCUT_BAND = 20e-9
"""An apex read more than this (m) above the plate's top was not cut to a point: its flanks
cross in the air over a flat of the uncut top (`PyramidWindow.uncut`); about eight times the
2.6 nm scatter of the crossings in the lab realism. For an instrument that reads in the
part's frame (no stated registration)."""
UNCUT_BAND_REGISTERED = 0.5e-6
"""The same (m) against the window's highest sample, for an instrument whose heights carry a
registration (its stated `registration_scatter`: a height zero and tilt of its own, tens of
um between windows): a flat of uncut top reads there, and a ridge cut to a point reads its
highest sample up to 0.36 um below the crossing with the lab's spot, lateral noise and stage
(seeds 0 and 11), the profile running up to that far beside the other set's ridge."""

@dataclass(frozen=True, eq=False)
class PyramidWindow:
    """What one window's profiles gave (m, rad).

    Attributes
    ----------
    centre : tuple
        The window's centre, m.
    apex : ndarray (i, j)
        Pyramid apex heights, ``min(ridge1_i, ridge2_j)``.
    pitch : float
        Mean groove spacing of both sets.
    angle_error : float
        Angle between the two sets minus 90 deg.
    """

    centre: tuple
    apex: np.ndarray
    pitch: float
    angle_error: float
    top: float = PLATE_TOP
    top_band: float = UNCUT_BAND

    @property
    def uncut(self) -> int:
        """How many apexes read more than ``top_band`` above ``top``, the plate's top (the
        window's highest sample for a registered instrument, `UNCUT_BAND_REGISTERED`): there
        the tool did not reach the plan's depth, the ridges stand as flats of the plate's
        top, and the apex read is where the flanks would cross, in the air over the part."""
        return int(np.sum(self.apex > self.top + self.top_band))


def uncut_note(windows, state: str) -> str:
    """What a reader of the pyramid figures must know when some ``windows`` (`PyramidWindow`,
    in `WINDOWS`' order) were not cut to a point (`PyramidWindow.uncut`): each such window,
    how many apexes and how far above the plate's top, and the range of the part's own
    apexes (each at most the plate's top). Empty when every apex was cut."""
    parts = [f"window {k} ({round(w.centre[0] * 1e3)}, {round(w.centre[1] * 1e3)}) mm: {w.uncut} "
             f"of {w.apex.size} apexes up to {(w.apex.max() - w.top) * 1e6:.3g} um"
             for k, w in enumerate(windows, start=1) if w.uncut]
    if not parts:
        return ""
    real = np.concatenate([np.minimum(w.apex, w.top).ravel() for w in windows])
    return (f"{state}: {'; '.join(parts)} above the plate's top, uncut (the tool tip above "
            "the program there: tool.z, C's tilt?): there the ridges stand flat at the top "
            "and the apex read is where the flanks cross, in the air; the part's own apexes "
            f"(at most the top) range {np.ptp(real) * 1e6:.3f} um")


#: Sample spacing of the profiles that find a window's edges, m.
LOCATE = 2e-6


#: Flank slopes |dz/ds| a fitted V groove must have: 0.3 .. 3 (17 .. 72 deg), about the 1
#: of a 90 deg V tool read square across its grooves (`v_flanks`).
FLANK_SLOPES = (0.3, 3.0)
#: Where a groove's flanks are fitted (`v_flanks`): from 0.1 to 0.35 pitch from its bottom.
FLANK_BAND = (0.1, 0.35)


def v_flanks(s, z, centres, pitch: float, band=FLANK_BAND):
    """Fit each V groove near the given centres: (positions, bottoms, left, right).

    For each approximate centre the lowest sample within half a pitch is the groove's
    bottom estimate; each flank is the least-squares line through the samples between
    ``band[0]`` and ``band[1]`` pitches from it. ``left``/``right`` are (a, b) of
    ``z = a + b s``; positions and bottoms are the flanks' intersections. A groove whose
    flanks do not fall to its bottom at `FLANK_SLOPES` (a flat, a groove of the other set
    along the profile, or none) is refused: its "position" would be noise.
    """
    s = np.asarray(s, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    ok = np.isfinite(z)
    s, z = s[ok], z[ok]
    pos, bottom, lefts, rights = [], [], [], []
    for c in centres:
        near = np.abs(s - c) < 0.5 * pitch
        if near.sum() < 10:
            raise InputError(f"Expected profile samples around the groove at {c} m",
                             key="centres")
        low = s[near][np.argmin(z[near])]
        lines = []
        for sign in (-1.0, 1.0):
            d = sign * (s - low)
            pick = (d > band[0] * pitch) & (d < band[1] * pitch)
            if pick.sum() < 5:
                raise InputError(f"Expected flank samples beside the groove at {c} m",
                                 key="centres")
            b, a = np.polyfit(s[pick], z[pick], 1)
            lines.append((a, b))
        (a1, b1), (a2, b2) = lines
        lo, hi = FLANK_SLOPES
        if not (lo <= -b1 <= hi and lo <= b2 <= hi):
            raise InputError(f"Expected a V groove near {c * 1e3:.4f} mm along the profile: "
                             f"its flanks fall at slopes {-b1:.3g} and {b2:.3g} to its "
                             f"lowest point, not {lo:g} .. {hi:g}: no groove of the plan is "
                             "there (cut elsewhere, or not at all)", key="centres")
        sc = (a2 - a1) / (b1 - b2)
        pos.append(sc)
        bottom.append(a1 + b1 * sc)
        lefts.append(lines[0])
        rights.append(lines[1])
    return np.array(pos), np.array(bottom), lefts, rights


def _ridges(lefts, rights) -> np.ndarray:
    """Heights where each groove's right flank meets the next groove's left flank."""
    out = []
    for (a_r, b_r), (a_l, b_l) in zip(rights[:-1], lefts[1:], strict=True):
        s = (a_l - a_r) / (b_r - b_l)
        out.append(a_r + b_r * s)
    return np.array(out)


def groove_phase(s, z, pitch: float) -> float:
    """Where a profile's grooves are, modulo the pitch: the position of the bottoms of the
    fundamental of the periodic pattern (m, in [0, pitch)).

    A V-groove pattern is a triangle wave whose fundamental, ``-A cos(2 pi (s - s0) / p)``,
    has its minima at the groove bottoms ``s0 + k p``; its phase is the angle of the
    profile's Fourier coefficient at ``1 / p``. Used to find the grooves where the
    instrument's registration (its stage) put them, not where they were designed.
    """
    s = np.asarray(s, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    ok = np.isfinite(z)
    s, z = s[ok], z[ok]
    if s.size < 3 or s[-1] - s[0] < pitch:
        # the fundamental needs a whole period read: the phase of fewer samples (or of none:
        # NaN's mean, a zero coefficient) is a number that says nothing
        raise InputError(f"Expected a profile read over at least one pitch ({pitch:g} m) to "
                         f"find its grooves, got {s.size} samples read"
                         + (f" over {s[-1] - s[0]:g} m" if s.size else "")
                         + " (the rest off the part)", key="z")
    c = np.sum((z - z.mean()) * np.exp(-2j * np.pi * s / pitch))
    return float((-np.angle(-c) * pitch / (2.0 * np.pi)) % pitch)


def locate_window(instrument, part, centre, window: float) -> tuple[float, float]:
    """The centre of a cut window as the instrument sees it: the middle of the surface it
    finds on a profile along X and one along Y through the designed ``centre``, each
    reaching a window's width beyond the window (the part is the window alone, `cut_and_read`
    cuts it with ``roi``)."""
    cx, cy = (float(v) for v in centre)
    found = []
    for along_x in (True, False):
        if along_x:
            prof = instrument.profile(part, (cx - window, cy), (cx + window, cy), LOCATE)
        else:
            prof = instrument.profile(part, (cx, cy - window), (cx, cy + window), LOCATE)
        seen = prof.s[np.isfinite(prof.z)]
        if seen.size < 2:
            raise InputError(f"Found no surface within {window * 1e3:g} mm of the window "
                             f"at ({cx * 1e3:g}, {cy * 1e3:g}) mm", key="centre")
        found.append((cx if along_x else cy) - window + 0.5 * (seen.min() + seen.max()))
    return found[0], found[1]


def read_window(instrument, part, centre, plan: PyramidPlan = PAPER_PLAN,
                span: float = 0.3e-3) -> PyramidWindow:
    """Read one window (module docstring) with the white-light interferometer.

    A registered instrument (``Realism.registration``) sees the window off its design, by
    micrometres at the plate's centre and by a few tenths of a millimetre at its corners (a
    stage's rotation of ~1 mrad over 190 mm), so the window is first found as labs find it:
    its edges on two profiles through the designed centre (`locate_window`). The window is
    then read in one field (one placement of the stage): each set's grooves located on a
    profile across it (`groove_phase`), then each set read on profiles along the other
    set's ridges as found, at the centre and either side.
    """
    cx, cy = locate_window(instrument, part, centre, plan.window)
    p = plan.pitch
    nominal, half = _read_span(plan)
    with instrument.placement():  # one field of view holds the window's profiles
        # where each set's grooves are (the stage put the field off its command): first a
        # profile across each, then each set read along the other set's ridges
        phase = [_groove_offset(instrument, part, cx, cy, along_x, half, p)
                 for along_x in (True, False)]
        sets = [_read_set(instrument, part, cx, cy, along_x, nominal, half, p, span,
                          phase[0], phase[1]) for along_x in (True, False)]
    (pos1, r1, m1, top1), (pos2, r2, m2, top2) = sets
    apex = np.minimum(r1[:, None], r2[None, :])
    pitch = float(np.mean(np.concatenate([np.diff(pos1), np.diff(pos2)])))
    # the plate's top, against which an apex read above it was not cut to a point: where
    # the instrument reads in the part's frame, the stock's; else its own highest sample
    top = ((PLATE_TOP, UNCUT_BAND) if getattr(instrument, "registration_scatter", None) is None
           else (max(top1, top2), UNCUT_BAND_REGISTERED))
    return PyramidWindow((cx, cy), apex, pitch, float(-(m1 + m2)), *top)


def _across(instrument, part, cx, cy, along_x, half, at):
    """A profile across one set (``along_x``: the set running along X, read along Y at
    x = ``at``; else along X at y = ``at``)."""
    if along_x:
        return instrument.profile(part, (at, cy - half), (at, cy + half), SPACING)
    return instrument.profile(part, (cx - half, at), (cx + half, at), SPACING)


def _groove_offset(instrument, part, cx, cy, along_x, half, p) -> float:
    """How far a set's grooves sit from their design across the set, within half a pitch."""
    prof = _across(instrument, part, cx, cy, along_x, half, (cx if along_x else cy) + 0.25 * p)
    found = groove_phase(prof.s, prof.z, p)
    return (found - half + 0.5 * p) % p - 0.5 * p


def _read_set(instrument, part, cx, cy, along_x, nominal, half, p, span, offset_1, offset_2):
    """One groove set of a window: positions and ridge heights on the centre profile, the
    grooves' slope from the profiles either side, and the centre profile's highest sample,
    all along the other set's ridges
    (half a pitch off its grooves as found: ``offset_1``, ``offset_2`` of sets 1 and 2)."""
    offset, other = (offset_1, offset_2) if along_x else (offset_2, offset_1)
    centre = (cx if along_x else cy) + other + 0.5 * p
    profiles = {shift: _across(instrument, part, cx, cy, along_x, half, centre + shift)
                for shift in (0.0, -span, span)}
    base = (cy if along_x else cx) - half
    positions, ridges = {}, {}
    for shift, prof in profiles.items():
        try:
            pos, _, lefts, rights = v_flanks(prof.s, prof.z, nominal + half + offset, p)
        except InputError as error:
            which = "along X" if along_x else "along Y"
            raise InputError(f"the groove set {which}: {error}",
                             key=f"pyramid window at ({cx * 1e3:.3f}, {cy * 1e3:.3f}) mm") \
                from None
        positions[shift] = pos + base
        ridges[shift] = _ridges(lefts, rights)
    slope = np.mean((positions[span] - positions[-span]) / (2.0 * span))
    # the highest the centre profile reads: along the other set's ridge it runs over every
    # pyramid's top, the plate's own where a ridge was not cut to a point
    return positions[0.0], ridges[0.0], slope, float(np.nanmax(profiles[0.0].z))


def _read_span(plan: PyramidPlan) -> tuple[np.ndarray, float]:
    """The groove offsets read in a window (whole pitches within 0.3 window of its centre)
    and the half length of the profiles across a set, m."""
    n = int(round(0.3 * plan.window / plan.pitch))
    nominal = plan.pitch * np.arange(-n, n + 1)
    return nominal, float(nominal[-1] + 1.5 * plan.pitch)


def capture(plan: PyramidPlan = PAPER_PLAN) -> tuple[float, float]:
    """How far (m) the tool tip may cut off its programmed path for a window to be read
    right: (across or along the grooves, in x and in y each; above the path).

    In the plane: the pattern overruns the window by ``plan.margin`` and the profiles reach
    `_read_span` from its centre, with half a pitch to find a groove: for the paper's plan
    0.5 + 0.1 - 0.375 - 0.025 = 0.2 mm. Beyond, a profile finds no groove where it looks.
    Above: a groove cut that much shallower than ``plan.depth`` still has flank where
    `v_flanks` fits it (up to ``FLANK_BAND[1]`` pitch from its bottom): 25 - 17.5 = 7.5 um.
    Beyond, the fit takes in the plate's uncut top between the grooves, and the apexes read
    low without a word (a tool 10 um high read 8.3 um). Below, nothing limits the reading;
    the program's rapids do (`rapid_reach`).
    """
    _, half = _read_span(plan)
    return (0.5 * plan.window + plan.margin - half - 0.5 * plan.pitch,
            plan.depth - FLANK_BAND[1] * plan.pitch)


def rapid_reach(plan: PyramidPlan = PAPER_PLAN) -> float:
    """How far (m) the tool tip may cut below its programmed path before the program's
    rapids, run ``plan.clearance`` over the plate's top, run into the plate: a crash (the
    cut lists them, `CutReport.rapids_that_cut`, and from about 0.7 mm low each window's
    boolean of the rapids' sweeps took minutes, where it takes 0.2 s: 0.9 mm low did not
    end in 60 s, a run 1 mm low not in 7 min). Set against `path_errors` before anything
    is cut, as `capture` is."""
    return plan.clearance


def path_errors(machine, errors, plan: PyramidPlan = PAPER_PLAN, windows=WINDOWS):
    """Where the tool tip cuts off its programmed path at the ends of each window's outer
    grooves (both sets), by ``machine``'s kinematics with ``errors``: (axis values (N,
    n_axes), tool-tip error (N, 3) in the workpiece frame, m). Set against `capture` before
    anything is cut."""
    n = len(machine.axes)
    half = 0.5 * plan.window + plan.margin
    edge = float(plan.offsets()[-1])
    q = []
    for cx, cy in windows:
        for c in (0.0, 0.5 * math.pi):
            for along, across in ((-half, -edge), (-half, edge), (half, -edge), (half, edge)):
                point = (cx + along, cy + across) if c == 0.0 else (cx + across, cy + along)
                xy = workpiece_axes(machine, *point, c)
                row = np.zeros(n)
                for letter, value in zip("XYZC", (xy[0], xy[1], -plan.depth, c), strict=True):
                    row[machine.axes.index(letter)] = value
                q.append(row)
    q = np.array(q)
    return q, machine.tool_pose(q, errors)[:, :3, 3] - machine.tool_pose(q)[:, :3, 3]


def cut_and_read(lab, compensation=None, plan: PyramidPlan = PAPER_PLAN,
                 windows=WINDOWS, label: str = "pyramids"):
    """Cut the pattern in every window (compensated by ``compensation.program`` when given)
    and read it; returns the list of `PyramidWindow` and, per window, the program and the
    part as cut (the window alone)."""
    windows = _check_windows(windows, plan)
    wli = lab.white_light_interferometer(label=label)
    out, cuts = [], []
    for centre in windows:
        program = pyramid_program(lab.machine, centre, plan)
        if compensation is not None:
            program = compensation.program(program)
        cx, cy = centre
        roi = [(cx - 0.5 * plan.window, cx + 0.5 * plan.window,
                cy - 0.5 * plan.window, cy + 0.5 * plan.window)]
        part, _ = lab.cut(program, "v:90", STOCK, roi=roi)
        out.append(read_window(wli, part, centre, plan))
        cuts.append((program, part))
    return out, cuts


def _check_windows(windows, plan: PyramidPlan) -> list[tuple[float, float]]:
    """The window centres as (x, y) pairs of finite numbers (m) whose ``plan.window``
    squares lie on the plate (`STOCK_XY`). A window over its edge was refused, if at all,
    only after its cut and by the reading ('the groove set along X: key 'centres': Expected
    flank samples ...', 'the profile ... misses the part'), and a centre of one number
    raised a bare ValueError."""
    half, (low, high) = 0.5 * plan.window, STOCK_XY
    out = []
    for centre in windows:
        try:  # numbers as every length is taken (as_number): no str, no bool
            cx, cy = (as_number(c, "windows") for c in centre)
        except (TypeError, ValueError, InputError):
            cx = cy = math.nan
        if not (math.isfinite(cx) and math.isfinite(cy)):
            raise InputError(f"Expected each window centre as (x, y), two finite numbers in m, "
                             f"got {centre!r}", key="windows")
        if not (low + half <= cx <= high - half and low + half <= cy <= high - half):
            raise InputError(
                f"the {plan.window * 1e3:g} mm window at ({cx * 1e3:g}, {cy * 1e3:g}) mm runs "
                f"off the plate ({low * 1e3:g} .. {high * 1e3:g} mm in x and y, {STOCK}); "
                f"expected its centre within {(high - half) * 1e3:g} mm of the plate's centre "
                "in x and y", key="windows")
        out.append((cx, cy))
    return out
