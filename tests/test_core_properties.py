"""Property tests (hypothesis, derandomised): invariants of the closed form and of fusion."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from psgsl_pgm import fuse, semantic_information_gain, semantic_source_probability

settings.register_profile("psgsl", derandomize=True, max_examples=60, deadline=None)
settings.load_profile("psgsl")


@st.composite
def problems(draw):
    seed = draw(st.integers(0, 2**32 - 1))
    n = draw(st.integers(1, 60))
    k = draw(st.integers(2, 10))
    rng = np.random.default_rng(seed)
    alpha = draw(st.sampled_from([0.1, 1.0, 10.0]))
    q = rng.dirichlet(np.ones(k) * alpha, size=n)
    lik = rng.dirichlet(np.ones(k))
    prior = rng.dirichlet(np.ones(k)) * 0.9 + 0.1 / k
    return q, lik, prior, rng


@given(problems())
def test_output_is_a_distribution(problem):
    q, lik, prior, _ = problem
    p = semantic_source_probability(q, lik, prior)
    assert p.shape == q.shape[:1] and np.all(p >= 0) and abs(p.sum() - 1) < 1e-12


@given(problems())
def test_uninformative_beliefs_give_a_uniform_semantic_term(problem):
    q, lik, prior, _ = problem
    p = semantic_source_probability(np.tile(prior, (q.shape[0], 1)), lik, prior)
    np.testing.assert_allclose(p, 1.0 / q.shape[0], rtol=1e-12)


@given(problems())
def test_fusing_with_a_uniform_distribution_is_the_identity(problem):
    q, lik, prior, _ = problem
    p = semantic_source_probability(q, lik, prior)
    np.testing.assert_allclose(fuse(p, np.full(p.shape, 1.0 / p.size)), p, rtol=1e-12, atol=1e-300)


@given(problems())
def test_cell_permutation_equivariance(problem):
    q, lik, prior, rng = problem
    perm = rng.permutation(q.shape[0])
    olf = rng.dirichlet(np.ones(q.shape[0]))
    p = semantic_source_probability(q, lik, prior)
    np.testing.assert_allclose(semantic_source_probability(q[perm], lik, prior), p[perm], rtol=1e-12)
    g = semantic_information_gain(q, lik, prior, olfactory=olf)
    np.testing.assert_allclose(semantic_information_gain(q[perm], lik, prior, olfactory=olf[perm]), g[perm], rtol=1e-9, atol=1e-15)


@given(problems())
def test_float32_agrees_with_float64_to_float32_precision(problem):
    q, lik, prior, rng = problem
    q32 = q.astype(np.float32)
    p64 = semantic_source_probability(q32.astype(np.float64), lik, prior)
    p32 = semantic_source_probability(q32, lik, prior)
    assert p32.dtype == np.float32
    np.testing.assert_allclose(p32, p64, rtol=2e-5 * q.shape[1], atol=1e-7 / q.shape[0])
    olf = rng.dirichlet(np.ones(q.shape[0])).astype(np.float32)
    f32 = fuse(olf, p32)
    assert f32.dtype == np.float32
    np.testing.assert_allclose(f32, fuse(olf.astype(np.float64), p64), rtol=5e-5 * q.shape[1], atol=1e-7 / q.shape[0])
