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
docs/identification.md.

>>> import numpy as np, machinesim
>>> from machinesim.identification.fit import fit, observations
>>> machine = machinesim.load_machine("robonano_ui")
>>> q = np.zeros((3, 6)); u = np.eye(3)
>>> obs = observations(q, u, [1e-6, -2e-6, 0.0], 1e-8)
>>> estimate = fit(machine, obs, ["workpiece.x", "workpiece.y"])
>>> np.round(estimate.values * 1e6, 9), estimate.rank
(array([-1.,  2.]), 2)
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from machinesim import tolerances
from machinesim.arrays import frozen
from machinesim.errors import LARGEST_ERROR, ErrorModel
from machinesim.exceptions import AxisLimitError, ErrorModelError, InputError, NotConvergedError
from machinesim.identification.observations import (
    Observation,
    Observations,
    is_angle,
    observations,
)
from machinesim.metrology.instruments import as_machine

__all__ = [
    "Combination", "Estimate", "NotConvergedError", "Observation", "Observations",
    "PlanQuality", "fit", "observations", "plan_quality",
]

#: Gauss-Newton steps before `fit` gives up. From a zero prior it converges in 4 steps for
#: setting errors of hundreds of um and 2 degrees (quadratically once near the solution);
#: 50 leaves room for a slowly converging fit without hiding a divergence.
MAX_ITERATIONS = 50


# ------------------------------------------------------------------------- identifiability


@dataclass(frozen=True, eq=False)
class Combination:
    """A null-space direction: moving the parameters by ``t * coefficients`` (SI) together
    changes no reading of the plan (to first order), whatever ``t``.

    Attributes
    ----------
    names : tuple of str
        The parameters involved, in the fit's order.
    coefficients : ndarray, shape (len(names),)
        SI (m or rad per unit of t), the largest magnitude exactly 1 (positive); coefficients
        whose effect on the readings is below `tolerances.FIT_NULL_COMPONENT` of the largest
        are dropped.
    """

    names: tuple[str, ...]
    coefficients: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "coefficients", frozen(self.coefficients))

    def value(self, parameters: Mapping[str, float]) -> float:
        """``coefficients . parameters[names]`` (missing names count as 0)."""
        return float(sum(c * parameters.get(n, 0.0)
                         for n, c in zip(self.names, self.coefficients, strict=True)))

    def __str__(self) -> str:
        terms = []
        for name, c in zip(self.names, self.coefficients, strict=True):
            size = f"{abs(c):.4g}"
            terms.append(("- " if c < 0 else "+ ") + (name if size == "1" else f"{size}*{name}"))
        text = " ".join(terms)
        return text[2:] if text.startswith("+ ") else "-" + text[2:]

    def __repr__(self) -> str:
        return f"Combination({str(self)!r})"


#: |correlation| beyond which two parameters are reported as barely separable (`notes`).
NEARLY_INSEPARABLE = 0.999
#: Normalised residual RMS beyond which the readings are reported as not fitting the model:
#: with N - rank degrees of freedom and right sigma it is about 1 (above 1.5 by chance with
#: probability < 1e-3 from 20 degrees of freedom on).
MODEL_MISFIT = 3.0
#: A reading, a sigma or an identified length beyond this, m, is no machine error that a
#: displacement sensor reads (R-test and dial indicator ranges are a few mm; the largest
#: setting errors these fits meet, 2 degrees seen 50 mm away, read 1.7 mm): the usual cause
#: is micrometres or millimetres given where metres are expected, which the fit, linear in
#: the readings, turns into values off by that factor (`notes`).
IMPLAUSIBLE_LENGTH_M = 0.01


@dataclass(frozen=True, eq=False)
class _Figures:
    """What a plan can identify, from its Jacobian (shared by PlanQuality and Estimate)."""

    names: tuple[str, ...]
    std: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    rank: int
    condition: float
    singular_values: np.ndarray
    unidentifiable: tuple
    n_observations: int

    @property
    def identifiable(self) -> tuple[str, ...]:
        """Names of the parameters identifiable on their own."""
        return tuple(n for n, s in zip(self.names, self.std, strict=True) if not math.isnan(s))

    @property
    def combinations(self) -> tuple[Combination, ...]:
        """The named null-space directions (the `Combination` entries of `unidentifiable`)."""
        return tuple(u for u in self.unidentifiable if isinstance(u, Combination))

    @property
    def notes(self) -> tuple[str, ...]:
        """What a person should read before trusting the figures: sizes no machine error has
        (readings or sigma given in um or mm, `IMPLAUSIBLE_LENGTH_M`), each direction the
        readings cannot see (rank below the number of parameters: the values along it are
        the prior's, not measured), and each pair of parameters correlated beyond
        `NEARLY_INSEPARABLE` (a near-symmetry of the plan: identifiable in the SVD's sense,
        yet barely told apart, as their std say)."""
        out = list(self.scale_notes)
        out += [_unseen_note(c, self.rank, len(self.names)) for c in self.combinations]
        k = len(self.names)
        for i in range(k):
            for j in range(i + 1, k):
                r = float(self.correlation[i, j])
                if math.isfinite(r) and abs(r) > NEARLY_INSEPARABLE:
                    out.append(f"{self.names[i]} and {self.names[j]} are correlated {r:+.6f}: "
                               f"the readings barely tell them apart (std {self.std[i]:.3g} "
                               f"and {self.std[j]:.3g}); fix one, or add readings that "
                               "separate them")
        return tuple(out)


def _unseen_note(c: Combination, rank: int, k: int) -> str:
    """The note on one direction the readings cannot see (`_Figures.notes`)."""
    head = f"rank {rank} of {k}: the readings cannot see "
    if len(c.names) == 1:
        what = (f"{c}: its value is the prior's, not measured; a compensation through it "
                "corrects nothing of it")
    else:
        what = (f"the combination {c}: its value is the prior's, so {', '.join(c.names)} "
                "are not identified on their own and their values are one solution among "
                "many; a compensation through them is right only for what the readings saw")
    return (head + what + ". Fix a datum (leave a parameter out of the fit) or add readings "
            "that see it")


_FIGURES_DOC = """
    names : tuple of str
        The parameters, in the order given.
    std : ndarray, shape (k,)
        Standard uncertainty of each parameter (m or rad) from the readings' sigma (a priori,
        not rescaled by the residuals); NaN for a parameter not identifiable on its own.
    covariance : ndarray, shape (k, k)
        From the truncated pseudo-inverse of the weighted Jacobian (SI); rows and columns of
        unidentifiable parameters are NaN.
    correlation : ndarray, shape (k, k)
        covariance / (std std^T); NaN where either parameter is unidentifiable.
    rank : int
        Number of singular values above `tolerances.FIT_RANK_REL` of the largest.
    condition : float
        Largest over smallest kept singular value of the column-scaled weighted Jacobian:
        the condition number of its identifiable part (NaN when nothing is identifiable).
    singular_values : ndarray, shape (k,)
        Of the column-scaled weighted Jacobian, largest first (dimensionless); zero for a
        parameter that moves no reading and beyond the number of readings.
    unidentifiable : tuple
        The names (str) of the parameters not identifiable on their own, then one
        `Combination` per null-space direction (k - rank of them): a reduced echelon basis,
        each with a leading parameter the others lack (a parameter that moves no reading is
        a combination of one).
    n_observations : int
        Number of readings.
"""


@dataclass(frozen=True, eq=False)
class PlanQuality(_Figures):
    __doc__ = ("""What a measurement plan can identify, before any reading (`plan_quality`).

    The per-parameter ``std`` is the plan's valuation: what the readings' uncertainty
    becomes in each parameter.

    Attributes
    ----------""" + _FIGURES_DOC + """    scale_notes : tuple of str
        The note on a sigma beyond `IMPLAUSIBLE_LENGTH_M` (given in um or mm?), if any.
""")

    scale_notes: tuple = ()


@dataclass(frozen=True, eq=False)
class Estimate(_Figures):
    __doc__ = ("""The result of `fit`: the parameters and what the readings could identify.

    Attributes
    ----------""" + _FIGURES_DOC + """    values : ndarray, shape (k,)
        The estimates, SI. Along the null space they stay as near the prior as the readings
        allow (estimate minus prior is orthogonal, in SI, to every `Combination`); a
        parameter that moves no reading keeps the prior's value exactly.
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
        The directions the readings could not see at the prior (the plan's symmetries there,
        as `plan_quality` at the prior names them), when the fit ended with a higher rank:
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
    def notes(self) -> tuple[str, ...]:
        """As `PlanQuality.notes`, and when the readings do not fit the model: a normalised
        residual above `MODEL_MISFIT` (a parameter the readings show but neither ``params``
        nor the prior holds, or sigma given too small)."""
        out = list(super().notes)
        for c in self.unseen_at_prior:
            stds = ", ".join(f"{n} {self.std[self.names.index(n)]:.3g}" for n in c.names)
            out.append(f"at the prior the readings cannot see {c}; the fit, of rank "
                       f"{self.rank}, sees it only through the estimate's own errors, so "
                       f"these values rest on that small lever (std {stds}) and may be far "
                       "off (a compensation through them may add error). Fix a datum (leave "
                       "a parameter out of the fit) or add readings that see it")
        if self.normalised_residual_rms > MODEL_MISFIT:
            out.append(f"the readings do not fit the model: normalised residual "
                       f"{self.normalised_residual_rms:.3g} (about 1 when the model holds "
                       f"every error the readings show and sigma is right; residual RMS "
                       f"{self.residual_rms:.3g} m): an error missing from the parameters "
                       "or the prior, or sigma too small; the values may be far off")
        return tuple(out)

    def as_dict(self) -> dict[str, dict[str, float]]:
        """``{name: {"value": v, "std": s}}`` in SI (std NaN when unidentifiable)."""
        return {n: {"value": float(v), "std": float(s)}
                for n, v, s in zip(self.names, self.values, self.std, strict=True)}


@dataclass(frozen=True, eq=False)
class _Linearisation:
    """SVD of the column-scaled weighted Jacobian of one linearisation."""

    scale: np.ndarray  # (k,) column norms of the weighted Jacobian (1 for zero columns)
    zero: np.ndarray  # (k,) bool: parameters that move no reading
    u: np.ndarray  # (N, r) kept left singular vectors
    s: np.ndarray  # (k,) singular values, largest first (zeros: zero columns, N < k)
    v: np.ndarray  # (k, r) kept right singular vectors (scaled coordinates)
    null: np.ndarray  # (k, k - r) orthonormal null basis (scaled), zero columns' first

    @property
    def rank(self) -> int:
        return self.v.shape[1]

    def step(self, residual_w: np.ndarray, to_prior: np.ndarray) -> np.ndarray:
        """Gauss-Newton step (SI) for weighted residuals (N,) and ``to_prior`` = prior minus
        current values (k,): the truncated-SVD solution of the linearised problem (scaled
        coordinates), with its null-space part chosen so that the new values lie as near
        the prior as the data allow (SI distance, m and rad counted alike)."""
        step = (self.v @ ((self.u.T @ residual_w) / self.s[:self.rank])) / self.scale
        # The null basis starts with the unit vectors of the zero columns, orthogonal to the
        # rest in any metric: handled exactly. The rest is orthonormalised in SI.
        step[self.zero] = to_prior[self.zero]
        rest = self.null[:, np.count_nonzero(self.zero):] / self.scale[:, None]
        if rest.shape[1]:
            basis, _ = np.linalg.qr(rest / np.linalg.norm(rest, axis=0))
            step += basis @ (basis.T @ (to_prior - step))
        return step


def _linearise(jacobian: np.ndarray, sigma: np.ndarray) -> _Linearisation:
    """Weight the Jacobian (N, k) by 1 / sigma, scale its columns to unit norm, SVD it."""
    k = jacobian.shape[1]
    weighted = jacobian / sigma[:, None]
    norms = np.linalg.norm(weighted, axis=0)
    # weighted RMS sensitivity, m per unit of the parameter, whatever the sigma
    zero = norms / np.linalg.norm(1.0 / sigma) <= tolerances.FIT_ZERO_COLUMN
    scale = np.where(zero, 1.0, norms)
    live = np.flatnonzero(~zero)
    u, s, vt = np.linalg.svd(weighted[:, live] / scale[live], full_matrices=False)
    rank = int(np.count_nonzero(s > tolerances.FIT_RANK_REL * s[0])) if s.size and s[0] else 0
    if vt.shape[0] < live.size:  # fewer readings than parameters: complete the basis
        vt = np.linalg.svd(vt[:rank], full_matrices=True)[2] if rank else np.eye(live.size)
    v = np.zeros((k, rank))
    v[live] = vt[:rank].T
    null = np.zeros((k, k - rank))
    null[np.flatnonzero(zero), np.arange(zero.sum())] = 1.0
    null[live, zero.sum():] = vt[rank:].T
    singular_values = np.zeros(k)
    singular_values[:s.size] = s
    return _Linearisation(scale, zero, u[:, :rank], singular_values, v, null)


def _figures(lin: _Linearisation, names: tuple[str, ...]) -> dict:
    """Identifiability figures of a linearisation: the fields of `PlanQuality`. The one
    function behind both `fit` and `plan_quality`."""
    r, s, v = lin.rank, lin.s, lin.v
    identifiable = np.linalg.norm(lin.null, axis=1) <= tolerances.FIT_NULL_COMPONENT
    covariance = (v / s[:r] ** 2) @ v.T / np.outer(lin.scale, lin.scale)
    covariance[~identifiable, :] = np.nan
    covariance[:, ~identifiable] = np.nan
    std = np.sqrt(np.diag(covariance))
    correlation = covariance / np.outer(std, std)
    np.fill_diagonal(correlation, np.where(identifiable, 1.0, np.nan))
    alone = tuple(n for n, ok in zip(names, identifiable, strict=True) if not ok)
    return dict(names=tuple(names), std=frozen(std), covariance=frozen(covariance),
                correlation=frozen(correlation), rank=r,
                condition=float(s[0] / s[r - 1]) if r else math.nan,
                singular_values=frozen(s),
                unidentifiable=alone + _combinations(lin.null, lin.scale, names),
                n_observations=lin.u.shape[0])


def _combinations(null: np.ndarray, scale: np.ndarray, names) -> tuple[Combination, ...]:
    """Readable names of the null space: a reduced echelon basis (Gauss-Jordan, full
    pivoting) of its orthonormal basis, so that each direction has a leading parameter the
    others lack; coefficients then in SI, the largest 1."""
    rows = null.T.copy()
    m = rows.shape[0]
    pivots = []
    for i in range(m):
        sub = np.abs(rows[i:])
        r, c = np.unravel_index(int(np.argmax(sub)), sub.shape)
        rows[[i, i + r]] = rows[[i + r, i]]
        rows[i] /= rows[i, c]
        for j in range(m):
            if j != i:
                rows[j] -= rows[j, c] * rows[i]
        pivots.append(c)
    out = []
    for i in np.argsort(pivots):
        row = rows[i]
        keep = np.abs(row) > tolerances.FIT_NULL_COMPONENT * np.max(np.abs(row))
        si = np.where(keep, row / scale, 0.0)
        si /= si[np.argmax(np.abs(si))]
        out.append(Combination(tuple(np.asarray(names)[keep]), si[keep]))
    return tuple(out)


# -------------------------------------------------------------------------------- the model


class _Plan:
    """The readings bound to a machine and a parameter list: model readings and Jacobian."""

    def __init__(self, machine, obs: Observations, names: tuple[str, ...]) -> None:
        if obs.q.shape[1] != len(machine.axes):
            raise InputError(
                f"{machine.name} has axes {''.join(machine.axes)}: expected axis values of "
                f"shape (N, {len(machine.axes)}), got {obs.q.shape}", key="q")
        unknown = sorted(set(obs.frames) - set(machine.frames))
        if unknown:
            raise InputError(f"frame {unknown[0]!r} is not on {machine.name}; it has "
                             f"{', '.join(machine.frames)}", key="frames")
        outside = machine.limit_violations(obs.q)
        if outside:
            raise AxisLimitError(f"{machine.name}: readings at axis values the machine cannot "
                                 f"take: {'; '.join(outside)} (axis values in m and rad)")
        self.machine = machine
        self.obs = obs
        self.names = names
        frames = np.asarray(obs.frames)
        self.groups = []
        for frame in dict.fromkeys(obs.frames):
            rows = np.flatnonzero(frames == frame)
            unique, inverse = np.unique(obs.q[rows], axis=0, return_inverse=True)
            self.groups.append((frame, rows, unique, inverse.ravel()))
        self.nominal = self._positions(None)
        # readings of sensors set to zero at a pose: less the same reading there
        self.zeroed = np.flatnonzero(obs.zeroed)
        self.zero = None if not self.zeroed.size else _Plan(machine, Observations(
            obs.zero_at[self.zeroed], 0.0, obs.directions[self.zeroed],
            obs.sigma[self.zeroed], tuple(np.asarray(obs.frames)[self.zeroed].tolist()),
            obs.points[self.zeroed]), names)

    def _positions(self, errors) -> np.ndarray:
        """Positions (N, 3) of the observed points in the workpiece frame, m.

        One Pinocchio pass per distinct pose, as `Machine.error_jacobian` does: a plan reads
        several points and directions per pose, and the batched evaluator would build its
        chain anew for every error model of the iteration.
        """
        out = np.empty((len(self.obs), 3))
        for frame, rows, unique, inverse in self.groups:
            poses = np.array([self.machine.pinocchio_pose(qn, errors, frame) for qn in unique])
            poses = poses[inverse]
            out[rows] = poses[:, :3, 3] + np.einsum("nij,nj->ni", poses[:, :3, :3],
                                                    self.obs.points[rows])
        return out

    def readings(self, errors) -> np.ndarray:
        """Model readings (N,), m: u . (x(errors) - x(nominal)), less the same at
        ``zero_at`` for a zeroed reading."""
        out = np.einsum("ni,ni->n", self.obs.directions, self._positions(errors) - self.nominal)
        if self.zero is not None:
            out[self.zeroed] -= self.zero.readings(errors)
        return out

    def jacobian(self, errors) -> np.ndarray:
        """d readings / d parameters (N, k), m per m or per rad."""
        out = np.empty((len(self.obs), len(self.names)))
        for frame, rows, _, _ in self.groups:
            jac = self.machine.error_jacobian(self.obs.q[rows], errors, self.names, frame=frame,
                                              point=self.obs.points[rows])
            out[rows] = np.einsum("ni,nik->nk", self.obs.directions[rows], jac[:, :3, :])
        if self.zero is not None:
            out[self.zeroed] -= self.zero.jacobian(errors)
        return out


def _prior(machine, prior) -> ErrorModel:
    if prior is None:
        model = ErrorModel()
    elif isinstance(prior, ErrorModel):
        model = prior
    elif isinstance(prior, Mapping):
        model = ErrorModel().with_parameters(prior)
    else:
        raise InputError(f"expected the prior as an ErrorModel or a mapping name -> value "
                         f"(SI), got {type(prior).__name__}", key="prior")
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
    `Combination` out of ``params`` (it keeps the prior's value).

    Parameters
    ----------
    machine : Machine or str
        The machine, or the name of a shipped one (or a URDF path), as `load_machine` takes.
    observations : Observations, or sequence of Observation / Observations
        The readings.
    params : sequence of str
        The parameters to fit (`Machine.parameter_names`), k of them.
    prior : ErrorModel or mapping of str to float, optional
        The starting point, and the values of every parameter not fitted (default: no error).
    max_iterations : int
        Gauss-Newton steps before `NotConvergedError`.
    progress : callable(str), optional
        Told one line per Gauss-Newton step (its number, the RMS of (reading - model) / sigma
        before it, and its largest step relative to the stopping rule): each step evaluates
        the model and its Jacobian at every distinct pose, about 0.2 ms a pose, so a plan
        of 100,000 distinct poses takes some 20 s a step (robonano_a0ib, 4 parameters).

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
        lin = _linearise(plan.jacobian(errors), obs.sigma)
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


def _scale_notes(sigma: np.ndarray, readings: np.ndarray | None = None, names=(),
                 values: np.ndarray | None = None) -> tuple[str, ...]:
    """One note naming the largest reading, the largest sigma and each identified length
    beyond `IMPLAUSIBLE_LENGTH_M` (none when all are within it)."""
    found = []
    for what, arr in (("reading", readings), ("sigma", sigma)):
        if arr is not None and np.max(np.abs(arr)) > IMPLAUSIBLE_LENGTH_M:
            i = int(np.argmax(np.abs(arr)))
            found.append(f"{what} {i} is {float(arr[i]):.3g} m")
    if values is not None:
        found += [f"{n} = {float(v):.3g} m" for n, v in zip(names, values, strict=True)
                  if not is_angle(n) and abs(v) > IMPLAUSIBLE_LENGTH_M]
    if not found:
        return ()
    return (f"{'; '.join(found)}: beyond {IMPLAUSIBLE_LENGTH_M:g} m, more than a displacement "
            "sensor reads of a machine's errors. Readings and sigma are in metres: were they "
            "given in um or mm? The values are then off by that factor",)


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


def plan_quality(machine, q, frames, directions, params: Sequence[str], sigma, *,
                 prior=None, points=None, zero_at=None) -> PlanQuality:
    """What a measurement plan can identify, before any reading is taken.

    The same figures as `fit` reports (one function computes both), from the Jacobian at
    the prior: per-parameter standard uncertainty (the plan's valuation of each parameter),
    rank, condition, singular values and the unidentifiable parameters and combinations.

    Parameters
    ----------
    machine : Machine or str
        As for `fit`.
    q : array_like, shape (N, n_axes)
        Axis values of the readings, m and rad.
    frames : str or sequence of str
        The frame of the observed point: one for all readings, or one per reading.
    directions : array_like, shape (N, 3)
        Sensing directions in the workpiece frame.
    params : sequence of str
        The parameters to identify.
    sigma : float or array_like, shape (N,)
        Standard uncertainty of the readings, m.
    prior : ErrorModel or mapping of str to float, optional
        Where to linearise (default: the nominal machine).
    points : array_like, shape (3,) or (N, 3), optional
        Point coordinates in their frames, m (default the frame origins).
    zero_at : array_like, shape (n_axes,) or (N, n_axes), optional
        Where the sensors are set to zero (`Observation.zero_at`): what a zeroed plan cannot
        see (a constant offset) is then named.

    Returns
    -------
    PlanQuality
    """
    machine = as_machine(machine)
    prior = _prior(machine, prior)
    names = _names(machine, params, prior)
    obs = Observations(q, 0.0, directions, sigma, frames, points, zero_at)
    plan = _Plan(machine, obs, names)
    return PlanQuality(**_figures(_linearise(plan.jacobian(prior), obs.sigma), names),
                       scale_notes=_scale_notes(obs.sigma))
