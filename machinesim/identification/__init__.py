"""Identification: error parameters from measurements, and nothing else.

`fit` identifies any subset of error parameters from displacement observations (weighted
Gauss-Newton on Pinocchio's error Jacobians) and reports what the observations can and
cannot separate; `plan_quality` gives the same figures for a measurement plan before it is
cut. One module per published procedure holds that paper's own formulas, named by what it
identifies:

- `tool_rotation_arm`: arm radius r and tool setting error e_ys of a tool-rotation axis
  (paper 000);
- `tool_setting_6axis`: the tool edge's offset from the A, B and C centres (paper 001);
- `workpiece_setting`: a robot-loaded workpiece's setting errors and the C centre (paper 002).

Every function here takes measurements (readings, profiles, fitted features) and returns
identified values: none receives a lab, an instrument bound to one, or the injected errors
(the honesty rule of DESIGN.md; `tests/test_lab_truth.py` scans this package).
"""

from machinesim._submodules import submodule
from machinesim.identification.fit import (
    Combination,
    Estimate,
    PlanQuality,
    fit,
    plan_quality,
)
from machinesim.identification.observations import (
    Observation,
    Observations,
    from_r_test,
    observations,
)

__all__ = ["Combination", "Estimate", "Observation", "Observations", "PlanQuality", "fit",
           "from_r_test", "observations", "plan_quality"]


def __getattr__(name: str):
    # machinesim.identification.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
