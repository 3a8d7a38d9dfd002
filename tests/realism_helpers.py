"""What the realism test files (tests/test_realism_*.py) share (not collected: no test_
prefix): the units, the round-off heights are checked to, and the groove cut on
robonano_a0ib under the lab's truth (a module fixture: imported by name)."""

from __future__ import annotations

import pytest
from lab_helpers import TRUTH, groove

from machinesim import Lab

MM, UM, NM = 1e-3, 1e-6, 1e-9
#: Heights of mm-scale geometry carry float64 round-off of ~1e-19 m; a transformed mesh
#: (registration) ~1e-18 m: 1e-15 m fails on any modelling error above a femtometre.
ROUND_OFF_M = 1e-15


@pytest.fixture(scope="module")
def cut_part():
    part, _ = Lab("robonano_a0ib", TRUTH, noise=False).cut(groove(), "v:90", "block:10x10x2")
    return part
