"""Grid geometry shared by the olfactory estimators: validated occupancy, frame, outlets, position -> cell.

Convention (shared with :func:`psgsl_pgm.field_of_view` and ``psgsl_pgm.sim``): row index <-> y, column
index <-> x, row 0 at the lowest y; cell (r, c) has its centre at
``(origin_x + (c + 0.5) * resolution, origin_y + (r + 0.5) * resolution)``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["GridGeometry", "as_wind_field", "as_wind_vector"]


def _as_mask(x, name: str, shape=None) -> np.ndarray:
    """(H, W) boolean mask from a bool array or an integer array of 0/1 (own, read-only copy)."""
    if x is None or isinstance(x, (str, bytes)):
        raise TypeError(f"{name} must be a boolean (H, W) array, got {type(x).__name__} {x!r}")
    arr = np.asarray(x)
    if arr.dtype != bool:
        if not np.issubdtype(arr.dtype, np.integer) or not np.isin(arr, (0, 1)).all():
            raise TypeError(f"{name} must be a boolean (H, W) array (or integers 0/1), got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise ValueError(f"{name} must be a non-empty (H, W) array, got shape {arr.shape}")
    if shape is not None and arr.shape != tuple(shape):
        raise ValueError(f"{name} must have the map's shape {tuple(shape)}, got {arr.shape}")
    out = np.array(arr, dtype=bool)
    out.flags.writeable = False
    return out


def as_wind_field(wind, shape, free: np.ndarray, name: str = "wind") -> np.ndarray:
    """Validated (H, W, 2) float64 wind field (u_x, u_y) in m/s; ``None`` means still air.

    An object with a ``.velocity`` (H, W, 2) array (e.g. ``psgsl_pgm.sim.WindField``) is accepted too.
    Values on occupied cells are ignored (set to 0): walls carry no flow, and a wind solver may leave
    anything there. Free cells must be finite.
    """
    h, w = shape
    if wind is not None and not isinstance(wind, np.ndarray) and hasattr(wind, "velocity"):
        wind = wind.velocity
    if wind is None:
        out = np.zeros((h, w, 2))
        out.flags.writeable = False
        return out
    if isinstance(wind, (str, bytes)):
        raise TypeError(f"{name} must be a numeric (H, W, 2) array in m/s, got {type(wind).__name__}")
    arr = np.asarray(wind)
    if arr.dtype == object or not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
        raise TypeError(f"{name} must be a real numeric (H, W, 2) array in m/s, got dtype {arr.dtype}")
    if arr.shape != (h, w, 2):
        raise ValueError(f"{name} must have shape {(h, w, 2)} (u_x, u_y per cell), got {arr.shape}")
    out = np.array(arr, dtype=np.float64)
    out[~free] = 0.0
    if not np.isfinite(out).all():
        r, c, _ = np.argwhere(~np.isfinite(out))[0]
        raise ValueError(f"{name} must be finite on free cells, got {out[r, c]} at cell {(int(r), int(c))}")
    out.flags.writeable = False
    return out


def as_wind_vector(wind, name: str = "wind"):
    """``None`` or a validated (u_x, u_y) tuple of floats in m/s."""
    if wind is None:
        return None
    w = real_pair(wind, name, "a (u_x, u_y)", "m/s")
    return (float(w[0]), float(w[1]))


def real_pair(value, name: str, what: str, unit: str) -> np.ndarray:
    """Validate a finite pair of real numbers, e.g. a position (x, y) or a wind vector; (2,) float64."""
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name} must be {what} pair in {unit}, got {type(value).__name__}")
    p = np.asarray(value)
    if p.dtype == object or not np.issubdtype(p.dtype, np.number) or np.iscomplexobj(p):
        raise TypeError(f"{name} must be {what} pair of real numbers in {unit}, got dtype {p.dtype}")
    if p.shape != (2,):
        raise ValueError(f"{name} must be {what} pair in {unit}, got shape {p.shape}")
    p = p.astype(np.float64)
    if not np.isfinite(p).all():
        raise ValueError(f"{name} must be finite, got {tuple(p)}")
    return p


class GridGeometry:
    """Occupancy grid in a metric frame, with optional absorbing outlet cells.

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
        True = occupied (wall / obstacle); integer 0/1 arrays are accepted.
    resolution : float
        Cell side in metres (> 0).
    origin : (2,) array_like of float
        Map-frame (x, y) of the lower-left corner of cell (0, 0), in metres.
    outlets : (H, W) ndarray of bool, optional
        Free cells through which gas leaves the domain (open windows/doors to the outside). They must not be
        occupied.

    Examples
    --------
    >>> import numpy as np
    >>> g = GridGeometry(np.zeros((3, 4), bool), resolution=0.5, origin=(-1.0, 2.0))
    >>> g.cell_of((0.9, 3.4))
    (2, 3)
    >>> g.centre_of((2, 3))
    (0.75, 3.25)
    """

    def __init__(self, occupancy, *, resolution, origin=(0.0, 0.0), outlets=None):
        occ = _as_mask(occupancy, "occupancy")
        try:
            res = float(resolution)
        except (TypeError, ValueError):
            raise TypeError(f"resolution must be a positive number in metres, got {resolution!r}") from None
        if not (np.isfinite(res) and res > 0):
            raise ValueError(f"resolution must be a positive finite number in metres, got {resolution!r}")
        try:
            org = tuple(float(v) for v in origin)
        except (TypeError, ValueError):
            raise TypeError(f"origin must be an (x, y) pair of numbers, got {origin!r}") from None
        if len(org) != 2 or not np.all(np.isfinite(org)):
            raise ValueError(f"origin must be a finite (x, y) pair in metres, got {origin!r}")
        if occ.all():
            raise ValueError("occupancy has no free cell: there is nowhere for a source or a sensor to be")
        if outlets is None:
            out = np.zeros(occ.shape, dtype=bool)
            out.flags.writeable = False
        else:
            out = _as_mask(outlets, "outlets", occ.shape)
            if (out & occ).any():
                r, c = np.argwhere(out & occ)[0]
                raise ValueError(f"outlets must be free cells, got an outlet on occupied cell {(int(r), int(c))}")
        self.occupancy = occ
        self.resolution = res
        self.origin = org
        self.outlets = out
        free = ~occ
        free.flags.writeable = False
        self.free = free

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W): rows (along y) and columns (along x)."""
        return self.occupancy.shape

    def cell_of(self, position, name: str = "position") -> tuple[int, int]:
        """Grid cell (row, col) containing a map-frame point; refuses points outside the map or in walls.

        Parameters
        ----------
        position : (2,) array_like of float
            (x, y) in metres.

        Returns
        -------
        cell : tuple of int
            (row, col).
        """
        p = real_pair(position, name, "an (x, y)", "metres")
        col = int(np.floor((p[0] - self.origin[0]) / self.resolution))
        row = int(np.floor((p[1] - self.origin[1]) / self.resolution))
        h, w = self.shape
        if not (0 <= row < h and 0 <= col < w):
            x0, y0 = self.origin
            raise ValueError(
                f"{name} {tuple(p)} lies outside the map (x in [{x0}, {x0 + w * self.resolution}), "
                f"y in [{y0}, {y0 + h * self.resolution}))"
            )
        if self.occupancy[row, col]:
            raise ValueError(f"{name} {tuple(p)} falls in occupied cell {(row, col)}; a sensor must be in free space")
        return row, col

    def check_cell(self, cell, name: str = "cell") -> tuple[int, int]:
        """Validated (row, col) of a free cell of the map."""
        try:
            r, c = (int(v) for v in cell)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be a (row, col) pair of integers, got {cell!r}") from None
        h, w = self.shape
        if not (0 <= r < h and 0 <= c < w):
            raise ValueError(f"{name} {(r, c)} lies outside the {h} x {w} grid")
        if self.occupancy[r, c]:
            raise ValueError(f"{name} {(r, c)} is occupied")
        return r, c

    def centre_of(self, cell) -> tuple[float, float]:
        """Map-frame centre (x, y) of cell (row, col)."""
        r, c = cell
        return (self.origin[0] + (c + 0.5) * self.resolution, self.origin[1] + (r + 0.5) * self.resolution)

    def cell_centres(self) -> np.ndarray:
        """(H, W, 2) map-frame centres (x, y) of every cell."""
        h, w = self.shape
        x = self.origin[0] + (np.arange(w) + 0.5) * self.resolution
        y = self.origin[1] + (np.arange(h) + 0.5) * self.resolution
        xx, yy = np.meshgrid(x, y, indexing="xy")
        return np.stack([xx, yy], axis=-1)

    @classmethod
    def from_grid_map(cls, grid_map, *, outlets=None) -> "GridGeometry":
        """Geometry of any object with ``.occupancy``, ``.resolution`` and ``.origin`` (e.g. ``sim.GridMap``)."""
        missing = [a for a in ("occupancy", "resolution", "origin") if not hasattr(grid_map, a)]
        if missing:
            raise TypeError(
                f"grid_map must have .occupancy, .resolution and .origin; {type(grid_map).__name__} lacks "
                f"{', '.join('.' + m for m in missing)}"
            )
        return cls(grid_map.occupancy, resolution=grid_map.resolution, origin=grid_map.origin, outlets=outlets)


def positive(value, name: str, unit: str = "") -> float:
    """A positive finite number (bools and strings refused); ``unit`` is named in the messages."""
    where = f" in {unit}" if unit else ""
    if isinstance(value, (bool, str, bytes)) or value is None:
        raise TypeError(f"{name} must be a positive number{where}, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a positive number{where}, got {value!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number{where}, got {value!r}")
    return v
