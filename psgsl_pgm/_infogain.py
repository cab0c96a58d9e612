r"""Semantic information gain I(S; O_n) for every cell at once (Sec. "Information Gain Optimization").

Derivation (checked in ``proofs/check_information_gain.py``). Let the current source distribution be the
fusion P(c) = f_c w_c / U of an olfactory posterior f with the semantic weights w_c = q_c · ρ
(eq. ``prob-semantics-final``, ρ from :mod:`psgsl_pgm._ratios`), U = Σ_c f_c w_c. Learning O_n = i removes
cell n's uncertain factor: in Network A, p(O_n = i, z_n | S = c) / p(z_n | ¬s_n) is q_ni for c ≠ n and
q_ni ρ_i for c = n, so *only cell n's weight changes*, from f_n w_n to f_n ρ_i. With a_n = f_n / U and

    x_ni = a_n (ρ_i − w_n),   Z_ni = 1 + x_ni   (the new normaliser; P_n = a_n w_n),

the posterior after O_n = i has entropy H_ni = [B_n − a_n ρ_i log(a_n ρ_i)] / Z_ni + log Z_ni with
B_n = H(S) + P_n log P_n, and the exact predictive is p(O_n = i | all) = q_ni Z_ni. Hence

* exact:  I(S; O_n) = a_n (v_n − w_n log w_n) − Σ_i q_ni φ(x_ni),  φ(x) = (1+x) log(1+x) − x,
  v_n = Σ_i q_ni ρ_i log ρ_i (both terms ≥ 0 by Jensen; H(S) drops out);
* paper:  H(S) − Σ_i q_ni H_ni (the paper weights H(S | o_ni) by p(o_ni | z) = q_ni).

For most cells |x_ni| is tiny (a_n ~ 1/n), and both sums expand in the central moments
μ_j = Σ_i q_ni (ρ_i − w_n)^j and ν_j = Σ_i q_ni ρ_i log ρ_i (ρ_i − w_n)^j, which come from one fused pass
over the beliefs (products with ρ^l and ρ log ρ · ρ^l). Cells where the series would converge slowly are
computed element-wise. Total cost O(n·k); no per-cell recomputation of the posterior (which is O(n²·k)).
"""

from __future__ import annotations

import numpy as np
from scipy.special import binom, xlogy

from ._beliefs_check import belief_products
from ._ratios import class_ratio
from ._semantic import cell_distribution

__all__ = ["semantic_information_gain"]

_ORDER = 7  # series terms: truncation error ≲ _RADIUS**(_ORDER + 1) = 1e-16 relative
_RADIUS = 0.01  # use the series where a_n · max_i |ρ_i − w_n| ≤ _RADIUS
_CHUNK_ELEMENTS = 1 << 17


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
    r"""Expected information about the source from learning each cell's object class, I(S; O_n).

    .. math:: I(S; O_n) = H(S) - \sum_i p(o_{ni} | \cdot)\, H(S | o_{ni})

    where S's current distribution is the fusion (eq. ``combined-conditionals``) of ``olfactory`` with the
    semantic term of :func:`semantic_source_probability`. The posterior after observing O_n only rescales
    cell n's weight, which gives all n cells in O(n·k) total (see the module docstring for the formulas).

    Parameters
    ----------
    class_probs : (..., k) array_like
        p(o_c | z_c), as for :func:`semantic_source_probability`.
    source_likelihood : (k,) or (m, k) array_like
        p(o | s) or p(o | s, γ).
    class_prior : (k,) array_like
        p(o) under which ``class_probs`` were computed.
    olfactory : (...) array_like, optional
        p(s | g) over the same cells; uniform when omitted.
    gas_probs : (m,) array_like, optional
        p(γ | ζ), required with m > 1 gas rows.
    predictive : {"paper", "exact"}
        ``"paper"`` weights H(S | o_ni) by p(o_ni | z) as the paper writes; ``"exact"`` uses the predictive
        p(O_n = i | all evidence) = Σ_c P(c) p(o_ni | s_c, z_n), which makes the result the exact mutual
        information (non-negative; exact in Network A when ``class_prior`` is the background p(o | ¬s)).
    validate : bool, default True
        Check ``class_probs`` (see :func:`semantic_source_probability`).

    Returns
    -------
    gain : (...) ndarray
        I(S; O_n) in nats for every cell, float64.

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
    if predictive not in ("paper", "exact"):
        raise ValueError(f"predictive must be 'paper' or 'exact', got {predictive!r}")
    ratio = class_ratio(source_likelihood, class_prior, gas_probs)
    rho = ratio.rho
    rho_log_rho = xlogy(rho, rho)
    powers = rho[:, None] ** np.arange(1, _ORDER + 1)  # ρ^1 … ρ^J
    log_powers = rho_log_rho[:, None] * rho[:, None] ** np.arange(_ORDER)  # ρ log ρ · ρ^0 … ρ^(J−1)
    bp = belief_products(
        class_probs, np.hstack([powers, log_powers]), zero_prior=ratio.zero_prior, validate=validate
    )
    raw = bp.products.astype(np.float64, copy=False)
    raw_mu, raw_nu = raw[:, :_ORDER], raw[:, _ORDER:]
    w = raw_mu[:, 0]  # w_n = q_n · ρ
    v = raw_nu[:, 0]  # v_n = q_n · ρ log ρ

    n = w.shape[0]
    if olfactory is None:
        f = np.full(n, 1.0 / n)
    else:
        f = cell_distribution(olfactory, "olfactory", bp.cell_shape).reshape(-1).astype(np.float64)
    total = f @ w  # U = Σ_c f_c w_c
    if not total > 0:
        raise ValueError(
            "olfactory and the semantic term have no cell in common: their fusion is zero everywhere"
        )
    a = f / total  # a_n
    p_n = a * w  # P(n)
    entropy = -np.sum(xlogy(p_n, p_n))  # H(S)
    jensen = v - xlogy(w, w)  # v_n − w_n log w_n ≥ 0

    spread = np.maximum(rho.max() - w, w - rho.min())
    series = a * spread <= _RADIUS
    gain = np.empty(n)
    moments = raw.T  # (2J, n): one row per raw moment, so the series works on contiguous vectors
    if np.all(series):
        gain[:] = _series_gain(a, w, jensen, np.ascontiguousarray(moments), entropy, predictive)
    elif np.any(series):
        idx = np.flatnonzero(series)
        gain[idx] = _series_gain(a[idx], w[idx], jensen[idx], moments[:, idx], entropy, predictive)
    if not np.all(series):
        idx = np.flatnonzero(~series)
        gain[idx] = _elementwise_gain(bp.q, idx, rho, a, w, jensen, entropy, predictive)
    # I ≥ 0 for the exact mutual information: clip round-off of size ~eps·a_n only.
    if predictive == "exact":
        np.maximum(gain, 0.0, out=gain)
    return gain.reshape(bp.cell_shape)


def _central(raw, neg_w_pow, order):
    """Central moments Σ_i q_i g_i (ρ_i − w)^j for j < order from raw ones Σ_i q_i g_i ρ_i^l (list of rows).

    μ_j = Σ_l C(j, l) M_l (−w)^(j−l); a few dozen vector operations of length n.
    """
    out = []
    for j in range(order):  # loops over moment orders, not cells
        acc = raw[j].copy()
        for l in range(j):
            acc += binom(j, l) * raw[l] * neg_w_pow[j - l]
        out.append(acc)
    return out


def _series_gain(a, w, jensen, moments, entropy, predictive):
    J = _ORDER
    neg_w_pow = [np.ones_like(w)]
    neg_a_pow = [np.ones_like(a)]
    for _ in range(J):
        neg_w_pow.append(neg_w_pow[-1] * -w)
        neg_a_pow.append(neg_a_pow[-1] * -a)
    mu = _central([np.ones_like(w)] + list(moments[:J]), neg_w_pow, J + 1)  # μ_0 … μ_J
    mu[1] = np.zeros_like(w)  # μ_1 = Σ q (ρ − w) = 0 exactly (round-off removed)
    if predictive == "exact":
        # Σ_i q_i φ(x_i) = Σ_{j≥2} (−a)^j μ_j / (j (j−1))
        return a * jensen - sum(neg_a_pow[j] * mu[j] / (j * (j - 1)) for j in range(2, J + 1))
    nu = _central(list(moments[J:]), neg_w_pow, J)  # ν_0 … ν_(J−1)
    w_log_w = xlogy(w, w)
    # paper: I = H·(1 − S0) + a log a · T1 + a·(S2 − w log w · S0) − S3, each a series in (−a)^j:
    one_minus_s0 = -sum(neg_a_pow[j] * mu[j] for j in range(2, J + 1))  # 1 − Σ q/Z
    t1 = sum(neg_a_pow[j] * mu[j + 1] for j in range(1, J))  # Σ q (ρ − w)/Z
    s2_gap = jensen + sum(neg_a_pow[j] * (nu[j] - w_log_w * mu[j]) for j in range(1, J))  # j = 0: Jensen gap
    s3 = -sum(neg_a_pow[j] * mu[j] / j for j in range(2, J + 1))  # Σ q log Z, log(1+x) = −Σ (−x)^j / j
    return entropy * one_minus_s0 + xlogy(a, a) * t1 + a * s2_gap - s3


def _elementwise_gain(q, idx, rho, a, w, jensen, entropy, predictive):
    out = np.empty(idx.shape[0])
    rho_log_rho = xlogy(rho, rho)
    k = q.shape[1]
    step = max(1, _CHUNK_ELEMENTS // k)
    for s in range(0, idx.shape[0], step):  # loop over blocks of cells
        rows = idx[s : s + step]
        qs = q[rows].astype(np.float64)
        an, wn = a[rows][:, None], w[rows][:, None]
        x = an * (rho[None, :] - wn)  # x_ni = a_n (ρ_i − w_n)
        z = 1.0 + x  # Z_ni
        with np.errstate(divide="ignore", invalid="ignore"):
            log_z = np.log1p(x)
            if predictive == "exact":
                phi = np.where(z > 0, z * log_z, 0.0) - x  # φ(x) = Z log Z − x
                out[s : s + step] = a[rows] * jensen[rows] - np.sum(qs * phi, axis=1)
            else:
                # H − Σ_i q_i H_ni rearranged as in the series (no cancellation between H and Σ q H):
                # I = H·Σq x/Z + a log a·Σq (ρ−w)/Z + a·Σq (ρ log ρ − w log w)/Z − Σq log Z
                q_over_z = np.where(z > 0, qs / z, 0.0)  # impossible outcomes (Z = 0) contribute nothing
                gap = rho_log_rho[None, :] - xlogy(wn, wn)
                out[s : s + step] = (
                    entropy * np.sum(q_over_z * x, axis=1)
                    + xlogy(a[rows], a[rows]) * np.sum(q_over_z * (rho[None, :] - wn), axis=1)
                    + a[rows] * np.sum(q_over_z * gap, axis=1)
                    - np.sum(np.where(z > 0, qs * log_z, 0.0), axis=1)
                )
    return out
