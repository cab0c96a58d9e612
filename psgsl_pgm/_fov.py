"""Camera field of view on an occupancy grid, and φ_O(p) = Σ_{n ∈ F_p} I(S; O_n) (Sec. "Information Gain
Optimization")."""

from __future__ import annotations

import numpy as np

from ._validate import as_float_array, describe

__all__ = ["field_of_view", "view_information_gain"]

_SAMPLES_PER_CELL = 5  # line-of-sight samples per cell length along each ray


def _occupancy(occupancy) -> np.ndarray:
    occ = np.asarray(occupancy)
    if occ.ndim != 2 or occ.size == 0:
        raise ValueError(f"occupancy must be a non-empty (H, W) grid, got {describe(occ)}")
    if occ.dtype != bool:
        if not np.issubdtype(occ.dtype, np.number) or not np.all(np.isin(occ, (0, 1))):
            raise TypeError(f"occupancy must be boolean (True = occupied) or 0/1, got {describe(occ)}")
        occ = occ.astype(bool)
    return occ


def _positive(x, name, *, allow_zero=False) -> float:
    if isinstance(x, (bool, np.bool_)) or not np.isscalar(x) or not np.isreal(x):
        raise TypeError(f"{name} must be a real number, got {x!r}")
    x = float(x)
    if not np.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        raise ValueError(f"{name} must be {'non-negative' if allow_zero else 'positive'} and finite, got {x}")
    return x


def field_of_view(occupancy, pose, *, max_range, half_angle, min_range=0.0, resolution=1.0, origin=(0.0, 0.0)):
    """Cells seen by a camera at ``pose``: the set F_p of Sec. "Information Gain Optimization".

    A cell is visible when its centre lies within ``[min_range, max_range]`` of the camera and within
    ``half_angle`` of its heading, and the segment from the camera to that centre crosses no occupied cell
    other than the target itself (so walls and objects are seen, but nothing behind them). The segment is
    tested at ``resolution / 5`` steps: an occupied cell clipped over a shorter stretch (a corner) does not
    block, nor do two occupied cells that touch only at a corner.

    Parameters
    ----------
    occupancy : (H, W) array_like of bool
        True = occupied. Row index ↔ y, column index ↔ x; cell (r, c) has its centre at
        ``(origin[0] + (c + 0.5) * resolution, origin[1] + (r + 0.5) * resolution)``.
    pose : (3,) array_like
        Camera ``(x, y, heading)``; heading in radians, 0 along +x (+column), π/2 along +y (+row).
    max_range, min_range : float
        Range limits, in the units of ``pose``.
    half_angle : float
        Half the horizontal opening angle, radians, in (0, π].
    resolution : float, default 1.0
        Cell size in the units of ``pose``.
    origin : (2,) array_like, default (0, 0)
        World coordinates of the lower-left corner of cell (0, 0).

    Returns
    -------
    visible : (H, W) ndarray of bool

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import field_of_view
    >>> occ = np.zeros((5, 7), bool); occ[:, 3] = True               # a wall at column 3
    >>> seen = field_of_view(occ, (1.5, 2.5, 0.0), max_range=10, half_angle=np.pi)
    >>> bool(seen[2, 3]), bool(seen[2, 4:].any())                     # the wall, not what is behind it
    (True, False)
    """
    occ = _occupancy(occupancy)
    p = as_float_array(pose, "pose", dtype=np.float64, ndim=1)
    if p.shape != (3,):
        raise ValueError(f"pose must be (x, y, heading), got {describe(p)}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"pose must be finite, got {p.tolist()}")
    max_range = _positive(max_range, "max_range")
    min_range = _positive(min_range, "min_range", allow_zero=True)
    half_angle = _positive(half_angle, "half_angle")
    if half_angle > np.pi:
        raise ValueError(f"half_angle must be at most π, got {half_angle}")
    if min_range > max_range:
        raise ValueError(f"min_range ({min_range}) must not exceed max_range ({max_range})")
    res = _positive(resolution, "resolution")
    org = as_float_array(origin, "origin", dtype=np.float64, ndim=1)
    if org.shape != (2,):
        raise ValueError(f"origin must be (x, y), got {describe(org)}")

    h, w = occ.shape
    x, y, heading = p
    col0, row0 = (x - org[0]) / res, (y - org[1]) / res  # continuous grid coordinates of the camera
    if not (0 <= col0 < w and 0 <= row0 < h):
        raise ValueError(f"pose ({x}, {y}) lies outside the map (extent {w * res} × {h * res} from origin {org.tolist()})")

    reach = int(np.ceil(max_range / res)) + 1
    r_lo, r_hi = max(0, int(row0) - reach), min(h, int(row0) + reach + 1)
    c_lo, c_hi = max(0, int(col0) - reach), min(w, int(col0) + reach + 1)
    rows, cols = np.mgrid[r_lo:r_hi, c_lo:c_hi]
    dx, dy = (cols + 0.5 - col0) * res, (rows + 0.5 - row0) * res
    dist = np.hypot(dx, dy)
    bearing = np.angle(np.exp(1j * (np.arctan2(dy, dx) - heading)))  # wrapped to (−π, π]
    candidate = (dist >= min_range) & (dist <= max_range) & ((np.abs(bearing) <= half_angle) | (dist < 1e-12 * res))
    rows, cols = rows[candidate], cols[candidate]

    n_samples = max(2, int(np.ceil(_SAMPLES_PER_CELL * max_range / res)))
    t = (np.arange(n_samples) + 0.5) / n_samples  # interior of each segment
    sr = np.floor(row0 + t[None, :] * (rows + 0.5 - row0)[:, None]).astype(np.intp)
    sc = np.floor(col0 + t[None, :] * (cols + 0.5 - col0)[:, None]).astype(np.intp)
    np.clip(sr, 0, h - 1, out=sr)
    np.clip(sc, 0, w - 1, out=sc)
    is_target = (sr == rows[:, None]) & (sc == cols[:, None])
    is_start = (sr == int(row0)) & (sc == int(col0))
    blocked = np.any(occ[sr, sc] & ~is_target & ~is_start, axis=1)

    visible = np.zeros((h, w), dtype=bool)
    visible[rows[~blocked], cols[~blocked]] = True
    return visible


def view_information_gain(information_gain, occupancy, pose, **fov):
    """Semantic information gain of a camera pose, φ_O(p) = Σ_{n ∈ F_p} I(S; O_n).

    Parameters
    ----------
    information_gain : (H, W) array_like
        I(S; O_n) per cell, e.g. from :func:`semantic_information_gain`.
    occupancy : (H, W) array_like of bool
        As for :func:`field_of_view`.
    pose : (3,) or (P, 3) array_like
        One camera pose (x, y, heading), or P candidate poses.
    **fov
        Keyword options of :func:`field_of_view` (``max_range``, ``half_angle`` are required).

    Returns
    -------
    phi : float or (P,) ndarray
        φ_O for the pose, or for each candidate pose.
    """
    gain = as_float_array(information_gain, "information_gain", dtype=np.float64, ndim=2)
    occ = _occupancy(occupancy)
    if gain.shape != occ.shape:
        raise ValueError(f"information_gain must have the occupancy's shape {occ.shape}, got {describe(gain)}")
    if not np.all(np.isfinite(gain)):
        raise ValueError("information_gain must be finite")
    poses = as_float_array(pose, "pose", dtype=np.float64)
    if poses.ndim == 1:
        return float(gain[field_of_view(occ, poses, **fov)].sum())
    if poses.ndim != 2 or poses.shape[1] != 3:
        raise ValueError(f"pose must be (3,) or (P, 3), got {describe(poses)}")
    return np.array([gain[field_of_view(occ, p, **fov)].sum() for p in poses])  # loop over poses
