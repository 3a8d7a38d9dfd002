"""One ``machinesim cut`` in a fresh process, timed end to end (shared by the benchmarks that
compare two variants of the engine: each variant patches it in ``runner`` before the CLI runs).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path


def timed_cut(runner: str, variant: str, arguments: list[str], report: Path,
              what: str) -> tuple[float, dict, str]:
    """Run ``python -c runner variant cut *arguments`` (which must write ``report``); return
    the wall time (s), the report's JSON and the process's stderr. A failed run ends the
    benchmark, naming ``what`` and how the process ended (a process the kernel killed for
    memory ends by signal 9 and leaves no stderr)."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", runner, variant, "cut", *arguments],
                          capture_output=True, text=True)
    if done.returncode:
        signal = -done.returncode
        ended = (f"exit status {done.returncode}" if signal < 0 else
                 f"killed by signal {signal}" + (" (SIGKILL: out of memory?)" if signal == 9
                                                  else ""))
        raise SystemExit(f"{what} ({variant}) failed, {ended}:\n{done.stderr}")
    seconds = time.perf_counter() - start
    return seconds, json.loads(report.read_text()), done.stderr
