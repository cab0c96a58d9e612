"""The occupancy grid map: frame, map-frame <-> grid-index conversion, coarsening, free-space graph.

Convention (shared by every part of the package: :func:`psgsl_pgm.field_of_view`, ``psgsl_pgm.sim``,
``psgsl_pgm.olfaction``, ``psgsl_pgm.experiment``): row index <-> y, column index <-> x, row 0 at the map's
lowest y; cell (r, c) has its centre at ``origin + ((c + 0.5) * resolution, (r + 0.5) * resolution)``.
Image files (PGM/PNG) store row 0 at the *top*, so loaders flip them vertically.

Line of sight between cells is :mod:`psgsl_pgm.geometry._sight` (:meth:`GridMap.line_of_sight`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .._shared._validate import bool_mask, positive, real_pair
from ._sight import cells_clear

__all__ = ["GridMap", "free_space_graph"]


@dataclass(frozen=True, eq=False)
class GridMap:
    """A 2-D occupancy grid in a metric map frame.

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
        True = occupied (wall / obstacle). Row 0 is at the lowest y. Stored read-only.
    resolution : float
        Cell side in metres (> 0).
    origin : (2,) tuple of float
        Map-frame (x, y) of the lower-left corner of cell (0, 0), in metres.

    Examples
    --------
    >>> import numpy as np
    >>> g = GridMap(np.zeros((3, 4), bool), 0.5, (-1.0, 2.0))
    >>> g.world_to_cell([[-0.9, 2.1], [0.9, 3.4]])
    array([[0, 0],
           [2, 3]])
    >>> g.cell_to_world([2, 3])
    array([0.75, 3.25])
    """

    occupancy: np.ndarray
    resolution: float
    origin: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        occ = bool_mask(self.occupancy, "occupancy")  # own, read-only copy
        res = positive(self.resolution, "resolution", "metres")
        origin = real_pair(self.origin, "origin", "an (x, y)", "metres")
        object.__setattr__(self, "occupancy", occ)
        object.__setattr__(self, "resolution", res)
        object.__setattr__(self, "origin", (float(origin[0]), float(origin[1])))

    # --- geometry -------------------------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """(H, W): rows (along y) and columns (along x)."""
        return self.occupancy.shape

    @property
    def free(self) -> np.ndarray:
        """(H, W) bool: not occupied (a new array)."""
        return ~self.occupancy

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) of the map in metres (for ``imshow(..., origin="lower")``)."""
        h, w = self.shape
        x0, y0 = self.origin
        return (x0, x0 + w * self.resolution, y0, y0 + h * self.resolution)

    def world_to_cell(self, xy) -> np.ndarray:
        """Grid indices (row, col) of the cells containing map-frame points.

        Parameters
        ----------
        xy : (..., 2) array_like
            Points (x, y) in metres.

        Returns
        -------
        rc : (..., 2) ndarray of int64
            (row, col); may lie outside the grid (see :meth:`contains`).
        """
        p = np.asarray(xy, dtype=np.float64)
        if p.ndim == 0 or p.shape[-1] != 2:
            raise ValueError(f"xy must have shape (..., 2) (x, y in metres), got shape {p.shape}")
        with np.errstate(over="ignore"):  # x = 1e308 m: an infinite column, far outside (below)
            col = np.floor((p[..., 0] - self.origin[0]) / self.resolution)
            row = np.floor((p[..., 1] - self.origin[1]) / self.resolution)
        far = float(2**62)  # a point beyond int64 (x = 1e30 m) is a cell far outside, not an overflowing cast
        return np.clip(np.stack([row, col], axis=-1), -far, far).astype(np.int64)

    def cell_to_world(self, rc) -> np.ndarray:
        """Map-frame centres (x, y) of grid cells; inverse of :meth:`world_to_cell` on cell centres.

        Parameters
        ----------
        rc : (..., 2) array_like of int
            (row, col) indices.

        Returns
        -------
        xy : (..., 2) ndarray of float64
        """
        idx = np.asarray(rc)
        if idx.ndim == 0 or idx.shape[-1] != 2:
            raise ValueError(f"rc must have shape (..., 2) (row, col), got shape {idx.shape}")
        if not np.issubdtype(idx.dtype, np.integer):
            raise TypeError(f"rc must hold integer (row, col) indices, got dtype {idx.dtype}")
        x = self.origin[0] + (idx[..., 1] + 0.5) * self.resolution
        y = self.origin[1] + (idx[..., 0] + 0.5) * self.resolution
        return np.stack([x, y], axis=-1)

    def contains(self, rc) -> np.ndarray:
        """(...) bool: whether (row, col) indices lie inside the grid."""
        idx = np.asarray(rc)
        h, w = self.shape
        return (idx[..., 0] >= 0) & (idx[..., 0] < h) & (idx[..., 1] >= 0) & (idx[..., 1] < w)

    def cell_centres(self) -> np.ndarray:
        """(H, W, 2) map-frame centres (x, y) of every cell."""
        h, w = self.shape
        x = self.origin[0] + (np.arange(w) + 0.5) * self.resolution
        y = self.origin[1] + (np.arange(h) + 0.5) * self.resolution
        xx, yy = np.meshgrid(x, y, indexing="xy")
        return np.stack([xx, yy], axis=-1)

    def line_of_sight(self, rc0, rc1) -> np.ndarray:
        """(n,) bool: whether the segments between cell centres ``rc0`` and ``rc1`` ((n, 2) (row, col)) cross
        no occupied cell, end cells included; light-tight at corners (see :func:`psgsl_pgm.geometry._sight.cells_clear`)."""
        return cells_clear(self.occupancy, rc0, rc1)

    def free_space_graph(self, mask=None):
        """8-connected graph of the free cells (or of ``mask``), no corner cutting; see :func:`free_space_graph`."""
        free = self.free if mask is None else bool_mask(mask, "mask", self.shape)
        return free_space_graph(free, self.resolution)

    def cell_of(self, position, name: str = "position") -> tuple[int, int]:
        """The free cell (row, col) containing one map-frame point; refuses points outside the map or in walls.

        Parameters
        ----------
        position : (2,) array_like of float
            (x, y) in metres.
        name : str
            Argument name used in error messages.
        """
        p = real_pair(position, name, "an (x, y)", "metres")
        row, col = (int(v) for v in self.world_to_cell(p))
        h, w = self.shape
        if not (0 <= row < h and 0 <= col < w):
            x0, y0, x1, y1 = self.extent[0], self.extent[2], self.extent[1], self.extent[3]
            raise ValueError(f"{name} {tuple(p.tolist())} lies outside the map (x in [{x0}, {x1}), y in [{y0}, {y1}))")
        if self.occupancy[row, col]:
            raise ValueError(
                f"{name} {tuple(p.tolist())} falls in occupied cell {(row, col)}; a sensor must be in free space"
            )
        return row, col

    def check_cell(self, cell, name: str = "cell") -> tuple[int, int]:
        """Validated (row, col) of a free cell of the map."""
        try:
            r, c = cell
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be a (row, col) pair of integers, got {cell!r}") from None
        if any(isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) for v in (r, c)):
            raise TypeError(f"{name} must be a (row, col) pair of integers, got {cell!r}")
        r, c = int(r), int(c)
        h, w = self.shape
        if not (0 <= r < h and 0 <= c < w):
            raise ValueError(f"{name} {(r, c)} lies outside the {h} x {w} grid")
        if self.occupancy[r, c]:
            raise ValueError(f"{name} {(r, c)} is occupied")
        return r, c

    def centre_of(self, cell) -> tuple[float, float]:
        """Map-frame centre (x, y) of one cell (row, col), as a tuple of floats."""
        x, y = self.cell_to_world(np.asarray(cell, dtype=np.int64))
        return float(x), float(y)

    def is_occupied(self, xy) -> np.ndarray:
        """(...) bool: whether points fall in an occupied cell; points outside the map count as occupied."""
        rc = self.world_to_cell(xy)
        inside = self.contains(rc)
        out = np.ones(rc.shape[:-1], dtype=bool)
        out[inside] = self.occupancy[rc[inside][:, 0], rc[inside][:, 1]]
        return out

    # --- derived maps ---------------------------------------------------------------------------------------
    def with_occupancy(self, occupancy) -> "GridMap":
        """Same frame, another (H, W) occupancy."""
        occ = np.asarray(occupancy)
        if occ.shape != self.shape:
            raise ValueError(f"occupancy must have the grid's shape {self.shape}, got {occ.shape}")
        return GridMap(occ, self.resolution, self.origin)

    def coarsen(self, factor: int, *, occupied_fraction: float | str = 0.5) -> "GridMap":
        """Block-reduce by an integer ``factor`` (e.g. 0.01 m -> 0.1 m with ``factor=10``).

        A coarse cell is occupied when at least ``occupied_fraction`` of its fine cells are; with
        ``occupied_fraction="any"`` when any fine cell is (conservative: a wall one fine cell thick stays a
        wall, and the coarse map stays light-tight wherever the fine one is). Rows/columns that do not fill a
        whole block are padded as occupied.
        """
        f = _check_factor(factor)
        if isinstance(occupied_fraction, str):
            if occupied_fraction != "any":
                raise ValueError(f"occupied_fraction must be a number in (0, 1] or 'any', got {occupied_fraction!r}")
            frac = block_mean(self.occupancy.astype(np.float64), f, pad_value=1.0)
            return GridMap(frac > 0, self.resolution * f, self.origin)
        if isinstance(occupied_fraction, bool) or not 0 < occupied_fraction <= 1:
            raise ValueError(f"occupied_fraction must lie in (0, 1], got {occupied_fraction!r}")
        frac = block_mean(self.occupancy.astype(np.float64), f, pad_value=1.0)
        return GridMap(frac >= occupied_fraction - 1e-12, self.resolution * f, self.origin)

    def __repr__(self) -> str:
        h, w = self.shape
        return (
            f"GridMap({h}x{w} cells, resolution={self.resolution:g} m, origin={self.origin}, "
            f"{int(self.occupancy.sum())} occupied)"
        )


def _check_factor(factor) -> int:
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ValueError(f"factor must be a positive integer, got {factor!r}")
    return int(factor)


def block_mean(a: np.ndarray, factor: int, *, pad_value: float) -> np.ndarray:
    """Mean over ``factor`` x ``factor`` blocks of a 2-D array, padding the last partial blocks."""
    h, w = a.shape
    hh, ww = -(-h // factor), -(-w // factor)
    padded = np.full((hh * factor, ww * factor), pad_value, dtype=np.float64)
    padded[:h, :w] = a
    return padded.reshape(hh, factor, ww, factor).mean(axis=(1, 3))


def free_space_graph(free: np.ndarray, resolution: float) -> sp.csr_matrix:
    """8-connected graph of free cells with edge lengths h and h√2, without corner cutting.

    A diagonal step between two free cells is an edge only when both cells beside it (the two orthogonal
    neighbours it passes) are free too, so no path squeezes between two occupied cells that touch at a corner.

    Parameters
    ----------
    free : (H, W) ndarray of bool
        Cells that may be visited.
    resolution : float
        Cell side h, metres.

    Returns
    -------
    graph : (H*W, H*W) scipy.sparse.csr_matrix
        Symmetric, over row-major flat cell indices; cells that are not free have no edges.

    Examples
    --------
    >>> import numpy as np
    >>> free = np.ones((2, 2), bool); free[0, 1] = free[1, 0] = False    # two free cells touching at a corner
    >>> free_space_graph(free, 1.0).nnz
    0
    """
    free = np.asarray(free, dtype=bool)
    h, w = free.shape
    idx = np.arange(h * w).reshape(h, w)
    rows, cols, vals = [], [], []
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
        c0, c1 = max(0, -dc), w - max(0, dc)
        a = (slice(0, h - dr), slice(c0, c1))
        b = (slice(dr, h), slice(c0 + dc, c1 + dc))
        ok = free[a] & free[b]
        if dr and dc:  # the two cells beside the diagonal step must be free: no corner cutting
            ok &= free[(slice(dr, h), slice(c0, c1))] & free[(slice(0, h - dr), slice(c0 + dc, c1 + dc))]
        length = resolution * (np.sqrt(2.0) if (dr and dc) else 1.0)
        ia, ib = idx[a][ok], idx[b][ok]
        rows += [ia, ib]
        cols += [ib, ia]
        vals += [np.full(ia.size, length)] * 2
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(h * w, h * w))
