"""Squareness of the C table to X and Y from heights read while C turns (paper 003 Figs 7-9).

Readings (through the lab's displacement sensors, here the R-test's three sensors,
`machinesim.metrology.RTest`): the displacement of a point on the tool side from its nominal
place relative to the table, at axis values ``q``. Two kinds of test, each over a full
revolution of C at equally spaced angles:

- *following* (paper Fig. 8): X and Y follow the circle of one point of the table at radius
  ``r``, so the sensor stays on that point and the artefact's own form drops out; its Z
  reading is ``h(theta)`` of Fig. 9(a);
- *fixed*: X and Y still at ``(r, 0)`` and ``(0, r)``, C turning under the sensor: these
  read the table's tilt alone, without the X and Y motion errors (the axes do not move).

Separation (Fig. 9). The table's surface is a plane through the C centre; its height at
machine point ``(x, y)`` is linear in the position, so the fixed tests give it anywhere:
``t(theta; psi) = cos(psi) h_fx(theta) + sin(psi) h_fy(theta)`` at the point's machine angle
``psi``. Removed from the following test this leaves the X and Y motion errors along the
circle (Fig. 9(c)). The table's tilt itself splits, as ISO 230-7 splits an axis' errors,
into the location errors of the C line (its average line: EX0C, EY0C offsets and EA0C,
EB0C tilts, the perpendicularity of C to Y and to X) and the tilt motion (wobble) EAC(C),
EBC(C) about it, which has no mean and no once-per-revolution part. The location errors are
the least-squares solution of the fixed tests' readings on their sensitivities (the
nominal machine's error Jacobian, `Machine.error_jacobian`), with one constant offset per
test in the machine frame (the held axes' own errors, which the workpiece frame sees turn
with C); over a full revolution the wobble's higher harmonics are orthogonal to them. The
tilt motion is what remains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.cam.pyramids import workpiece_axes
from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError

__all__ = ["LOCATION", "CAxisSeparation", "following_axes", "fixed_axes", "first_harmonic",
           "height_from_commands", "readings_from_commands", "separate"]

LOCATION = ("location.C.EX0C", "location.C.EY0C", "location.C.EA0C", "location.C.EB0C")


def following_axes(machine, theta, radius: float, z: float = 0.0) -> np.ndarray:
    """Axis values (N, n_axes) that keep the tool tip on the table point at ``(radius, 0)``
    (workpiece frame) while C takes the angles ``theta`` (rad), on the nominal machine."""
    theta = _angles(theta)
    ix, iy, iz, ic = (machine.axes.index(a) for a in "XYZC")
    out = np.zeros((theta.size, len(machine.axes)))
    for i, t in enumerate(theta):
        out[i, iz], out[i, ic] = z, t
        out[i, [ix, iy]] = workpiece_axes(machine, radius, 0.0, t, z)
    return out


def fixed_axes(machine, theta, x: float, y: float, z: float = 0.0) -> np.ndarray:
    """Axis values (N, n_axes): X, Y, Z held, C at ``theta`` (rad)."""
    theta = _angles(theta)
    q = np.zeros((theta.size, len(machine.axes)))
    for letter, value in (("X", x), ("Y", y), ("Z", z)):
        q[:, machine.axes.index(letter)] = value
    q[:, machine.axes.index("C")] = theta
    return q


@dataclass(frozen=True, eq=False)
class CAxisSeparation:
    """Paper 003 Fig. 9's separation of h(theta), m and rad.

    Attributes
    ----------
    theta : ndarray (N,)
        C angles, rad.
    h : ndarray (N,)
        The following test's height reading (Fig. 9(a), solid).
    table_tilt : ndarray (N,)
        The table's height at the followed point from the fixed tests (Fig. 9(a), dashed:
        location tilts and tilt motion together).
    perpendicularity : ndarray (N,)
        The part of ``table_tilt`` due to EA0C, EB0C (Fig. 9(b), dashed).
    wobble : ndarray (N,)
        The tilt motion part, ``table_tilt - perpendicularity``.
    xy_motion : ndarray (N,)
        ``h - table_tilt``: the X and Y motion errors along the circle (Fig. 9(c)).
    location : dict
        EX0C, EY0C (m), EA0C, EB0C (rad) by `Machine.parameter_names`.
    std : dict
        Their standard uncertainties from the readings' scatter, same units.
    """

    theta: np.ndarray
    h: np.ndarray
    table_tilt: np.ndarray
    perpendicularity: np.ndarray
    wobble: np.ndarray
    xy_motion: np.ndarray
    location: dict
    std: dict

    @property
    def perpendicularity_angle(self) -> float:
        """The angle of the C line to the normal of the XY plane, rad: hypot(EA0C, EB0C)."""
        return float(np.hypot(self.location["location.C.EA0C"],
                              self.location["location.C.EB0C"]))

    def identified(self) -> ErrorModel:
        """The location errors as an `ErrorModel` (for the model-based compensation)."""
        return ErrorModel().with_parameters(self.location)


def separate(machine, follow_q, follow, fixed_q, fixed, sigma: float | None = None
             ) -> CAxisSeparation:
    """Separate the readings (module docstring).

    Parameters
    ----------
    machine : Machine
        The nominal machine (its kinematics and error Jacobian only).
    follow_q : ndarray (N, n_axes)
        Axis values of the following test (`following_axes`), C over a full revolution at
        equal steps.
    follow : ndarray (N, 3)
        Its readings, X, Y, Z displacements, m.
    fixed_q : sequence of two ndarray (N, n_axes)
        The fixed tests at (r, 0) and (0, r) (`fixed_axes`), the same C angles.
    fixed : sequence of two ndarray (N, 3)
        Their readings, m.
    sigma : float, optional
        The sensors' stated standard uncertainty, m: the location errors' std is then
        sigma sqrt(diag((J^T J)^-1)). Without it the residuals' RMS stands in for sigma; they
        hold the wobble as well (orthogonal to the location errors over a full revolution,
        so it moves none of them), and that std overstates.
    """
    follow_q, follow = _readings(follow_q, follow, "follow")
    tests = [_readings(q, r, "fixed") for q, r in zip(fixed_q, fixed, strict=True)]
    if len(tests) != 2:
        raise InputError(f"Expected two fixed tests, got {len(tests)}", key="fixed")
    ic = machine.axes.index("C")
    theta = follow_q[:, ic]
    for q, _ in tests:
        if q.shape[0] != theta.size or not np.allclose(q[:, ic], theta, atol=1e-12):
            raise InputError("Expected the fixed tests at the following test's C angles",
                             key="fixed_q")
    steps = np.diff(np.append(theta, theta[0] + 2 * np.pi))
    if not np.allclose(steps, steps[0], rtol=1e-9, atol=1e-12) or steps[0] <= 0:
        raise InputError("Expected C over one full revolution at equal steps", key="follow_q")
    prior = ErrorModel()
    rows, values = [], []
    for t, (q, r) in enumerate(tests):
        j = machine.error_jacobian(q, prior, list(LOCATION), frame="tool_tip")[:, :3, :]
        # The held axes' own errors: a constant offset d in the machine frame, read in the
        # workpiece frame that turns with C: R d, R the tool's orientation in the workpiece
        # frame on the nominal machine (the tool side does not turn).
        turn = machine.tool_pose(q)[:, :3, :3]
        for d in range(3):
            constants = np.zeros((q.shape[0], 6))
            constants[:, 3 * t:3 * t + 3] = turn[:, d, :]
            rows.append(np.hstack([j[:, d, :], constants]))
            values.append(r[:, d])
    design = np.concatenate(rows)
    y = np.concatenate(values)
    solution, _, rank, _ = np.linalg.lstsq(design, y, rcond=None)
    if rank < design.shape[1]:
        raise InputError("The fixed tests do not separate the C location errors (rank "
                         f"{rank} of {design.shape[1]}); use a radius > 0", key="fixed_q")
    if sigma is None:
        residual = y - design @ solution
        scale = float(np.sqrt(residual @ residual / max(1, y.size - design.shape[1])))
    elif not (isinstance(sigma, int | float) and math.isfinite(sigma) and sigma > 0.0):
        raise InputError(f"Expected sigma as a standard uncertainty > 0 (m), got {sigma!r}",
                         key="sigma")
    else:
        scale = float(sigma)
    cov = np.linalg.inv(design.T @ design) * scale ** 2
    location = {n: float(v) for n, v in zip(LOCATION, solution[:4], strict=True)}
    std = {n: float(np.sqrt(cov[i, i])) for i, n in enumerate(LOCATION)}
    # The table's height at the followed point, from the fixed tests' Z readings (zeroed
    # at theta = 0 as the following test is compared from there).
    psi = np.arctan2(follow_q[:, machine.axes.index("Y")], follow_q[:, machine.axes.index("X")])
    hx, hy = (r[:, 2] - r[0, 2] for _, r in tests)
    table = np.cos(psi) * hx + np.sin(psi) * hy
    # The location part of it: the same combination of the fitted sensitivities.
    jz = [machine.error_jacobian(q, prior, list(LOCATION), frame="tool_tip")[:, 2, :]
          for q, _ in tests]
    fx, fy = ((j - j[0]) @ solution[:4] for j in jz)
    perpendicularity = np.cos(psi) * fx + np.sin(psi) * fy
    h = follow[:, 2] - follow[0, 2]
    return CAxisSeparation(theta=_frozen(theta), h=_frozen(h), table_tilt=_frozen(table),
                           perpendicularity=_frozen(perpendicularity),
                           wobble=_frozen(table - perpendicularity),
                           xy_motion=_frozen(h - table), location=location, std=std)


def first_harmonic(theta, values) -> float:
    """Amplitude of the once-per-revolution part of ``values`` over a full revolution at
    equal steps (least squares on 1, cos, sin), same unit as ``values``."""
    t = _angles(theta)
    v = np.asarray(values, dtype=np.float64)
    a = np.stack([np.ones_like(t), np.cos(t), np.sin(t)], axis=1)
    coef, *_ = np.linalg.lstsq(a, v, rcond=None)
    return float(np.hypot(coef[1], coef[2]))


def readings_from_commands(machine, intended_q, commanded_q, readings) -> np.ndarray:
    """The displacements against the intended points when the control commanded
    ``commanded_q`` (a compensation) for ``intended_q``: the sensors read the displacement
    from the nominal place of the commanded values, so the nominal move between the two is
    added back (nominal kinematics only). Returns (N, 3), m."""
    shift = machine.tool_pose(commanded_q)[:, :3, 3] - machine.tool_pose(intended_q)[:, :3, 3]
    return np.asarray(readings, dtype=np.float64) + shift


def height_from_commands(machine, intended_q, commanded_q, readings) -> np.ndarray:
    """The height part of `readings_from_commands`, zeroed at the first reading, m."""
    h = readings_from_commands(machine, intended_q, commanded_q, readings)[:, 2]
    return h - h[0]


def _readings(q, r, name):
    q = np.array(q, dtype=np.float64)
    r = np.array(r, dtype=np.float64)
    if q.ndim != 2 or r.shape != (q.shape[0], 3) or q.shape[0] < 8:
        raise InputError(f"Expected {name} axis values (N >= 8, n_axes) and readings (N, 3), "
                         f"got {q.shape} and {r.shape}", key=name)
    if not (np.isfinite(q).all() and np.isfinite(r).all()):
        raise InputError(f"Expected finite {name} values", key=name)
    return q, r


def _angles(theta) -> np.ndarray:
    t = np.array(theta, dtype=np.float64)
    if t.ndim != 1 or not np.isfinite(t).all():
        raise InputError(f"Expected C angles (rad) of shape (N,), got {theta!r}", key="theta")
    return t


def _frozen(a):
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a
