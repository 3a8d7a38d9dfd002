"""Each procedure's ``lab_uses`` is what its steps ask the lab for, by a run.

A campaign varies an instrument's noise, the robot's repeatability or the tool's nose radius
only where the procedure declares it reads them (`machinesim.experiment.LAB_USES`,
`CampaignSpec.parameters`), so a wrong declaration either refuses a parameter the procedure
reads or takes one it never reads (an option silently ignored). Here a trial runs through
`run_trial` (the campaign's own route: its lab wrapper, its procedure) with `Lab`'s
instrument and cutting methods recording which step called them:

- an instrument (`machinesim.campaign.distributions.INSTRUMENTS`) is used where the step
  asks the lab for one at the lab's noise: not one given its own ``sigma`` (paper 003's
  R-test) nor one read through an objective (paper 002's 10x), whose noise a campaign's
  sigma does not reach;
- ``tool_geometry`` where a step cuts (or turns) with a tool a nose radius error changes
  (`machinesim.tools.with_nose_radius_error` takes it; a V tool refuses it);
- ``robot`` is no call to the lab: the landing is drawn into the workpiece setting before
  the lab is made. It is used where the step reads that setting: the step whose
  identification gives ``workpiece.x .. gamma``.

Paper 002's crown (``workpiece_setting``) takes about 70 s a trial even with ``--quick``;
its measuring step is run here (``--identify-only``), its evaluation was checked the same
way by hand (evaluate: ``microscope``, ``tool_geometry``; the 10x readings apart).
"""

from __future__ import annotations

import functools

import pytest

import machinesim.campaign.trials as trials
from machinesim.campaign import CampaignSpec, run_trial
from machinesim.campaign.distributions import INSTRUMENTS
from machinesim.errors import ErrorModel
from machinesim.exceptions import InputError
from machinesim.lab import Lab
from machinesim.tool_specs import tool_from_spec
from machinesim.tools import with_nose_radius_error

SETTING = {f"workpiece.{a}" for a in ("x", "y", "z", "alpha", "beta", "gamma")}


def _has_nose_radius(tool) -> bool:
    tool = tool_from_spec(tool) if isinstance(tool, str) else tool
    try:
        with_nose_radius_error(tool, ErrorModel().with_parameters(
            {"tool_geometry.nose_radius": 1e-6}))
    except InputError:
        return False
    return True


class _Steps:
    """The procedure, each step telling ``now`` its name while it runs."""

    def __init__(self, procedure, now: list) -> None:
        self._procedure, self._now = procedure, now
        self.name, self.paper = procedure.name, procedure.paper
        self.lab_uses = procedure.lab_uses

    def __getattr__(self, step):
        method = getattr(self._procedure, step)

        def run(*args):
            self._now[0] = step
            try:
                return method(*args)
            finally:
                self._now[0] = None
        return run


def used_by_step(spec: CampaignSpec, monkeypatch) -> tuple[dict, dict]:
    """(what trial 0 of ``spec`` asked the lab for, by step; its record)."""
    now, used = [None], {}

    def record(step, use):
        assert step is not None, f"{use} asked for outside a procedure's step"
        used.setdefault(step, set()).add(use)

    def instrument(kind, make):
        @functools.wraps(make)
        def spied(self, *args, **options):
            if "sigma" not in options and options.get("objective") is None:
                record(now[0], kind)
            return make(self, *args, **options)
        return spied

    def cutter(make):
        @functools.wraps(make)
        def spied(self, program, tool="v:90", *args, **options):
            if _has_nose_radius(tool):
                record(now[0], "tool_geometry")
            return make(self, program, tool, *args, **options)
        return spied

    for kind in INSTRUMENTS:
        monkeypatch.setattr(Lab, kind, instrument(kind, getattr(Lab, kind)))
    for name in ("cut", "turn"):
        monkeypatch.setattr(Lab, name, cutter(getattr(Lab, name)))
    run = trials.run
    monkeypatch.setattr(trials, "run", lambda procedure, lab: run(_Steps(procedure, now), lab))
    result = run_trial(spec, 0)
    assert result["error"] is None, result["error"]
    if SETTING <= set(result["identified"]):
        record("measure", "robot")
    return {step: sorted(uses) for step, uses in used.items()}, result


@pytest.mark.parametrize("procedure, identify_only", [
    ("tool_rotation_arm", False), ("tool_setting_6axis", False), ("xy_plane_errors", False),
    ("workpiece_setting_grooves", False), ("workpiece_setting", True)])
def test_a_procedure_asks_the_lab_for_what_it_declares(procedure, identify_only, monkeypatch):
    spec = CampaignSpec(procedure, 1, identify_only=identify_only)
    declared = {step: sorted(uses) for step, uses in spec.build().lab_uses.items() if uses}
    used, _ = used_by_step(spec, monkeypatch)
    assert used == declared
