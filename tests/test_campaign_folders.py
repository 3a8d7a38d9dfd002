"""machinesim.campaign: a campaign's identity across spellings, the checks run before any
trial, and folders that cannot be written.

Trials run paper 000's calibration alone (``identify_only``: ~1.5 s each), a few per file.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

import machinesim.campaign.runner as runner
from machinesim.campaign import CampaignSpec, parse_vary, run
from machinesim.campaign.results import CampaignFolder, campaign_id, legacy_campaign_id
from machinesim.exceptions import InputError

ARM = dict(identify_only=True)
VARY = ["tool.y=normal:-178um,20um", "microscope.sigma=uniform:5nm,60nm"]
#: VARY spelt otherwise: the same distributions
SPELT = ["tool.y=normal:-0.178mm,0.02mm", "microscope.sigma=uniform:5 nm,0.06um"]


@pytest.fixture(scope="module")
def begun(tmp_path_factory):
    """A campaign of two trials begun with VARY: (folder, Dataset)."""
    out = tmp_path_factory.mktemp("begun")
    return out, run("tool_rotation_arm", 2, vary=VARY, seed=11, out=out, workers=0,
                    progress=False, report=False, **ARM)


def trials_run(monkeypatch) -> list[int]:
    """The indices of the trials the runner runs from now on, in order (each still run)."""
    ran, real = [], runner.run_trial
    monkeypatch.setattr(runner, "run_trial", lambda spec, i: ran.append(i) or real(spec, i))
    return ran


def _spec(vary, seed=11) -> dict:
    return CampaignSpec("tool_rotation_arm", 2, tuple(parse_vary(t) for t in vary), seed=seed,
                        **ARM).describe()


# ------------------------------------------------------------------------------ identity


def test_an_identity_is_of_the_distributions_meaning_not_their_spelling():
    # campaign_id hashed the DIST texts as spelt: 10nm and 0.01um were two campaigns
    ten = _spec(["microscope.sigma=10nm"])
    assert campaign_id(ten) == campaign_id(_spec(["microscope.sigma=0.01um"])) \
        == campaign_id(_spec(["microscope.sigma=fixed:1e-8m"]))
    assert campaign_id(_spec(VARY)) == campaign_id(_spec(SPELT))
    assert campaign_id(ten) != campaign_id(_spec(["microscope.sigma=11nm"]))
    assert campaign_id(ten) != campaign_id(_spec(["microscope.sigma=normal:10nm,1nm"]))
    assert campaign_id(ten) != campaign_id(_spec(["microscope.sigma=10nm"], seed=12))
    # nothing varied: the identity it always had (nothing to read otherwise)
    bare = _spec([])
    assert campaign_id(bare) == legacy_campaign_id(bare)


def test_a_trial_file_of_the_same_campaign_spelt_otherwise_is_this_campaigns(
        begun, tmp_path, monkeypatch):
    # a trial file of the campaign begun with VARY, copied into the folder of the one begun
    # with SPELT, was refused as "the trial file of another campaign"
    source, ds = begun
    CampaignFolder(tmp_path, _spec(SPELT))  # begun with SPELT, as the runner begins it
    shutil.copy(source / "trials/trial_000001.json", tmp_path / "trials")
    ran = trials_run(monkeypatch)
    again = run("tool_rotation_arm", 2, vary=SPELT, seed=11, out=tmp_path, workers=0,
                progress=False, report=False, **ARM)
    assert ran == [0]
    # trial 0 drew from 0.06um here, from 60nm there: the same to the units' last bit
    np.testing.assert_allclose(again["drawn"].values, ds["drawn"].values, rtol=1e-12)
    np.testing.assert_allclose(again["identified"].values, ds["identified"].values,
                               rtol=1e-9)
    written = json.loads((tmp_path / "trials/trial_000000.json").read_text())
    copied = json.loads((source / "trials/trial_000000.json").read_text())
    assert written["campaign"] == copied["campaign"]
    # another value is another campaign: its file is refused, naming it
    other = tmp_path / "other"
    CampaignFolder(other, _spec([VARY[0], "microscope.sigma=uniform:5nm,61nm"]))
    shutil.copy(source / "trials/trial_000001.json", other / "trials")
    with pytest.raises(InputError, match="trial_000001.json.*of another campaign"):
        run("tool_rotation_arm", 2, vary=[VARY[0], "microscope.sigma=uniform:5nm,61nm"],
            seed=11, out=other, workers=0, progress=False, report=False, **ARM)
    assert ran == [0]


def test_a_folder_written_with_the_identity_of_the_texts_resumes(begun, tmp_path,
                                                                  monkeypatch):
    # its trial files hold the identity of campaign.json's texts as spelt, which campaigns
    # wrote before the identity took their meaning: still this folder's, not "another
    # campaign's" to delete and run anew
    source, ds = begun
    shutil.copytree(source, tmp_path / "old")
    old = tmp_path / "old"
    stored = json.loads((old / "campaign.json").read_text())
    assert legacy_campaign_id(stored) != campaign_id(stored)
    for path in (old / "trials").iterdir():
        record = json.loads(path.read_text())
        path.write_text(json.dumps({**record, "campaign": legacy_campaign_id(stored)}))
    ran = trials_run(monkeypatch)
    again = run("tool_rotation_arm", 3, vary=VARY, seed=11, out=old, workers=0,
                progress=False, report=False, **ARM)
    assert ran == [2]
    for name in ("drawn", "identified", "identified_std", "injected"):
        assert np.array_equal(again[name].values[:2], ds[name].values), name
    assert json.loads((old / "trials/trial_000002.json").read_text())["campaign"] \
        == campaign_id(stored)
