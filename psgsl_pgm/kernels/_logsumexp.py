"""log Σ exp over real float arrays: the arithmetic of ``scipy.special.logsumexp``, without its per-call overhead.

SciPy's ``logsumexp`` (array-API dispatch, type promotion, an extra ``exp`` of the whole input kept for its
infinite-result fallback, masked copies) costs ~0.5 ms on a 5 000-cell map and ~2.7 ms on a 20 000-cell one,
where the arithmetic itself takes a few tens of µs; the closed loop normalises a posterior several times per
stop. :func:`logsumexp` performs SciPy's floating-point operations in SciPy's order — the maximum, the
maxima counted and separated out of the sum, ``log1p(s / m) + log(m) + max`` — on arrays of the same layout,
so it returns the same bits (checked against SciPy in ``tests/kernels/test_logsumexp.py``); the fallback
``log(Σ exp a)`` is computed only where that result is not finite (an all −∞ slice, +∞ or NaN in the input).
"""

from __future__ import annotations

import numpy as np

__all__ = ["logsumexp"]


def logsumexp(a: np.ndarray, axis: int | None = None, keepdims: bool = False):
    """log Σ exp(a) over ``axis`` (all axes when None), bit for bit ``scipy.special.logsumexp(a, axis, keepdims=)``.

    Parameters
    ----------
    a : ndarray of float32 or float64
        Real floating-point input, non-empty (callers own their validation).
    axis : int, optional
    keepdims : bool

    Returns
    -------
    ndarray or numpy floating scalar
        As SciPy returns it: a scalar of ``a``'s dtype for ``axis=None`` without ``keepdims``.
    """
    if a.ndim == 0:
        a = a.reshape(1)
    axes = tuple(range(a.ndim)) if axis is None else axis
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a_max = np.max(a, axis=axes, keepdims=True)
        mask = a == a_max
        shifted = np.array(a, copy=True)  # SciPy's copy keeps the input's memory layout (order "K")
        shifted[mask] = -np.inf  # the maxima are separated out of the sum, for precision (as SciPy does)
        m = np.sum(mask.astype(a.dtype), axis=axes, keepdims=True, dtype=a.dtype)
        e = np.exp(shifted - a_max)
        s = np.sum(e, axis=axes, keepdims=True, dtype=e.dtype)
        s = np.where(s == 0, s, s / m)
        out = np.log1p(s) + np.log(m) + a_max
        finite = np.isfinite(out)
        if not finite.all():  # SciPy's direct log Σ exp where the shifted result is infinite or NaN
            out = np.where(finite, out, np.log(np.sum(np.exp(a), axis=axes, keepdims=True)))
    if not keepdims:
        out = np.squeeze(out, axis=axes)
    return out[()] if out.ndim == 0 else out
