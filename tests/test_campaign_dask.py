"""A campaign on a real 2-worker dask.distributed LocalCluster (kept small: 3 trials of paper
000's calibration), against the same campaign in one process without Dask: every trial the
same, whichever worker ran it and in whichever order it finished."""

from __future__ import annotations

import numpy as np
import pytest

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
