"""The form error of a slow-tool-servo cut, predicted before cutting (paper 004, step 4 of
Fig. 14, and Fig. 16's share of each factor).

From what the lab can know before it cuts, never from its truth:

* the program (its tool tips, compensated for some nose radius);
* the tool errors identified from a test cut (dx, dy, the nose radius);
* the follow-up error the control's encoders recorded for this program
  (`machinesim.metrology.encoders.Encoders.record_turning`);
* the nominal machine.

Each figure is the profile along theta = 0 (`sts_plans.MEASURE_LINE`) against the design after
the best fit of piston and tilt, as the measurement is evaluated:

* ``total``: the turning engine along the encoder positions, through the nominal machine with
  the identified tool setting, with the tool as measured;
* ``program``: the engine along the commanded tips with a perfect tool (eqs 10-11 on the
  machined surface: interpolation, point spacing, cusps);
* ``tool``: the exact forms of eqs 12-20 (`machinesim.cutting.tool_form_error`) of the
  identified dx, dy and the nose radius left uncompensated, added;
* ``servo``: the engine along the encoder positions minus the engine along the commands.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machinesim.cutting.tool_form_error import (
    alignment_error_x,
    alignment_error_y,
    nose_radius_error,
)
from machinesim.cutting.turning import edge_path_from_poses, turned_heights
from machinesim.errors import ErrorModel, ToolSetting
from machinesim.procedures.sts_plans import MEASURE_LINE, profile_error

__all__ = ["Prediction", "predict"]


@dataclass(frozen=True)
class Prediction:
    """Predicted P-V form errors along the measured profile, m (module docstring)."""

    total: float
    program: float
    tool: float
    servo: float
    residual: np.ndarray


def _line() -> np.ndarray:
    (x0, _), (x1, _), step = MEASURE_LINE
    return x0 + step * np.arange(int(np.floor((x1 - x0) / step + 1e-9)) + 1)


def _heights(machine, axes, errors, radius: float, r: np.ndarray) -> np.ndarray:
    path = edge_path_from_poses(machine.tool_pose(axes, errors), radius)
    return np.asarray(turned_heights(path, radius, r, np.zeros_like(r)))


def predict(machine, design, recording, known, nose_radius: float,
            compensated_radius: float) -> Prediction:
    """The prediction for one program (module docstring).

    Parameters
    ----------
    machine : Machine
        The lathe (nominal: its errors are what the prediction does not know).
    design : Design
    recording : EncoderReading
        The encoders' record of the program (commands and positions, the machine's axes).
    known : TurnedToolErrors
        The tool errors as identified.
    nose_radius : float
        The tool's nominal nose radius, m.
    compensated_radius : float
        The nose radius the program was compensated for, m.
    """
    recording.check_machine(machine)
    r = _line()
    zero = np.zeros_like(r)
    target = design(r, zero)
    commanded = np.asarray(recording.commanded)
    reached = np.asarray(recording.position)
    tool_radius = nose_radius + known.d_radius
    identified = ErrorModel(tool=ToolSetting([known.dx, known.dy, 0.0]))
    total = profile_error(r, _heights(machine, reached, identified, tool_radius, r), target)
    ideal = _heights(machine, commanded, None, compensated_radius, r)
    program = profile_error(r, ideal, target).pv
    servo = profile_error(r, _heights(machine, reached, None, compensated_radius, r), ideal).pv
    left = tool_radius - compensated_radius
    tool_form = (alignment_error_x(design, r, zero, known.dx)
                 + alignment_error_y(design, r, zero, known.dy)
                 + nose_radius_error(design, r, zero, left))
    tool = profile_error(r, target + tool_form, target).pv
    return Prediction(total.pv, program, tool, servo, total.residual)
