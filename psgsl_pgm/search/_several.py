r"""Several sources: the robot declares them one by one and stops when it no longer believes in another.

**Model: sequential conditioning.** The robot's estimators hold a belief about *one* source location. With
several sources it searches for them in turn: its target is "a source not yet declared". After the k-th
declaration (at c*_k, :mod:`psgsl_pgm.search._declare`) the region E(c*_k) — every cell within
max(``declare_radius``, ``success_radius``) of c*_k's found region: a source that close would be scored as the
one declared, so the robot counts it as the same leak — is removed from the hypothesis space,
p(s) ∝ p(s) [s ∉ E(c*_1) ∪ … ∪ E(c*_k)], and the detections that confirmed the declared source (the
"found" factors, which concern that source) are dropped; every "not found here" factor stays (a place searched
without a detection holds no undeclared source either). A later detector firing at a point within reach of a
declared hypothesis is explained by it and ignored. The gas readings are kept as they are: the estimators' hit
model is a one-source model, so hits carried from a declared source still pull the belief toward it, and its
removal leaves mass on its border; that is the approximation of this model (a noisy-OR likelihood of several
plumes would explain them away; it needs per-reading likelihood maps that not every estimator has).

**Declaring the next source.** The target belief is conditioned on a further source existing; as the searched
area grows, its mass crowds into what is left unsearched, where a rule on that conditional mass alone would
declare a source that may not be there. After k ≥ 1 declarations the rule of :mod:`psgsl_pgm.search._declare`
therefore uses the robot's unconditional probability that a source lies in D(c*): M · P(N > k | data) ≥ κ (the
first declaration is unchanged: N ≥ 1 is certain). The stored declared mass is that product.

**Stopping.** The robot's prior over how many sources emit is p(N) on {1, 2, 3}. After k declarations, with no
further source found so far, Bayes' rule gives the probability that another exists,

.. math::

    P(N > k \mid \text{data}) = \frac{a\,Z}{a\,Z + (1 - a)}, \qquad
    a = P(N > k \mid N \ge k) = \frac{\sum_{n > k} p(n)}{\sum_{n \ge k} p(n)},
    \qquad Z = \sum_c \pi(c)\, P(\bar F \mid s = c),

where Z is the probability that a further source would have escaped every detection so far: π(c) the robot's
prior of where a source is (its estimator's prior, times the semantic term p(s | z) for a semantic variant, on
the findable cells outside the removed regions E, normalised) and P(F̄ | s = c) the product of the "not found
here" likelihoods of every move (:meth:`DetectionModel.not_found_likelihood`, with the robot's miss
probability). A detection that no declared source explains makes it 1: the detector never fires where no
source is (:class:`psgsl_pgm.sim.SourceDetector`). The robot stops when this falls below κ_N
(``more_sources_level``, 0.1). It uses the close-range detector's evidence only, not the gas readings (whose one-source model cannot say how many plumes it smells): a
conservative rule — it stops once it has looked, without a detection, where the remaining sources would likely
be. Since a = 0 once k = 3, it always stops at the third declaration.

**Scoring.** Each declaration names the nearest true source not yet named within ``success_radius`` (in the
order of the declarations), or none: a false declaration. A source is found at the time of the declaration that
names it; "all found" at the last of them; both are censored at the budget.
"""

from __future__ import annotations

import numpy as np

__all__ = ["match_declarations", "more_sources_probability"]


def more_sources_probability(prior, k: int, escape: float) -> float:
    """P(N > k | data) (module docstring).

    Parameters
    ----------
    prior : (3,) array_like
        p(N) for N = 1, 2, 3.
    k : int
        Sources declared so far (≥ 1).
    escape : float
        Z in [0, 1], the probability that a further source would have escaped every detection so far.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        ``prior`` is not of shape (3,), ``k`` is not an integer >= 1, or ``escape`` is not in [0, 1].

    Examples
    --------
    >>> round(more_sources_probability([1/3, 1/3, 1/3], 1, 1.0), 4)   # nothing searched: the prior's 2/3
    0.6667
    >>> round(more_sources_probability([1/3, 1/3, 1/3], 1, 0.05), 4)
    0.0909
    >>> more_sources_probability([1/3, 1/3, 1/3], 3, 1.0)
    0.0
    """
    p = np.asarray(prior, dtype=np.float64)
    if p.shape != (3,):
        raise ValueError(f"prior must be p(N) for N = 1, 2, 3, shape (3,), got shape {p.shape}")
    if not (isinstance(k, (int, np.integer)) and k >= 1):
        raise ValueError(f"k must be the number of sources declared, an integer >= 1, got {k!r}")
    if not (0.0 <= escape <= 1.0 + 1e-12):
        raise ValueError(f"escape must be a probability in [0, 1], got {escape!r}")
    rest = float(p[k - 1:].sum()) if k <= 3 else 0.0
    more = float(p[k:].sum()) if k < 3 else 0.0
    if more == 0.0 or rest == 0.0:
        return 0.0
    a = more / rest
    return float(a * escape / (a * escape + (1.0 - a)))


def match_declarations(declared_xy, sources_xy, *, radius: float, regions=None) -> np.ndarray:
    """(k,) the true source each declaration names, −1 for none (module docstring, "Scoring").

    Parameters
    ----------
    declared_xy : (k, 2) array_like
        The declared points in declaration order, m.
    sources_xy : (N, 2) array_like
        The true sources, m.
    radius : float, keyword-only
        m, ``success_radius``.
    regions : sequence of (m_i, 2) arrays or None, optional, keyword-only
        Each source object's footprint cell centres (None entries: a point source), as
        :func:`psgsl_pgm.search._declare.declaration_error` scores them.

    Examples
    --------
    >>> match_declarations([[0.0, 0.0], [0.2, 0.0], [5.0, 5.0]], [[5.0, 5.5], [0.0, 0.5]], radius=1.0).tolist()
    [1, -1, 0]
    """
    from ._declare import declaration_error

    d = np.asarray(declared_xy, dtype=np.float64).reshape(-1, 2)
    s = np.asarray(sources_xy, dtype=np.float64).reshape(-1, 2)
    regions = [None] * len(s) if regions is None else list(regions)
    taken = np.zeros(len(s), bool)
    out = np.full(len(d), -1, dtype=np.int64)
    for i, xy in enumerate(d):
        err = np.array([declaration_error(xy, s[j], regions[j]) for j in range(len(s))])
        err[taken] = np.inf
        j = int(np.argmin(err)) if len(err) else -1
        if j >= 0 and err[j] <= radius:
            out[i], taken[j] = j, True
    return out
