"""approximation_error (the teaching API): references agree, the exact closed form has round-off error only, bad
input is refused. That the marginal error shrinks like 1/n is the property of proofs/check_marginal_approximation.py
(derivation) and tests/core/test_core_exactness.py (through the closed form's API)."""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm.networks import SemanticGSLProblem
from psgsl_pgm.teaching import approximation_error


def test_references_agree_and_background_is_exact():
    cells = [3, 8, 20]
    fast = approximation_error(cells, n_problems=4, seed=7)
    slow = approximation_error(cells, n_problems=4, seed=7, reference="pgmpy")  # independent: pgmpy VE
    np.testing.assert_array_equal(fast["cells"], cells)
    np.testing.assert_allclose(fast["marginal"], slow["marginal"], rtol=1e-9, atol=0)
    assert fast["background"].max() == 0.0  # compared with itself
    assert slow["background"].max() < 1e-13  # the closed form with β against pgmpy: round-off
    assert fast["marginal"].min() > 1e-4


def test_matches_a_direct_computation():
    n, i = 6, 1
    problem = SemanticGSLProblem.random(np.random.default_rng([3, n, i]), n, 4, uniform_prior=True,
                                        max_observations=2, zero_fraction=0.0)
    tv = 0.5 * np.abs(problem.closed_form_posterior(class_prior="marginal") - problem.closed_form_posterior()).sum()
    got = approximation_error([n], n_problems=2, seed=3)["marginal"][0]
    other = SemanticGSLProblem.random(np.random.default_rng([3, n, 0]), n, 4, uniform_prior=True,
                                      max_observations=2, zero_fraction=0.0)
    tv0 = 0.5 * np.abs(other.closed_form_posterior(class_prior="marginal") - other.closed_form_posterior()).sum()
    np.testing.assert_allclose(got, (tv + tv0) / 2, rtol=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    ({"cell_counts": [1]}, "cell_counts"), ({"cell_counts": []}, "at least one"),
    ({"cell_counts": [4], "n_problems": 0}, "n_problems"), ({"cell_counts": [4], "k": 1}, "k must"),
    ({"cell_counts": [4], "reference": "exact"}, "reference"), ({"cell_counts": [4.5]}, "cell_counts"),
])
def test_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        approximation_error(**kwargs)
