"""Underflow guard for exact inference: the evidence probability of the *scaled* network, in log space.

Exact variable elimination multiplies one factor ≤ 1 per observed cell, so the unnormalised result shrinks
geometrically with n; past the float64 normal range pgmpy normalises subnormal numbers (lost precision) or
0/0 (NaN, silently — from roughly 450 cells on). Every partial product of the elimination dominates the
final unnormalised weight of the same configuration, so it suffices to check that the largest final weight
is a normal float: we compute log p(evidence) of the network as built (same scaling as the CPDs) and refuse
queries whose evidence probability is below :data:`MIN_EVIDENCE`.
"""

from __future__ import annotations

import numpy as np
from scipy.special import logsumexp

from ..core._problem import SemanticGSLProblem
from ._network_b import source_bernoulli

__all__ = ["MIN_EVIDENCE", "check_result", "check_scale", "log_evidence"]

#: Smallest evidence probability (of the scaled network) an exact query accepts: 1e-290 leaves
#: n·m ≤ 1e17 configurations' worth of head-room above the float64 normal minimum 2.2e-308.
MIN_EVIDENCE = 1e-290


def _log_scaled(x: np.ndarray) -> np.ndarray:
    """log(x / max x) along the last axis (the CPD scaling of one likelihood), zeros → -inf."""
    with np.errstate(divide="ignore"):
        return np.log(x) - np.log(x.max(axis=-1, keepdims=True))


def log_evidence(problem: SemanticGSLProblem, network: str) -> float:
    """log p(evidence) in the network built from ``problem`` (``"A"`` or ``"B"``), without normalising.

    Parameters
    ----------
    problem : SemanticGSLProblem
    network : {"A", "B"}

    Returns
    -------
    float
        Natural log of the probability pgmpy's elimination normalises by.

    Raises
    ------
    ValueError
        ``network`` is neither ``"A"`` nor ``"B"``.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.networks import SemanticGSLProblem, log_evidence
    >>> problem = SemanticGSLProblem.random(np.random.default_rng(0), 4, 3)
    >>> a, b = log_evidence(problem, "A"), log_evidence(problem, "B")
    >>> bool(a <= 0.0 and b <= 0.0)                            # likelihoods scaled to at most 1: a probability
    True
    """
    log_lam = np.zeros((problem.n, problem.k))  # Σ_j log p̃(z_cj | o), each observation scaled as in its CPD
    np.add.at(log_lam, problem.observation_cells, _log_scaled(problem.observation_likelihoods))
    lam_max = log_lam.max(axis=1, keepdims=True)
    lam = np.exp(log_lam - lam_max)
    with np.errstate(divide="ignore"):
        log_bg = np.log(lam @ problem.background) + lam_max[:, 0]  # log p̃(z_c | ¬s_c)
        log_src = np.log(lam @ problem.source_likelihood.T) + lam_max  # log p̃(z_c | s_c, γ), (n, m)
        log_gas = np.log(problem.gas_prior) + _log_scaled(problem.gas_observations).sum(axis=0)
        log_g = _log_scaled(problem.olfactory_likelihood)
        if network == "A":
            log_cell = np.log(problem.source_prior) + log_g  # p(S = c) p̃(g | c)
        elif network == "B":
            p = source_bernoulli(problem)
            log_cell = np.log(p) + np.sum(np.log1p(-p)) - np.log1p(-p) + log_g  # p_c Π_{i≠c}(1 − p_i) p̃(g|c)
        else:
            raise ValueError(f"network must be 'A' or 'B', got {network!r}")
    if problem.m == 1:
        log_gas = np.zeros(1)
    terms = log_cell[:, None] + log_gas[None, :] + log_src - log_bg[:, None] + log_bg.sum()
    return float(logsumexp(terms))


def check_scale(problem: SemanticGSLProblem, network: str) -> None:
    """Raise ValueError when an exact query of this network would leave the float64 normal range."""
    log_z = log_evidence(problem, network)
    if log_z < np.log(MIN_EVIDENCE):
        raise ValueError(
            f"exact inference would underflow: the evidence probability of Network {network} is about "
            f"10^{log_z / np.log(10):.0f} (n = {problem.n} cells), below the float64 range pgmpy can "
            f"normalise ({MIN_EVIDENCE:g}); use SemanticGSLProblem.closed_form_posterior() at this size"
        )


def check_result(values: np.ndarray, what: str) -> np.ndarray:
    """Return ``values`` if finite with a positive sum, else raise (pgmpy's silent 0/0 → NaN)."""
    values = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(values)) or not values.sum() > 0:
        raise ValueError(
            f"exact query for {what} returned NaN/inf or an all-zero distribution: the evidence probability "
            "underflowed (or is zero) in variable elimination"
        )
    return values
