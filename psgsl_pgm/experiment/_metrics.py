"""The paper's metrics (Sec. "Validation"), the calibration of the declared credible regions, and confidence
intervals over runs (a mean's, a success rate's)."""

from __future__ import annotations

import numpy as np
from scipy import stats

from .._shared._validate import (
    as_float_array,
    check_nonnegative,
    check_sums,
    describe,
    real_number,
    real_pair,
    unit_interval,
)

__all__ = ["CALIBRATION_POINTS", "calibration_summary", "credible_region", "error_and_spread", "hpd_level", "mean_ci",
           "at_fractions", "wilson_interval"]


def error_and_spread(posteriors, centres, truth):
    """Error ‖E[s] − s_true‖ and spread √E‖s − E[s]‖² of source distributions over grid cells.

    Parameters
    ----------
    posteriors : (..., H, W) ndarray
        Distributions over the cells (each sums to 1).
    centres : (H, W, 2) ndarray
        Cell centres (x, y), metres.
    truth : (2,) array_like
        True source position, metres.

    Returns
    -------
    error, spread : (...) ndarray
        Metres. The spread is the paper's "standard deviation of the distribution" (its error bars): the root
        of the trace of the covariance of s.

    Raises
    ------
    ValueError
        ``posteriors`` are not non-negative distributions over the (H, W) cells, ``centres`` are not (H, W, 2)
        finite centres, ``truth`` is not a finite (x, y), or the result exceeds the float64 range.

    Examples
    --------
    >>> import numpy as np
    >>> c = np.stack(np.meshgrid([0.5, 1.5], [0.5], indexing="xy"), axis=-1)   # two cells on a row
    >>> e, s = error_and_spread(np.array([[0.5, 0.5]]), c, (0.5, 0.5))
    >>> float(e), float(s)
    (0.5, 0.5)
    """
    p = as_float_array(posteriors, "posteriors", dtype=np.float64, min_ndim=2)
    c = as_float_array(centres, "centres", dtype=np.float64, ndim=3)
    if c.shape[-1] != 2 or c.shape[:2] != p.shape[-2:]:
        raise ValueError(f"centres must be (H, W, 2) cell centres for posteriors over (H, W) = {p.shape[-2:]}, got "
                         f"{describe(c)}")
    if c.size == 0 or not np.isfinite(c).all():
        raise ValueError(f"centres must be non-empty and finite, got {describe(c)}")
    check_nonnegative(p, "posteriors")
    check_sums(p.reshape(p.shape[:-2] + (-1,)).sum(axis=-1), "posteriors", p.dtype, over="each over its (H, W) cells")
    truth = real_pair(truth, "truth", "an (x, y)", "metres")
    error, spread = _error_and_spread(p.reshape(p.shape[:-2] + (-1,)), c.reshape(-1, 2), truth)
    if not (np.isfinite(error).all() and np.isfinite(spread).all()):
        raise ValueError(f"centres and truth: the error or the spread exceeds the float64 range (coordinates up to "
                         f"{max(np.abs(c).max(), np.abs(truth).max()):.3g} m)")
    return error, spread


def _error_and_spread(flat, xy, truth):
    """:func:`error_and_spread` of checked arguments: ``flat`` (..., n) distributions over the n cells of
    centres ``xy`` (n, 2), ``truth`` (2,) float64 (not finite when the result exceeds float64)."""

    # numpy's pairwise sums along the cells, not the BLAS: a threaded GEMV splits its sums by the thread count,
    # which moved the spread by ~4e-15 m between a grid's one-thread workers and a run in the main process
    def moments(xy, truth):
        x, y = np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1])
        mx, my = (flat * x).sum(axis=-1), (flat * y).sum(axis=-1)  # E[s] = (E[x], E[y])
        d = (x - mx[..., None]) ** 2
        d += (y - my[..., None]) ** 2  # ‖s − E[s]‖² per cell
        d *= flat
        var = d.sum(axis=-1)  # trace Cov(s) = E‖s − E[s]‖² (centred: no cancellation)
        error = np.hypot(mx - truth[0], my - truth[1])
        return error, np.sqrt(var)

    return _scale_free(moments, (xy, truth), lambda: max(np.abs(xy).max(), np.abs(truth).max()))


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

    Raises
    ------
    ValueError
        ``mass`` is not in (0, 1), or ``posterior`` is not a distribution (finite, non-negative, summing to 1).

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
    ranked = np.sort(flat[flat > 0])[::-1]  # the values in decreasing order (zero cells add nothing to the sums)
    csum = np.cumsum(ranked)
    k = int(np.searchsorted(csum, mass * csum[-1] * (1 - 1e-12))) + 1  # first prefix reaching the mass
    # the k most probable cells, ties with the k-th value taken in cell order: a sort of the values, not of the
    # cells (a stable arg-sort is ten times slower, and the region is the same)
    threshold = ranked[k - 1]
    region = flat > threshold
    tied = np.flatnonzero(flat == threshold)
    region[tied[: k - int(np.count_nonzero(region))]] = True
    return region.reshape(p.shape)


def hpd_level(posterior, cell) -> float:
    """HPD level of a cell: the smallest credible mass whose highest-density region contains it.

    The highest-density region of mass α is {c : p_c ≥ k} with the largest threshold k that reaches α; the
    smallest such region holding ``cell`` is {c : p_c ≥ p_cell}, so the level is Σ_{c: p_c ≥ p_cell} p_c (over
    the total mass). Cells *tied* with ``cell`` count in full — a region holds a cell only with every cell as
    probable, so a cell of a flat posterior over m cells has level 1, not 1/m — and a tie is equality up to
    rounding: abs(p_c − p_cell) ≤ max(1e-12, 8 ε) p_cell, ε the machine epsilon of the posterior's dtype (cells
    equal in exact arithmetic differ in their last bits after the posterior's products and sums). A calibrated
    posterior puts the true source at a level that is about uniform on [0, 1] over runs (median ½); an
    overconfident one pushes it towards 1.

    The :func:`credible_region` of mass α (the fewest cells reaching α) holds ``cell`` whenever its level is
    ≤ α, and, the region being discrete, also for α in (level − p_cell, level) (it then ends with the cells
    as probable as ``cell``).

    Parameters
    ----------
    posterior : (...) array_like
        A distribution over cells.
    cell : int
        Flat (C-order) index of the cell.

    Raises
    ------
    ValueError
        ``cell`` is not a flat index of ``posterior``, or ``posterior`` is not finite and non-negative with a
        positive total.

    Examples
    --------
    >>> hpd_level([0.5, 0.125, 0.25, 0.125], 2), hpd_level([0.5, 0.125, 0.25, 0.125], 1)
    (0.75, 1.0)
    """
    arr = np.asarray(posterior)
    eps = np.finfo(arr.dtype).eps if arr.dtype.kind == "f" else np.finfo(np.float64).eps
    p = arr.astype(np.float64).ravel()
    cell = int(cell)
    if not 0 <= cell < p.size:
        raise ValueError(f"cell must be a flat index in [0, {p.size}), got {cell}")
    total = p.sum()
    if not (np.isfinite(p).all() and (p >= 0).all() and total > 0):
        raise ValueError("posterior must be a distribution (finite, >= 0, positive total)")
    floor = p[cell] * (1.0 - max(1e-12, 8.0 * float(eps)))
    return float(min(1.0, p[p >= floor].sum() / total))


#: Fractions of a run at which the coverage of the credible region is reported (summary key -> fraction).
CALIBRATION_POINTS = {"quarter": 0.25, "half": 0.5, "three_quarters": 0.75, "final": 1.0}


def at_fractions(time, values, fractions) -> np.ndarray:
    """``values`` in effect at the fractions f of a run: the value of the last step j with time[j] ≤ f·time[-1].

    A posterior holds from its stop until the next, so the state "at a quarter of the run" is the last one
    recorded by then (f = 1: the final step).

    Parameters
    ----------
    time : (n + 1,) array_like
        Non-decreasing times of the steps, s (step 0 at 0).
    values : (n + 1, ...) array_like
    fractions : (f,) array_like
        In [0, 1].

    Returns
    -------
    (f, ...) ndarray
    """
    t = np.asarray(time, dtype=np.float64)
    v = np.asarray(values)
    f = np.asarray(fractions, dtype=np.float64)
    if t.ndim != 1 or t.size == 0 or v.shape[:1] != t.shape:
        raise ValueError(f"time must be (n + 1,) and values (n + 1, ...), got {describe(t)} and {describe(v)}")
    j = np.searchsorted(t, f * t[-1] * (1 + 1e-12), side="right") - 1
    return v[np.clip(j, 0, t.size - 1)]


def calibration_summary(runs, *, variant=None) -> dict:
    """Calibration of the 90 % credible regions over runs (each with per-step ``time``, ``region_hit``,
    ``region_area`` and ``hpd_level``; ``variant`` indexes their last axis when they hold several variants).

    Returns
    -------
    dict
        ``{"coverage90": {"quarter", "half", "three_quarters", "final"}`` — the fraction of runs whose region
        contains the true source's cell at ¼, ½, ¾ of the run and at its end (:func:`at_fractions`);
        ``"region_area90"``: the region's area at the end, m², ``{"mean", "ci95"}`` (Student t over runs, cut at
        0); ``"hpd_level"``: the true cell's HPD level at the end, ``{"median", "mean"}``}.
    """
    def pick(run, name):
        a = np.asarray(getattr(run, name))
        return a if variant is None else a[:, variant]

    fr = list(CALIBRATION_POINTS.values())
    hits = np.array([at_fractions(r.time, pick(r, "region_hit"), fr) for r in runs], dtype=bool)  # (runs, 4)
    area = [float(pick(r, "region_area")[-1]) for r in runs]
    level = np.array([float(pick(r, "hpd_level")[-1]) for r in runs])
    return {
        "coverage90": {k: float(hits[:, i].mean()) for i, k in enumerate(CALIBRATION_POINTS)},
        "region_area90": mean_ci(area, lower=0.0),
        "hpd_level": {"median": float(np.median(level)), "mean": float(level.mean())},
    }


def mean_ci(values, *, level: float = 0.95, lower: float | None = None) -> dict:
    """Mean and Student-t confidence interval of the mean over runs (axis 0).

    Returns ``{"mean": m, "ci95": [lo, hi]}`` (floats for 1-D input). A single run has no interval:
    ``ci95`` is then ``[nan, nan]``, and the caller reports the number of runs beside it.

    ``lower`` is a bound the quantity cannot cross (0 for an error or a spread, which are distances): the
    interval is then the t-interval m ± t·s/√n intersected with [lower, ∞). The intersection keeps the
    coverage — the true mean of a quantity ≥ lower lies in [lower, ∞), so whenever the t-interval contains
    it, so does the intersection — and a reader is never shown an impossible negative error. (With three
    runs the t-interval of a mean error of 2 m with s = 1.7 m reaches below zero; the cut only says "≥ 0".)

    Parameters
    ----------
    values : (n, ...) array_like of float
        One value (or array of values) per run on axis 0; finite.
    level : float, default 0.95, keyword-only
        The confidence level, in (0, 1) (the key stays ``"ci95"``).
    lower : float, optional, keyword-only
        A bound the quantity cannot cross; the interval is cut there. None: no cut.

    Returns
    -------
    dict
        ``{"mean": m, "ci95": [lo, hi]}``; floats for 1-D ``values``, lists of the trailing shape otherwise.

    Raises
    ------
    TypeError
        ``level`` or ``lower`` is not a real number.
    ValueError
        ``values`` holds no run or a value that is not finite, ``level`` is outside (0, 1), or the interval
        exceeds the float64 range.

    Examples
    --------
    >>> r = mean_ci([1.0, 2.0, 3.0])                  # t(0.975, 2) = 4.303, s.e. = 1/√3
    >>> r["mean"], [round(x, 3) for x in r["ci95"]]
    (2.0, [-0.484, 4.484])
    >>> [round(x, 3) for x in mean_ci([1.0, 2.0, 3.0], lower=0.0)["ci95"]]
    [0.0, 4.484]
    """
    v = as_float_array(values, "values", dtype=np.float64, min_ndim=1)
    if v.shape[0] == 0 or not np.isfinite(v).all():
        raise ValueError(f"values must hold at least one run of finite numbers on axis 0, got {describe(v)}")
    level = unit_interval(level, "level", low_open=True, high_open=True)
    lower = None if lower is None else real_number(lower, "lower")
    n = v.shape[0]
    if n < 2:
        m = v.mean(axis=0)
        lo = hi = np.full_like(m, np.nan)
    else:
        t = stats.t.ppf(0.5 + level / 2, n - 1)

        def interval(v):
            m = v.mean(axis=0)
            half = t * v.std(axis=0, ddof=1) / np.sqrt(n)
            return m, m - half, m + half

        m, lo, hi = _scale_free(interval, (v,), lambda: np.abs(v).max(axis=0))  # per column: columns are apart
        if not (np.isfinite(m).all() and np.isfinite(lo).all() and np.isfinite(hi).all()):
            raise ValueError(f"values: the mean or its confidence interval exceeds the float64 range (values up to "
                             f"{np.abs(v).max():.3g})")
    if lower is not None:
        lo = np.where(np.isnan(lo), lo, np.maximum(lo, float(lower)))
    if np.ndim(m) == 0:
        return {"mean": float(m), "ci95": [float(lo), float(hi)]}
    return {"mean": m.tolist(), "ci95": [lo.tolist(), hi.tolist()]}


def _scale_free(compute, arrays, scale):
    """``compute(*arrays)`` for outputs of degree 1 in the arrays (means, distances, spreads), safe from overflow.

    Ordinary inputs take the direct path, the same arithmetic bit for bit. Where an intermediate square or sum
    overflows (numbers near 1e154 and beyond) those outputs are recomputed on the arrays divided by ``scale()``
    (their magnitude, broadcasting against the arrays and the outputs) and multiplied back, the others kept as
    they are; what is still not finite then lies beyond float64, and the caller refuses it.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        out = compute(*arrays)
        if all(np.isfinite(o).all() for o in out):
            return out
        s = scale()
        s = np.where(s > 0, s, 1.0)
        again = compute(*(a / s for a in arrays))
        ok = np.logical_and.reduce([np.isfinite(o) for o in out])
        return tuple(np.where(ok, o, r * s)[()] for o, r in zip(out, again))


def _wilson(p: float, n: float, level: float) -> list:
    """Wilson score interval of a proportion ``p`` observed on ``n`` (possibly effective, non-integer) trials."""
    z = stats.norm.ppf(0.5 + level / 2)
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    lo = 0.0 if p == 0 else max(0.0, centre - half)
    hi = 1.0 if p == 1 else min(1.0, centre + half)
    return [float(lo), float(hi)]


def wilson_interval(successes: int, n: int, *, level: float = 0.95) -> list:
    """Wilson score interval of a binomial proportion, [lo, hi].

    Never a point: at 0 or n successes it is [0, hi] or [lo, 1] with hi > 0, lo < 1 (the same interval as
    ``scipy.stats.binomtest(successes, n).proportion_ci(method="wilson")``; Wilson, *JASA* 22, 209-212, 1927).

    Parameters
    ----------
    successes : int
        Number of successes, 0 ≤ ``successes`` ≤ ``n``.
    n : int
        Number of trials; below 1 there is no interval.
    level : float, keyword-only
        Confidence level, in (0, 1).

    Returns
    -------
    list of float
        ``[lo, hi]``, within [0, 1]; ``[nan, nan]`` when ``n`` < 1.

    Examples
    --------
    >>> [round(x, 4) for x in wilson_interval(8, 10)]
    [0.4902, 0.9433]
    >>> [round(x, 4) for x in wilson_interval(10, 10)]
    [0.7225, 1.0]
    """
    if n < 1:
        return [float("nan"), float("nan")]
    return _wilson(successes / n, n, level)
