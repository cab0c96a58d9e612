"""PMFS's hit-frequency simulation, compiled: the filament model's time step (:mod:`._filaments`) and, after
each recorded step, one count per lattice block that holds at least one filament.

Compiled by numba on first call and cached on disk (``cache=True``); imported lazily.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from . import _cache as _numba_cache  # noqa: F401  (kernels cached in the user cache dir, not site-packages)
from ._filaments import _step

__all__ = ["record_hits"]

_JIT = dict(nogil=True, cache=True, error_model="numpy")


@nb.njit(**_JIT)
def record_hits(rng, n_warmup, n_record, pos, births, cells, vel, dt, release_rate, noise_std, source_x, source_y,
                source_r, source_q, walls, stays, h, w, ox, oy, res, block_of, n_blocks):
    """Release filaments at (source_x, source_y) in cell (source_r, source_q) and move them on the wind ``vel``
    ((H·W, 2) m/s) by the rules of :func:`psgsl_pgm.kernels._filaments.steps` for ``n_warmup`` steps, then
    ``n_record`` more, counting after each of these the blocks (``block_of``: (H·W,) block index of each cell,
    −1 for none) that hold at least one filament (each block once per step).

    Returns
    -------
    counts : (n_blocks,) int64
        Steps (of ``n_record``) in which each block held a filament.
    """
    counts = np.zeros(n_blocks, np.int64)
    last = np.full(n_blocks, -1, np.int64)
    n_live = 0
    n_released = 0
    for s in range(n_warmup + n_record):
        n_live, n_released, _ = _step(rng, s, s * dt, n_released, pos, births, cells, n_live, vel, dt, release_rate,
                                      noise_std, source_x, source_y, source_r, source_q, walls, stays, h, w, ox, oy,
                                      res)
        if s >= n_warmup:
            for i in range(n_live):
                b = block_of[cells[i, 0] * w + cells[i, 1]]
                if b >= 0 and last[b] != s:
                    last[b] = s
                    counts[b] += 1
    return counts
