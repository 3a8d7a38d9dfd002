"""A few long, independent calls on worker processes, one per core: an error budget's reruns.

One rerun of a procedure (a crown cut and its reading) keeps about one core busy; the
budget's reruns are independent of each other (each builds its lab from its own inputs,
seeded), so on a machine of N cores N of them at a time finish in about 1/N of the time.
`in_processes` runs them in a `concurrent.futures.ProcessPoolExecutor` of fresh
interpreters (``spawn``: nothing of the parent's state but what is sent, the same in every
start method and platform) and gives the results in the order of the inputs, whatever order
they finish in: what is computed, and what comes back (pickled floats are exact), is the
same as in one process.

A Ctrl-C reaches the whole foreground process group: the workers start with SIGINT blocked
(`machinesim._interrupts.sigint_blocked`) and ignore it once started, so the parent alone
takes it, ends the workers (SIGTERM, then SIGKILL after `STOP_WAIT_S`) and raises it; the
same for SIGTERM sent to the parent, for an error in a worker, and for a worker that died.
No worker outlives the call.

Workers that fill the cores (as many as this process may use, or more) are pinned one to a
core, each with one thread, as a campaign's Dask workers are
(`machinesim.campaign.runner`): a crown rerun alone keeps its main thread busy and
manifold3d's TBB worker thread about 45 % of a second core (thread CPU times, paper 002's
quick crown), which two reruns on two cores would fight for.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import signal
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from machinesim._cores import usable_cores
from machinesim._interrupts import ctrl_c_deferred, sigint_blocked
from machinesim.exceptions import InputError, MachineSimError

__all__ = ["WorkerDied", "check_jobs", "in_processes"]

#: Seconds a worker has to end after SIGTERM before it is killed.
STOP_WAIT_S = 5.0


class WorkerDied(MachineSimError):
    """A worker process ended without an answer (killed: out of memory, ``kill -9``)."""


def check_jobs(jobs, what: str = "call") -> int:
    """``jobs`` as an int, 1 or more (a numpy integer taken; a bool, a float, text refused
    by name: ``jobs=True`` is no count). ``what``: what a call is, for the message."""
    if isinstance(jobs, bool) or not isinstance(jobs, int | np.integer) or jobs < 1:
        raise InputError(f"{what}s: expected 1 or more worker processes, got jobs={jobs!r}",
                         key="jobs")
    return int(jobs)


def _worker_start(cores, setup) -> None:
    """In each worker: a Ctrl-C is the parent's to handle (it ends the workers); with
    ``cores`` (a queue of the cores to take, one each), pinned to one core, its thread pools
    (manifold3d's TBB, started later, sized by the cores it may use; the planner's and the
    NC reader's) to one thread; then ``setup()``, when given."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if cores is not None:
        os.sched_setaffinity(0, {cores.get()})
        from machinesim.motion import chords
        from machinesim.nc import fastscan

        chords.WORKERS = fastscan.WORKERS = 1
    if setup is not None:
        setup()


def _timed(call: bytes, what: str):
    """In a worker: ``function(item)`` of the pickled ``(function, item)`` and its seconds.
    Loaded here rather than by the pool, so that one the worker cannot load is an error of
    that call, not a worker dying: a function defined under ``if __name__ == "__main__":``
    (or in ``python -c``) pickles by its name in the parent, but a spawned worker imports
    the main script as ``__mp_main__``, without that block, and finds no such name; the
    pool's own loading failed, killing the worker with a traceback on stderr, and the call
    was told as a worker 'killed: out of memory, or by a signal'."""
    try:
        function, item = pickle.loads(call)
    except Exception as error:  # AttributeError, ModuleNotFoundError, ...: all say why
        raise InputError(f"{what}s on worker processes: a worker process could not load the "
                         f"function or its item ({type(error).__name__}: {error}); define "
                         "it at the top level of a module the worker can import (not under "
                         "'if __name__ == \"__main__\":', nor in python -c), or run them in "
                         "this process instead (jobs 1)", key="jobs") from None
    began = time.perf_counter()
    result = function(item)
    return time.perf_counter() - began, result


def in_processes(function: Callable, items: Sequence, jobs: int, *,
                 done: Callable[[int, float], None] | None = None, what: str = "call",
                 setup: Callable[[], None] | None = None) -> list:
    """``[function(item) for item in items]``, computed on ``min(jobs, len(items))`` worker
    processes.

    Parameters
    ----------
    function : callable
        Picklable (a module-level function, or a `functools.partial` of one with picklable
        arguments), as are ``items`` and what it returns.
    items : sequence
    jobs : int
        Worker processes, 1 or more (1: one worker process all the same).
    done : callable(int, float), optional
        Called here, in the calling process, as each call finishes (in the order they
        finish): the item's index and the call's seconds.
    what : str
        What a call is, for messages (``"budget rerun"``).
    setup : callable, optional
        Called in each worker as it starts, before any call (picklable too): state the
        calls share, such as the cuts this process made (`machinesim.budget`).

    Returns
    -------
    list
        The results, in the order of ``items``.

    Raises
    ------
    InputError
        ``function`` or an item that does not pickle.
    WorkerDied
        A worker that ended without an answer.
    """
    jobs = check_jobs(jobs, what)
    for name, value in (("function", function), ("items", list(items)), ("setup", setup)):
        try:
            pickle.dumps(value)
        except Exception as error:  # PicklingError, AttributeError, TypeError: all say why
            raise InputError(f"{what}s on worker processes: the {name} must pickle (a "
                             f"module-level function or a functools.partial of one, with "
                             f"plain arguments); {value!r:.80} does not ({error}); run them "
                             "in this process instead (jobs 1)", key="jobs") from None
    results: list = [None] * len(items)
    if not items:
        return results
    context = multiprocessing.get_context("spawn")
    jobs = min(jobs, len(items))
    cores = None
    if hasattr(os, "sched_setaffinity") and jobs >= usable_cores():  # the workers fill them
        cores = context.SimpleQueue()
        for k in range(jobs):
            cores.put(sorted(os.sched_getaffinity(0))[k % usable_cores()])
    pool = None
    running: dict = {}
    try:
        # the workers start (in submit) with SIGINT blocked; a Ctrl-C meanwhile is raised
        # as the block ends, here, where the workers it started are stopped: raised outside
        # this try, it left them running the calls, the parent gone
        with sigint_blocked():
            pool = ProcessPoolExecutor(jobs, mp_context=context, initializer=_worker_start,
                                       initargs=(cores, setup))
            for i, item in enumerate(items):
                running[pool.submit(_timed, pickle.dumps((function, item)), what)] = i
        while running:
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in finished:
                i = running.pop(future)
                try:
                    seconds, results[i] = future.result()
                except BrokenProcessPool:
                    raise WorkerDied(f"a worker process of the {what}s ended without an "
                                     "answer (killed: out of memory, or by a signal); the "
                                     "others were stopped") from None
                if done is not None:
                    done(i, seconds)
    except BaseException:  # Ctrl-C, SIGTERM (Terminated), a worker's error
        if pool is not None:
            with ctrl_c_deferred():  # a second Ctrl-C waits until every worker is gone
                _stop(pool)
        raise
    pool.shutdown(wait=True)
    return results


def _stop(pool: ProcessPoolExecutor) -> None:
    """End ``pool``'s workers now: queued calls cancelled, running ones ended (SIGTERM, then
    SIGKILL after `STOP_WAIT_S`), every worker waited for."""
    # ProcessPoolExecutor ends running calls only from Python 3.14 (terminate_workers)
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    deadline = time.monotonic() + STOP_WAIT_S
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
            process.join()
    # every worker is joined; the pool's manager thread sees them gone and ends by itself
    # (waiting for it here had the stop wait on a thread, not a worker: a Ctrl-C under a
    # loaded CI machine ran past 30 s)
    pool.shutdown(wait=False)
