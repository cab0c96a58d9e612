"""Camera views of the house: beliefs after a survey, and candidate poses for φ_O(p)."""

from __future__ import annotations

import numpy as np

from ..sim import Camera, DetectorModel, take_frame

__all__ = ["candidate_poses", "survey"]


def survey(house, poses, semantic_map, *, seed, camera=None, detector=None, layer_edges=None):
    """Update ``semantic_map`` in place with one simulated camera frame from each pose.

    Each frame is :func:`psgsl_pgm.sim.take_frame` (the detector's labels sampled from the true classes) and
    :meth:`psgsl_pgm.sim.SemanticMap.update` (Bayes' rule, p(o | z, z') ∝ p(o | z) p(z' | o)).

    Parameters
    ----------
    house : psgsl_pgm.sim.House
    poses : (P, 3) array_like
        Camera poses (x, y, heading), metres and radians.
    semantic_map : psgsl_pgm.sim.SemanticMap
        2-D (H, W, k) or voxel (H, W, L, k) beliefs in the detector's class order.
    seed : int, keyword-only
        Seeds the detector's noise.
    camera : psgsl_pgm.sim.Camera, optional, keyword-only
        Default ``Camera()``.
    detector : psgsl_pgm.sim.DetectorModel, optional, keyword-only
        Default ``DetectorModel.default(house.classes)``.
    layer_edges : (L + 1,) array_like, optional, keyword-only
        Voxel layer boundaries (metres) for a voxel map.

    Returns
    -------
    psgsl_pgm.sim.SemanticMap
        ``semantic_map``, updated.

    Raises
    ------
    ValueError
        ``poses`` is not (P, 3), or :func:`psgsl_pgm.sim.take_frame` refuses the detector or the frame.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.sim import SemanticMap, default_house
    >>> from psgsl_pgm.teaching import survey
    >>> house = default_house(seed=0)
    >>> m = SemanticMap.from_prior(house.shape, np.full(14, 1 / 14), house.classes)
    >>> survey(house, [(7.5, 3.0, -1.5)], m, seed=0).n_frames
    1
    """
    p = np.asarray(poses, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"poses must be a (P, 3) array of (x, y, heading), got shape {p.shape}")
    camera = Camera() if camera is None else camera
    detector = DetectorModel.default(house.classes) if detector is None else detector
    rng = np.random.default_rng(seed)
    for pose in p:  # loop over a handful of frames
        semantic_map.update(take_frame(house, pose, camera=camera, detector=detector, rng=rng,
                                       layer_edges=layer_edges))
    return semantic_map


def candidate_poses(house, *, spacing, n_headings=8, clearance=0.3):
    """A lattice of camera poses on the free floor: positions every ``spacing`` metres × ``n_headings``.

    A position is kept when every cell within ``clearance`` of it is free of walls, furniture and windows
    (``house.robot_obstacles``).

    Parameters
    ----------
    house : psgsl_pgm.sim.House
    spacing : float, keyword-only
        Lattice step, metres.
    n_headings : int, default 8, keyword-only
        Headings 0, 2π/n, …, evenly spaced.
    clearance : float, default 0.3, keyword-only
        Metres of free space around the robot.

    Returns
    -------
    poses : (Q · n_headings, 3) ndarray
        (x, y, heading), position-major: ``poses.reshape(Q, n_headings, 3)`` groups the headings of one
        position.

    Raises
    ------
    ValueError
        ``spacing`` is not a positive number, ``n_headings`` is not a positive int, or ``clearance`` is negative.

    Examples
    --------
    >>> from psgsl_pgm.sim import default_house
    >>> from psgsl_pgm.teaching import candidate_poses
    >>> poses = candidate_poses(default_house(seed=0), spacing=1.0, n_headings=4)
    >>> poses.shape[1], poses.shape[0] % 4
    (3, 0)
    """
    import scipy.ndimage as ndi

    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be positive metres, got {spacing!r}")
    if isinstance(n_headings, (bool, np.bool_)) or not isinstance(n_headings, (int, np.integer)) or n_headings < 1:
        raise ValueError(f"n_headings must be a positive int, got {n_headings!r}")
    if not (np.isfinite(clearance) and clearance >= 0):
        raise ValueError(f"clearance must be non-negative metres, got {clearance!r}")
    g = house.grid
    radius = int(np.ceil(clearance / g.resolution))
    disk = np.hypot(*np.mgrid[-radius:radius + 1, -radius:radius + 1]) <= radius
    blocked = ndi.binary_dilation(house.robot_obstacles, structure=disk)  # cells too close to an obstacle
    x0, x1, y0, y1 = g.extent
    xs = np.arange(x0 + spacing / 2, x1, spacing)
    ys = np.arange(y0 + spacing / 2, y1, spacing)
    xy = np.stack(np.meshgrid(xs, ys, indexing="xy"), axis=-1).reshape(-1, 2)
    rc = g.world_to_cell(xy)
    keep = g.contains(rc)
    keep[keep] = ~blocked[rc[keep][:, 0], rc[keep][:, 1]]
    xy = xy[keep]
    headings = 2 * np.pi * np.arange(n_headings) / n_headings
    return np.column_stack([np.repeat(xy, n_headings, axis=0), np.tile(headings, xy.shape[0])])
