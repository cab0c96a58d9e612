"""Argument validation at the public boundary.

Every public function converts and checks its inputs here, once, and raises :class:`ValueError` or
:class:`TypeError` with a message that names the argument, what was expected and what arrived. Internal code
may then assume finite, non-negative, correctly shaped floating arrays.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "SUM_RTOL",
    "as_float_array",
    "check_distribution",
    "check_nonnegative",
    "check_last_axis",
    "check_sums",
    "describe",
]

#: Tolerance on ``|sum - 1|`` for arrays that must be normalised, per floating dtype. Probabilities written
#: to disk with 7 significant digits, or computed in float32, are accepted; anything further off is refused.
SUM_RTOL = {np.dtype(np.float64): 1e-6, np.dtype(np.float32): 1e-4}


def describe(x) -> str:
    """Short description of an array-like for error messages: type, shape and dtype."""
    if isinstance(x, np.ndarray):
        return f"ndarray of shape {x.shape} and dtype {x.dtype}"
    return f"{type(x).__name__} {x!r}" if np.ndim(x) == 0 else f"{type(x).__name__} of shape {np.shape(x)}"


def as_float_array(x, name: str, *, dtype=None, min_ndim: int = 0, ndim: int | None = None) -> np.ndarray:
    """Convert ``x`` to a floating array (float64 unless ``x`` is already float32, or ``dtype`` is given).

    Raises
    ------
    TypeError
        If ``x`` is not numeric (strings, objects, complex numbers).
    ValueError
        If the number of dimensions is wrong, or an entry is NaN or infinite.
    """
    if isinstance(x, (str, bytes)) or x is None:
        raise TypeError(f"{name} must be a numeric array, got {type(x).__name__} {x!r}")
    arr = np.asarray(x)
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise TypeError(f"{name} must be a real numeric array, got {describe(arr)}")
    if np.iscomplexobj(arr):
        raise TypeError(f"{name} must be real, got complex dtype {arr.dtype}")
    if dtype is None:
        dtype = np.float32 if arr.dtype == np.float32 else np.float64
    arr = np.asarray(arr, dtype=dtype)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must have {ndim} dimension(s), got {describe(arr)}")
    if arr.ndim < min_ndim:
        raise ValueError(f"{name} must have at least {min_ndim} dimension(s), got {describe(arr)}")
    return arr


def check_nonnegative(arr: np.ndarray, name: str) -> np.ndarray:
    """Refuse NaN, infinite or negative entries (one pass: ``min`` propagates NaN, ``max`` finds +inf)."""
    if arr.size == 0:
        raise ValueError(f"{name} must not be empty, got {describe(arr)}")
    lo, hi = np.min(arr), np.max(arr)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"{name} must be finite, got {arr[tuple(bad)]} at index {tuple(int(i) for i in bad)}")
    if lo < 0:
        bad = np.argwhere(arr < 0)[0]
        raise ValueError(
            f"{name} must be non-negative (probabilities), got {arr[tuple(bad)]} at index "
            f"{tuple(int(i) for i in bad)}"
        )
    return arr


def check_last_axis(arr: np.ndarray, name: str, k: int, what: str = "classes") -> None:
    """Require the last axis of ``arr`` to have length ``k``."""
    if arr.ndim == 0 or arr.shape[-1] != k:
        raise ValueError(f"{name} must have {k} {what} on its last axis, got {describe(arr)}")


def check_distribution(arr: np.ndarray, name: str, *, axis: int = -1, sums=None) -> np.ndarray:
    """Refuse entries that are negative/NaN/inf, or slices along ``axis`` that do not sum to 1.

    ``sums`` may pass precomputed sums along ``axis`` (e.g. from a fused matrix product) to save a pass.
    The tolerance is :data:`SUM_RTOL` for the array's dtype.
    """
    check_nonnegative(arr, name)
    if sums is None:
        sums = np.sum(arr, axis=axis, dtype=np.float64)
    check_sums(sums, name, arr.dtype)
    return arr


def check_sums(sums: np.ndarray, name: str, dtype) -> None:
    """Refuse normalising sums further than :data:`SUM_RTOL` from 1 (NaN sums are refused too)."""
    tol = SUM_RTOL.get(np.dtype(dtype), 1e-6)
    dev = np.abs(np.asarray(sums, dtype=np.float64) - 1.0)
    worst = np.nanargmax(dev) if np.ndim(dev) else None
    worst_dev = dev.flat[worst] if worst is not None else dev
    if not np.all(dev <= tol):
        where = f" at cell {np.unravel_index(worst, np.shape(sums))}" if worst is not None else ""
        value = np.asarray(sums).flat[worst] if worst is not None else sums
        raise ValueError(
            f"{name} must sum to 1 along its last axis (tolerance {tol:g}), got a sum of {float(value)!r}{where}"
            + ("" if np.isfinite(worst_dev) else " (NaN or inf entries)")
        )
