"""What a campaign runs (`CampaignSpec`): its procedure (shipped, `PROCEDURES`, or a user's
own), N, the parameters varied and their distributions, the seed and switches, all checked
when it is built, before any trial runs or any file is written; and `IdentificationOnly`,
a procedure's measurement and identification alone.

One trial of a spec is `machinesim.campaign.trials.run_trial`.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from machinesim.campaign.distributions import (
    LAB_PARAMETERS,
    Distribution,
    checked,
    parameter_kind,
    refuse_beyond_model,
)
from machinesim.campaign.shipped import PROCEDURES, ProcedureEntry
from machinesim.exceptions import InputError, brief
from machinesim.experiment import Evaluation, Identified

__all__ = ["MAX_TRIALS", "WHOLE_ARGUMENTS", "CampaignSpec", "IdentificationOnly", "check_flag",
           "check_whole"]


#: Most trials a campaign takes (docs/campaigns.md): a trial is seconds to minutes of CPU and
#: one file, so 100000 trials are already days on a cluster; a larger N is a typo, refused at
#: once (it used to leave the command silent for minutes, looking for that many trial files).
MAX_TRIALS = 100_000


#: A campaign's whole-number arguments: the least, the most (None: no bound) and why.
WHOLE_ARGUMENTS = {
    "trials": (1, MAX_TRIALS, " (the most trials a campaign takes, docs/campaigns.md)"),
    "seed": (0, None, ""),
    "workers": (0, None, " (0: no Dask)"),
}


def check_whole(value, name: str, *, option: bool = False) -> int:
    """``value`` of the whole-number argument ``name`` (`WHOLE_ARGUMENTS`) as an int, or an
    InputError naming it as the caller gave it: ``trials=0`` (key ``trials``) from Python,
    ``--trials 0`` (key ``--trials``) from the command line (``option``), whose text that
    is no number arrives as given (``'1e3'``). Python's campaign.run had been told of
    ``--trials``, a flag it has not."""
    least, most, why = WHOLE_ARGUMENTS[name]
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least \
            or (most is not None and value > most):
        given = f"--{name} {value!r}" if option else f"{name}={value!r}"
        bound = f">= {least}" if most is None else f"from {least} to {most}"
        raise InputError(f"{given}; expected a whole number {bound}{why}",
                         key=f"--{name}" if option else name)
    return int(value)


def check_flag(value, name: str) -> None:
    """Refuse a switch given as anything but True or False: ``noise="off"`` (the command's
    ``--noise off`` written in Python) is a true string, and ran every trial with noise."""
    if not isinstance(value, bool | np.bool_):
        raise InputError(f"{name}={value!r}; expected True or False", key=name)


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
        object.__setattr__(self, "trials", check_whole(self.trials, "trials"))
        object.__setattr__(self, "seed", check_whole(self.seed, "seed"))
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

    def _object(self) -> bool:
        """Whether the user gave an object (not a class, nor a reference): its state is
        then the arguments it was made with, which a campaign must tell apart."""
        return self.given is not None and not isinstance(self.given, type)

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
            from machinesim.campaign.identity import attributes_of, code_of, state_of

            built = self.entry.build({})  # a fresh instance, or a copy of the one given
            state = state_of(built, self.procedure, made=not self._object())
            if not self._object() and state != state_of(self.entry.build({}), "", made=True):
                # a class that makes another state each time (a time, a draw, a counter in
                # __init__): no resume could match it; its code, which decides it, names it
                state = None
            described.update(name=built.name, machine=self.machine_name,
                             errors=self.errors.to_dict(), code=code_of(built), state=state,
                             state_attributes=None if state is None else attributes_of(built))
        # the code a trial runs: machinesim's by its version, a user's by its digests
        # (`machinesim.campaign.identity`); a resume with other code is refused
        described["machinesim"] = _version()
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


def _version() -> str:
    from machinesim import __version__

    return __version__


_MACHINES: dict[str, Any] = {}


def _machine(name: str, load):
    # one load per process: a worker running many trials parses the URDF once
    if name not in _MACHINES:
        _MACHINES[name] = load(name)
    return _MACHINES[name]
