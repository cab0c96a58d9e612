r"""The robot's belief about the gas, p(γ | ζ_1:t), from an electronic nose's classifications.

An electronic nose names a gas ζ_t at each reading, with a strength b_t (the length of its response); its
confusion p(ζ | γ, b) depends on the strength (weak readings classify worse). Given the gas, the readings'
classification errors are independent (each reading's noise is its own), so

.. math:: p(\gamma \mid \zeta_{1:t}) \propto p(\gamma) \prod_{u \le t} p(\zeta_u \mid \gamma, b_u),

with b_u the strength bin of reading u. A reading the device does not classify (below its detection limit)
changes nothing: whether it classifies depends on the strength only, which is the same for every gas at the
same concentration (the e-nose's patterns are of equal length). Treating the strength as given and not as
evidence about γ is exact for the same reason: its distribution does not depend on the gas.

The belief is the weight ``gas_probs`` of the paper's mixture p(s | z, ζ) = Σ_γ p(γ | ζ) p(s | z, γ)
(Sec. "Probabilistic Gas Classification", :func:`psgsl_pgm.semantic_source_probability`).
"""

from __future__ import annotations

import numpy as np

from .._shared._validate import as_float_array, check_distribution, describe, names

__all__ = ["GasBelief"]


class GasBelief:
    r""":math:`p(\gamma \mid \zeta_{1:t})` over ``gases``, updated by classified readings.

    An electronic nose names a gas :math:`\zeta_u` at each reading u; :math:`b_u` is the bin of the reading's
    strength (weak readings classify worse). Given the gas, the readings' classification errors are
    independent, so

    .. math:: p(\gamma \mid \zeta_{1:t}) \propto p(\gamma) \prod_{u \le t} p(\zeta_u \mid \gamma, b_u).

    A reading the device does not classify changes nothing. The belief is the weight ``gas_probs`` of the
    gas mixture of :func:`psgsl_pgm.semantic_source_probability` (eq. (27) of the paper).

    Parameters
    ----------
    gases : sequence of str
        The gases γ, in the order of ``confusion``'s rows and columns.
    confusion : (B, m, m) array_like
        :math:`p(\zeta \mid \gamma, b)`: ``confusion[b, g, z]`` the probability that a reading of strength bin
        b of gas g is named z; every row ``confusion[b, g]`` sums to one.
    edges : (B + 1,) array_like
        Increasing strength-bin edges (the e-nose's response units); a reading of strength s is in bin b when
        ``edges[b] <= s < edges[b + 1]`` (the last edge may be ``inf``).
    prior : (m,) array_like, optional
        :math:`p(\gamma)`; uniform when omitted.

    Examples
    --------
    >>> conf = np.array([[[0.8, 0.2], [0.3, 0.7]]])           # one strength bin, two gases
    >>> belief = GasBelief(("smoke", "ethanol"), conf, [0.0, np.inf])
    >>> belief.update("smoke", 1.0).round(4).tolist()          # ∝ (0.5 · 0.8, 0.5 · 0.3)
    [0.7273, 0.2727]
    >>> belief.update(None, 0.1).round(4).tolist()             # no classification: no change
    [0.7273, 0.2727]
    """

    def __init__(self, gases, confusion, edges, *, prior=None):
        self.gases = names(gases, "gases")
        m = len(self.gases)
        conf = as_float_array(confusion, "confusion", dtype=np.float64)
        if conf.ndim != 3 or conf.shape[1:] != (m, m):
            raise ValueError(f"confusion must have shape (bins, {m}, {m}) for the gases {self.gases}, got "
                             f"{describe(conf)}")
        check_distribution(conf, "confusion (each row p(ζ | γ, strength bin))")
        e = as_float_array(edges, "edges", dtype=np.float64, ndim=1)
        if e.shape != (conf.shape[0] + 1,) or np.isnan(e).any() or not (np.diff(e) > 0).all() or e[0] < 0:
            raise ValueError(f"edges must be {conf.shape[0] + 1} increasing strengths from >= 0 (one bin per "
                             f"confusion table), got {describe(e)}")
        self.confusion, self.edges = conf, e
        if prior is None:
            p = np.full(m, 1.0 / m)
        else:
            p = as_float_array(prior, "prior", dtype=np.float64, ndim=1)
            if p.shape != (m,):
                raise ValueError(f"prior must have shape ({m},), one entry per gas, got {describe(p)}")
            check_distribution(p, "prior")
        with np.errstate(divide="ignore"):
            self._log = np.log(p)
        self.n_readings = 0

    @property
    def probs(self) -> np.ndarray:
        r"""(m,) :math:`p(\gamma \mid \zeta_{1:t})`, float64, summing to one."""
        a = self._log - self._log.max()
        p = np.exp(a)
        return p / p.sum()

    def bin_of(self, strength: float) -> int:
        """The strength bin of a reading (strengths outside the edges: the nearest bin)."""
        b = int(np.searchsorted(self.edges, float(strength), side="right")) - 1
        return min(max(b, 0), len(self.edges) - 2)

    def likelihood(self, label, strength: float) -> np.ndarray:
        r"""(m,) :math:`p(\zeta = \text{label} \mid \gamma, b(\text{strength}))` for every γ; ones for ``label``
        None."""
        if label is None:
            return np.ones(len(self.gases))
        if label not in self.gases:
            raise ValueError(f"label must be one of the gases {self.gases} or None, got {label!r}")
        if not np.isfinite(strength) or strength < 0:
            raise ValueError(f"strength must be a finite, non-negative response length, got {strength!r}")
        return self.confusion[self.bin_of(strength), :, self.gases.index(label)].copy()

    def update(self, label, strength: float) -> np.ndarray:
        """Assimilate one reading named ``label`` (a gas, or None: unclassified) of ``strength``; returns
        :attr:`probs`."""
        if label is not None:
            with np.errstate(divide="ignore"):
                log = self._log + np.log(self.likelihood(label, strength))
            if not np.isfinite(log).any():
                raise ValueError(f"a reading named {label!r} is impossible under every gas still possible")
            self._log = log
            self.n_readings += 1
        return self.probs

    def __repr__(self) -> str:
        return f"GasBelief({dict(zip(self.gases, self.probs.round(3).tolist()))}, readings={self.n_readings})"
