"""Statistics of censored times to find: Kaplan–Meier survival with pointwise bands, the restricted mean survival
time, paired comparisons on the same seeds, and Holm's correction.

A closed-loop run that does not find the source within the budget τ is *censored* at τ: its time to find is only
known to exceed τ. Means and Student-t intervals of the capped times treat τ as an observed time and describe
nothing a reader can use (they run past the budget, and shrink to zero width when every run hits it). This module
summarises such times the way survival analysis does:

* :func:`kaplan_meier` — S(t) = P(not found by t), the product-limit estimator, with 95 % pointwise bands from
  Greenwood's variance on the log(−log S) scale (the "exponential Greenwood" interval: it stays inside [0, 1]; the
  default of the ``lifelines`` package, against which the tests check it).
* :func:`rmst` — the restricted mean survival time RMST(τ) = ∫₀^τ S(t) dt, the expected time to find with a
  not-found run counted at τ, and its 95 % normal interval from the Greenwood-type variance of the area (Klein &
  Moeschberger, *Survival Analysis*, 2nd ed., Sec. 4.5). With only administrative censoring at τ — every run
  observed until it finds the source or the budget ends, as in ``psgsl search`` — RMST(τ) equals the sample mean of
  min(T, τ), and this variance equals the plug-in variance of min(T, τ) divided by n (tested).
* :func:`paired_comparison` — two policies or variants run on the same seeds: the RMST difference Σ(min(T_a, τ) −
  min(T_b, τ))/n, a percentile bootstrap interval over seeds (seeded), and the two-sided p-value of the paired
  sign-flip permutation test (exact enumeration of the 2^n sign vectors for n ≤ :data:`EXACT_MAX`, a seeded Monte
  Carlo sample otherwise). Under the null hypothesis that the two conditions are exchangeable within a seed, each
  difference is as likely positive as negative, whatever the distribution of the capped times.
* :func:`holm` — Holm's step-down adjustment of a table's p-values (family-wise error ≤ α).
* :func:`nested_bootstrap` — a percentile interval for runs nested in groups (episodes in houses): resample the
  groups with replacement, then the runs within each drawn group; any statistic of one or several paired arms
  (an RMST, an RMST ratio).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from .._shared._validate import as_float_array, describe, index, positive, unit_interval

__all__ = ["EXACT_MAX", "bootstrap_mean_ci", "holm", "kaplan_meier", "km_median", "nested_bootstrap",
           "nested_indices", "paired_comparison", "rmst", "sign_flip_pvalue"]

#: Up to this many pairs the sign-flip test enumerates all 2^n sign vectors (65 536 for n = 16).
EXACT_MAX = 16


def _times_events(times, found):
    t = as_float_array(times, "times", dtype=np.float64, ndim=1)
    if t.size == 0 or not np.isfinite(t).all() or (t < 0).any():
        raise ValueError(f"times must be a non-empty 1-D array of finite times >= 0 (s), got {describe(t)}")
    e = np.asarray(found)
    if e.shape != t.shape or e.dtype != bool:
        raise ValueError(f"found must be a bool array of the times' shape {t.shape}, got {describe(e)}")
    return t, e


def _table(t, e):
    """Distinct observed times u (ascending), numbers at risk n(u) and events d(u) there."""
    u, inv = np.unique(t, return_inverse=True)
    d = np.bincount(inv, weights=e, minlength=u.size)
    c = np.bincount(inv, minlength=u.size)
    at_risk = t.size - np.concatenate(([0], np.cumsum(c)[:-1]))
    return u, at_risk.astype(np.float64), d


def kaplan_meier(times, found, *, level: float = 0.95) -> dict:
    """Kaplan–Meier estimate of S(t) = P(T > t) with pointwise log(−log) Greenwood bands.

    Parameters
    ----------
    times : (n,) array_like
        Time of each run, s: the time to find when ``found``, else the time at which it was censored (the budget).
    found : (n,) array_like of bool
        Whether the event (found) was observed.
    level : float, keyword-only
        Confidence level of the bands.

    Returns
    -------
    dict
        ``{"t", "survival", "lower", "upper"}``, lists of equal length: a right-continuous step function, S(t) =
        ``survival[i]`` for ``t[i] <= t < t[i + 1]``. ``t`` starts at 0 and holds every distinct observed time
        (events and censorings), as ``lifelines.KaplanMeierFitter.survival_function_`` does. The band at t is
        S^exp(∓z σ/ln S) with σ² = Σ_{u ≤ t} d/(n(n − d)) (Greenwood); [1, 1] where S = 1 and [0, 0] where S = 0.

    Raises
    ------
    ValueError
        ``times`` is not a non-empty 1-D array of finite times >= 0, ``found`` is not a bool array of its shape, or
        ``level`` is not in (0, 1).

    Examples
    --------
    >>> km = kaplan_meier([10.0, 20.0, 20.0, 30.0], [True, True, False, False])
    >>> km["t"], km["survival"]
    ([0.0, 10.0, 20.0, 30.0], [1.0, 0.75, 0.5, 0.5])
    """
    t, e = _times_events(times, found)
    level = unit_interval(level, "level", low_open=True, high_open=True)
    u, n, d = _table(t, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.cumprod(1.0 - d / n)
        green = np.cumsum(np.where(n > d, d / (n * (n - d)), 0.0))
        z = stats.norm.ppf(0.5 + level / 2)
        v = np.log(s)
        lower = np.exp(-np.exp(np.log(-v) - z * np.sqrt(green) / v))
        upper = np.exp(-np.exp(np.log(-v) + z * np.sqrt(green) / v))
    lower = np.where(s == 1.0, 1.0, np.where(s == 0.0, 0.0, lower))
    upper = np.where(s == 1.0, 1.0, np.where(s == 0.0, 0.0, upper))
    if u[0] > 0:
        u, s, lower, upper = (np.concatenate(([a], b)) for a, b in ((0.0, u), (1.0, s), (1.0, lower), (1.0, upper)))
    return {"t": u.tolist(), "survival": s.tolist(), "lower": lower.tolist(), "upper": upper.tolist()}


def km_median(km: dict):
    """Median time of a :func:`kaplan_meier` curve: the first time with S(t) ≤ ½ (None if S stays above ½)."""
    s = np.asarray(km["survival"])
    below = np.flatnonzero(s <= 0.5)
    return float(km["t"][below[0]]) if below.size else None


def rmst(times, found, tau, *, level: float = 0.95) -> dict:
    """Restricted mean survival time RMST(τ) = ∫₀^τ S(t) dt of the Kaplan–Meier curve, with a normal interval.

    Parameters
    ----------
    times, found : (n,) array_like
        See :func:`kaplan_meier`.
    tau : float
        Upper limit τ, s (the time budget).
    level : float, keyword-only

    Returns
    -------
    dict
        ``{"value", "ci95", "se", "tau"}``. The variance is Greenwood's for the area,
        Var = Σ_{events u < τ} A(u)² d/(n(n − d)) with A(u) = ∫_u^τ S(t) dt (terms with n = d have A = 0); the
        interval value ± z·se is intersected with [0, τ], where RMST(τ) lies (this keeps its coverage). With no
        event before τ the variance is 0 and the interval a point: read it beside the success rate.

    Raises
    ------
    ValueError
        ``times`` or ``found`` as for :func:`kaplan_meier`, ``tau`` is not a positive number, or ``level`` is not in
        (0, 1).

    Examples
    --------
    >>> r = rmst([10.0, 30.0, 100.0, 100.0], [True, True, False, False], 100.0)   # mean of min(T, τ)
    >>> r["value"]
    60.0
    """
    t, e = _times_events(times, found)
    tau = positive(tau, "tau", "seconds")
    level = unit_interval(level, "level", low_open=True, high_open=True)
    u, n, d = _table(t, e)
    s = np.cumprod(1.0 - d / n)  # S on [u_i, u_{i+1})
    knots = np.concatenate(([0.0], u[u < tau], [tau]))
    s_left = np.concatenate(([1.0], s[u < tau]))  # S on [knots_j, knots_{j+1})
    pieces = s_left * np.diff(knots)
    value = float(pieces.sum())
    # A(u_i) for the event times u_i < τ: the area to the right of u_i
    tail = np.cumsum(pieces[::-1])[::-1]  # tail[j] = ∫_{knots_j}^τ S
    inside = u < tau
    a = tail[1:][: int(inside.sum())]
    ni, di = n[inside], d[inside]
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = np.where(ni > di, a * a * di / (ni * (ni - di)), 0.0)
    se = float(np.sqrt(terms.sum()))
    z = stats.norm.ppf(0.5 + level / 2)
    lo, hi = max(0.0, value - z * se), min(tau, value + z * se)
    return {"value": value, "ci95": [lo, hi], "se": se, "tau": tau}


def holm(pvalues) -> np.ndarray:
    """Holm's step-down adjusted p-values: p̃_(i) = max_{j ≤ i} min(1, (m − j + 1) p_(j)) in ascending order.

    Rejecting where p̃ ≤ α keeps the family-wise error rate of the m tests ≤ α under any dependence (Holm,
    *Scand. J. Statist.* 6, 65-70, 1979).

    Parameters
    ----------
    pvalues : (m,) array_like of float
        The m tests' p-values, each in [0, 1], in any order.

    Returns
    -------
    (m,) ndarray of float64
        The adjusted p-values, in the order of ``pvalues``; each ≥ its raw p-value and ≤ 1.

    Raises
    ------
    TypeError, ValueError
        ``pvalues`` not a 1-D array of numbers, or a value outside [0, 1] or not finite.

    Examples
    --------
    >>> holm([0.01, 0.04, 0.03]).tolist()
    [0.03, 0.06, 0.06]
    """
    p = as_float_array(pvalues, "pvalues", dtype=np.float64, ndim=1)
    if not (np.isfinite(p).all() and ((p >= 0) & (p <= 1)).all()):
        raise ValueError(f"pvalues must be probabilities in [0, 1], got {describe(p)}")
    m = p.size
    order = np.argsort(p, kind="stable")
    adj = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out = np.empty(m)
    out[order] = adj
    return out


def sign_flip_pvalue(differences, *, n_resamples: int = 100_000, seed: int = 0) -> dict:
    """Two-sided paired sign-flip permutation test of "the mean difference is 0".

    The statistic is abs(Σ dᵢ); under the null hypothesis each dᵢ is as likely as −dᵢ. For n ≤ :data:`EXACT_MAX`
    all 2^n sign vectors are enumerated and p = #{abs(Σ sᵢdᵢ) ≥ abs(Σ dᵢ)} / 2^n (exact); otherwise ``n_resamples``
    sign vectors are drawn with ``numpy.random.default_rng(seed)`` and p = (1 + #) / (1 + n_resamples).
    Sums equal up to rounding (abs(Σ sᵢdᵢ) within 1e-12 relative of the observed) count as ≥.

    Parameters
    ----------
    differences : (n,) array_like of float
        dᵢ, the paired differences (e.g. A − B over seeds); finite, n ≥ 1.
    n_resamples : int, default 100_000, keyword-only
        Sign vectors drawn when n > :data:`EXACT_MAX` (≥ 1); unused for the exact test.
    seed : int, default 0, keyword-only
        Seed (≥ 0) of the generator drawing them.

    Returns
    -------
    dict
        ``{"p_value", "method"}`` (``"exact"`` or ``"monte carlo (N resamples, seed S)"``).

    Raises
    ------
    TypeError
        ``differences`` is not a real numeric array, or ``n_resamples`` or ``seed`` is not an int.
    ValueError
        ``differences`` is not 1-D, is empty or holds a value that is not finite; ``n_resamples`` < 1 or
        ``seed`` < 0.

    Examples
    --------
    >>> sign_flip_pvalue([1.0, 2.0, 3.0])["p_value"]   # only (+, +, +) and (−, −, −) reach |6|: 2/8
    0.25
    """
    d = as_float_array(differences, "differences", dtype=np.float64, ndim=1)
    if d.size == 0 or not np.isfinite(d).all():
        raise ValueError(f"differences must be a non-empty 1-D array of finite numbers, got {describe(d)}")
    n_resamples = index(n_resamples, "n_resamples", minimum=1)
    seed = index(seed, "seed")
    n = d.size
    obs = abs(d.sum())
    tol = 1e-12 * max(np.abs(d).sum(), np.finfo(float).tiny)
    if n <= EXACT_MAX:
        bits = (np.arange(2**n)[:, None] >> np.arange(n)[None, :]) & 1
        sums = (1.0 - 2.0 * bits) @ d
        return {"p_value": float(np.mean(np.abs(sums) >= obs - tol)), "method": "exact"}
    rng = np.random.default_rng(seed)
    count = 0
    for start in range(0, n_resamples, 10_000):  # in blocks: memory stays small for many seeds
        k = min(10_000, n_resamples - start)
        signs = rng.choice(np.array([-1.0, 1.0]), size=(k, n))
        count += int(np.count_nonzero(np.abs(signs @ d) >= obs - tol))
    return {"p_value": (1 + count) / (1 + n_resamples),
            "method": f"monte carlo ({n_resamples} resamples, seed {seed})"}


def bootstrap_mean_ci(values, *, level: float = 0.95, n_resamples: int = 10_000, seed: int = 0) -> list:
    """Percentile bootstrap interval of the mean: resample the n values with replacement ``n_resamples`` times
    (``numpy.random.default_rng(seed)``), take the (1 ± level)/2 quantiles of the resampled means.

    Examples
    --------
    >>> bootstrap_mean_ci([5.0, 5.0, 5.0])
    [5.0, 5.0]
    """
    v = as_float_array(values, "values", dtype=np.float64, ndim=1)
    if v.size == 0 or not np.isfinite(v).all():
        raise ValueError(f"values must be a non-empty 1-D array of finite numbers, got {describe(v)}")
    level = unit_interval(level, "level", low_open=True, high_open=True)
    n_resamples = index(n_resamples, "n_resamples", minimum=1)
    rng = np.random.default_rng(index(seed, "seed"))
    means = v[rng.integers(0, v.size, size=(n_resamples, v.size))].mean(axis=1)
    lo, hi = np.quantile(means, [0.5 - level / 2, 0.5 + level / 2])
    return [float(lo), float(hi)]


def paired_comparison(times_a, times_b, tau, *, level: float = 0.95, n_resamples: int = 10_000,
                      seed: int = 0) -> dict:
    """RMST(τ) of condition a minus that of condition b, run on the same seeds (pair i = seed i).

    Parameters
    ----------
    times_a, times_b : (n,) array_like
        Times to find, s, each run's time when found, τ when not (administrative censoring at the budget).
    tau : float
        The budget τ, s; every time must be ≤ τ.
    level, n_resamples, seed : keyword-only
        Of the bootstrap interval (:func:`bootstrap_mean_ci`); ``seed`` also seeds a Monte Carlo sign-flip test.

    Returns
    -------
    dict
        ``{"value", "ci95", "p_value", "n", "test", "interval"}``: value = mean(min(T_a, τ) − min(T_b, τ)) =
        RMST_a(τ) − RMST_b(τ) (negative: a finds the source sooner), its percentile bootstrap interval over seeds,
        and the sign-flip p-value (:func:`sign_flip_pvalue`).

    Raises
    ------
    ValueError
        ``tau`` is not a positive number, the times are not paired (same non-empty length), or a time lies
        outside [0, ``tau``].

    Examples
    --------
    Three seeds, a 120-s budget (120: not found); condition a finds the source sooner on two of them:

    >>> from psgsl_pgm.search import paired_comparison
    >>> r = paired_comparison([10.0, 50.0, 120.0], [30.0, 80.0, 120.0], 120.0, n_resamples=500)
    >>> round(r["value"], 2), r["p_value"], r["n"]
    (-16.67, 0.5, 3)
    """
    tau = positive(tau, "tau", "seconds")
    a = as_float_array(times_a, "times_a", dtype=np.float64, ndim=1)
    b = as_float_array(times_b, "times_b", dtype=np.float64, ndim=1)
    if a.shape != b.shape or a.size == 0:
        raise ValueError(f"times_a and times_b must be paired (same non-empty length), got {a.shape} and {b.shape}")
    for name, x in (("times_a", a), ("times_b", b)):
        if not (np.isfinite(x).all() and (x >= 0).all() and (x <= tau).all()):
            raise ValueError(f"{name} must be times in [0, tau = {tau:g}] s (not found: tau), got {describe(x)}")
    d = np.minimum(a, tau) - np.minimum(b, tau)
    test = sign_flip_pvalue(d, n_resamples=max(n_resamples, 1), seed=seed)
    return {"value": float(d.mean()), "ci95": bootstrap_mean_ci(d, level=level, n_resamples=n_resamples, seed=seed),
            "p_value": test["p_value"], "n": int(d.size), "test": f"paired sign-flip permutation, {test['method']}",
            "interval": f"percentile bootstrap over seeds, {n_resamples} resamples, seed {seed}"}


def nested_indices(groups, rng) -> np.ndarray:
    """One two-stage bootstrap resample of runs nested in ``groups``: indices into the runs.

    With G distinct groups of sizes n_g: draw G groups uniformly with replacement, then for each drawn group n_g
    of its runs uniformly with replacement (the hierarchical bootstrap of Davison & Hinkley, *Bootstrap Methods
    and their Application*, 1997, Sec. 3.8, resampling at both stages).

    Parameters
    ----------
    groups : (n,) array_like
        The group label of each run (any hashable values; runs of a group need not be adjacent).
    rng : numpy.random.Generator

    Returns
    -------
    (m,) ndarray of int
        m = Σ over the drawn groups of their sizes.
    """
    labels = np.asarray(groups)
    _, inv = np.unique(labels, return_inverse=True)
    order = np.argsort(inv, kind="stable")  # runs sorted by group
    sizes = np.bincount(inv)
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    drawn = rng.integers(0, sizes.size, size=sizes.size)
    counts = sizes[drawn]
    local = np.floor(rng.random(int(counts.sum())) * np.repeat(counts, counts)).astype(np.int64)
    return order[np.repeat(starts[drawn], counts) + local]


def nested_bootstrap(values, groups, statistic=None, *, level: float = 0.95, n_resamples: int = 4000,
                     seed: int = 0) -> dict:
    """Percentile interval of a statistic of runs nested in groups (``nested_indices``).

    Parameters
    ----------
    values : (n,) or (a, n) array_like
        One value per run (e.g. the capped time min(T, τ)), or ``a`` paired arms on the same runs (the same
        episode under ``a`` policies): resampling keeps the pairs.
    groups : (n,) array_like
        The group (house) of each run.
    statistic : callable, optional
        ``statistic(v)`` of an array shaped like ``values`` with the runs' axis resampled -> float; default (one
        arm only) the mean over the runs, the RMST of capped times.
    level : float, keyword-only
    n_resamples : int, keyword-only
    seed : int, keyword-only
        Seeds ``numpy.random.default_rng``.

    Returns
    -------
    dict
        ``{"value", "ci95", "n", "groups", "interval"}``: the statistic of the data, the (1 ± level)/2 quantiles
        of its resampled values, the numbers of runs and groups, and how the interval was made. A statistic that
        is not finite on some resample (a ratio over zero) is left out of the quantiles; all of them: NaN bounds.

    Raises
    ------
    ValueError
        ``values`` is not a non-empty (n,) or (arms, n) array of finite numbers, ``groups`` does not give one group
        per run, ``level`` is not in (0, 1), ``n_resamples`` is below 1, or several arms come without
        ``statistic``.
    TypeError
        ``statistic`` is not callable, or ``n_resamples`` or ``seed`` is not an integer.

    Examples
    --------
    >>> r = nested_bootstrap([5.0, 5.0, 5.0, 5.0], [0, 0, 1, 1])
    >>> r["value"], r["ci95"]
    (5.0, [5.0, 5.0])
    """
    v = as_float_array(values, "values", dtype=np.float64)
    if v.ndim not in (1, 2) or v.shape[-1] == 0 or not np.isfinite(v).all():
        raise ValueError(f"values must be a non-empty (n,) or (arms, n) array of finite numbers, got {describe(v)}")
    g = np.asarray(groups)
    if g.shape != (v.shape[-1],):
        raise ValueError(f"groups must give one group per run, shape ({v.shape[-1]},), got shape {g.shape}")
    level = unit_interval(level, "level", low_open=True, high_open=True)
    n_resamples = index(n_resamples, "n_resamples", minimum=1)
    if statistic is None:
        if v.ndim != 1:
            raise ValueError("statistic is required for several arms (values of shape (arms, n))")
        statistic = np.mean
    elif not callable(statistic):
        raise TypeError(f"statistic must be callable, got {type(statistic).__name__}")
    rng = np.random.default_rng(index(seed, "seed"))
    stats_ = np.array([float(statistic(v[..., nested_indices(g, rng)])) for _ in range(n_resamples)])
    ok = stats_[np.isfinite(stats_)]
    lo, hi = np.quantile(ok, [0.5 - level / 2, 0.5 + level / 2]) if ok.size else (np.nan, np.nan)
    return {"value": float(statistic(v)), "ci95": [float(lo), float(hi)], "n": int(v.shape[-1]),
            "groups": int(np.unique(g).size),
            "interval": f"nested percentile bootstrap (groups, then runs within them), {n_resamples} resamples, "
                        f"seed {seed}"}
