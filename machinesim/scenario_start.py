"""Imported first by each scenario script, before the libraries it loads: a Ctrl-C while
they load (numpy, Pinocchio, SciPy: a second or two) ends in one line on stderr and status
130, as one during the run does (`machinesim.scenario_runs.scenario_status`), not in a
traceback of the import it stopped (or in numpy's "Importing the numpy C-extensions failed",
when the Ctrl-C lands inside numpy's own loading).

Nothing is written before the run begins, so the handler says so and ends the process at
once (`os._exit`). It is installed only where Python's own handler is (a background job
started with SIGINT ignored keeps ignoring it) and only when the script run is a scenario
(``sys.argv[0]`` in a ``scenarios`` folder: a test that imports a scenario's module keeps
its own Ctrl-C); `scenario_status` puts Python's handler back when the run begins.
ruff's isort keeps this import first (pyproject.toml, its own section).
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path


def on_ctrl_c(signum, frame) -> None:
    """SIGINT while the scenario loads: one line, status 130."""
    name = Path(sys.argv[0]).stem or "scenario"
    os.write(2, f"{name}: interrupted; nothing was written\n".encode())
    os._exit(130)


def loaded() -> None:
    """The scenario's run begins: Python's own handler again."""
    if signal.getsignal(signal.SIGINT) is on_ctrl_c:
        signal.signal(signal.SIGINT, signal.default_int_handler)


if (signal.getsignal(signal.SIGINT) is signal.default_int_handler
        and Path(sys.argv[0] if sys.argv else "").resolve().parent.name == "scenarios"):
    signal.signal(signal.SIGINT, on_ctrl_c)
