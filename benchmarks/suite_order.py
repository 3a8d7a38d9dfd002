"""The suite's wall time on 2 pytest-xdist workers under ``--dist worksteal``, simulated on
measured per-test durations: the collected order against tests/conftest.py's order (the
files of `SLOWEST_FILES_S` first), over draws of noise on every duration.

Run: ``.venv/bin/python benchmarks/suite_order.py --collected FILE DURATIONS...`` where each
DURATIONS file is the output of ``pytest -n 2 --durations=0`` on some of the test files and
FILE the output of ``pytest --collect-only -q`` taken without this order
(``git stash`` the hook, or collect on an older commit). Prints, per order, the median, mean
and largest seconds by which the simulated run exceeds half the summed durations (the
bound two workers cannot beat).

The simulation follows pytest-xdist 3.8's worksteal scheduler as its source reads: each of
the 2 workers is handed a contiguous half of the collection; a worker with fewer than 2
queued tests (the one it runs and the next) takes half of the tail of the longest queue,
keeping that queue at 2 or more; when nothing can be taken it is shut down and finishes its
queue. Checked against measured groups of files: 646 s and 319 s simulated, 682 s and 332 s
measured (collection and start-up included there).
"""

from __future__ import annotations

import argparse
import heapq
import random
import re
import statistics
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import SLOWEST_FILES_S  # noqa: E402

MIN_PENDING = 2
LINE = re.compile(r"^\s*([0-9.]+)s (setup|call|teardown)\s+(\S.*)$")


def read_durations(paths: list[Path]) -> dict[str, float]:
    """Seconds per node id: setup, call and teardown summed."""
    seconds: dict[str, float] = defaultdict(float)
    for path in paths:
        for line in path.read_text().splitlines():
            match = LINE.match(line)
            if match:
                seconds[match.group(3).strip()] += float(match.group(1))
    return seconds


def worksteal(times: list[float], workers: int = 2) -> float:
    """The simulated wall time of tests of ``times`` (collection order) on ``workers``."""
    queues: dict[int, list[int]] = {w: [] for w in range(workers)}
    pending = list(range(len(times)))
    shut: set[int] = set()

    def schedule() -> None:
        idle = [w for w in queues if w not in shut and len(queues[w]) < MIN_PENDING]
        if not idle:
            return
        if pending:
            for k, w in enumerate(idle):
                count = len(pending) // (len(idle) - k)
                queues[w].extend(pending[:count])
                del pending[:count]
            idle = [w for w in queues if w not in shut and len(queues[w]) < MIN_PENDING]
            if not idle:
                return
        longest = max((w for w in queues if w not in shut), key=lambda w: len(queues[w]))
        queue = queues[longest]
        count = min(len(queue) // 2, max(0, len(queue) - MIN_PENDING))
        if count == 0:
            shut.update(idle)
            return
        pending.extend(queue[-count:])
        del queue[-count:]
        schedule()

    schedule()
    running: dict[int, int] = {}
    events: list[tuple[float, int]] = []
    now = end = 0.0

    def start() -> None:
        for w, queue in queues.items():
            if w not in running and queue:
                running[w] = queue[0]
                heapq.heappush(events, (now + times[queue[0]], w))

    start()
    while events:
        now, w = heapq.heappop(events)
        queues[w].remove(running.pop(w))
        end = now
        schedule()
        start()
    return end


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("durations", nargs="+", type=Path)
    parser.add_argument("--collected", type=Path, required=True)
    parser.add_argument("--draws", type=int, default=30)
    parser.add_argument("--noise", type=float, default=0.3, help="sigma of lognormal noise")
    args = parser.parse_args()
    collected = [line.strip() for line in args.collected.read_text().splitlines()
                 if "::" in line]
    seconds = read_durations(args.durations)
    first = sorted(collected, key=lambda n: -SLOWEST_FILES_S.get(Path(n.split("::")[0]).name,
                                                                 0.0))
    orders = {"collected": collected, "slowest files first": first}
    rng = random.Random(1)
    over: dict[str, list[float]] = {name: [] for name in orders}
    for _ in range(args.draws):
        drawn = {n: s * rng.lognormvariate(0.0, args.noise) for n, s in seconds.items()}
        bound = sum(drawn.get(n, 0.005) for n in collected) / 2
        for name, order in orders.items():
            over[name].append(worksteal([drawn.get(n, 0.005) for n in order]) - bound)
    print(f"{len(collected)} tests, {sum(n in seconds for n in collected)} with a duration, "
          f"{sum(seconds.get(n, 0.0) for n in collected):.0f} s in all; {args.draws} draws")
    for name, values in over.items():
        print(f"{name:>20}: over the bound median {statistics.median(values):.1f} s, "
              f"mean {statistics.mean(values):.1f} s, largest {max(values):.1f} s")


if __name__ == "__main__":
    main()
