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
  segments of L cells (compiled, :func:`psgsl_pgm.kernels._sight.segment_clear`, which the filament model's
  compiled loops also call).
* :func:`visible_from` — every cell seen from one cell centre, by shadow casting over the Chebyshev rings
  around it (compiled, :mod:`psgsl_pgm.kernels._sight`): an occupied cell in ring j hides exactly the directions of its closed angular interval for
  every target in a ring k > j (and at a ring's diagonal, the two ring cells beside the corner). Directions
  are compared through the angles of gcd-reduced integer vectors, so equal directions give equal floats and
  a corner touch is never missed. Cost O(A log B): A cells in the rings up to the one where the shadows close
  (in a room: the room, not range² per ray), B merged shadow intervals; memory O(one ring + B).

The same supercover in 2.5-D, :func:`rays_clear_above`: cells with a vertical extent [z_low, z_high) (furniture)
and a ray between two heights; a cell the segment meets hides the ray when the ray's height above that cell's
centre lies within its extent (the camera's furniture occlusion, ``psgsl_pgm.sim.Camera(occlusion="furniture")``).
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

__all__ = ["cells_clear", "LineOfSightCache", "rays_clear_above", "visible_from"]


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

    Raises
    ------
    ValueError
        ``rc0`` and ``rc1`` differ in shape, or an end lies outside the grid.

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
    from ..kernels._sight import clear_segments  # compiled on first use (numba)

    clear = np.empty(a.shape[0], dtype=bool)
    clear_segments(np.ascontiguousarray(occ), a, b, clear)
    return clear


def rays_clear_above(z_low, z_high, origin, targets, *, eye: float, tops) -> np.ndarray:
    """Whether rays between heights pass over (or under) every cell they cross: the 2.5-D line of sight.

    The ray n runs from height ``eye`` above the centre of the ``origin`` cell to height ``tops[n]`` above the
    centre of ``targets[n]``. It meets the cells of the supercover of the segment between the two centres (the
    rule of :func:`cells_clear`, corner touches included). Such a cell (r, c), not one of the two end cells, hides
    the ray when the ray's height above it, y = eye + (top − eye) · t, satisfies
    ``z_low[r, c] <= y < z_high[r, c]``. Here t ∈ [0, 1] is the projection of the cell's centre on the segment.
    A ray grazing a cell's top face is not hidden. A cell with z_low = +inf never hides, a wall
    (−inf, +inf) always does.

    Parameters
    ----------
    z_low, z_high : (H, W) array_like of float
        Vertical extent of each cell's contents, metres above the floor.
    origin : (2,) int
        (row, col) of the eye.
    targets : (n, 2) array_like of int
        (row, col) of the targets, inside the grid.
    eye : float, keyword-only
        Height of the eye, metres.
    tops : (n,) array_like of float, keyword-only
        Height of each ray's end, metres.

    Returns
    -------
    clear : (n,) ndarray of bool

    Examples
    --------
    >>> import numpy as np
    >>> lo = np.full((1, 5), np.inf); hi = np.full((1, 5), -np.inf)
    >>> lo[0, 2], hi[0, 2] = 0.0, 0.8                      # a 0.8 m table in the middle cell
    >>> rays_clear_above(lo, hi, (0, 0), [[0, 4], [0, 4]], eye=1.0, tops=[0.0, 0.9]).tolist()
    [False, True]
    """
    lo = np.ascontiguousarray(z_low, dtype=np.float64)
    hi = np.ascontiguousarray(z_high, dtype=np.float64)
    if lo.ndim != 2 or lo.shape != hi.shape:
        raise ValueError(f"z_low and z_high must be (H, W) arrays of one shape, got {lo.shape} and {hi.shape}")
    if np.isnan(lo).any() or np.isnan(hi).any():
        raise ValueError("z_low and z_high must not be NaN (+inf / -inf mark cells that never / always hide)")
    t = np.asarray(targets, dtype=np.int64).reshape(-1, 2)
    z = np.asarray(tops, dtype=np.float64).reshape(-1)
    if z.shape[0] != t.shape[0]:
        raise ValueError(f"tops must have one height per target, got {z.shape[0]} for {t.shape[0]} targets")
    if not (np.isfinite(eye) and np.all(np.isfinite(z))):
        raise ValueError(f"eye and tops must be finite heights in metres, got eye={eye!r}")
    h, w = lo.shape
    r0, c0 = int(origin[0]), int(origin[1])
    if not (0 <= r0 < h and 0 <= c0 < w):
        raise ValueError(f"origin must lie inside the {h} x {w} grid, got {(r0, c0)}")
    if t.size and (t[:, 0].min() < 0 or t[:, 0].max() >= h or t[:, 1].min() < 0 or t[:, 1].max() >= w):
        raise ValueError(f"targets must lie inside the {h} x {w} grid")
    from ..kernels._sight import clear_above  # compiled on first use (numba)

    clear = np.empty(t.shape[0], dtype=bool)
    clear_above(lo, hi, r0, c0, float(eye), t, z, clear)
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

    def table(self, origin) -> np.ndarray:
        """The (H, W) int8 table of the ``origin`` cell (row, col): 1 clear, 0 blocked, −1 not traversed yet
        (:meth:`clear_from` fills it); the cache's own array, counted as a use of the origin."""
        key = (int(origin[0]), int(origin[1]))
        table = self._tables.get(key)
        if table is None:
            table = np.full(self.occupancy.shape, -1, dtype=np.int8)
            self._tables[key] = table
            if len(self._tables) > self.capacity:
                self._tables.popitem(last=False)
        else:
            self._tables.move_to_end(key)
        return table

    def clear_from(self, origin, targets) -> np.ndarray:
        """(n,) bool: line of sight from the ``origin`` cell (row, col) to each target cell (n, 2)."""
        key = (int(origin[0]), int(origin[1]))
        table = self.table(key)
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
def visible_from(occupancy: np.ndarray, cell, *, reach: int, disc=None, camera=None) -> np.ndarray:
    """Cells whose centre is in line of sight of the centre of ``cell`` (the rule of :func:`cells_clear`,
    except that the two end cells may be occupied), restricted to candidate cells.

    The shadow cast of the module docstring, compiled (:mod:`psgsl_pgm.kernels._sight`).

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
    cell : (2,) int
        (row, col) of the viewpoint.
    reach : int
        Largest Chebyshev distance (in cells) of a candidate from ``cell``.
    disc : float, optional
        Candidates: the cells whose centre is within ``disc`` cells of the viewpoint.
    camera : psgsl_pgm.geometry._fov._Camera, optional
        Candidates: the cells in the camera's range and opening angle (:mod:`psgsl_pgm.kernels._view`); the
        cast stops once the shadows cover every direction from ``cell`` that such a cell can still have (the
        cone around the heading widened by ``arcsin(offset / k)`` at ring k, ``offset`` being the distance of
        the camera from the cell centre). Exactly one of ``disc`` and ``camera``.

    Returns
    -------
    visible : (H, W) ndarray of bool
    """
    from ..kernels._sight import cast  # compiled on first use (numba)

    if (disc is None) == (camera is None):
        raise TypeError("visible_from needs exactly one of disc and camera")
    return cast(occupancy, cell, reach=reach, disc=disc, camera=camera)
