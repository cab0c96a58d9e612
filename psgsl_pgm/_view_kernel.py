"""The camera's range-and-angle test over a list of cells, compiled: the one implementation of "is this cell
inside the opening angle and range of the pose" (Sec. "Information Gain Optimization", the set F_p).

A cell is in the cone of a pose when the distance d from the pose to its centre satisfies
min_range ≤ d ≤ max_range and its bearing β relative to the heading satisfies |β| ≤ half_angle. The bearing
test is done without trigonometry per cell: for β ∈ [0, π], |β| ≤ α ⇔ cos β ≥ cos α, and
cos β = (Δx cos θ + Δy sin θ) / d, so the test is Δx cos θ + Δy sin θ ≥ d cos α (every angle when α = π). The
boundary is closed up to rounding: both sides carry a few ulps of d of rounding error, so the test is made
with a slack of 8 ε d (ε the float64 epsilon). A cell exactly on the boundary — the diagonal cell of a
camera with α = π/4 looking along an axis — is inside, whatever the rounding of cos α and √2; a cell counts
wrongly only if its bearing is within about 8 ε / sin α ≈ 2e-15 rad of the boundary. The cell holding the
pose itself (d below 1e-12 cells) is always in the cone.

Compiled by numba on first call and cached on disk (``cache=True``); imported lazily, so ``import psgsl_pgm``
does not import numba.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["SLACK", "cone_mask"]

SLACK = 8 * float(np.finfo(np.float64).eps)  # rounding slack of the bearing test, relative to the distance


@nb.njit(nogil=True, cache=True, error_model="numpy")
def _cone_mask(rows, cols, col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range, out):
    tiny = 1e-12 * res
    for j in range(rows.shape[0]):
        dx = (cols[j] + 0.5 - col0) * res
        dy = (rows[j] + 0.5 - row0) * res
        d = math.hypot(dx, dy)
        ok = (d >= min_range) & (d <= max_range)
        if ok and not full and d >= tiny:
            ok = dx * cos_h + dy * sin_h + SLACK * d >= d * cos_half  # cos β ≥ cos α  ⇔  |β| ≤ α
        out[j] = ok


def cone_mask(rows, cols, *, col0, row0, res, heading, half_angle, min_range, max_range):
    """Which cells (rows, cols) lie in the camera's cone.

    Parameters
    ----------
    rows, cols : (m,) ndarray of int
        Cell indices.
    col0, row0 : float
        The pose in continuous grid coordinates (cells; cell (r, c) spans [c, c + 1) × [r, r + 1)).
    res : float
        Cell size (units of the ranges).
    heading, half_angle : float
        Radians; ``half_angle`` in (0, π].
    min_range, max_range : float
        Range limits, units of ``res``.

    Returns
    -------
    inside : (m,) ndarray of bool
    """
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    cols = np.ascontiguousarray(cols, dtype=np.int64)
    out = np.empty(rows.shape[0], dtype=np.bool_)
    _cone_mask(rows, cols, float(col0), float(row0), float(res), math.cos(heading), math.sin(heading),
               math.cos(half_angle), bool(half_angle >= math.pi), float(min_range), float(max_range), out)
    return out
