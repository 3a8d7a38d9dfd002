"""The honesty rule walked as an adversary would walk it: from inside each shipped procedure's
``identify`` and ``compensate`` (the procedure itself, its measurements, its `Identified`),
nothing the lab handed out (the lab, a part or report of its cuts, a workpiece it made, an
instrument) and none of the lab's truth is reachable by any attribute, public or private,
item or closure cell; a Machine's private caches apart, the door docs/lab.md names. And the
identification runs as well with the lab's truth poisoned.

Each procedure is measured once (module fixture: the slow part), then walked and identified.
"""

from __future__ import annotations

import pytest
from honesty_walk import HandingLab, doors, truth_of

from machinesim import Lab
from machinesim.realism import Realism


def _arm():
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    return ToolRotationArm(), "planer_4axis", {"tool": {"offset_um": [0.0, 3.0, 2.0]}}


def _six():
    from machinesim.procedures.tool_setting_6axis import ToolSetting6Axis

    return ToolSetting6Axis(), "robonano_ui", {"tool": {"offset_um": [3.0, 1.0, 2.0]}}


def _grooves():
    from machinesim.procedures.workpiece_setting import RobotLoadedWorkpiece

    return (RobotLoadedWorkpiece("grooves", quick=True), "robonano_a0ib",
            {"workpiece": {"delta_um": [5.0, -3.0, 2.0]}})


def _xy():
    from machinesim.machines import models_dir
    from machinesim.procedures.xy_plane_errors import XYPlaneErrors

    model = models_dir() / "errors" / "xy_plane_grooving_4axis.toml"
    return XYPlaneErrors(), "grooving_4axis", model


def _sts():
    from machinesim.procedures.sts_turning import STSTurning

    return STSTurning(), "sts_lathe", {"tool": {"offset_um": [1.0, 0.0, 0.0]}}


#: name -> (procedure, machine, injected errors), and the realism each runs with (the lathe's
#: turned parts are read without spot and registration: noise alone).
PROCEDURES = {"tool_rotation_arm": (_arm, Realism.lab()),
              "tool_setting_6axis": (_six, Realism.lab()),
              "workpiece_setting_grooves": (_grooves, Realism.lab()),
              "xy_plane_errors": (_xy, Realism.lab()),
              "sts_turning": (_sts, Realism.noise_only())}


@pytest.fixture(scope="module", params=sorted(PROCEDURES))
def measured(request):
    make, realism = PROCEDURES[request.param]
    procedure, machine, errors = make()
    lab = Lab(machine, errors, seed=5, realism=realism)
    handing = HandingLab(lab)
    measurements = procedure.measure(handing)
    return request.param, procedure, lab, handing, measurements


def test_nothing_identification_holds_leads_to_the_lab_what_it_handed_out_or_its_truth(
        measured):
    name, procedure, lab, handing, measurements = measured
    identified = procedure.identify(measurements)
    forbidden = {**handing.handed, id(handing): "the lab", **truth_of(lab)}
    found = doors({"procedure": procedure, "measurements": measurements,
                   "identified": identified}, forbidden)
    assert not found, f"{name}:\n" + "\n".join(found)
