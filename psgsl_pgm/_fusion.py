"""Fusion of posteriors over the same cells: eq. ``combined-conditionals`` and its general form."""

from __future__ import annotations

import numpy as np
from scipy.special import logsumexp

from ._validate import as_float_array, check_nonnegative, describe, check_sums

__all__ = ["fuse"]


def fuse(*posteriors, prior=None):
    r"""Combine posteriors over the source cell that used conditionally independent evidence.

    For evidence sets e_1 … e_m independent given S (e.g. olfaction g and semantics z, Sec. "Separating the
    Semantic and Olfactory Estimation Processes"), each p(s | e_j) ∝ p(e_j | s) p(s), so

    .. math:: p(s_c | e_1, \dots, e_m) \propto \frac{\prod_j p(s_c | e_j)}{p(s_c)^{m-1}},

    which for a uniform prior and m = 2 is eq. ``combined-conditionals``,
    p(s_c | g, z) ∝ p(s_c | g) · p(s_c | z). Computed in log space (no underflow for any number of cells or
    inputs).

    Parameters
    ----------
    *posteriors : (...) array_like
        Two or more distributions over the same cells (same shape, each sums to 1), all computed under the
        same source prior. One input is returned normalised.
    prior : (...) array_like, optional
        That source prior p(s); uniform when omitted. Must be positive wherever a posterior is.

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
    arrays = [as_float_array(p, f"posteriors[{j}]", min_ndim=1) for j, p in enumerate(posteriors)]
    shape = arrays[0].shape
    for j, a in enumerate(arrays):
        if a.shape != shape:
            raise ValueError(f"posteriors[{j}] must have the shape of posteriors[0], {shape}, got {describe(a)}")
        check_nonnegative(a, f"posteriors[{j}]")
        check_sums(np.sum(a, dtype=np.float64), f"posteriors[{j}] (over all cells)", a.dtype)
    out_dtype = np.float32 if all(a.dtype == np.float32 for a in arrays) else np.float64

    # log 0 = −inf is intended; −inf − (−inf) on cells outside every support is masked below
    with np.errstate(divide="ignore", invalid="ignore"):
        log_p = np.sum([np.log(a, dtype=np.float64) for a in arrays], axis=0)  # Σ_j log p(s|e_j)
        if prior is not None:
            pr = as_float_array(prior, "prior", dtype=np.float64)
            if pr.shape != shape:
                raise ValueError(f"prior must have the posteriors' shape {shape}, got {describe(pr)}")
            check_nonnegative(pr, "prior")
            check_sums(pr.sum(), "prior (over all cells)", pr.dtype)
            support = np.isfinite(log_p)
            if np.any(support & (pr == 0)):
                cell = np.argwhere(support & (pr == 0))[0]
                raise ValueError(f"prior is zero at cell {tuple(int(i) for i in cell)} where every posterior is positive")
            log_p = np.where(support, log_p - (len(arrays) - 1) * np.log(pr), -np.inf)  # ÷ p(s)^(m-1)

    norm = logsumexp(log_p)
    if not np.isfinite(norm):
        raise ValueError(_conflict_message(arrays))
    return np.exp(log_p - norm).astype(out_dtype, copy=False)


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
