"""The memory this process may use, and a cap on it that turns running out into MemoryError.

A cut whose unions grow past the machine's memory (manifold3d's booleans of many
near-coincident sweeps: passes of an end mill on a workpiece tilted against Z, before such
cuts were made in the tool's frame, `machinesim.cutting.frame`) was ended by the kernel's
out-of-memory killer, with no message and with whatever else it chose to kill.
Capped at the memory there is, the allocation that would pass it fails instead (numpy's and
manifold3d's alike raise MemoryError), and the command line says so in one line.

"The memory there is" is what the machine has free when the command starts (the kernel's
``MemAvailable``), added to the address space the process holds already, within the
machine's or its container's total: capped at the total alone, a cut on a machine where
other processes held 3 of its 23 GB grew to 21.6 GB, under the 23 GB cap, and was ended by
the out-of-memory killer with no message (a 100,000-line spiral with `ball:0.5`, 227 kB a
sweep, `machinesim cut` of a new-user pass).

`memory_capped` holds the cap for a command's or a scenario's work and restores the limit
after it. A process started meanwhile inherits the cap, so a command that may start a web
browser (Chromium reserves tens of GB of address space, and does not start under such a
cap) runs without it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

#: Environment variable: the cap in GB (a number > 0, `given_cap`) instead of the memory there
#: is (for a shared machine, or to try the message).
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
#: Where Linux states the memory free for new work (``MemAvailable``: free memory and the
#: caches it can drop) and this process's address space (``VmSize``), in kB.
MEMINFO = "/proc/meminfo"
PROCESS_STATUS = "/proc/self/status"
#: The largest cap set (bytes, 4 EiB): more than any machine has, within what setrlimit takes.
_MOST = 1 << 62


def _kilobytes(path: str, key: str) -> int | None:
    """Bytes of the ``key:  N kB`` line of a /proc file, None where there is none."""
    try:
        lines = Path(path).read_text().splitlines()
    except OSError:
        return None
    for line in lines:
        name, _, value = line.partition(":")
        words = value.split()
        if name == key and words and words[0].isdigit():
            return int(words[0]) * 1024
    return None


def usable_memory() -> int:
    """Bytes of address space this process may use: the machine's physical memory, or its
    container's limit when smaller, and no more than the memory free now (``MemAvailable``)
    beside the address space the process holds already (``VmSize``), where Linux states
    them: what other processes hold is not there to take."""
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    for path in CGROUP_LIMITS:
        try:
            text = Path(path).read_text().strip()
        except OSError:
            continue
        if text.isdigit():
            total = min(total, int(text))
    available = _kilobytes(MEMINFO, "MemAvailable")
    held = _kilobytes(PROCESS_STATUS, "VmSize")
    if available is not None and held is not None:
        total = min(total, held + available)
    return total


def given_cap() -> int | None:
    """Bytes of the cap ``$MACHINESIM_MEMORY_GB`` gives (GB, a number > 0), None where it
    is unset or empty. Anything else is an `InputError` naming it: a value that was no
    number ("abc", "8G") or below zero had been dropped without a word (the command ran
    under the memory there is), 0 capped the command at nothing (``machinesim machines``
    ended "out of memory"), and "inf" in an internal error (OverflowError). A cap at or
    below the address space the process holds already (``VmSize``, where Linux states it)
    is refused too, naming what it holds: it leaves no room, as 0 did (1e-9 and 0.05 ended
    ``machinesim machines`` in "out of memory" alike, blaming a spec or program)."""
    from machinesim.exceptions import InputError

    given = os.environ.get(LIMIT_VARIABLE, "").strip()
    if not given:
        return None
    try:
        gb = float(given)
    except ValueError:
        gb = math.nan
    if not (math.isfinite(gb) and gb > 0.0):
        raise InputError(f"got {given!r}; expected the memory cap in GB, a number > 0 (e.g. "
                         "8), or the variable unset (the memory there is)", key=LIMIT_VARIABLE)
    cap = min(int(gb * (1 << 30)), _MOST)
    held = _kilobytes(PROCESS_STATUS, "VmSize")
    if held is not None and cap <= held:
        raise InputError(f"got {given!r}, a cap of {cap / (1 << 30):.3g} GB, where this "
                         f"process holds {held / (1 << 30):.3g} GB of address space already, "
                         "before any work: every allocation would fail ('out of memory'); "
                         f"expected the memory cap in GB, a number above "
                         f"{held / (1 << 30):.3g} (e.g. 8), or the variable unset (the memory "
                         "there is)", key=LIMIT_VARIABLE)
    return cap


def limit_memory() -> int | None:
    """Cap this process's address space (``RLIMIT_AS``) at `usable_memory` (or
    ``$MACHINESIM_MEMORY_GB``), never below `FLOOR` nor above a cap already set; returns
    the cap in bytes, or None where there is no such limit (not POSIX) or none applies."""
    try:
        import resource
    except ImportError:  # Windows
        return None
    given = given_cap()
    limit = given if given is not None else max(usable_memory(), FLOOR)
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
