"""The one line-of-sight rule of the package: the supercover of the segment between two cell centres.

A segment between two cell centres is blocked when it meets the *closed* square of an occupied cell other
than its two end cells — including a square it only touches at a corner. The rule is therefore light-tight: a
wall of occupied cells that touch only at their corners (a diagonal wall, cells (i, i)) hides everything
behind it. The camera (:func:`psgsl_pgm.field_of_view`, ``psgsl_pgm.sim.Camera``), the gas sensor
(``psgsl_pgm.sim.FilamentModel``) and the plume grid all use it, so they agree on every wall.

Two exact implementations of the same rule:

* :func:`cells_clear` — many segments, each traversed exactly: in grid units a segment crosses the column
  boundaries at parameters t = (k - 1/2)/|Δc| and the row boundaries at t = (j - 1/2)/|Δr|, so the cell
  entered at every crossing follows from integer counting (no floating-point stepping). Where the segment
  passes exactly through a cell corner, both cells beside the corner are checked. Cost O(n · L) for n
  segments of L cells.
* :func:`visible_from` — every cell seen from one cell centre, by shadow casting over the Chebyshev rings
  around it: an occupied cell in ring j hides exactly the directions of its closed angular interval for
  every target in a ring k > j (and at a ring's diagonal, the two ring cells beside the corner). Directions
  are compared through the angles of gcd-reduced integer vectors, so equal directions give equal floats and
  a corner touch is never missed. Cost O(A log B): A cells in the rings up to the one where the shadows close
  (in a room: the room, not range² per ray), B merged shadow intervals; memory O(one ring + B).
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

__all__ = ["cells_clear", "LineOfSightCache", "visible_from"]


def _count_below(q: np.ndarray, d: np.ndarray, strict: bool) -> np.ndarray:
    """#{j >= 1 : (2j - 1) d < q} (strict) or <= q, for integer arrays q >= 0, d >= 1."""
    if strict:
        return (q + 3 * d - 1) // (2 * d) - 1  # ceil((q + d) / 2d) - 1
    return (q + d) // (2 * d)  # floor((q + d) / 2d)


def _crossing_cells(n_steps, other, start_main, start_other, sign_main, sign_other, strict, kmax):
    """Cells entered at the crossings of the main axis: (main index, other index), shape (n, kmax)."""
    k = np.arange(1, kmax + 1)
    valid = k[None, :] <= n_steps[:, None]
    d = np.maximum(n_steps, 1)[:, None]
    q = (2 * k[None, :] - 1) * other[:, None]
    m = _count_below(q, d, strict)
    main = start_main[:, None] + sign_main[:, None] * k[None, :]
    oth = start_other[:, None] + sign_other[:, None] * m
    return main, oth, valid


def cells_clear(occupancy: np.ndarray, rc0, rc1) -> np.ndarray:
    """Whether the segments between cell centres cross no occupied cell (end cells included).

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
    rc0, rc1 : (n, 2) array_like of int
        (row, col) of the segment ends; must lie inside the grid.

    Returns
    -------
    clear : (n,) ndarray of bool

    Examples
    --------
    >>> import numpy as np
    >>> occ = np.zeros((3, 3), bool); occ[1, 1] = True
    >>> cells_clear(occ, [[0, 0], [0, 0], [0, 0]], [[2, 2], [0, 2], [2, 1]]).tolist()
    [False, True, False]
    """
    occ = np.asarray(occupancy, dtype=bool)
    a = np.asarray(rc0, dtype=np.int64).reshape(-1, 2)
    b = np.asarray(rc1, dtype=np.int64).reshape(-1, 2)
    if a.shape != b.shape:
        raise ValueError(f"rc0 and rc1 must have the same shape, got {a.shape} and {b.shape}")
    h, w = occ.shape
    for name, x in (("rc0", a), ("rc1", b)):
        if x.size and (x[:, 0].min() < 0 or x[:, 0].max() >= h or x[:, 1].min() < 0 or x[:, 1].max() >= w):
            raise ValueError(f"{name} must lie inside the {h} x {w} grid")
    clear = ~occ[a[:, 0], a[:, 1]] & ~occ[b[:, 0], b[:, 1]]
    if a.shape[0] == 0:
        return clear
    dr, dc = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    nr, nc = np.abs(dr), np.abs(dc)
    sr, sc = np.sign(dr), np.sign(dc)
    kc = int(nc.max())
    if kc:  # column crossings: cell (row after counting row crossings, col after the step)
        for strict in (True, False):  # strict/non-strict differ only at corner crossings: both cells checked
            cols, rows, valid = _crossing_cells(nc, nr, a[:, 1], a[:, 0], sc, sr, strict, kc)
            rows = np.clip(rows, 0, h - 1)
            cols = np.clip(cols, 0, w - 1)
            clear &= ~(occ[rows, cols] & valid).any(axis=1)
    kr = int(nr.max())
    if kr:  # row crossings, strictly before the simultaneous column crossing
        rows, cols, valid = _crossing_cells(nr, nc, a[:, 0], a[:, 1], sr, sc, True, kr)
        rows = np.clip(rows, 0, h - 1)
        cols = np.clip(cols, 0, w - 1)
        clear &= ~(occ[rows, cols] & valid).any(axis=1)
    return clear


class LineOfSightCache:
    """Cached :func:`cells_clear` from a few origin cells to many target cells.

    Line of sight between cell centres depends only on the two cells, so a query position (a sensor that
    stays in one cell for many time steps) reuses everything computed for its cell before. The cache keeps
    one (H, W) int8 table (-1 unknown, 0 blocked, 1 clear) per origin cell, for the ``capacity`` most recently
    used origins.

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
    capacity : int, keyword-only
    """

    def __init__(self, occupancy, *, capacity: int = 64):
        self.occupancy = np.asarray(occupancy, dtype=bool)
        if self.occupancy.ndim != 2:
            raise ValueError(f"occupancy must be (H, W), got shape {self.occupancy.shape}")
        if capacity < 1:
            raise ValueError(f"capacity must be >= 1, got {capacity!r}")
        self.capacity = int(capacity)
        self._tables: OrderedDict = OrderedDict()

    def clear_from(self, origin, targets) -> np.ndarray:
        """(n,) bool: line of sight from the ``origin`` cell (row, col) to each target cell (n, 2)."""
        key = (int(origin[0]), int(origin[1]))
        table = self._tables.get(key)
        if table is None:
            table = np.full(self.occupancy.shape, -1, dtype=np.int8)
            self._tables[key] = table
            if len(self._tables) > self.capacity:
                self._tables.popitem(last=False)
        else:
            self._tables.move_to_end(key)
        t = np.asarray(targets, dtype=np.int64).reshape(-1, 2)
        known = table[t[:, 0], t[:, 1]]
        todo = known < 0
        if todo.any():
            cells = np.unique(t[todo], axis=0)
            ok = cells_clear(self.occupancy, np.broadcast_to(np.array(key), cells.shape), cells)
            table[cells[:, 0], cells[:, 1]] = ok
            known = table[t[:, 0], t[:, 1]]
        return known.astype(bool)


# ---- shadow casting from one cell centre ------------------------------------------------------------------
def _direction_angle(ix: np.ndarray, iy: np.ndarray) -> np.ndarray:
    """arctan2 of integer direction vectors reduced by their gcd (equal directions -> bitwise-equal angles)."""
    g = np.gcd(ix, iy)
    g[g == 0] = 1
    return np.arctan2((iy // g).astype(np.float64), (ix // g).astype(np.float64))


def _ring(k: int) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (dx, dy) of the cells at Chebyshev distance ``k`` (column offset dx, row offset dy)."""
    if k == 0:
        return np.zeros(1, np.int64), np.zeros(1, np.int64)
    t = np.arange(-k, k + 1, dtype=np.int64)
    inner = t[1:-1]
    dx = np.concatenate([t, t, np.full(inner.size, -k), np.full(inner.size, k)])
    dy = np.concatenate([np.full(t.size, k), np.full(t.size, -k), inner, inner])
    return dx, dy


def _shadow_intervals(dx: np.ndarray, dy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed angular intervals [lo, hi] ⊂ [-π, π] of the squares of cells (dx, dy) ≠ (0, 0) seen from (0, 0).

    An interval across the ±π cut is split in two. Endpoints are the angles of the extreme corners, computed
    by :func:`_direction_angle` on doubled (integer) corner coordinates.
    """
    cx = 2 * dx[:, None] + np.array([-1, 1, -1, 1])[None, :]
    cy = 2 * dy[:, None] + np.array([-1, -1, 1, 1])[None, :]
    a = _direction_angle(cx, cy)  # (n, 4)
    centre = np.arctan2(dy, dx).astype(np.float64)[:, None]
    rel = np.angle(np.exp(1j * (a - centre)))  # within (-π/2, π/2): a square not containing the origin
    rows = np.arange(len(dx))
    lo, hi = a[rows, np.argmin(rel, axis=1)], a[rows, np.argmax(rel, axis=1)]
    wrap = lo > hi
    starts = np.concatenate([lo[~wrap], lo[wrap], np.full(int(wrap.sum()), -np.pi)])
    ends = np.concatenate([hi[~wrap], np.full(int(wrap.sum()), np.pi), hi[wrap]])
    return starts, ends


def _merge(starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Union of closed intervals as sorted disjoint closed intervals (touching intervals merge)."""
    if starts.size == 0:
        return starts, ends
    order = np.argsort(starts, kind="stable")
    s, e = starts[order], ends[order]
    run = np.maximum.accumulate(e)
    new = np.ones(s.size, dtype=bool)
    new[1:] = s[1:] > run[:-1]
    first = np.flatnonzero(new)
    return s[first], np.maximum.reduceat(e, first)


def _covered(theta: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Whether each angle lies in the union of the (merged) closed intervals."""
    if starts.size == 0:
        return np.zeros(theta.shape, dtype=bool)
    i = np.searchsorted(starts, theta, side="right") - 1
    return (i >= 0) & (theta <= ends[np.maximum(i, 0)])


def _arcs_covered(arcs, starts: np.ndarray, ends: np.ndarray) -> bool:
    """Whether every arc [a, b] lies inside one merged interval."""
    for a, b in arcs:  # one or two arcs
        i = np.searchsorted(starts, a, side="right") - 1
        if i < 0 or ends[i] < b:
            return False
    return True


def _cone_arcs(heading: float, half_angle: float, pad: float):
    """The directions of a cone as one or two arcs in [-π, π] (the whole circle if it is that wide)."""
    half = half_angle + pad
    if half >= np.pi:
        return [(-np.pi, np.pi)]
    lo = float(np.angle(np.exp(1j * (heading - half))))
    hi = float(np.angle(np.exp(1j * (heading + half))))
    return [(lo, hi)] if lo <= hi else [(lo, np.pi), (-np.pi, hi)]


def visible_from(occupancy: np.ndarray, cell, *, reach: int, candidate, cone=None) -> np.ndarray:
    """Cells whose centre is in line of sight of the centre of ``cell`` (the rule of :func:`cells_clear`,
    except that the two end cells may be occupied), restricted to ``candidate`` cells.

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
    cell : (2,) int
        (row, col) of the viewpoint.
    reach : int
        Largest Chebyshev distance (in cells) of a candidate from ``cell``.
    candidate : callable
        ``candidate(rows, cols) -> (n,) bool``: which cells of a ring may be seen (range, opening angle).
    cone : (heading, half_angle, offset), optional
        When given, the search stops once the shadows cover every direction from ``cell`` that a
        candidate can still have: the cone around ``heading`` widened by ``arcsin(offset / k)`` at ring k,
        ``offset`` being the distance (cells) of the true viewpoint from the cell centre.

    Returns
    -------
    visible : (H, W) ndarray of bool
    """
    occ = occupancy
    h, w = occ.shape
    r0, c0 = int(cell[0]), int(cell[1])
    visible = np.zeros((h, w), dtype=bool)
    starts = ends = np.zeros(0)
    for k in range(reach + 1):  # loop over rings (at most max(H, W)); each ring is vectorised
        if k >= 2 and starts.size:
            if cone is None:
                arcs = [(-np.pi, np.pi)]
            else:
                heading, half_angle, offset = cone
                arcs = _cone_arcs(heading, half_angle, float(np.arcsin(min(1.0, offset / k))) + 1e-9)
            if _arcs_covered(arcs, starts, ends):
                break
        dx, dy = _ring(k)
        rows, cols = r0 + dy, c0 + dx
        inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
        if not inside.any():  # this ring, and every further one, lies outside the grid
            break
        dx, dy, rows, cols = dx[inside], dy[inside], rows[inside], cols[inside]
        cand = np.asarray(candidate(rows, cols), dtype=bool)
        if cand.any():
            tx, ty = dx[cand], dy[cand]
            seen = ~_covered(_direction_angle(tx, ty), starts, ends)
            if k >= 1:  # at a ring's diagonal the segment passes the corner of the two ring cells beside it
                diag = (np.abs(tx) == k) & (np.abs(ty) == k)
                if diag.any():
                    tr, tc = rows[cand], cols[cand]
                    sx, sy = np.sign(tx), np.sign(ty)
                    side = occ[tr, np.clip(tc - sx, 0, w - 1)] | occ[np.clip(tr - sy, 0, h - 1), tc]
                    seen &= ~(diag & side)
            visible[rows[cand][seen], cols[cand][seen]] = True
        if k >= 1:
            blocker = occ[rows, cols]
            if blocker.any():
                s_new, e_new = _shadow_intervals(dx[blocker], dy[blocker])
                starts, ends = _merge(np.concatenate([starts, s_new]), np.concatenate([ends, e_new]))
    return visible
