"""The cores this process may run on."""

from __future__ import annotations

import os


def usable_cores() -> int:
    """The CPUs this process is allowed to run on (its affinity set on Linux, under
    ``taskset`` or a container's cpuset), else the machine's count; at least 1.

    `os.cpu_count` counts the machine's CPUs, which a process pinned to some of them does
    not have: a pool of that many workers would share the allowed cores."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return os.cpu_count() or 1
