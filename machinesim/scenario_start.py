"""Imported first by each scenario script, before the libraries it loads: a Ctrl-C while
they load (numpy, Pinocchio, SciPy: a second or two) ends in one line on stderr and status
130, as one during the run does (`machinesim.scenario_runs.scenario_status`), not in a
traceback of the import it stopped (or in numpy's "Importing the numpy C-extensions failed",
when the Ctrl-C lands inside numpy's own loading). A SIGTERM (``kill PID``) or SIGHUP (a
closed terminal) while they load ends alike, in ``NAME: terminated; nothing was written``
(status 143) or ``hung up`` (129), as the run's own handlers say them: before, the process
died of the signal with no line (a parent saw -15, not 143).

Nothing is written before the run begins, so the handler says so and ends the process at
once (`os._exit`). It is installed only where the usual handler is (Python's own for SIGINT,
the default action for SIGTERM and SIGHUP: a background job started with SIGINT ignored
keeps ignoring it; a budget's worker process keeps SIGTERM's and SIGHUP's, `_WORKER`) and
only when the script run is a scenario (``sys.argv[0]`` in a
``scenarios`` folder: a test that imports a scenario's module keeps its own handlers);
`scenario_status` puts the usual handlers back when the run begins (`loaded`).
ruff's isort keeps this import first (pyproject.toml, its own section).
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

#: Each signal handled while the scenario loads: (the handler it replaces, what the line
#: says, the exit status: 128 + the signal, as `machinesim._interrupts` gives them).
_STOPS = {signal.SIGINT: (signal.default_int_handler, "interrupted", 130),
          signal.SIGTERM: (signal.SIG_DFL, "terminated", 143),
          **({signal.SIGHUP: (signal.SIG_DFL, "hung up", 129)}
             if hasattr(signal, "SIGHUP") else {})}


#: The program's name in the line `on_ctrl_c` writes (`install`).
_NAME = "scenario"


def on_ctrl_c(signum, frame) -> None:
    """SIGINT (or SIGTERM, SIGHUP) while the program loads: one line, status 130 (143, 129)."""
    _, how, status = _STOPS[signum]
    try:
        os.write(2, f"{_NAME}: {how}; nothing was written\n".encode())
    except OSError:  # no stderr (2>&-, or a terminal that closed): the status says it
        pass
    os._exit(status)


def loaded() -> None:
    """The program's run begins: the usual handlers again."""
    for number, (usual, _, _) in _STOPS.items():
        if signal.getsignal(number) is on_ctrl_c:
            signal.signal(number, usual)


def finished() -> None:
    """The program's work is done and said (its files written or not, its last line
    printed): a Ctrl-C, SIGTERM or SIGHUP from here to the process's exit is ignored, where
    `install` handled them (the command, a scenario) and the usual handler is back. Python
    puts the default action back as it finalises (some 0.3 s after a cut, longer after a
    campaign), and a stop there ended the process by its signal with no line: a ``kill``
    just after a cut's "wrote part.ply" or a campaign's "campaign: 6 trials ..." gave -15,
    not 0 (the files whole and said) nor 143 with its line."""
    if not _INSTALLED:
        return
    for number, (usual, _, _) in _STOPS.items():
        if signal.getsignal(number) is usual:
            signal.signal(number, signal.SIG_IGN)


#: Whether `install` ran: the program is the command or a scenario (`finished`).
_INSTALLED = False


#: A budget's worker (`machinesim._processes`, spawned: its ``python -c`` loaded
#: multiprocessing.spawn before it runs the scenario's script as ``__mp_main__``, with the
#: scenario's argv) keeps SIGTERM's and SIGHUP's default: the parent ends its workers with
#: SIGTERM, and says itself what was stopped.
_WORKER = "multiprocessing.spawn" in sys.modules

def install(name: str) -> None:
    """Handle each of `_STOPS` with `on_ctrl_c`, naming the program ``name``, where its usual
    handler is (not in a spawned worker, `_WORKER`, for SIGTERM and SIGHUP). Also the command
    line's (`machinesim._cli_start`)."""
    global _NAME, _INSTALLED
    _NAME = name
    _INSTALLED = True
    for number, (usual, _, _) in _STOPS.items():
        if signal.getsignal(number) is usual and not (_WORKER and usual is signal.SIG_DFL):
            signal.signal(number, on_ctrl_c)


if Path(sys.argv[0] if sys.argv else "").resolve().parent.name == "scenarios":
    install(Path(sys.argv[0]).stem or "scenario")
