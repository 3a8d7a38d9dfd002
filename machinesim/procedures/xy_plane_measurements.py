"""Paper 003's laser measurements of the XY plane, taken through a `machinesim.Lab`.

The 1-D measurements along the table's centre lines (ISO 230-2 positioning of X and Y,
straightness of each read across it) at the machining point, and the two ISO 230-6 face
diagonals of the 400 mm square at the corners with the beam 120 mm above the table (paper
003 Fig. 3). The beam height is set by reading the optic on the tool mount (``tool_mount``,
25 mm above the table's top at Z = 0 on ``grooving_4axis``) with Z at 95 mm. The paper's
beam is level with its machining point ("average height of the machining point") and it
puts the diagonals' difference from eq 1's estimate on the corners against the centre lines
(the yaw term below); this machine cuts 5 mm above the table, so its beam-height diagonals
also carry the pitch over a 115 mm lever, an Abbe offset the paper did not have
(docs/procedures/xy_plane_errors.md); the tool-tip diagonals are read beside them.

The yaw of Y (the table turning about Z as it travels) moves a table point at X = x by
``x ECY(y)`` in Y: a term in both x and y that eq 1, a sum of 1-D functions, cannot hold,
and that the centre-line tests do not see. It is read as an angular interferometer with a
400 mm beam separation reads it: Y's positioning on the plate's two edge lines X = -200 and
+200 mm, their difference over the separation (``yaw_y``). The diagonals are read twice:
at beam height, as the paper did, and at the machining point (the tool tip), where the part
is cut and where the compensation puts the tool.

The map's squareness is the paper's eq 2: the first diagonal read level with the cut
against the X and Y travels of the positioning tests. Each test runs on a laser set-up of
its own (`LaserSetups`), as a lab aligns the optics again for X, for Y and for the
diagonals; with the lab's air compensation missing part of the air, each reads on a scale
of its own, and eq 2 carries ``s_x + s_y - 2 s_diagonal`` of them into the squareness, where
the two-diagonal form (ISO 230-6, kept as ``diagonal_squareness``) cancels them.

With a `machinesim.compensation_table.CompensationTable` (``table=``) the same tests are read
with it active in the control: every commanded point goes through the table, as the control's
compensation does, and the interferometer reads the machine's actual motion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from machinesim.exceptions import InputError
from machinesim.identification.xy_plane import (
    Curve,
    DiagonalReading,
    XYPlaneMap,
    squareness_of_lines,
)
from machinesim.metrology.interferometer import squareness_from_diagonal
from machinesim.metrology.iso230 import (
    PositioningEvaluation,
    evaluate_positioning,
    iso230_2_targets,
    squareness_from_diagonals,
)
from machinesim.tolerances import POSE_M

__all__ = ["BEAM_FRAME", "BEAM_Z", "DIAGONALS", "PLATE", "LaserSetups",
           "XYPlaneMeasurements", "measure_xy_plane"]

PLATE = (-0.2, 0.2)
"""The 400 mm square on the table, machine X and Y, m (table centre at 0)."""
DIAGONALS = (((0.2, 0.2), (-0.2, -0.2)), ((-0.2, 0.2), (0.2, -0.2)))
"""Paper 003's diagonals (400,400)->(0,0) and (0,400)->(400,0) mm of the plate, in X, Y."""
BEAM_FRAME = "tool_mount"
BEAM_Z = 0.095
"""Z value putting the ``tool_mount`` frame 120 mm above the table (25 mm + 95 mm)."""


@dataclass(frozen=True, eq=False)
class XYPlaneMeasurements:
    """What the interferometer gave, and eq 1's map built from it.

    Attributes
    ----------
    positioning_x, positioning_y : PositioningEvaluation
        ISO 230-2 tests of X on Y = 0 and of Y on X = 0.
    straightness_x_in_y, straightness_y_in_x : Curve
        Straightness (least-squares line removed) of X read in Y, of Y read in X.
    raw_x_in_y, raw_y_in_x : Curve
        The same read against the table's axes (optic aligned to the nominal axis), for
        `machinesim.identification.xy_plane.fit_xy_plane`.
    diagonals : tuple of PositioningEvaluation
        ISO 230-6 tests of the two diagonals (`DIAGONALS`), positions = distance from the
        start corner.
    diagonal_squareness : float
        Squareness from the two diagonals' far-end mean deviations at beam height (ISO
        230-6), the yaw's part taken out, rad: free of the laser's scale errors.
    eq2_squareness : float
        Squareness of the chords by paper 003's eq 2: the first diagonal, read level with
        the cut, against the X and Y travels of the positioning tests, the yaw's part taken
        out, rad. The map's squareness is this one, as the paper's was.
    map : XYPlaneMap
        Eq 1's map.
    yaw_y : Curve
        ``dPy / dx`` as Y travels (the table's yaw), zero at Y = 0, rad: the difference of
        Y's mean positioning on the edge lines X = +-200 mm over 400 mm.
    work_diagonals : tuple of PositioningEvaluation
        The diagonals read at the machining point (the tool tip at Z = 0).
    """

    positioning_x: PositioningEvaluation
    positioning_y: PositioningEvaluation
    straightness_x_in_y: Curve
    straightness_y_in_x: Curve
    raw_x_in_y: Curve
    raw_y_in_x: Curve
    diagonals: tuple
    diagonal_squareness: float
    eq2_squareness: float
    map: XYPlaneMap
    yaw_y: Curve
    work_diagonals: tuple

    @property
    def diagonal_deviation(self) -> float:
        """The larger diagonal systematic deviation E (ISO 230-6) at beam height, m."""
        return max(d.E for d in self.diagonals)

    @property
    def work_diagonal_deviation(self) -> float:
        """The larger diagonal systematic deviation E at the machining point, m."""
        return max(d.E for d in self.work_diagonals)

    def fit_inputs(self) -> tuple:
        """(curves, diagonals) as `machinesim.identification.xy_plane.fit_xy_plane` takes
        them: mean positioning, straightness against the table's axes, the diagonals."""
        curves = (self.map.position_x, self.map.position_y, self.raw_x_in_y, self.raw_y_in_x)
        diagonals = tuple(DiagonalReading(c, o, d.targets, d.mean, BEAM_FRAME, BEAM_Z)
                          for (c, o), d in zip(DIAGONALS, self.diagonals, strict=True))
        return curves, diagonals


@dataclass(frozen=True, eq=False)
class LaserSetups:
    """The laser interferometer as a lab sets it up for one session of the tests.

    The optics are aligned again for each axis and for the diagonals, so each is a set-up
    of its own: its own noise and, with the lab's ``air_refraction``, its own scale (the
    air its compensation misses that day). Each reads the tool point (``frame="tool_tip"``)
    but ``diagonals_120mm``, which reads the optic 120 mm above the table (`BEAM_FRAME`).

    Attributes
    ----------
    x_axis : LaserInterferometer
        X's positioning and straightness on the centre line Y = 0.
    y_axis : LaserInterferometer
        Y's positioning and straightness on X = 0, and its positioning on the edge lines
        X = +-200 mm (the yaw's two beams, one set-up).
    diagonals : LaserInterferometer
        The two face diagonals level with the cut (the steering mirror turned between
        them), as the paper's beam was.
    diagonals_120mm : LaserInterferometer
        The two face diagonals 120 mm above the table.
    """

    x_axis: object
    y_axis: object
    diagonals: object
    diagonals_120mm: object

    @classmethod
    def from_lab(cls, lab, session: str = "", resolution: float | None = None) -> LaserSetups:
        """The lab's laser set up for each test of one session, labelled by set-up and
        ``session`` (``""`` before, ``"_after"`` after compensation): set up again for
        another session, each has its own noise and, with the lab's ``air_refraction``, its
        own scale; set up again for the same session, the same draws. ``resolution``: the
        display resolution, m (None: the instrument's own, 1 nm)."""
        extra = {} if resolution is None else {"resolution": resolution}
        return cls(*(lab.laser_interferometer(label=f"{name}{session}", **extra)
                     for name in ("x_axis", "y_axis", "diagonals")),
                   lab.laser_interferometer(label=f"diagonals_120mm{session}",
                                            frame=BEAM_FRAME, **extra))


def measure_xy_plane(setups: LaserSetups, *, count: int = 21, runs: int = 5,
                     seed: int | None = 0, table=None) -> XYPlaneMeasurements:
    """Run the laser measurements and build eq 1's map.

    Parameters
    ----------
    setups : LaserSetups
        The laser as set up for each test (`LaserSetups.from_lab`).
    count : int
        Targets per test (ISO 230-2 asks at least 5 over 400 mm; paper-like 21).
    runs : int
        Runs per direction.
    seed : int or None
        Seed of the targets' ISO 230-2 offsets; None: uniformly spaced targets.
    table : CompensationTable, optional
        A compensation active in the control while measuring (the "after" tests).
    """
    if not isinstance(setups, LaserSetups):
        # the tests read on four set-ups since paper 003's eq 2 took the squareness; one
        # interferometer (or the earlier pair) would fail deep inside with no word of why
        raise InputError(f"Expected the laser's set-ups for the tests, LaserSetups(x_axis, "
                         f"y_axis, diagonals, diagonals_120mm), got "
                         f"{type(setups).__name__}", key="setups")
    along_x = _Reader(setups.x_axis, table)
    along_y = _Reader(setups.y_axis, table)
    targets = iso230_2_targets(*PLATE, count=count, rng=seed)
    pos_x = _positioning(along_x, 0, targets, runs)
    pos_y = _positioning(along_y, 1, targets, runs)
    position_x, position_y = Curve(targets, pos_x.mean), Curve(targets, pos_y.mean)
    raw_xy = Curve(targets, along_x.across(0, targets))
    raw_yx = Curve(targets, along_y.across(1, targets))
    str_xy = Curve(targets, _without_line(targets, raw_xy.values))
    str_yx = Curve(targets, _without_line(targets, raw_yx.values))
    edges = [_positioning(along_y, 1, targets, runs, other=x).mean for x in PLATE]
    yaw = (edges[1] - edges[0]) / (PLATE[1] - PLATE[0])
    yaw_y = Curve(targets, yaw - np.interp(0.0, targets, yaw))
    beam = _Reader(setups.diagonals_120mm, table, z=BEAM_Z)
    diagonals = tuple(_diagonal(beam, c, o, count, runs) for c, o in DIAGONALS)
    at_cut = _Reader(setups.diagonals, table)
    work = tuple(_diagonal(at_cut, c, o, count, runs) for c, o in DIAGONALS)
    # ISO 230-6 from the two diagonals at beam height. The first diagonal runs (0.2, 0.2)
    # -> (-0.2, -0.2): spans of the same sign; the second (-0.2, 0.2) -> (0.2, -0.2):
    # opposite signs. The yaw's part of each far-end reading is taken out (the angular
    # errors' Abbe terms at beam height are functions of one axis each, like scale errors,
    # and cancel in the difference).
    same, opposite = (d.mean[-1] - _yaw_along(yaw_y, c, o)
                      for d, (c, o) in zip(diagonals, DIAGONALS, strict=True))
    e_diag = squareness_from_diagonals(same, opposite, 0.4, 0.4)
    # The map's squareness as the paper took it (eq 2): one diagonal, read level with the
    # cut, against the X and Y travels the positioning tests read. It carries the three
    # set-ups' scales (s_x + s_y - 2 s_diagonal), which the two-diagonal form cancels.
    e_eq2 = _eq2_squareness(work[0], DIAGONALS[0], position_x, position_y, yaw_y)
    e_lines = squareness_of_lines(e_eq2, str_xy, str_yx, PLATE, PLATE)
    xy_map = XYPlaneMap(position_x, position_y, str_xy, str_yx, e_lines)
    return XYPlaneMeasurements(pos_x, pos_y, str_xy, str_yx, raw_xy, raw_yx, diagonals,
                               e_diag, e_eq2, xy_map, yaw_y, work)


def _eq2_squareness(diagonal: PositioningEvaluation, ends, position_x: Curve,
                    position_y: Curve, yaw_y: Curve) -> float:
    """Paper 003 eq 2 (derived form, `squareness_from_diagonal`): the squareness of the
    chords from one diagonal's measured length P_d and the measured X and Y travels P_x,
    P_y between its corners (the positioning tests' mean deviations added to the commanded
    spans), the yaw's part of the diagonal taken out as for the two-diagonal form, rad."""
    (x0, y0), (x1, y1) = ends
    p_x = (x1 - x0) + float(position_x(x1) - position_x(x0))
    p_y = (y1 - y0) + float(position_y(y1) - position_y(y0))
    p_d = math.dist(*ends) + float(diagonal.mean[-1]) - _yaw_along(yaw_y, *ends)
    return squareness_from_diagonal(p_d, p_x, p_y)


def _yaw_along(yaw_y: Curve, corner, opposite) -> float:
    """The part of a diagonal's far-end reading that the yaw ``x yaw_y(y)`` (in Y) makes."""
    (x0, y0), (x1, y1) = corner, opposite
    u_y = (y1 - y0) / math.dist(corner, opposite)
    return float((x1 * yaw_y(y1) - x0 * yaw_y(y0)) * u_y)


# -------------------------------------------------------------------------------- internals

class _Reader:
    """Displacements of the instrument's point between commanded XY points, the control's
    compensation (if any) applied to every command.

    The lab's interferometer moves one axis per positioning test; a compensated point moves
    both X and Y by micrometres. Each reading is therefore taken as a move along the axis
    from the compensated reference command, at the other axes of the compensated target
    (``base``), plus the remaining command difference. The reference is so read at the
    target's cross-axis command, micrometres from its own: the reading is off by the
    deviation's cross slope (squareness, straightness: ~3e-5) times that shift, ~0.1 nm
    for the errors of these machines.
    """

    def __init__(self, interferometer, table, z: float = 0.0):
        self.li = interferometer
        self.table = table
        self.n = len(interferometer.machine.axes)
        self.z = z

    def command(self, x, y) -> np.ndarray:
        q = np.zeros((np.size(x), self.n))
        q[:, 0], q[:, 1], q[:, 2] = x, y, self.z
        return q if self.table is None else self.table.apply(q)

    def along(self, k: int, targets, other: float, reference: float) -> np.ndarray:
        """Displacement along machine direction k, from the point at ``reference`` to the
        points at ``targets`` on the line (the other axis at ``other``), minus the commanded
        travel."""
        t = np.asarray(targets, dtype=np.float64)
        xy = (t, np.full_like(t, other)) if k == 0 else (np.full_like(t, other), t)
        ref = (reference, other) if k == 0 else (other, reference)
        q = self.command(*xy)
        q0 = self.command(*ref)[0]
        axis = "XY"[k]
        if self.table is None:
            return self.li.positioning(axis, t, base=q0, reference=reference).deviation
        out = np.empty(t.size)
        for i in range(t.size):
            reading = self.li.positioning(axis, [q[i, k]], base=q[i], reference=q0[k])
            out[i] = reading.deviation[0] + (q[i, k] - q0[k]) - (t[i] - reference)
        return out

    def across(self, k: int, targets) -> np.ndarray:
        """Lateral displacement (the other direction) of the axis k moving along its centre
        line, zeroed at the first target (no reference line removed)."""
        t = np.asarray(targets, dtype=np.float64)
        axis, lateral = "XY"[k], "YX"[k]
        xy = (t, np.zeros_like(t)) if k == 0 else (np.zeros_like(t), t)
        q = self.command(*xy)
        j = 1 - k
        if self.table is None:
            return self.li.straightness(axis, t, lateral, base=q[0], reference="none").deviation
        out = np.empty(t.size)
        for i in range(t.size):
            rest = q[i, j] - q[0, j]
            if q[i, k] == q[0, k]:          # the start point: only the cross shift
                out[i] = rest
                continue
            reading = self.li.straightness(axis, [q[0, k], q[i, k]], lateral, base=q[i],
                                           reference="none")
            out[i] = reading.deviation[1] + rest
        return out

    def diagonal(self, corner, opposite, positions) -> np.ndarray:
        c = np.asarray(corner, dtype=np.float64)
        span = np.asarray(opposite, dtype=np.float64) - c
        length = float(np.linalg.norm(span))
        u = span / length
        s = np.asarray(positions, dtype=np.float64)
        if self.table is None:
            base = np.zeros(self.n)
            base[2] = self.z
            return self.li.diagonal(s, c, c + span, base=base).deviation
        qc = self.command(c[0], c[1])[0]
        points = c + s[:, None] * u
        q = self.command(points[:, 0], points[:, 1])
        out = np.empty(s.size)
        for i in range(s.size):
            # A straight move from the compensated corner along the nominal diagonal to the
            # point m nearest the compensated target, then the micrometre rest q - m.
            step = float(np.dot(q[i, :2] - qc[:2], u))
            # at the corner itself the compensated command can differ from the corner's by
            # an ulp (1e-17 m): a move that short is no move (it was read as one of zero
            # length and refused)
            if step <= POSE_M:
                out[i] = float(np.dot(q[i, :2] - qc[:2], u)) - s[i]
                continue
            m = qc[:2] + step * u
            reading = self.li.diagonal([step], qc[:2], m, base=qc).deviation[0]
            out[i] = reading + step + float(np.dot(q[i, :2] - m, u)) - s[i]
        return out


def _positioning(reader: _Reader, k: int, targets, runs: int,
                 other: float = 0.0) -> PositioningEvaluation:
    """ISO 230-2 test of axis k on the line where the other axis is at ``other``."""
    up = [reader.along(k, targets, other, targets[0]) for _ in range(runs)]
    down = [reader.along(k, targets[::-1], other, targets[0])[::-1] for _ in range(runs)]
    return evaluate_positioning(targets, np.array(up), np.array(down))


def _without_line(targets, raw) -> np.ndarray:
    """The reading about its least-squares line (ISO 230-1's reference straight line)."""
    centre = targets.mean()
    slope = np.dot(targets - centre, raw - raw.mean()) / np.dot(targets - centre,
                                                                 targets - centre)
    return raw - (raw.mean() + slope * (targets - centre))


def _diagonal(reader: _Reader, corner, opposite, count: int, runs: int):
    length = math.dist(corner, opposite)
    s = np.linspace(0.0, length, count)
    up = [reader.diagonal(corner, opposite, s) for _ in range(runs)]
    down = [reader.diagonal(corner, opposite, s[::-1])[::-1] for _ in range(runs)]
    return evaluate_positioning(s, np.array(up), np.array(down))
