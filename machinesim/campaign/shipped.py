"""The procedures a campaign ships with (`PROCEDURES`): each one's machine, how it is built,
its paper's default errors, its lab parameters and the error model they are set on; and the
SI unit of a parameter a campaign of one varies (`parameter_unit`, `spec_parameter_unit`).

What a campaign runs is `machinesim.campaign.spec.CampaignSpec`; one trial of it,
`machinesim.campaign.trials.run_trial`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from machinesim.campaign.distributions import LAB_PARAMETERS
from machinesim.exceptions import InputError, brief
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = ["PROCEDURES", "ProcedureEntry", "error_model_file", "parameter_unit",
           "spec_parameter_unit"]


def _tool_rotation_arm(options):
    from machinesim.procedures.tool_rotation_arm import ToolRotationArm

    return ToolRotationArm()


def _tool_rotation_arm_defaults(machine) -> dict:
    from machinesim.identification.tool_rotation_arm import arm_radius

    # paper 000: r = 120.555 mm, e_ys = -178 um (scenarios/tool_rotation_arm.py)
    return {"tool.y": -178.0 * M_PER_UM, "tool.z": -(120.555 * M_PER_MM - arm_radius(machine))}


def _workpiece(experiment: str):
    def build(options):
        from machinesim.procedures.workpiece_setting import RobotLoadedWorkpiece

        return RobotLoadedWorkpiece(experiment, quick=options.get("quick", False))
    return build


def _grooves_rapids_clear(errors) -> None:
    """Refuse a drawn landing of the grooves' block that the groove program's rapids would
    run into (`machinesim.cam.crown.groove_rapids_crash`): a crash, and a cut of thousands
    of tiny sweeps, rather than a trial."""
    from machinesim.cam.crown import groove_rapids_crash

    crash = groove_rapids_crash(errors.workpiece)
    if crash is not None:
        raise InputError(f"the drawn landing sets the grooves' block "
                         f"{errors.workpiece.delta[2] * 1e6:.1f} um high: {crash}, so the "
                         "rapids would run into the block (a crash on a real machine); the "
                         "trial was not cut")


def _tool_setting_6axis(options):
    from machinesim.procedures.tool_setting_6axis import ToolSetting6Axis

    return ToolSetting6Axis()


def _tool_setting_defaults(machine) -> dict:
    # paper 001: the scenario's defaults (round values of the paper's order)
    from machinesim.procedures.tool_setting_6axis import DEFAULT_INJECTED

    return dict(DEFAULT_INJECTED)


def _xy_plane_errors(options):
    from machinesim.procedures.xy_plane_errors import XYPlaneErrors

    return XYPlaneErrors()


def _xy_plane_base():
    """Paper 003's error model: its position-dependent tables (component errors) can only
    be varied where the model already has them, so the trial starts from this file."""
    from machinesim.machines import models_dir

    return error_model_file(models_dir() / "errors" / "xy_plane_grooving_4axis.toml")


#: Error model files read in this process: path -> (the file's bytes, its model).
_MODEL_FILES: dict[Path, tuple[bytes, Any]] = {}


def error_model_file(path):
    """``ErrorModel.from_toml(path)``, parsed once per process while the file's bytes stay
    the same: every trial of paper 003 parsed its base model anew (2.4 ms a trial: TOML,
    units, the tables' checks), where reading the 3 kB to compare them takes microseconds.
    An edited file is read again. The model is immutable (frozen, read-only arrays;
    `ErrorModel.with_parameters` makes a new one), so every trial may share it."""
    from machinesim.errors import ErrorModel

    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError:  # from_toml refuses it, naming the file and why
        return ErrorModel.from_toml(path)
    cached = _MODEL_FILES.get(path)
    if cached is not None and cached[0] == raw:
        return cached[1]
    model = ErrorModel.from_toml(path)
    _MODEL_FILES[path] = (raw, model)
    return model


def _no_errors():
    from machinesim.errors import ErrorModel

    return ErrorModel()


@dataclass(frozen=True)
class ProcedureEntry:
    """A procedure a campaign can run: its machine, how to build it, its default errors
    (the paper's, SI), default lab parameters (`LAB_PARAMETERS`), the error model those
    parameters are set on (`base`: no errors unless the procedure needs tables), and
    whether ``--quick`` changes what it measures (`quick`), and a check of each trial's
    error model before it runs (`check`: raises `InputError` for a model the procedure's
    programs cannot cut, which fails that trial at once)."""

    machine: str
    build: Callable[[Mapping], Any]
    defaults: Callable[[Any], dict] = field(default=lambda machine: {})
    lab: Mapping[str, float] = field(default_factory=dict)
    about: str = ""
    base: Callable[[], Any] = _no_errors
    quick: bool = False
    check: Callable[[Any], None] | None = None


#: Procedures by campaign name (``machinesim campaign NAME``).
PROCEDURES = {
    "tool_rotation_arm": ProcedureEntry(
        "planer_4axis", _tool_rotation_arm, _tool_rotation_arm_defaults,
        about="paper 000: r and e_ys of a planer's tool-rotation arm (default errors: the "
        "paper's r = 120.555 mm, e_ys = -178 um)"),
    "workpiece_setting": ProcedureEntry(
        "robonano_a0ib", _workpiece("crown"), lab={"robot.repeatability": 30.0 * M_PER_UM},
        quick=True, about="paper 002: a robot-loaded workpiece's setting and the C centre, the "
        "crown before and after (default: the robot's landing, repeatability 30 um)"),
    "workpiece_setting_grooves": ProcedureEntry(
        "robonano_a0ib", _workpiece("grooves"), lab={"robot.repeatability": 30.0 * M_PER_UM},
        check=_grooves_rapids_clear,
        about="paper 002, section 3.1: the same identification, the crossing grooves"),
    "tool_setting_6axis": ProcedureEntry(
        "robonano_ui", _tool_setting_6axis, _tool_setting_defaults,
        about="paper 001: the tool edge's offset from the A, B, C centres (default errors: "
        "Table 1's)"),
    "xy_plane_errors": ProcedureEntry(
        "grooving_4axis", _xy_plane_errors, base=_xy_plane_base,
        about="paper 003: the XY plane's 2-D errors, diagonals, C squareness and pyramids "
        "(default errors: models/errors/xy_plane_grooving_4axis.toml)"),
}


def spec_parameter_unit(spec: Mapping, name: str) -> str:
    """`parameter_unit` of a campaign's spec (campaign.json's, `CampaignSpec.describe`): a
    user's procedure's campaign holds its machine and error model (``errors``, SI) there."""
    if "machine" not in spec:
        return parameter_unit(spec["procedure"], name)
    if name in LAB_PARAMETERS:
        return {"length": "m", "angle": "rad"}[LAB_PARAMETERS[name]]
    from machinesim.errors import ErrorModel

    return ErrorModel.from_dict(spec["errors"], source="campaign.json").parameter_unit(name)


def parameter_unit(procedure: str, name: str) -> str:
    """The SI unit of parameter ``name`` in a campaign of ``procedure``: a lab parameter's
    (`LAB_PARAMETERS`, whose kinds are all lengths: m) or the error model's
    (`machinesim.errors.ErrorModel.parameter_unit` on the procedure's base model, which says
    whether a component entry is a table's value, m or rad, or a polynomial's coefficient
    k >= 1, per m**k or rad**k: the name alone does not).

    Raises
    ------
    InputError
        For a procedure not in `PROCEDURES`.
    ErrorModelError
        For a name that is no parameter of the base model (`ErrorModel.parameter_unit`).
    """
    if procedure not in PROCEDURES:
        raise InputError(f"procedure {brief(repr(procedure))}; expected one of "
                         f"{', '.join(PROCEDURES)}", key="procedure")
    if name in LAB_PARAMETERS:
        return {"length": "m", "angle": "rad"}[LAB_PARAMETERS[name]]
    return PROCEDURES[procedure].base().parameter_unit(name)
