"""Declarations with an honest uncertainty: the credible region and the HPD level of the true source (defined
with the validation experiment's metrics, :mod:`psgsl_pgm.experiment._metrics`), and the Wilson interval of a
success rate. Times to find are censored at the budget; their statistics are in :mod:`._survival`."""

from __future__ import annotations

import numpy as np
from scipy import stats

from ..experiment._metrics import credible_region, hpd_level

__all__ = ["credible_region", "hpd_level", "wilson_interval"]


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
