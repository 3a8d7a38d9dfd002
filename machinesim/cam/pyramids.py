"""Pyramid patterns across a plate (paper 003 section IV): two sets of V grooves crossed by
turning the workpiece 90 deg on C.

The first set is grooved along X (C = 0), C turns the workpiece 90 deg, and the same set is
grooved again along X, now across the first (paper 003: "the triangular prism pattern is
grooved firstly along X axis then patterned material is rotated 90 deg by C axis and same
triangular prism is grooved cross of the previous pattern"). With a 90-deg V tool, 50 um
pitch and 25 um depth the flanks of neighbouring grooves meet in sharp ridges at the top
surface, and the two sets leave square pyramids 25 um high.

Only the grooves that reach a measuring window are programmed (a window of 1 x 1 mm on a
400 x 400 mm plate), each one long stroke of X across the window and a margin. Positions are
placed on the nominal machine (`workpiece_axes`); the program carries no compensation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology._arrays import as_floats, as_number, shown
from machinesim.nc import ProgramBuilder
from machinesim.nc.program import Program

__all__ = ["MAX_GROOVES", "PAPER_PLAN", "PyramidPlan", "pyramid_program", "workpiece_axes"]

#: Most grooves a `PyramidPlan` may program (both sets): the paper's plan has 50; a pitch of
#: 1e-12 m (a value in another unit) asked for 2.4 * 10^9, 9.6 GB of `offsets`.
MAX_GROOVES = 10**6


@dataclass(frozen=True)
class PyramidPlan:
    """Pyramid pattern parameters (SI).

    Attributes
    ----------
    pitch : float
        Groove spacing, m (paper 003: 50 um).
    depth : float
        Groove depth below the plate's top, m (25 um: the 90-deg flanks meet at the top).
    window : float
        Side of the square measuring window, m (1 mm).
    margin : float
        Extra groove length and extra grooves beyond the window, m.
    clearance : float
        Tool height over the top for rapids, m.
    feed_mm_per_min : float
    """

    pitch: float = 50e-6
    depth: float = 25e-6
    window: float = 1e-3
    margin: float = 0.1e-3
    clearance: float = 0.5e-3
    feed_mm_per_min: float = 2000.0

    def __post_init__(self) -> None:
        # as_number: True is no 1 m (it was taken), np.float32(5e-5) a pitch (it was refused)
        for name in ("pitch", "depth", "window", "margin", "clearance", "feed_mm_per_min"):
            unit = "mm/min" if name == "feed_mm_per_min" else "m"
            object.__setattr__(self, name, as_number(getattr(self, name), name, sign="> 0",
                                                     unit=unit))
        grooves = 2.0 * (2.0 * math.ceil((0.5 * self.window + self.margin) / self.pitch) + 1.0)
        if not grooves <= MAX_GROOVES:
            raise InputError(f"Expected at most {MAX_GROOVES:.0e} grooves (MAX_GROOVES), got "
                             f"{grooves:.4g} from pitch {self.pitch!r} m over the window "
                             f"{self.window!r} m and margin {self.margin!r} m: a value in "
                             "another unit?", key="pitch")

    def offsets(self) -> np.ndarray:
        """Groove centre offsets from the window centre, m (symmetric, whole pitches)."""
        # a reach a whole number of pitches up to round-off (or a float32 pitch's 3e-8) is
        # that number: ceil(12.0000003) added a groove either side beyond the margin
        n = int(math.ceil((0.5 * self.window + self.margin) / self.pitch * (1.0 - 1e-6)))
        return self.pitch * np.arange(-n, n + 1, dtype=np.float64)


PAPER_PLAN = PyramidPlan()
"""Paper 003's pattern: 50 um pitch, 25 um deep, in 1 x 1 mm windows."""


def workpiece_axes(machine, x: float, y: float, c: float, z: float = 0.0) -> np.ndarray:
    """X and Y that put the nominal tool tip over workpiece point (x, y) with C at ``c``."""
    n = len(machine.axes)
    missing = [a for a in "XYZC" if a not in machine.axes]
    if missing:  # sts_lathe (XZC): 'tuple.index(x): x not in tuple'
        raise InputError(f"Expected a machine with X, Y, Z and C axes, got {machine.name} "
                         f"({''.join(machine.axes)}), without {', '.join(missing)}",
                         key="machine")
    ix, iy, iz, ic = (machine.axes.index(a) for a in "XYZC")
    q = np.zeros(n)
    q[iz], q[ic] = z, c
    p0 = machine.tool_pose(q)[:3, 3]
    columns = []
    for k in (ix, iy):
        dq = q.copy()
        dq[k] += 1e-3
        columns.append((machine.tool_pose(dq)[:3, 3] - p0) / 1e-3)
    jac = np.stack(columns, axis=1)[:2]         # affine in X and Y on the nominal machine
    return np.linalg.solve(jac, np.array([x, y]) - p0[:2])


def pyramid_program(machine, centre, plan: PyramidPlan = PAPER_PLAN,
                    number: int = 3003) -> Program:
    """The two groove sets over the window centred at workpiece point ``centre`` (m, 2
    numbers), on ``machine`` (a `Machine` with X, Y, Z and C axes, or its name).

    Each groove: a rapid over its start at ``plan.clearance``, a feed down to ``-depth``
    and along X across the window and its margins, a rapid up; C turns at the clearance.
    """
    # a centre of 3 numbers, text or one number was Python's ValueError or TypeError, and a
    # plan that is no PyramidPlan an AttributeError ('int' object has no attribute 'window')
    from machinesim.metrology.instruments import as_machine

    machine = as_machine(machine)  # a name was 'str' object has no attribute 'axes'
    if not isinstance(plan, PyramidPlan):
        raise InputError(f"Expected plan as a PyramidPlan, got {type(plan).__name__}",
                         key="plan")
    point = as_floats(centre, "centre", "2 numbers (m): the window's centre x, y")
    if point.shape != (2,) or not np.isfinite(point).all():
        raise InputError(f"Expected centre as 2 finite numbers (m), the window's centre x, y "
                         f"on the workpiece, got {shown(centre)}", key="centre")
    cx, cy = (float(v) for v in point)
    half = 0.5 * plan.window + plan.margin
    b = ProgramBuilder(number)
    z_cut = -plan.depth
    for c in (0.0, 0.5 * math.pi):
        b.rapid(Z=plan.clearance).rapid(C=c)
        for off in plan.offsets():
            if c == 0.0:       # set 1: along the workpiece's X
                start, end = (cx - half, cy + off), (cx + half, cy + off)
            else:              # set 2: along the workpiece's Y, cut by X after C turned
                start, end = (cx + off, cy - half), (cx + off, cy + half)
            a = workpiece_axes(machine, *start, c)
            e = workpiece_axes(machine, *end, c)
            # down into the plate at the feed: a rapid plunge there cut the plate at G00
            # (every groove's start, `CutReport.rapids_that_cut`)
            b.rapid(X=float(a[0]), Y=float(a[1]))
            b.linear(Z=z_cut, feed_mm_per_min=plan.feed_mm_per_min)
            b.linear(X=float(e[0]), Y=float(e[1]), feed_mm_per_min=plan.feed_mm_per_min)
            b.rapid(Z=plan.clearance)
    return b.build()
