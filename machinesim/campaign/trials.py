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

`run_trial(spec, i)` is a plain function of picklable arguments, for Dask workers. What a
campaign runs is `machinesim.campaign.spec.CampaignSpec`; the procedures it ships with,
`machinesim.campaign.shipped.PROCEDURES` (both importable from here as well).
"""

from __future__ import annotations

import contextlib
import math
import time
import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from machinesim.campaign.distributions import INSTRUMENTS, LAB_PARAMETERS
from machinesim.campaign.shipped import (
    PROCEDURES,
    ProcedureEntry,
    error_model_file,
    parameter_unit,
    spec_parameter_unit,
)
from machinesim.campaign.spec import (
    MAX_TRIALS,
    CampaignSpec,
    IdentificationOnly,
    check_flag,
    check_whole,
)
from machinesim.exceptions import InputError, MachineSimError, MachineSimWarning, brief
from machinesim.experiment import run
from machinesim.streams import stream
from machinesim.units import M_PER_UM

__all__ = ["MAX_TRIALS", "PROCEDURES", "CampaignSpec", "IdentificationOnly", "ProcedureEntry",
           "check_flag", "error_model_file", "kept_warnings", "parameter_unit", "run_trial",
           "spec_parameter_unit", "trial_seed", "check_whole"]


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
        record["error"] = unexpected(error, procedure if spec.own else None)
    else:
        unknown = _no_parameter(spec, procedure.name, result.identified)
        if unknown is not None:
            record["error"] = unknown
            return
        record["injected"] = {n: float(v) for n, v in result.injected.items()}
        record["identified"] = {n: [float(v), float(s)] for n, (v, s)
                                in result.identified.items()}
        record["figures"] = {f.name: [f.unit, _float(f.before), _float(f.after),
                                      _float(f.after_std)] for f in result.figures}
        record["notes"] = [str(note) for note in result.notes]


def _no_parameter(spec: CampaignSpec, shown: str, identified) -> str | None:
    """The failure of a trial whose procedure of the user's own identified a name that is no
    parameter of the campaign's error model (a lab parameter neither: `experiment.run`
    compares an identified name with the lab's errors, which hold no instrument's sigma,
    so its error was read against 0), or None. Such a trial had
    been kept as done, and the campaign ended once every trial had run, refusing to assemble
    them ("parameter 'foo.bar' ... has no unit ...; delete the trial files that name it")."""
    if not spec.own:  # machinesim's procedures name their own parameters
        return None
    base = spec.entry.base()
    for name in identified:
        try:  # a lab parameter too: the truth has no value of it, its error read as if 0
            base.parameter_unit(name)
        except MachineSimError as error:
            return (f"InputError: key 'identify': {shown}.identify named "
                    f"{brief(repr(name))}, no parameter of the campaign's error model "
                    f"({getattr(error, 'message', error)}); expected the names of the "
                    "error parameters it identifies")
    return None


def _float(value) -> float:
    return math.nan if value is None else float(value)


def unexpected(error: Exception, procedure=None) -> str:
    """A trial's failure message for an ``error`` that is no `MachineSimError` (a
    ZeroDivisionError, numpy's LinAlgError): a fault of machinesim that this trial's draws
    met, said as such with the line it was raised at, so that the report names it and the
    campaign goes on. It ended the whole campaign in a traceback, and the same command,
    resumed, ran the same trial into it again: a campaign that could never finish.

    ``procedure``: a user's own procedure (docs/procedures/your_own.md), whose code may
    raise too. When the innermost frame that is machinesim's or of the procedure's own
    class (or a base of it outside machinesim) is the procedure's, the fault is the
    procedure's, and said so, with that frame: such a failure had read "a fault of
    machinesim ...; please report it" for a ValueError raised in the user's ``identify``."""
    import traceback

    frames = traceback.extract_tb(error.__traceback__)
    where = ""
    if frames:
        frame = frames[-1]
        path = Path(frame.filename)
        shown = ("/".join(path.parts[path.parts.index("machinesim"):])
                 if "machinesim" in path.parts else path.name)
        where = f", raised at {shown}:{frame.lineno} in {frame.name}"
    from machinesim.campaign.own import innermost_frame

    own = None if procedure is None else innermost_frame(frames, procedure)
    if own is not None:
        deeper = "" if own is frames[-1] else f" (innermost{where.removeprefix(',')})"
        return (f"{type(error).__name__}: {brief(str(error)) or '(no message)'} (not a "
                f"MachineSimError: raised by your procedure's code at "
                f"{Path(own.filename).name}:{own.lineno} in {own.name}{deeper}, met by "
                "this trial's draws; a failed trial is kept as done: once the procedure "
                "is fixed, run the campaign into another --out)")
    return (f"{type(error).__name__}: {brief(str(error)) or '(no message)'} (not a "
            f"MachineSimError: a fault of machinesim met by this trial's draws{where}; "
            "please report it with the campaign's command)")
