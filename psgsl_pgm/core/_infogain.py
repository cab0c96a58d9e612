r"""Semantic information gain :math:`I(S; O_n)` for every cell at once (Sec. "Information Gain Optimization").

Derivation (checked in ``proofs/check_information_gain.py``). Let the current source distribution be the
fusion :math:`P(c) = f_c w_c / U` of an olfactory posterior f with the semantic weights :math:`w_c = q_c \cdot \rho`
(eq. (20), ρ from :mod:`psgsl_pgm.core._ratios`), :math:`U = \sum_c f_c w_c`. Learning :math:`O_n = i` removes
cell n's uncertain factor: in Network A, :math:`p(O_n = i, z_n \mid S = c) / p(z_n \mid \neg s_n)` is
:math:`q_{ni}` for c ≠ n and :math:`q_{ni} \rho_i` for c = n, so *only cell n's weight changes*, from
:math:`f_n w_n` to :math:`f_n \rho_i`. With :math:`a_n = f_n / U`, :math:`P_n = a_n w_n` and the new normaliser

.. math:: x_{ni} = a_n (\rho_i - w_n), \qquad Z_{ni} = 1 + x_{ni},

the posterior after :math:`O_n = i` has entropy

.. math:: H_{ni} = \frac{B_n - a_n \rho_i \log(a_n \rho_i)}{Z_{ni}} + \log Z_{ni},
          \qquad B_n = H(S) + P_n \log P_n,

and the exact predictive is :math:`p(O_n = i \mid \text{all}) = q_{ni} Z_{ni}`. Hence

* exact (both terms ≥ 0 by Jensen; H(S) drops out):

  .. math:: I(S; O_n) = a_n (v_n - w_n \log w_n) - \sum_i q_{ni}\, \phi(x_{ni}),
            \qquad \phi(x) = (1 + x) \log(1 + x) - x, \qquad v_n = \sum_i q_{ni} \rho_i \log \rho_i;

* paper: :math:`H(S) - \sum_i q_{ni} H_{ni}` (the paper weights :math:`H(S \mid o_{ni})` by
  :math:`p(o_{ni} \mid z) = q_{ni}`).

For most cells :math:`|x_{ni}|` is tiny (:math:`a_n \sim 1/n`), and both sums expand in the central moments
:math:`\mu_j = \sum_i q_{ni} (\rho_i - w_n)^j` and :math:`\nu_j = \sum_i q_{ni} \rho_i \log \rho_i (\rho_i - w_n)^j`,
which one compiled pass over
the beliefs computes directly (:func:`psgsl_pgm.kernels._belief.belief_moments`: each row read once, the moments
taken about w_n while the row is in cache — no raw-moment cancellation). Cells where the series would
converge slowly are computed element-wise from their row. Total cost O(n·k); no per-cell recomputation of the posterior (which is O(n²·k)).
"""

from __future__ import annotations

import numpy as np
from scipy.special import xlogy

from .._shared._validate import cell_distribution, flag
from . import _dask_arrays
from ._beliefs_check import check_belief_stats, flat_beliefs
from ._dask_arrays import is_dask_array
from ._ratios import class_ratio

__all__ = ["semantic_information_gain"]

_ORDER = 5  # series terms j = 2 … J: truncation ≲ _RADIUS**(_ORDER − 1) = 1e-12 of the leading (j = 2) term
_RADIUS = 1e-3  # use the series where a_n · max_i |ρ_i − w_n| ≤ _RADIUS (at n = 1e6 cells: nearly all)


def semantic_information_gain(
    class_probs,
    source_likelihood,
    class_prior,
    *,
    olfactory=None,
    gas_probs=None,
    predictive="paper",
    validate=True,
):
    r"""Expected information about the source from learning each cell's object class, :math:`I(S; O_n)`.

    Eq. (30) of the paper:

    .. math:: I(S; O_n) = H(S) - \sum_i p(o_{ni} \mid z)\, H(S \mid o_{ni})

    where the current distribution of :math:`S` is the fusion (eq. (11)) of ``olfactory`` with the semantic
    term of :func:`semantic_source_probability`. The posterior after observing :math:`O_n` only rescales cell
    n's weight, which gives all n cells in O(n·k) total (see the module docstring for the formulas).

    Parameters
    ----------
    class_probs : (..., k) array_like
        :math:`p(o_c \mid z_c)`, as for :func:`semantic_source_probability`.
    source_likelihood : (k,) or (m, k) array_like
        :math:`p(o \mid s)` or :math:`p(o \mid s, \gamma)`.
    class_prior : (k,) array_like
        :math:`p(o)` under which ``class_probs`` were computed.
    olfactory : (...) array_like, optional
        :math:`p(s \mid g)` over the same cells; uniform when omitted.
    gas_probs : (m,) array_like, optional
        :math:`p(\gamma \mid \zeta)`, required with m > 1 gas rows.
    predictive : {"paper", "exact"}
        ``"paper"`` weights :math:`H(S \mid o_{ni})` by :math:`p(o_{ni} \mid z)` as the paper writes;
        ``"exact"`` uses the predictive :math:`p(O_n = i \mid \text{all evidence}) = \sum_c P(c)\,
        p(o_{ni} \mid s_c, z_n)`, which makes the result the exact mutual information (non-negative; exact in
        Network A when ``class_prior`` is the background :math:`p(o \mid \neg s)`).
    validate : bool, default True
        Check ``class_probs`` (see :func:`semantic_source_probability`).

    Returns
    -------
    gain : (...) ndarray
        :math:`I(S; O_n)` in nats for every cell, float64.

    Raises
    ------
    TypeError
        ``validate`` is not a bool.
    ValueError
        ``predictive`` is neither ``"paper"`` nor ``"exact"``; ``class_probs``, ``source_likelihood``,
        ``class_prior``, ``gas_probs`` or ``olfactory`` are refused (see :func:`semantic_source_probability`); or
        ``olfactory`` and the semantic term have no cell in common.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import semantic_information_gain
    >>> lik = np.array([0.4, 0.25, 0.3, 0.05])
    >>> prior = np.full(4, 0.25)
    >>> beliefs = np.array([[0.97, 0.01, 0.01, 0.01], prior, prior])   # cell 0 is almost surely an oven
    >>> gain = semantic_information_gain(beliefs, lik, prior, predictive="exact")
    >>> bool(gain[1] > gain[0]), bool(np.isclose(gain[1], gain[2]))   # unseen cells are worth looking at
    (True, True)
    """
    validate = flag(validate, "validate")
    if predictive not in ("paper", "exact"):
        raise ValueError(f"predictive must be 'paper' or 'exact', got {predictive!r}")
    if is_dask_array(class_probs) or is_dask_array(olfactory):  # chunked over cells, lazy: psgsl_pgm.core._dask_arrays
        return _dask_arrays.information_gain_dask(class_probs, source_likelihood, class_prior, olfactory=olfactory,
                                                  gas_probs=gas_probs, predictive=predictive, validate=validate,
                                                  radius=_RADIUS)
    from ..kernels._belief import (  # compiled on first use
        ORDER,
        belief_moments,
        cell_logs,
        entropy_terms,
        gain_from_moments,
    )

    if _ORDER != ORDER:
        raise RuntimeError(f"_infogain._ORDER = {_ORDER} but the compiled kernels hold {ORDER} moments")
    ratio = class_ratio(source_likelihood, class_prior, gas_probs)
    rho = ratio.rho
    rho_log_rho = xlogy(rho, rho)
    q2, cell_shape = flat_beliefs(class_probs, ratio.k)
    n = q2.shape[0]
    if olfactory is None:
        f, f_uniform = np.empty(0), 1.0 / max(n, 1)
    else:
        f = cell_distribution(olfactory, "olfactory", cell_shape, like="class_probs")
        f = np.ascontiguousarray(f, dtype=np.float64)
        f, f_uniform = f.reshape(-1), 0.0
    paper = predictive == "paper"
    # one pass over the beliefs: w_n, the Jensen gap, central moments μ_j (and ν_j) per cell, U = Σ f w, and
    # the statistics that validate the beliefs
    w, moments, stats = belief_moments(
        q2, rho, rho_log_rho, ratio.zero_prior.astype(np.float64), f, f_uniform, paper)
    if validate:
        check_belief_stats(q2, stats, ratio.zero_prior)
    total = stats[4]  # U = Σ_c f_c w_c
    if not total > 0:
        raise ValueError(
            "olfactory and the semantic term have no cell in common: their fusion is zero everywhere"
        )
    logs = cell_logs(w, f)  # log w_n, log f_n (NumPy's SIMD log)
    entropy = entropy_terms(w, f, f_uniform, total, logs) if paper else 0.0  # H(S)
    gain = gain_from_moments(q2, w, moments, f, f_uniform, total, rho, rho_log_rho, entropy, _RADIUS, paper, logs)
    return gain.reshape(cell_shape)
