"""Camera frames: what a camera at a pose sees of the house, and what the detector reports there.

The horizontal field of view is the core :func:`psgsl_pgm.field_of_view` on the walls (furniture is low and
does not hide anything in 2-D): the same light-tight line of sight as the gas model's. Only free cells are observed (walls are not part of any object class). With
voxel layers, a voxel of a visible column is in view when its centre lies within the camera's vertical
half-angle.

What a camera sees from a pose depends on the walls only, so the visible cells are kept per grid (for as long
as the grid lives) and pose: a robot that looks again from the same pose does not recompute its view.
"""

from __future__ import annotations

import functools

import weakref
from dataclasses import dataclass

import numpy as np

from .._shared._validate import positive
from ..geometry._fov import field_of_view
from ._classes import OTHER, match_names
from ._detector import DetectorModel

__all__ = ["Camera", "Frame", "take_frame"]

_VIEWS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # GridMap -> {(camera, pose): flat cells}
_VIEWS_PER_GRID = 1024  # poses kept per grid (the oldest goes first)


@dataclass(frozen=True)
class Camera:
    """A forward-looking camera on the robot.

    Parameters
    ----------
    max_range, min_range : float
        Range limits, metres.
    half_angle : float
        Half the horizontal opening, radians (default 35°, a 70° lens).
    height : float
        Mounting height, metres (voxel maps only).
    vertical_half_angle : float
        Half the vertical opening, radians (voxel maps only).
    """

    max_range: float = 4.0
    half_angle: float = float(np.deg2rad(35.0))
    min_range: float = 0.2
    height: float = 1.0
    vertical_half_angle: float = float(np.deg2rad(30.0))

    def __post_init__(self):
        for name in ("max_range", "half_angle", "min_range", "height", "vertical_half_angle"):
            unit = "radians" if "angle" in name else "metres"
            object.__setattr__(self, name, positive(getattr(self, name), f"Camera.{name}", unit,
                                                    allow_zero=name in ("min_range", "height")))
        if not (0 <= self.min_range < self.max_range and np.isfinite(self.max_range)):
            raise ValueError(f"need 0 <= min_range < max_range, got {self.min_range!r}, {self.max_range!r}")
        if not 0 < self.half_angle <= np.pi:
            raise ValueError(f"half_angle must lie in (0, π], got {self.half_angle!r}")
        if not 0 < self.vertical_half_angle <= np.pi / 2:
            raise ValueError(f"vertical_half_angle must lie in (0, π/2], got {self.vertical_half_angle!r}")

    def visible(self, grid, pose) -> np.ndarray:
        """(H, W) bool: free cells in view from ``pose`` = (x, y, heading)."""
        h, w = grid.shape
        seen = np.zeros(h * w, dtype=bool)
        seen[self._visible_flat(grid, pose)] = True
        return seen.reshape(h, w)

    def _visible_flat(self, grid, pose) -> np.ndarray:
        """Row-major flat indices of the free cells in view from ``pose`` (read-only; kept per grid and pose)."""
        pose = np.asarray(pose, dtype=np.float64)
        key = (self, pose.shape, pose.tobytes())  # the pose bit for bit
        views = _VIEWS.get(grid)
        if views is None:
            views = _VIEWS[grid] = {}
        flat = views.get(key)
        if flat is None:
            seen = field_of_view(grid.occupancy, pose, max_range=self.max_range, half_angle=self.half_angle,
                                 min_range=self.min_range, resolution=grid.resolution, origin=grid.origin)
            flat = np.flatnonzero(seen & grid.free)
            flat.flags.writeable = False
            if len(views) >= _VIEWS_PER_GRID:
                views.pop(next(iter(views)), None)  # the oldest pose
            views[key] = flat
        return flat

    def voxels_in_view(self, distance, layer_centres) -> np.ndarray:
        """(n, L) bool: voxels at horizontal ``distance`` (n,) and heights ``layer_centres`` (L,) in view."""
        d = np.asarray(distance, dtype=np.float64)[:, None]
        dz = np.asarray(layer_centres, dtype=np.float64)[None, :] - self.height
        return np.abs(np.arctan2(dz, d)) <= self.vertical_half_angle


@dataclass(frozen=True, eq=False)
class Frame:
    """One camera frame: the observed cells (or voxels), the labels reported and their likelihoods.

    Attributes
    ----------
    pose : (3,) ndarray
    cells : (n, 2) ndarray of int
        (row, col) of each observation.
    layers : (n,) ndarray of int or None
        Voxel layer of each observation (voxel frames only).
    distance : (n,) ndarray
        Horizontal camera–cell-centre distance, m.
    labels : (n,) ndarray of int
        Reported label indices into ``detector.labels``.
    likelihood : (n, k) ndarray
        p(z_n | o) over the detector's classes, for :func:`psgsl_pgm.update_class_probs`.
    classes : tuple of str
    """

    pose: np.ndarray
    cells: np.ndarray
    layers: np.ndarray | None
    distance: np.ndarray
    labels: np.ndarray
    likelihood: np.ndarray
    classes: tuple


@functools.lru_cache(maxsize=64)
def _class_index(house_classes: tuple, classes: tuple) -> np.ndarray:
    """Index into ``classes`` of each of the house's classes (absent classes -> ``other``), read-only."""
    idx = match_names(house_classes, classes)
    if OTHER not in classes:
        raise ValueError(f"classes must include {OTHER!r}, got {classes}")
    idx = np.where(idx < 0, list(classes).index(OTHER), idx)
    idx.flags.writeable = False
    return idx


def _true_classes(house, classes, layer_edges, cells):
    """The true class of each of the (n, 2) ``cells`` (the 2-D class map; (n, L) for a voxel map), indexed into
    ``classes``."""
    idx = _class_index(tuple(house.classes), tuple(classes))
    if layer_edges is None:
        return idx[house.class_map[cells[:, 0], cells[:, 1]]]
    return idx[house.voxel_class_map(layer_edges)[cells[:, 0], cells[:, 1]]]


def take_frame(house, pose, *, camera: Camera, detector: DetectorModel, rng, model: DetectorModel | None = None,
               layer_edges=None) -> Frame:
    """Simulate one camera frame of ``house`` from ``pose`` and the detector's reports.

    Parameters
    ----------
    house : House
    pose : (3,) array_like
        (x, y, heading) in metres / radians.
    camera : Camera, keyword-only
    detector : DetectorModel, keyword-only
        Generates the labels from the true classes.
    rng : numpy.random.Generator, keyword-only
    model : DetectorModel, optional, keyword-only
        The robot's model of its detector, used for the likelihoods (default: ``detector`` itself, i.e. a
        well-calibrated detector). Must have the same classes.
    layer_edges : (L + 1,) array_like, optional, keyword-only
        Voxel layer boundaries (metres); gives a voxel frame.

    Returns
    -------
    Frame
    """
    model = detector if model is None else model
    if model.classes != detector.classes:
        raise ValueError(f"model classes {model.classes} differ from the detector's {detector.classes}")
    pose = np.asarray(pose, dtype=np.float64)
    g = house.grid
    cells = np.stack(np.divmod(camera._visible_flat(g, pose), g.shape[1]), axis=-1)  # np.argwhere of the view
    dist = np.linalg.norm(g.cell_to_world(cells) - pose[:2], axis=-1)
    truth = _true_classes(house, detector.classes, layer_edges, cells)
    layers = None
    if layer_edges is None:
        true_c = truth
    else:
        edges = np.asarray(layer_edges, dtype=np.float64)
        in_view = camera.voxels_in_view(dist, (edges[:-1] + edges[1:]) / 2)  # (n, L)
        ci, layers = np.nonzero(in_view)
        cells, dist = cells[ci], dist[ci]
        true_c = truth[ci, layers]
    labels = detector.sample(true_c, dist, rng)
    lik = model.likelihood(labels, dist)
    return Frame(pose, cells, layers, dist, labels, lik, detector.classes)
