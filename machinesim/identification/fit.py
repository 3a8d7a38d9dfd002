"""Generic identification: any subset of error parameters, from displacement readings.

An observation is what one displacement sensor reads: how far a point fixed in a machine
frame (the centre of a ball on the tool, a probe tip) lies from its nominal place, relative
to the workpiece, along a unit direction of the workpiece frame. The R-test of ISO 10791-6
reads a ball on the tool with three such sensors; a touch probe or a laser interferometer
reads one. `fit` finds the error parameters that explain the readings (weighted Gauss-Newton
on Pinocchio's error Jacobians, `Machine.error_jacobian`, with column scaling and
truncated-SVD steps) and reports what the plan could and could not identify;
`plan_quality` gives the same figures for a plan before any reading is taken. The derivation
(observation model, weighting, rank, covariance, the null space and its names) is in
docs/identification.md. The figures and their notes are in `identifiability`, the model
readings and Jacobian in `observation_model`; every name stays importable from here.

>>> import numpy as np, machinesim
>>> from machinesim.identification.fit import fit, observations
>>> machine = machinesim.load_machine("robonano_ui")
>>> q = np.zeros((3, 6)); u = np.eye(3)
>>> obs = observations(q, directions=u, values=[1e-6, -2e-6, 0.0], sigma=1e-8)
>>> estimate = fit(machine, obs, ["workpiece.x", "workpiece.y"])
>>> np.round(estimate.values * 1e6, 9), estimate.rank
(array([-1.,  2.]), 2)
"""

from __future__ import annotations

import difflib
import math
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from machinesim import tolerances
from machinesim._keywords import keywords_checked
from machinesim.arrays import frozen
from machinesim.errors import LARGEST_ERROR, ErrorModel, as_error_model
from machinesim.exceptions import ErrorModelError, InputError, NotConvergedError
from machinesim.identification.identifiability import (
    _FIGURES_DOC,
    IMPLAUSIBLE_LENGTH_M,  # noqa: F401 (importable from here, as before the split)
    NEARLY_INSEPARABLE,  # noqa: F401 (importable from here, as before the split)
    Combination,
    PlanQuality,
    _Figures,
    _figures,
    _linearise,
    _scale_notes,
    listed,
)
from machinesim.identification.observation_model import _Plan
from machinesim.identification.observations import (
    Observation,
    Observations,
    is_angle,
    observations,
)
from machinesim.metrology.instruments import as_machine

__all__ = [
    "Combination", "Estimate", "NotConvergedError", "Observation", "Observations",
    "PlanQuality", "fit", "misfit_limit", "observations", "plan_quality",
]

#: Gauss-Newton steps before `fit` gives up. From a zero prior it converges in 4 steps for
#: setting errors of hundreds of um and 2 degrees (quadratically once near the solution);
#: 50 leaves room for a slowly converging fit without hiding a divergence.
MAX_ITERATIONS = 50

#: The chance that `fit` notes a misfit of readings the model holds, their sigma right: with
#: Gaussian noise of those sigma, the weighted sum of squared residuals at the estimate,
#: ``normalised_residual_rms**2 * dof``, is chi-square with dof = N - rank degrees of
#: freedom, and a misfit is noted when it exceeds that distribution's 1 - MISFIT_FALSE_ALARM
#: quantile (`misfit_limit`; docs/identification.md, "The misfit test").
MISFIT_FALSE_ALARM = 1e-3

#: Normalised residual RMS beyond which the readings are reported as not fitting the model
#: where the chi-square test has no degrees of freedom to go on (`misfit_limit` of dof < 1):
#: the fallback. At dof 0 `fit`'s normalised residual is NaN, never above it.
MODEL_MISFIT = 3.0


def misfit_limit(dof: int) -> float:
    """The normalised residual RMS above which a fit with ``dof`` degrees of freedom (N - rank)
    is noted as not fitting its model: ``sqrt(chi2.isf(MISFIT_FALSE_ALARM, dof) / dof)``, the
    RMS that right sigma and a right model exceed with probability `MISFIT_FALSE_ALARM`
    (3.29 at 1 degree of freedom, 1.39 at 33, 1.01 at 100,000); `MODEL_MISFIT` when
    ``dof`` < 1."""
    # chdtri(dof, q) is chi2.isf(q, dof), the same cephes routine and the same float64, without
    # importing scipy.stats: that took a scenario's first fit from 0.0 to 0.8 s
    from scipy.special import chdtri

    if isinstance(dof, bool) or not isinstance(dof, int | np.integer):
        raise InputError(f"expected the degrees of freedom as an int, got {dof!r}", key="dof")
    dof = int(dof)
    if dof < 1:
        return MODEL_MISFIT
    return math.sqrt(float(chdtri(dof, MISFIT_FALSE_ALARM)) / dof)


@dataclass(frozen=True, eq=False, repr=False)
class Estimate(_Figures):
    __doc__ = ("""The result of `fit`: the parameters and what the readings could identify.

    Attributes
    ----------""" + _FIGURES_DOC + """    values : ndarray, shape (k,)
        The estimates, SI. Along the null space they stay as near the prior as the readings
        allow (estimate minus prior is orthogonal, in SI, to every `Combination`); a
        parameter no reading moves at the prior keeps the prior's value exactly (held there
        for the whole fit, as if left out of it; std NaN).
    residual_rms : float
        RMS of reading minus model at the estimate, m (unweighted).
    normalised_residual_rms : float
        sqrt(sum(((reading - model) / sigma)^2) / (N - rank)), dimensionless: about 1 when
        the sigma are right (NaN when N <= rank).
    iterations : int
        Gauss-Newton steps taken.
    errors : ErrorModel
        The prior with the fitted values.
    unseen_at_prior : tuple of Combination
        The combinations the readings could not see at the prior (the plan's symmetries
        there, as `plan_quality` at the prior names them; not a single parameter, which is
        held at the prior), when the fit ended with a higher rank:
        seen at the estimate only through its own errors' lever (`notes`).
    scale_notes : tuple of str
        The note on readings, sigma or identified lengths beyond `IMPLAUSIBLE_LENGTH_M`
        (given in um or mm?), if any; first in `notes`.
""")

    values: np.ndarray
    residual_rms: float
    normalised_residual_rms: float
    iterations: int
    errors: ErrorModel
    unseen_at_prior: tuple = ()
    scale_notes: tuple = ()

    @property
    def misfit(self) -> bool:
        """True when the readings do not fit the model: the normalised residual is above
        `misfit_limit` of N - rank degrees of freedom (a parameter the readings show but
        neither ``params`` nor the prior holds, or sigma given too small; with right sigma
        and a right model, by chance with probability `MISFIT_FALSE_ALARM`)."""
        return bool(self.normalised_residual_rms
                    > misfit_limit(self.n_observations - self.rank))

    @property
    def notes(self) -> tuple[str, ...]:
        """As `PlanQuality.notes`, and when the readings do not fit the model (`misfit`)."""
        out = list(super().notes)
        for c in self.unseen_at_prior:
            stds = ", ".join(f"{n} {self.std[self.names.index(n)]:.3g}" for n in c.names)
            out.append(f"at the prior the readings cannot see {c}; the fit, of rank "
                       f"{self.rank}, sees it only through the estimate's own errors, so "
                       f"these values rest on that small lever (std {stds}) and may be far "
                       "off (a compensation through them may add error). Fix a datum (leave "
                       "a parameter out of the fit) or add readings that see it")
        if self.misfit:
            dof = self.n_observations - self.rank
            out.append(f"the readings do not fit the model: normalised residual "
                       f"{self.normalised_residual_rms:.3g} (about 1 when the model holds "
                       f"every error the readings show and sigma is right; above "
                       f"{misfit_limit(dof):.3g} by chance with probability "
                       f"{MISFIT_FALSE_ALARM:g} at {dof} degrees of freedom; residual RMS "
                       f"{self.residual_rms:.3g} m): an error missing from the parameters "
                       "or the prior, or sigma too small; the values may be far off")
        return tuple(out)

    def __repr__(self) -> str:
        return (f"Estimate({self._summary()}, residual RMS {self.residual_rms:.3g} m "
                f"(normalised {self.normalised_residual_rms:.3g}), {self.iterations} "
                f"iterations: "
                f"{listed(self.names, self.values, self.std, self.errors.parameter_unit)})")

    def as_dict(self) -> dict[str, dict[str, float]]:
        """``{name: {"value": v, "std": s}}`` in SI (std NaN when unidentifiable)."""
        return {n: {"value": float(v), "std": float(s)}
                for n, v, s in zip(self.names, self.values, self.std, strict=True)}

def _prior(machine, prior) -> ErrorModel:
    if prior is None:
        model = ErrorModel()
    elif isinstance(prior, ErrorModel):
        model = prior
    elif isinstance(prior, Mapping) and prior and not any("." in str(k) for k in prior):
        # the TOML layout ({"tool": {"offset_um": ...}}), as Lab and cut take errors: its
        # sections had been read as parameter names ("key 'tool': unknown parameter name")
        model = as_error_model(prior, key="prior")
    elif isinstance(prior, Mapping):
        model = ErrorModel().with_parameters(prior)
    elif isinstance(prior, str | os.PathLike):  # a TOML file, as Lab and cut take one
        model = as_error_model(prior, key="prior")
    else:
        raise InputError(f"expected the prior as an ErrorModel, a mapping name -> value "
                         f"(SI), a dict in the TOML layout or a TOML path, got "
                         f"{type(prior).__name__}", key="prior")
    machine.check_errors(model)
    return model


def _names(machine, params, prior: ErrorModel) -> tuple[str, ...]:
    if isinstance(params, str) or not isinstance(params, Sequence | np.ndarray):
        raise InputError(f"expected a sequence of parameter names, got {params!r}",
                         key="params")
    names = tuple(params)
    if not names:
        raise InputError("expected at least one parameter name, got none", key="params")
    listed = machine.parameter_names(prior)
    accepted = set(listed)
    for name in names:
        if name not in accepted:
            raise ErrorModelError(
                f"unknown error parameter {name!r} for {machine.name}; "
                f"{_near_names(str(name), listed, machine)}expected one of "
                "Machine.parameter_names(prior): tool.x .. tool.rz, workpiece.x .. "
                f"workpiece.gamma, location.<axis>.<symbol> of axes {''.join(machine.axes)}, "
                "or component.<axis>.<symbol>[i] of a table or polynomial in the prior",
                key=str(name))
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise InputError(f"parameter {repeated[0]!r} is listed more than once", key="params")
    return names


def _near_names(name: str, listed: Sequence[str], machine) -> str:
    """The accepted names a mistyped ``name`` may have meant, as a phrase to put before the
    list of what is accepted (empty when none is near): the location errors of the axis it
    names (``location.C.EZ0C``: C has EX0C, EY0C, EA0C, EB0C, EC0C), the names it ends
    (``EX0C``), or those spelt most alike (``workpiece.gama``)."""
    parts = name.split(".")
    axis = parts[1].upper() if len(parts) == 3 and parts[0] == "location" else None
    if axis in machine.axes:
        own = [n for n in listed if n.startswith(f"location.{axis}.")]
        return f"the location errors of its axis {axis} are {', '.join(own)}; "
    near = [n for n in listed if n.lower().endswith("." + name.lower())]
    if not near:  # the best spelt alike (workpiece.gama: gamma, not alpha as well)
        ratios = {n: difflib.SequenceMatcher(None, name, n).ratio() for n in listed}
        best = max(ratios.values())
        near = [n for n, r in ratios.items() if r >= 0.75 and r >= best - 0.05][:3]
    lowered = {n.lower(): n for n in listed}
    near = near or ([lowered[name.lower()]] if name.lower() in lowered else [])
    if name.startswith("component.") and not any(n.startswith("component.") for n in listed):
        return ("a component error is a parameter only when the prior holds its table or "
                "polynomial (prior=ErrorModel with [component.<axis>]); ")
    return f"(did you mean {' or '.join(near)}?) " if near else ""


@keywords_checked
def fit(machine, observations: Observations | Iterable, params: Sequence[str], *,
        prior=None, max_iterations: int = MAX_ITERATIONS,
        progress: Callable[[str], None] | None = None) -> Estimate:
    """Identify the named error parameters from displacement readings.

    Model: reading_i = u_i . (x_i(p) - x_i(nominal)), with x_i(p) the observed point's
    position in the workpiece frame at q_i on the machine with errors
    ``prior.with_parameters(p)``. Weighted Gauss-Newton (weights 1 / sigma), Jacobian columns
    scaled to unit norm, truncated-SVD steps (`tolerances.FIT_RANK_REL`) whose null-space
    part keeps the estimate as near the prior as the readings allow; stops when every
    length step is below `tolerances.FIT_STEP_M` and every angle step below
    `tolerances.FIT_STEP_RAD` (docs/identification.md). What the readings cannot see is
    reported in `Estimate.unidentifiable`; to fix a datum, leave one parameter of each
    `Combination` out of ``params`` (it keeps the prior's value). A parameter no reading
    moves at the prior is held there so, for the whole fit.

    Parameters
    ----------
    machine : Machine or str
        The machine, or the name of a shipped one (or a URDF path), as `load_machine` takes.
    observations : Observations, or sequence of Observation / Observations
        The readings.
    params : sequence of str
        The parameters to fit (`Machine.parameter_names`), k of them.
    prior : ErrorModel or mapping of str to float, optional
        The starting point, and the values of every parameter not fitted (default: no error);
        also a dict in the TOML layout or a TOML path, as `machinesim.Lab` takes errors.
    max_iterations : int
        Gauss-Newton steps before `NotConvergedError`.
    progress : callable(str), optional
        Told one line per Gauss-Newton step (its number, the RMS of (reading - model) / sigma
        before it, and its largest step relative to the stopping rule): each step evaluates
        the model and its Jacobian at every distinct pose, all of them at once (under 1 and
        2-8 us a pose), so a plan of 100,000 distinct poses takes about a second a step
        (robonano_a0ib, 4 parameters; benchmarks/fit_speed.py).

    Returns
    -------
    Estimate

    Raises
    ------
    InputError
        Malformed readings (axis count, unknown frame), repeated parameter names, a machine
        that is neither a `Machine` nor a name.
    ErrorModelError
        An unknown parameter name, or a prior that does not fit the machine.
    NotConvergedError
        When the steps do not fall below the stopping rule within ``max_iterations``.
    """
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, int) \
            or max_iterations < 1:
        raise InputError(f"max_iterations must be an int >= 1, got {max_iterations!r}",
                         key="max_iterations")
    machine = as_machine(machine)
    prior = _prior(machine, prior)
    names = _names(machine, params, prior)
    obs = Observations.of(observations)
    plan = _Plan(machine, obs, names)
    start = np.array([prior.parameters().get(n, 0.0) for n in names])
    tolerance = np.where([is_angle(n) for n in names], tolerances.FIT_STEP_RAD,
                         tolerances.FIT_STEP_M)
    values = start.copy()
    iterations = 0
    at_prior = None
    while True:
        iterations += 1
        errors = prior.with_parameters(dict(zip(names, values.tolist(), strict=True)))
        residual = (obs.values - plan.readings(errors)) / obs.sigma
        # A parameter no reading moves at the prior stays there: later, the estimate's own
        # errors give it a lever (the B line's tilt EC0B through the fitted tool offset),
        # a direction seen only through the fit's own values, which drove fits to diverge
        lin = _linearise(plan.jacobian(errors), obs.sigma,
                         None if at_prior is None else at_prior.zero)
        at_prior = lin if at_prior is None else at_prior
        step = lin.step(residual, start - values)
        values = values + step
        if progress is not None:
            worst = int(np.argmax(np.abs(step) / tolerance))
            progress(f"Gauss-Newton step {iterations} on {len(obs):,} readings: RMS of "
                     f"(reading - model) / sigma before it "
                     f"{math.sqrt(float(np.mean(residual ** 2))):.4g}, "
                     f"largest step {names[worst]} {step[worst]:.3g} "
                     f"{'rad' if is_angle(names[worst]) else 'm'} "
                     f"({abs(step[worst]) / tolerance[worst]:.3g} x the stopping rule)")
        if np.all(np.abs(step) < tolerance):
            break
        _check_not_diverged(machine, names, values, iterations)
        if iterations == max_iterations:
            worst = int(np.argmax(np.abs(step) / tolerance))
            raise NotConvergedError(
                f"fit on {machine.name} did not converge in {max_iterations} Gauss-Newton steps: "
                f"the last step of {names[worst]} was {step[worst]:.3g} "
                f"{'rad' if is_angle(names[worst]) else 'm'} (stopping rule "
                f"{tolerance[worst]:g}); the plan's condition number is "
                f"{_figures(lin, names)['condition']:.3g}. Give a prior nearer the solution, or "
                "check the readings' signs and units (m)")
    errors = prior.with_parameters(dict(zip(names, values.tolist(), strict=True)))
    residual = obs.values - plan.readings(errors)
    figures = _figures(lin, names)
    dof = len(obs) - lin.rank
    chi = math.sqrt(float(np.sum((residual / obs.sigma) ** 2)) / dof) if dof > 0 else math.nan
    unseen = ()
    if lin.rank > at_prior.rank:  # those of the prior's symmetries the estimate now sees
        finite = {n for n, sd in zip(names, figures["std"], strict=True) if math.isfinite(sd)}
        unseen = tuple(u for u in _figures(at_prior, names)["unidentifiable"]
                       if isinstance(u, Combination) and set(u.names) <= finite)
    return Estimate(**figures, values=frozen(values),
                    residual_rms=float(np.sqrt(np.mean(residual ** 2))),
                    normalised_residual_rms=chi, iterations=iterations, errors=errors,
                    unseen_at_prior=unseen,
                    scale_notes=_scale_notes(obs.sigma, obs.values, names, values))

def _check_not_diverged(machine, names, values: np.ndarray, iterations: int) -> None:
    """Raise `NotConvergedError` when a step took a parameter beyond what an error model
    takes (`errors.LARGEST_ERROR`: 1 m, pi rad): the fit diverged."""
    size = np.where([is_angle(n) for n in names], LARGEST_ERROR["angle"],
                    LARGEST_ERROR["length"])
    if np.any(beyond := np.abs(values) > size):
        worst = int(np.argmax(beyond))
        raise NotConvergedError(
            f"fit on {machine.name} diverged: after {iterations} Gauss-Newton steps "
            f"{names[worst]} = {values[worst]:.3g} {'rad' if is_angle(names[worst]) else 'm'}, "
            f"beyond any error ({size[worst]:g}). Check the readings' signs and units (m), "
            "or give a prior nearer the solution")


@keywords_checked
def plan_quality(machine, q, params: Sequence[str], *, directions, sigma,
                 frame="tool_tip", point=None, zero_at=None, prior=None) -> PlanQuality:
    """What a measurement plan can identify, before any reading is taken.

    The same figures as `fit` reports (one function computes both), from the Jacobian at
    the prior: per-parameter standard uncertainty (the plan's valuation of each parameter),
    rank, condition, singular values and the unidentifiable parameters and combinations.
    ``plan_quality(machine, q, params, directions=..., sigma=...)`` takes the plan as
    `observations` takes readings (q first, the rest by the same keywords, without
    ``values``) and the parameters as `fit` does.

    Parameters
    ----------
    machine : Machine or str
        As for `fit`.
    q : array_like, shape (N, n_axes)
        Axis values of the readings, m and rad.
    params : sequence of str
        The parameters to identify.
    directions : array_like, shape (3,) or (N, 3)
        Sensing directions in the workpiece frame.
    sigma : float or array_like, shape (N,)
        Standard uncertainty of the readings, m.
    frame : str or sequence of str
        The frame of the observed point: one for all readings, or one per reading.
    point : array_like, shape (3,) or (N, 3), optional
        Point coordinates in their frames, m (default the frame origins).
    zero_at : array_like, shape (n_axes,) or (N, n_axes), optional
        Where the sensors are set to zero (`Observation.zero_at`): what a zeroed plan cannot
        see (a constant offset) is then named.
    prior : ErrorModel or mapping of str to float, optional
        Where to linearise (default: the nominal machine); also a dict in the TOML layout or
        a TOML path.

    Returns
    -------
    PlanQuality
    """
    machine = as_machine(machine)
    prior = _prior(machine, prior)
    names = _names(machine, params, prior)
    obs = Observations(q, values=0.0, directions=directions, sigma=sigma, frames=frame,
                       points=point, zero_at=zero_at)
    plan = _Plan(machine, obs, names)
    return PlanQuality(**_figures(_linearise(plan.jacobian(prior), obs.sigma), names),
                       scale_notes=_scale_notes(obs.sigma))
