"""machinesim: a virtual multi-axis ultraprecision machine tool.

Load a machine, inject the errors a real machine has, and ask where its tool edge lands:

>>> import machinesim
>>> machine = machinesim.load_machine("robonano_a0ib")
>>> errors = machinesim.ErrorModel.from_dict({"tool": {"offset_um": [5.0, 0.0, 0.0]}})
>>> machine.tool_pose([0, 0, 0, 0, 0], errors)[:3, 3].round(15)  # m, in the workpiece frame
array([5.e-06, 0.e+00, 0.e+00])
"""

from __future__ import annotations

import importlib

from machinesim._submodules import submodule
from machinesim.exceptions import (
    ArgumentError,
    AxisLimitError,
    ErrorModelError,
    FileError,
    HolderContactError,
    InputError,
    KinematicsError,
    MachineSimError,
    MachineSimWarning,
    ModelError,
    NCProgramError,
    NotConvergedError,
    ProgramTimeError,
    ReadOnlyError,
    SubtractionError,
    UnreachableError,
)

#: Names imported on first use (PEP 562), so that ``import machinesim.cli`` costs little:
#: the command line then catches even a Ctrl-C while numpy and Pinocchio load.
_LAZY = {
    "ComponentError": "machinesim.errors", "ErrorModel": "machinesim.errors",
    "ToolSetting": "machinesim.errors", "WorkpieceSetting": "machinesim.errors",
    "ToolGeometry": "machinesim.errors",
    "Lab": "machinesim.lab", "Realism": "machinesim.realism", "AxisSolution": "machinesim.inverse",
    "Machine": "machinesim.machines", "list_machines": "machinesim.machines",
    "load_machine": "machinesim.machines",
}


def __getattr__(name: str):
    if name not in _LAZY:
        # a subpackage or module by attribute, as the README writes it
        # (``machinesim.viewer.read_ply(...)`` after ``import machinesim``): it had been an
        # AttributeError unless something had imported machinesim.viewer already
        return submodule(__name__, name)
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


def cut(program, machine, tool="v:90", stock="block:10x10x2", errors=None, **options):
    """Run an NC program on a machine with errors: `machinesim.cutting.cut` (see there).

    Returns ``(Part, CutReport)``. Imported on first use: the cutting engine's libraries
    (manifold3d, trimesh) load only when something is cut.
    """
    from machinesim.cutting import cut as run

    return run(program, machine, tool, stock, errors, **options)


__all__ = [
    "ArgumentError",
    "AxisLimitError",
    "AxisSolution",
    "ComponentError",
    "ErrorModel",
    "ErrorModelError",
    "FileError",
    "HolderContactError",
    "InputError",
    "KinematicsError",
    "Lab",
    "Machine",
    "MachineSimError",
    "MachineSimWarning",
    "ModelError",
    "NCProgramError",
    "NotConvergedError",
    "ProgramTimeError",
    "ReadOnlyError",
    "SubtractionError",
    "UnreachableError",
    "Realism",
    "ToolGeometry",
    "ToolSetting",
    "WorkpieceSetting",
    "cut",
    "list_machines",
    "load_machine",
]
__version__ = "0.1.0"
