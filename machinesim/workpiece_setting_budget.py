"""Paper 002's error budget: one rerun of both robot loads with one source off.

`scenarios/workpiece_setting.py` budgets the crown's "after" figures and the grooves' spread
(`machinesim.budget.error_budget`): each source switched off in turn, both loads run again
on labs of their own (the crown "after" only). `crown_rerun` is that rerun as a
module-level function of plain arguments, so that a `functools.partial` of it pickles and
the reruns can run on worker processes (``--jobs``, `machinesim._processes`), the same
rerun whether here or there.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import SimpleNamespace

from machinesim.experiment import run
from machinesim.lab import Lab
from machinesim.procedures.workpiece_setting import EXPERIMENTS, RobotLoadedWorkpiece

__all__ = ["TIP_VS_NOSE", "budget_figures", "crown_rerun"]

#: Procedure approximation in the error budget: the paper's eq 7 keeps the tip on the path.
TIP_VS_NOSE = "tip_vs_nose"


def budget_figures(runs: Mapping) -> SimpleNamespace:
    """The budgeted figures of the two loads' runs (``{"crown": Result, "grooves": Result}``):
    the crown's (not the machining times, which come from the feeds alone) and the grooves'
    spread (their depths are not errors), as ``figures``, as `error_budget` reads a
    result."""
    figures = [f for f in runs["crown"].figures if not f.name.startswith("machining_time")]
    figures += [f for f in runs["grooves"].figures if f.name == "groove_depth_spread"]
    return SimpleNamespace(figures=tuple(figures))


def crown_rerun(source: str, *, machine, errors: Mapping, seed: int, realism,
                nose_correction: bool, all_layers: bool, quick: bool,
                progress: Callable | None = None) -> SimpleNamespace:
    """Both loads run again with ``source`` off: a lab of its own for each (``machine``,
    ``errors[load]``, ``seed``, ``realism`` without ``source``; `TIP_VS_NOSE` puts the nose
    on the path instead), the crown "after" only; their `budget_figures`. ``progress``: the
    scenario's stage printer (`machinesim.scenario_runs.progress_printer`), told
    ``budget, <source> off, <load> load``."""
    runs = {}
    for load in EXPERIMENTS:
        lab = Lab(machine, errors[load], seed=seed,
                  realism=realism if source == TIP_VS_NOSE else realism.without(source))
        told = None if progress is None else progress(f"budget, {source} off, {load} load")
        runs[load] = run(RobotLoadedWorkpiece(
            load, nose_correction=nose_correction or source == TIP_VS_NOSE,
            all_layers=all_layers, quick=quick, after_only=True, progress=told),
            lab, progress=told)
    return budget_figures(runs)
