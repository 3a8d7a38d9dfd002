"""Compensation by re-shaped commands: a control's compensation table applied to a program.

Paper 003 (section III): "each errors were corrected by re-shaped command signal. The
horizontal motion error was eliminated by small shift of the cross-axis." A CNC keeps such
tables per axis: the positioning error of X and of Y (pitch-error compensation), the
straightness of each as a shift of the cross axis (cross compensation), and the squareness
as a cross shift proportional to the other axis. Together they are eq 1's map
(`machinesim.identification.xy_plane.XYPlaneMap`), and compensating means commanding

    q' = q - a(q')

so that the machine, whose actual XY point is ``q' + a(q')``, lands on ``q``. The equation
is solved by fixed-point iteration from ``q' = q``: the map's slopes are ~1e-4 at most, so
each step gains four orders and three steps reach round-off.

Beyond eq 1, the table takes the table's yaw as a cross term (``yaw_y``, from
`machinesim.procedures.xy_plane_measurements`): ``dPy += x yaw_y(y)``, the Y deviation a
point X = x from the table's centre gets as Y turns the table about Z, which controls hold as
a 2-D (bilinear) cross-compensation table.

`CompensationTable.program` rewrites an NC program through
`machinesim.compensation.map_program` (every block's end point, rounded to the machine's
resolution), so the same rules hold as for every other compensation of the project.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from machinesim.compensation import map_program, model_based
from machinesim.exceptions import InputError, MachineSimWarning
from machinesim.identification.xy_plane import Curve, XYPlaneMap
from machinesim.inverse import singular_note

__all__ = ["CompensationTable", "ModelCompensation"]

_ITERATIONS = 6


@dataclass(frozen=True, eq=False)
class CompensationTable:
    """XY compensation of a control: positioning, cross-axis straightness, squareness.

    Attributes
    ----------
    map : XYPlaneMap
        The identified deviations a(x, y) (m) the table removes.
    yaw_y : Curve or None
        The table's yaw as Y travels (rad, ``dPy / dx``, zero at Y = 0); None: eq 1 only,
        as paper 003 compensated.
    x_index, y_index : int
        Columns of X and Y in the machine's axis vector (0 and 1 on ``grooving_4axis``).
    """

    map: XYPlaneMap
    yaw_y: Curve | None = None
    x_index: int = 0
    y_index: int = 1

    def __post_init__(self) -> None:
        # x_index = y_index wrote the compensated Y over the compensated X in one column, a
        # negative index took a column from the end and True was column 1, each without a word
        if not isinstance(self.map, XYPlaneMap):
            raise InputError(f"Expected map as an XYPlaneMap, got {type(self.map).__name__}",
                             key="map")
        if self.yaw_y is not None and not isinstance(self.yaw_y, Curve):
            raise InputError(f"Expected yaw_y as a Curve or None, got "
                             f"{type(self.yaw_y).__name__}", key="yaw_y")
        for name in ("x_index", "y_index"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
                raise InputError(f"Expected {name} as a column number >= 0 of the axis "
                                 f"values, got {value!r}", key=name)
        if self.x_index == self.y_index:
            raise InputError(f"Expected X and Y in two columns, got x_index = y_index = "
                             f"{self.x_index}", key="y_index")

    def deviation(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """The deviations (dPx, dPy) the table removes at commanded (x, y), m."""
        dx, dy = self.map.deviation(x, y)
        if self.yaw_y is not None:
            dy = dy + np.asarray(x, dtype=np.float64) * self.yaw_y(y)
        return dx, dy

    def apply(self, q) -> np.ndarray:
        """Compensated axis values of nominal ones, (N, n_axes) -> (N, n_axes), SI."""
        q = np.array(q, dtype=np.float64)
        if q.ndim != 2 or q.shape[1] <= max(self.x_index, self.y_index):
            raise InputError(f"Expected axis values of shape (N, n_axes >= "
                             f"{max(self.x_index, self.y_index) + 1}), got {q.shape}",
                             key="q")
        x, y = q[:, self.x_index].copy(), q[:, self.y_index].copy()
        cx, cy = x.copy(), y.copy()
        for _ in range(_ITERATIONS):
            dx, dy = self.deviation(cx, cy)
            cx, cy = x - dx, y - dy
        out = q.copy()
        out[:, self.x_index], out[:, self.y_index] = cx, cy
        return out

    def program(self, program, machine, *, start=None, rounded: bool = True):
        """The program with every block's X and Y re-shaped by the table."""
        return map_program(program, machine, self.apply, start=start, rounded=rounded)


@dataclass(frozen=True, eq=False)
class ModelCompensation:
    """The model-based route as a control's compensation of single commands.

    ``apply`` does for any axis values what `machinesim.compensation.model_based` does for
    a program's blocks: the nominal tool pose at ``q``, then the axis values that reach it
    on the identified model (`Machine.axis_values` from ``q``). Used to measure the machine
    with the model-based compensation active, beside `CompensationTable`. Rows at a
    singularity of the axes, where the tool orientation is left unmatched, are told by a
    `MachineSimWarning` (`machinesim.inverse.singular_note`).
    """

    machine: object
    identified: object

    def apply(self, q) -> np.ndarray:
        q = np.array(q, dtype=np.float64)
        if q.ndim != 2 or q.shape[1] != len(self.machine.axes):
            raise InputError(f"Expected axis values of shape (N, {len(self.machine.axes)}), "
                             f"got {q.shape}", key="q")
        target = self.machine.tool_pose(q)
        solution = self.machine.axis_values(target, self.identified, q_start=q)
        singular = singular_note(self.machine, solution.singular_residual,
                                 lambda row: f"row {row}")
        if singular:
            warnings.warn(f"the compensated axis values: {singular}", MachineSimWarning,
                          stacklevel=2)
        return solution.q

    def program(self, program, *, start=None, rounded: bool = True):
        """The program through `machinesim.compensation.model_based`."""
        return model_based(program, self.machine, self.identified, start=start,
                           rounded=rounded).program
