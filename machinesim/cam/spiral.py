"""Slow-tool-servo (STS) tool paths for freeform surfaces (paper 004, section 3.1).

Zhu, Takeuchi, et al., deterministic error compensation in STS turning
(`shared/seeds/004_3f9e6f9e74319d55.txt`); equation numbers are the paper's. The steps, as
a CAM system runs them for the ``sts_lathe`` (X Z C, C the work spindle; docs/machines.md):

1. a designed surface z(x, y) in the workpiece frame (`Design`, `machinesim.cam.designs`,
   re-exported here): the 2-D sine grid of eq 2
   (`sine_grid`), a sphere (`sphere`), any callable (`Design`), or a height map in memory or
   in a file (`design_from_height_map`, `read_design`);
2. an Archimedean spiral of pitch f (the feed per revolution) from the outer radius r to the
   centre (`Spiral`, eqs 3-6), and cutting points on it by Constant Angle or Constant Arc
   Length (`cutting_angles`, `constant_angle`, `constant_arc_length`), each with the designed
   height and its radial slope (`cutting_points`): `machinesim.cam.spiral_points`,
   re-exported here;
3. the tool tip for each point, compensated for the nose radius (`tool_path`, eqs 18-19);
4. the path between points: linear or cubic spline (`interpolate`, eqs 7-9), and the
   program-related form error that interpolation leaves, from the path alone
   (`program_error`, `program_error_table`: eqs 10-11 and Fig. 11);
5. the X Z C program (`spiral_program`; write it with `machinesim.nc.write_program`).

Geometry. On ``sts_lathe`` the tool tip sits in the workpiece frame at (X cos C, X sin C, Z)
(`Machine.tool_pose`): C is the polar angle theta of the point being cut and X its radius.
The spiral starts at theta = 0 on the outer radius and winds in as C grows, rho(theta) =
r - f theta / (2 pi) (eq 4 as it must read; the printed "rho = r - f_r r" is garbled). The
machine interpolates linear moves linearly in X, Z and C, so between two points the tip
stays on the Archimedean spiral and Z is linear in C; the spline is taken in C as well (in
STS the slides are slaved to the spindle angle). Derivations, the garbled equations and the
forms used: docs/procedures/sts_turning.md.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from machinesim.arrays import frozen
from machinesim.cam.designs import (
    AMPLITUDE_M,
    WAVELENGTH_M,
    Design,
    design_from_height_map,
    radial_curvature,
    read_design,
    sine_grid,
    sphere,
    tilted_plane,
)
from machinesim.cam.spiral_points import (  # re-exported, and the checks a path shares
    MAX_PATH_POINTS,
    CuttingPoints,
    Spiral,
    _check_increasing,
    _check_points,
    _positive,
    constant_angle,
    constant_arc_length,
    cutting_angles,
    cutting_points,
)
from machinesim.exceptions import InputError, MachineSimWarning, check_length
from machinesim.metrology._arrays import as_floats, as_number
from machinesim.nc import AXES, KIND_LINEAR, KIND_RAPID, Program
from machinesim.units import M_PER_MM, M_PER_UM, RAD_PER_DEG

__all__ = [
    "AMPLITUDE_M", "CAL_STEP_M", "CA_STEP_RAD", "FEED_M", "MAX_PATH_POINTS", "MAX_SPINDLE_RPM",
    "NOSE_RADIUS_M",
    "PART_RADIUS_M",
    "SPINDLE_RPM", "WAVELENGTH_M", "CuttingPoints", "Design", "ProgramError", "Spiral",
    "ToolPath", "constant_angle", "constant_arc_length", "cutting_angles", "cutting_points",
    "design_from_height_map", "interpolate", "program_error", "program_error_table",
    "read_design", "sine_grid", "sphere", "spiral_program", "tilted_plane", "tool_path",
]

# --- the paper's conditions (Table 1, section 2.3, Table 4) ---------------------------------
#: Table 1: feed 2 um/rev, spindle 20 rpm.
FEED_M = 2 * M_PER_UM
SPINDLE_RPM = 20.0
#: Section 2.3: nose radius 1.0 mm (Table 1 prints 2 mm; the text's 1.0 mm is the one that
#: gives its "~130 nm" chip thickness by eq 1 at f = 2 um, a = 2.1 um: 128 nm, 2 mm gives 91).
NOSE_RADIUS_M = 1 * M_PER_MM
#: Radius of the turned area, not printed: 0.5 mm is the one for which Table 4's counts
#: follow from Figs. 9-10's spacings (CAL, 30 um: 13,090 steps; CA, 2 deg: 45,000 steps).
PART_RADIUS_M = 0.5 * M_PER_MM
#: Table 4 "after" (Case 3, 4): Constant Angle, 2 deg (45,000 cutting points).
CA_STEP_RAD = 2.0 * RAD_PER_DEG
#: Table 4 "before" (Case 1, 2): Constant Arc Length, 30 um (13,090 cutting points).
CAL_STEP_M = 30 * M_PER_UM

#: The fastest spindle a program is written for, rpm: the rapid rate of ``sts_lathe``'s C
#: (models/sts_lathe.urdf, ``<limit velocity="150.0">`` rad/s, 1432.39 rpm), the machine
#: `spiral_program` writes for. 1e300 rpm was taken (F 6e297 m/s).
MAX_SPINDLE_RPM = 150.0 * 60.0 / (2.0 * math.pi)


# --- tool path (eqs 18-19) and interpolation (eqs 7-9) -----------------------------------------
@dataclass(frozen=True)
class ToolPath:
    """Tool tip positions as ``sts_lathe`` axis values.

    Attributes
    ----------
    c : ndarray, shape (N,)
        C = theta, rad, increasing.
    x : ndarray, shape (N,)
        X, the tip's radius (may be negative near the centre), m.
    z : ndarray, shape (N,)
        Z, the tip height, m.
    """

    c: np.ndarray
    x: np.ndarray
    z: np.ndarray

    def __post_init__(self) -> None:
        # a path made by hand: each a finite float64 array, all of one length (a short X
        # was numpy's broadcast ValueError in spiral_program, a NaN a modal-axis refusal)
        arrays = [as_floats(getattr(self, name), f"path.{name}", "numbers (rad, m)")
                  for name in ("c", "x", "z")]
        if any(a.ndim != 1 for a in arrays) or len({a.size for a in arrays}) != 1:
            raise InputError(f"Expected path.c, path.x and path.z as 1-D arrays of one "
                             f"length, got shapes {', '.join(str(a.shape) for a in arrays)}",
                             key="path")
        for name, array in zip(("c", "x", "z"), arrays, strict=True):
            if not np.isfinite(array).all():
                raise InputError(f"Expected finite path.{name}, got a NaN or infinity at "
                                 f"index {int(np.flatnonzero(~np.isfinite(array))[0])}",
                                 key=f"path.{name}")
            object.__setattr__(self, name, frozen(array, copy=False))

    def tips(self) -> np.ndarray:
        """Tip positions in the workpiece frame, (X cos C, X sin C, Z), shape (N, 3), m."""
        return np.column_stack([self.x * np.cos(self.c), self.x * np.sin(self.c), self.z])

    def __len__(self) -> int:
        return self.c.size


def tool_path(points: CuttingPoints, nose_radius: float | None = None) -> ToolPath:
    """Tool tips for the cutting points, compensated for the nose radius (eqs 18-19).

    The nose (radius R, in the radial plane) touches the designed profile at the cutting
    point when its centre lies R along the profile's normal: centre = (rho - R sin phi,
    z + R cos phi), tan phi = dz/drho. The tip, R below the centre, is then

        X = rho - R sin(phi),   Z = z - R (1 - cos(phi)).

    The paper's eq 18 is this X; its eq 19, z_t = z - R cos(phi), is the nose centre with Z
    counted into the part (docs/procedures/sts_turning.md). ``nose_radius`` None or 0: the
    tip on the cutting point, uncompensated.

    Where the design's profile in the radial plane is concave with a radius of curvature
    below R, the nose touching it at one point cuts into it beside (gouges): the path is
    made all the same (the cut it leaves is the physical one), with a `MachineSimWarning`
    naming the design, its least concave radius, the cutting point and R (`_note_gouging`).
    """
    if nose_radius is None or nose_radius == 0.0:
        return ToolPath(points.theta, points.rho, points.z)
    radius = check_length(nose_radius, "nose_radius", positive=True)
    _note_gouging(points, radius)
    phi = np.arctan(points.slope)
    return ToolPath(points.theta, frozen(points.rho - radius * np.sin(phi)),
                    frozen(points.z - radius * (1.0 - np.cos(phi))))


def _note_gouging(points: CuttingPoints, nose_radius: float) -> None:
    """Warn when the least concave radius of curvature of the design's radial profile at
    the cutting points (`radial_curvature`) is below ``nose_radius`` (m)."""
    if points.design is None:
        return
    curvature = radial_curvature(points.design, points.x, points.y)
    concave = np.isfinite(curvature) & (curvature * nose_radius > 1.0)
    if not concave.any():
        return
    i = int(np.argmax(np.where(concave, curvature, -np.inf)))
    warnings.warn(
        f"design {points.design.name!r}: its least concave radius of curvature in the nose's "
        f"(radial) plane, {1.0 / curvature[i] / M_PER_MM:.6g} mm at the cutting point "
        f"({points.x[i] / M_PER_MM:.6g}, {points.y[i] / M_PER_MM:.6g}) mm (C "
        f"{points.theta[i]:.6g} rad), is below the nose radius {nose_radius / M_PER_MM:.6g} "
        f"mm (at {np.count_nonzero(concave)} of {len(points)} cutting points): the nose "
        "touching the profile there cuts into it beside the point (gouging), and the cut "
        "leaves the nose's wider valley", MachineSimWarning, stacklevel=3)


def interpolate(path: ToolPath, method: str = "linear", substeps: int = 10) -> ToolPath:
    """The path between its points as the controller moves it, ``substeps`` samples per
    step: ``"linear"`` (eqs 7-8: X and Z linear in C, the machine's G01) or ``"spline"``
    (eq 9: not-a-knot cubic splines of X and Z in C through the points).

    A dense path for the turning engine (`machinesim.cutting.turning`) or the motion planner.
    """
    if method not in ("linear", "spline"):
        raise InputError(f"Expected method 'linear' or 'spline', got {method!r}", key="method")
    if isinstance(substeps, bool) or not isinstance(substeps, int | np.integer) or substeps < 1:
        raise InputError(f"Expected substeps as an int >= 1, got {substeps!r}", key="substeps")
    _check_points((len(path) - 1.0) * substeps + 1.0,
                  f"substeps {substeps!r} on {len(path)} points", "substeps")
    _check_increasing(path.c, "path.c")
    c = _substeps(path.c, substeps)
    if method == "linear":
        return ToolPath(frozen(c), frozen(np.interp(c, path.c, path.x)),
                        frozen(np.interp(c, path.c, path.z)))
    return ToolPath(frozen(c), frozen(CubicSpline(path.c, path.x)(c)),
                    frozen(CubicSpline(path.c, path.z)(c)))


def _substeps(values: np.ndarray, substeps: int) -> np.ndarray:
    """``values`` with ``substeps - 1`` equally spaced values inserted in each step."""
    fractions = np.arange(substeps) / substeps
    inner = values[:-1, None] + fractions[None, :] * np.diff(values)[:, None]
    return np.append(inner.ravel(), values[-1])


# --- program-related form error (eqs 10-11, Fig. 11) ----------------------------------------------
@dataclass(frozen=True)
class ProgramError:
    """Eqs 10-11: dz = z_ideal - z_interpolated at sub-steps along the spiral.

    Attributes
    ----------
    theta, rho, dz : ndarray, shape (M,)
        Sample angle (rad), radius (m) and deviation (m).
    """

    theta: np.ndarray
    rho: np.ndarray
    dz: np.ndarray

    @property
    def pv(self) -> float:
        """Peak to valley of dz, m."""
        return float(self.dz.max() - self.dz.min())

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.dz * self.dz)))


def program_error(design: Design, spiral: Spiral, theta, *, method: str = "linear",
                  substeps: int = 10, rho_range: tuple[float, float] | None = None
                  ) -> ProgramError:
    """The form error the interpolation of the cutting points leaves, from the path alone.

    Each step between cutting points (``theta``, rad) is divided into ``substeps`` equal
    steps of C (Fig. 6(c)); there the designed height z_ideal (on the spiral, eq 4) is
    compared with the interpolated path of the cutting points' heights, linear (eqs 7-8) or
    spline (eq 9): dz = z_ideal - z_interpolated (eqs 10-11). Only samples with rho in
    ``rho_range`` (m, inclusive) are kept, if given.
    """
    points = cutting_points(design, spiral, theta)
    path = interpolate(ToolPath(points.theta, points.rho, points.z), method, substeps)
    rho = spiral.radius_at(path.c)
    ideal = design(rho * np.cos(path.c), rho * np.sin(path.c))
    dz = ideal - path.z
    keep = np.ones(dz.size, dtype=bool)
    if rho_range is not None:
        low, high = (float(v) for v in rho_range)
        keep = (rho >= low) & (rho <= high)
        if not keep.any():
            raise InputError(f"Expected rho_range to meet the spiral (0 .. {spiral.radius!r} "
                             f"m), got {rho_range!r}", key="rho_range")
    return ProgramError(frozen(path.c[keep]), frozen(rho[keep]), frozen(dz[keep]))


def program_error_table(design: Design, spiral: Spiral, counts: Sequence[int], *,
                        distributions: Sequence[str] = ("CA", "CAL"),
                        methods: Sequence[str] = ("linear", "spline"), substeps: int = 10,
                        rho_range: tuple[float, float] | None = None) -> dict:
    """Fig. 11: P-V of the program-related form error against the number of cutting points.

    Returns
    -------
    dict
        ``(distribution, method) -> ndarray`` of P-V (m), one per count.
    """
    table = {}
    for distribution in distributions:
        angles = [cutting_angles(spiral, distribution, count=int(n)) for n in counts]
        for method in methods:
            table[distribution, method] = frozen([
                program_error(design, spiral, theta, method=method, substeps=substeps,
                              rho_range=rho_range).pv for theta in angles])
    return table


# --- the NC program -----------------------------------------------------------------------
def spiral_program(path: ToolPath, *, spindle_rpm: float = SPINDLE_RPM,
                   clearance: float = 10 * M_PER_UM, plunge_mm_per_min: float = 1.0,
                   number: int | None = None, start_c: float = 0.0) -> Program:
    """The X Z C program of ``path`` for ``sts_lathe``.

    Blocks: a rapid to the first point ``clearance`` above it, a feed down to it, one G01
    per further point, a feed up by ``clearance``. The path moves run at F = 360 x
    ``spindle_rpm`` deg/min: with the FANUC feed of a move that turns C (the move length
    counts degrees as millimetres; `machinesim.motion`) the spindle then turns at
    ``spindle_rpm`` up to (dX^2 + dZ^2) / (2 dC^2) relative (X, Z in mm, C in deg), below
    1e-9 for the paper's paths; ``spindle_rpm`` at most `MAX_SPINDLE_RPM`. The path's C
    increases strictly, as `interpolate` takes it (InputError naming the first step back).
    ``start_c`` (rad)
    is added to C (the spindle's position at
    the start; ``sts_lathe`` allows |C| <= 1e5 rad, i.e. 15,915 revolutions).

    Returns
    -------
    Program
        Axis values in SI (m, rad); `machinesim.nc.write_program` writes it in mm and deg at
        1 nm and 0.00001 deg.
    """
    if not isinstance(path, ToolPath):
        raise InputError(f"Expected a ToolPath, got {type(path).__name__}", key="path")
    _check_increasing(path.c, "path.c")
    rpm = _positive(spindle_rpm, "spindle_rpm")
    if rpm > MAX_SPINDLE_RPM:
        raise InputError(f"Expected spindle_rpm <= {MAX_SPINDLE_RPM:.6g} rpm (sts_lathe's C "
                         "rapid rate, models/sts_lathe.urdf <limit velocity=\"150.0\"> rad/s; "
                         f"machinesim.cam.spiral.MAX_SPINDLE_RPM), got {rpm!r}",
                         key="spindle_rpm")
    lift = check_length(clearance, "clearance", positive=True)
    plunge = _positive(plunge_mm_per_min, "plunge_mm_per_min") * M_PER_MM / 60.0
    c0 = as_number(start_c, "start_c", unit="rad")  # True is no 1 rad, None no traceback
    # rows: rapid above the first point, feed down to it, the path, feed up
    x = np.concatenate([path.x[:1], path.x, path.x[-1:]])
    z = np.concatenate([path.z[:1] + lift, path.z, path.z[-1:] + lift])
    c = np.concatenate([path.c[:1], path.c, path.c[-1:]]) + c0
    targets = np.full((x.size, len(AXES)), np.nan)
    for axis, values in (("X", x), ("Z", z), ("C", c)):
        targets[:, AXES.index(axis)] = values
    kinds = np.full(x.size, KIND_LINEAR, dtype=np.int64)
    kinds[0] = KIND_RAPID
    # F in deg/min, which the controller reads as mm/min of the move length, in m/s
    feeds = np.full(x.size, 360.0 * rpm * M_PER_MM / 60.0)
    feeds[0] = np.nan
    feeds[1] = feeds[-1] = plunge
    return Program.from_arrays(targets, kinds, feeds, number=number, source="<spiral>")
