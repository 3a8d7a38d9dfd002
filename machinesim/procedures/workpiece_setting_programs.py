"""Paper 002's compensated NC programs: a program for the ideal workpiece rewritten for the
workpiece as the probe found it, by the paper's eqs 5-7 or through the identified error
model (`machinesim.procedures.workpiece_setting` uses both; docs/procedures/
workpiece_setting.md, "Compensation")."""

from __future__ import annotations

import numpy as np

from machinesim.cam.crown import PARK
from machinesim.compensation import map_program, model_based
from machinesim.identification.workpiece_setting import (
    Identification,
    check_machine,
    eqs_5_to_7,
    identified_errors,
    nose_shift,
    program_poses,
)
from machinesim.nc import Program

__all__ = ["eqs_5_to_7_program", "model_based_program"]


def eqs_5_to_7_program(program: Program, machine, found: Identification,
                       nose_radius: float = 0.0, *, start=PARK, rounded: bool = True
                       ) -> Program:
    """Rewrite ``program`` by eqs 5-7 (`machinesim.compensation.map_program` with
    `machinesim.identification.workpiece_setting.eqs_5_to_7`).

    Parameters
    ----------
    program : Program
        Written for the ideal workpiece on the nominal machine (axes X Y Z B C).
    machine : Machine
    found : Identification
    nose_radius : float
        m: keep the nose arc's lowest point on the path (`nose_shift`); 0 keeps the tip, as
        the paper's eq 7.
    start : array-like, shape (5,)
        Axis values before the first block (default `machinesim.cam.crown.PARK`).
    rounded : bool
        Round to the machine's resolution (default; the NC text's values).
    """
    return map_program(program, machine,
                       lambda q: eqs_5_to_7(q, found.setting, found.c_centre, nose_radius),
                       start=start, rounded=rounded)


def model_based_program(program: Program, machine, found: Identification,
                        nose_radius: float = 0.0, *, start=PARK, rounded: bool = True,
                        iterations: int = 3) -> Program:
    """Rewrite ``program`` through the identified model (`identified_errors`).

    The tip route is `machinesim.compensation.model_based`. With a nose radius the point to
    keep on the path is the nose arc's lowest point along the wanted tool axis, which depends
    on the orientation reached (`nose_shift`) and so is no fixed point of the tool frame, the
    only kind `model_based` keeps (keeping the nose centre misses by 0.4 nm at 3 mrad
    settings, docs/procedures/workpiece_setting.md). So that route solves
    `Machine.axis_values` for the tip moved by `nose_shift`, ``iterations`` times, through
    `machinesim.compensation.map_program`.
    """
    check_machine(machine)
    errors = identified_errors(found)
    if nose_radius == 0.0:
        return model_based(program, machine, errors, start=start, rounded=rounded).program

    def solve(q: np.ndarray) -> np.ndarray:
        wanted, tip = program_poses(q)
        target = np.tile(np.eye(4), (len(q), 1, 1))
        target[:, :3, :3] = wanted
        target[:, :3, 3] = tip
        solution = q
        for _ in range(iterations):
            solution = machine.axis_values(target, errors, q_start=solution).q
            reached = machine.tool_pose(solution, errors)[:, :3, :3]
            target[:, :3, 3] = tip + nose_shift(wanted, reached, nose_radius)
        return solution

    return map_program(program, machine, solve, start=start, rounded=rounded)
