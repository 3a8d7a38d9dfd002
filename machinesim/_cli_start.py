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

# the handlers, their line and statuses are a scenario's (one mechanism for both programs)
from machinesim.scenario_start import finished, install, loaded, on_ctrl_c  # noqa: F401

import sys
from pathlib import Path


def _is_the_command(argv0: str) -> bool:
    path = Path(argv0)
    return path.name.removesuffix(".exe") == "machinesim" or (
        path.name == "__main__.py" and path.parent.name == "machinesim")


if _is_the_command(sys.argv[0] if sys.argv else ""):
    install("machinesim")
