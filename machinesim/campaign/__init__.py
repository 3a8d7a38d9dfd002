"""Campaigns: a procedure run as N seeded Monte Carlo trials, locally or on a Dask cluster.

Trial i draws its injected errors (distributions over any error parameter, or the loading
robot's repeatability) and its lab's noise seed from ``SeedSequence(seed).spawn(N)[i]``, so
its result is the same with any number of workers and in any completion order
(`machinesim.campaign.trials`). The results come out as an xarray Dataset with a ``trial``
dimension, per-trial files that make an interrupted campaign resumable
(`machinesim.campaign.results`), and a report: distributions before and after, 95 % coverage
intervals, z-scores of the identification, rank-correlation sensitivity
(`machinesim.campaign.statistics`, `machinesim.campaign.summary`). docs/campaigns.md.

>>> import machinesim.campaign as campaign
>>> ds = campaign.run("tool_rotation_arm", 8, vary=["microscope.sigma=uniform:5nm,50nm"],
...                   out="reports/campaign_arm", workers=2)  # doctest: +SKIP
"""

from machinesim._submodules import submodule
from machinesim.campaign.distributions import Distribution, parse_distribution, parse_vary
from machinesim.campaign.runner import run
from machinesim.campaign.shipped import PROCEDURES
from machinesim.campaign.spec import CampaignSpec
from machinesim.campaign.trials import run_trial, trial_seed

__all__ = ["PROCEDURES", "CampaignSpec", "Distribution", "parse_distribution", "parse_vary",
           "run", "run_trial", "trial_seed"]


def __getattr__(name: str):
    # machinesim.campaign.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
