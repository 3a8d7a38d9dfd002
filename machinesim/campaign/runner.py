"""Run a campaign: its missing trials on Dask (or in this process), then its Dataset and report.

Locally by default: a `dask.distributed.LocalCluster` of ``workers`` processes (default: the
machine's cores), one thread each (the trials are CPU-bound Python). Given a
`distributed.Client` or a scheduler address, the trials run on that cluster instead; the
client writes every finished trial, so the workers need no shared file system (they need
machinesim installed). ``workers=0`` runs the trials here, one after the other, without Dask.
The cluster itself, its start, checks and close, is `machinesim.campaign.cluster`'s.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
import os
import sys
import time
import warnings
from collections.abc import Iterable

from machinesim._interrupts import ctrl_c_deferred
from machinesim._keywords import keywords_checked
from machinesim.campaign.cluster import (
    GUARD,
    NO_DASHBOARD,
    SCHEDULER_TIMEOUT_S,
    _client,
    _close,
    check_scheduler,
)
from machinesim.campaign.distributions import Distribution, parse_distribution, parse_vary
from machinesim.campaign.preflight import check_before_trials
from machinesim.campaign.results import (
    Assembly,
    CampaignFolder,
    finished_trials,
    locked,
    refuse_busy,
    refuse_foreign,
)
from machinesim.campaign.spec import CampaignSpec, check_flag, check_whole
from machinesim.campaign.summary import remove_report, write_report
from machinesim.campaign.trials import run_trial
from machinesim.exceptions import InputError, MachineSimError, MachineSimWarning, brief

__all__ = ["GUARD", "NO_DASHBOARD", "SCHEDULER_TIMEOUT_S", "check_scheduler", "run"]


#: Without a terminal (a log file, a pipe) progress is whole lines, at most one every this
#: many seconds (the cut's, machinesim.cli.LOG_PROGRESS_EVERY_S), and the last; in a
#: terminal the line is rewritten in place, at most every `TTY_EVERY_S`.
LOG_EVERY_S, TTY_EVERY_S = 30.0, 0.1


def _is_tty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):  # no isatty, or closed
        return False


class _Line:
    """A progress line on ``stream`` (None: nothing). In a terminal it is rewritten in
    place ('\r'), at most every `TTY_EVERY_S`; elsewhere each is a whole line, at most one
    every `LOG_EVERY_S`: every trial's '\r' update had gone into a log file, ~90 bytes a
    trial, one 'line' of megabytes. Nothing is written before ``after`` seconds (a short
    phase says nothing); the first line after that at once, the ``last`` always, and `end`
    writes the latest if it was held back, once any line was written."""

    def __init__(self, stream, after: float = 0.0, clock=time.monotonic) -> None:
        self.stream, self.clock = stream, clock
        self.tty = stream is not None and _is_tty(stream)
        self.every = TTY_EVERY_S if self.tty else LOG_EVERY_S
        self.quiet_until = clock() + after
        self.written, self.held, self.width = -math.inf, None, 0
        self.shown = False  # a line to end: none when nothing was written

    def show(self, text: str, last: bool = False) -> None:
        if self.stream is None:
            return
        now = self.clock()
        if (last and self.shown) or (now >= self.quiet_until and (
                not self.shown or last or now - self.written >= self.every)):
            self._write(text)
            self.written = now
        else:
            self.held = text

    def _write(self, text: str) -> None:
        if self.tty:  # spaces over what is left of a longer line before
            self.stream.write(f"\r{text.ljust(self.width)}")
            self.width = len(text)
        else:
            self.stream.write(f"{text}\n")
        self.stream.flush()
        self.shown, self.held = True, None

    def end(self) -> None:
        if self.stream is None or not self.shown:
            return
        if self.held is not None:
            self._write(self.held)
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()


class _Progress:
    """The run's progress (`_Line`): done / total, rate, time left."""

    def __init__(self, total: int, resumed: int, stream, clock=time.monotonic) -> None:
        self.total, self.resumed, self.clock = total, resumed, clock
        self.line = _Line(stream, clock=clock)
        self.done, self.failed, self.began = resumed, 0, clock()

    def start(self) -> None:
        """The trials begin: the rate and the time left count from here, not from before a
        local cluster's start (several seconds, which put the first lines' time left at
        several times the truth)."""
        self.began = self.clock()

    def step(self, record: dict) -> None:
        self.done += 1
        self.failed += record["error"] is not None
        if self.line.stream is None:
            return
        new = self.done - self.resumed
        elapsed = self.clock() - self.began
        rate = new / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else float("nan")
        self.line.show(f"campaign: {self.done}/{self.total} trials ({self.resumed} resumed, "
                       f"{self.failed} failed), {rate:.2f} trials/s, {left:.0f} s left",
                       last=self.done == self.total)

    def end(self) -> None:
        self.line.end()


def _vary(vary) -> tuple[tuple[str, Distribution], ...]:
    if vary is None:
        return ()
    if isinstance(vary, str):  # one "PARAM=DIST": a list of one, not one per character
        vary = [vary]
    if isinstance(vary, dict):
        vary = list(vary.items())
    if not isinstance(vary, Iterable):
        raise InputError(f"vary={vary!r}; expected PARAM=DIST texts (e.g. "
                         "['tool.y=normal:-178um,5um']), (name, DIST) pairs or a dict",
                         key="--vary")
    out = []
    for item in vary:
        if isinstance(item, str):
            out.append(parse_vary(item))
            continue
        pair = tuple(item) if isinstance(item, tuple | list) else ()
        if len(pair) != 2 or not isinstance(pair[0], str):
            raise InputError(f"vary item {item!r}; expected PARAM=DIST or a (name, DIST) "
                             "pair", key="--vary")
        name, dist = pair  # a DIST text ("normal:0,5um") is parsed as the command's
        out.append(parse_vary(f"{name}={dist}") if isinstance(dist, str) else (name, dist))
    return tuple(out)


#: Trials a campaign keeps in flight on Dask per worker thread (one running, one waiting
#: to start as it finishes), and at least (while a cluster's workers join).
IN_FLIGHT_PER_THREAD, MIN_IN_FLIGHT = 2, 4
#: Longest wait, in seconds, for the scheduler's count of worker threads (a Ctrl-C is held
#: meanwhile): past it the last count stands, and it is asked again `_Window.every_s` later.
COUNT_WAIT_S = 2.0


class _Window:
    """How many trials to keep in flight on ``client``'s cluster: `IN_FLIGHT_PER_THREAD` per
    worker thread, `MIN_IN_FLIGHT` at least; the threads counted again every ``every_s``
    seconds, so that workers joining a cluster (or leaving it) get trials (or not).

    The count is asked under `ctrl_c_deferred`, for `COUNT_WAIT_S` at most: a Ctrl-C landing
    in Dask's ``sync`` before its coroutine made its future printed tornado's "NameError:
    cannot access free variable 'future'" traceback (Dask's cancel callback)."""

    def __init__(self, client, every_s: float = 5.0) -> None:
        self.client, self.every_s = client, every_s
        self.counted, self.threads = -math.inf, 0

    def size(self) -> int:
        now = time.monotonic()
        if now - self.counted >= self.every_s:
            self.counted = now
            with ctrl_c_deferred():  # raised after it, within COUNT_WAIT_S
                try:
                    self.threads = sum(
                        self.client.nthreads(callback_timeout=COUNT_WAIT_S).values())
                except TimeoutError:  # a busy scheduler: the last count stands
                    pass
        return max(MIN_IN_FLIGHT, IN_FLIGHT_PER_THREAD * self.threads)


def windowed(client, function, spec, indices):
    """``function(spec, i)`` for each of ``indices`` on ``client``'s cluster, yielded as
    they finish, with a few in flight per worker thread (`_Window`), the next sent as one
    finishes: the path every trial of a campaign takes (benchmarks/campaign.py times it).
    All of them at once (client.map) held 100000 tasks in the client and the scheduler,
    1.3 GB and 30 s before the first trial started, and as long again to cancel on a
    Ctrl-C.

    A finished future's result is taken and the future let go under `ctrl_c_deferred`:
    its last reference ran Dask's ``Future.__del__`` here, where a Ctrl-C landing was
    printed as "Exception ignored in: <function Future.__del__ ...> KeyboardInterrupt" and
    swallowed (the campaign went on to its next write), and one landing in ``result``'s
    Dask ``sync`` before its coroutine made its future printed tornado's "NameError: cannot
    access free variable 'future'" traceback. It is finished (as_completed yielded it), so
    ``result`` returns at once and the held Ctrl-C is raised right after. Each one sent is
    held by ``running`` until it finishes; it is sent under `ctrl_c_deferred` too (a Ctrl-C
    inside ``Future.__init__`` left one without ``_cleared``, and its ``__del__`` printed
    "Exception ignored ... AttributeError")."""
    from distributed import as_completed

    waiting, window = iter(indices), _Window(client)
    running, sent = as_completed(), {}
    while True:
        for i in itertools.islice(waiting, max(0, window.size() - len(sent))):
            with ctrl_c_deferred():  # no Future left half made (submit does not wait)
                future = client.submit(function, spec, i, pure=False)
                sent[future.key] = i
                running.add(future)
                del future
        if not sent:
            return
        future = next(running)
        i = sent.pop(future.key)
        with ctrl_c_deferred():  # result and __del__ run here, a Ctrl-C raised after them
            try:
                result = future.result()
            except Exception as error:  # run_trial keeps a trial's own errors in its record
                raise MachineSimError(_lost(i, error)) from error
            finally:
                del future
        yield result


def _lost(i: int, error: Exception) -> str:
    """What the campaign says of trial ``i``, whose task came back from the cluster as
    ``error`` rather than a record (`run_trial` keeps a trial's own errors in its record):
    its worker died (Dask's KilledWorker, after its retries: out of memory, a crash of a
    compiled library), or the task could not be sent or run. It had ended the campaign in
    Dask's traceback, naming no trial and not what was kept."""
    return (f"campaign: trial {i} did not come back from the Dask cluster "
            f"({type(error).__name__}: {brief(str(error)) or 'no message'}): its worker died "
            "(out of memory, a crash) or the task could not be run there; the trials "
            "finished before it are kept: run the same command again to resume (only the "
            "missing trials run)")


def _execute(spec: CampaignSpec, missing: list[int], folder: CampaignFolder,
             assembly: Assembly, progress, workers, scheduler, client) -> None:
    if not missing:
        return
    if workers == 0 and scheduler is None and client is None:
        progress.start()
        for i in missing:
            record = _warned(run_trial(spec, i))
            assembly.add(folder.write_trial(record))
            progress.step(record)
        return
    client, cluster = _client(workers, scheduler, client, len(missing))
    owned = cluster is not None or scheduler is not None
    try:
        progress.start()
        for record in windowed(client, run_trial, spec, missing):
            record = _warned(record)
            assembly.add(folder.write_trial(record))
            progress.step(record)
    finally:
        if owned:
            _close(client, cluster)


def _warned(record: dict) -> dict:
    """``record`` without its ``warnings`` (`run_trial`: the `MachineSimWarning` s its worker
    kept), each warned here, in the campaign's process, where `_each_warning_once` shows
    it as this process's own are shown (one line on the command line), once."""
    record = dict(record)
    for message in record.pop("warnings", ()):
        warnings.warn(message, MachineSimWarning, stacklevel=2)
    return record


@contextlib.contextmanager
def _each_warning_once():
    """Within the block, a `MachineSimWarning` whose message was shown already is not shown
    again: the machine's warning as this process loads it (`CampaignSpec`) and as each
    trial's worker did (`_warned`) is one line, not one per worker or per trial."""
    shown_messages: set[str] = set()
    with warnings.catch_warnings():
        show = warnings.showwarning

        def once(message, category, filename, lineno, file=None, line=None):
            if issubclass(category, MachineSimWarning):
                if str(message) in shown_messages:
                    return
                shown_messages.add(str(message))
            show(message, category, filename, lineno, file, line)

        warnings.showwarning = once
        yield


#: Reading the finished trials says nothing for this many seconds (a few files: nothing
#: to wait for), in a terminal; in a log file, for as long as a cut does
#: (machinesim.cli.LOG_PROGRESS_AFTER_S).
READ_QUIET_S, LOG_READ_QUIET_S = 0.5, 10.0


def _read(folder: CampaignFolder, done: list[int], assembly: Assembly, stream) -> None:
    """Read (and check) the finished trials ``done`` into ``assembly``, saying how far on
    ``stream``: at 0.2 ms a file, 100000 of them took ~23 s before any trial ran, in
    silence."""
    line = _Line(stream, after=READ_QUIET_S if _is_tty(stream) else LOG_READ_QUIET_S)
    try:
        for k, i in enumerate(done, 1):
            assembly.add(folder.read_trial(i))
            line.show(f"campaign: reading the finished trials in {folder.trials_path}: "
                      f"{k}/{len(done)}", last=k == len(done))
    finally:
        line.end()


@keywords_checked
def run(procedure, trials: int, *, vary: Iterable = (), seed: int = 0, out,
        workers: int | None = None, scheduler: str | None = None, client=None,
        noise: bool = True, identify_only: bool = False, quick: bool = False,
        progress: bool = True, report: bool = True, machine: str | None = None,
        errors=None):
    """Run ``trials`` trials of ``procedure`` (those not already in ``out``) and assemble them.

    Parameters
    ----------
    procedure : str, or a procedure class or object
        A key of `machinesim.campaign.PROCEDURES` (``"tool_rotation_arm"``, ...), or a
        procedure of your own (docs/procedures/your_own.md, `machinesim.campaign.own`): a
        ``"package.module:ClassName"`` reference, which each worker imports; or the class
        or an instance, which Dask pickles to its workers (a trial runs the class called
        with no arguments, or a copy of the instance).
    trials : int
        N.
    vary : iterable of ``"PARAM=DIST"`` or (name, DIST) pairs; or a dict name -> DIST
        On top of the procedure's default errors (`machinesim.campaign.distributions`); a
        DIST is a `Distribution` or its text (``"normal:0,5um"``). None: nothing varies.
    seed : int
        The campaign's seed: trial i is ``SeedSequence(seed).spawn(trials)[i]``.
    out : str or Path
        The campaign folder (`machinesim.campaign.results`); trials already there are reused.
    workers : int, optional
        Local Dask worker processes (default: the cores); 0: run here without Dask.
    scheduler : str, optional
        Address of a Dask scheduler (``tcp://host:8786``) to run on instead.
    client : distributed.Client, optional
        A client to run on (left open).
    noise, identify_only, quick : bool
        `CampaignSpec`.
    progress : bool
        Show progress on stderr.
    report : bool
        Write summary.json, summary.md and the plots beside campaign.nc; False: campaign.nc
        alone, and an earlier report in ``out`` (of the trials then) is removed.
    machine : str
        Your own procedure's machine (``"grooving_4axis"``); not for a shipped one.
    errors : ErrorModel, dict (the TOML layout) or TOML path, optional
        Your own procedure's errors, as `machinesim.Lab` takes them: the model each trial's
        ``vary`` is set on (default: none); not for a shipped one, whose are its paper's.

    Returns
    -------
    xarray.Dataset
        Also written to ``out/campaign.nc``.
    """
    _refuse_in_a_starting_worker()
    with _each_warning_once():
        return _run(procedure, trials, vary, seed, out, workers, scheduler, client, noise,
                    identify_only, quick, progress, report, machine, errors)


def _refuse_in_a_starting_worker() -> None:
    """Refuse a call made while a local worker imports the script that made it. A call at a
    script's top level ran again in every worker Dask started (multiprocessing's spawn
    imports the main script as ``__mp_main__``), found the campaign folder locked by the
    script itself ("another campaign is running in this folder"), and the cluster ended in
    Dask's "RuntimeError: Nanny failed to start."."""
    # multiprocessing names the main module '__mp_main__' too; only while a spawned
    # process imports the parent's script are they two modules (measured on 3.11)
    script = sys.modules.get("__mp_main__")
    if script is not None and script is not sys.modules.get("__main__"):
        raise InputError(f"campaign.run was called while a Dask worker imported "
                         f"{getattr(script, '__file__', 'the main script')}: {GUARD}",
                         key="campaign.run")


def _run(procedure, trials, vary, seed, out, workers, scheduler, client, noise,
         identify_only, quick, progress, report, machine, errors):
    """`run`, its warnings shown by `_each_warning_once`."""
    given = sum(x is not None for x in (scheduler, client)) + (workers is not None)
    if given > 1:
        raise InputError("give one of workers, scheduler and client", key="workers")
    workers = None if workers is None else check_whole(workers, "workers")
    if client is not None and not all(callable(getattr(client, name, None))
                                      for name in ("submit", "nthreads")):
        # a scheduler's address given as client= was taken, campaign.json written, and the
        # campaign ended in Dask's 'ValueError: No clients found'
        raise InputError(f"client={brief(repr(client))}; expected a distributed.Client (a "
                         "scheduler's address goes as scheduler='tcp://host:8786')",
                         key="client")
    if not isinstance(out, str | os.PathLike) or not str(out):
        raise InputError(f"out={out!r}; expected the campaign folder, a str or Path",
                         key="--out")
    for flag, value in (("progress", progress), ("report", report)):
        check_flag(value, flag)
    spec = CampaignSpec(procedure, trials, _vary(vary), seed=seed, noise=noise,
                        identify_only=identify_only, quick=quick, machine_name=machine,
                        errors=errors)
    check_before_trials(spec)  # the procedure's own checks: refused now, not in every trial
    if spec.own and spec.errors is not None:  # machinesim cut's and view's notes on the file
        from machinesim.errors.unit_slips import unit_slip_notes

        for note in unit_slip_notes(spec.errors, spec.machine):
            warnings.warn(note, MachineSimWarning, stacklevel=3)
    if spec.given is not None and not (workers == 0 and scheduler is None and client is None):
        from machinesim.campaign.own import check_picklable

        check_picklable(spec.given, spec.procedure)  # Dask's to send: refused before any file
    if scheduler is not None:  # before the folder is made: nothing written for a wrong address
        check_scheduler(scheduler)
    try:
        refuse_foreign(out)  # before the lock's file is made in it (checked again under the lock)
    except InputError:
        refuse_busy(out)  # another run making DIR a campaign's just now: its temporary file
        raise
    with locked(out):  # a second campaign on DIR meanwhile is refused
        # described once: a user's procedure is built twice for each description (its state)
        described = spec.describe()
        folder = CampaignFolder(out, described)
        stored = folder.spec["vary"]
        if list(stored.items()) != list(described["vary"].items()):
            # the same distributions spelt otherwise (10nm, 0.01um) or given in another order:
            # the missing trials draw from the texts the campaign was begun with, to the last
            # bit as its first trials did, and the Dataset keeps its order of them
            spec = dataclasses.replace(spec, vary=tuple(
                (name, parse_distribution(text, name)) for name, text in stored.items()))
            described = {**described, "vary": {n: d.text for n, d in spec.vary}}  # describe()'s
        done = folder.done(spec.trials)
        beyond = [i for i in finished_trials(folder.path) if i >= spec.trials]
        if beyond:  # not progress: said under --quiet too, the summary is of fewer trials
            print(f"campaign: {folder.trials_path} holds {len(beyond)} trial file"
                  f"{'s' * (len(beyond) > 1)} beyond --trials {spec.trials} (from trial "
                  f"{beyond[0]}): left out of this summary, kept for a larger --trials",
                  file=sys.stderr)
        missing = sorted(set(range(spec.trials)) - set(done))
        assembly = Assembly(described, spec.trials)  # each record's numbers, not the record
        # the trials already there are read first: a damaged file is refused before the missing
        # trials run, not after
        _read(folder, done, assembly, sys.stderr if progress else None)
        shown = _Progress(spec.trials, len(done), sys.stderr if progress else None)
        try:
            _execute(spec, missing, folder, assembly, shown, workers, scheduler, client)
        finally:
            shown.end()
        dataset = assembly.dataset()
        if report:  # campaign.nc and its report together: never one run's file beside another's
            write_report(dataset, folder.path, {"campaign.nc": bytes(dataset.to_netcdf())})
        else:  # nor an earlier report beside this campaign.nc, of which it is not
            remove_report(folder.path)
            folder.write_dataset(dataset)
        return dataset
