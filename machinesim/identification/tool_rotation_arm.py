"""The tool setting error e_ys and arm radius r of a planer's tool-rotation axis (paper 000).

The planer (``planer_4axis``) carries its V (prism) tool on an arm below the A axis (tool
rotation about X). The NC program places the edge with the nominal arm radius r0: for an edge
point (y, z) at tool angle t it commands ``Y = y - r0 sin t``, ``Z = z - r0 (1 - cos t)``
(`nominal_axes`). The real edge hangs at radius r and sits e_ys sideways of the arm's centre
line, so at angle t it lands at ``(y + dy(t), z + dz(t))`` with

    dz(t) = e_ys sin t - (r - r0) cos t,     dy(t) = e_ys cos t + (r - r0) sin t.

Measured from t = 0, as paper 000 measures them (its eqs 1 and 2, missing from the text and
derived in docs/procedures/tool_rotation_arm.md):

    e_z,total(t) = dz(t) - dz(0) = (r - r0) (1 - cos t) + e_ys sin t          (eq 1)
    e_y,total(t) = dy(t) - dy(0) = (r - r0) sin t + e_ys (cos t - 1)          (eq 2)

e_z,total is the rise of the edge: a groove gets shallower by it (with e_ys = -0.178 mm the
0-20 deg pattern deepens by up to 58 um).

Everything here takes measurements only: the calibration readings (`AngleReading` of
`machinesim.procedures.tool_rotation_arm`: per tool angle, the edge's height and lateral
error read by the microscope at stations along a ramp groove). `fit_arm` fits eq 1 (and
optionally eq 2) by weighted least squares, `touch_off` gives the state a tool touch at 0 deg
leaves, and `fit_check` identifies the same quantities with the generic
`machinesim.identification.fit` on the machine's kinematics, as a cross-check.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from machinesim.exceptions import InputError
from machinesim.metrology.prisms import SIGMA_FLOOR_M

__all__ = [
    "ArmCheck", "ArmEstimate", "arm_radius", "fit_arm", "fit_check", "fit_observations",
    "height_change", "lateral_change", "nominal_axes", "touch_off",
]


def height_change(angle, r: float, e_ys: float, r0: float):
    """Paper 000 eq 1: rise of the edge at tool angle ``angle`` (rad) from angle 0 (m)."""
    return (r - r0) * (1.0 - np.cos(angle)) + e_ys * np.sin(angle)


def lateral_change(angle, r: float, e_ys: float, r0: float):
    """Paper 000 eq 2: shift of the edge along +Y at ``angle`` (rad) from angle 0 (m)."""
    return (r - r0) * np.sin(angle) + e_ys * (np.cos(angle) - 1.0)


def arm_radius(machine) -> float:
    """Nominal arm radius r0 (m) of a machine's A axis, from its nominal kinematics."""
    if "A" not in machine.axes:
        raise InputError(f"Expected a machine with a tool-rotation axis A, got axes "
                         f"{machine.axes}", key="machine")
    q = np.zeros((3, len(machine.axes)))
    q[:, machine.axes.index("A")] = (0.0, -0.5, 0.5)
    poses = machine.tool_pose(q)
    y = poses[:, 1, 3]
    r0 = float((y[2] - y[1]) / (2.0 * math.sin(0.5)))
    # paper 000's arm: A turns the tool about +X, its edge r0 > 0 below the axis, so that
    # turning by t moves the edge to (x, r0 sin t, r0 (1 - cos t)) and turns it by Rx(t)
    # (planer_4axis). A machine whose A passes through the edge (robonano_ui: r0 = 0) or
    # turns about another direction would give eqs 1-2 nothing to read.
    swing = np.array([[0.0, -r0 * math.sin(0.5), r0 * (1.0 - math.cos(0.5))],
                      [0.0, r0 * math.sin(0.5), r0 * (1.0 - math.cos(0.5))]])
    turns = [_rx(t) @ poses[0, :3, :3] for t in (-0.5, 0.5)]
    if not (r0 > 0.0 and np.allclose(poses[1:, :3, 3] - poses[0, :3, 3], swing, rtol=0.0,
                                      atol=1e-9 * max(r0, 1.0))
            and all(np.allclose(poses[k + 1, :3, :3], turns[k], rtol=0.0, atol=1e-9)
                    for k in range(2))):
        raise InputError(
            f"Expected a machine whose A axis turns the tool about +X on an arm, the edge "
            f"r0 > 0 below the axis (paper 000's planer, e.g. planer_4axis); machine "
            f"{machine.name}'s A moves the edge by {_mm(poses[1, :3, 3] - poses[0, :3, 3])} "
            f"mm at A = -0.5 rad and {_mm(poses[2, :3, 3] - poses[0, :3, 3])} mm at +0.5 rad "
            f"(r0 = {r0 * 1e3:.6g} mm)", key="machine")
    return r0


def _rx(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _mm(vector) -> str:
    return "(" + ", ".join(f"{v * 1e3:.6g}" for v in vector) + ")"


def nominal_axes(y, z, angle, r0: float):
    """Y and Z (m) that put the nominal edge at (y, z) at tool angle ``angle`` (rad)."""
    return y - r0 * np.sin(angle), z - r0 * (1.0 - np.cos(angle))


@dataclass(frozen=True)
class ArmEstimate:
    """The edge on the A-axis arm as identified (or as assumed before identification).

    Attributes
    ----------
    r0, r : float
        Nominal and identified arm radius (m).
    e_ys : float
        Tool setting error: the edge's offset along Y from the arm's centre line at t = 0 (m).
    z_offset, y_offset : float
        Height and lateral error of the edge at t = 0 (m): dz(0), dy(0).
    r_sigma, e_ys_sigma, z_offset_sigma : float
        Standard uncertainties (m) from the readings' uncertainties; NaN when not fitted.
    residual_z, residual_y : tuple of float
        Reading minus model at each angle (m); empty when not fitted.
    """

    r0: float
    r: float
    e_ys: float
    z_offset: float = 0.0
    y_offset: float = 0.0
    r_sigma: float = math.nan
    e_ys_sigma: float = math.nan
    z_offset_sigma: float = math.nan
    residual_z: tuple[float, ...] = field(default=())
    residual_y: tuple[float, ...] = field(default=())

    def edge_error(self, angle):
        """(dy, dz) of the edge from where the nominal program puts it, at ``angle`` (m)."""
        return (self.y_offset + lateral_change(angle, self.r, self.e_ys, self.r0),
                self.z_offset + height_change(angle, self.r, self.e_ys, self.r0))


def _distinct_angles(readings) -> None:
    if len({round(reading.angle, 12) for reading in readings}) < 3:
        raise InputError(f"Expected readings at three or more distinct angles, got "
                         f"{[math.degrees(r.angle) for r in readings]} deg", key="readings")


def fit_arm(readings: Sequence, r0: float, *, lateral: bool = False) -> ArmEstimate:
    """Identify r and e_ys from the calibration readings (paper 000 eq 1, least squares).

    Parameters
    ----------
    readings : sequence of AngleReading
        At least three distinct angles (the offset at t = 0 is a third unknown).
    r0 : float
        Nominal arm radius (m).
    lateral : bool
        Also fit the apex positions with eq 2 (with their own offset). Default False, the
        paper's fit of depths alone; the lateral offset and residuals are then reported with
        eq 2 evaluated at the fitted constants.

    Returns
    -------
    ArmEstimate
        Uncertainties propagated from the readings' (weighted least squares).
    """
    _distinct_angles(readings)
    t = np.array([reading.angle for reading in readings])
    z, z_sigma = np.array([reading.mean("dz") for reading in readings]).T
    y, y_sigma = np.array([reading.mean("dy") for reading in readings]).T
    one, zero = np.ones_like(t), np.zeros_like(t)
    # unknowns: z offset, rho = r - r0, e_ys, y offset
    rows = np.column_stack([one, 1.0 - np.cos(t), np.sin(t), zero])
    values, sigmas = z, z_sigma
    if lateral:
        rows = np.vstack([rows, np.column_stack([zero, np.sin(t), np.cos(t) - 1.0, one])])
        values, sigmas = np.r_[z, y], np.r_[z_sigma, y_sigma]
    else:
        rows = rows[:, :3]
    weight = 1.0 / np.maximum(sigmas, SIGMA_FLOOR_M)
    solution = np.linalg.lstsq(rows * weight[:, None], values * weight, rcond=None)[0]
    covariance = np.linalg.inv((rows * weight[:, None]).T @ (rows * weight[:, None]))
    c, rho, e = solution[:3]
    r = r0 + rho
    change = lateral_change(t, r, e, r0)
    # without the lateral fit, eq 2 at the fitted constants gives the offset at t = 0
    y_offset = solution[3] if lateral else np.average(y - change, weights=1.0 / np.maximum(
        y_sigma, SIGMA_FLOOR_M) ** 2)
    sigma = np.sqrt(np.diag(covariance))
    return ArmEstimate(r0=r0, r=float(r), e_ys=float(e), z_offset=float(c),
                       y_offset=float(y_offset), r_sigma=float(sigma[1]),
                       e_ys_sigma=float(sigma[2]), z_offset_sigma=float(sigma[0]),
                       residual_z=tuple(z - c - height_change(t, r, e, r0)),
                       residual_y=tuple(y - y_offset - change))


def touch_off(readings: Sequence, r0: float) -> ArmEstimate:
    """The state before compensation: the edge set by its reading at t = 0 only.

    As a tool touch at t = 0 would, this corrects the edge's height and lateral offset at
    t = 0 and assumes the nominal arm (r = r0, e_ys = 0) at every other angle (paper 000's
    uncompensated patterns).
    """
    at_zero = [reading for reading in readings if reading.angle == 0.0]
    if not at_zero:
        raise InputError("Expected a reading at tool angle 0 to touch off from, got angles "
                         f"{[math.degrees(r.angle) for r in readings]} deg", key="readings")
    (dz, dz_sigma), (dy, _) = at_zero[0].mean("dz"), at_zero[0].mean("dy")
    return ArmEstimate(r0=r0, r=r0, e_ys=0.0, z_offset=dz, y_offset=dy,
                       z_offset_sigma=dz_sigma)


# ------------------------------------------------------------------- cross-check by `fit`

#: The error parameters `fit_check` estimates from the edge heights: the arm's two (e_ys is
#: the tool setting along the tool_mount's y, r - r0 lowers the edge along its -z) and the
#: workpiece height, which takes the edge's height offset at t = 0 as eq 1's free offset
#: does. tool.z turns with A (its z component is tool.z cos t) while workpiece.z does not,
#: so readings at three or more angles separate them.
HEIGHT_PARAMETERS = ("tool.y", "tool.z", "workpiece.z")
#: With the lateral readings too: the workpiece's y takes the lateral offset at t = 0.
LATERAL_PARAMETERS = ("tool.y", "tool.z", "workpiece.y", "workpiece.z")


def fit_observations(readings: Sequence, machine, r0: float, *, lateral: bool = False):
    """The calibration readings as observations of the tool tip, for `fit`.

    Each station of each reading is one observation: at the axis values that program the
    station's edge point (X = the station's x, Y and Z by `nominal_axes` from the programmed
    edge, A = the reading's angle), the tool tip was seen displaced from its nominal place by
    ``dz`` along the workpiece's +z (and, with ``lateral``, by ``dy`` along +y), with the
    station's standard uncertainty (floored as `fit_arm` floors it).

    Parameters
    ----------
    readings : sequence of AngleReading
        With the programmed edge (``y_edge``, ``z_edge``) of every station.
    machine : Machine
        The nominal machine (axes X, Y, Z, A in any order).
    r0 : float
        Nominal arm radius (m), as the program used it.
    lateral : bool
        Observe the lateral readings ``dy`` as well.

    Returns
    -------
    Observations
    """
    from machinesim.identification.fit import Observations

    axes = machine.axes
    if any(a not in axes for a in ("X", "Y", "Z", "A")):
        raise InputError(f"Expected a machine with axes X, Y, Z and A, got {''.join(axes)}",
                         key="machine")
    columns = [axes.index(a) for a in ("X", "Y", "Z", "A")]
    which = ("dz", "dy") if lateral else ("dz",)
    q, directions, values, sigma = [], [], [], []
    for reading in readings:
        if reading.y_edge is None or reading.z_edge is None:
            raise InputError("Expected readings with the programmed edge of every station "
                             "(y_edge, z_edge) to place them on the machine", key="readings")
        Y, Z = nominal_axes(np.asarray(reading.y_edge), np.asarray(reading.z_edge),
                            reading.angle, r0)
        stations = np.zeros((len(reading.x), len(axes)))
        stations[:, columns] = np.column_stack([reading.x, Y, Z,
                                                np.full(len(reading.x), reading.angle)])
        for name in which:
            q.append(stations)
            directions.append(np.tile((0.0, 0.0, 1.0) if name == "dz" else (0.0, 1.0, 0.0),
                                      (len(reading.x), 1)))
            values.append(np.asarray(getattr(reading, name)))
            sigma.append(np.maximum(getattr(reading, f"{name}_sigma"), SIGMA_FLOOR_M))
    return Observations(np.concatenate(q), values=np.concatenate(values),
                        directions=np.concatenate(directions), sigma=np.concatenate(sigma))


@dataclass(frozen=True)
class ArmCheck:
    """r and e_ys identified by the generic `fit` from the same readings as `fit_arm`.

    Attributes
    ----------
    estimate : Estimate
        The fit (`machinesim.identification.fit.Estimate`) of `HEIGHT_PARAMETERS` (or
        `LATERAL_PARAMETERS`), SI.
    r, e_ys : float
        The arm radius ``r0 - tool.z`` and ``e_ys = tool.y`` (m).
    r_sigma, e_ys_sigma : float
        Their standard uncertainties (m), from the fit's.
    """

    estimate: object
    r: float
    e_ys: float
    r_sigma: float
    e_ys_sigma: float


def fit_check(readings: Sequence, machine, r0: float, *, lateral: bool = False) -> ArmCheck:
    """Cross-check `fit_arm`: r and e_ys by `machinesim.identification.fit` on the machine.

    The same readings (`fit_observations`), the same weights, but the machine's own error
    Jacobians instead of eqs 1 and 2: the tool setting (tool.y, tool.z) turns with A on the
    kinematic chain, and workpiece.z (workpiece.y with ``lateral``) takes the offset at
    t = 0. Eq 1's three unknowns (offset, r - r0, e_ys) are a linear change of these three
    (offset = tool.z - workpiece.z), and the weighted mean per angle that `fit_arm` fits is
    a sufficient statistic of the stations, so both give the same least-squares estimate:
    they differ by round-off only (docs/procedures/tool_rotation_arm.md gives the figure).

    Parameters
    ----------
    readings : sequence of AngleReading
    machine : Machine
        The nominal machine.
    r0 : float
        Nominal arm radius (m).
    lateral : bool
        Fit the lateral readings too (compare with ``fit_arm(..., lateral=True)``).

    Returns
    -------
    ArmCheck
    """
    from machinesim.identification.fit import fit

    _distinct_angles(readings)
    params = LATERAL_PARAMETERS if lateral else HEIGHT_PARAMETERS
    estimate = fit(machine, fit_observations(readings, machine, r0, lateral=lateral),
                   list(params))
    values = dict(zip(estimate.names, estimate.values, strict=True))
    stds = dict(zip(estimate.names, estimate.std, strict=True))
    return ArmCheck(estimate=estimate, r=r0 - float(values["tool.z"]),
                    e_ys=float(values["tool.y"]), r_sigma=float(stds["tool.z"]),
                    e_ys_sigma=float(stds["tool.y"]))
