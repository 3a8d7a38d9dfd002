"""Paper 004's four cases, one at a time: what each compensates and runs, and what its cut
read (`STSTurning.run_case`): the prediction before the cut, the measured profile and Sa
after it, and how much of the grid the tool did not cut (`uncut_share`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from machinesim.procedures.sts_prediction import Prediction

__all__ = ["CASES", "GRID_TOP", "PROGRAM_OF", "UNCUT_BAND", "CaseResult", "details",
           "uncut_share"]

NM, UM = 1e-9, 1e-6

#: The cases (section 5.1): what is compensated in each.
CASES = {"case_1": "none", "case_2": "tool", "case_3": "tool + program",
         "case_4": "tool + program + servo"}
#: The program each case runs (`STSTurning.compensate`): Table 4 "before" compensated for the
#: nominal nose radius, the same for the measured one, Table 4 "after" for the measured one.
PROGRAM_OF = {"case_1": "as_found", "case_2": "nose_compensated", "case_3": "modified",
              "case_4": "modified"}

#: The stock's top over the sine grid's design, m: the program cuts the grid (0 .. 100 nm)
#: 0.9 to 1 um below it.
GRID_TOP = 1 * UM
#: A point of the grid's measured line or window that reads within this (m) of the stock's
#: top was not cut (`uncut_share`): twenty times the interferometer's 0.5 nm noise, so that
#: the stock's top always reads within it, where a cut point lies 0.9 um or more below it
#: unless the tool tip is set nearly that much higher than programmed.
UNCUT_BAND = 10 * NM


@dataclass(frozen=True)
class CaseResult:
    """One case: the prediction before the cut and the measurement after it."""

    name: str
    prediction: Prediction
    measured_pv: float
    measured_r: np.ndarray
    measured_residual: np.ndarray
    sa: float
    points: int
    machining_time_s: float
    heights: tuple = field(repr=False, default=())
    #: Shares of the measured line and of the Sa window that read the stock's top
    #: (`uncut_share`): 0 when the grid was cut everywhere it was read.
    uncut_line: float = 0.0
    uncut_window: float = 0.0

    def uncut_note(self) -> str:
        """What a reader of the case's figures must know when part of it was not cut."""
        if not (self.uncut_line or self.uncut_window):
            return ""
        return (f"; {self.name}: {self.uncut_line:.0%} of the measured line and "
                f"{self.uncut_window:.0%} of the Sa window read the stock's top, uncut (the "
                "tool tip above the program there: tool.z, workpiece.z?), so its P-V is "
                "partly the stock's")


def uncut_share(heights) -> float:
    """The share of the finite ``heights`` (m) that read within `UNCUT_BAND` of the stock's
    top over the grid (`GRID_TOP`): points the tool did not cut."""
    z = np.asarray(heights, dtype=np.float64)
    z = z[np.isfinite(z)]
    return float(np.mean(z > GRID_TOP - UNCUT_BAND)) if z.size else 0.0


def details(cases, alignment) -> dict:
    """Per case: the prediction's shares and the measurement, in summary.json's units."""
    out = dict(alignment)
    for name, case in cases.items():
        p = case.prediction
        out[name] = {"compensated": CASES[name], "predicted_pv_nm": p.total / NM,
                     "predicted_program_pv_nm": p.program / NM,
                     "predicted_tool_pv_nm": p.tool / NM,
                     "predicted_servo_pv_nm": p.servo / NM,
                     "measured_pv_nm": case.measured_pv / NM, "sa_nm": case.sa / NM,
                     "uncut_line_ratio": case.uncut_line,
                     "uncut_window_ratio": case.uncut_window,
                     "points_count": case.points,
                     "machining_time_s": case.machining_time_s,
                     "profile_r_um": (case.measured_r / UM).tolist(),
                     "profile_form_error_nm": (case.measured_residual / NM).tolist()}
    x, y, z = cases["case_4"].heights
    step = max(1, x.size // 50)  # the 3-D view's map, every 2 um
    out["case_4"] |= {"window_x_um": (x[::step] / UM).tolist(),
                      "window_y_um": (y[::step] / UM).tolist(),
                      "window_height_nm": (z[::step, ::step] / NM).tolist()}
    return out
