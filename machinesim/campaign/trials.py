"""One trial of a campaign: draw its errors and noise seed, run the procedure, keep the numbers.

Trial ``i`` of a campaign with seed ``s`` lives entirely in the seed sequence
``SeedSequence(s).spawn(N)[i]`` (equal to ``SeedSequence(s, spawn_key=(i,))``, whatever N):

- each varied parameter draws from its own stream, ``stream(child, "campaign", name)``
  (`machinesim.streams`), so adding or fixing another parameter changes nothing here;
- the robot's landing (when ``robot.repeatability`` is set) from
  ``stream(child, "campaign", "robot")``;
- the lab gets ``child`` as its seed, so every instrument's noise stream is
  ``stream(child, kind, label)``.

Nothing depends on the process, the worker or the order in which trials run: a trial is the
same with 1, 2 or 8 workers (the per-worker seeding mistake, where each worker seeds its own
generator and a trial's draws depend on which worker took it, cannot happen: no generator
lives outside a trial).

`run_trial(spec, i)` is a plain function of picklable arguments, for Dask workers.
"""

from __future__ import annotations

import contextlib
import difflib
import math
import re
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from machinesim.campaign.distributions import (
    INSTRUMENTS,
    LAB_PARAMETERS,
    Distribution,
    checked,
    parameter_kind,
    refuse_beyond_model,
)
from machinesim.exceptions import InputError, MachineSimError, MachineSimWarning, brief
from machinesim.experiment import Evaluation, Identified, run
from machinesim.streams import stream
from machinesim.units import M_PER_MM, M_PER_UM

__all__ = ["MAX_TRIALS", "PROCEDURES", "CampaignSpec", "IdentificationOnly", "ProcedureEntry",
           "check_flag", "kept_warnings", "parameter_unit", "run_trial", "spec_parameter_unit",
           "trial_seed", "trials_refused"]


#: Most trials a campaign takes (docs/campaigns.md): a trial is seconds to minutes of CPU and
#: one file, so 100000 trials are already days on a cluster; a larger N is a typo, refused at
#: once (it used to leave the command silent for minutes, looking for that many trial files).
MAX_TRIALS = 100_000


def trials_refused(trials) -> str:
    """The message refusing ``trials`` as a campaign's N."""
    return (f"--trials {trials!r}; expected a whole number from 1 to {MAX_TRIALS} (the most "
            "trials a campaign takes, docs/campaigns.md)")


def check_flag(value, name: str) -> None:
    """Refuse a switch given as anything but True or False: ``noise="off"`` (the command's
    ``--noise off`` written in Python) is a true string, and ran every trial with noise."""
    if not isinstance(value, bool | np.bool_):
        raise InputError(f"{name}={value!r}; expected True or False", key=name)


# ------------------------------------------------------------------------------ procedures


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


class IdentificationOnly:
    """A procedure's measurement and identification alone (a probing-only trial): no
    compensation, no test pieces after, so no figures; the identified values and their
    errors are the trial's result."""

    def __init__(self, procedure) -> None:
        self.procedure = procedure
        self.name = f"{procedure.name}/identification"
        self.paper = getattr(procedure, "paper", "")
        self.lab_uses = {"measure": tuple(procedure.lab_uses.get("measure", ())),
                         "evaluate": ()}

    def measure(self, lab):
        return self.procedure.measure(lab)

    def identify(self, measurements) -> Identified:
        return self.procedure.identify(measurements)

    def compensate(self, identified: Identified) -> dict:
        return {}

    def evaluate(self, lab, identified: Identified, programs) -> Evaluation:
        return Evaluation(figures=())


class _LabWithInstruments:
    """The lab, its instruments built with the campaign's noise ``sigma`` (``options`` given
    by the procedure still win, and so does an ``objective``'s own noise: paper 002 reads
    its crown through the 10x, `machinesim.realism.OBJECTIVE_10X`). Everything else is the
    lab's own."""

    def __init__(self, lab, sigmas: Mapping[str, float]) -> None:
        self._lab = lab
        for kind, sigma in sigmas.items():
            setattr(self, kind, self._instrument(getattr(lab, kind), sigma))

    @staticmethod
    def _instrument(make, sigma):
        def instrument(*args, **options):
            if options.get("objective") is None:
                options.setdefault("sigma", sigma)
            return make(*args, **options)
        return instrument

    def __getattr__(self, name):
        return getattr(self._lab, name)


# ----------------------------------------------------------------------------------- spec


@dataclass(frozen=True)
class CampaignSpec:
    """What a campaign runs: everything a trial needs, picklable, checked when built.

    Parameters
    ----------
    procedure : str, or a procedure class or object
        A key of `PROCEDURES`; or a user's own procedure (docs/procedures/your_own.md,
        `machinesim.campaign.own`): a ``"package.module:ClassName"`` reference, the class or
        an instance. Kept as the key or the reference (a class's or object's
        ``module:qualname``); the class or object given is kept as `given`.
    trials : int
        N, the number of trials (1 .. `MAX_TRIALS`).
    vary : tuple of (str, Distribution)
        Parameters and their distributions, SI; on top of the procedure's defaults.
    seed : int
        The campaign's seed (non-negative).
    noise : bool
        Instrument noise on (default).
    identify_only : bool
        Run `IdentificationOnly` (a probing-only trial) instead of the whole procedure.
    quick : bool
        The crown's smaller windows; refused for a procedure it changes nothing in (every
        one but ``workpiece_setting``), and with ``identify_only`` (no crown is read).
    machine_name : str, optional
        A user's procedure's machine (`machinesim.load_machine`'s name); refused for a
        shipped one, which has its own.
    errors : optional
        A user's procedure's errors, the model the trials' ``vary`` is set on: what `Lab`
        takes (an `ErrorModel`, a dict in the TOML layout, a TOML path; None: no errors),
        kept as an `ErrorModel`; refused for a shipped procedure, whose defaults are its
        paper's.
    given : optional
        The user's procedure class or object, run in place of importing the reference.
    """

    procedure: Any
    trials: int
    vary: tuple[tuple[str, Distribution], ...] = ()
    seed: int = 0
    noise: bool = True
    identify_only: bool = False
    quick: bool = False
    machine_name: str | None = None
    errors: Any = None
    given: Any = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        self._procedure()
        if isinstance(self.trials, bool) or not isinstance(self.trials, int | np.integer) \
                or not 1 <= self.trials <= MAX_TRIALS:
            raise InputError(trials_refused(self.trials), key="--trials")
        object.__setattr__(self, "trials", int(self.trials))
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer) \
                or self.seed < 0:
            raise InputError(f"--seed {self.seed!r}; expected a whole number >= 0",
                             key="--seed")
        object.__setattr__(self, "seed", int(self.seed))
        for flag in ("noise", "identify_only", "quick"):
            check_flag(getattr(self, flag), flag)
            object.__setattr__(self, flag, bool(getattr(self, flag)))
        if self.quick and (self.identify_only or not self.entry.quick):
            takes = ", ".join(name for name, entry in PROCEDURES.items() if entry.quick)
            why = ("--identify-only reads no crown" if self.identify_only
                   else f"{self.procedure} has no crown windows to shrink")
            raise InputError(f"--quick changes nothing here ({why}); it is for {takes} "
                             "(the crown's smaller measuring windows)", key="--quick")
        vary = tuple((str(n), d) for n, d in self.vary)
        names = [n for n, _ in vary]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise InputError(f"--vary {', '.join(twice)} given more than once", key="--vary")
        for name, dist in vary:
            if not isinstance(dist, Distribution):
                raise InputError(f"--vary {brief(name)}: expected a Distribution, got "
                                 f"{type(dist).__name__}", key="--vary")
        # one built in Python passes parse_distribution's checks too, and gets a text
        vary = tuple((name, checked(name, dist)) for name, dist in vary)
        object.__setattr__(self, "vary", vary)
        errors = self.error_parameters()  # the base model read and checked once, not twice
        known = set(errors) | set(LAB_PARAMETERS)
        used = self._parameters(errors)
        what = self.procedure + " --identify-only" * self.identify_only
        for name in names:
            if name not in known:  # the list: what may vary here, not what is then refused
                close = difflib.get_close_matches(name, used, n=1)
                raise InputError(
                    f"--vary {brief(name)}: not a parameter of {self.entry.machine} nor of the "
                    f"lab{f' (did you mean {close[0]}?)' if close else ''}; expected one of the "
                    f"parameters {what} uses: {_listed(used)}", key="--vary")
        base = self.entry.base()
        for name in names:  # a polynomial's coefficient k >= 1: m/m**k, no --vary unit
            if name.startswith("component.") and parameter_kind(name, base) is None:
                raise InputError(
                    f"--vary {name}: a polynomial's coefficient, in "
                    f"{base.parameter_unit(name)} (SI), which a distribution's units (a "
                    "length or an angle) cannot give; expected a table's entry, a location "
                    "error, or the polynomial's coefficient 0", key="--vary")
        silent = [name for name in names if name.endswith(".sigma") and not self.noise]
        if silent:  # noise off: every instrument reads exact values, whatever its sigma
            raise InputError(f"--vary {', '.join(silent)}: with --noise off no instrument has "
                             "noise, so its sigma changes nothing; expected --noise on, or no "
                             "instrument's sigma", key="--vary")
        for name in names:
            if name not in used:
                why = _UNUSED.get(_head(name),
                                  f"it reads with no {_head(name)} at the lab's noise")
                raise InputError(f"--vary {name}: {what} never reads it ({why}); expected one "
                                 f"of the parameters {what} uses: {_listed(used)}",
                                 key="--vary")
        refuse_beyond_model(vary, base)  # before any trial fails on it

    def _procedure(self) -> None:
        """Check `procedure` (and for a user's own, `machine_name` and `errors`), keeping
        it as a key or a reference."""
        from machinesim.campaign import own

        procedure = self.procedure
        ours = isinstance(procedure, str) and procedure in PROCEDURES
        if ours:
            for key in ("machine_name", "errors"):
                if getattr(self, key) is not None:
                    raise InputError(
                        f"{key.removesuffix('_name')}={brief(repr(getattr(self, key)))} is for "
                        f"a procedure of your own; {procedure} runs on "
                        f"{PROCEDURES[procedure].machine} with its paper's errors (vary them "
                        "with --vary)", key=key.removesuffix("_name"))
            return
        reference, given, errors = own.accepted(procedure, self.given, self.machine_name,
                                                self.errors, shipped=PROCEDURES)
        object.__setattr__(self, "procedure", reference)
        object.__setattr__(self, "given", given)
        object.__setattr__(self, "errors", errors)
        self.build()  # a procedure, checked: refused now rather than in every trial

    @property
    def own(self) -> bool:
        """Whether this is a user's own procedure (not one of `PROCEDURES`)."""
        return self.machine_name is not None

    def _own_build(self, options):
        from machinesim.campaign import own

        given = self.given if self.given is not None else own.resolve(self.procedure)
        return own.fresh(given, self.procedure)

    @property
    def entry(self) -> ProcedureEntry:
        if self.own:
            errors = self.errors
            return ProcedureEntry(self.machine_name, self._own_build,
                                  base=lambda: errors, about=f"your own: {self.procedure}")
        return PROCEDURES[self.procedure]

    @property
    def machine(self):
        from machinesim.machines import load_machine

        return _machine(self.entry.machine, load_machine)

    def error_parameters(self) -> tuple[str, ...]:
        """The machine's error parameters on the procedure's base model (`ProcedureEntry.base`):
        its component tables' entries among them (paper 003's)."""
        return tuple(self.machine.parameter_names(self.entry.base()))

    def parameters(self) -> tuple[str, ...]:
        """The parameters this campaign may vary, sorted: every error parameter of the
        machine the lab sets into its cuts and readings, and of the lab parameters
        (`LAB_PARAMETERS`) and ``tool_geometry.nose_radius`` those the procedure reads, as
        its ``lab_uses`` declares them (`machinesim.experiment.LAB_USES`; with
        ``identify_only``, its measurement's alone)."""
        return self._parameters(self.error_parameters())

    def _parameters(self, error_parameters: tuple[str, ...]) -> tuple[str, ...]:
        from machinesim.experiment import LAB_USES

        uses = {use for step in self.build().lab_uses.values() for use in step}
        known = [*error_parameters, *LAB_PARAMETERS]
        return tuple(sorted(name for name in known
                            if _head(name) not in LAB_USES or _head(name) in uses))

    def build(self):
        """The procedure to run (`IdentificationOnly` around it with ``identify_only``)."""
        procedure = self.entry.build({"quick": self.quick})
        return IdentificationOnly(procedure) if self.identify_only else procedure

    def describe(self) -> dict:
        """The spec as plain values (campaign.json; the resume check compares it)."""
        described = {"procedure": self.procedure, "seed": self.seed, "noise": self.noise,
                     "identify_only": self.identify_only, "quick": self.quick,
                     "vary": {n: d.text for n, d in self.vary}}
        if self.own:  # what a user's procedure's campaign is besides (a shipped one's: fixed)
            described.update(name=self.entry.build({}).name, machine=self.machine_name,
                             errors=self.errors.to_dict())
        return described


#: Why a procedure that does not declare a use (`machinesim.experiment.LAB_USES`) never
#: reads its parameter; an instrument's: it reads with no such instrument at the lab's noise.
_UNUSED = {"robot": "no robot loads its workpiece",
           "tool_geometry": "it cuts with no tool that has a nose radius"}


def _listed(names) -> str:
    """``names`` for a message, a table's entries as one range each: paper 003's 128
    parameters read ``component.C.EAC[0..16], ...``, not each of the 17 entries (a message of
    2500 characters that hid the few other names)."""
    ranges: dict[str, list[int]] = {}
    out: list[str] = []
    for name in names:
        match = _ENTRY.fullmatch(name)
        if match is None:
            out.append(name)
            continue
        if match[1] not in ranges:
            ranges[match[1]] = []
            out.append(match[1])
        ranges[match[1]].append(int(match[2]))
    return ", ".join(_entries(name, ranges[name]) if name in ranges else name for name in out)


_ENTRY = re.compile(r"(component\.\w+\.\w+)\[(\d+)\]")


def _entries(table: str, indices: list[int]) -> str:
    indices = sorted(indices)
    if indices == list(range(indices[0], indices[-1] + 1)) and len(indices) > 1:
        return f"{table}[{indices[0]}..{indices[-1]}]"
    return ", ".join(f"{table}[{k}]" for k in indices)


def _head(name: str) -> str:
    return name.partition(".")[0]


_MACHINES: dict[str, Any] = {}


def _machine(name: str, load):
    # one load per process: a worker running many trials parses the URDF once
    if name not in _MACHINES:
        _MACHINES[name] = load(name)
    return _MACHINES[name]


def trial_seed(seed: int, i: int) -> np.random.SeedSequence:
    """``SeedSequence(seed).spawn(N)[i]`` for any N > i."""
    return np.random.SeedSequence(seed, spawn_key=(i,))


def _landing(repeatability: float, rng) -> dict:
    from machinesim.loading import RobotLoader

    try:
        setting = RobotLoader(repeatability).land(rng)
    except MachineSimError as error:  # a repeatability of metres lands the part metres off
        raise InputError(f"the robot's landing at robot.repeatability "
                         f"{repeatability / M_PER_UM:g} um: {getattr(error, 'message', error)}",
                         key="robot.repeatability") from None
    out = {f"workpiece.{a}": float(v) for a, v in zip("xyz", setting.delta, strict=True)}
    out.update({f"workpiece.{a}": float(getattr(setting, a))
                for a in ("alpha", "beta", "gamma")})
    return out


def _drawn(spec: CampaignSpec, i: int) -> dict:
    """Trial ``i``'s values of the varied parameters, SI: a lab parameter's normal draw in
    the 0.13 % below zero as the zero the lab takes (the Dataset's ``drawn`` is what the
    trial ran with, not a negative noise)."""
    child = trial_seed(spec.seed, i)
    drawn = {name: dist.draw(stream(child, "campaign", name)) for name, dist in spec.vary}
    return {name: max(value, 0.0) if name in LAB_PARAMETERS else value
            for name, value in drawn.items()}


def draw(spec: CampaignSpec, i: int) -> tuple[dict, dict, dict]:
    """Trial ``i``'s draws: ``(drawn, errors, lab)``: the varied parameters' values, the
    error parameters injected (defaults, robot landing, drawn: later wins) and the lab
    parameters, all SI."""
    drawn = _drawn(spec, i)
    return (drawn, *_set_up(spec, i, drawn))


def _set_up(spec: CampaignSpec, i: int, drawn: dict) -> tuple[dict, dict]:
    """``(errors, lab)`` of trial ``i`` whose varied parameters drew ``drawn`` (`draw`)."""
    child = trial_seed(spec.seed, i)
    lab = {**spec.entry.lab, **{n: v for n, v in drawn.items() if n in LAB_PARAMETERS}}
    errors = dict(spec.entry.defaults(spec.machine))
    if "robot.repeatability" in lab:
        errors.update(_landing(lab["robot.repeatability"], stream(child, "campaign", "robot")))
    errors.update({n: v for n, v in drawn.items() if n not in LAB_PARAMETERS})
    return errors, lab


def run_trial(spec: CampaignSpec, i: int) -> dict:
    """Run trial ``i`` of ``spec``: a record of plain values (JSON-ready but for NaN).

    Returns
    -------
    dict
        ``trial``, ``drawn`` (varied parameters, SI), ``injected`` (`Result.injected`: the
        identified parameters' true values, the injected model's other non-zero ones),
        ``identified`` (name -> [value, std]),
        ``figures`` (name -> [unit, before, after, after_std]; after_std NaN where the
        procedure states none), ``notes`` (`Result.notes`: what the identification's fits
        said a reader should know before trusting the values, such as readings that do not
        fit the model; empty for a failed trial), ``elapsed_s``, ``error`` (None, or the
        message of the `MachineSimError` the trial ended with: a failed identification is a
        result too; of any other exception, its type and message said as a fault of
        machinesim, with where it was raised, `unexpected`), ``warnings`` (the messages of
        the `MachineSimWarning` s raised in the trial, kept rather than shown: for the
        campaign's process to show, `kept_warnings`).
    """
    began = time.perf_counter()
    drawn = _drawn(spec, i)  # once: the record's are the lab's (they were drawn twice)
    record = {"trial": int(i), "drawn": drawn, "injected": {}, "identified": {},
              "figures": {}, "notes": [], "elapsed_s": math.nan, "error": None,
              "warnings": []}
    if spec.own:  # the reference, as campaign.json has it (a shipped key: campaign.json's alone)
        record["procedure"] = spec.procedure
    with kept_warnings(record["warnings"]):
        _run(spec, i, drawn, record)
    record["elapsed_s"] = time.perf_counter() - began
    return record


@contextlib.contextmanager
def kept_warnings(kept: list[str]):
    """Within the block, the message of each `MachineSimWarning` raised goes into ``kept``
    (each once) instead of being shown; any other warning is shown as before.

    A Dask worker showed the machine's warning (rotary limits that read as degrees) in
    Python's own form, file and line of machinesim's source, once per worker process and
    after the campaign's own one line; the campaign's process shows a trial's ``kept``
    as it shows its own (`machinesim.campaign.runner`). Not for threads that run trials
    side by side (a worker of several threads): Python's warning state is the process's.
    """
    with warnings.catch_warnings():
        show = warnings.showwarning

        def keep(message, category, filename, lineno, file=None, line=None):
            if not issubclass(category, MachineSimWarning):
                show(message, category, filename, lineno, file, line)
            elif str(message) not in kept:
                kept.append(str(message))

        warnings.showwarning = keep
        yield


def _run(spec: CampaignSpec, i: int, drawn: dict, record: dict) -> None:
    """Run trial ``i`` (`run_trial`), filling ``record``."""
    from machinesim.lab import Lab

    # outside the try: a user's procedure this process cannot import or make (a worker
    # without its module) is no result of this trial's draws, and ends the campaign with
    # the trials kept, rather than failing every trial for good
    procedure = spec.build()
    try:  # a landing out of the error model's range fails its trial, not the campaign
        errors, lab_parameters = _set_up(spec, i, drawn)
        model = spec.entry.base().with_parameters(errors)
        if spec.entry.check is not None and not spec.identify_only:
            spec.entry.check(model)
        lab = Lab(spec.machine, model, noise=spec.noise, seed=trial_seed(spec.seed, i))
        sigmas = {kind: lab_parameters[f"{kind}.sigma"] for kind in INSTRUMENTS
                  if f"{kind}.sigma" in lab_parameters}
        result = run(procedure, _LabWithInstruments(lab, sigmas) if sigmas else lab)
    except MachineSimError as error:
        record["error"] = f"{type(error).__name__}: {error}"
    except MemoryError:
        # the machine's memory, not this trial's draws (other trials ran beside it, under
        # the command's cap): no record, so that the campaign ends as out of memory and the
        # same command, resumed, runs this trial again. Kept as a failure it had been said
        # to be "a fault of machinesim ... please report it" and skipped for good on resuming
        raise
    except Exception as error:  # a fault this trial's draws met: its failure, `unexpected`
        record["error"] = unexpected(error)
    else:
        record["injected"] = {n: float(v) for n, v in result.injected.items()}
        record["identified"] = {n: [float(v), float(s)] for n, (v, s)
                                in result.identified.items()}
        record["figures"] = {f.name: [f.unit, _float(f.before), _float(f.after),
                                      _float(f.after_std)] for f in result.figures}
        record["notes"] = [str(note) for note in result.notes]


def _float(value) -> float:
    return math.nan if value is None else float(value)


def unexpected(error: Exception) -> str:
    """A trial's failure message for an ``error`` that is no `MachineSimError` (a
    ZeroDivisionError, numpy's LinAlgError): a fault of machinesim that this trial's draws
    met, said as such with the line it was raised at, so that the report names it and the
    campaign goes on. It ended the whole campaign in a traceback, and the same command,
    resumed, ran the same trial into it again: a campaign that could never finish."""
    import traceback

    frames = traceback.extract_tb(error.__traceback__)
    where = ""
    if frames:
        frame = frames[-1]
        path = Path(frame.filename)
        shown = ("/".join(path.parts[path.parts.index("machinesim"):])
                 if "machinesim" in path.parts else path.name)
        where = f", raised at {shown}:{frame.lineno} in {frame.name}"
    return (f"{type(error).__name__}: {brief(str(error)) or '(no message)'} (not a "
            f"MachineSimError: a fault of machinesim met by this trial's draws{where}; "
            "please report it with the campaign's command)")
