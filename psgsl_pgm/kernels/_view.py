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
pose itself (d below 1e-12 cells) is always in the cone. The distance is d = hypot(Δx, Δy); the kernel uses
the faster √(Δx² + Δy²) (within an ulp of it) wherever that cannot change a decision, i.e. away from 1e-12 d
of every boundary.

Compiled by numba on first call and cached on disk (``cache=True``); imported lazily, so ``import psgsl_pgm``
does not import numba.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from . import _cache as _numba_cache  # noqa: F401  (kernels cached in the user cache dir, not site-packages)

__all__ = ["SLACK", "cone_mask", "cone_values"]

SLACK = 8 * float(np.finfo(np.float64).eps)  # rounding slack of the bearing test, relative to the distance


@nb.njit(nogil=True, cache=True, error_model="numpy", inline="always")
def _exact(r, c, col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range):
    """The decision itself, with d = hypot(Δx, Δy)."""
    dx = (c + 0.5 - col0) * res
    dy = (r + 0.5 - row0) * res
    d = math.hypot(dx, dy)
    ok = (d >= min_range) & (d <= max_range)
    if ok and not full and d >= 1e-12 * res:
        ok = dx * cos_h + dy * sin_h + SLACK * d >= d * cos_half  # cos β ≥ cos α  ⇔  |β| ≤ α
    return ok


@nb.njit(nogil=True, cache=True, error_model="numpy")
def _screen(rows, cols, col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range, code):
    """Branch-free (vectorisable) first pass: code = 1 inside, 0 outside, 2 too close to call (recompute).

    Uses d = √(Δx² + Δy²), within an ulp of hypot where 1e-280 < d² < 1e280; a cell within 1e-12 d of a
    boundary (range, the pose's own point, or the cone's edge), or outside that scale range, is left to
    :func:`_exact`, so the decisions are exactly those of :func:`_exact`.
    """
    tiny = 1e-12 * res
    for j in range(rows.shape[0]):
        dx = (cols[j] + 0.5 - col0) * res
        dy = (rows[j] + 0.5 - row0) * res
        d2 = dx * dx + dy * dy
        d = math.sqrt(d2)
        eps = 1e-12 * d
        v = dx * cos_h + dy * sin_h + SLACK * d - d * cos_half
        ok = (d >= min_range) & (d <= max_range) & (full | (d < tiny) | (v >= 0.0))
        tie = ((abs(d - min_range) <= eps) | (abs(d - max_range) <= eps) | (abs(d - tiny) <= eps)
               | (abs(v) <= eps) | ~((d2 > 1e-280) & (d2 < 1e280)))
        code[j] = np.uint8(2) if tie else np.uint8(ok)


@nb.njit(nogil=True, cache=True, error_model="numpy")
def _decide(rows, cols, col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range, code):
    """code[j] = 1 inside, 0 outside: the screening pass, then :func:`_exact` for the cells too close to call."""
    _screen(rows, cols, col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range, code)
    for j in range(rows.shape[0]):
        if code[j] == 2:
            code[j] = _exact(rows[j], cols[j], col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range)


@nb.njit(nogil=True, cache=True, error_model="numpy")
def _cone_values(rows, cols, values, col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range, out):
    code = np.empty(rows.shape[0], np.uint8)
    _decide(rows, cols, col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range, code)
    n = 0
    for j in range(rows.shape[0]):
        if code[j]:
            out[n] = values[rows[j], cols[j]]
            n += 1
    return n


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
    rows, cols = np.asarray(rows), np.asarray(cols)
    code = np.empty(rows.shape[0], dtype=np.uint8)
    _decide(rows, cols, *_camera_args(col0, row0, res, heading, half_angle, min_range, max_range), code)
    return code.view(np.bool_)


def cone_values(rows, cols, values, *, col0, row0, res, heading, half_angle, min_range, max_range):
    """``values[rows, cols]`` of the cells in the cone, in the order given (as :func:`cone_mask` selects).

    Parameters
    ----------
    rows, cols : (m,) ndarray of int
    values : (H, W) ndarray of float64
    col0, row0, res, heading, half_angle, min_range, max_range
        As for :func:`cone_mask`.

    Returns
    -------
    selected : (s,) ndarray of float64
    """
    out = np.empty(rows.shape[0])
    n = _cone_values(rows, cols, values, *_camera_args(col0, row0, res, heading, half_angle, min_range, max_range),
                     out)
    return out[:n]


def _camera_args(col0, row0, res, heading, half_angle, min_range, max_range):
    return (float(col0), float(row0), float(res), math.cos(heading), math.sin(heading), math.cos(half_angle),
            bool(half_angle >= math.pi), float(min_range), float(max_range))
