r"""The ontology side of the semantic term: validated :math:`p(o \mid s, \gamma)`, :math:`p(\gamma \mid \zeta)` and
:math:`p(o)`, reduced to one k-vector.

Eq. (20) and its gas-mixture form (Sec. "Probabilistic Gas Classification") are linear in
the class beliefs:

.. math:: p(s_c \mid z, \zeta) \propto \sum_\gamma p(\gamma \mid \zeta) \sum_i \frac{p(o_{ci} \mid z_c)}{p(o_{ci})}\,
          p(o_{ci} \mid s_c, \gamma) = p(o_c \mid z_c) \cdot \rho

with the *class ratio* :math:`\rho_i = \sum_\gamma p(\gamma \mid \zeta)\, p(o_i \mid s, \gamma) / p(o_i)`.
Everything per cell is then a dot product with ρ; this module builds and validates ρ once.
:func:`likelihood_ratio` is the division :math:`p(o \mid \cdot) / p(o)` itself, for ρ and for the room evidence
:math:`p(o \mid \text{room}) / p(o)`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._shared._validate import as_float_array, check_distribution, check_nonnegative, describe

__all__ = ["ClassRatio", "class_ratio", "likelihood_ratio"]


@dataclass(frozen=True)
class ClassRatio:
    """ρ = Σ_γ p(γ|ζ) p(o | s, γ) / p(o), scaled so that ``max(rho) == 1`` (posteriors are scale-free).

    Attributes
    ----------
    rho : (k,) ndarray
        Scaled class ratio, float64; zero for classes with zero prior.
    class_prior : (k,) ndarray
        The validated p(o).
    zero_prior : (k,) ndarray of bool
        Classes with p(o) = 0; a cell belief must give them zero mass.
    """

    rho: np.ndarray
    class_prior: np.ndarray
    zero_prior: np.ndarray

    @property
    def k(self) -> int:
        return self.rho.shape[0]


#: the last validated ontology inputs (float64 arrays, by shape and bytes) -> their ClassRatio: a closed loop
#: evaluates the semantic term and its information gain with the same k-vectors several times per stop
_MEMO: dict = {}
_MEMO_SIZE = 8


def _memo_key(*arrays):
    """The inputs' exact identity (shape and bytes) when every one is a small float64 ndarray (or None), else None."""
    key = []
    for a in arrays:
        if a is None:
            key.append(None)
        elif type(a) is np.ndarray and a.dtype == np.float64 and a.size <= 4096:
            key.append((a.shape, a.tobytes()))
        else:
            return None
    return tuple(key)


def class_ratio(source_likelihood, class_prior, gas_probs=None) -> ClassRatio:
    """Validate the ontology inputs and return the class ratio ρ (see module docstring).

    Parameters
    ----------
    source_likelihood : (k,) or (m, k) array_like
        p(o | s) for one gas, or p(o | s, γ) for m gas types (each row sums to 1).
    class_prior : (k,) array_like
        p(o), the prior under which the class beliefs were computed (sums to 1).
    gas_probs : (m,) array_like, optional
        p(γ | ζ); required when ``source_likelihood`` has m > 1 rows.

    Inputs that passed validation before (the same float64 values bit for bit) return copies of the ρ computed
    then, without validating again.
    """
    key = _memo_key(source_likelihood, class_prior, gas_probs)
    done = _MEMO.get(key) if key is not None else None
    if done is None:
        done = _class_ratio(source_likelihood, class_prior, gas_probs)
        if key is not None:
            while len(_MEMO) >= _MEMO_SIZE:
                _MEMO.pop(next(iter(_MEMO)))
            _MEMO[key] = done = ClassRatio(done.rho, done.class_prior.copy(), done.zero_prior)  # not the caller's
    return ClassRatio(done.rho.copy(), done.class_prior.copy(), done.zero_prior.copy())


def _class_ratio(source_likelihood, class_prior, gas_probs) -> ClassRatio:
    lik = as_float_array(source_likelihood, "source_likelihood", dtype=np.float64)
    if lik.ndim not in (1, 2):
        raise ValueError(f"source_likelihood must have shape (k,) or (m, k), got {describe(lik)}")
    rows = lik if lik.ndim == 2 else lik[None, :]
    m, k = rows.shape
    check_distribution(rows, "source_likelihood (each row, p(o | s, γ))")
    prior = as_float_array(class_prior, "class_prior", dtype=np.float64, ndim=1)
    if prior.shape != (k,):
        raise ValueError(f"class_prior must have shape ({k},) like source_likelihood's classes, got {describe(prior)}")
    check_distribution(prior, "class_prior")

    if gas_probs is None:
        if lik.ndim == 2 and m > 1:
            raise ValueError(
                f"gas_probs (shape ({m},), p(γ | ζ)) is required when source_likelihood has {m} gas rows"
            )
        mix = rows[0]
    else:
        if lik.ndim == 1:
            raise ValueError(
                "gas_probs was given but source_likelihood has shape (k,) for a single gas; pass p(o | s, γ) "
                f"as an (m, k) array, got {describe(lik)}"
            )
        gas = as_float_array(gas_probs, "gas_probs", dtype=np.float64, ndim=1)
        if gas.shape != (m,):
            raise ValueError(f"gas_probs must have shape ({m},), one entry per gas row, got {describe(gas)}")
        check_distribution(gas, "gas_probs")
        mix = gas @ rows  # Σ_γ p(γ|ζ) p(o | s, γ)

    zero = prior == 0
    if np.any(zero & (rows > 0).any(axis=0)):
        bad = np.flatnonzero(zero & (rows > 0).any(axis=0)).tolist()
        raise ValueError(
            f"class_prior is zero for classes {bad} to which source_likelihood gives positive probability; "
            "p(o | z) / p(o) is undefined there — give those classes a positive prior"
        )
    rho = likelihood_ratio(mix, prior, zero)  # ρ_i = p(o_i | s) / p(o_i)
    rho /= rho.max()  # scale-free; keeps Σ over 1e7 cells far from overflow even for p(o_i) ~ 1e-300
    check_nonnegative(rho, "class ratio p(o|s)/p(o)")
    return ClassRatio(rho=rho, class_prior=prior, zero_prior=zero)


def likelihood_ratio(num: np.ndarray, prior: np.ndarray, zero: np.ndarray) -> np.ndarray:
    """``num / prior`` along the last axis (each row a likelihood over the k classes), 0 where ``zero``.

    A row whose ratio would exceed float64 (a prior of 1e-310 under a likelihood of 0.5) is computed in log space
    and scaled to a maximum of 1 — a likelihood row means the same at any scale. Every other row is the plain
    quotient.

    Parameters
    ----------
    num : (..., k) ndarray
        p(o | ·), finite and non-negative.
    prior : (k,) ndarray
        p(o), finite and non-negative.
    zero : (k,) ndarray of bool
        Classes whose ratio is set to 0 (``prior == 0``, where ``num`` is 0 too).
    """
    out = np.zeros(np.broadcast_shapes(num.shape, prior.shape))
    with np.errstate(over="ignore"):
        np.divide(num, prior, out=out, where=~zero)
    rows = out.reshape(-1, out.shape[-1])
    big = ~np.isfinite(rows).all(axis=-1)
    if big.any():
        with np.errstate(divide="ignore"):
            logs = np.log(np.broadcast_to(num, out.shape).reshape(rows.shape)[big]) - np.log(np.where(zero, 1.0, prior))
        logs[:, zero] = -np.inf
        rows[big] = np.exp(logs - logs.max(axis=-1, keepdims=True))
    return out
