"""Declarations with an honest uncertainty: the credible region and the HPD level of the true source (defined
with the validation experiment's metrics, :mod:`psgsl_pgm.experiment._metrics`), and the Wilson interval of a
success rate. Times to find are censored at the budget; their statistics are in :mod:`._survival`."""

from __future__ import annotations

import numpy as np
from scipy import stats

from ..experiment._metrics import credible_region, hpd_level, mean_ci

__all__ = ["credible_region", "hpd_level", "paired_difference", "survival", "wilson_interval"]


def wilson_interval(successes: int, n: int, *, level: float = 0.95) -> list:
    """Wilson score interval of a binomial proportion, [lo, hi].

    Examples
    --------
    >>> [round(x, 4) for x in wilson_interval(8, 10)]
    [0.4902, 0.9433]
    """
    if n < 1:
        return [float("nan"), float("nan")]
    z = stats.norm.ppf(0.5 + level / 2)
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    lo = 0.0 if successes == 0 else max(0.0, centre - half)
    hi = 1.0 if successes == n else min(1.0, centre + half)
    return [float(lo), float(hi)]


def paired_difference(a, b, *, level: float = 0.95) -> dict:
    """Mean of a − b over paired runs (same seeds) with its Student-t interval: ``{"mean", "ci95", "n"}``.

    For quantities that are never capped (errors, spreads, areas). Times censored at a budget need
    :func:`psgsl_pgm.search.paired_comparison` (RMST difference, sign-flip test) instead.
    """
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"paired samples must have the same shape, got {a.shape} and {b.shape}")
    out = mean_ci(a - b, level=level)
    out["n"] = int(a.size)
    return out


def survival(times, found, grid) -> np.ndarray:
    """Fraction of runs not yet found at each time of ``grid``, (len(grid),).

    Runs not found stay in for ever. When every run not found is censored at one budget and ``grid`` lies within
    it, this is the Kaplan–Meier estimate (:func:`psgsl_pgm.search.kaplan_meier`, which also gives its bands).
    """
    t = np.asarray(times, dtype=np.float64)
    f = np.asarray(found, dtype=bool)
    g = np.asarray(grid, dtype=np.float64)
    done = f[None, :] & (t[None, :] <= g[:, None])
    return 1.0 - done.mean(axis=1)
