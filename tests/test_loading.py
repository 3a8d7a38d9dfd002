"""RobotLoader's draws: seeded as every draw of machinesim is."""

from __future__ import annotations

import numpy as np
import pytest

from machinesim.exceptions import InputError
from machinesim.loading import RobotLoader


def test_land_takes_a_numpy_integer_seed_and_refuses_a_negative_one():
    # a numpy integer was refused ("Expected rng as a numpy Generator, an int seed or None,
    # got np.int64(3)"), and -1 ended in numpy's "ValueError: expected non-negative integer"
    robot = RobotLoader()
    drawn = robot.land(np.int64(3))
    same = robot.land(np.random.default_rng(3))  # the seed's own generator: the same draw
    np.testing.assert_array_equal(drawn.delta, same.delta)
    assert (drawn.alpha, drawn.beta, drawn.gamma) == (same.alpha, same.beta, same.gamma)
    np.testing.assert_array_equal(robot.land(3).delta, same.delta)
    for bad in (-1, np.int64(-1), True, 1.5, "3"):
        with pytest.raises(InputError, match="Expected rng as a numpy Generator, a "
                                             "non-negative int seed or None") as info:
            robot.land(bad)
        assert info.value.key == "rng"
