"""A user's own procedure in a campaign (docs/procedures/your_own.md): how it is named,
found, checked and made afresh for each trial.

A campaign runs a shipped procedure by its key (`machinesim.campaign.PROCEDURES`) or one of
the user's, given as

- a reference ``"package.module:ClassName"``: the class is imported and called with no
  arguments in whichever process runs a trial (each Dask worker imports it; the module must
  be on that process's ``sys.path``);
- the class itself, or an instance of it: a trial runs a fresh instance (the class called
  with no arguments) or a copy of the instance given (`copy.deepcopy`), so nothing a trial's
  procedure keeps on itself reaches the next trial. On Dask the object travels to the
  workers pickled (`distributed.protocol.pickle`: by reference to its module, by value
  for one defined in ``__main__``); one that cannot be pickled is refused before anything
  is written (`check_picklable`).

The campaign knows a user's procedure by its reference (for a class or an instance, its
class's ``module:qualname``), its ``name``, the machine and the error model the trials are
drawn on (`machinesim.campaign.CampaignSpec.describe`): a folder begun with one is not
resumed with another. The procedure sees the lab only as `machinesim.experiment.run`
gives it, as a shipped one does.
"""

from __future__ import annotations

import copy
import difflib
import importlib
import inspect
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from machinesim.exceptions import InputError, brief

__all__ = ["STEPS", "accepted", "check_picklable", "fresh", "innermost_frame", "is_reference",
           "reference_of", "resolve"]

#: What `machinesim.experiment.run` calls, in order.
STEPS = ("measure", "identify", "compensate", "evaluate")

#: ``package.module:Name`` (the name may be dotted: ``Outer.Inner``).
_REFERENCE = re.compile(r"[A-Za-z_][\w.]*:[A-Za-z_][\w.]*")

#: What a reference must be, said in each refusal.
_EXPECTED = ("expected an importable 'package.module:ClassName' reference (the module on "
             "sys.path here and in every worker; the class called with no arguments), a "
             "procedure class or object, or a shipped procedure's name")


def is_reference(text: str) -> bool:
    """Whether ``text`` has the form of a ``package.module:Name`` reference."""
    return _REFERENCE.fullmatch(text) is not None


def reference_of(procedure) -> str:
    """The ``module:qualname`` of ``procedure``'s class (of ``procedure``, a class)."""
    cls = procedure if isinstance(procedure, type) else type(procedure)
    return f"{cls.__module__}:{cls.__qualname__}"


def resolve(reference: str):
    """The class (or object) ``reference`` names, its module imported once per process.

    Raises
    ------
    InputError
        Key ``procedure``: a module that cannot be imported (or raised as it was), or a name
        it does not hold, naming the reference and what is expected.
    """
    # not kept per reference: the module as sys.modules holds it now, so that a module
    # reloaded (importlib.reload in a notebook) runs its new class, as campaign.json's code
    # digest (`machinesim.campaign.identity`) reads it; import_module imports it once
    module_name, _, path = reference.partition(":")
    try:
        target = importlib.import_module(module_name)
    except ImportError as error:
        raise InputError(f"procedure {reference!r}: cannot import {module_name!r} ({error}); "
                         f"{_EXPECTED}", key="procedure") from None
    except Exception as error:  # the module's own fault as it was imported
        raise InputError(f"procedure {reference!r}: importing {module_name!r} raised "
                         f"{type(error).__name__}: {brief(str(error))}; {_EXPECTED}",
                         key="procedure") from None
    for k, part in enumerate(path.split(".")):
        if not hasattr(target, part):
            held = [name for name in dir(target) if not name.startswith("_")]
            close = difflib.get_close_matches(part, held, n=1)
            where = module_name + "".join(f".{p}" for p in path.split(".")[:k])
            raise InputError(f"procedure {reference!r}: {where} has no {part!r}"
                             f"{f' (did you mean {close[0]}?)' if close else ''}; "
                             f"{_EXPECTED}", key="procedure")
        target = getattr(target, part)
    return target


def accepted(procedure, given, machine, errors, shipped: Mapping) -> tuple[str, Any, Any]:
    """``(reference, given, errors)`` of a campaign of the user's ``procedure`` (a reference,
    a class or an object; ``given``: the class or object, once known), checked: the reference
    imports here (unless ``given``), ``machine`` is a name, ``errors`` an error model as
    `machinesim.Lab` takes it (returned as an `ErrorModel`). Anything that is neither this
    nor a key of ``shipped`` is refused, naming those keys."""
    from machinesim.errors.model import as_error_model

    if isinstance(procedure, str) and is_reference(procedure):
        if given is None:
            resolve(procedure)  # importable here, or refused naming it
    elif isinstance(procedure, type) or (not isinstance(procedure, str) and all(
            callable(getattr(procedure, step, None)) for step in STEPS)):
        procedure, given = reference_of(procedure), procedure
    else:  # a list or dict is no key: 'in' raised "TypeError: unhashable type: 'list'"
        raise InputError(f"procedure {brief(repr(procedure))}; expected one of "
                         f"{', '.join(shipped)}, or a procedure of your own: a "
                         "'package.module:ClassName' reference, the class or an instance "
                         "(docs/procedures/your_own.md)", key="procedure")
    if not isinstance(machine, str) or not machine:
        raise InputError(f"machine={brief(repr(machine))}; expected the name of the machine "
                         f"procedure {procedure} is for (e.g. machine='grooving_4axis'): a "
                         "campaign of your own procedure needs it", key="machine")
    return procedure, given, as_error_model(errors)


def fresh(given, shown: str):
    """A procedure for one trial from ``given`` (a class: called with no arguments; an
    object: a deep copy), checked (`_check`); ``shown`` names it in a refusal."""
    if isinstance(given, type):
        try:
            procedure = given()
        except Exception as error:
            raise InputError(f"procedure {shown}: {given.__qualname__}() raised "
                             f"{type(error).__name__}: {brief(str(error))}; expected a class "
                             "a campaign can call with no arguments (one per trial), or give "
                             "an instance of it", key="procedure") from None
    else:
        try:
            procedure = copy.deepcopy(given)
        except Exception as error:
            raise InputError(f"procedure {shown}: a copy of it for each trial failed "
                             f"({type(error).__name__}: {brief(str(error))}); expected a "
                             "procedure object copy.deepcopy takes, or its class (called "
                             "with no arguments)", key="procedure") from None
    _check(procedure, shown)
    return procedure


def _check(procedure, shown: str) -> None:
    """Refuse an object that is no procedure a campaign can run: the four steps, a ``name``
    and a ``paper`` (texts) and ``lab_uses`` (a mapping of ``"measure"``/``"evaluate"`` to
    names of `machinesim.experiment.LAB_USES`, which says what the campaign may vary)."""
    from machinesim.experiment import LAB_USES

    missing = [step for step in STEPS if not callable(getattr(procedure, step, None))]
    if missing:
        raise InputError(f"procedure {shown} ({type(procedure).__name__}) has no "
                         f"{', '.join(missing)}; expected a procedure with "
                         f"{', '.join(STEPS)} (docs/procedures/your_own.md)", key="procedure")
    name = _attribute(procedure, "name", shown)
    if not isinstance(name, str) or not name:
        raise InputError(f"procedure {shown}: name {brief(repr(name))}; expected a text (its "
                         "key, e.g. 'tool_offset_rtest')", key="procedure")
    # experiment.run puts it into each Result: without it every trial failed, after its
    # cuts and readings, as "AttributeError: ... 'paper'" said to be a fault of machinesim
    paper = _attribute(procedure, "paper", shown)
    if not isinstance(paper, str):
        raise InputError(f"procedure {shown}: paper {brief(repr(paper))}; expected a text "
                         "(where its method comes from, e.g. 'docs/procedures/your_own.md'; "
                         "any text)", key="procedure")
    uses = _attribute(procedure, "lab_uses", shown)
    if not isinstance(uses, Mapping) or not set(uses) <= {"measure", "evaluate"}:
        raise InputError(f"procedure {shown}: lab_uses {brief(repr(uses))}; expected a "
                         "mapping {'measure': (...), 'evaluate': (...)} of what each step "
                         f"reads of the lab, among {', '.join(LAB_USES)}", key="procedure")
    for step, names in uses.items():
        # a number or None is no tuple: 'for n in names' raised "TypeError: 'int' object is
        # not iterable" out of the campaign's start
        if not isinstance(names, tuple | list | set | frozenset) \
                or not all(isinstance(n, str) for n in names) or not set(names) <= set(LAB_USES):
            raise InputError(f"procedure {shown}: lab_uses[{step!r}] {brief(repr(names))}; "
                             f"expected a tuple of {', '.join(LAB_USES)}", key="procedure")


def _attribute(procedure, key: str, shown: str):
    """``procedure``'s attribute ``key`` (None when it has none); a property that raises is
    refused naming it (a RuntimeError out of ``name`` had ended the campaign's start in a
    traceback)."""
    try:
        return getattr(procedure, key, None)
    except Exception as error:  # noqa: BLE001 - whatever the user's property raises
        raise InputError(f"procedure {shown}: reading its {key} raised "
                         f"{type(error).__name__}: {brief(str(error))}; expected "
                         f"{_WANTED[key]} (docs/procedures/your_own.md)",
                         key="procedure") from None


_WANTED = {"name": "a text, its key", "paper": "a text, where its method comes from",
           "lab_uses": "a mapping of what each step reads of the lab"}


def check_picklable(given, shown: str) -> None:
    """Refuse a procedure object (or class) that Dask cannot send to its workers, before
    anything is written: pickled as Dask pickles a task's arguments."""
    from distributed.protocol.pickle import dumps

    try:
        dumps(given)
    except Exception as error:
        raise InputError(f"procedure {shown} cannot be pickled for the Dask workers "
                         f"({type(error).__name__}: {brief(str(error))}); expected an "
                         "importable 'package.module:ClassName' reference (each worker "
                         "imports it and calls the class with no arguments), or workers=0 "
                         "to run the trials in this process", key="procedure") from None


def innermost_frame(frames, procedure):
    """The innermost of ``frames`` (`traceback.extract_tb`'s) in the source of
    ``procedure``'s class or a base of it outside machinesim, when no frame of machinesim
    lies deeper; else None (`machinesim.campaign.trials.unexpected`: whose fault it is)."""
    package = Path(__file__).resolve().parents[1]  # machinesim/
    files = set()
    for cls in type(procedure).__mro__:
        try:
            source = inspect.getsourcefile(cls)
        except (TypeError, OSError):  # a builtin (object), or no file
            continue
        if source is not None and package not in Path(source).resolve().parents:
            files.add(Path(source).resolve())
    for frame in reversed(frames):
        where = Path(frame.filename).resolve()
        if where in files:
            return frame
        if package in where.parents:
            return None
    return None
