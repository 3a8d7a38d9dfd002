"""What the metrology test files (tests/test_metrology_instruments.py, _hostile.py) share
(not collected: no test_ prefix): axis values that put the touch probe's ball where asked."""

import numpy as np

MM = 1e-3


def above(a0ib, x, y, z_centre):
    """Axis values that put the nominal ball centre at (x, y, z_centre): the probe_tip sits
    40 mm along +Y and 1 mm above the tool edge (docs/machines.md)."""
    q = np.zeros(len(a0ib.axes))
    q[:3] = x, y - 40 * MM, z_centre - 1 * MM
    return q
