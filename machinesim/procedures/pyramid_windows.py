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

from dataclasses import dataclass

import numpy as np

from machinesim.cam.pyramids import PAPER_PLAN, PyramidPlan, pyramid_program
from machinesim.exceptions import InputError

__all__ = ["WINDOWS", "PyramidWindow", "cut_and_read", "read_window", "v_flanks"]

WINDOWS = ((0.0, 0.0), (-0.19, -0.19), (0.19, -0.19), (0.19, 0.19), (-0.19, 0.19))
"""Window centres on the 400 mm plate (workpiece frame, m): centre and four corners."""
STOCK = "block:400x400x5@-200,-200,0"
"""The 400 x 400 mm plate, top at z = 0, centred on the C axis."""
SPACING = 0.1e-6
"""Profile sample spacing, m."""


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


def v_flanks(s, z, centres, pitch: float, band=(0.1, 0.35)):
    """Fit each V groove near the given centres: (positions, bottoms, left, right).

    For each approximate centre the lowest sample within half a pitch is the groove's
    bottom estimate; each flank is the least-squares line through the samples between
    ``band[0]`` and ``band[1]`` pitches from it. ``left``/``right`` are (a, b) of
    ``z = a + b s``; positions and bottoms are the flanks' intersections.
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


def read_window(instrument, part, centre, plan: PyramidPlan = PAPER_PLAN,
                span: float = 0.3e-3) -> PyramidWindow:
    """Read one window (module docstring) with the white-light interferometer."""
    cx, cy = (float(v) for v in centre)
    p = plan.pitch
    k = np.arange(-int(round(0.3 * plan.window / p)), int(round(0.3 * plan.window / p)) + 1)
    nominal = k * p                                  # groove offsets read, inside the window
    half = nominal[-1] + 0.5 * p
    sets = []
    for along_x in (True, False):
        positions, ridges = [], []
        for shift in (-span, span, 0.0):
            # Along the other set's ridge (half a pitch off its grooves), across this set.
            if along_x:     # set 1 runs along X: profile along Y at fixed x
                x = cx + shift + 0.5 * p
                prof = instrument.profile(part, (x, cy - half), (x, cy + half), SPACING)
                base = cy - half
            else:
                y = cy + shift + 0.5 * p
                prof = instrument.profile(part, (cx - half, y), (cx + half, y), SPACING)
                base = cx - half
            pos, _, lefts, rights = v_flanks(prof.s, prof.z, nominal + half, p)
            positions.append(pos + base)
            ridges.append(_ridges(lefts, rights))
        slope = np.mean((positions[1] - positions[0]) / (2.0 * span))
        sets.append((positions[2], ridges[2], slope))
    (pos1, r1, m1), (pos2, r2, m2) = sets
    apex = np.minimum(r1[:, None], r2[None, :])
    pitch = float(np.mean(np.concatenate([np.diff(pos1), np.diff(pos2)])))
    return PyramidWindow((cx, cy), apex, pitch, float(-(m1 + m2)))


def cut_and_read(lab, compensation=None, plan: PyramidPlan = PAPER_PLAN,
                 windows=WINDOWS, label: str = "pyramids"):
    """Cut the pattern in every window (compensated by ``compensation.program`` when given)
    and read it; returns the list of `PyramidWindow` and the programs."""
    wli = lab.white_light_interferometer(label=label)
    out, programs = [], []
    for centre in windows:
        program = pyramid_program(lab.machine, centre, plan)
        if compensation is not None:
            program = compensation.program(program)
        cx, cy = centre
        roi = [(cx - 0.5 * plan.window, cx + 0.5 * plan.window,
                cy - 0.5 * plan.window, cy + 0.5 * plan.window)]
        part, _ = lab.cut(program, "v:90", STOCK, roi=roi)
        out.append(read_window(wli, part, centre, plan))
        programs.append(program)
    return out, programs
