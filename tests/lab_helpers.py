"""What the lab's test files (tests/test_lab_truth.py, _report.py, _refusals.py) and the
realism ones (tests/test_realism_*.py, through realism_helpers.py too) share (not collected:
no test_ prefix): the truth they inject and a groove to cut."""

from __future__ import annotations

from machinesim.nc import ProgramBuilder

TRUTH = {"tool": {"offset_um": [5.0, -3.0, 1.0]}, "location": {"C": {"EX0C_um": 2.0}}}


def groove():
    return (ProgramBuilder(1).rapid(X=1e-3, Y=1e-3, Z=1e-3).linear(Z=-1e-5, feed_mm_per_min=100)
            .linear(X=8e-3, feed_mm_per_min=100).rapid(Z=1e-3).build())
