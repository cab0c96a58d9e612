"""The semantic term p(s_c | z): eq. (20), its gas mixture and its voxel columns."""

from __future__ import annotations

import numpy as np

from .._shared._validate import as_float_array, cell_distribution, check_distribution, describe, flag
from . import _dask_arrays
from ._beliefs_check import check_belief_stats, flat_beliefs
from ._columns import column_sum
from ._dask_arrays import is_dask_array
from ._ratios import class_ratio

__all__ = ["semantic_source_probability", "column_sum"]


def semantic_source_probability(
    class_probs,
    source_likelihood,
    class_prior,
    *,
    gas_probs=None,
    column_axis=None,
    normalize=True,
    source_prior=None,
    validate=True,
):
    r"""Probability of the source being in each cell given the semantic map alone, :math:`p(s_c \mid z)`.

    Eq. (20) of the paper:

    .. math:: p(s_c \mid z) \propto \sum_i \frac{p(o_{ci} \mid z_c)}{p(o_{ci})}\, p(o_{ci} \mid s_c)

    When ``gas_probs`` is given, the gas-mixture form of Sec. "Probabilistic Gas Classification", eq. (27) of
    the paper:

    .. math:: p(s_c \mid z, \zeta) \propto \sum_\gamma p(\gamma \mid \zeta)
              \sum_i \frac{p(o_{ci} \mid z_c)}{p(o_{ci})}\, p(o_{ci} \mid s_c, \gamma)

    When ``column_axis`` is given, the column sum of Sec. "Voxelized Scene Representations", eq. (21) of the
    paper:

    .. math:: p(s_c \mid z) = \sum_{v \in c} p(s_v \mid z)

    Cost: one matrix-vector product, O(k) per cell.

    **Exactness.** In the paper's Network A with background distribution :math:`p(o \mid \neg s) = \beta`, the
    result is *exact* when ``class_prior`` = β and ``class_probs`` are the beliefs computed under β: the
    product over the other cells, :math:`\prod_{n \ne c} p(z_n \mid \neg s_n)`, is the same constant for every
    candidate c. The same holds for the gas mixture when β does not depend on γ (then ``gas_probs`` =
    :math:`p(\gamma \mid \zeta)` is the right weight). With ``class_prior`` = the marginal
    :math:`p(o) = p(s_n)\, p(o \mid s) + p(\neg s_n)\, \beta`, it is the paper's approximation
    :math:`p(o_{ni} \mid s_c) \simeq p(o_{ni})`, whose error vanishes as the number of cells grows
    (:math:`p(s_n) = 1/n`).

    Parameters
    ----------
    class_probs : (..., k) array_like
        :math:`p(o_c \mid z_c)`: per-cell class beliefs (cells on the leading axes — a list, a 2-D grid or a
        3-D voxel grid — and the k classes last). float32 input gives float32 output.
    source_likelihood : (k,) or (m, k) array_like
        :math:`p(o \mid s)` from the ontology, or :math:`p(o \mid s, \gamma)` for m gas types.
    class_prior : (k,) array_like
        :math:`p(o)`, the prior under which ``class_probs`` were computed. Must be positive wherever
        ``source_likelihood`` or ``class_probs`` is.
    gas_probs : (m,) array_like, optional
        :math:`p(\gamma \mid \zeta)`, the gas classifier's belief; required with an (m, k)
        ``source_likelihood``, m > 1.
    column_axis : int, optional
        A cell axis (counted among the leading axes of ``class_probs``, negative from the last cell axis)
        to sum over: voxels → 2-D columns.
    normalize : bool, default True
        Return a distribution over cells; ``False`` returns the unnormalised weights (scaled so that the
        largest possible per-cell weight is 1), for composition.
    source_prior : (...) array_like, optional
        :math:`p(s)` over the cells of ``class_probs`` (before any column sum); uniform when omitted. The
        result is then the posterior under that prior, :math:`p(s_c \mid z) \propto p(s_c)\, p(z \mid s_c)`,
        ready for :func:`fuse` with ``prior=source_prior``.
    validate : bool, default True
        Check ``class_probs`` (finite, non-negative, normalised to :data:`psgsl_pgm._shared._validate.SUM_RTOL`).
        Only switch off for beliefs that were already checked.

    Returns
    -------
    p : (...) ndarray
        Over the cells (with ``column_axis`` removed), summing to 1 when ``normalize``.

    Raises
    ------
    ValueError
        Shapes that do not match, probabilities that are negative, NaN, infinite or not normalised, a zero
        ``class_prior`` where a belief or the ontology is positive, ``gas_probs`` missing or of the wrong
        length, or beliefs under which no cell can hold the source.

    Examples
    --------
    The paper's kitchen ontology; one cell seen as an oven, one unobserved:

    >>> import numpy as np
    >>> from psgsl_pgm import semantic_source_probability
    >>> lik = np.array([0.4, 0.25, 0.3, 0.05])        # oven, microwave, refrigerator, countertop
    >>> prior = np.full(4, 0.25)
    >>> beliefs = np.array([[0.9, 0.05, 0.025, 0.025], prior])
    >>> semantic_source_probability(beliefs, lik, prior).round(4)
    array([0.604, 0.396])
    """
    normalize, validate = flag(normalize, "normalize"), flag(validate, "validate")
    if is_dask_array(class_probs):  # chunked over cells, lazy: psgsl_pgm.core._dask_arrays
        return _dask_arrays.semantic_source_probability_dask(
            class_probs, source_likelihood, class_prior, gas_probs=gas_probs, column_axis=column_axis,
            normalize=normalize, source_prior=source_prior, validate=validate)
    from ..kernels._belief import belief_weights  # compiled on first use (numba), not at package import

    ratio = class_ratio(source_likelihood, class_prior, gas_probs)
    q2, cell_shape = flat_beliefs(class_probs, ratio.k)
    # one pass over the beliefs: weights w_c = Σ_i p(o_ci|z_c) ρ_i (float64 accumulators) and the statistics
    # that validate them
    w, stats = belief_weights(q2, ratio.rho, ratio.zero_prior.astype(np.float64))
    if validate:
        check_belief_stats(q2, stats, ratio.zero_prior)
    weights = w.reshape(cell_shape)
    total = stats[4]  # Σ_c w_c, from the same pass
    if source_prior is not None:
        weights *= cell_distribution(source_prior, "source_prior", cell_shape, like="class_probs")  # p(s_c) p(z|s_c)
        total = np.sum(weights, dtype=np.float64)
    weights = column_sum(weights, column_axis, len(cell_shape))  # Σ_{v∈c} p(s_v|z)
    if not normalize:
        return weights.astype(q2.dtype, copy=False)
    if not total > 0:
        raise ValueError(
            "no cell can hold the source: every cell's class beliefs (times source_prior) give zero weight "
            "to the classes that source_likelihood allows"
        )
    # normalise in float64 (in place), round once to the beliefs' dtype (float32 in, float32 out)
    out = weights if q2.dtype == np.float64 else np.empty(weights.shape, q2.dtype)
    return np.divide(weights, total, out=out, casting="same_kind")
