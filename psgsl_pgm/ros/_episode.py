"""One recorded episode as plain arrays: what the bag and MCAP writers take (no simulator objects)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["START_NS", "Episode", "stamp_ns"]

#: Wall-clock stamp (ns) of an episode's t = 0: 2023-11-14 22:13:20 UTC, a fixed epoch, so bags are reproducible.
START_NS = 1_700_000_000 * 1_000_000_000


def stamp_ns(t, start_ns: int = START_NS) -> np.ndarray:
    """Integer nanosecond stamps of episode times ``t`` (s since the episode's start)."""
    return start_ns + np.round(np.asarray(t, dtype=np.float64) * 1e9).astype(np.int64)


@dataclass(eq=False)
class Episode:
    """A robot's episode in the map frame (times in seconds since the episode's start).

    Attributes
    ----------
    grid : psgsl_pgm.GridMap
        The occupancy grid.
    pose_t : (p,) ndarray, pose : (p, 3) ndarray
        Robot pose samples (x, y, yaw).
    gas_t : (m,) ndarray, gas : (m,) ndarray
        Gas readings, ppm (taken at the robot's pose).
    wind_t : (w,) ndarray, wind : (w, 2) ndarray
        Anemometer readings, the wind vector in the map frame, m/s.
    frame_t : (f,) ndarray
        Camera frame times (the camera looks along the robot's heading at that time).
    frame_cells : list of (n_i, 2) int ndarray
        Cells (row, col) reported as an object in each frame.
    frame_labels : list of (n_i,) sequence of str
        Their class names.
    objects : list of (class name, (n, 2) footprint, (z0, z1)) tuples
        The scene's objects, for drawing.
    classes : tuple of str
        Class names of ``best_class``.
    variants : tuple of str
        Names of the posteriors.
    step_t : (s,) ndarray
        Time of each estimator step.
    posteriors : (s, V, H, W) ndarray
        The posterior of every variant after each step.
    best_class : (s, H, W) uint8 ndarray or None
        The most likely class per cell after each step (None: the variants keep no class beliefs).
    chosen : (s, 3) ndarray
        The pose chosen next after each step (NaN: none).
    threshold : float
        The gas sensor's hit threshold, ppm.
    meta : dict
        World, source, seed, estimator (JSON-able).
    """

    grid: object
    pose_t: np.ndarray
    pose: np.ndarray
    gas_t: np.ndarray
    gas: np.ndarray
    wind_t: np.ndarray
    wind: np.ndarray
    frame_t: np.ndarray
    frame_cells: list
    frame_labels: list
    objects: list = field(default_factory=list)
    classes: tuple = ()
    variants: tuple = ()
    step_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    posteriors: np.ndarray | None = None
    best_class: np.ndarray | None = None
    chosen: np.ndarray | None = None
    threshold: float = 1.0
    meta: dict = field(default_factory=dict)
