"""The software prefetch of the compiled kernels (psgsl_pgm.kernels._prefetch): one prefetch instruction, no effect on values."""

import numba as nb
import numpy as np
import pytest

from psgsl_pgm.kernels._prefetch import prefetch


@nb.njit(cache=False)
def _sum_with_prefetch(a, ahead):
    s = 0.0
    for i in range(a.size):
        if i + ahead < a.size:
            prefetch(a, i + ahead)
        s += a.flat[i]
    return s


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_prefetch_compiles_to_a_prefetch_instruction_and_changes_nothing(dtype):
    a = np.random.default_rng(0).random((37, 5)).astype(dtype)
    assert _sum_with_prefetch(a, 16) == _sum_with_prefetch(a, 10**9)  # with and without prefetches
    # the loop accumulates in float64 (s = 0.0): it and NumPy's pairwise float64 sum of the 185 values differ by
    # at most ~185·2^-53 ≈ 2e-14 relative, whatever the values' dtype
    assert _sum_with_prefetch(a, 16) == pytest.approx(float(a.sum(dtype=np.float64)), rel=1e-13)
    asm = "\n".join(_sum_with_prefetch.inspect_asm().values())
    assert "prefetcht0" in asm


def test_prefetch_is_typed_for_arrays_and_integer_indices_only():
    with pytest.raises(nb.core.errors.TypingError):
        nb.njit(lambda a: prefetch(a, 1.5))(np.zeros(3))
