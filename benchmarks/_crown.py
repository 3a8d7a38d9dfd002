"""Paper 002's crown before compensation, as the flagship measures it (seed 0, lab realism):
the lab, the procedure, the layout and the program (shared by the benchmarks that cut it)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import SimpleNamespace


def crown_errors():
    """The errors the flagship's lab cuts the crown with (its scenario's ``loads``, seed 0
    and every option at its default)."""
    path = Path(__file__).resolve().parents[1] / "scenarios" / "workpiece_setting.py"
    spec = importlib.util.spec_from_file_location("workpiece_setting_scenario", path)
    scenario = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(scenario)
    defaults = SimpleNamespace(robot_repeatability_um=None, delta_um=None, rot_deg=None,
                               crown_delta_um=None, crown_rot_deg=None, errors=None, seed=0)
    return scenario.loads(defaults)["crown"]


def crown_before():
    """(lab, procedure, layout, program) of the crown before compensation, its setting found
    from the spheres as the scenario finds it; the lab cuts each time (``reuse_cuts``
    off), so that timed runs of the same inputs cut again."""
    from machinesim import Lab, load_machine
    from machinesim.procedures.workpiece_setting import RobotLoadedWorkpiece
    from machinesim.realism import Realism

    lab = Lab(load_machine("robonano_a0ib"), crown_errors(), seed=0, realism=Realism.lab())
    lab.reuse_cuts = False
    procedure = RobotLoadedWorkpiece("crown")
    found = procedure.identify(procedure.measure(lab)).detail.found
    return lab, procedure, procedure.layout(found), procedure.nominal_program(found)
