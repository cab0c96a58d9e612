"""How wrong is p(o_ni | s_c) ≈ p(o_ni)? The paper's approximation against the exact posterior, versus n.

With the class prior ρ = β = p(o | ¬s) the closed form (eqs. (20) and
(11)) is exact in Network A; with the marginal ρ = p(o) = L/n + (1 − 1/n) β it is the
paper's approximation, whose total-variation error shrinks like 1/n (``proofs/check_marginal_approximation.py``).
"""

from __future__ import annotations

import numpy as np

from .._shared._validate import index as as_index
from ..core._problem import SemanticGSLProblem

__all__ = ["approximation_error"]


def approximation_error(cell_counts, *, n_problems=20, k=4, seed=0, max_observations=2, reference="closed_form"):
    """Mean total-variation distance to the exact posterior p(s | g, z), over seeded random problems.

    For each number of cells n and each problem i, a random :class:`~psgsl_pgm.networks.SemanticGSLProblem`
    (uniform source prior, one gas, ``k`` classes, 0 … ``max_observations`` observations per cell, random
    olfactory likelihood) is drawn from ``numpy.random.default_rng([seed, n, i])`` — the same problems
    whatever the reference — and two closed forms are compared with the exact posterior:

    * ``"marginal"``: class prior p(o) (the paper's approximation p(o_ni | s_c) ≈ p(o_ni));
    * ``"background"``: class prior β = p(o | ¬s) (exact: its error is round-off).

    TV(p, q) = ½ Σ_c abs(p_c − q_c).

    Parameters
    ----------
    cell_counts : sequence of int
        The numbers of cells n (each >= 2).
    n_problems : int, default 20, keyword-only
        Random problems per n.
    k : int, default 4, keyword-only
        Object classes.
    seed : int, default 0, keyword-only
    max_observations : int, default 2, keyword-only
    reference : {"closed_form", "pgmpy"}, keyword-only
        The exact posterior: ``"closed_form"`` = :meth:`SemanticGSLProblem.closed_form_posterior` with
        ``class_prior="background"`` (exact, fast for any n); ``"pgmpy"`` = variable elimination in Network A
        (independent, slow beyond a few hundred cells).

    Returns
    -------
    result : dict
        ``"cells"`` (len,) int array; ``"marginal"`` and ``"background"`` (len,) mean TV per n.

    Raises
    ------
    ValueError
        Bad counts or an unknown ``reference``.

    Examples
    --------
    >>> from psgsl_pgm.teaching import approximation_error
    >>> err = approximation_error([4, 40], n_problems=5)
    >>> bool(err["marginal"][1] < err["marginal"][0]), bool(err["background"].max() < 1e-12)
    (True, True)
    """
    if reference not in ("closed_form", "pgmpy"):
        raise ValueError(f"reference must be 'closed_form' or 'pgmpy', got {reference!r}")
    counts = [as_index(n, "cell_counts entries", minimum=2) for n in np.atleast_1d(np.asarray(cell_counts)).tolist()]
    if not counts:
        raise ValueError("cell_counts must list at least one number of cells")
    n_problems = as_index(n_problems, "n_problems", minimum=1)
    k = as_index(k, "k", minimum=2)
    seed = as_index(seed, "seed")
    max_observations = as_index(max_observations, "max_observations")

    tv = np.zeros((2, len(counts)))
    for a, n in enumerate(counts):  # loops over sizes and problems, each vectorised over cells
        for i in range(n_problems):
            problem = SemanticGSLProblem.random(np.random.default_rng([seed, n, i]), n, k, uniform_prior=True,
                                                max_observations=max_observations, zero_fraction=0.0)
            if reference == "pgmpy":
                # pgmpy is an optional extra ("networks"): imported only when this reference is asked for
                from ..networks import build_network_a, exact_source_posterior

                exact = exact_source_posterior(build_network_a(problem), problem)
            else:
                exact = problem.closed_form_posterior(class_prior="background")  # exact with ρ = β
            for b, rho in enumerate(("marginal", "background")):
                approx = problem.closed_form_posterior(class_prior=rho)
                tv[b, a] += 0.5 * np.abs(approx - exact).sum() / n_problems  # TV = ½ Σ_c |p_c − q_c|
    return {"cells": np.array(counts), "marginal": tv[0], "background": tv[1]}
