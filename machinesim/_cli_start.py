"""Imported first by `machinesim.cli`, before the modules the command line loads: a Ctrl-C
while they load (about 0.13 s of the command's start) ends in one line on stderr and status
130, as one in the command does, not in a traceback of the import it stopped; a SIGTERM or
SIGHUP there in ``machinesim: terminated; nothing was written`` (143) or ``hung up`` (129).

As `machinesim.scenario_start` does for a scenario: nothing is written before the command
runs, so the handler says so and ends the process at once (`os._exit`). It is installed only
where Python's own handler is (a background job started with SIGINT ignored keeps ignoring
it) and only when the program run is the command (``sys.argv[0]`` the ``machinesim`` script,
or ``python -m machinesim``'s ``machinesim/__main__.py``: a test or a program that imports
machinesim.cli keeps its own Ctrl-C); `machinesim.cli.main` puts Python's handler back as it
begins (`loaded`). What comes before this import, Python's own start and ``import
machinesim`` (about 0.1 s), still ends in Python's traceback.
ruff's isort keeps this import first (pyproject.toml, its own section).
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

#: Each signal handled while the command line loads: (the handler it replaces, what the line
#: says, the exit status, 128 + the signal as `machinesim._interrupts` gives them). SIGTERM
#: and SIGHUP there ended the process by the signal itself, with no line (a parent saw -15).
_STOPS = {signal.SIGINT: (signal.default_int_handler, "interrupted", 130),
          signal.SIGTERM: (signal.SIG_DFL, "terminated", 143),
          **({signal.SIGHUP: (signal.SIG_DFL, "hung up", 129)}
             if hasattr(signal, "SIGHUP") else {})}

#: A process multiprocessing spawned from the command (a campaign's local Dask workers run
#: its main module again, with its argv; its ``python -c`` loaded multiprocessing.spawn
#: first) keeps SIGTERM's and SIGHUP's default: it never reaches `loaded`, and its parent
#: ends it with SIGTERM.
_WORKER = "multiprocessing.spawn" in sys.modules


def on_ctrl_c(signum, frame) -> None:
    """SIGINT (SIGTERM, SIGHUP) while the command line loads: one line, status 130 (143,
    129)."""
    _, how, status = _STOPS[signum]
    try:
        os.write(2, f"machinesim: {how}; nothing was written\n".encode())
    except OSError:  # started without a stderr (2>&-): the status says it
        pass
    os._exit(status)


def loaded() -> None:
    """The command begins: the usual handlers again."""
    for number, (usual, _, _) in _STOPS.items():
        if signal.getsignal(number) is on_ctrl_c:
            signal.signal(number, usual)


def _is_the_command(argv0: str) -> bool:
    path = Path(argv0)
    return path.name.removesuffix(".exe") == "machinesim" or (
        path.name == "__main__.py" and path.parent.name == "machinesim")


if _is_the_command(sys.argv[0] if sys.argv else ""):
    for _number, (_usual, _, _) in _STOPS.items():
        if signal.getsignal(_number) is _usual and not (_WORKER and _usual is signal.SIG_DFL):
            signal.signal(_number, on_ctrl_c)
