"""Property tests (hypothesis, derandomised): invariants of the closed form and of fusion."""

from typing import NamedTuple

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from psgsl_pgm import fuse, semantic_information_gain, semantic_source_probability

settings.register_profile("psgsl", derandomize=True, max_examples=60, deadline=None)
settings.load_profile("psgsl")

U32 = float(np.finfo(np.float32).eps) / 2  # float32's unit roundoff, 2^-24


class Problem(NamedTuple):
    q: np.ndarray  # (n, k) class beliefs
    lik: np.ndarray  # (k,) p(o | s)
    prior: np.ndarray  # (k,) p(o), bounded away from 0
    perm: np.ndarray  # (n,) a permutation of the cells
    olf: np.ndarray  # (n,) an olfactory distribution


def _simplex(draw, shape, sharpness=1.0):
    """Rows on the simplex from bounded positive floats (hypothesis.extra.numpy, so failures shrink)."""
    w = draw(arrays(np.float64, shape, elements=st.floats(1e-3, 1.0))) ** sharpness
    return w / w.sum(axis=-1, keepdims=True)


@st.composite
def problems(draw):
    n = draw(st.integers(1, 60))
    k = draw(st.integers(2, 10))
    sharpness = draw(st.sampled_from([1.0, 4.0, 12.0]))  # from flat to nearly one-hot beliefs
    q = _simplex(draw, (n, k), sharpness)
    lik = _simplex(draw, (k,))
    prior = _simplex(draw, (k,)) * 0.9 + 0.1 / k
    perm = np.array(draw(st.permutations(range(n))), dtype=np.intp)
    olf = _simplex(draw, (n,))
    return Problem(q, lik, prior, perm, olf)


@given(problems())
def test_output_is_a_distribution(problem):
    q, lik, prior = problem.q, problem.lik, problem.prior
    p = semantic_source_probability(q, lik, prior)
    assert p.shape == q.shape[:1] and np.all(p >= 0) and abs(p.sum() - 1) < 1e-12


@given(problems())
def test_uninformative_beliefs_give_a_uniform_semantic_term(problem):
    q, lik, prior = problem.q, problem.lik, problem.prior
    p = semantic_source_probability(np.tile(prior, (q.shape[0], 1)), lik, prior)
    np.testing.assert_allclose(p, 1.0 / q.shape[0], rtol=1e-12)


@given(problems())
def test_fusing_with_a_uniform_distribution_is_the_identity(problem):
    q, lik, prior = problem.q, problem.lik, problem.prior
    p = semantic_source_probability(q, lik, prior)
    np.testing.assert_allclose(fuse(p, np.full(p.shape, 1.0 / p.size)), p, rtol=1e-12, atol=1e-300)


@given(problems())
def test_cell_permutation_equivariance(problem):
    q, lik, prior, perm, olf = problem
    p = semantic_source_probability(q, lik, prior)
    np.testing.assert_allclose(semantic_source_probability(q[perm], lik, prior), p[perm], rtol=1e-12)
    g = semantic_information_gain(q, lik, prior, olfactory=olf)
    np.testing.assert_allclose(semantic_information_gain(q[perm], lik, prior, olfactory=olf[perm]), g[perm], rtol=1e-9, atol=1e-15)


@given(problems())
def test_float32_agrees_with_float64_to_float32_precision(problem):
    q, lik, prior, _, olf64 = problem
    q32 = q.astype(np.float32)
    p64 = semantic_source_probability(q32.astype(np.float64), lik, prior)
    p32 = semantic_source_probability(q32, lik, prior)
    assert p32.dtype == np.float32
    # The compiled pass sums a cell's k terms q_ci ρ_i in float32 (ρ_i rounded to float32, each product rounded):
    # relative error ≤ (k + 1)·u per weight w_c, u = 2^-24 (first order); the normaliser Σ_c w_c is a weighted
    # mean of those errors (≤ (k + 1)·u), and the quotient rounds once (u): |p32 / p64 − 1| ≤ (2k + 3)·u.
    bound = (2 * q.shape[1] + 3) * U32
    np.testing.assert_allclose(p32, p64, rtol=bound, atol=0)
    olf = olf64.astype(np.float32)
    f32 = fuse(olf, p32)
    assert f32.dtype == np.float32
    # fusion of exact float32 inputs runs in float64 and rounds once: p32's error twice (cell and normaliser) + u
    np.testing.assert_allclose(f32, fuse(olf.astype(np.float64), p64), rtol=2 * bound + U32, atol=0)
