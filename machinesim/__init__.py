"""machinesim: a virtual multi-axis ultraprecision machine tool.

Load a machine, inject the errors a real machine has, and ask where its tool edge lands:

>>> import machinesim
>>> machine = machinesim.load_machine("robonano_a0ib")
>>> errors = machinesim.ErrorModel.from_dict({"tool": {"offset_um": [5.0, 0.0, 0.0]}})
>>> machine.tool_pose([0, 0, 0, 0, 0], errors)[:3, 3]  # m, in the workpiece frame
array([5.e-06, 0.e+00, 0.e+00])
"""

from __future__ import annotations

from machinesim.errors import ComponentError, ErrorModel, ToolSetting, WorkpieceSetting
from machinesim.exceptions import MachineSimError
from machinesim.lab import Lab
from machinesim.machines import AxisSolution, Machine, list_machines, load_machine


def cut(program, machine, tool="v:90", stock="block:10x10x2", errors=None, **options):
    """Run an NC program on a machine with errors: `machinesim.cutting.cut` (see there).

    Returns ``(Part, CutReport)``. Imported on first use: the cutting engine's libraries
    (manifold3d, trimesh) load only when something is cut.
    """
    from machinesim.cutting import cut as run

    return run(program, machine, tool, stock, errors, **options)


__all__ = [
    "AxisSolution",
    "ComponentError",
    "ErrorModel",
    "Lab",
    "Machine",
    "MachineSimError",
    "ToolSetting",
    "WorkpieceSetting",
    "cut",
    "list_machines",
    "load_machine",
]
__version__ = "0.1.0"
