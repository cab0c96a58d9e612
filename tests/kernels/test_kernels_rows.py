"""The explicit-vector four-row reduction (psgsl_pgm.kernels._rows.rows4) behind the weight kernel: every class of
every row counted once, in whole vectors and in the masked rest of a row, for both dtypes."""

import numpy as np
import pytest

from psgsl_pgm.kernels import _belief as _kernel

# whole 64-byte vectors only (16 float32 / 8 float64 lanes), a rest only, and both
CLASS_COUNTS = (1, 7, 8, 9, 15, 16, 17, 31, 32, 33, 40, 80, 81)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("k", CLASS_COUNTS)
def test_weights_and_row_sums_match_a_float64_product_for_every_row_length(k, dtype):
    rng = np.random.default_rng(k)
    n = 11  # two four-row blocks and a tail of three rows
    q = rng.dirichlet(np.ones(k), size=n).astype(dtype)
    rho = rng.random(k) * 4
    w, stats = _kernel.belief_weights(q, rho, np.zeros(k))
    want = q.astype(np.float64) @ rho.astype(dtype).astype(np.float64)
    # float32 sums of k float32 terms: a few float32 ulps of the total
    np.testing.assert_allclose(w, want, rtol=1e-14 if dtype == np.float64 else 4 * k * 2.0**-24)
    row_sums = q.astype(np.float64).sum(axis=1)
    worst = int(np.argmax(np.abs(row_sums - 1)))
    assert stats[0] == 0
    assert stats[1] == pytest.approx(abs(row_sums[worst] - 1), abs=4 * k * float(np.finfo(dtype).eps))
    assert stats[4] == pytest.approx(want.sum(), rel=1e-12 if dtype == np.float64 else 1e-5)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("k", (17, 40, 81))
def test_a_single_negative_entry_is_found_in_any_class_of_any_row_of_a_block(k, dtype):
    rng = np.random.default_rng(100 + k)
    q = rng.dirichlet(np.ones(k), size=8).astype(dtype)
    rho = rng.random(k)
    zero = np.zeros(k)
    assert _kernel.belief_weights(q, rho, zero)[1][0] == 0
    tiny = np.finfo(dtype).smallest_subnormal  # the smallest negative number there is
    for row in range(8):
        for cls in range(k):
            bad = q.copy()
            bad[row, cls] = -tiny
            assert _kernel.belief_weights(bad, rho, zero)[1][0] > 0, (row, cls)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("k", CLASS_COUNTS)
@pytest.mark.parametrize("paper", [True, False])
def test_moments_match_a_direct_float64_computation_for_every_row_length(k, dtype, paper):
    # rows4v (w, v, row sums of a four-row block) and central (μ_2..μ_5, ν_1..ν_4 about w_n), whole vectors and
    # the masked rest, float32 entries widened to float64
    rng = np.random.default_rng(200 + k)
    n = 11
    q = rng.dirichlet(np.ones(k) * 0.4, size=n).astype(dtype)
    rho = rng.random(k) * 2
    rlr = rho * np.log(rho)
    f = rng.dirichlet(np.ones(n))
    w, mom, stats = _kernel.belief_moments(q, rho, rlr, np.zeros(k), f, 0.0, paper)
    q64 = q.astype(np.float64)
    np.testing.assert_allclose(w, q64 @ rho, rtol=1e-14)
    np.testing.assert_allclose(mom[:, 0], q64 @ rlr, rtol=1e-13, atol=1e-16)
    d = rho[None, :] - w[:, None]
    for j in range(2, _kernel.ORDER + 1):
        np.testing.assert_allclose(mom[:, j - 1], np.sum(q64 * d**j, axis=1), rtol=1e-12, atol=1e-18)
    if paper:
        for j in range(1, _kernel.ORDER):
            np.testing.assert_allclose(mom[:, _kernel.ORDER + j - 1], np.sum(q64 * rlr * d**j, axis=1),
                                       rtol=1e-12, atol=1e-18)
    assert stats[0] == 0
    assert stats[4] == pytest.approx(f @ (q64 @ rho), rel=1e-14)
    tiny = np.finfo(dtype).smallest_subnormal
    for row in (0, 3, 5, 10):  # in a block (first, last of the first, inside the second) and in the tail
        for cls in {0, k // 2, k - 1}:
            bad = q.copy()
            bad[row, cls] = -tiny
            assert _kernel.belief_moments(bad, rho, rlr, np.zeros(k), f, 0.0, paper)[2][0] > 0, (row, cls)


@pytest.mark.parametrize("shape", [(200, 25), (6, 7, 5), (3, 4100), (9000, 3), (1, 1), (0, 3), (4, 0, 2), (5,)])
def test_column_sums_add_each_column_in_order_along_its_axis(shape):
    # Sec. "Voxelized Scene Representations": Σ_{v ∈ c} p(s_v | z), over any axis, several chunks of columns
    rng = np.random.default_rng(len(shape))
    values = rng.random(shape) * 10.0 ** rng.integers(-8, 8, size=shape)  # magnitudes where order shows
    for axis in range(len(shape)):
        got = _kernel.column_sums(values, axis)
        want = np.zeros(shape[:axis] + shape[axis + 1:])
        for j in range(shape[axis]):  # the first voxel of the column first, one addition after another
            want = want + np.take(values, j, axis=axis)
        assert got.shape == want.shape and got.dtype == np.float64
        np.testing.assert_array_equal(got, want)
