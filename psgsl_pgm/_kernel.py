"""One fused pass over a large ``(n, k)`` belief matrix: products with a few k-vectors and its minimum.

Validating ``class_probs`` (finite, non-negative, rows summing to 1) and computing the semantic weights are
all memory-bound, so doing them in separate NumPy passes costs one full read of the array each. Here the rows
are processed in cache-sized blocks, each block read once from memory and then reused from cache for the
matrix product (weights and row sums together) and the minimum; the blocks are shared between two threads
(NumPy releases the GIL in both operations). This is a loop over blocks of ~10^4 rows, never over cells.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

__all__ = ["fused_products"]

_BLOCK_BYTES = 1 << 20  # ~1 MiB of beliefs per block: stays in L2 while it is reused
_PARALLEL_MIN_BYTES = 64 << 20  # below this, thread start-up costs more than it saves
_N_THREADS = max(1, min(2, os.cpu_count() or 1))
_POOL: ThreadPoolExecutor | None = None


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:  # created on first use, never at import
        _POOL = ThreadPoolExecutor(max_workers=_N_THREADS, thread_name_prefix="psgsl")
    return _POOL


def _run(q: np.ndarray, vectors: np.ndarray, out: np.ndarray, start: int, stop: int, rows: int) -> float:
    lo = np.inf
    for a in range(start, stop, rows):
        b = min(a + rows, stop)
        block = q[a:b]
        np.matmul(block, vectors, out=out[a:b])
        lo = min(lo, float(block.min()))  # NaN propagates through min, so this also detects NaN
    return lo


def fused_products(q: np.ndarray, vectors: np.ndarray) -> tuple[np.ndarray, float]:
    """Return ``q @ vectors`` and ``q.min()`` from a single blocked pass over ``q``.

    Parameters
    ----------
    q : (n, k) ndarray
        C-contiguous floating matrix.
    vectors : (k, p) ndarray
        A few column vectors (p small), same dtype as ``q``.

    Returns
    -------
    products : (n, p) ndarray
    minimum : float
        ``q.min()`` (NaN if ``q`` has a NaN).
    """
    n, k = q.shape
    out = np.empty((n, vectors.shape[1]), dtype=np.result_type(q, vectors))
    rows = max(1, _BLOCK_BYTES // max(1, k * q.itemsize))
    if q.nbytes < _PARALLEL_MIN_BYTES or _N_THREADS == 1:
        return out, _run(q, vectors, out, 0, n, rows)
    edges = np.linspace(0, n, _N_THREADS + 1).astype(int)
    futures = [
        _pool().submit(_run, q, vectors, out, int(edges[i]), int(edges[i + 1]), rows) for i in range(_N_THREADS)
    ]
    return out, min(f.result() for f in futures)
