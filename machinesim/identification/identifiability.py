"""What a plan of displacement readings can identify: the figures `fit` and `plan_quality` report.

The weighted Jacobian of a plan (`machinesim.identification.fit`), column-scaled and taken
apart by an SVD (`_linearise`), gives every figure of `PlanQuality` and of the fit's
`Estimate`: standard uncertainties, covariance, correlation, rank, condition, singular
values, the null-space directions named as `Combination` entries, and the notes a person
should read before trusting them. The derivation is in docs/identification.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from machinesim import tolerances
from machinesim.arrays import frozen
from machinesim.identification.observations import is_angle

__all__ = ["IMPLAUSIBLE_LENGTH_M", "NEARLY_INSEPARABLE", "Combination", "PlanQuality"]


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

    def _summary(self) -> str:
        """Counts and figures for a repr: what the object is, without its matrices."""
        notes = len(self.notes)
        return (f"{len(self.names)} parameters, {self.n_observations} readings, rank "
                f"{self.rank}, condition {self.condition:.3g}, {notes} "
                f"note{'' if notes == 1 else 's'}")


#: Parameters a repr lists before it says how many more there are.
REPR_PARAMETERS = 8


def parameter_unit(name: str) -> str:
    """The SI unit of a parameter's value: 'rad' or 'm', 'SI' for a component error's
    table entry or polynomial coefficient (m or rad, per unit of the axis' travel^k) and
    for a name that is no error parameter's (a procedure's own quantity)."""
    known = ("tool.", "tool_geometry.", "workpiece.", "location.")
    if name.startswith("component.") or not name.startswith(known):
        return "SI"
    return "rad" if is_angle(name) else "m"


def listed(names, values, std=None, unit_of=parameter_unit,
           no_std: str = "unidentifiable") -> str:
    """``name = value unit +- std unit`` for a repr, the first `REPR_PARAMETERS` of them
    (`unit_of`: a model's `ErrorModel.parameter_unit`, which knows its polynomials;
    `no_std`: what a NaN std means)."""
    items = []
    for i, name in enumerate(names[:REPR_PARAMETERS]):
        unit = unit_of(name)
        text = f"{name} = {float(values[i]):.6g} {unit}" if values is not None else name
        if std is not None:
            s = float(std[i])
            text += (f" {no_std}" if math.isnan(s) else
                     f"{' +- ' if values is not None else ' std '}{s:.3g} {unit}")
        items.append(text)
    if len(names) > REPR_PARAMETERS:
        items.append(f"... {len(names) - REPR_PARAMETERS} more")
    return ", ".join(items)


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


@dataclass(frozen=True, eq=False, repr=False)
class PlanQuality(_Figures):
    __doc__ = ("""What a measurement plan can identify, before any reading (`plan_quality`).

    The per-parameter ``std`` is the plan's valuation: what the readings' uncertainty
    becomes in each parameter.

    Attributes
    ----------""" + _FIGURES_DOC + """    scale_notes : tuple of str
        The note on a sigma beyond `IMPLAUSIBLE_LENGTH_M` (given in um or mm?), if any.
""")

    scale_notes: tuple = ()

    def __repr__(self) -> str:
        return (f"PlanQuality({self._summary()}: "
                f"{listed(self.names, None, self.std)})")


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


def _linearise(jacobian: np.ndarray, sigma: np.ndarray,
               held: np.ndarray | None = None) -> _Linearisation:
    """Weight the Jacobian (N, k) by 1 / sigma, scale its columns to unit norm, SVD it.
    ``held`` (k,) bool marks parameters taken as moving no reading whatever their column
    (`fit` holds those no reading moves at the prior)."""
    k = jacobian.shape[1]
    weighted = jacobian / sigma[:, None]
    norms = np.linalg.norm(weighted, axis=0)
    # weighted RMS sensitivity, m per unit of the parameter, whatever the sigma
    zero = norms / np.linalg.norm(1.0 / sigma) <= tolerances.FIT_ZERO_COLUMN
    if held is not None:
        zero |= held
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
