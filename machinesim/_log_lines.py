"""Progress of a long command as whole lines on stderr, for a log (stderr not a terminal)."""

from __future__ import annotations

import sys
import time

#: A log gets its first progress line once the work has run this many seconds (short work
#: says nothing), then at most one every `LOG_EVERY_S`, and one at the end once any was
#: written.
LOG_AFTER_S = 10.0
LOG_EVERY_S = 30.0


def log_lines(stage: str, unit: str, clock=time.monotonic, after_s: float = LOG_AFTER_S,
              every_s: float = LOG_EVERY_S):
    """``progress(done, total, stage=stage)`` writing ``  {stage}: {done}/{total} {unit}
    ({percent} %), {seconds} s`` lines: nothing for work shorter than ``after_s``, then a
    line at most every ``every_s``, and one at the end once any was written."""
    start = clock()
    due = [start + after_s, False]  # next line's time, whether any was written

    def show(done: int, total: int, stage: str = stage) -> None:
        now = clock()
        if now >= due[0] or (done >= total and due[1]):
            sys.stderr.write(f"  {stage}: {done}/{total} {unit} "
                             f"({100 * done // max(total, 1)} %), {now - start:.0f} s\n")
            sys.stderr.flush()
            due[0], due[1] = now + every_s, True

    return show


__all__ = ["LOG_AFTER_S", "LOG_EVERY_S", "log_lines"]
