"""The tool edge's offset from the A, B and C rotary centres of a 6-axis machine (paper 001).

Paper 001 (Nakamoto et al., 6-axis ROBOnano Ui; docs/procedures/tool_setting_6axis.md
derives every step). NC data for the 6-axis machine is written with the tool edge on the
rotary centres. The edge really sits at ``d = (dx, dy, dz)`` from the A/B centres
(tool_mount axes: error parameters ``tool.x``, ``tool.y``, ``tool.z``) and the C centre line
at ``e = (ex, ey)`` (workpiece frame at C = 0: ``location.C.EX0C``, ``location.C.EY0C``),
so with ``P = (X, Y, Z)`` the edge lands at ``e + Rz(C) (P + Ry(B) Rz(A) d - e)`` instead
of ``Rz(C) P``.

Everything here takes measured features only (`GrooveReading`: groove centre points, depths
and end points read under the microscope, with the axis values each groove was cut at)
and returns identified values; reading the plates is `machinesim.procedures.
tool_setting_6axis`'s job, their design `machinesim.cam.tool_setting_plates`'.

- `a_axis_sets`: the A sets (paper Fig. 4): two grooves from one start point, cut at C and
  C + 180 deg, end ``2 L + 2 (d - Rz(-A) e)`` apart in the set's own frame; at A = 0 and
  180 deg that gives dx and dy (and e a second time).
- `c_axis_triangle`: the triangle cut at C = 0, 120, 240 deg is centred on ``e``.
- `b_axis_offsets` (paper eqs 1-2, eq 2 corrected) and `b_axis_tilts`: the depths of
  grooves cut at B = 0, theta2, theta3 give the edge offset from the B centre.
- `identify`: all stages, the final `Compensation`, and the standard uncertainties of the
  paper's values propagated from the readings'.
- `corrected_axes`: the paper's rewrite of the NC data, as the function
  `machinesim.compensation.map_program` applies.

The model-based cross-check (the same readings through the generic
`machinesim.identification.fit`) is `machinesim.identification.tool_setting_6axis_fit`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from machinesim._frozen import reduce_frozen
from machinesim.arrays import frozen
from machinesim.exceptions import InputError
from machinesim.metrology import Line2D, fit_line, fit_parallel_lines, groove_crossing
from machinesim.rotations import rot_y, rot_z

__all__ = [
    "AAxisResult", "BAxisResult", "CAxisResult", "Compensation", "GrooveReading",
    "Identification", "PARAMETERS", "a_axis_sets", "b_axis_offsets", "b_axis_tilts",
    "b_tilt_determinant", "c_axis_triangle", "corrected_axes", "identify", "read_stages",
]

#: The error parameters paper 001 identifies, as `Machine.parameter_names` spells them.
PARAMETERS = ("tool.x", "tool.y", "tool.z", "location.C.EX0C", "location.C.EY0C")
#: Axes `corrected_axes` expects, in this order (robonano_ui's `Machine.axes`).
AXES = ("X", "Y", "Z", "A", "B", "C")
#: Smallest |den| of eqs 1-2 accepted: there (tilts of +-0.06 deg) a 1 nm depth error already
#: moves dZ by ~1 mm, so the tilts measure nothing.
MIN_DETERMINANT = 1e-9


# ---------------------------------------------------------------------------- readings


@dataclass(frozen=True, eq=False)
class GrooveReading:
    """One straight groove as the microscope read it, and the axis values it was cut at.

    Attributes
    ----------
    q_start, q_end : ndarray, shape (n_axes,)
        Axis values (m, rad, `Machine.axes` order) at the two ends of the block that cut the
        groove, as the program that was cut commanded them.
    points : ndarray, shape (k, 2)
        The groove's centre (apex) in k profiles across it, workpiece frame (m).
    point_sigma : ndarray, shape (k,)
        Standard uncertainty of each centre across the groove (m).
    depths, depth_sigma : ndarray, shape (k,)
        Apex depth below the plate top in the same profiles, and its uncertainty (m).
    end : ndarray, shape (2,), optional
        Where the centre line meets the groove's end face (m), the face the edge leaves as
        it is lifted out at the end of the block (the A sets).
    end_sigma : float
        Standard uncertainty of the end point along the groove (m): across, the end point is
        the centre line's, whose uncertainty comes from the points.
    """

    q_start: np.ndarray
    q_end: np.ndarray
    points: np.ndarray
    point_sigma: np.ndarray
    depths: np.ndarray
    depth_sigma: np.ndarray
    end: np.ndarray | None = None
    end_sigma: float = math.nan

    def __post_init__(self) -> None:
        for name in ("q_start", "q_end", "points", "point_sigma", "depths", "depth_sigma"):
            object.__setattr__(self, name, frozen(getattr(self, name)))
        k = len(self.points)
        if (self.points.shape != (k, 2) or k < 2 or self.q_start.shape != self.q_end.shape
                or any(getattr(self, n).shape != (k,)
                       for n in ("point_sigma", "depths", "depth_sigma"))):
            raise InputError(f"Expected a groove reading of k >= 2 points (k, 2) with k "
                             f"sigmas, depths and depth sigmas, got points "
                             f"{self.points.shape}", key="points")
        if self.end is not None:
            object.__setattr__(self, "end", frozen(self.end))

    @property
    def line(self) -> Line2D:
        """The centre line fitted to `points`."""
        return fit_line(self.points)


@dataclass(frozen=True, eq=False)
class Compensation:
    """What the NC data must cancel (m, workpiece frame; SI).

    Attributes
    ----------
    tool_offset : ndarray, shape (3,)
        Edge offset (dx, dy, dz) from the A/B centres, tool_mount axes.
    c_centre : ndarray, shape (2,)
        C centre line (ex, ey) in the workpiece frame at C = 0.
    z_shift : float
        Added to every Z (a work offset: the touch-off of stage 0).
    """

    tool_offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    c_centre: np.ndarray = field(default_factory=lambda: np.zeros(2))
    z_shift: float = 0.0

    def __post_init__(self) -> None:
        for name, n in (("tool_offset", 3), ("c_centre", 2)):
            value = np.array(getattr(self, name), dtype=np.float64)
            if value.shape != (n,) or not np.isfinite(value).all():
                raise InputError(f"Expected {name} as {n} finite numbers (m), got {value!r}",
                                 key=name)
            object.__setattr__(self, name, frozen(value))
        if not math.isfinite(self.z_shift):
            raise InputError(f"Expected a finite z_shift (m), got {self.z_shift!r}",
                             key="z_shift")


@dataclass(frozen=True, eq=False)
class AAxisResult:
    """The A sets: their grooves' end points and what they give (m).

    Attributes
    ----------
    ends : ndarray, shape (4, 2)
        End points of the four grooves, in cutting order (as read).
    relations : ndarray, shape (2, 2)
        Per set, the end points' displacement in the set's own frame less the programmed
        2 L: ``2 (d - Rz(-A) e)``, along and across the set (A = 0: ``2 (d - e)``;
        A = 180 deg: ``2 (d + e)``).
    distances : ndarray, shape (1, 2)
        Half their sum, ``2 (dx, dy)``: Table 1's "distance between grooves" against the A
        axis (the A = 0 set's grooves against the A = 180 deg set's).
    offset : ndarray, shape (2,)
        (dx, dy).
    centre : ndarray, shape (2,)
        The C centre line e, a second reading (a quarter of the relations' difference).
    """

    ends: np.ndarray
    relations: np.ndarray
    distances: np.ndarray
    offset: np.ndarray
    centre: np.ndarray


@dataclass(frozen=True, eq=False)
class BAxisResult:
    """B-axis grooves: depths (3,) at B = 0, theta2, theta3, and eqs 1-2's edge offset from
    the B centre, dX (machine X at A = theta1, B = 0) and dZ (along the tool), all in m."""

    depths: np.ndarray
    offset_x: float
    offset_z: float


@dataclass(frozen=True, eq=False)
class CAxisResult:
    """C-axis triangle: its three crossings (3, 2), its centre (2,) and its sides (m).

    With a reference mark, ``vertices`` and ``centre`` are placed by the mark (workpiece
    frame up to the mark's own cutting error), ``mark`` is the mark's crossing with the
    C = 0 side and ``rotation`` the turn of the microscope's frame found on that side, both
    as the microscope read them; the sides stay as read."""

    vertices: np.ndarray
    centre: np.ndarray
    sides: tuple[Line2D, ...]
    mark: np.ndarray | None = None
    rotation: float = 0.0


@dataclass(frozen=True, eq=False)
class Identification:
    """All stages of paper 001, and what they identify.

    Attributes
    ----------
    z_touch : float
        Z (m) at which the edge met the plate at B = 0 (the touch-off).
    a, b, c : AAxisResult, BAxisResult, CAxisResult
        The stages.
    compensation : Compensation
        The final compensation: d = (dx, dy, dZ) and e, no Z shift.
    std : Mapping[str, float]
        Standard uncertainty (m) of each of `PARAMETERS`, propagated from the readings'
        through the paper's formulas.
    check : Estimate, optional
        The model-based cross-check (`fit_check`) on the same readings.
    check_std : Mapping[str, float]
        Standard uncertainty (m) of the cross-check's values: the fit's own covariance (the
        readings' independent errors) and the plates' registration propagated through the
        fit, in quadrature (`ToolSetting6Axis.identify`).
    readings : object, optional
        The readings identified from (a procedure's measurements), for the uncertainty of
        what is cut with the result (`after_std`).
    """

    z_touch: float
    a: AAxisResult
    b: BAxisResult
    c: CAxisResult
    compensation: Compensation
    std: Mapping[str, float] = field(default_factory=dict)
    check: object = None
    check_std: Mapping[str, float] = field(default_factory=dict)
    readings: object = None

    __reduce__ = reduce_frozen  # pickles (a Result holds it), its read-only mappings too

    @property
    def values(self) -> dict[str, float]:
        """`PARAMETERS` -> identified value (m): d = (dx, dy, dZ), then e."""
        comp = self.compensation
        return dict(zip(PARAMETERS, (*comp.tool_offset.tolist(), *comp.c_centre.tolist()),
                        strict=True))

    @property
    def parameters(self) -> dict[str, tuple[float, float]]:
        """`PARAMETERS` -> (value, std) (m), as `machinesim.experiment.Identified` holds."""
        return {name: (value, float(self.std.get(name, math.nan)))
                for name, value in self.values.items()}


# ---------------------------------------------------------------------------- the stages


def a_axis_sets(grooves: Sequence[GrooveReading], length: float) -> AAxisResult:
    """dx and dy from the A sets' grooves (paper 001, Fig. 4).

    Each set is two grooves from one programmed start point, the origin, along the tool's
    own X at A: one cut at C, one at C + 180 deg. A groove cut at (A, C) starts at
    ``e + Rz(C) (Rz(A) d - e)`` and ends L further along ``Rz(C) Rz(A) x``, so in the set's
    own frame ``F = Rz(C + A)`` (x along the first groove)

        F^T (end_1 - end_2) - (2 L, 0) = 2 (d - Rz(-A) e),

    which is ``2 (d - e)`` at A = 0 and ``2 (d + e)`` at A = 180 deg: the sets' half sum is
    ``2 d``, their half difference ``2 e``. Both components are read between the set's own
    two lines (`fit_parallel_lines` on the two grooves' centres, one common direction):
    along it, the end points' distance; across it, the lines' offset. Neither changes with
    a turn or shift of the frame the plate was read in.

    Parameters
    ----------
    grooves : sequence of GrooveReading
        The sets' grooves in cutting order (first and second of each set), each with its end
        point and the axis values it was cut at (A from ``q_start``, `AXES` order).
    length : float
        The programmed length L of each groove (m).

    Returns
    -------
    AAxisResult
    """
    if len(grooves) < 4 or len(grooves) % 2:
        raise InputError(f"Expected two or more sets of two A grooves, got {len(grooves)}",
                         key="grooves")
    if any(g.end is None for g in grooves):
        raise InputError("Expected the end point of every A groove", key="end")
    relations, rows = [], []
    for first, second in zip(grooves[::2], grooves[1::2], strict=True):
        one, two = fit_parallel_lines(first.points, second.points)
        along = one.direction if one.direction @ (one.point - two.point) > 0 else -one.direction
        across = np.array([-along[1], along[0]])
        relations.append([(first.end - second.end) @ along - 2.0 * length,
                          (one.point - two.point) @ across])
        turn = rot_z(-float(first.q_start[AXES.index("A")]))[:2, :2]
        rows.append(np.hstack([np.eye(2), -turn]))
    relations, rows = np.array(relations), np.vstack(rows)
    if np.linalg.matrix_rank(rows) < 4:
        raise InputError("Expected A sets whose A angles separate d from e (e.g. 0 and 180 "
                         "deg)", key="grooves")
    # relation_k / 2 = d - Rz(-A_k) e, every set: least squares for (d, e)
    solved, *_ = np.linalg.lstsq(rows, 0.5 * relations.reshape(-1), rcond=None)
    ends = np.array([g.end for g in grooves])
    return AAxisResult(frozen(ends), frozen(relations), frozen(2.0 * solved[None, :2]),
                       frozen(solved[:2]), frozen(solved[2:]))


def c_axis_triangle(points: Sequence, mark_at=None) -> CAxisResult:
    """The C centre line from the triangle cut at C = 0, 120, 240 deg (paper 001, Fig. 3).

    One groove turned about the true C centre ``e`` by thirds of a turn bounds an equilateral
    triangle centred on ``e``, whatever the tool offset; the programmed triangle is centred on
    the origin, so the centroid of the three crossings is ``e``.

    A microscope does not know where the workpiece origin is (its stage's registration), so
    the triangle is placed by a reference mark cut at C = 0 across the C = 0 side: the mark's
    crossing with that side is where the program put it (``mark_at``), up to the residual
    tool offset it was cut with, and the C = 0 side runs along the workpiece's x. So the
    vertices, as read, are taken relative to the crossing, turned so that the C = 0 side is
    along x, and placed at ``mark_at``: neither the stage's offset nor its rotation is left.

    Parameters
    ----------
    points : sequence of 3 or 4 array_like, shape (k, 2)
        Centre points of the grooves cut at C = 0, 120, 240 deg (m), and of the reference
        mark (4th, optional).
    mark_at : array_like, shape (2,), optional
        The programmed crossing of the mark with the C = 0 side (m); needed with a mark.

    Returns
    -------
    CAxisResult
    """
    if len(points) not in (3, 4):
        raise InputError(f"Expected the centre points of 3 grooves (and a mark), got "
                         f"{len(points)}", key="points")
    crossings = [groove_crossing(points[i], points[j]) for i, j in ((0, 1), (1, 2), (2, 0))]
    vertices = np.array([cr.point for cr in crossings])
    sides = (crossings[0].first, crossings[1].first, crossings[2].first)
    if len(points) == 3:
        return CAxisResult(frozen(vertices), frozen(vertices.mean(axis=0)), sides)
    if mark_at is None:
        raise InputError("Expected the programmed crossing of the reference mark (mark_at)",
                         key="mark_at")
    mark = groove_crossing(points[0], points[3]).point
    along = sides[0].direction if sides[0].direction[0] > 0 else -sides[0].direction
    rotation = math.atan2(along[1], along[0])
    placed = (vertices - mark) @ rot_z(-rotation)[:2, :2].T + np.asarray(mark_at, float)
    return CAxisResult(frozen(placed), frozen(placed.mean(axis=0)), sides, frozen(mark),
                       rotation)


def b_tilt_determinant(theta2: float, theta3: float) -> float:
    """The determinant ``sin t2 (1 - cos t3) - sin t3 (1 - cos t2)`` of eqs 1-2
    (`b_axis_offsets`) for the B tilts theta2, theta3 (rad): it is zero where either tilt is
    zero or the two are equal (modulo a turn), and eqs 1-2 need its magnitude above
    `MIN_DETERMINANT`."""
    return (math.sin(theta2) * (1.0 - math.cos(theta3))
            - math.sin(theta3) * (1.0 - math.cos(theta2)))


def b_axis_offsets(d0: float, d1: float, d2: float, theta2: float, theta3: float):
    """Edge offset from the B centre from three groove depths (paper 001, eqs 1-2).

    At B = theta the edge offset (dX, dZ) (machine X and Z at B = 0) turns to
    ``Ry(theta) (dX, dZ)``, whose z is ``-dX sin(theta) + dZ cos(theta)``, so the groove
    depth grows by ``d - D = dX sin(theta) + dZ (1 - cos(theta))`` over the B = 0 depth D.
    Solved for the two tilts (Cramer's rule)::

        dX = ((d1 - D)(1 - cos t3) - (d2 - D)(1 - cos t2)) / den       (eq 1, sign below)
        dZ = ((d2 - D) sin t2 - (d1 - D) sin t3) / den                  (eq 2, corrected)
        den = sin t2 (1 - cos t3) - sin t3 (1 - cos t2)

    The paper's eq 1 is -dX: its positive B tilts the other way (theta -> -theta changes
    the signs of dX and den only), and dZ is the same in both senses. The printed eq 2,
    ``((d1 - D) sin t2 + (d2 - D) sin t3) / den``, follows from neither.

    Parameters
    ----------
    d0, d1, d2 : float
        Depths (m) at B = 0 (D), theta2 and theta3.
    theta2, theta3 : float
        The B tilts (rad).

    Returns
    -------
    (float, float)
        dX, dZ (m).
    """
    den = b_tilt_determinant(theta2, theta3)
    if not abs(den) > MIN_DETERMINANT:
        raise InputError(f"Expected two distinct non-zero B tilts, got theta2 = "
                         f"{math.degrees(theta2):g} deg, theta3 = {math.degrees(theta3):g} deg")
    u, v = d1 - d0, d2 - d0
    return ((u * (1.0 - math.cos(theta3)) - v * (1.0 - math.cos(theta2))) / den,
            (v * math.sin(theta2) - u * math.sin(theta3)) / den)


def b_axis_tilts(depths, theta2: float, theta3: float, commanded_z=None) -> BAxisResult:
    """The B stage (paper 001, Fig. 5): eqs 1-2 (`b_axis_offsets`) on the depths of the
    grooves cut at B = 0, theta2 and theta3.

    The paper cuts the three grooves at one depth of cut D. Where their commanded Z differ
    (a compensation of what earlier stages found, and its rounding to the machine's 1 nm),
    each depth is first taken back to the B = 0 groove's command: ``d_k + Z_k - Z_0``. Eqs
    1-2 then give the edge's offset from the B centre whatever the program added.

    Parameters
    ----------
    depths : array_like, shape (3,)
        Measured depths below the plate top (m), B = 0, theta2, theta3.
    theta2, theta3 : float
        The B tilts (rad).
    commanded_z : array_like, shape (3,), optional
        The Z each groove was cut at (m); default all equal.

    Returns
    -------
    BAxisResult
        ``depths`` as measured; dX, dZ from the depths at one command.
    """
    depths = np.asarray(depths, dtype=np.float64)
    z = np.zeros(3) if commanded_z is None else np.asarray(commanded_z, dtype=np.float64)
    if depths.shape != (3,) or z.shape != (3,):
        raise InputError(f"Expected 3 groove depths and 3 commanded Z, got shapes "
                         f"{depths.shape} and {z.shape}", key="depths")
    dx, dz = b_axis_offsets(*(depths + z - z[0]), theta2, theta3)
    return BAxisResult(frozen(depths), float(dx), float(dz))


def identify(z_touch: float, a: Sequence[GrooveReading], c: Sequence[GrooveReading],
             b: Sequence[GrooveReading], length: float, theta2: float,
             theta3: float, mark_at=None, registration=None) -> Identification:
    """Paper 001's identification from the readings of its three plates.

    Parameters
    ----------
    z_touch : float
        The touch-off Z (m).
    a : sequence of 4 GrooveReading
        The A sets' grooves (`a_axis_sets`), each with its end point.
    c : sequence of 3 or 4 GrooveReading
        The triangle's grooves (C = 0, 120, 240 deg), and its reference mark (4th).
    b : sequence of 3 GrooveReading
        The B grooves (B = 0, theta2, theta3); each groove's depth is the mean over its
        profiles, taken back to one commanded Z (`b_axis_tilts`).
    length : float
        The A grooves' programmed length (m).
    theta2, theta3 : float
        The B tilts (rad).
    mark_at : array_like, shape (2,), optional
        The programmed crossing of the reference mark with the C = 0 side (m), with a mark
        (`c_axis_triangle`).
    registration : mapping, optional
        Plate ("a", "c", "b") -> the stated scatter of its microscope's registration
        (`machinesim.metrology.imperfections.RegistrationScatter`), for ``std``.

    Returns
    -------
    Identification
        ``compensation`` holds d = (dx, dy, dZ) and e with no Z shift; ``std`` the
        uncertainties propagated through the same formulas from the readings'
        (`point_sigma`, `depth_sigma`, `end_sigma`), the plates' registration and the C
        and B plates' being cut with the A sets' result
        (`machinesim.identification.tool_setting_6axis_uncertainty`).
    """
    if len(a) != 4 or len(c) not in (3, 4) or len(b) != 3:
        raise InputError(f"Expected 4 A, 3 C (and a mark) and 3 B groove readings, got "
                         f"{len(a)}, {len(c)} and {len(b)}", key="readings")

    from machinesim.identification.tool_setting_6axis_uncertainty import propagated_std

    def stages(a, c, b):
        return read_stages(a, c, b, length, theta2, theta3, mark_at)

    def values(a, c, b):
        ra, rc, rb = stages(a, c, b)
        return np.r_[ra.offset, rb.offset_z, rc.centre]

    ra, rc, rb = stages(a, c, b)
    compensation = Compensation(tool_offset=[ra.offset[0], ra.offset[1], rb.offset_z],
                                c_centre=rc.centre)
    std = propagated_std(values, a, c, b, length, registration)
    return Identification(float(z_touch), ra, rb, rc, compensation,
                          MappingProxyType(dict(zip(PARAMETERS, std.tolist(), strict=True))))


def read_stages(a: Sequence[GrooveReading], c: Sequence[GrooveReading],
                b: Sequence[GrooveReading], length: float, theta2: float, theta3: float,
                mark_at=None) -> tuple[AAxisResult, CAxisResult, BAxisResult]:
    """The three stages' results from the plates' readings (`identify`'s arguments): the A
    sets (`a_axis_sets`), the triangle (`c_axis_triangle`) and the B tilts
    (`b_axis_tilts`, each groove's depth the mean over its profiles)."""
    return (a_axis_sets(a, length),
            c_axis_triangle([g.points for g in c], mark_at),
            b_axis_tilts([g.depths.mean() for g in b], theta2, theta3,
                         [g.q_start[AXES.index("Z")] for g in b]))


# ---------------------------------------------------------------------------- compensation


def corrected_axes(q: np.ndarray, compensation: Compensation) -> np.ndarray:
    """The paper's rewrite of the NC data: axis values that put the edge where the NC data
    put it, for `machinesim.compensation.map_program`.

    ``P' = P - Ry(B) Rz(A) d + e - Rz(-C) e`` (e in xy) and ``Z' += z_shift``: then the edge
    at ``e + Rz(C) (P' + Ry(B) Rz(A) d - e)`` is ``Rz(C) P``. A, B and C are kept. Exact at
    every block end; a block that turns A, B or C while it moves is exact only at its ends.

    Parameters
    ----------
    q : ndarray, shape (N, 6)
        Axis values X Y Z A B C (m, rad), one row per block.
    compensation : Compensation

    Returns
    -------
    ndarray, shape (N, 6)
    """
    q = np.array(q, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != len(AXES):
        raise InputError(f"Expected axis values of shape (N, 6), columns {' '.join(AXES)}, "
                         f"got {q.shape}", key="q")
    d, e = compensation.tool_offset, compensation.c_centre
    a, b, c = q[:, 3], q[:, 4], q[:, 5]
    shift = -(rot_y(b) @ rot_z(a) @ d)
    shift[:, :2] += e - rot_z(-c)[:, :2, :2] @ e
    shift[:, 2] += compensation.z_shift
    q[:, :3] += shift
    return q
