"""The memory this process may use, and a cap on it that turns running out into MemoryError.

A cut whose unions grow past the machine's memory (manifold3d's booleans of many
near-coincident sweeps: passes of an end mill on a workpiece tilted against Z, before such
cuts were made in the tool's frame, `machinesim.cutting.frame`) was ended by the kernel's
out-of-memory killer, with no message and with whatever else it chose to kill.
Capped at the memory there is, the allocation that would pass it fails instead (numpy's and
manifold3d's alike raise MemoryError), and the command line says so in one line.

`memory_capped` holds the cap for a command's or a scenario's work and restores the limit
after it. A process started meanwhile inherits the cap, so a command that may start a web
browser (Chromium reserves tens of GB of address space, and does not start under such a
cap) runs without it.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

#: Environment variable: the cap in GB instead of the memory there is (for a shared machine,
#: or to try the message).
LIMIT_VARIABLE = "MACHINESIM_MEMORY_GB"
#: No cap below this (bytes): the interpreter and its libraries reserve about 1-2 GB of
#: address space before any work, and a smaller machine is better left to its own swap.
FLOOR = 4 << 30
#: What the command line and the scenarios say when memory runs out.
OUT_OF_MEMORY = (
    f"a spec or program asks for more than this machine has (capped at its memory, or at "
    f"${LIMIT_VARIABLE}). One known cause: a cut of many sweeps whose faces nearly coincide "
    "(passes repeated while the tool turns), whose unions can grow that large; cut a window "
    "of it (--roi), or fewer passes")
#: Where a cgroup (a container) states its memory limit: v2, then v1.
CGROUP_LIMITS = ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes")


def usable_memory() -> int:
    """Bytes of memory this process may use: the machine's physical memory, or its
    container's limit when smaller."""
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    for path in CGROUP_LIMITS:
        try:
            text = Path(path).read_text().strip()
        except OSError:
            continue
        if text.isdigit():
            total = min(total, int(text))
    return total


def limit_memory() -> int | None:
    """Cap this process's address space (``RLIMIT_AS``) at `usable_memory` (or
    ``$MACHINESIM_MEMORY_GB``), never below `FLOOR` nor above a cap already set; returns
    the cap in bytes, or None where there is no such limit (not POSIX) or none applies."""
    try:
        import resource
    except ImportError:  # Windows
        return None
    given = os.environ.get(LIMIT_VARIABLE)
    try:
        limit = int(float(given) * (1 << 30)) if given else max(usable_memory(), FLOOR)
    except ValueError:
        return None
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    if soft != resource.RLIM_INFINITY and soft <= limit:
        return soft
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    return limit


@contextmanager
def memory_capped(apply: bool = True) -> Iterator[None]:
    """`limit_memory` for the work inside, the limit as it was restored after (nothing with
    ``apply`` False)."""
    try:
        import resource
    except ImportError:  # Windows
        yield
        return
    before = resource.getrlimit(resource.RLIMIT_AS)
    if apply:
        limit_memory()
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, before)
