"""What a campaign's trials say: distributions, coverage intervals, z-scores, sensitivity.

- **Coverage interval** (JCGM 101:2008, section 7.7): from the M sorted trial values
  y_(1) <= ... <= y_(M), with q = pM rounded to the nearest integer (pM + 1/2, truncated):
  the *probabilistically symmetric* interval [y_(r), y_(r+q)] with r = (M - q) / 2 rounded
  the same way (7.7.1, an equal share (1 - p)/2 of the trials left out on each side), and the
  *shortest* interval, the r* in 1 .. M - q minimising y_(r+q) - y_(r) (7.7.2). The summary
  gives both and names which; the shortest suits the skewed, one-sided distributions of
  after-compensation errors, the symmetric one values of either sign.
- **z-score** of an identified parameter in a trial: (identified - injected) / std, with the
  std the identification reported. Honest uncertainty makes the z-scores N(0, 1): mean 0,
  std 1, 95 % of them within +-1.96.
- **Sensitivity**: Spearman's rank correlation of each varied parameter with each figure
  after compensation (the Pearson correlation of the ranks, ties averaged): monotonic, not
  only linear, dependence, and insensitive to the heavy tails of a failed compensation.
"""

from __future__ import annotations

import math

import numpy as np

from machinesim.exceptions import InputError

__all__ = ["coverage_interval", "describe", "ranks", "spearman", "z_scores"]

#: Coverage probability of the reported intervals.
COVERAGE = 0.95


def _sorted(values) -> np.ndarray:
    y = np.asarray(values, dtype=np.float64).ravel()
    y = np.sort(y[np.isfinite(y)])
    return y


def coverage_interval(values, p: float = COVERAGE, kind: str = "shortest"
                      ) -> tuple[float, float]:
    """The coverage interval for probability ``p`` from trial values (JCGM 101, 7.7).

    Parameters
    ----------
    values : array_like
        The trials' values; NaN (failed trials, unmeasured figures) left out.
    p : float
        Coverage probability, 0 < p < 1.
    kind : {"shortest", "symmetric"}
        JCGM 101 7.7.2 (shortest) or 7.7.1 (probabilistically symmetric).

    Returns
    -------
    (low, high) : floats, NaN when fewer values than make q >= 1 and r >= 1.
    """
    if not 0.0 < p < 1.0:
        raise InputError(f"coverage probability {p!r}; expected 0 < p < 1", key="p")
    if kind not in ("shortest", "symmetric"):
        raise InputError(f"coverage interval kind {kind!r}; expected shortest or symmetric",
                         key="kind")
    y = _sorted(values)
    m = y.size
    q = int(p * m + 0.5)
    if m == 0 or q < 1 or q >= m:
        return (math.nan, math.nan)
    if kind == "symmetric":
        r = int((m - q) / 2 + 0.5) if (m - q) % 2 else (m - q) // 2
        r = max(r, 1)
        return (float(y[r - 1]), float(y[r - 1 + q]))
    widths = y[q:] - y[:m - q]          # r = 1 .. M - q (0-based r - 1)
    r = int(np.argmin(widths))
    return (float(y[r]), float(y[r + q]))


def _mean_std(y: np.ndarray) -> tuple[float, float]:
    """The mean and std (n - 1; NaN for one value) of the sorted finite values ``y`` (at
    least one), without overflow: values near float64's end (an edited after of 1e308) made
    their sum infinite, with numpy's RuntimeWarning, and the mean and std NaN. Such values
    are taken again divided by the largest magnitude (the same mean and std, scaled back; a
    std beyond float64, of values of both signs near its end, is inf). Others are computed
    as before, to the bit."""
    with np.errstate(over="ignore", invalid="ignore"):
        mean = float(y.mean())
        std = float(y.std(ddof=1)) if y.size > 1 else math.nan
        if math.isfinite(mean) and (y.size == 1 or math.isfinite(std)):
            return mean, std
        scale = max(abs(float(y[0])), abs(float(y[-1])))  # sorted: the largest at an end
        scaled = y / scale
        return (scale * float(scaled.mean()),
                scale * float(scaled.std(ddof=1)) if y.size > 1 else math.nan)


def describe(values) -> dict:
    """count, mean, std (n - 1), both 95 % coverage intervals, min, max of the finite values."""
    y = _sorted(values)
    out = {"count": int(y.size), "mean": math.nan, "std": math.nan, "min": math.nan,
           "max": math.nan}
    if y.size:
        mean, std = _mean_std(y)
        out.update(mean=mean, std=std, min=float(y[0]), max=float(y[-1]))
    out["shortest_95"] = list(coverage_interval(y, kind="shortest"))
    out["symmetric_95"] = list(coverage_interval(y, kind="symmetric"))
    return out


def z_scores(identified, injected, std) -> np.ndarray:
    """(identified - injected) / std, elementwise; NaN where std is not a positive number,
    inf where it is beyond float64 (left out of the statistics as any non-finite value)."""
    identified, injected, std = (np.asarray(a, dtype=np.float64)
                                 for a in (identified, injected, std))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        z = (identified - injected) / std
    return np.where(np.isfinite(std) & (std > 0.0), z, np.nan)


def z_summary(z) -> dict:
    """count, mean, std of the z-scores and the share within +-1.96 (0.95 for N(0, 1))."""
    y = _sorted(z)
    out = {"count": int(y.size), "mean": math.nan, "std": math.nan,
           "within_1_96_ratio": math.nan}
    if y.size:
        out["mean"], out["std"] = _mean_std(y)
        out["within_1_96_ratio"] = float(np.mean(np.abs(y) <= 1.959963984540054))
    return out


def ranks(values) -> np.ndarray:
    """Ranks 1 .. n of ``values``, ties given their average rank."""
    x = np.asarray(values, dtype=np.float64)
    order = np.argsort(x, kind="mergesort")
    sorted_x = x[order]
    out = np.empty(x.size)
    start = 0
    for end in range(1, x.size + 1):
        if end == x.size or sorted_x[end] != sorted_x[start]:
            out[order[start:end]] = (start + end + 1) / 2.0
            start = end
    return out


def spearman(x, y) -> float:
    """Spearman's rank correlation of ``x`` and ``y`` over the pairs where both are finite;
    NaN with fewer than 3 pairs or a constant side."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    keep = np.isfinite(x) & np.isfinite(y)
    if keep.sum() < 3:
        return math.nan
    rx, ry = ranks(x[keep]), ranks(y[keep])
    rx, ry = rx - rx.mean(), ry - ry.mean()
    den = math.sqrt(float(rx @ rx) * float(ry @ ry))
    return math.nan if den == 0.0 else float(rx @ ry) / den
