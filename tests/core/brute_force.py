"""Independent reference computations for Network A, and the exact line-of-sight geometry (no code shared with
psgsl_pgm).

The model: S ~ π over n cells; γ ~ p(γ); O_c | S = c, γ ~ L[γ]; O_c | S ≠ c ~ β; each observation z_cj of
cell c has likelihood lik[c][j] = p(z_cj | O_c); G | S has likelihood g = p(g | S = c); ζ_j | γ has
likelihood p(ζ_j | γ). Two references:

* :func:`enumerate_posterior` sums the full joint over all k^n object maps (tiny problems only);
* :func:`product_posterior` evaluates p(S = c, γ | ·) ∝ π_c p(γ) Π_j p(ζ_j|γ) p(g|c) Π_n p(z_n | S=c, γ)
  with p(z_n | S = c, γ) = Σ_i p(z_n | o_i) p(o_i | S = c, γ) for every (c, n): O(n² k), in log space,
  without the cancellation of the closed form.

:func:`touches` is the line-of-sight rule's reference: exact integer geometry of a segment and a cell.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
from scipy.special import logsumexp


@dataclass
class Problem:
    L: np.ndarray  # (m, k) p(o | s, γ)
    beta: np.ndarray  # (k,) p(o | ¬s)
    obs: list  # n lists of (k,) likelihood vectors p(z_cj | o)
    g: np.ndarray  # (n,) p(g | S = c)
    pi: np.ndarray  # (n,) source prior
    gas_prior: np.ndarray = field(default_factory=lambda: np.ones(1))  # (m,)
    zeta: list = field(default_factory=list)  # (m,) likelihood vectors p(ζ_j | γ)

    @property
    def n(self):
        return len(self.obs)

    def cell_lik(self) -> np.ndarray:
        """(n, k) p(z_c | o) = Π_j p(z_cj | o)."""
        k = self.beta.shape[0]
        return np.array([np.prod(np.vstack([np.ones(k)] + list(o)), axis=0) for o in self.obs])

    def gas_weights(self) -> np.ndarray:
        """p(γ | ζ) ∝ p(γ) Π_j p(ζ_j | γ)."""
        w = self.gas_prior * np.prod(np.vstack([np.ones_like(self.gas_prior)] + list(self.zeta)), axis=0)
        return w / w.sum()


def random_problem(rng, n, k, m=1, *, max_obs=3, zeros=True, uniform_prior=False) -> Problem:
    L = rng.dirichlet(np.ones(k), size=m)
    if zeros and k > 2:
        L[:, rng.integers(k)] = 0.0  # a class that never emits (per gas)
        L /= L.sum(axis=1, keepdims=True)
    beta = rng.dirichlet(np.ones(k)) * 0.9 + 0.1 / k  # strictly positive background
    obs = [[rng.random(k) ** 2 for _ in range(rng.integers(0, max_obs + 1))] for _ in range(n)]
    if zeros and n > 1:
        lik = rng.random(k)
        lik[rng.integers(k)] = 0.0  # an observation that rules a class out
        obs[0].append(lik)
    g = rng.random(n) + 0.05
    pi = np.full(n, 1.0 / n) if uniform_prior else rng.dirichlet(np.ones(n) * 2)
    gas_prior = rng.dirichlet(np.ones(m))
    zeta = [rng.random(m) + 0.01 for _ in range(rng.integers(0, 3))] if m > 1 else []
    return Problem(L, beta, obs, g, pi, gas_prior, zeta)


def enumerate_posterior(p: Problem, *, off_ontology: float = 0.0) -> np.ndarray:
    """p(S = c | z, ζ, g) by summing the joint over all k^n maps, all sources and all gases.

    ``off_ontology`` = ε adds a latent Ω ∈ {on, off}, p(off) = ε, summed over too: an *off* source is emitted by
    whatever is in its cell, whose object then follows β like every other cell's."""
    n, k = p.n, p.beta.shape[0]
    zl = p.cell_lik()
    gas = p.gas_prior * np.prod(np.vstack([np.ones_like(p.gas_prior)] + list(p.zeta)), axis=0)
    post = np.zeros(n)
    for o_map in itertools.product(range(k), repeat=n):
        o_map = np.array(o_map)
        z_term = np.prod(zl[np.arange(n), o_map])
        if z_term == 0:
            continue
        for c in range(n):
            for gi in range(len(gas)):
                for p_omega, source_cpd in ((1.0 - off_ontology, p.L[gi]), (off_ontology, p.beta)):
                    o_term = np.prod(np.where(np.arange(n) == c, source_cpd[o_map], p.beta[o_map]))
                    post[c] += p.pi[c] * p.g[c] * gas[gi] * p_omega * o_term * z_term
    return post / post.sum()


def _log_cell_factor(p: Problem) -> np.ndarray:
    """(m, n_sources, n_cells) log p(z_n | S = c, γ)."""
    zl = p.cell_lik()
    with np.errstate(divide="ignore"):
        on_source = np.log(zl @ p.L.T).T  # (m, n): p(z_n | S = n, γ)
        background = np.log(zl @ p.beta)  # (n,): p(z_n | S ≠ n)
    n = p.n
    out = np.broadcast_to(background, (p.L.shape[0], n, n)).copy()
    idx = np.arange(n)
    out[:, idx, idx] = on_source
    return out


def log_joint_s_gamma(p: Problem) -> np.ndarray:
    """(m, n) log p(S = c, γ, z, ζ, g) up to a constant."""
    with np.errstate(divide="ignore"):
        log_gas = np.log(p.gas_weights())
        return log_gas[:, None] + np.log(p.pi * p.g)[None, :] + _log_cell_factor(p).sum(axis=2)


def product_posterior(p: Problem) -> np.ndarray:
    lj = log_joint_s_gamma(p)
    ls = logsumexp(lj, axis=0)
    return np.exp(ls - logsumexp(ls))


def gas_posterior(p: Problem) -> np.ndarray:
    lj = log_joint_s_gamma(p)
    lg = logsumexp(lj, axis=1)
    return np.exp(lg - logsumexp(lg))


def joint_s_on(p: Problem, cell: int) -> np.ndarray:
    """(n, k) exact p(S = c, O_cell = i | all evidence)."""
    zl = p.cell_lik()
    lcf = _log_cell_factor(p)  # (m, n, n)
    with np.errstate(divide="ignore"):
        rest = lcf.sum(axis=2) - lcf[:, :, cell]  # Π over cells other than `cell`
        # p(O_cell = i, z_cell | S = c, γ) = p(z_cell | o_i) p(o_i | S = c, γ)
        o_given = np.broadcast_to(p.beta, (p.L.shape[0], p.n, p.beta.size)).copy()
        o_given[:, cell, :] = p.L
        term = np.log(zl[cell])[None, None, :] + np.log(o_given)
        lj = (np.log(p.gas_weights())[:, None, None] + np.log(p.pi * p.g)[None, :, None] + rest[:, :, None] + term)
    lj = logsumexp(lj, axis=0)
    return np.exp(lj - logsumexp(lj))


def entropy(p) -> float:
    p = np.asarray(p).ravel()
    p = p[p > 0]
    return float(-(p * np.log(p)).sum())


def mutual_information(p: Problem, cell: int, *, predictive="exact") -> float:
    """I(S; O_cell) from the exact joint; ``predictive="paper"`` weights by p(o | z_cell) instead."""
    joint = joint_s_on(p, cell)
    ps = joint.sum(axis=1)
    po = joint.sum(axis=0)
    h_cond = np.array([entropy(joint[:, i] / po[i]) if po[i] > 0 else 0.0 for i in range(joint.shape[1])])
    if predictive == "exact":
        weights = po
    else:
        zl = p.cell_lik()[cell] * p.beta
        weights = zl / zl.sum()  # p(o_cell | z_cell) under the prior β
    return entropy(ps) - float(weights @ h_cond)


def touches(a, b, r, c) -> bool:
    """Does the segment between the centres of cells a and b meet the closed square of cell (r, c)?
    Exact integer geometry in doubled coordinates (independent of the traversal in psgsl_pgm.geometry._sight)."""
    ax, ay, bx, by = 2 * a[1] + 1, 2 * a[0] + 1, 2 * b[1] + 1, 2 * b[0] + 1
    x0, x1, y0, y1 = 2 * c, 2 * c + 2, 2 * r, 2 * r + 2
    if max(ax, bx) < x0 or min(ax, bx) > x1 or max(ay, by) < y0 or min(ay, by) > y1:
        return False
    s = [np.sign((bx - ax) * (y - ay) - (by - ay) * (x - ax)) for x in (x0, x1) for y in (y0, y1)]
    return not (all(v > 0 for v in s) or all(v < 0 for v in s))
