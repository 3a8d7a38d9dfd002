"""A campaign on a real 2-worker dask.distributed LocalCluster (kept small: 3 trials of paper
000's calibration), against the same campaign in one process without Dask: every trial the
same, whichever worker ran it and in whichever order it finished."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from machinesim._cores import usable_cores
from machinesim.campaign import run

pytest.importorskip("distributed")

VARY = ["tool.y=normal:-178um,20um", "microscope.sigma=uniform:5nm,60nm"]
NAMES = ("drawn", "injected", "identified", "identified_std")


def test_two_local_workers_and_one_process_give_the_same_trials(tmp_path):
    options = dict(vary=VARY, seed=21, identify_only=True, progress=False, report=False)
    one = run("tool_rotation_arm", 3, out=tmp_path / "one", workers=0, **options)
    two = run("tool_rotation_arm", 3, out=tmp_path / "two", workers=2, **options)
    for name in NAMES:
        assert np.array_equal(two[name].values, one[name].values), name
    assert not two["failed"].values.any()
    # three distinct trials, not one trial three times (a seed shared across trials)
    assert len(set(two["drawn"].sel(varied="tool.y").values)) == 3


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="Linux affinity")
def test_the_default_worker_count_is_the_cores_the_process_may_use():
    # pinned to one core (as `taskset -c 0` does), the process has one core, whatever the
    # machine has: a default pool of cpu_count() workers would share it
    code = ("import os; os.sched_setaffinity(0, {min(os.sched_getaffinity(0))}); "
            "from machinesim._cores import usable_cores; "
            "from machinesim.motion import chords; from machinesim.nc import fastscan; "
            "print(usable_cores(), chords.WORKERS, fastscan.WORKERS)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.split() == ["1", "1", "1"]
    assert usable_cores() == len(os.sched_getaffinity(0))


def test_ctrl_c_on_a_campaign_with_workers_is_one_line_and_no_worker_traceback(
        tmp_path, as_in_a_terminal):
    """A Ctrl-C reaches every process of the terminal's group, the workers too; each printed
    a KeyboardInterrupt traceback while the campaign said what it kept. Sent to the group
    once a trial has finished (the workers are up), only the campaign's line remains."""
    import signal

    process = subprocess.Popen(
        [sys.executable, "-m", "machinesim.cli", "campaign", "tool_rotation_arm", "--trials", "40",
         "--workers", "1", "--identify-only", "--out", str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
        **as_in_a_terminal)
    try:
        progress = ""
        while "campaign: 1/40" not in progress:
            char = process.stderr.read(1)
            assert char, "the campaign ended before its first trial"
            progress += char
        os.killpg(process.pid, signal.SIGINT)
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 130
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert "interrupted; kept the" in err and str(tmp_path / "trials") in err
