"""Fusion of posteriors over the same cells: eq. (11) and its general form."""

from __future__ import annotations

import numpy as np
from scipy.special import logsumexp

from .._shared._validate import as_float_array, check_nonnegative, check_sums, describe
from . import _dask_arrays
from ._dask_arrays import is_dask_array

__all__ = ["fuse"]


def fuse(*posteriors, prior=None):
    r"""Combine posteriors over the source cell that used conditionally independent evidence.

    For evidence sets :math:`e_1, \dots, e_m` independent given :math:`S` (e.g. olfaction :math:`g` and
    semantics :math:`z`, Sec. "Separating the Semantic and Olfactory Estimation Processes"), each
    :math:`p(s \mid e_j) \propto p(e_j \mid s)\, p(s)`, so

    .. math:: p(s_c \mid e_1, \dots, e_m) \propto \frac{\prod_j p(s_c \mid e_j)}{p(s_c)^{m-1}}.

    For a uniform prior and :math:`m = 2` this is eq. (11) of the paper:

    .. math:: p(s_c \mid g, z) \propto p(s_c \mid g) \cdot p(s_c \mid z)

    Computed in linear space by compiled passes that also validate the inputs: for two inputs one pass forms
    the normaliser and a second writes the result (no temporary); for more, one pass per input builds the
    product. The cells whose product would leave float64's normal range (below :math:`2^{-1000}`, e.g.
    1e-300 · 1e-300) are recomputed in log space, so the result is exact to round-off for any number of cells
    or inputs and never NaN.

    Parameters
    ----------
    *posteriors : (...) array_like
        Two or more distributions over the same cells (same shape, each sums to 1), all computed under the
        same source prior. One input is returned normalised.
    prior : (...) array_like, optional
        That source prior :math:`p(s)`; uniform when omitted. Must be positive wherever a posterior is.

    Returns
    -------
    p : (...) ndarray
        The fused distribution (float32 only if every input is float32).

    Raises
    ------
    ValueError
        Inputs of different shapes, not distributions, or whose product is zero in every cell — the message
        names a pair of inputs with disjoint support.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import fuse
    >>> fuse([0.5, 0.3, 0.2], [0.2, 0.2, 0.6]).round(4)
    array([0.3571, 0.2143, 0.4286])
    """
    if len(posteriors) == 0:
        raise TypeError("fuse needs at least one posterior, got none")
    if any(is_dask_array(p) for p in (*posteriors, prior)):  # chunked over cells, lazy: psgsl_pgm.core._dask_arrays
        return _dask_arrays.fuse_dask(*posteriors, prior=prior)
    from ..kernels._belief import fuse_finish, fuse_step, fuse_sum, fuse_write  # compiled on first use

    arrays = [as_float_array(p, f"posteriors[{j}]", min_ndim=1) for j, p in enumerate(posteriors)]
    shape = arrays[0].shape
    for j, a in enumerate(arrays):
        if a.shape != shape:
            raise ValueError(f"posteriors[{j}] must have the shape of posteriors[0], {shape}, got {describe(a)}")
    out_dtype = np.float32 if all(a.dtype == np.float32 for a in arrays) else np.float64
    flat = [np.ascontiguousarray(a).reshape(-1) for a in arrays]
    if flat[0].size == 0:
        check_nonnegative(arrays[0], "posteriors[0]")  # names the empty input

    extra = len(arrays) - 1
    if prior is None:
        pr = np.empty(0)
    else:
        pr = as_float_array(prior, "prior", dtype=np.float64)
        if pr.shape != shape:
            raise ValueError(f"prior must have the posteriors' shape {shape}, got {describe(pr)}")
        check_nonnegative(pr, "prior")
        check_sums(pr.sum(), "prior", pr.dtype, over="over all cells")
        pr = np.ascontiguousarray(pr).reshape(-1)

    if len(flat) == 2:
        # eq. (11) in two passes and no temporary: T = Σ_c p(s_c|g) p(s_c|z) / p(s_c)
        # (and the checks of both inputs), then p_c / T written once, in the output's dtype
        st_a, st_b, unsafe, total, zero_support = fuse_sum(flat[0], flat[1], pr, extra)
        _check_inputs(arrays, [st_a, st_b])
        _check_support(zero_support, flat, pr, shape)
        if not unsafe:
            if not total > 0:
                raise ValueError(_conflict_message(arrays))
            out = np.empty(flat[0].size, out_dtype)
            fuse_write(out, flat[0], flat[1], pr, extra, total)
            return out.reshape(shape)

    # Linear space: p_c = Π_j p(s_c|e_j), one pass per input that also checks it (sign, finiteness, sum).
    prod = np.empty(flat[0].size)
    stats = [fuse_step(prod, a, j == 0) for j, a in enumerate(flat)]
    _check_inputs(arrays, stats)
    linear_total, marked, zero_support = fuse_finish(prod, pr, extra)  # ÷ p(s)^(m-1), Σ_c
    _check_support(zero_support, flat, pr, shape)
    if marked:
        return _with_log_space_cells(prod, flat, pr, extra, linear_total, arrays).astype(out_dtype, copy=False)
    if not linear_total > 0:
        raise ValueError(_conflict_message(arrays))
    out = np.divide(prod, linear_total, out=prod if out_dtype == np.float64 else np.empty(prod.size, out_dtype),
                    casting="same_kind")
    return out.reshape(shape)


def _check_inputs(arrays, stats) -> None:
    """Each input non-negative, finite and summing to 1, from the kernel's [negatives, Σ] of it."""
    for j, (a, st) in enumerate(zip(arrays, stats)):
        if st[0] > 0 or not np.isfinite(st[1]):
            check_nonnegative(a, f"posteriors[{j}]")  # locates and names the bad entry
        check_sums(st[1], f"posteriors[{j}]", a.dtype, over="over all cells")


def _check_support(zero_support, flat, pr, shape) -> None:
    """The prior must be positive wherever every posterior is."""
    if zero_support:
        support = np.logical_and.reduce([a > 0 for a in flat])
        cell = np.unravel_index(np.flatnonzero(support & (pr == 0))[0], shape)
        raise ValueError(f"prior is zero at cell {tuple(int(i) for i in cell)} where every posterior is positive")


def _with_log_space_cells(prod, flat, pr, extra, linear_total, arrays):
    """Normalise when some cells' products left the safe range of float64 (marked −1 in ``prod``).

    Only those cells are recomputed in log space, log p_c = Σ_j log p(s_c|e_j) − (m−1) log p(s_c); the
    normaliser T = Σ_linear p + Σ_marked exp(log p) is formed in log space, and the linear cells are scaled
    by (p / Σ_linear) · (Σ_linear / T), which is exact whenever the result is a normal float.
    """
    idx = np.flatnonzero(prod < 0)
    log_p = np.sum([np.log(a[idx], dtype=np.float64) for a in flat], axis=0)
    if extra and pr.size:
        log_p -= extra * np.log(pr[idx])
    log_linear = np.log(linear_total) if linear_total > 0 else -np.inf
    log_total = np.logaddexp(log_linear, logsumexp(log_p))
    if not np.isfinite(log_total):
        raise ValueError(_conflict_message(arrays))
    out = prod
    if linear_total > 0:
        out /= linear_total
        out *= np.exp(log_linear - log_total)
    else:
        out[:] = 0.0
    out[idx] = np.exp(log_p - log_total)
    return out.reshape(arrays[0].shape)


def _conflict_message(arrays) -> str:
    supports = [a > 0 for a in arrays]
    for i in range(len(arrays)):
        for j in range(i + 1, len(arrays)):
            if not np.any(supports[i] & supports[j]):
                return (
                    f"the posteriors conflict: posteriors[{i}] and posteriors[{j}] have no cell where both are "
                    "positive, so their product is zero everywhere"
                )
    return "the posteriors conflict: their product is zero in every cell (no single cell is positive in all)"
