"""The paper's metrics (Sec. "Validation") and confidence intervals over runs."""

from __future__ import annotations

import numpy as np
from scipy import stats

from .._validate import (as_float_array, check_nonnegative, check_sums, describe, real_number, real_pair,
                         unit_interval)

__all__ = ["error_and_spread", "mean_ci"]


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
    flat = p.reshape(p.shape[:-2] + (-1,))

    def moments(xy, truth):
        mean = flat @ xy  # E[s]
        second = flat @ np.einsum("ij,ij->i", xy, xy)  # E‖s‖²
        var = np.maximum(second - np.einsum("...i,...i->...", mean, mean), 0.0)  # trace Cov(s) = E‖s‖² − ‖E[s]‖²
        error = np.linalg.norm(mean - truth, axis=-1)
        return error, np.sqrt(var)

    xy = c.reshape(-1, 2)
    error, spread = _scale_free(moments, (xy, truth), lambda: max(np.abs(xy).max(), np.abs(truth).max()))
    if not (np.isfinite(error).all() and np.isfinite(spread).all()):
        raise ValueError(f"centres and truth: the error or the spread exceeds the float64 range (coordinates up to "
                         f"{max(np.abs(c).max(), np.abs(truth).max()):.3g} m)")
    return error, spread


def mean_ci(values, *, level: float = 0.95, lower: float | None = None) -> dict:
    """Mean and Student-t confidence interval of the mean over runs (axis 0).

    Returns ``{"mean": m, "ci95": [lo, hi]}`` (floats for 1-D input). A single run has no interval:
    ``ci95`` is then ``[nan, nan]``, and the caller reports the number of runs beside it.

    ``lower`` is a bound the quantity cannot cross (0 for an error or a spread, which are distances): the
    interval is then the t-interval m ± t·s/√n intersected with [lower, ∞). The intersection keeps the
    coverage — the true mean of a quantity ≥ lower lies in [lower, ∞), so whenever the t-interval contains
    it, so does the intersection — and a reader is never shown an impossible negative error. (With three
    runs the t-interval of a mean error of 2 m with s = 1.7 m reaches below zero; the cut only says "≥ 0".)

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
