"""Camera frames: what a camera at a pose sees of the house, and what the detector reports there.

The horizontal field of view is the core :func:`psgsl_pgm.field_of_view` on the walls: the same light-tight line
of sight as the gas model's. Only free cells are observed (walls are not part of any object class). With
voxel layers, a voxel of a visible column is in view when its centre lies within the camera's vertical
half-angle.

Occlusion (``Camera.occlusion``):

* ``"walls"`` (default): furniture hides nothing (the camera looks over it);
* ``"furniture"``: walls hide everything behind them, and furniture hides by height (2.5-D). A cell holding
  objects occupies the heights [z_low, z_high) — the lowest ``z_min`` and the highest ``z_max`` of the objects
  covering it. The camera's eye is at ``height`` h above the centre of its cell; a target cell is seen when the
  ray from the eye to the target's top z_t (the highest ``z_max`` of its objects, 0 for a floor cell) clears
  every cell between: a cell at the fraction t = d / D of the way (d the projection of its centre on the
  camera–target segment, D that segment's length) hides the target when
  z_low ≤ h + (z_t − h) · t < z_high (:func:`psgsl_pgm.geometry._sight.rays_clear_above`). So a floor cell
  behind a table is hidden when the table's top is above the ray to the floor, an object behind a taller one
  is hidden, and a lower one in front of it hides nothing (the far cells of a flat top seen from above stay in
  view; a ray that only grazes a top face passes). In a voxel frame a column seen by this rule shows the
  voxels within the vertical opening (the rule is not applied per voxel).

What a camera sees from a pose depends on the walls only, so the visible cells are kept per grid (for as long
as the grid lives) and pose: a robot that looks again from the same pose does not recompute its view.
"""

from __future__ import annotations

import functools

import weakref
from dataclasses import dataclass, replace

import numpy as np

from .._shared._validate import positive
from ..geometry._fov import field_of_view
from ..geometry._sight import rays_clear_above
from ._classes import OTHER, match_names
from ._detector import DetectorErrors, DetectorModel

__all__ = ["Camera", "Frame", "OCCLUSIONS", "take_frame"]

#: What hides cells from the camera: the walls only (default), or the walls and the furniture by its height.
OCCLUSIONS = ("walls", "furniture")

_VIEWS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # GridMap or House -> {(camera, pose): flat cells}
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
    occlusion : {"walls", "furniture"}
        What hides cells: the walls only, or the walls and the furniture by its height above the floor, seen
        from ``height`` (module docstring).

    Examples
    --------
    >>> from psgsl_pgm.sim import Camera, default_house
    >>> house = default_house(0)
    >>> pose = (6.5, 2.5, 0.0)                        # in the kitchen, looking at the dining table
    >>> walls, both = Camera(), Camera(occlusion="furniture")
    >>> int(walls.visible(house.grid, pose).sum()) > int(both.visible(house.grid, pose, house=house).sum())
    True
    """

    max_range: float = 4.0
    half_angle: float = float(np.deg2rad(35.0))
    min_range: float = 0.2
    height: float = 1.0
    vertical_half_angle: float = float(np.deg2rad(30.0))
    occlusion: str = "walls"

    def __post_init__(self):
        if self.occlusion not in OCCLUSIONS:
            raise ValueError(f"Camera.occlusion must be one of {OCCLUSIONS}, got {self.occlusion!r}")
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

    def visible(self, grid, pose, *, house=None) -> np.ndarray:
        """(H, W) bool: free cells in view from ``pose`` = (x, y, heading).

        ``house`` (keyword-only, a :class:`House` on ``grid``) gives the furniture's heights; it is required when
        ``occlusion="furniture"`` and unused otherwise.
        """
        h, w = grid.shape
        seen = np.zeros(h * w, dtype=bool)
        seen[self._visible_flat(grid, pose, house=house)] = True
        return seen.reshape(h, w)

    def _visible_flat(self, grid, pose, *, house=None) -> np.ndarray:
        """Row-major flat indices of the free cells in view from ``pose`` (read-only; kept per grid and pose)."""
        if self.occlusion == "furniture":
            return self._behind_furniture(grid, pose, house)
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

    def _behind_furniture(self, grid, pose, house) -> np.ndarray:
        """The walls-only view without the cells the furniture hides (module docstring); kept per house and pose."""
        from ._house import House

        if not isinstance(house, House):
            raise TypeError(f"Camera(occlusion='furniture') needs the house (house=House) for the furniture's "
                            f"heights, got {type(house).__name__}")
        if house.grid is not grid:
            raise ValueError("house must be the House whose grid is given (the furniture's heights on that grid)")
        pose = np.asarray(pose, dtype=np.float64)
        key = (self, pose.shape, pose.tobytes())
        views = _VIEWS.get(house)
        if views is None:
            views = _VIEWS[house] = {}
        flat = views.get(key)
        if flat is None:
            walls = replace(self, occlusion="walls")._visible_flat(grid, pose)
            z_low, z_high = _extents(house)
            cells = np.stack(np.divmod(walls, grid.shape[1]), axis=-1)
            eye = grid.world_to_cell(pose[:2])
            eye = np.clip(eye, 0, np.array(grid.shape) - 1)
            top = np.where(np.isfinite(z_high), z_high, 0.0).ravel()[walls]
            clear = rays_clear_above(z_low, z_high, eye, cells, eye=self.height, tops=top)
            flat = walls[clear]
            flat.flags.writeable = False
            if len(views) >= _VIEWS_PER_GRID:
                views.pop(next(iter(views)), None)
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
    bearing : (n,) ndarray or None
        Bearing of each cell centre off the optical axis, radians in (−π, π] (None unless the detector's
        detection probability depends on it).
    """

    pose: np.ndarray
    cells: np.ndarray
    layers: np.ndarray | None
    distance: np.ndarray
    labels: np.ndarray
    likelihood: np.ndarray
    classes: tuple
    bearing: np.ndarray | None = None


def _extents(house):
    """(z_low, z_high), each (H, W): the lowest z_min and the highest z_max of the objects covering each cell
    (+inf, −inf where none), kept with the house."""

    def make():
        lo = np.full(house.shape, np.inf)
        hi = np.full(house.shape, -np.inf)
        for o, m in zip(house.objects, house.object_masks):
            lo[m] = np.minimum(lo[m], o.z_range[0])
            hi[m] = np.maximum(hi[m], o.z_range[1])
        lo.flags.writeable = hi.flags.writeable = False
        return lo, hi

    return house._cached("camera_extents", make)


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


def _instances(house, layer_edges):
    """(H, W) int (or (H, W, L) for voxel layers): index into ``house.objects`` of the instance the class map
    shows in each cell (the last object covering it), −1 where none."""
    key = ("camera_instances", None if layer_edges is None else tuple(np.asarray(layer_edges, float).tolist()))

    def make():
        if layer_edges is None:
            out = np.full(house.shape, -1, dtype=np.int64)
            for i, m in enumerate(house.object_masks):
                out[m] = i
            return out
        edges = np.asarray(layer_edges, dtype=np.float64)
        out = np.full(house.shape + (edges.size - 1,), -1, dtype=np.int64)
        for i, (o, m) in enumerate(zip(house.objects, house.object_masks)):
            layers = (edges[:-1] < o.z_range[1]) & (edges[1:] > o.z_range[0])
            sub = out[m]
            sub[:, layers] = i
            out[m] = sub
        return out

    return house._cached(key, make)


def _persist(labels, cells, layers, house, detector, errors, dist, bearing, rng, layer_edges):
    """``labels`` with the world's errors applied (:mod:`psgsl_pgm.sim._detector`): per instance one draw per
    frame (probability ρ) makes each of its detections read its persistent label; each distractor cell in view
    reads its site's label with probability p_d(d, β). Draws: one per object, one per distractor cell in view."""
    labels = labels.copy()
    inst = _instances(house, layer_edges)
    inst = inst[cells[:, 0], cells[:, 1]] if layer_edges is None else inst[cells[:, 0], cells[:, 1], layers]
    coin = rng.random(len(house.objects)) < detector.persistence
    keep = (labels != detector.nothing) & (inst >= 0)
    keep[keep] = coin[inst[keep]]
    labels[keep] = errors.instance_label[inst[keep]]
    if errors.site_map.shape != house.shape:
        raise ValueError(f"errors were drawn on a {errors.site_map.shape} map, the house is {house.shape}")
    site = errors.site_map[cells[:, 0], cells[:, 1]]
    on_site = site >= 0
    if layer_edges is not None:
        on_site &= layers == 0  # a surface on the floor: the bottom layer
    if on_site.any():
        pd = detector.detection_probability(dist[on_site], None if bearing is None else bearing[on_site])
        show = rng.random(int(on_site.sum())) < pd
        where = np.flatnonzero(on_site)[show]
        labels[where] = site[where]
    return labels


def take_frame(house, pose, *, camera: Camera, detector: DetectorModel, rng, model: DetectorModel | None = None,
               layer_edges=None, errors: DetectorErrors | None = None) -> Frame:
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
    errors : DetectorErrors, optional, keyword-only
        The world's persistent instance labels and distractor sites (:meth:`DetectorErrors.draw`); needed when
        the detector has ``persistence`` or ``distractors``, and then applied to the labels.

    Returns
    -------
    Frame

    Raises
    ------
    ValueError
        ``model`` has other classes than ``detector``; a detector with persistence or distractors is given no
        ``errors``; ``errors`` were drawn for another number of objects.
    TypeError
        ``errors`` is not a :class:`DetectorErrors`.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.sim import Camera, DetectorModel, default_house, take_frame
    >>> house = default_house(seed=0)
    >>> frame = take_frame(house, (7.5, 3.0, -1.5), camera=Camera(), detector=DetectorModel.default(house.classes),
    ...                    rng=np.random.default_rng(0))
    >>> frame.cells.shape[1], frame.likelihood.shape[1] == len(house.classes)   # (row, col) and p(z | o) per cell
    (2, True)
    """
    model = detector if model is None else model
    if model.classes != detector.classes:
        raise ValueError(f"model classes {model.classes} differ from the detector's {detector.classes}")
    if errors is not None and not isinstance(errors, DetectorErrors):
        raise TypeError(f"errors must be DetectorErrors (or None), got {type(errors).__name__}")
    if detector.correlated and errors is None:
        raise ValueError("a detector with persistence or distractors needs the world's errors (errors="
                         "DetectorErrors.draw(detector, house, rng)); World.camera_frame passes them")
    if errors is not None and len(errors.instance_label) != len(house.objects):
        raise ValueError(f"errors were drawn for {len(errors.instance_label)} objects, the house has "
                         f"{len(house.objects)}")
    pose = np.asarray(pose, dtype=np.float64)
    g = house.grid
    cells = np.stack(np.divmod(camera._visible_flat(g, pose, house=house), g.shape[1]), axis=-1)  # argwhere
    offset = g.cell_to_world(cells) - pose[:2]
    dist = np.linalg.norm(offset, axis=-1)
    truth = _true_classes(house, detector.classes, layer_edges, cells)
    layers = None
    if layer_edges is None:
        true_c = truth
    else:
        edges = np.asarray(layer_edges, dtype=np.float64)
        in_view = camera.voxels_in_view(dist, (edges[:-1] + edges[1:]) / 2)  # (n, L)
        ci, layers = np.nonzero(in_view)
        cells, dist, offset = cells[ci], dist[ci], offset[ci]
        true_c = truth[ci, layers]
    bearing = None
    if detector.angle_power > 0 or model.angle_power > 0:
        bearing = np.arctan2(offset[:, 1], offset[:, 0]) - pose[2]
        bearing = np.arctan2(np.sin(bearing), np.cos(bearing))  # wrapped to (−π, π]
    labels = detector.sample(true_c, dist, rng, bearing)
    if errors is not None:
        labels = _persist(labels, cells, layers, house, detector, errors, dist, bearing, rng, layer_edges)
    lik = model.likelihood(labels, dist, bearing)
    return Frame(pose, cells, layers, dist, labels, lik, detector.classes, bearing)
