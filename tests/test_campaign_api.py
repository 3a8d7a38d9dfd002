"""machinesim.campaign.run called from Python with what a user may pass by mistake: each is
refused with an InputError naming the value, before a folder is made or a trial runs."""

from __future__ import annotations

import pytest

from machinesim.campaign import CampaignSpec, run
from machinesim.exceptions import InputError

ARM = dict(identify_only=True, workers=0, progress=False)


@pytest.mark.parametrize("flag, value", [("noise", "off"), ("noise", "on"), ("noise", 0),
                                         ("identify_only", "yes"), ("quick", None)])
def test_a_switch_that_is_not_true_or_false_is_refused(flag, value):
    """``noise="off"`` (the command's ``--noise off`` in Python) is a true string: it ran
    every trial with the noise on, and wrote "off" into campaign.json."""
    with pytest.raises(InputError, match=rf"{flag}={value!r}; expected True or False"):
        CampaignSpec("tool_rotation_arm", 1, **{flag: value})


@pytest.mark.parametrize("flag", ["progress", "report"])
def test_run_refuses_a_progress_or_report_that_is_not_true_or_false(flag, tmp_path):
    with pytest.raises(InputError, match=rf"{flag}='no'; expected True or False"):
        run("tool_rotation_arm", 1, out=tmp_path / "c", **{**ARM, flag: "no"})
    assert not (tmp_path / "c").exists()


def test_noise_false_reads_exact_values(tmp_path):
    """The switch as a bool does what it says (numpy's bool too): with the noise off the
    arm's calibration reads exact values, so two seeds identify the same."""
    import numpy as np

    one = run("tool_rotation_arm", 1, out=tmp_path / "a", noise=np.False_, seed=1, **ARM)
    two = run("tool_rotation_arm", 1, out=tmp_path / "b", noise=False, seed=2, **ARM)
    assert one.identified.values.tolist() == two.identified.values.tolist()
    assert one.attrs["noise"] == 0
