"""Wind given to the olfactory estimators: a validated (H, W, 2) field or one (u_x, u_y) vector in m/s."""

from __future__ import annotations

import numpy as np

from .._shared._validate import as_float_array, real_pair

__all__ = ["as_wind_field", "as_wind_vector"]


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
    arr = as_float_array(wind, name, dtype=np.float64)
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
