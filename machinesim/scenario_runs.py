"""How a scenario runs from its command line: its options, its progress on stderr, and its
report folder written whole or not at all (`scenario_status`), with a clean exit on an error,
Ctrl-C or a full memory. The folder's contents are `machinesim.report`'s.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NoReturn

from machinesim._arguments import ArgumentParser
from machinesim._interrupts import ctrl_c_remembered, stopped
from machinesim._io import (
    broken_link,
    check_readable_file,
    folder_path,
    input_path,
    os_reason,
    stdout_to_null,
)
from machinesim._memory import OUT_OF_MEMORY, memory_capped
from machinesim._staged import StagedFolder
from machinesim.exceptions import InputError
from machinesim.report import STAGED, folder_key, listed_files
from machinesim.units import typed_float

#: A whole number as typed: ASCII digits, a '+' before them allowed. int() reads more: '1_0'
#: as 10 and full-width digits ('３') as 3, without a word.
_TYPED_WHOLE = re.compile(r"\+?[0-9]+")


def progress_printer(scenario: str):
    """Printers of a scenario's steps on stderr, with the time since this call:
    ``stage = progress_printer("name")``; ``told = stage("budget, x off")``; ``told("measure
    ...")`` prints ``name [m:ss] budget, x off: measure ...``. A ``told`` is what
    `machinesim.experiment.run` takes as ``progress``; stdout keeps the report alone."""
    began = time.perf_counter()

    def stage(name: str):
        def show(text: str) -> None:
            minutes, seconds = divmod(int(time.perf_counter() - began), 60)
            print(f"{scenario} [{minutes:d}:{seconds:02d}] {name}: {text}", file=sys.stderr,
                  flush=True)
        return show
    return stage


def scenario_status(report, args, name: str | None = None) -> int:
    """Run a scenario's ``report(args)`` and give its exit status: 0; 2 after a
    `machinesim.MachineSimError`, its one-line message on stderr (``NAME: error: message``,
    as ``machinesim: error: ...`` on the command line; a `MachineSimWarning` as one
    ``machinesim: warning: ...`` line, as there; ``name`` defaults to the script's
    name; also a report folder (``args.out``) that cannot be made or written, checked before
    the run, and a file that failed to write); 130 after Ctrl-C, one line saying so
    (``NAME: interrupted; ...``), 143 after SIGTERM (``NAME: terminated; ...``). Never a
    traceback.

    The report folder is written whole or not at all: every `ReportFolder` of ``args.out``
    writes into a staging folder beside it, swapped in when ``report`` returns
    (`machinesim._staged.StagedFolder`). Stopped or failed before, the run leaves the folder as
    it was (the previous report, or none), except what ``report`` made whole earlier with
    `ReportFolder.publish`. A folder that is not a report (files, but no summary.json
    listing them) is refused before the run rather than replaced.
    """
    from machinesim.scenario_start import finished, loaded

    from machinesim.exceptions import MachineSimError, say, warnings_as_lines

    loaded()
    name = name or Path(sys.argv[0]).stem or "scenario"
    out = getattr(args, "out", None)
    staged = None
    try:
        # past the memory there is: MemoryError, not the OOM killer
        with (ctrl_c_remembered(), memory_capped(), _may_close("stdout") as stdout,
              _may_close("stderr"), warnings_as_lines()):
            if out is not None:
                staged = _stage_report(out)
            report(args)
            if staged is not None and staged.path is not None:
                staged.commit()
            stdout.flush()  # the last buffered lines meet a closed pipe here, if at all
            if stdout.closed:
                say(name, f"{stdout.closed}; {_interrupted(out, staged)}")
    except MachineSimError as error:
        say(name, f"error: {error}")
        return 2
    except OSError as error:  # a write that failed on the way (disk full, folder removed)
        where = f"{_as_reported(error.filename, out, staged)}: " if error.filename else ""
        left = "" if staged is None else f"; {_interrupted(out, staged)}"
        say(name, f"error: {where}{error.strerror or error}{left}")
        return 2
    except KeyboardInterrupt as stop:  # Ctrl-C, or SIGTERM (`machinesim._interrupts.Terminated`)
        how, status = stopped(stop)
        say(name, f"{how}; {_interrupted(out, staged)}")
        return status
    except MemoryError:
        say(name, f"error: out of memory: {OUT_OF_MEMORY}")
        return 1
    finally:
        if staged is not None:
            staged.discard()
            STAGED.pop(folder_key(out), None)
        finished()  # done and said: a stop as the interpreter ends is ignored
    return 0


class _may_close:
    """Within: a reader that stops reading stdout (``scenario ... | head -1``) does not stop
    the run. The first write that meets the closed pipe sends stdout to the null device
    from then on, as Python's documentation advises (the signal module's notes on SIGPIPE),
    and the report folder is still written whole; ``closed`` says it happened, and how. So
    for a run started with stdout closed (``>&-``), where Python's ``sys.stdout`` is None
    and the first print ended in AttributeError's traceback.

    ``_may_close("stderr")``: the same for stderr, where the progress lines and notes go,
    and on any failed write (a full disk, a closed terminal), not a closed pipe only: with
    ``scenario ... 2>&1 | head -1`` the next progress line ended the run in status 2 with
    no report and no line, and the lines are worth no run."""

    def __init__(self, name: str = "stdout") -> None:
        self.name = name
        self.lost = BrokenPipeError if name == "stdout" else OSError
        self.closed = ""

    def __enter__(self):
        self.stream = self.usual = getattr(sys, self.name)
        if self.stream is None:
            self.stream = open(os.devnull, "w", encoding="utf-8")
            self.closed = (f"{self.name} was closed when the run began (no file descriptor "
                           f"{1 if self.name == 'stdout' else 2})")
        setattr(sys, self.name, self)
        return self

    def __exit__(self, *exc) -> None:
        setattr(sys, self.name, self.usual)
        try:
            self.stream.flush()
        except self.lost:
            self._to_null()
        if self.usual is None:
            self.stream.close()

    def write(self, text: str) -> int:
        try:
            return self.stream.write(text)
        except self.lost:
            self._to_null()
            return len(text)

    def flush(self) -> None:
        try:
            self.stream.flush()
        except self.lost:
            self._to_null()

    def _to_null(self) -> None:
        self.closed = f"{self.name} was closed early (a pipe's reader that stopped reading)"
        try:
            stdout_to_null(self.stream)
        except (OSError, ValueError):  # no descriptor to point elsewhere: a stream of its own
            self.stream = open(os.devnull, "w", encoding="utf-8")

    def __getattr__(self, attribute: str):  # isatty, encoding, fileno, ...
        return getattr(self.stream, attribute)


def _as_reported(filename, out, staged) -> str:
    """A file of the staged report named as it would be in ``--out`` (the staging folder,
    removed on the way out, is no name the user can look for)."""
    path = Path(os.fsdecode(filename))
    if staged is not None and staged.path is not None and path.is_relative_to(staged.path):
        return str(Path(out) / path.relative_to(staged.path))
    return str(path)


def _interrupted(out, staged) -> str:
    """What an interrupted scenario left in its report folder (true in every case)."""
    if staged is None:
        return ("no report folder was touched" if out is not None
                else "nothing was written")
    if staged.commits == 0:
        return (f"this run's report was not written: {str(out)!r} is as it was before "
                "(the previous report, whole, or nothing)")
    if staged.path is None:
        return f"this run's report was written whole to {str(out)!r}"
    return (f"{str(out)!r} holds this run's report as written whole before the interrupt, "
            "without what the run was adding to it")


def _debris(name: str) -> bool:
    """A temporary file `machinesim._io.write_atomic` may leave (a killed run): not the
    user's."""
    return name.startswith(".") and name.endswith((".tmp", ".old"))


def _stage_report(out) -> StagedFolder:
    """The staged report folder of ``--out``, after checking that it can be made and that
    what is there now is a report (so replacing it whole loses nothing of the user's)."""
    path = Path(out)
    target = Path(os.path.realpath(path))

    def refuse(reason: str):
        raise InputError(f"--out {str(path)!r}: {reason}", key="out")

    def cannot(reason: str):
        refuse(f"cannot make the report folder there ({reason}); expected a folder, or a "
               "path where one can be made")

    try:  # a name too long for the file system fails its stat (ENAMETOOLONG)
        if os.path.lexists(target) and not target.is_dir():
            loop = broken_link(path)  # a link that leads round in a loop is no file
            cannot(f"it {loop}" if loop else "a file is there")
        blocking = next((p for p in target.parents if p.exists()), None)
        if blocking is not None and not blocking.is_dir():
            cannot(f"{str(blocking)!r} is a file, not a folder")
        is_folder = target.is_dir()
    except OSError as exc:
        cannot(os_reason(exc))
    if is_folder:
        if not os.access(target, os.R_OK | os.W_OK | os.X_OK):
            refuse("the report folder is not writable")
        _check_replaceable(target, refuse)
    try:
        staged = StagedFolder(path)
    except OSError as exc:
        cannot(f"cannot write beside it in {str(target.parent)!r}: {exc.strerror or exc}")
    STAGED[folder_key(path)] = staged
    return staged


def _check_replaceable(folder: Path, refuse) -> None:
    """Refuse (``refuse(reason)``) a folder the new report may not replace whole: one that
    holds files besides a report (summary.json and the files it lists)."""
    try:
        names = sorted(n for n in os.listdir(folder) if not _debris(n))
    except OSError as exc:
        refuse(f"cannot read the report folder ({exc.strerror or exc})")
    if not names:
        return

    def shown(found: list[str]) -> str:
        return ", ".join(found[:5]) + (f" and {len(found) - 5} more" if len(found) > 5 else "")

    if "summary.json" not in names:
        refuse(f"holds files ({shown(names)}) but no summary.json, so it is not a report "
               "folder, and a new report replaces its folder whole; give a new or empty "
               "folder (or one a scenario wrote)")
    listed, unlike = listed_files(folder)
    if unlike is not None:
        refuse(f"holds a summary.json that is no report's ({unlike}), so it is not a report "
               "folder, and a new report replaces its folder whole; give a new or empty "
               "folder (or one a scenario wrote)")
    foreign = [n for n in names if n != "summary.json" and n not in listed]
    if foreign:
        refuse(f"holds files its summary.json does not list ({shown(foreign)}); a new report "
               "replaces its folder whole, so they would be lost: move them, or give "
               "another folder")


def run_scenario(report, args) -> None:
    """Run a scenario's ``report(args)`` and exit with `scenario_status`'s status."""
    sys.exit(scenario_status(report, args))


def _whole(text: str) -> int | None:
    """``text`` (blanks around it allowed) as an int when written as a whole number of ASCII
    digits (`_TYPED_WHOLE`), else None."""
    text = str(text).strip()
    if not _TYPED_WHOLE.fullmatch(text):
        return None
    if len(text.lstrip("+")) > sys.get_int_max_str_digits():
        # int() refuses it (ValueError), and argparse had said "invalid _seed value"
        raise argparse.ArgumentTypeError(
            f"expected a whole number of at most {sys.get_int_max_str_digits()} digits "
            f"(Python's limit), got one of {len(text.lstrip('+'))} digits")
    return int(text)


def _seed(text: str) -> int:
    """``--seed``: a non-negative integer (numpy's seeds), refused as the command line's
    error (argparse: usage and status 2), not deep in the first random draw."""
    value = _whole(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}")
    return value


def scenario_arguments(description: str, default_out: str) -> argparse.ArgumentParser:
    """The options every scenario takes: --errors FILE.toml, --noise on|off, --seed N,
    --out DIR."""
    parser = ArgumentParser(description=description)
    parser.add_argument("--errors", type=input_path, metavar="FILE.toml",
                        help="inject this error model (any ErrorModel TOML, units in every "
                        "key) instead of the scenario's default; the scenario's own error "
                        "options, when given, are applied on top")
    parser.add_argument("--noise", choices=("on", "off"), default="on",
                        help="instrument noise (default on, the instruments' stated models)")
    parser.add_argument("--seed", type=_seed, default=0,
                        help="seed of the noise, a non-negative integer (default 0)")
    parser.add_argument("--out", type=folder_path, default=Path(default_out),
                        help=f"report folder (default {default_out})")
    return parser


def _jobs(text: str) -> int:
    """``--jobs``: a whole number, 1 or more, refused as the command line's error."""
    value = _whole(text)
    if value is None or value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number of worker "
                                         "processes, 1 or more")
    return value


def jobs_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--jobs N`` to a scenario's parser: its error budget's reruns N at a time, each
    on a worker process (`machinesim.budget.error_budget` ``jobs``; docs/budget.md); default
    1, one after the other in the scenario's process."""
    from machinesim._cores import usable_cores

    parser.add_argument("--jobs", type=_jobs, default=1, metavar="N",
                        help="the budget's reruns at a time, each on a worker process "
                        "(default 1: one after the other in this process; the cores this "
                        f"process may use: {usable_cores()})")


#: The presets of `machinesim.realism.Realism` a scenario's ``--realism`` takes.
REALISM_PRESETS = ("ideal", "noise_only", "lab")


def realism_options(parser: argparse.ArgumentParser, default: str = "lab") -> None:
    """Add ``--realism ideal|noise_only|lab``, ``--budget on|off`` and ``--jobs N``
    (`jobs_option`) to a scenario's parser
    (`scenario_arguments` gives the options every scenario takes; these are for scenarios
    that build their lab with a `machinesim.realism.Realism`, see `realism_from`)."""
    parser.add_argument("--realism", choices=REALISM_PRESETS, default=default,
                        help="how real the lab is (docs/lab.md): ideal (exact readings), "
                        "noise_only (instrument noise), lab (instruments, artefacts and "
                        f"machine as real labs have them); default {default}. --noise off "
                        "takes the instrument noise out of it")
    parser.add_argument("--budget", choices=("on", "off"), default="on",
                        help="error budget (docs/budget.md): run again with each source of "
                        "the realism switched off in turn (default on; one more run per "
                        "source)")
    jobs_option(parser)


def realism_from(args):
    """The `machinesim.realism.Realism` of ``--realism``, less the instrument noise with
    ``--noise off``."""
    from machinesim.realism import Realism

    realism = getattr(Realism, args.realism)()
    return realism.without("instrument_noise") if args.noise == "off" else realism


def parse_floats(text: str, count: int, option: str) -> list[float]:
    """``"a,b,c"`` -> floats, with a clear error naming the option; each written as a
    plain number (`machinesim.units.typed_float`: not '0_5', which float() read as 5)."""
    try:
        values = [typed_float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InputError(f"{option} {text!r}: expected {count} comma-separated finite numbers "
                         "(ASCII digits, a point, an exponent: 250,-3.5e2,0)")
    return values


def errors_file(path, machine):
    """The `machinesim.errors.ErrorModel` of ``--errors`` ``path``, with a note on stderr
    (``NAME: note: ...``, one line each) where the file reads as no error at all, as
    ``machinesim cut`` notes it in its report: a file without keys (every error zero), and
    values below anything a machine shows (`machinesim.errors.unit_slips.below_any_machine`: SI
    written under a key in um or urad), and values beyond the errors of any machine
    (`beyond_any_machine`: um or urad under a key in mm or deg); and tables whose positions
    span less than 1 % of their axis's travel on the scenario's ``machine`` (a
    `machinesim.machines.Machine`, required: `short_tables`, um of travel under position_um,
    mm meant), and polynomials that reach 10 mm or 10 deg within its travel
    (`far_polynomials`), and a rotary axis's table of a turn whose values a turn apart
    differ where the travel wraps it (`turn_steps`): `unit_slip_notes`, as cut's. The run
    goes on: each can be meant."""
    from machinesim.errors import ErrorModel
    from machinesim.errors.unit_slips import unit_slip_notes

    # named as machinesim cut names it: "nope.toml: cannot read the file" named no option
    errors = ErrorModel.from_toml(check_readable_file(path, "error model (--errors)"))
    name = Path(sys.argv[0]).stem or "scenario"
    notes = [] if errors.written else [
        f"{path}: sets no error (no key in any section): the machine as built, every error "
        "zero"]
    for line in [*notes, *unit_slip_notes(errors, machine)]:
        print(f"{name}: note: {line}", file=sys.stderr, flush=True)
    return errors


def injected_errors(args, defaults: Mapping[str, float], given: Mapping[str, float],
                    machine: str):
    """The error model a scenario injects: ``--errors`` (or ``defaults`` without it), with
    the scenario's own options that were given on the command line (``given``) on top.
    A model that does not fit ``machine`` (the scenario's, by name) is refused naming the
    ``--errors`` file first, then the machine, and the file's short tables on it are noted
    (`errors_file`).

    Parameters
    ----------
    args : argparse.Namespace
        From `scenario_arguments`.
    defaults : Mapping[str, float]
        The scenario's default parameters (SI, names as `ErrorModel.parameters`).
    given : Mapping[str, float]
        Parameters set by options given explicitly.
    machine : str
        The scenario's machine (`machinesim.machines.load_machine` name).
    """
    from machinesim.errors import ErrorModel
    from machinesim.machines import load_machine

    if args.errors is None:
        base = ErrorModel().with_parameters(defaults)
    else:
        loaded = load_machine(machine)
        base = errors_file(args.errors, loaded)
        loaded.check_errors(base)  # names the --errors file, then the machine
    return base.with_parameters(given) if given else base


def refuse_beyond_capture(args, options: Mapping[str, tuple[object, str]],
                          keys: Sequence[str], found: str, capture: str, expected: str,
                          otherwise: tuple[str, str] | None = None) -> NoReturn:
    """Refuse, before anything is cut, injected errors beyond what a procedure's plan
    captures, naming what set them: the scenario's own options that were given (with what
    each is expected within), else ``otherwise`` when there is no ``--errors`` file, else
    that file and the error model's keys at fault.

    Parameters
    ----------
    args : argparse.Namespace
        From `scenario_arguments`.
    options : Mapping[str, tuple]
        Option (``"--tool-offset-um"``) -> (its value as given, None when not given; what it
        is expected within), for each option that sets the errors at fault, in the order
        they are named.
    keys : sequence of str
        The errors at fault (`ErrorModel.parameters` names), named with the ``--errors`` file.
    found : str
        The quantity beyond the range, with its value.
    capture : str
        The plan's capture range.
    expected : str
        What the errors are expected within when no option set them.
    otherwise : (str, str), optional
        What set them and the option it names when neither an option nor ``--errors`` did
        (paper 000: a ``--capture-mm`` below the paper's own errors).

    Raises
    ------
    InputError
        Always; its key the first option given, ``errors`` or ``otherwise``'s option.
    """
    given = [(f"{option} {value!r}", option, within)
             for option, (value, within) in options.items() if value is not None]
    if given:
        names, key, ranges = [name for name, _, _ in given], given[0][1], [
            within for _, _, within in given]
    elif otherwise is not None and args.errors is None:
        names, key, ranges = [otherwise[0]], otherwise[1], [expected]
    else:
        names, key, ranges = [f"--errors {args.errors} ({', '.join(keys)})"], "errors", [
            expected]
    raise InputError(f"{' with '.join(names)}: {found} exceeds the plan's capture range "
                     f"{capture}: expected {' or '.join(ranges)}", key=key.lstrip("-"))
