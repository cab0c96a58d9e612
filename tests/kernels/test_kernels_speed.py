"""The compiled single-pass kernels (psgsl_pgm.kernels._belief): exact where products underflow, independent of how
the work is split between threads, validating as strictly as separate NumPy passes, float32 kept float32."""

import tracemalloc

import numpy as np
import pytest
from scipy.special import logsumexp

from psgsl_pgm import fuse, semantic_information_gain, semantic_source_probability
from psgsl_pgm.kernels import _belief as _kernel

N_BIG = 3 * _kernel.CHUNK + 17  # several chunks, the last one partial


def _log_space_reference(posteriors, prior=None):
    """Σ_j log p_j − (m−1) log prior, normalised with logsumexp (the textbook log-space fusion)."""
    with np.errstate(divide="ignore"):
        log_p = np.sum([np.log(np.asarray(p, dtype=np.float64)) for p in posteriors], axis=0)
        if prior is not None:
            log_p -= (len(posteriors) - 1) * np.log(prior)
    return np.exp(log_p - logsumexp(log_p))


def _normalised(x):
    return x / x.sum()


def test_fusion_of_2e6_cells_at_1e_300_is_exact_and_never_nan():
    """Products of 1e-300 entries (1e-600) underflow in linear space; those cells go to log space."""
    n = 2_000_000
    rng = np.random.default_rng(0)
    a, b = np.full(n, 1e-300), np.full(n, 1e-300)
    big_a = rng.choice(n, 1000, replace=False)
    big_b = np.union1d(big_a[:300], rng.choice(n, 700, replace=False))
    a[big_a] = rng.random(1000)
    b[big_b] = rng.random(big_b.size)
    a, b = _normalised(a), _normalised(b)
    both = np.intersect1d(big_a, big_b)
    assert both.size > 0  # mixed: some cells linear, the rest in log space
    got = fuse(a, b)
    want = _log_space_reference([a, b])
    assert np.all(np.isfinite(got)) and abs(got.sum() - 1) < 1e-12
    normal = want > np.finfo(float).tiny
    np.testing.assert_allclose(got[normal], want[normal], rtol=1e-12, atol=0)
    # disjoint supports of the large entries: every product is below 2^-1000, no cell is linear
    b2 = np.full(n, 1e-300)
    b2[np.setdiff1d(np.arange(5000), big_a)[:500]] = 1.0
    b2 = _normalised(b2)
    got2 = fuse(a, b2)
    want2 = _log_space_reference([a, b2])
    assert np.all(np.isfinite(got2)) and abs(got2.sum() - 1) < 1e-12
    normal2 = want2 > np.finfo(float).tiny
    np.testing.assert_allclose(got2[normal2], want2[normal2], rtol=1e-12, atol=0)


def test_fusion_with_a_tiny_prior_overflows_to_log_space_exactly():
    """÷ p(s)^(m−1) with p(s) = 1e-200 and m = 3 is 1e400: those cells are recomputed in log space."""
    rng = np.random.default_rng(1)
    n = N_BIG
    prior = rng.random(n)
    prior[:50] = 1e-200
    prior = _normalised(prior)
    posts = [_normalised(prior * rng.random(n)) for _ in range(3)]
    got = fuse(*posts, prior=prior)
    want = _log_space_reference(posts, prior)
    normal = want > np.finfo(float).tiny
    np.testing.assert_allclose(got[normal], want[normal], rtol=1e-12, atol=0)
    assert np.all(np.isfinite(got)) and abs(got.sum() - 1) < 1e-12


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_results_do_not_depend_on_how_the_chunks_are_split_between_threads(monkeypatch, dtype):
    rng = np.random.default_rng(2)
    q = rng.dirichlet(np.ones(6) * 0.5, size=(N_BIG, 2)).astype(dtype)
    lik, prior = rng.dirichlet(np.ones(6)), rng.dirichlet(np.ones(6) * 3)
    olf = rng.dirichlet(np.ones(2 * N_BIG)).reshape(N_BIG, 2)

    def everything():
        sem = semantic_source_probability(q, lik, prior)
        return [
            sem,
            semantic_source_probability(q, lik, prior, column_axis=1),
            fuse(olf.astype(dtype), sem),
            semantic_information_gain(q, lik, prior, olfactory=olf),
            semantic_information_gain(q, lik, prior, olfactory=olf, predictive="exact"),
        ]

    monkeypatch.setattr(_kernel, "PARALLEL_MIN", 1 << 62)
    serial = everything()
    monkeypatch.setattr(_kernel, "PARALLEL_MIN", 0)
    monkeypatch.setattr(_kernel, "_THREADS", 3)  # three uneven ranges of chunks
    monkeypatch.setattr(_kernel, "_POOL", None)
    split = everything()
    for s, p in zip(serial, split):
        assert s.dtype == p.dtype
        np.testing.assert_array_equal(s, p)


def test_run_hands_every_chunk_to_exactly_one_thread_and_a_slow_thread_takes_fewer(monkeypatch):
    import threading
    import time

    monkeypatch.setattr(_kernel, "_THREADS", 2)
    monkeypatch.setattr(_kernel, "_POOL", None)
    caller = threading.get_ident()
    taken = []

    def kernel(c0, c1):  # the calling thread is slowed, as a core busy with other work would be
        taken.append((c0, c1, threading.get_ident()))
        time.sleep(0.05 if threading.get_ident() == caller else 0.001)

    n = 64 * _kernel.CHUNK - 5
    _kernel.run(kernel, n, _kernel.PARALLEL_MIN)
    ranges = sorted((c0, c1) for c0, c1, _ in taken)
    assert ranges[0][0] == 0 and ranges[-1][1] == _kernel.n_chunks(n)
    assert all(a[1] == b[0] and a[0] < a[1] for a, b in zip(ranges, ranges[1:]))  # a partition, no gap or overlap
    assert len(ranges) == _kernel.SPLITS * 2
    by_caller = sum(1 for *_, t in taken if t == caller)
    assert by_caller < _kernel.SPLITS  # fewer than the half a static split would have given it
    taken.clear()
    _kernel.run(kernel, n, _kernel.PARALLEL_MIN - 1)  # below the threshold: one call on the calling thread
    assert taken == [(0, _kernel.n_chunks(n), caller)]


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize(
    "bad, match",
    [
        (np.nan, r"class_probs must be finite, got nan at index \(%d, 3\)"),
        (np.inf, r"class_probs must be finite, got inf at index \(%d, 3\)"),
        (-np.inf, r"class_probs must be finite, got -inf at index \(%d, 3\)"),
        (-1e-30, r"class_probs must be non-negative .*-1(\.0*\d*)?e-30 at index \(%d, 3\)"),
    ],
)
def test_a_bad_entry_in_the_last_chunk_is_found_and_named(dtype, bad, match):
    rng = np.random.default_rng(3)
    q = rng.dirichlet(np.ones(5), size=N_BIG).astype(dtype)
    row = N_BIG - 2
    q[row, 3] = bad
    for fn in (semantic_source_probability, semantic_information_gain):
        with pytest.raises(ValueError, match=match % row):
            fn(q, np.full(5, 0.2), np.full(5, 0.2))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_row_sum_off_in_the_last_chunk_names_the_worst_cell(dtype):
    rng = np.random.default_rng(4)
    q = rng.dirichlet(np.ones(5), size=N_BIG).astype(dtype)
    q[N_BIG - 5] *= 1.01
    q[N_BIG - 3] *= 1.02  # the worst
    for fn in (semantic_source_probability, semantic_information_gain):
        with pytest.raises(ValueError, match=rf"class_probs must sum to 1 .*1\.02.* at cell \((np\.int64\()?{N_BIG - 3}"):
            fn(q, np.full(5, 0.2), np.full(5, 0.2))
        # validate=False trusts the caller: no error (the result is then the caller's responsibility)
        assert np.all(np.isfinite(fn(q, np.full(5, 0.2), np.full(5, 0.2), validate=False)))


def test_negative_zero_is_accepted_and_mass_on_a_zero_prior_class_is_refused():
    rng = np.random.default_rng(5)
    q = rng.dirichlet(np.ones(3), size=N_BIG)
    q[:, 2] = 0.0
    q /= q.sum(axis=1, keepdims=True)
    q[7, 2] = -0.0
    prior = np.array([0.5, 0.5, 0.0])
    lik = [0.7, 0.3, 0.0]
    ok = semantic_source_probability(q, lik, prior)
    assert np.isfinite(ok).all()
    q[N_BIG - 1] = [0.5, 0.4999, 1e-4]
    for fn in (semantic_source_probability, semantic_information_gain):
        with pytest.raises(ValueError, match=r"mass 0\.0001 on classes \[2\] whose class_prior is zero"):
            fn(q, lik, prior)


def test_float32_stays_float32_without_a_float64_copy_of_the_beliefs():
    rng = np.random.default_rng(6)
    n, k = 200_000, 40
    q = rng.dirichlet(np.ones(k) * 0.5, size=n).astype(np.float32)
    lik, prior = rng.dirichlet(np.ones(k)), rng.dirichlet(np.ones(k) * 5)
    sp = rng.dirichlet(np.ones(n)).astype(np.float32)
    olf = rng.dirichlet(np.ones(n)).astype(np.float32)
    assert semantic_source_probability(q, lik, prior).dtype == np.float32
    assert semantic_source_probability(q, lik, prior, normalize=False).dtype == np.float32
    assert semantic_source_probability(q, lik, prior, source_prior=sp).dtype == np.float32
    assert semantic_source_probability(q.reshape(400, 500, k), lik, prior, column_axis=0).dtype == np.float32
    assert fuse(olf, semantic_source_probability(q, lik, prior)).dtype == np.float32
    # peak extra memory: (n,) vectors for the closed form; for the gain (n, 9) float64 moments and six (n,)
    # float64 vectors (w, f, log w, log f, the gain, one temporary). A float64 copy of the beliefs alone would be
    # 2× the input.
    for fn, bound in [
        (lambda: fuse(olf, semantic_source_probability(q, lik, prior)), 28 * n),
        (lambda: semantic_information_gain(q, lik, prior, olfactory=olf), (9 + 6) * 8 * n),
    ]:
        fn()
        tracemalloc.start()
        fn()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < bound < q.nbytes
    assert semantic_information_gain(q, lik, prior).dtype == np.float64  # nats, documented float64


def test_central_moments_match_a_direct_float64_computation():
    """The kernel's μ_j and ν_j about w_n (no raw-moment cancellation) against NumPy on a few cells."""
    rng = np.random.default_rng(7)
    n, k = 50, 9
    q = rng.dirichlet(np.ones(k) * 0.4, size=n)
    rho = rng.random(k)
    rho[2] = 0.0
    rho /= rho.max()
    rlr = np.where(rho > 0, rho * np.log(np.where(rho > 0, rho, 1.0)), 0.0)
    f = rng.dirichlet(np.ones(n))
    w, mom, stats = _kernel.belief_moments(q, rho, rlr, np.zeros(k), f, 0.0, True)
    np.testing.assert_allclose(w, q @ rho, rtol=1e-14)
    d = rho[None, :] - w[:, None]
    np.testing.assert_allclose(mom[:, 0], q @ rlr, rtol=1e-12, atol=1e-16)
    J = _kernel.ORDER
    for j in range(2, J + 1):
        np.testing.assert_allclose(mom[:, j - 1], np.sum(q * d**j, axis=1), rtol=1e-12, atol=1e-18)
    for j in range(1, J):
        np.testing.assert_allclose(mom[:, J + j - 1], np.sum(q * rlr * d**j, axis=1), rtol=1e-12, atol=1e-18)
    assert stats[4] == pytest.approx(f @ w, rel=1e-14)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("case", ["plain", "marked", "prior", "three"])
def test_fusion_does_not_depend_on_the_alignment_of_its_inputs(case, dtype):
    # a copy of the same values at another address fuses to the same bits (the vectorised normaliser has no
    # alignment-dependent peel), on one thread and across the threads of a parallel pass
    rng = np.random.default_rng(11)
    for n in (5000, 600_000):
        a, b, c = (rng.dirichlet(np.ones(n)).astype(dtype) for _ in range(3))
        if case == "marked":  # products below 2^-1000: recomputed in log space
            a = a.astype(np.float64)
            a[:3] = 1e-300
            a /= a.sum()
        prior = rng.dirichlet(np.ones(n)) if case == "prior" else None
        rest = (c,) if case == "three" else ()
        want = fuse(a, b, *rest, prior=prior)
        for offset in (1, 3, 7):
            shifted = []
            for x in (a, b):
                buf = np.empty(n + 8, x.dtype)
                buf[offset:offset + n] = x
                shifted.append(buf[offset:offset + n])
            np.testing.assert_array_equal(fuse(shifted[0], b, *rest, prior=prior), want)
            np.testing.assert_array_equal(fuse(a, shifted[1], *rest, prior=prior), want)
            np.testing.assert_array_equal(fuse(*shifted, *rest, prior=prior), want)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_the_weight_kernel_sees_every_row_of_its_four_row_blocks_and_of_the_tail(dtype):
    # rows are reduced four at a time, the last n mod 4 one by one: a weight, a negative entry, a bad row sum
    # or mass on a zero-prior class is found in every position of either
    rng = np.random.default_rng(12)
    k = 7
    rho = rng.random(k) * 3
    zero = np.zeros(k)
    zero[2] = 1.0
    for n in (1, 2, 3, 4, 5, 7, 8, 9):
        q = rng.dirichlet(np.ones(k), size=n).astype(dtype)
        q[:, 2] = 0.0
        q /= q.sum(axis=1, keepdims=True)
        w, stats = _kernel.belief_weights(q, rho, zero)
        np.testing.assert_allclose(w, q.astype(np.float64) @ rho.astype(dtype), rtol=1e-14 if dtype == np.float64 else 1e-6)
        assert stats[0] == 0 and stats[3] == 0 and stats[1] < 1e-5
        for row in range(n):
            neg = q.copy()
            neg[row, 4] = -1e-30
            assert _kernel.belief_weights(neg, rho, zero)[1][0] > 0
            off = q.copy()
            off[row] *= 1.01
            st = _kernel.belief_weights(off, rho, zero)[1]
            assert st[2] == row and st[1] == pytest.approx(0.01, rel=1e-3)
            nan = q.copy()
            nan[row, 0] = np.nan
            st = _kernel.belief_weights(nan, rho, zero)[1]
            assert st[2] == row and st[1] == np.inf
            leak = q.copy()
            leak[row, 2] = 1e-3
            assert _kernel.belief_weights(leak, rho, zero)[1][3] > 0
