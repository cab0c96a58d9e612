"""Line of sight, compiled: the shadow cast of :func:`psgsl_pgm.geometry._sight.visible_from` (every cell seen
from one cell centre) and the segment traversal of :func:`psgsl_pgm.geometry._sight.cells_clear`
(:func:`segment_clear`, one segment between two cell centres).

The shadow cast:

Ring by ring around the viewpoint (Chebyshev distance k = 0, 1, …): a candidate cell of ring k is seen when
its direction lies in no shadow cast by the occupied cells of rings < k (and, at a ring's diagonal, neither
ring cell beside the corner is occupied); then the occupied cells of ring k add their shadows — the closed
angular interval of their square — to a sorted list of disjoint intervals. Directions are the angles of
gcd-reduced integer vectors (equal directions give bitwise-equal angles), square corners are taken on the
doubled lattice, so a corner touch is never missed. The cast stops at the first ring outside the grid, at
``reach``, or once the shadows cover every direction a candidate can still have.

Candidates: ``mode`` 0 — the cells within a disc, (r − r0)² + (c − c0)² ≤ ``limit``; ``mode`` 1 — the cells
in the camera's cone (:func:`psgsl_pgm.kernels._view._exact`, the one range-and-angle rule).

Compiled by numba on first call and cached on disk (``cache=True``); imported lazily.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from . import _cache as _numba_cache  # noqa: F401  (kernels cached in the user cache dir, not site-packages)
from ._view import _exact

__all__ = ["cast", "clear_above", "clear_segments", "segment_clear", "segment_clear_above"]

_JIT = dict(nogil=True, cache=True, error_model="numpy")


@nb.njit(**_JIT)
def _angle(ix, iy):
    """arctan2 of the integer direction (ix, iy) reduced by its gcd."""
    a, b = abs(ix), abs(iy)
    while b:
        a, b = b, a % b
    g = a if a else 1
    return math.atan2(float(iy // g), float(ix // g))


@nb.njit(**_JIT)
def _last_start(x, starts, m):
    """Index of the last of the m sorted starts that is ≤ x (−1 if none), by bisection."""
    lo, hi = 0, m
    while lo < hi:
        mid = (lo + hi) // 2
        if starts[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return lo - 1


@nb.njit(**_JIT)
def _covered(theta, starts, ends, m):
    """Whether theta lies in one of the m sorted disjoint closed intervals."""
    i = _last_start(theta, starts, m)
    return i >= 0 and theta <= ends[i]


@nb.njit(**_JIT)
def _arc_covered(a, b, starts, ends, m):
    """Whether the arc [a, b] lies inside one interval."""
    i = _last_start(a, starts, m)
    return i >= 0 and ends[i] >= b


@nb.njit(**_JIT)
def _wrap(x):
    """x wrapped to (−π, π] (as the angle of e^{ix})."""
    return math.atan2(math.sin(x), math.cos(x))


@nb.njit(**_JIT)
def _merge(starts, ends, m):
    """Sort the first m intervals by start and merge overlapping or touching ones, in place; returns the count."""
    if m == 0:
        return 0
    order = np.argsort(starts[:m], kind="mergesort")
    s = starts[:m][order]
    e = ends[:m][order]
    out = 0
    cur_s, cur_e = s[0], e[0]
    for j in range(1, m):
        if s[j] > cur_e:
            starts[out] = cur_s
            ends[out] = cur_e
            out += 1
            cur_s, cur_e = s[j], e[j]
        elif e[j] > cur_e:
            cur_e = e[j]
    starts[out] = cur_s
    ends[out] = cur_e
    return out + 1


@nb.njit(**_JIT)
def _cast(occ, r0, c0, reach, mode, limit, col0, row0, res, cos_h, sin_h, cos_half, full, min_range,
          max_range, heading, half_angle, offset, visible):
    h, w = occ.shape
    cap = 64
    starts = np.empty(cap)
    ends = np.empty(cap)
    m = 0
    for k in range(reach + 1):  # loop over rings
        if k >= 2 and m:
            if mode == 0:
                done = _arc_covered(-math.pi, math.pi, starts, ends, m)
            else:
                half = half_angle + math.asin(min(1.0, offset / k)) + 1e-9
                if half >= math.pi:
                    done = _arc_covered(-math.pi, math.pi, starts, ends, m)
                else:
                    lo, hi = _wrap(heading - half), _wrap(heading + half)
                    if lo <= hi:
                        done = _arc_covered(lo, hi, starts, ends, m)
                    else:
                        done = (_arc_covered(lo, math.pi, starts, ends, m)
                                and _arc_covered(-math.pi, hi, starts, ends, m))
            if done:
                break
        n_ring = 1 if k == 0 else 8 * k
        any_inside = False
        added = m
        for j in range(n_ring):
            # ring k, in the order: top row, bottom row, left column, right column (corners in the rows)
            if k == 0:
                dx, dy = 0, 0
            elif j < 2 * k + 1:
                dx, dy = j - k, k
            elif j < 4 * k + 2:
                dx, dy = j - (2 * k + 1) - k, -k
            elif j < 6 * k + 1:
                dx, dy = -k, j - (4 * k + 2) - k + 1
            else:
                dx, dy = k, j - (6 * k + 1) - k + 1
            r, c = r0 + dy, c0 + dx
            if r < 0 or r >= h or c < 0 or c >= w:
                continue
            any_inside = True
            if mode == 0:
                cand = (r - r0) ** 2 + (c - c0) ** 2 <= limit
            else:
                cand = _exact(r, c, col0, row0, res, cos_h, sin_h, cos_half, full, min_range, max_range)
            if cand:
                seen = True
                if k >= 1:
                    if m:
                        seen = not _covered(_angle(dx, dy), starts, ends, m)
                    if seen and abs(dx) == k and abs(dy) == k:  # the corner between the two ring cells beside it
                        sx = 1 if dx > 0 else -1
                        sy = 1 if dy > 0 else -1
                        cc = min(max(c - sx, 0), w - 1)
                        rr = min(max(r - sy, 0), h - 1)
                        if occ[r, cc] or occ[rr, c]:
                            seen = False
                if seen:
                    visible[r, c] = True
            if k >= 1 and occ[r, c]:
                # the shadow of the closed square: the extreme corner directions seen from the viewpoint
                centre = math.atan2(float(dy), float(dx))
                best_lo, best_hi = 10.0, -10.0
                a_lo = a_hi = 0.0
                for corner in range(4):
                    ex = 2 * dx + (1 if corner & 1 else -1)
                    ey = 2 * dy + (1 if corner & 2 else -1)
                    a = _angle(ex, ey)
                    rel = a - centre
                    if rel > math.pi:
                        rel -= 2 * math.pi
                    elif rel < -math.pi:
                        rel += 2 * math.pi
                    if rel < best_lo:
                        best_lo, a_lo = rel, a
                    if rel > best_hi:
                        best_hi, a_hi = rel, a
                if added + 2 > cap:
                    cap *= 2
                    s2 = np.empty(cap)
                    e2 = np.empty(cap)
                    s2[:added] = starts[:added]
                    e2[:added] = ends[:added]
                    starts, ends = s2, e2
                if a_lo <= a_hi:
                    starts[added], ends[added] = a_lo, a_hi
                    added += 1
                else:  # across the ±π cut: two intervals
                    starts[added], ends[added] = a_lo, math.pi
                    starts[added + 1], ends[added + 1] = -math.pi, a_hi
                    added += 2
        if not any_inside:  # this ring, and every further one, lies outside the grid
            break
        if added > m:
            m = _merge(starts, ends, added)


@nb.njit(inline="always", **_JIT)
def _count_below(q, d, strict):
    """#{j ≥ 1 : (2j − 1) d < q} (strict) or ≤ q, for integers q ≥ 0, d ≥ 1."""
    if strict:
        return (q + 3 * d - 1) // (2 * d) - 1  # ceil((q + d) / 2d) − 1
    return (q + d) // (2 * d)  # floor((q + d) / 2d)


@nb.njit(inline="always", **_JIT)
def _crossings_clear(occ, n_main, n_other, main0, other0, s_main, s_other, strict, rows_main):
    """No occupied cell among those entered at the n_main crossings of the main axis (k = 1 … n_main: main index
    main0 + s_main k, other index other0 + s_other #{crossings of the other axis before it})."""
    h, w = occ.shape
    d = max(n_main, 1)
    for k in range(1, n_main + 1):
        main = main0 + s_main * k
        other = other0 + s_other * _count_below((2 * k - 1) * n_other, d, strict)
        r, c = (main, other) if rows_main else (other, main)
        if occ[min(max(r, 0), h - 1), min(max(c, 0), w - 1)]:
            return False
    return True


@nb.njit(**_JIT)
def segment_clear(occ, r0, c0, r1, c1):
    """Whether the segment between the centres of cells (r0, c0) and (r1, c1) meets no occupied cell, its two
    end cells included: the supercover rule of :func:`psgsl_pgm.geometry._sight.cells_clear`. In grid units the
    segment crosses the column boundaries at t = (k − ½)/|Δc| and the row boundaries at t = (j − ½)/|Δr|; the
    cell entered at each crossing follows from counting the other axis' crossings before it (integers only).
    At a corner crossing (equal parameters) both cells beside the corner are checked: the column crossings
    counted strictly and not, the row crossings strictly."""
    if occ[r0, c0] or occ[r1, c1]:
        return False
    dr, dc = r1 - r0, c1 - c0
    nr, nc = abs(dr), abs(dc)
    sr = 1 if dr > 0 else (-1 if dr < 0 else 0)
    sc = 1 if dc > 0 else (-1 if dc < 0 else 0)
    if nc:
        if not _crossings_clear(occ, nc, nr, c0, r0, sc, sr, True, False):
            return False
        if not _crossings_clear(occ, nc, nr, c0, r0, sc, sr, False, False):
            return False
    if nr:
        if not _crossings_clear(occ, nr, nc, r0, c0, sr, sc, True, True):
            return False
    return True


@nb.njit(**_JIT)
def clear_segments(occ, a, b, out):
    """out[i] = :func:`segment_clear` from cell a[i] to cell b[i] ((n, 2) int64 (row, col) inside the grid)."""
    for i in range(a.shape[0]):
        out[i] = segment_clear(occ, a[i, 0], a[i, 1], b[i, 0], b[i, 1])


def cast(occupancy, cell, *, reach, disc=None, camera=None):
    """Cells seen from the centre of ``cell``, restricted to the candidates of a disc or of a camera's cone.

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool, C-contiguous
    cell : (2,) int
        (row, col) of the viewpoint.
    reach : int
        Largest Chebyshev ring cast.
    disc : float, optional
        Candidates within this distance (cells) of the viewpoint.
    camera : psgsl_pgm.geometry._fov._Camera, optional
        Candidates in its range and opening angle; the cast stops once its cone is in shadow.

    Returns
    -------
    visible : (H, W) ndarray of bool
    """
    occ = np.ascontiguousarray(occupancy, dtype=np.bool_)
    visible = np.zeros(occ.shape, dtype=np.bool_)
    r0, c0 = int(cell[0]), int(cell[1])
    if camera is None:
        _cast(occ, r0, c0, int(reach), 0, float(disc) ** 2, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, True, 0.0, 0.0, 0.0,
              math.pi, 0.0, visible)
    else:
        cam = camera
        _cast(occ, r0, c0, int(reach), 1, 0.0, float(cam.col0), float(cam.row0), float(cam.res),
              math.cos(cam.heading), math.sin(cam.heading), math.cos(cam.half_angle),
              bool(cam.half_angle >= math.pi), float(cam.min_range), float(cam.max_range), float(cam.heading),
              float(cam.half_angle), float(cam.offset), visible)
    return visible


# ---- the 2.5-D test: a ray between two heights over the cells of one segment -------------------------------
@nb.njit(inline="always", **_JIT)
def _cell_blocks(z_low, z_high, r, c, r0, c0, dr, dc, n2, eye, top):
    """Whether cell (r, c) holds the ray's height above its centre: z_low[r, c] <= y < z_high[r, c], with y the
    height of the ray from (cell r0, c0; height eye) to (its end cell; height top) at the projection t of the cell
    centre on the segment (t = ((r − r0) dr + (c − c0) dc) / n2, clamped to [0, 1])."""
    t = ((r - r0) * dr + (c - c0) * dc) / n2
    t = min(max(t, 0.0), 1.0)
    y = eye + (top - eye) * t
    return z_low[r, c] <= y < z_high[r, c]


@nb.njit(inline="always", **_JIT)
def _crossings_above(z_low, z_high, n_main, n_other, main0, other0, s_main, s_other, strict, rows_main, r0, c0,
                     r1, c1, eye, top):
    """No cell among those entered at the n_main crossings of the main axis (the enumeration of
    :func:`_crossings_clear`), other than the end cell (r1, c1), holds the ray (:func:`_cell_blocks`)."""
    h, w = z_low.shape
    d = max(n_main, 1)
    dr, dc = r1 - r0, c1 - c0
    n2 = float(dr * dr + dc * dc)
    for k in range(1, n_main + 1):
        main = main0 + s_main * k
        other = other0 + s_other * _count_below((2 * k - 1) * n_other, d, strict)
        r, c = (main, other) if rows_main else (other, main)
        r, c = min(max(r, 0), h - 1), min(max(c, 0), w - 1)
        if (r != r1 or c != c1) and _cell_blocks(z_low, z_high, r, c, r0, c0, dr, dc, n2, eye, top):
            return False
    return True


@nb.njit(**_JIT)
def segment_clear_above(z_low, z_high, r0, c0, r1, c1, eye, top):
    """Whether the ray from height ``eye`` over the centre of cell (r0, c0) to height ``top`` over the centre of
    cell (r1, c1) passes every cell the segment meets (the supercover of :func:`segment_clear`: the same cells,
    corner touches included) outside its vertical extent [z_low, z_high); the two end cells are not tested."""
    dr, dc = r1 - r0, c1 - c0
    nr, nc = abs(dr), abs(dc)
    sr = 1 if dr > 0 else (-1 if dr < 0 else 0)
    sc = 1 if dc > 0 else (-1 if dc < 0 else 0)
    if nc:
        if not _crossings_above(z_low, z_high, nc, nr, c0, r0, sc, sr, True, False, r0, c0, r1, c1, eye, top):
            return False
        if not _crossings_above(z_low, z_high, nc, nr, c0, r0, sc, sr, False, False, r0, c0, r1, c1, eye, top):
            return False
    if nr:
        if not _crossings_above(z_low, z_high, nr, nc, r0, c0, sr, sc, True, True, r0, c0, r1, c1, eye, top):
            return False
    return True


@nb.njit(**_JIT)
def clear_above(z_low, z_high, r0, c0, eye, targets, tops, out):
    """out[i] = :func:`segment_clear_above` from cell (r0, c0) at height ``eye`` to cell targets[i] ((n, 2)
    int64 (row, col) inside the grid) at height tops[i]."""
    for i in range(targets.shape[0]):
        out[i] = segment_clear_above(z_low, z_high, r0, c0, targets[i, 0], targets[i, 1], eye, tops[i])
