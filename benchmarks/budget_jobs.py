"""Paper 002's error budget (the quick crown) with its reruns one after the other and on 2 workers.

Run: ``.venv/bin/python benchmarks/budget_jobs.py [--repeats 1] [--jobs 1,2]`` (about
10 min on 2 free cores); ``--scenario NAME`` times another scenario's default run end to
end instead (below).

`scenarios/workpiece_setting.py --quick`'s two loads are run once with every source on, as
its report does; then its budget (`scenario_budget`: nine sources switched off in turn, each
a rerun of both loads, five of them cutting the crown again) is timed end to end for each
``--jobs`` in turn, ``--repeats`` times, alternating, each starting from the cuts of those
first runs alone (`machinesim.lab.CUTS`: not the parts an earlier budget cut, which a later
one would hand back instead of cutting). Printed per jobs: the median wall
time, the CPU seconds of this process and its workers (user + sys), and the peak memory of
all of them together (the sum of their resident sets, sampled every 0.2 s); then whether
every budget equals the first to the bit (`Budget.to_dict`, floats compared exactly), with
the table of each jobs value's first budget printed.

With ``--scenario NAME`` (``sts_turning``, ``xy_plane_errors``, ...): the scenario's default
command line, ``scenarios/NAME.py --jobs J --out <a new folder>``, run as a process of its
own for each ``--jobs`` in turn, ``--repeats`` times, alternating, and timed whole (its run
with every source on, the budget, the report). Printed per jobs: the median wall time, the
CPU seconds of the scenario and its workers, the peak memory of all of them together (as
above); then whether every summary.json's ``budget`` rows equal the first's to the bit.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

ROOT = Path(__file__).resolve().parents[1]


def scenario():
    spec = importlib.util.spec_from_file_location(
        "workpiece_setting_scenario", ROOT / "scenarios" / "workpiece_setting.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class PeakMemory:
    """The largest sum of the resident sets of this process and its children while within."""

    def __init__(self, every_s: float = 0.2) -> None:
        self.every_s, self.peak, self.stop = every_s, 0, threading.Event()

    def _sample(self) -> None:
        me = psutil.Process()
        while not self.stop.is_set():
            total = 0
            for process in [me, *me.children(recursive=True)]:
                try:
                    total += process.memory_info().rss
                except psutil.Error:  # ended between the listing and the reading
                    pass
            self.peak = max(self.peak, total)
            self.stop.wait(self.every_s)

    def __enter__(self):
        self.thread = threading.Thread(target=self._sample, daemon=True)
        self.thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop.set()
        self.thread.join()


def cpu_seconds() -> float:
    """User + sys seconds of this process and of its children that ended and were waited for."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=1, help="budgets per jobs value")
    parser.add_argument("--jobs", default="1,2", help="the jobs values, comma-separated")
    parser.add_argument("--scenario", default=None,
                        help="time this scenario's default run end to end instead")
    args = parser.parse_args()
    jobs_values = [int(j) for j in args.jobs.split(",")]
    if args.scenario is not None:
        end_to_end(args.scenario, jobs_values, args.repeats)
        return

    from machinesim import Lab, load_machine
    from machinesim.cutting.memo import CutMemo
    from machinesim.experiment import run
    from machinesim.lab import CUTS
    from machinesim.procedures.workpiece_setting import EXPERIMENTS, RobotLoadedWorkpiece

    ws = scenario()
    captured = {}
    ws.scenario_status = lambda report, given, name: captured.update(args=given) or 0
    with tempfile.TemporaryDirectory() as folder:
        ws.main(["--quick", "--out", str(Path(folder) / "out")])
    options = captured["args"]
    ws.progress = lambda stage: (lambda text: None)  # the budget's lines: not timed here
    machine = load_machine("robonano_a0ib")
    realism = ws.lab_realism(options)
    errors = ws.loads(options)
    began = time.perf_counter()
    results = {load: run(RobotLoadedWorkpiece(load, quick=True),
                         Lab(machine, errors[load], seed=options.seed, realism=realism))
               for load in EXPERIMENTS}
    print(f"the two loads, every source on: {time.perf_counter() - began:.0f} s "
          f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)", flush=True)
    first_cuts = CutMemo()  # each budget starts from the cuts of the first runs alone
    first_cuts.update(CUTS)
    walls = {j: [] for j in jobs_values}
    cpus = {j: [] for j in jobs_values}
    peaks = {j: [] for j in jobs_values}
    budgets = []
    for _ in range(args.repeats):
        for jobs in jobs_values:
            options.jobs = jobs
            CUTS.clear()  # not the cuts an earlier budget made: every budget cuts its own
            CUTS.update(first_cuts)
            cpu, began = cpu_seconds(), time.perf_counter()
            with PeakMemory() as memory:
                budgets.append(ws.scenario_budget(machine, errors, options, realism, results))
            walls[jobs].append(time.perf_counter() - began)
            cpus[jobs].append(cpu_seconds() - cpu)
            peaks[jobs].append(memory.peak)
            print(f"  jobs {jobs}: {walls[jobs][-1]:.0f} s, {cpus[jobs][-1]:.0f} CPU s, "
                  f"peak {memory.peak / 2**30:.2f} GB (load average "
                  f"{os.getloadavg()[0]:.1f})", flush=True)
    print(f"budget of the quick crown ({len(budgets[0].sources)} reruns), median of "
          f"{args.repeats}:")
    _medians(jobs_values, walls, cpus, peaks)
    for jobs, budget in zip(jobs_values, budgets, strict=False):  # the first of each
        print(f"the budget with --jobs {jobs}:\n{budget.table()}")
    same = all(b.to_dict() == budgets[0].to_dict() for b in budgets)
    print(f"every budget equal to the first, to the bit: {same}")
    for k, budget in enumerate(budgets[1:], start=1):
        for first, row in zip(budgets[0].rows, budget.rows, strict=True):
            if row != first:
                print(f"  budget {k + 1}, {row.source} off, {row.figure}: after "
                      f"{row.after_without!r}, the first's {first.after_without!r}")


def _medians(jobs_values: list[int], walls: dict, cpus: dict, peaks: dict) -> None:
    """A line for each ``--jobs`` value: median wall and CPU time, peak memory, speed-up."""
    for jobs in jobs_values:
        wall = statistics.median(walls[jobs])
        print(f"  --jobs {jobs}: {wall:6.0f} s wall, {statistics.median(cpus[jobs]):6.0f} CPU s "
              f"(all processes), peak memory {max(peaks[jobs]) / 2**30:.2f} GB; "
              f"{statistics.median(walls[jobs_values[0]]) / wall:.2f} x --jobs "
              f"{jobs_values[0]}")


def end_to_end(name: str, jobs_values: list[int], repeats: int) -> None:
    """``scenarios/<name>.py --jobs J`` timed whole, for each J in turn, ``repeats`` times."""
    script = ROOT / "scenarios" / f"{name}.py"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    walls = {j: [] for j in jobs_values}
    cpus = {j: [] for j in jobs_values}
    peaks = {j: [] for j in jobs_values}
    budgets = []
    with tempfile.TemporaryDirectory() as folder:
        for k in range(repeats):
            for jobs in jobs_values:
                out = Path(folder) / f"jobs{jobs}_{k}"
                cpu, began = cpu_seconds(), time.perf_counter()
                with PeakMemory() as memory:
                    done = subprocess.run([sys.executable, str(script), "--jobs", str(jobs),
                                           "--out", str(out)], cwd=ROOT, env=env,
                                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                          text=True)
                if done.returncode != 0:
                    raise SystemExit(f"{name} --jobs {jobs} ended with {done.returncode}:\n"
                                     f"{done.stderr[-2000:]}")
                walls[jobs].append(time.perf_counter() - began)
                cpus[jobs].append(cpu_seconds() - cpu)
                peaks[jobs].append(memory.peak)
                summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
                budgets.append((jobs, summary["budget"]))
                print(f"  jobs {jobs}: {walls[jobs][-1]:.0f} s, {cpus[jobs][-1]:.0f} CPU s, "
                      f"peak {memory.peak / 2**30:.2f} GB (load average "
                      f"{os.getloadavg()[0]:.1f})", flush=True)
    print(f"{name}, its default run end to end ({len(budgets[0][1])} budget rows), median "
          f"of {repeats}:")
    _medians(jobs_values, walls, cpus, peaks)
    same = all(rows == budgets[0][1] for _, rows in budgets)  # floats read back exactly
    print(f"every budget equal to the first, to the bit: {same}")


if __name__ == "__main__":
    main()
