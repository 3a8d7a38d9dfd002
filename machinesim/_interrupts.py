"""How a run stops: Ctrl-C, SIGTERM and SIGHUP, remembered, held back where a swap must finish,
and told.

A Ctrl-C (SIGINT), a ``kill`` (SIGTERM) or a closed terminal (SIGHUP) within
`ctrl_c_remembered` is raised as a KeyboardInterrupt (`Terminated` for SIGTERM, `HungUp` for
SIGHUP) and remembered, so that `machinesim._io` and `machinesim._staged` write nothing
after it even when a library swallowed it; `ctrl_c_deferred` holds one back until a rename
or a folder swap is done; `stopped` names the stop and its exit status.
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

#: Set by `ctrl_c_remembered`'s handler: a Ctrl-C arrived, even if a library swallowed it.
_ctrl_c_seen = False
#: Within `ctrl_c_remembered`, the files `machinesim._io` has put in place whole so far (a
#: stop held back until a rename was done is raised after it: the command must not then say
#: that nothing was written), given to the stop as it leaves; None outside.
_written: list[str] | None = None


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill PID``, a job scheduler's stop, a container's shutdown) within
    `ctrl_c_remembered`: handled as a Ctrl-C is (nothing half written, staging folders
    removed), reported as what it is, with status 143 (`stopped`)."""


class HungUp(Terminated):
    """SIGHUP (the terminal the run was started from closed, an ssh session dropped) within
    `ctrl_c_remembered`: handled as SIGTERM is, reported as what it is, with status 129.
    Its default action had ended the process where it stood, leaving the temporary file of
    an output being written (``.part.ply.*.tmp``) behind for good."""


#: Exit statuses of a run stopped by Ctrl-C, SIGTERM or SIGHUP (128 + the signal, as shells
#: say). SIGHUP's number is POSIX's (1): Windows has no such signal.
EXIT_INTERRUPTED = 128 + signal.SIGINT
EXIT_TERMINATED = 128 + signal.SIGTERM
EXIT_HUNG_UP = 128 + 1


def stopped(stop: KeyboardInterrupt) -> tuple[str, int]:
    """What to call a run ended by ``stop`` and its exit status: ``("interrupted", 130)``
    after a Ctrl-C, ``("terminated", 143)`` after SIGTERM, ``("hung up", 129)`` after
    SIGHUP."""
    if isinstance(stop, HungUp):
        return "hung up", EXIT_HUNG_UP
    if isinstance(stop, Terminated):
        return "terminated", EXIT_TERMINATED
    return "interrupted", EXIT_INTERRUPTED


#: The kind of the last stop `_on_ctrl_c` raised (KeyboardInterrupt, `Terminated`, `HungUp`),
#: for `_stop_behind` when a library turned it into another exception.
_stop_kind: type[KeyboardInterrupt] = KeyboardInterrupt


def _on_ctrl_c(signum, frame):
    global _ctrl_c_seen, _stop_kind
    _ctrl_c_seen = True
    _stop_kind = (HungUp if signum == getattr(signal, "SIGHUP", None)
                  else Terminated if signum == signal.SIGTERM else KeyboardInterrupt)
    raise _stop_kind


def _stops_unsaid(hook):
    """``hook`` (`sys.unraisablehook`) but for a stop `_on_ctrl_c` raised where Python cannot
    raise it, in a ``__del__`` or a weakref callback: Python reports it and goes on, and the
    stop is remembered (`_ctrl_c_seen`) and said in the command's one line. A ``kill`` of a
    campaign as it assembled its results printed "Exception ignored in: <function
    WeakKeyDictionary.__init__.<locals>.remove ...>", a traceback and
    "machinesim._interrupts.Terminated:" before its line."""
    def unsaid(unraisable) -> None:
        if not (_ctrl_c_seen and isinstance(unraisable.exc_type, type)
                and issubclass(unraisable.exc_type, KeyboardInterrupt)):
            hook(unraisable)
    return unsaid


def _stop_behind(error: BaseException) -> KeyboardInterrupt | None:
    """The stop behind ``error``, an exception that is no KeyboardInterrupt: one in its
    chain (``__cause__``, ``__context__``), or, when a stop was seen (`_ctrl_c_seen`: a
    library caught it and raised something else, or nothing), a new one of its kind; None
    when there is none. A Ctrl-C landing as a pybind11 module initialised (matplotlib's,
    scipy's, imported as the command ran) came out as "ImportError: initialization failed",
    its cause the KeyboardInterrupt, and the command said "internal error: ImportError:
    initialization failed", status 1."""
    seen, link = set(), error
    while link is not None and id(link) not in seen:
        if isinstance(link, KeyboardInterrupt):
            return link
        seen.add(id(link))
        link = link.__cause__ or link.__context__
    return _stop_kind() if _ctrl_c_seen else None


#: The signals `ctrl_c_remembered` handles, each with the handler it replaces (Python's own
#: for SIGINT, the default action, ending the process at once, for SIGTERM and SIGHUP).
_STOPS = ((signal.SIGINT, signal.default_int_handler), (signal.SIGTERM, signal.SIG_DFL),
          *(((signal.SIGHUP, signal.SIG_DFL),) if hasattr(signal, "SIGHUP") else ()))


@contextmanager
def ctrl_c_remembered() -> Iterator[None]:
    """Within the block, a Ctrl-C is remembered as well as raised, and nothing is written after it.

    Some libraries import their optional parts inside ``except BaseException`` (trimesh,
    for one), so a Ctrl-C that lands there is swallowed and the run would go on to write its
    files and exit 0. With this handler `write_together` refuses to rename anything into
    place once a Ctrl-C was seen, whoever caught it. SIGTERM is handled the same way, raised
    as `Terminated` (a KeyboardInterrupt): without it a ``kill`` ended the process where it
    stood and left its staging folder and temporary files behind; and so is SIGHUP, raised as
    `HungUp` (a `Terminated`), for the same reason. Each handler is installed
    only where the usual one is (a background job started with SIGINT ignored keeps
    ignoring it), and only in the main thread (where signals arrive); the old handlers are
    put back on leaving. An exception other than a KeyboardInterrupt that leaves the block
    after a stop (with one in its chain, or once one was seen) leaves as that stop
    (`_stop_behind`): the run was interrupted, whatever a library made of it. A stop raised
    where Python only reports it (a ``__del__``, a weakref callback) is not reported
    (`_stops_unsaid`): it is remembered, and the command says it in its line.
    """
    global _ctrl_c_seen, _written
    main = threading.current_thread() is threading.main_thread()
    previous = {number: signal.getsignal(number) for number, _ in _STOPS}
    ours = [number for number, usual in _STOPS if main and previous[number] is usual]
    for number in ours:
        signal.signal(number, _on_ctrl_c)
    hook = sys.unraisablehook
    if ours:
        sys.unraisablehook = _stops_unsaid(hook)
    written, _written = _written, []
    try:
        yield
    except KeyboardInterrupt as stop:
        stop.written = tuple(dict.fromkeys(_written))  # for `written_before`, past the block
        raise
    except Exception as error:  # a stop a library turned into another exception
        stop = _stop_behind(error)
        if stop is None:
            raise
        stop.written = tuple(dict.fromkeys(_written))
        if stop.__traceback__ is not None:  # the one in its chain: no loop of causes
            raise stop from None
        raise stop from error
    finally:
        for number in ours:
            signal.signal(number, previous[number])
        sys.unraisablehook = hook
        _ctrl_c_seen = False
        _written = written


def written_before(stop: KeyboardInterrupt, nothing: str = "nothing was written") -> str:
    """What a command ended by ``stop`` (raised out of `ctrl_c_remembered`) had written, for
    its last line: ``nothing`` when it put no file in place, else which files it wrote whole
    before the stop (``"a.html was written whole before it; nothing else was written"``). A
    stop that arrives during a rename is held until the renames are done, and a page is
    written before its screenshot is taken: "nothing was written" was then untrue."""
    names = getattr(stop, "written", ())
    if not names:
        return nothing
    listed = names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"
    return (f"{listed} {'was' if len(names) == 1 else 'were'} written whole before it; "
            "nothing else was written")


@contextmanager
def ctrl_c_deferred() -> Iterator[None]:
    """Within the block a Ctrl-C (or SIGTERM) is held back, and raised (by the handler that
    was there) on leaving it: a folder swap is never left half done. Only in the main
    thread, where the handlers can be set, and only for a signal with a Python handler;
    elsewhere the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {number: signal.getsignal(number) for number, _ in _STOPS}
    held: list[int] = []
    for number, handler in previous.items():
        if callable(handler):
            signal.signal(number, lambda signum, frame: held.append(signum))
    try:
        yield
    finally:
        for number, handler in previous.items():
            if callable(handler):
                signal.signal(number, handler)
    for number in dict.fromkeys(held):
        previous[number](number, None)


@contextmanager
def sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in this thread within the block, and so in every thread and process
    started from it (a signal mask is inherited by new threads, and across fork and exec):
    a local cluster's nannies and workers, a budget's rerun processes. Signals the process
    is sent meanwhile stay pending, and reach it as the block ends. Elsewhere than the main
    thread on POSIX, the block runs as it is."""
    if not hasattr(signal, "pthread_sigmask") or \
            threading.current_thread() is not threading.main_thread():
        yield
        return
    from multiprocessing import resource_tracker

    # its first start (in the first worker's spawn) unblocks SIGINT in the thread that
    # starts it, and so in every thread started from that one: started here, before
    resource_tracker.ensure_running()
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


__all__ = ["EXIT_HUNG_UP", "EXIT_INTERRUPTED", "EXIT_TERMINATED", "HungUp", "Terminated",
           "ctrl_c_remembered", "sigint_blocked", "stopped", "written_before"]
