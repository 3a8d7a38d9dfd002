"""Campaign throughput: trials/s with 1 and 2 Dask workers, and the scheduler's per-trial cost.

Run: ``.venv/bin/python benchmarks/campaign.py [--trials 12]`` (about 1 min on 2 free cores).

The trial is probing only: paper 002's three reference spheres probed at C = 0 and 180 deg
and the setting identified (`machinesim campaign workpiece_setting --identify-only`), the
robot's landing drawn with 30 um repeatability. Each worker count gets its own LocalCluster
as the runner makes it (processes, one thread and one core each), started and warmed up
(one trial per worker, which loads the machine) before the clock starts; the figure is the
wall time of ``trials`` trials through ``machinesim.campaign.runner``'s own path
(`runner.windowed`: a few trials per worker thread in flight, as_completed, one file written
per trial). The goal on a 2-core machine: 2 workers >= 1.7 x one worker.

The scheduler's per-trial overhead is timed with an empty task (a function returning its
argument) sent for 500 keys on the 2-worker cluster: the round trip per task through
`runner.windowed`, which every trial pays on top of its own work.
"""

from __future__ import annotations

import argparse
import tempfile
import time

from machinesim.campaign import CampaignSpec, parse_vary, run_trial
from machinesim.campaign.results import CampaignFolder
from machinesim.campaign.runner import _client, windowed

SPEC = CampaignSpec("workpiece_setting", 10_000, (parse_vary("robot.repeatability=30um"),),
                    seed=1, identify_only=True)


def _identity(spec, i):
    return i


def trials_per_second(workers: int, trials: int) -> tuple[float, float]:
    """(trials/s, per-task scheduler overhead in s) on a fresh LocalCluster of ``workers``."""
    client, cluster = _client(workers, None, None)  # the runner's own local cluster
    with cluster, client, tempfile.TemporaryDirectory() as folder:
        warm = client.map(run_trial, [SPEC] * workers, range(10_000 - workers, 10_000),
                          pure=False)
        client.gather(warm)
        store = CampaignFolder(folder, SPEC.describe())
        began = time.perf_counter()
        for record in windowed(client, run_trial, SPEC, range(trials)):
            store.write_trial(record)
        rate = trials / (time.perf_counter() - began)
        began = time.perf_counter()
        for _ in windowed(client, _identity, None, range(500)):
            pass
        overhead = (time.perf_counter() - began) / 500
    return rate, overhead


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=12, help="trials per worker count")
    args = parser.parse_args()
    began = time.perf_counter()
    single = run_trial(SPEC, 9_000)["elapsed_s"]
    print(f"one probing-only trial in this process: {single:.2f} s")
    rates = {}
    for workers in (1, 2):
        rates[workers], overhead = trials_per_second(workers, args.trials)
        print(f"{workers} worker(s): {rates[workers]:.3f} trials/s over {args.trials} trials; "
              f"scheduler overhead {overhead * 1e3:.2f} ms per task (empty tasks)")
    speedup = rates[2] / rates[1]
    print(f"speed-up 2 workers / 1 worker: {speedup:.2f} x (goal >= 1.7 x on 2 free cores)")
    print(f"total {time.perf_counter() - began:.0f} s")


if __name__ == "__main__":
    main()
