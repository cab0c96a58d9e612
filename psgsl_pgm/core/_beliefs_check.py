"""Per-cell class beliefs p(o_c | z_c): flattening, and validation from the statistics of the fused kernel pass.

The compiled kernels of :mod:`psgsl_pgm.kernels._belief` read ``class_probs`` once and report, besides the products
the caller needs, the number of negative entries, the largest deviation of a row sum from 1 (infinite when a
row holds NaN or inf) and the largest mass on zero-prior classes. Only when one of these says something is
wrong does :func:`check_belief_stats` look at the array again, through the shared vocabulary of
:mod:`psgsl_pgm._shared._validate`, to name the offending entry or cell.
"""

from __future__ import annotations

import numpy as np

from .._shared._validate import as_float_array, check_last_axis, check_nonnegative, check_sums

__all__ = ["flat_beliefs", "check_belief_stats"]


def flat_beliefs(class_probs, k: int) -> tuple[np.ndarray, tuple]:
    """``class_probs`` as a C-contiguous (n, k) float32/float64 matrix, and its cell shape.

    Parameters
    ----------
    class_probs : (..., k) array_like
        One distribution over the k classes per cell, cells on the leading axes. float32 stays float32
        (no copy when already C-contiguous).
    k : int
        Number of classes.
    """
    q = as_float_array(class_probs, "class_probs", min_ndim=1)
    check_last_axis(q, "class_probs", k)
    if q.ndim == 1:
        raise ValueError(
            f"class_probs must have cell axes before the class axis, shape (..., {k}); got {q.shape} — "
            f"for a single cell pass class_probs[None, :]"
        )
    return np.ascontiguousarray(q.reshape(-1, k)), q.shape[:-1]


def check_belief_stats(q2: np.ndarray, stats: np.ndarray, zero_prior: np.ndarray) -> None:
    """Raise ValueError (naming the entry or cell) unless the kernel's statistics describe valid beliefs.

    Parameters
    ----------
    q2 : (n, k) ndarray
        The beliefs the statistics were computed from.
    stats : (5,) ndarray
        [negative entries, largest |row sum − 1| (inf if not finite), its row, largest mass on zero-prior
        classes, unused] as returned by the kernels.
    zero_prior : (k,) ndarray of bool
        Classes with zero prior p(o).
    """
    negatives, worst_dev, worst_row, leak = stats[0], stats[1], int(stats[2]), stats[3]
    if q2.size == 0 or negatives > 0 or not np.isfinite(worst_dev):
        check_nonnegative(q2, "class_probs")  # locates and names the NaN, inf or negative entry
    worst_sum = np.float64(q2[worst_row].sum(dtype=np.float64)) if q2.shape[0] else np.float64(1.0)
    try:
        check_sums(worst_sum, "class_probs", q2.dtype)
        rows_ok = True
    except ValueError:
        rows_ok = False
    if not rows_ok:  # some row is off: let the vocabulary name the worst cell of the whole map
        check_sums(q2.sum(axis=1, dtype=np.float64), "class_probs", q2.dtype)
        check_sums(worst_sum, "class_probs", q2.dtype)  # reached only if the two sums differ by round-off
    if leak > 0:
        worst = q2[:, zero_prior].max()
        raise ValueError(
            f"class_probs puts mass {worst:g} on classes {np.flatnonzero(zero_prior).tolist()} whose "
            "class_prior is zero; beliefs computed under that prior cannot"
        )
