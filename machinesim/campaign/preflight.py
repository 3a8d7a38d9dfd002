"""The checks each trial of a campaign runs on its inputs, run once before any trial.

A trial (`machinesim.campaign.trials.run_trial`) sets its errors into the procedure's base
model (`ErrorModel.with_parameters`), runs the procedure's own check of that model
(`ProcedureEntry.check`: the grooves' block the groove program's rapids would run into),
builds its lab (`Lab` checks the model against the machine: its tool adjuster's stroke)
and its robot (`RobotLoader`). Any of them refusing failed that trial with its message,
after the campaign had begun: ``campaign workpiece_setting_grooves --trials 1000 --vary
workpiece.z=100um`` ran every trial to the same crash and wrote a folder of 1000 failed
trials, exiting 1 (on a cluster, after the cluster's start). `check_before_trials` runs the
same checks once, on the errors the trials are drawn around, and refuses the campaign with
their message before anything is written.
"""

from __future__ import annotations

from machinesim.campaign.distributions import (
    INSTRUMENTS,
    LAB_PARAMETERS,
    Distribution,
    _nearest,
)
from machinesim.exceptions import InputError, MachineSimError

__all__ = ["check_before_trials"]


#: A normal is checked at its draw nearest zero within this many standard deviations of its
#: mean: a refusal there is one of all but 0.13 % of its trials (for a check that refuses
#: values beyond a bound), where one at its mean was one of half of them, or more.
NORMAL_REACH = 3.0


def _around(dist: Distribution) -> float:
    """The value of ``dist`` the check takes: the draw nearest zero (a fixed value; a
    uniform's LOW or HIGH, or zero for one across it; a normal's within `NORMAL_REACH`
    standard deviations of its mean, zero for one whose reach crosses it). A refusal there
    is one of every trial (of all but 0.13 % for a normal). A normal's mean
    (`_nearest`, which `refuse_beyond_model` takes) is no such value: ``workpiece.z=normal:
    60um,30um``, half of whose trials the grooves take, was refused at its 60 um."""
    if dist.kind == "normal":
        low, high = dist.a - NORMAL_REACH * dist.b, dist.a + NORMAL_REACH * dist.b
        return low if low > 0.0 else high if high < 0.0 else 0.0
    value = _nearest(dist)
    return 0.0 if value is None else value


def _instrument(lab, kind: str, sigma: float) -> None:
    """Build ``lab``'s instrument ``kind`` with the noise ``sigma``, as a trial's lab does
    (`machinesim.campaign.trials._LabWithInstruments`), for its checks of ``sigma``: a
    noise beyond what the instrument takes (1 mm, `OPTICAL_LIMIT` or `READOUT_LIMIT`, a
    unit slip) failed every trial. A touch probe needs a part; its noise is checked as it
    checks it (`Readout.of`)."""
    if kind == "touch_probe":
        from machinesim.metrology.instruments import Readout

        Readout.of(sigma, 0.0, True)
    else:
        getattr(lab, kind)(sigma=sigma)


def check_before_trials(spec) -> None:
    """Run, once, the checks every trial of ``spec`` (a `CampaignSpec`) runs on its inputs:
    its errors (the procedure's defaults, each varied one at `_around`, the robot's landing
    at its mean: none) set into the base model, the procedure's check of that model
    (`ProcedureEntry.check`, as a trial that cuts runs it), the lab built on it, and the
    robot of its repeatability (`RobotLoader`, which refuses one whose landings would be
    refused: ``robot.repeatability=2m`` failed every trial at its landing).

    Raises
    ------
    InputError
        Naming the values checked and the procedure's own message, key ``--vary`` (or
        ``procedure`` when nothing varies).
    """
    from machinesim.lab import Lab
    from machinesim.loading import RobotLoader

    varied = {name: dist for name, dist in spec.vary}
    lab = {**spec.entry.lab, **{n: _around(d) for n, d in varied.items() if n in LAB_PARAMETERS}}
    errors = dict(spec.entry.defaults(spec.machine))
    errors.update({n: _around(d) for n, d in varied.items() if n not in LAB_PARAMETERS})
    try:
        if "robot.repeatability" in lab:
            RobotLoader(lab["robot.repeatability"])
        model = spec.entry.base().with_parameters(errors)
        if spec.entry.check is not None and not spec.identify_only:
            spec.entry.check(model)
        built = Lab(spec.machine, model, noise=spec.noise, seed=0)
        for kind in INSTRUMENTS:  # each varied noise as its instrument takes it
            if f"{kind}.sigma" in lab:
                _instrument(built, kind, lab[f"{kind}.sigma"])
    except MachineSimError as error:
        at = {"normal": f" at its draw nearest zero within {NORMAL_REACH:g} sigma of its mean",
              "uniform": " at its draw nearest zero"}
        shown = [f"{name}={dist.text}{at.get(dist.kind, '')}"
                 for name, dist in varied.items()]
        if "robot.repeatability" in lab:
            shown.append("the robot's landing at its mean")
        what = spec.procedure + " --identify-only" * spec.identify_only
        checked = f" ({'; '.join(shown)})" if shown else ""
        raise InputError(
            f"the trials of {what} would fail one by one as they start: the errors they are "
            f"drawn around{checked} are refused: {type(error).__name__}: {error}; expected "
            "errors the procedure and its lab take (checked before any trial ran)",
            key="--vary" if varied else "procedure") from None
