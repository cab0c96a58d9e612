"""The occupancy grid map and the map-frame <-> grid-index conversion.

Convention (shared with :func:`psgsl_pgm.field_of_view`): row index <-> y, column index <-> x, row 0 at the
map's lowest y; cell (r, c) has its centre at ``origin + ((c + 0.5) * resolution, (r + 0.5) * resolution)``.
Image files (PGM/PNG) store row 0 at the *top*, so loaders flip them vertically.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GridMap"]


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
        occ = np.asarray(self.occupancy)
        if occ.ndim != 2 or occ.shape[0] < 1 or occ.shape[1] < 1:
            raise ValueError(f"occupancy must be a non-empty (H, W) array, got shape {occ.shape}")
        if occ.dtype != bool:
            if not np.issubdtype(occ.dtype, np.integer) or not np.isin(occ, (0, 1)).all():
                raise TypeError(f"occupancy must be a boolean (H, W) array, got dtype {occ.dtype}")
        occ = np.array(occ, dtype=bool)  # own, read-only copy
        occ.flags.writeable = False
        try:
            res = float(self.resolution)
        except (TypeError, ValueError):
            raise TypeError(f"resolution must be a positive number in metres, got {self.resolution!r}") from None
        if not (np.isfinite(res) and res > 0):
            raise ValueError(f"resolution must be a positive finite number in metres, got {self.resolution!r}")
        try:
            origin = tuple(float(v) for v in self.origin)
        except (TypeError, ValueError):
            raise TypeError(f"origin must be an (x, y) pair of numbers, got {self.origin!r}") from None
        if len(origin) != 2 or not np.all(np.isfinite(origin)):
            raise ValueError(f"origin must be a finite (x, y) pair in metres, got {self.origin!r}")
        object.__setattr__(self, "occupancy", occ)
        object.__setattr__(self, "resolution", res)
        object.__setattr__(self, "origin", origin)

    # --- geometry -------------------------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """(H, W): rows (along y) and columns (along x)."""
        return self.occupancy.shape

    @property
    def free(self) -> np.ndarray:
        """(H, W) bool: not occupied."""
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
        col = np.floor((p[..., 0] - self.origin[0]) / self.resolution)
        row = np.floor((p[..., 1] - self.origin[1]) / self.resolution)
        return np.stack([row, col], axis=-1).astype(np.int64)

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
        rr, cc = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
        return self.cell_to_world(np.stack([rr, cc], axis=-1))

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

    def coarsen(self, factor: int, *, occupied_fraction: float = 0.5) -> "GridMap":
        """Block-reduce by an integer ``factor`` (e.g. 0.01 m -> 0.1 m with ``factor=10``).

        A coarse cell is occupied when at least ``occupied_fraction`` of its fine cells are (use a tiny value
        for "any"). Rows/columns that do not fill a whole block are padded as occupied.
        """
        f = _check_factor(factor)
        if not 0 < occupied_fraction <= 1:
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
