"""Declarations with an honest uncertainty: the credible region and the HPD level of the true source (defined
with the validation experiment's metrics, :mod:`psgsl_pgm.experiment._metrics`, as is the Wilson interval of a
success rate), and the house-clustered Wilson interval. Times to find are censored at the budget; their
statistics are in :mod:`._survival`."""

from __future__ import annotations

import numpy as np

from ..experiment._metrics import _wilson, credible_region, hpd_level, mean_ci, wilson_interval

__all__ = ["clustered_wilson", "credible_region", "declaration_summary", "hpd_level", "paired_difference", "survival",
           "wilson_interval"]


def clustered_wilson(successes, groups, *, level: float = 0.95) -> dict:
    """Wilson interval of a success proportion over runs nested in groups (episodes in houses).

    Episodes of one house share its floor plan, so they are not independent trials. The interval is Wilson's on the
    effective number of trials n_eff = n / D, D the design effect (Kish, *Survey Sampling*, 1965, Sec. 5.4):
    the ratio of the proportion's house-clustered variance, the ratio-estimator (linearisation) variance
    Σ_g (y_g − p̂ m_g)² / n² over the G houses (y_g successes of m_g episodes), to the binomial p̂(1 − p̂)/n.
    D is floored at 1 (houses never make episodes worth more than independent ones). Where it cannot be estimated
    — p̂ = 0 or 1 (no variation to apportion), or a single group (a world file: its episodes are the units) —
    D = 1: the limit of the estimate as failures become rare and isolated (one failing episode in a house gives
    y_g − p̂ m_g ≈ −1, the binomial term). Two checks: one episode per house gives D = 1, the plain Wilson
    interval; houses whose episodes all agree give D = m, the Wilson interval of the G houses.

    Unlike a percentile bootstrap of the proportion, the interval is never a point: at p̂ = 1 it is [lo, 1] with
    lo < 1.

    Parameters
    ----------
    successes : (n,) array_like of bool
        Each run's outcome.
    groups : (n,) array_like
        Each run's group (house) label.
    level : float, keyword-only

    Returns
    -------
    dict
        ``{"value", "ci95", "design_effect", "n_effective", "n", "groups", "interval"}``.

    Examples
    --------
    >>> r = clustered_wilson([True, True, True, True], ["a", "a", "b", "b"])
    >>> r["value"], [round(x, 4) for x in r["ci95"]], r["design_effect"]
    (1.0, [0.5101, 1.0], 1.0)
    """
    y = np.asarray(successes)
    if y.ndim != 1 or y.size == 0 or y.dtype != bool:
        raise ValueError(f"successes must be a non-empty 1-D bool array, got {y.dtype} of shape {y.shape}")
    g = np.asarray(groups)
    if g.shape != y.shape:
        raise ValueError(f"groups must give one group per run, shape {y.shape}, got shape {g.shape}")
    _, inv = np.unique(g, return_inverse=True)
    n, n_groups = y.size, int(inv.max()) + 1
    p = float(y.mean())
    deff = 1.0
    if 0.0 < p < 1.0 and n_groups > 1:
        y_g = np.bincount(inv, weights=y.astype(np.float64))
        m_g = np.bincount(inv).astype(np.float64)
        clustered = float(np.sum((y_g - p * m_g) ** 2)) / (n * n)
        deff = max(1.0, clustered / (p * (1.0 - p) / n))
    n_eff = n / deff
    return {"value": p, "ci95": _wilson(p, n_eff, level), "design_effect": deff, "n_effective": n_eff, "n": int(n),
            "groups": n_groups,
            "interval": "Wilson score interval on the effective sample size n / design effect (house-clustered)"}


def declaration_summary(declared, correct, errors, *, groups=None) -> dict:
    """The declarations of an arm's runs (:mod:`psgsl_pgm.search._declare`).

    Parameters
    ----------
    declared, correct : (n,) array_like of bool
        Each run's declaration, and whether it was right.
    errors : (n,) array_like of float
        m, each declaration's error (NaN where none was made).
    groups : (n,) array_like, optional, keyword-only
        House labels: the success interval is then house-clustered (:func:`clustered_wilson`).

    Returns
    -------
    dict
        ``declared_success`` {value, ci95}: runs with a right declaration, of all runs (Wilson);
        ``declared_error`` {median, q90, n} (m) over the declarations made (None without any);
        ``false_declaration_rate`` {value, ci95, n}: wrong declarations of the declarations made (Wilson; None
        without any); ``declared`` the number of declarations.

    Examples
    --------
    >>> s = declaration_summary([True, True, False], [True, False, False], [0.2, 3.0, float("nan")])
    >>> s["declared_success"]["value"], s["false_declaration_rate"]["value"], s["declared_error"]["median"]
    (0.3333333333333333, 0.5, 1.6)
    """
    declared = np.asarray(declared, dtype=bool)
    correct = np.asarray(correct, dtype=bool) & declared
    errors = np.asarray(errors, dtype=np.float64)[declared]
    n, k = declared.size, int(declared.sum())
    if groups is None:
        success = {"value": float(correct.mean()) if n else float("nan"), "ci95": wilson_interval(int(correct.sum()), n)}
    else:
        c = clustered_wilson(correct, groups)
        success = {"value": c["value"], "ci95": c["ci95"], "design_effect": c["design_effect"]}
    wrong = int(k - correct.sum())
    return {
        "declared": k,
        "declared_success": success,
        "declared_error": ({"median": float(np.median(errors)), "q90": float(np.quantile(errors, 0.9)), "n": k}
                           if k else None),
        "false_declaration_rate": ({"value": wrong / k, "ci95": wilson_interval(wrong, k), "n": k} if k else None),
    }


def paired_difference(a, b, *, level: float = 0.95) -> dict:
    """Mean of a − b over paired runs (same seeds) with its Student-t interval: ``{"mean", "ci95", "n"}``.

    For quantities that are never capped (errors, spreads, areas). Times censored at a budget need
    :func:`psgsl_pgm.search.paired_comparison` (RMST difference, sign-flip test) instead.

    Parameters
    ----------
    a, b : (n,) array_like of float
        The two sides' values, paired by position (run i of ``a`` and of ``b`` share a seed); finite, same shape.
    level : float, default 0.95, keyword-only
        The confidence level, in (0, 1) (the key stays ``"ci95"``).

    Returns
    -------
    dict
        ``{"mean": mean of a − b, "ci95": [lo, hi], "n": number of pairs}`` (:func:`psgsl_pgm.experiment.mean_ci`).

    Raises
    ------
    ValueError
        ``a`` and ``b`` differ in shape, hold no pair or a value that is not finite, or ``level`` is outside (0, 1).
    TypeError
        ``level`` is not a real number.

    Examples
    --------
    >>> d = paired_difference([3.0, 5.0, 4.0], [1.0, 2.0, 3.0])
    >>> d["mean"], [round(x, 3) for x in d["ci95"]], d["n"]
    (2.0, [-0.484, 4.484], 3)
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

    Parameters
    ----------
    times : (n,) array_like of float
        Each run's time to find the source, s (for a run not found: any value; it is not used).
    found : (n,) array_like of bool
        Whether each run found the source.
    grid : (m,) array_like of float
        The times at which the fraction is evaluated, s.

    Returns
    -------
    numpy.ndarray
        (m,) float64: the fraction of the n runs that have not found the source by each time of ``grid``
        (a run found at t counts as found from t on).

    Examples
    --------
    >>> survival([10.0, 30.0, 50.0], [True, True, False], [0.0, 20.0, 40.0]).round(3).tolist()
    [1.0, 0.667, 0.333]
    """
    t = np.asarray(times, dtype=np.float64)
    f = np.asarray(found, dtype=bool)
    g = np.asarray(grid, dtype=np.float64)
    done = f[None, :] & (t[None, :] <= g[:, None])
    return 1.0 - done.mean(axis=1)
