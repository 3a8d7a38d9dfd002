"""What the paper 001 replay's test files (tests/test_tool_setting_6axis_*.py) share (not
collected: no test_ prefix): the error model of a tool offset and a C centre, offsets of
the paper's size, and eq 2 as the paper prints it."""

from __future__ import annotations

import math

from machinesim import ErrorModel, ToolSetting

UM, MM = 1e-6, 1e-3


def errors_of(d, e) -> ErrorModel:
    return ErrorModel(tool=ToolSetting(d, [0.0, 0.0, 0.0]),
                      location={"C": {"EX0C": e[0], "EY0C": e[1]}})


def paper_offsets(rng):
    """Tool offset and C centre of the paper's size: Table 1 holds distances of 100-850 um,
    i.e. offsets of a few hundred um; every component at least 100 um (50 um for e), with a
    random sign, all within the plan's capture range."""
    d = rng.uniform(100, 450, 3) * UM * rng.choice([-1.0, 1.0], 3)
    e = rng.uniform(50, 650, 2) * UM * rng.choice([-1.0, 1.0], 2)
    return d, e


def printed_eq2(d0, d1, d2, t2, t3):
    """Paper 001's eq 2 as printed (with D the B = 0 depth)."""
    den = math.sin(t2) * (1 - math.cos(t3)) - math.sin(t3) * (1 - math.cos(t2))
    return ((d1 - d0) * math.sin(t2) + (d2 - d0) * math.sin(t3)) / den
