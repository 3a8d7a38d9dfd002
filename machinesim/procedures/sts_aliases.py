"""Which error families paper 004's tool test reads as the tool's errors dx, dy and dR.

The tool test (`machinesim.procedures.sts_turning.test_cut`) reads dx and dR from a turned
sphere and dy from a turned tilted plane (`machinesim.identification.turning_tool`). Another
error that moves the turned surfaces as a tool error does, at the test's poses, is read as
that tool error, and nothing in the readings shows it: its share lies within the fits'
columns and leaves no misfit. Which errors do so is a property of the procedure's model at
its poses, not of any lab's truth, so it is computed here from the nominal machine's
kinematics (`Machine.tool_pose` with one error term at a time) and the test plans, as the
error Jacobian's columns against the fits' columns.

For each pose of a test program, an error term moves the nose (its centre, tip + R z_tool)
by D and turns the edge plane by d(theta) about the vertical, as the turning engine takes a
pose (`machinesim.cutting.turning.edge_path_from_poses`); the surface that pose cuts then
moves, to first order, by D_z - grad f . (D_xy + d(theta) e_z x (P - centre)) at its
contact point P on the design f. Over the poses that is the term's column. The fits'
columns are built the same way: dx and dy are the machine's ``tool.x`` and ``tool.y``
through the same kinematics; dR is the fit's own nose form
(`machinesim.cutting.tool_form_error.nose_radius_error`); the sphere fit's centre (x0, y0)
and piston, and the plane fit's piston and tilts, are the columns of those nuisances. The
plane fit takes dx from the sphere, so a term's plane column is taken less its sphere dx
share times dx's plane column. Least squares of the term's column on the fit's columns,
the poses weighted by their radius (the map's pixels are even in area, the spiral's poses
even in angle), gives what the fit reads per unit of the term; what is left is the misfit
it would show.

Error terms: every scalar error parameter of the machine (`Machine.parameter_names`, the
tool errors themselves and the nose radius left out) and, for each component error of each
axis, the first terms of its form over the test's strokes: a linear axis's polynomial
terms of degree 0 to 2 about position 0, a rotary axis's harmonics 0 to 2 of its angle (a
table over a turn, which repeats each turn).

The exact aliases (`tool_test_aliases`) leave at most `MISFIT_SHARE_LIMIT` as misfit. The near
aliases (`near_aliases`) leave more, but less than the test's residual check would refuse at
the size of the paper's tool errors (`NEAR_READING_SIZE`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.cam import spiral as sp
from machinesim.cutting.tool_form_error import nose_radius_error
from machinesim.errors import ComponentError, ErrorModel
from machinesim.procedures.sts_plane_check import PLANE_MISFIT_LIMIT
from machinesim.procedures.sts_plans import TABLE5, TEST_PLANE, TEST_SPHERE
from machinesim.procedures.sts_turning import SPHERE_MISFIT_LIMIT

#: A term aliases into a tool error when at most this share of its column (RMS over the
#: read poses) is left as misfit by the fit's columns: the readings cannot tell it apart.
#: On sts_lathe the exact aliases (the C axis's location, the tool's tilts, a slide's
#: offsets, a straightness slope, which moves the sphere's heights as a cone of X, the
#: tip's radius) leave 1.04e-4 or less (EZX's curvature against dR's form); the next
#: closest, a slide's curvature and EB0Z, leave 2.9e-2. The spindle's axial runout at the
#: first harmonic (EZC sin 1) leaves 4.3e-3 on the plane, which reads it as dy (50 nm per
#: nm), but a third of its movement on the sphere: a near alias (`NEAR_READING_SIZE`).
MISFIT_SHARE_LIMIT = 1e-3
#: ... and the tool error's column carries at least this share of the term's column: less is
#: a term the fits take as piston, centre or tilt (a workpiece's place, a tool's height).
READ_SHARE_LIMIT = 0.01
#: Every n-th pose of a test program is used: the columns are smooth over the spiral
#: (1 um feed, 0.02 rad steps): with every pose, sts_lathe gives the same aliases and
#: readings per unit to 3e-7.
POSE_STEP = 7
#: Size of each error term's finite step: the largest movement of the nose it gives over
#: the test (m), far below anything the fits read yet far above the kinematics' round-off.
STEP_MOVE = 1e-8
#: A term whose largest size (``cap`` in `_terms`) moves the nose by less than this (m) over
#: the test does not move the tool there (the kinematics' round-off is about 1e-17 m).
MOVE_FLOOR = 1e-13
#: A reading moving by less than this share of the nose's movement is round-off.
READ_FLOOR = 1e-4
#: The symbols of the component errors of one axis, its letter after each.
COMPONENT_SYMBOLS = ("EX", "EY", "EZ", "EA", "EB", "EC")
#: The tool errors the test reads, by parameter, and the fit that reads each.
READINGS = {"tool.x": "dx", "tool.y": "dy", "tool_geometry.nose_radius": "dR"}
#: A near alias (`near_aliases`) is a term whose misfit share lies above
#: `MISFIT_SHARE_LIMIT` yet below the share at which a term moving its reading by as much as
#: the tool error the test is built for (Table 5 "before": |dx| = |dy| = 3.5 um, dR = 100 um)
#: leaves the misfit the tool test refuses on the map its reading comes from: on the sphere
#: (dx, dR) `SPHERE_MISFIT_LIMIT`, on the plane (dy) `sts_plane_check.PLANE_MISFIT_LIMIT`,
#: both 0.6 nm RMS. Such a term shifts a reading by as much as the paper's tool errors with
#: less misfit than the check refuses. On sts_lathe the limits are 4.8e-3 (dx), 8.3e-3 (dR)
#: and 1.2e-2 (dy). The exact limit `MISFIT_SHARE_LIMIT` is about the same rule at the ends
#: of the readings' ranges: dx 10 um gives 1.7e-3, dy 20 um 2.1e-3, dR 850 um 9.8e-4.
NEAR_READING_SIZE = {"tool.x": abs(TABLE5["before"][0]), "tool.y": abs(TABLE5["before"][1]),
                     "tool_geometry.nose_radius": abs(TABLE5["before"][2])}


@dataclass(frozen=True)
class Alias:
    """An error term that the tool test reads as a tool error.

    Attributes
    ----------
    term : str
        The error: a parameter name (``location.C.EX0C``) or a component error's term
        (``component.X.EZX`` with its ``form``).
    form : str
        "" for a parameter; a component error's term: "constant", "slope", "curvature"
        (polynomial c0, c1, c2 of a linear axis's position, SI) or "cos 1", "sin 1", ...
        (a rotary axis's harmonic, its amplitude in SI).
    reading : str
        The parameter read for it (``tool.x``, ``tool.y``, ``tool_geometry.nose_radius``).
    per_unit : float
        What the reading moves by per SI unit of the term (m per m, m per rad, m per m/m).
    misfit_share : float
        The share of the term's column the fits leave as misfit (RMS ratio).
    """

    term: str
    form: str
    reading: str
    per_unit: float
    misfit_share: float


@dataclass(frozen=True)
class NearAlias(Alias):
    """A term the tool test reads as a tool error, leaving a misfit share above
    `MISFIT_SHARE_LIMIT` but at most ``share_limit`` (`NEAR_READING_SIZE`). Its
    ``misfit_share`` is that of the map its reading comes from (the plane for dy). Besides
    `Alias`'s:

    Attributes
    ----------
    share_limit : float
        The largest misfit share a near alias of this reading may leave (`NEAR_READING_SIZE`).
    sphere_misfit : float
        The RMS misfit (m per SI unit of the term) it leaves on the test sphere, whose residual
        the tool test checks (`SPHERE_MISFIT_LIMIT`): for a dy alias read on the plane, what
        the sphere shows of it.
    """

    share_limit: float = float("nan")
    sphere_misfit: float = float("nan")


def _poses(machine, plan, nose_radius: float):
    """Axis values of ``plan``'s program (every `POSE_STEP`-th pose), its contact points on
    the design (x, y), and the design's slope there."""
    spiral = sp.Spiral(plan.turned_radius, plan.feed)
    theta = sp.constant_angle(spiral, plan.angle_step)
    points = sp.cutting_points(plan.design(), spiral, theta)
    path = sp.tool_path(points, nose_radius)
    keep = slice(None, None, POSE_STEP)
    q = np.zeros((path.c[keep].size, len(machine.axes)))
    for letter, values in (("X", path.x), ("Z", path.z), ("C", path.c)):
        q[:, machine.axes.index(letter)] = values[keep]
    x, y = points.x[keep], points.y[keep]
    gx, gy = plan.design().slope(x, y)
    return q, x, y, np.column_stack([gx, gy]), points.z[keep]


class _Columns:
    """The surface's first-order movement at a test's poses, per error model."""

    def __init__(self, machine, plan, nose_radius: float):
        self.machine, self.radius = machine, nose_radius
        self.q, self.x, self.y, self.grad, self.z = _poses(machine, plan, nose_radius)
        self.centre, self.angle = self._nose(None)
        rho = np.hypot(self.x, self.y)
        self.weight = np.sqrt(rho) * (rho < plan.read_half_width)

    def _nose(self, errors):
        poses = self.machine.tool_pose(self.q, errors)
        centre = poses[:, :3, 3] + self.radius * poses[:, :3, 2]
        return centre, np.arctan2(poses[:, 1, 0], poses[:, 0, 0])

    def moved(self, errors) -> float:
        """The nose's largest movement (m) over the poses with ``errors``."""
        return float(np.max(np.abs(self._nose(errors)[0] - self.centre)))

    def of(self, make, size: float) -> np.ndarray:
        """The column of the term ``make`` (its model of a given size), per unit of it: by
        central differences of ``size``, so the kinematics' second order cancels."""
        (plus, turn_plus), (minus, turn_minus) = self._nose(make(size)), self._nose(make(-size))
        move = (plus - minus) / (2.0 * size)
        turn = np.unwrap(turn_plus - turn_minus) / (2.0 * size)
        lever = np.column_stack([self.x, self.y, self.z]) - self.centre  # contact from centre
        sideways = turn[:, None] * np.column_stack([-lever[:, 1], lever[:, 0]])
        return move[:, 2] - np.einsum("ij,ij->i", self.grad, move[:, :2] + sideways)


def _terms(machine):
    """(name, form, make, cap) of every error term (module docstring): ``make(s)`` is the
    ErrorModel of the term of size s (SI), ``cap`` the largest size it is taken at: 1e-6 (m
    or rad) at the ends of the axis's travel, far within an error model's bounds."""
    skip = set(READINGS)
    for name in machine.parameter_names():
        if name not in skip:
            yield name, "", (lambda s, n=name: ErrorModel().with_parameters({n: s})), 1e-6
    for axis in machine.axes:
        rotary = machine.axis(axis).rotary
        reach = max(abs(machine.axis(axis).lower), abs(machine.axis(axis).upper))
        for symbol in (f"{s}{axis}" for s in COMPONENT_SYMBOLS):
            name = f"component.{axis}.{symbol}"
            if rotary:
                for n in range(3):
                    for kind in ("cos", "sin")[: 1 if n == 0 else 2]:
                        yield (name, "constant" if n == 0 else f"{kind} {n}",
                               _harmonic(axis, symbol, n, kind), 1e-6)
            else:
                for k, form in enumerate(("constant", "slope", "curvature")):
                    yield (name, form, lambda s, a=axis, y=symbol, k=k: ErrorModel(
                        component={a: {y: ComponentError("poly", None, [0.0] * k + [s])}}),
                        1e-6 / reach**k)


def term_model(machine, term: str, form: str, size: float) -> ErrorModel:
    """The error model of one error term (an `Alias`'s ``term`` and ``form``) of ``size``
    (SI), as the aliases are computed with it."""
    for name, shape, make, _ in _terms(machine):
        if (name, shape) == (term, form):
            return make(size)
    raise KeyError(f"{term} {form}")


def _harmonic(axis: str, symbol: str, n: int, kind: str):
    """``make`` of a rotary axis's component error ``symbol``: harmonic ``n`` (``kind``
    "cos" or "sin") of its angle, a table over a turn (which repeats each turn)."""
    turn = np.linspace(0.0, 2.0 * math.pi, 361)
    wave = np.cos(n * turn) if kind == "cos" else np.sin(n * turn)
    return lambda s: ErrorModel(component={axis: {symbol: ComponentError("table", turn,
                                                                         s * wave)}})


def tool_test_aliases(machine, nose_radius: float) -> tuple[Alias, ...]:
    """The error terms the tool test reads as dx, dy or dR on ``machine`` (its nominal
    kinematics and error parameters) with a tool of ``nose_radius`` (m): module docstring.

    dx and dR are read on the sphere, dy on the plane (with dx as the sphere reads it); a
    term counts for dy only if what it leaves on the sphere is as small against its plane
    column, as the sphere's misfit is checked."""
    return alias_lists(machine, nose_radius)[0]


def near_aliases(machine, nose_radius: float) -> tuple[NearAlias, ...]:
    """The near aliases (`NEAR_READING_SIZE`) of the tool test on ``machine`` with a tool of
    ``nose_radius`` (m): terms read as dx, dy or dR that leave more misfit than an exact
    alias but less, at the paper's tool-error size, than the test's residual check refuses.
    A dy alias's share is its plane misfit's; what it leaves on the sphere is given apart."""
    return alias_lists(machine, nose_radius)[1]


def alias_lists(machine, nose_radius: float) -> tuple[tuple[Alias, ...], tuple[NearAlias, ...]]:
    """`tool_test_aliases` and `near_aliases` from one pass over the error terms."""
    sphere = _Columns(machine, TEST_SPHERE, nose_radius)
    plane = _Columns(machine, TEST_PLANE, nose_radius)

    def tool(name):
        return lambda s: ErrorModel().with_parameters({name: s})

    dx_s, dx_p = sphere.of(tool("tool.x"), STEP_MOVE), plane.of(tool("tool.x"), STEP_MOVE)
    dy_p = plane.of(tool("tool.y"), STEP_MOVE)
    rho = np.hypot(sphere.x, sphere.y)
    small = 1e-9  # dR's form is linear in dR to 1e-6 at this size
    dr_s = nose_radius_error(TEST_SPHERE.design(), rho, np.arctan2(sphere.y, sphere.x),
                             small) / small
    sphere_fit = np.column_stack([np.ones(rho.size), sphere.grad, dx_s, dr_s])
    plane_fit = np.column_stack([np.ones(plane.x.size), plane.x, plane.y, dy_p])
    # the near limit of each reading: the misfit limit of the map it is read from over the
    # RMS movement its own column gives there at the paper's tool error (NEAR_READING_SIZE)
    near_limit = {reading: limit / (NEAR_READING_SIZE[reading] * _rms(own, w))
                  for reading, own, w, limit in (
                      ("tool.x", dx_s, sphere.weight, SPHERE_MISFIT_LIMIT),
                      ("tool.y", dy_p, plane.weight, PLANE_MISFIT_LIMIT),
                      ("tool_geometry.nose_radius", dr_s, sphere.weight, SPHERE_MISFIT_LIMIT))}
    aliases, near = [], []
    for name, form, make, cap in _terms(machine):
        moved = sphere.moved(make(cap)) / cap  # the nose's movement per unit of the term
        if moved * cap < MOVE_FLOOR:
            continue  # the term does not move the tool at the test's poses
        size = min(STEP_MOVE / moved, cap)
        column = sphere.of(make, size)
        read, misfit = _read(sphere_fit, column, sphere.weight)
        on_plane = plane.of(make, size) - read[3] * dx_p  # the plane fit takes dx as read
        read_p, misfit_p = _read(plane_fit, on_plane, plane.weight)
        seen = misfit * _norm(column, sphere.weight) / max(_norm(on_plane, plane.weight),
                                                            1e-300)
        on_sphere = misfit * _rms(column, sphere.weight)  # the sphere's misfit per unit
        for reading, value, left, own_left, own, col, weight in (
                ("tool.x", read[3], misfit, misfit, dx_s, column, sphere.weight),
                ("tool_geometry.nose_radius", read[4], misfit, misfit, dr_s, column,
                 sphere.weight),
                ("tool.y", read_p[3], max(misfit_p, seen), misfit_p, dy_p, on_plane,
                 plane.weight)):
            if not (abs(value) >= READ_FLOOR * moved
                    and _norm(own * value, weight) >= READ_SHARE_LIMIT * _norm(col, weight)):
                continue
            if left <= MISFIT_SHARE_LIMIT:
                aliases.append(Alias(name, form, reading, float(value), float(left)))
            elif own_left <= near_limit[reading]:  # not exact (left above the limit)
                near.append(NearAlias(name, form, reading, float(value), float(own_left),
                                      float(near_limit[reading]), float(on_sphere)))
    return tuple(aliases), tuple(near)


def _unit(alias: Alias) -> tuple[str, float]:
    """The unit an error file writes ``alias``'s term in, and the reading's nm per it."""
    symbol = alias.term.rsplit(".", 1)[1]
    angle = symbol.startswith(("EA", "EB", "EC")) or alias.term.startswith("tool.r") or (
        alias.term.split(".")[-1] in ("alpha", "beta", "gamma"))
    unit = "urad" if angle else "um"
    power = {"slope": 1, "curvature": 2}.get(alias.form, 0)
    shown = unit + {1: "/mm", 2: "/mm^2"}.get(power, "")
    return shown, alias.per_unit * 1e3 * 1e3**power


def alias_rows(aliases, against_axis=None) -> list[list]:
    """The aliases as table rows: term, form, reading, nm per the unit an error file writes
    the term in, that unit, the misfit share; with ``against_axis`` (alias -> how far the
    term moves the tool against the spindle axis along the reading, m per SI unit), that in
    nm per the unit too."""
    rows = []
    for a in aliases:
        unit, per = _unit(a)
        row = [a.term, a.form or "-", a.reading, per, unit, f"{a.misfit_share:.1e}"]
        if against_axis is not None:
            row.insert(4, per * against_axis(a) / a.per_unit)
        rows.append(row)
    return rows


#: Under the table of the aliases in a report.
ALIAS_NOTE = (
    "Computed from the machine's model at the tool test's poses, not from the lab "
    "(machinesim.procedures.sts_aliases): each error term's first-order movement of the turned "
    "test sphere (read for dx, dR) and tilted plane (read for dy) against the fits' own "
    f"columns. Each term listed leaves at most {MISFIT_SHARE_LIMIT:g} of its movement as "
    "misfit, so the test reads it as the tool error named, by the amount given per unit, and "
    "nothing in the readings shows it, whatever the std. Where the tool against the spindle "
    "axis moves by as much, that is what the test is meant to read (the alignment moves the "
    "tool by it); where it does not (a slide's slope or curvature), an injected error of that "
    "term puts the identified value off by the amount given.")


def near_alias_rows(near, against_axis=None) -> list[list]:
    """The near aliases as table rows: `alias_rows`'s (with ``against_axis`` as there), then
    the reading's near limit and the misfit the sphere shows, nm RMS per the unit."""
    rows = []
    for a, row in zip(near, alias_rows(near, against_axis), strict=True):
        per_si = row[3] / a.per_unit  # nm per the file's unit, per SI unit of the reading
        rows.append(row + [f"{a.share_limit:.1e}", a.sphere_misfit * per_si])
    return rows


#: Under the table of the near aliases in a report.
NEAR_ALIAS_NOTE = (
    "Computed as the exact aliases above (machinesim.procedures.sts_aliases.near_aliases). "
    f"Each term listed leaves more than {MISFIT_SHARE_LIMIT:g} of its movement as misfit on "
    "the map its reading comes from (sphere: dx, dR; plane: dy), but at most the near limit: "
    "the share at which a term moving the reading by the paper's tool error (Table 5 before: "
    "3.5 um for dx and dy, 100 um for dR) leaves the misfit the tool test refuses on that "
    f"map (sphere {SPHERE_MISFIT_LIMIT * 1e9:g} nm RMS, plane {PLANE_MISFIT_LIMIT * 1e9:g} nm "
    "RMS with the nose radius error's form known). "
    "The test reads it as the tool error named, by the amount given per unit, and its misfit "
    "stays under the check up to about that size. The last column is what the sphere shows of "
    "it (nm RMS per unit): the sphere check refuses the cut from "
    f"{SPHERE_MISFIT_LIMIT * 1e9:g} nm of it on.")


def _read(fit: np.ndarray, column: np.ndarray, weight: np.ndarray):
    """What ``fit``'s columns read of ``column`` (least squares, poses weighted), and the
    share of the column left as misfit (RMS ratio)."""
    w = weight[:, None]
    read, *_ = np.linalg.lstsq(fit * w, column * weight, rcond=None)
    left = column - fit @ read
    norm = float(np.linalg.norm(column * weight))
    return read, (float(np.linalg.norm(left * weight)) / norm if norm > 0.0 else 0.0)


def _norm(column: np.ndarray, weight: np.ndarray) -> float:
    return float(np.linalg.norm(column * weight))


def _rms(column: np.ndarray, weight: np.ndarray) -> float:
    """The column's RMS over the read map, the poses weighted as in `_read`."""
    return _norm(column, weight) / _norm(np.ones_like(column), weight)


__all__ = ["ALIAS_NOTE", "NEAR_ALIAS_NOTE", "Alias", "NearAlias", "alias_lists", "alias_rows",
           "near_alias_rows", "near_aliases", "term_model", "tool_test_aliases"]
