"""Declarations with an honest uncertainty and the statistics over runs (issue 15, items 3–4)."""

from __future__ import annotations

import numpy as np
from scipy import stats

from ..experiment._metrics import mean_ci

__all__ = ["credible_region", "paired_difference", "survival", "wilson_interval"]


def credible_region(posterior, mass: float = 0.9) -> np.ndarray:
    """The smallest set of cells holding at least ``mass`` of the distribution (its highest-probability cells).

    Parameters
    ----------
    posterior : (..., ) array_like
        A distribution over cells (sums to 1).
    mass : float
        In (0, 1).

    Returns
    -------
    region : ndarray of bool, the posterior's shape
        Ties at the boundary are broken by cell order (the region has the minimal number of cells).

    Examples
    --------
    >>> credible_region([0.5, 0.1, 0.3, 0.1], 0.75).tolist()
    [True, False, True, False]
    """
    p = np.asarray(posterior, dtype=np.float64)
    if not 0 < mass < 1:
        raise ValueError(f"mass must lie in (0, 1), got {mass!r}")
    if not (np.isfinite(p).all() and (p >= 0).all() and abs(p.sum() - 1.0) < 1e-6):
        raise ValueError("posterior must be a distribution (finite, >= 0, sums to 1)")
    flat = p.ravel()
    order = np.argsort(-flat, kind="stable")
    csum = np.cumsum(flat[order])
    k = int(np.searchsorted(csum, mass * csum[-1] * (1 - 1e-12))) + 1  # first prefix reaching the mass
    region = np.zeros(flat.size, bool)
    region[order[:k]] = True
    return region.reshape(p.shape)


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
    """Mean of a − b over paired runs (same seeds) with its Student-t interval: ``{"mean", "ci95", "n"}``."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"paired samples must have the same shape, got {a.shape} and {b.shape}")
    out = mean_ci(a - b, level=level)
    out["n"] = int(a.size)
    return out


def survival(times, found, grid) -> np.ndarray:
    """Fraction of runs not yet found at each time of ``grid`` (runs not found stay in for ever)."""
    t = np.asarray(times, dtype=np.float64)
    f = np.asarray(found, dtype=bool)
    g = np.asarray(grid, dtype=np.float64)
    done = f[None, :] & (t[None, :] <= g[:, None])
    return 1.0 - done.mean(axis=1)
