r"""Entrotaxis (Hutchinson, Oh & Chen 2018, "Entrotaxis as a strategy for autonomous search and source
reconnaissance based on entropy maximization", Information Fusion 42:179–189): move where the next measurement
is the least predictable.

Infotaxis (Vergassola et al. 2007) scores a pose by the expected *drop* of the source's entropy H(S). Entrotaxis
scores it by the entropy of the *predicted measurement* there,

.. math:: a^* = \arg\max_a H\big[p(\hat z_{k+1}(a) \mid D_k)\big]
               = \arg\max_a \Big(-\sum_z p(z \mid D_k, a) \log p(z \mid D_k, a)\Big),

with :math:`p(z \mid D_k, a) = \sum_s p(s \mid D_k)\, P(z \mid s, a)` the posterior predictive. By
:math:`I(S; Z) = H(Z) - H(Z \mid S)` it is the mutual information plus the measurement's own noise,
:math:`\mathbb{E}_s H(Z \mid s)`: it needs no posterior per outcome (one predictive per pose), and a pose where the
model is unsure of the reading for every source scores as well as one where the sources disagree.

**The measurement of a stop** in the closed loop is the found rule's outcome and, when not found, the gas
reading: z ∈ {found, (not found, hit), (not found, miss)}, under the detection model :math:`P_f` of
:mod:`psgsl_pgm.search._policies` and the estimator's hit model :math:`P_p(s) = P(\text{hit at } p \mid s)`:

.. math:: G(p) = H_b(P_f(p)) + (1 - P_f(p))\, H_b(\bar P_p),
          \qquad \bar P_p = \frac{\sum_s p(s)\, w_p(s)\, P_p(s)}{1 - P_f(p)},

:math:`H_b` the binary entropy in nats, :math:`w_p(s) = m` on the hypotheses the stop finds (m the miss probability)
and 1 elsewhere, p(s) the variant's posterior (with a semantic variant, the fused :math:`p(s \mid g, z)`: the
semantic term shapes the predictive; the camera's frames are not part of the scored measurement). G ≤ ln 3. The same
candidate poses, travel times τ(p) and scoring rule (``per-time``: G/τ; ``gain``: G) as ``infotaxis``; G does not
depend on the camera heading, so the heading that costs least time wins (the first one under ``gain``).

What the binary measurement does to the method: with Poisson counts (Hutchinson et al.) the predicted entropy
grows with the expected count and draws the searcher to the source; a hit/miss reading's entropy is largest
where P̄ = ½, at the edge of the predicted plume, not at its centre, and H_b(P_f) is largest where the stop finds
the source with probability ½. The robot is drawn to where the belief's mass is (the found term rises with P_f up
to ½) and to the plume's edges. Like infotaxis it ends by the loop's found rule or the time budget.
"""

from __future__ import annotations

import numpy as np
from scipy.special import entr

from ._policies import _best, _candidates, _detection, _found_mass, _hit_rows, _score

__all__ = ["choose_entrotaxis", "entrotaxis_gain"]


def _hb(p):
    p = np.clip(np.asarray(p, dtype=np.float64), 0.0, 1.0)
    return entr(p) + entr(1.0 - p)


def entrotaxis_gain(sit, cells) -> np.ndarray:
    r"""G(p), the entropy of the predicted measurement of a stop at each candidate cell, nats:

    .. math:: G(p) = H_b(P_f(p)) + \big(1 - P_f(p)\big)\, H_b(\bar P_p)

    (module docstring).

    Parameters
    ----------
    sit : psgsl_pgm.search.Situation
    cells : (K,) array_like of int
        Flat candidate cells.

    Returns
    -------
    gain : (K,) ndarray of float64
        In [0, ln 3].
    """

    cells = np.asarray(cells)
    post = np.asarray(sit.posterior, dtype=np.float64).ravel()
    p_f, rows = _found_mass(sit, cells)
    a = 1.0 - _detection(sit).miss_probability
    out = np.empty(len(cells))
    for k, (row, found) in enumerate(zip(_hit_rows(sit, cells), rows)):
        hit_mass = float(row @ post) - a * float(row[found] @ post[found])  # Σ p w P
        rest = 1.0 - p_f[k]  # Σ p w
        p_bar = hit_mass / rest if rest > 0 else 0.0
        out[k] = _hb(p_f[k]) + max(rest, 0.0) * _hb(p_bar)
    return out


def choose_entrotaxis(sit):
    """The entrotaxis decision: the best-scoring candidate pose of :func:`entrotaxis_gain` (first maximum in
    lattice order, then heading order), under the situation's scoring rule."""

    cells, drive, pred, tau = _candidates(sit)
    gain = entrotaxis_gain(sit, cells)
    return _best(_score(sit, np.repeat(gain[:, None], tau.shape[1], axis=1), tau), cells, pred, drive, sit)
