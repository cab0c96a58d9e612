"""psgsl_pgm.kernels._logsumexp.logsumexp returns scipy.special.logsumexp's bits (same value, dtype and shape) on
the inputs the package gives it and on the edge cases of SciPy's algorithm: ties at the maximum, −∞ entries, an
all −∞ slice, +∞, NaN, one element, float32, non-contiguous and Fortran-ordered input, every axis."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import logsumexp as scipy_logsumexp

from psgsl_pgm.kernels._logsumexp import logsumexp


def _same_bits(got, want):
    got, want = np.asarray(got), np.asarray(want)
    assert got.dtype == want.dtype and got.shape == want.shape
    assert got.tobytes() == want.tobytes(), (got, want)


def _cases():
    rng = np.random.default_rng(7)
    out = []
    for shape in ((1,), (5,), (4800,), (19040,), (300, 12), (7, 3, 5)):
        for dtype in (np.float64, np.float32):
            a = (rng.normal(size=shape) * 30).astype(dtype)
            out.append(a)
            b = a.copy()
            b.reshape(-1)[::5] = -np.inf  # occupied cells of a log posterior
            out.append(b)
            c = np.round(a / 10)  # many ties, also at the maximum
            out.append(c)
    a = rng.normal(size=(40, 6))
    a[3] = -np.inf  # an all −∞ row: SciPy's fallback gives −∞
    a[5, 2] = np.inf
    a[7, 1] = np.nan
    out += [a, np.full(4, -np.inf), np.array([np.inf, 1.0]), np.array([np.nan, 1.0]), np.asfortranarray(a[:, :5]),
            rng.normal(size=(30, 8))[:, ::2], np.array([1e308, 1e308]), np.array([-1e308, -1e308])]
    return out


@pytest.mark.parametrize("k", range(len(_cases())))
def test_logsumexp_is_scipys_bit_for_bit(k):
    a = _cases()[k]
    for axis in (None,) + tuple(range(a.ndim)):
        for keepdims in (False, True):
            with np.errstate(all="ignore"):
                want = scipy_logsumexp(a, axis=axis, keepdims=keepdims)
            _same_bits(logsumexp(a, axis=axis, keepdims=keepdims), want)
    assert type(logsumexp(a)) is type(scipy_logsumexp(a))  # a NumPy scalar for axis=None


def test_logsumexp_leaves_its_input_unchanged():
    a = np.array([0.5, 0.5, -np.inf, 2.0])
    before = a.copy()
    logsumexp(a)
    assert np.array_equal(a, before)
    assert logsumexp(a) == pytest.approx(np.log(2 * np.exp(0.5) + np.exp(2.0)), rel=1e-15)
