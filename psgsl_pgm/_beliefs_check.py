"""Validated per-cell class beliefs p(o_c | z_c) and their dot products with the class ratio, in one pass."""

from __future__ import annotations

import numpy as np

from ._kernel import fused_products
from ._validate import as_float_array, check_last_axis, check_nonnegative, check_sums

__all__ = ["BeliefProducts", "belief_products"]


class BeliefProducts:
    """``class_probs`` flattened to (n, k) with its products ``q @ vectors``.

    Attributes
    ----------
    q : (n, k) ndarray
        The class beliefs, C-contiguous, float32 or float64.
    cell_shape : tuple of int
        The leading (cell) axes of the original array.
    products : (n, p) ndarray
        ``q @ vectors``.
    """

    __slots__ = ("q", "cell_shape", "products")

    def __init__(self, q: np.ndarray, cell_shape: tuple, products: np.ndarray):
        self.q, self.cell_shape, self.products = q, cell_shape, products


def belief_products(class_probs, vectors: np.ndarray, *, zero_prior=None, validate: bool = True) -> BeliefProducts:
    """Validate ``class_probs`` and return its products with ``vectors`` from a single pass.

    Parameters
    ----------
    class_probs : (..., k) array_like
        p(o_c | z_c): one distribution over the k classes per cell.
    vectors : (k, p) ndarray
        k-vectors to multiply with (float64; cast to the beliefs' dtype). A column of ones is appended
        internally to get the row sums for validation.
    zero_prior : (k,) ndarray of bool, optional
        Classes with zero prior p(o); the beliefs must put no mass on them.
    validate : bool
        Check finiteness, non-negativity and normalisation (tolerance :data:`psgsl_pgm._validate.SUM_RTOL`).
        Only turn this off for beliefs this library produced or already checked.
    """
    q = as_float_array(class_probs, "class_probs", min_ndim=1)
    k = vectors.shape[0]
    check_last_axis(q, "class_probs", k)
    if q.ndim == 1:
        raise ValueError(
            f"class_probs must have cell axes before the class axis, shape (..., {k}); got {q.shape} — "
            f"for a single cell pass class_probs[None, :]"
        )
    cell_shape = q.shape[:-1]
    q2 = np.ascontiguousarray(q.reshape(-1, k))
    vec = np.column_stack([vectors, np.ones(k)]).astype(q.dtype)
    prods, lowest = fused_products(q2, vec)
    if validate:
        if not np.isfinite(lowest) or lowest < 0 or not np.all(np.isfinite(prods[:, -1])):
            check_nonnegative(q2, "class_probs")  # slow path: locate and name the bad entry
        check_sums(prods[:, -1], "class_probs", q.dtype)
        if zero_prior is not None and np.any(zero_prior):
            leak = q2[:, zero_prior].max()
            if leak > 0:
                raise ValueError(
                    f"class_probs puts mass {leak:g} on classes {np.flatnonzero(zero_prior).tolist()} whose "
                    "class_prior is zero; beliefs computed under that prior cannot"
                )
    return BeliefProducts(q2, cell_shape, prods[:, :-1])
