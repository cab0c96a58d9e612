"""The house: walls, windows, rooms and objects on one grid — and the embedded default house.

Modelling choices (2-D):

* **walls** (``grid.occupancy``) block everything: wind, gas filaments, the camera's line of sight and the
  robot;
* **furniture** (object cells) is low: wind, gas and the camera pass over it (gas is 3-D, the camera sits
  above it), but the robot must not drive through it (``robot_obstacles``);
* **windows** are openings in the outer wall (free cells): the inlet carries φ = 1, the outlet φ = 0 for the
  potential flow, and a filament entering an outlet leaves the house. The robot does not drive into them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import scipy.ndimage as ndi

from .._shared._validate import positive, real_pair
from ..geometry._grid import GridMap
from ._classes import HOUSE_CLASSES, HOUSE_ROOMS, OTHER
from ._objects import SceneObject, box_footprint

__all__ = ["House", "default_house", "segment_mask"]


@dataclass(frozen=True, eq=False)
class House:
    """A grid map with room categories, objects and the inlet/outlet windows.

    Parameters
    ----------
    grid : GridMap
        Walls only (windows are free cells).
    room_labels : (H, W) ndarray of int
        Index into ``room_names``; -1 = no room (walls, outside).
    room_names : tuple of str
    objects : tuple of SceneObject
        Later objects overwrite earlier ones where they share cells (an appliance on a countertop).
    inlet, outlet : (H, W) ndarray of bool
        Window cells.
    classes : tuple of str
        Class list for :attr:`class_map`; must contain every object's class and ``"other"``.
    """

    grid: GridMap
    room_labels: np.ndarray
    room_names: tuple
    objects: tuple
    inlet: np.ndarray
    outlet: np.ndarray
    classes: tuple = HOUSE_CLASSES
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        if not isinstance(self.grid, GridMap):
            raise TypeError(f"grid must be a GridMap, got {type(self.grid).__name__}")
        shape = self.grid.shape
        labels = np.array(self.room_labels)
        if labels.shape != shape or not np.issubdtype(labels.dtype, np.integer):
            raise ValueError(f"room_labels must be an integer array of shape {shape}, got {labels.shape} {labels.dtype}")
        names = tuple(str(n) for n in self.room_names)
        if labels.size and (labels.min() < -1 or labels.max() >= len(names)):
            raise ValueError(f"room_labels must lie in [-1, {len(names) - 1}] for {len(names)} room names")
        objs = tuple(self.objects)
        for o in objs:
            if not isinstance(o, SceneObject):
                raise TypeError(f"objects must be SceneObject instances, got {type(o).__name__}")
        classes = tuple(self.classes)
        if OTHER not in classes:
            raise ValueError(f"classes must include the catch-all {OTHER!r}, got {classes}")
        unknown = sorted({o.class_name for o in objs} - set(classes))
        if unknown:
            raise ValueError(f"object classes {unknown} are not in classes {classes}")
        masks = []
        for name in ("inlet", "outlet"):
            m = np.array(getattr(self, name))
            if m.shape != shape or m.dtype != bool:
                raise ValueError(f"{name} must be a boolean mask of shape {shape}, got {m.shape} {m.dtype}")
            if (m & self.grid.occupancy).any():
                raise ValueError(f"{name} cells must be free in grid (windows are openings)")
            m.flags.writeable = False
            masks.append(m)
        labels = labels.astype(np.int64)
        labels.flags.writeable = False
        object.__setattr__(self, "room_labels", labels)
        object.__setattr__(self, "room_names", names)
        object.__setattr__(self, "objects", objs)
        object.__setattr__(self, "classes", classes)
        object.__setattr__(self, "inlet", masks[0])
        object.__setattr__(self, "outlet", masks[1])

    @classmethod
    def from_maps(cls, grid: GridMap, room_labels, room_names, *, inlets, outlets, window_width: float = 0.15,
                  objects=(), classes=HOUSE_CLASSES) -> "House":
        """Assemble a house from loaded maps, opening the windows given as wall segments.

        Parameters
        ----------
        grid : GridMap
            Walls (e.g. :func:`load_ros_map` of a walls-only map, possibly coarsened).
        room_labels, room_names
            As returned by :func:`load_room_map` (in ``grid``'s frame).
        inlets, outlets : sequence of ((x0, y0), (x1, y1)), keyword-only
            Window segments in metres; cells within ``window_width`` of a segment become free window cells.
        window_width : float, keyword-only
        objects : sequence of SceneObject, keyword-only
        classes : tuple of str, keyword-only
        """
        inlet = np.zeros(grid.shape, bool)
        outlet = np.zeros(grid.shape, bool)
        for mask, segs, name in ((inlet, inlets, "inlets"), (outlet, outlets, "outlets")):
            for seg in segs:
                try:
                    p0, p1 = seg
                except (TypeError, ValueError):
                    raise ValueError(f"{name} must be a list of ((x0, y0), (x1, y1)) segments, got {seg!r}") from None
                mask |= segment_mask(grid, p0, p1, width=window_width)
            if not mask.any():
                raise ValueError(f"{name}: no cell lies within {window_width} m of the given segments")
        if (inlet & outlet).any():
            raise ValueError("inlet and outlet windows overlap")
        opened = grid.with_occupancy(grid.occupancy & ~inlet & ~outlet)
        return cls(opened, room_labels, room_names, tuple(objects), inlet, outlet, tuple(classes))

    # --- derived maps (cached) ------------------------------------------------------------------------------
    def _cached(self, key, make):
        if key not in self._cache:
            value = make()
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            self._cache[key] = value
        return self._cache[key]

    @property
    def shape(self) -> tuple[int, int]:
        return self.grid.shape

    @property
    def object_masks(self) -> tuple:
        """(H, W) bool mask of each object, in ``objects`` order."""
        return self._cached("masks", lambda: tuple(o.mask(self.grid) & self.grid.free for o in self.objects))

    @property
    def furniture(self) -> np.ndarray:
        """(H, W) bool: cells covered by any object."""
        return self._cached("furniture", lambda: np.any(self.object_masks, axis=0) if self.objects
                            else np.zeros(self.shape, bool))

    @property
    def robot_obstacles(self) -> np.ndarray:
        """(H, W) bool: walls, furniture and windows — where the robot may not be."""
        return self.grid.occupancy | self.furniture | self.inlet | self.outlet

    @property
    def class_map(self) -> np.ndarray:
        """(H, W) int: index into ``classes`` of each cell's true class (``other`` where no object)."""

        def make():
            out = np.full(self.shape, self.classes.index(OTHER), dtype=np.int64)
            for o, m in zip(self.objects, self.object_masks):
                out[m] = self.classes.index(o.class_name)
            return out

        return self._cached("class_map", make)

    def voxel_class_map(self, layer_edges) -> np.ndarray:
        """(H, W, L) int: true class of each voxel for layers [z_l, z_{l+1}) (``other`` where empty).

        An object fills a layer when its height range overlaps the layer; later objects win ties.
        """
        edges = np.asarray(layer_edges, dtype=np.float64)
        if edges.ndim != 1 or edges.size < 2 or not np.all(np.diff(edges) > 0):
            raise ValueError(f"layer_edges must be an increasing 1-D array of >= 2 heights, got {layer_edges!r}")
        out = np.full(self.shape + (edges.size - 1,), self.classes.index(OTHER), dtype=np.int64)
        for o, m in zip(self.objects, self.object_masks):
            z0, z1 = o.z_range
            layers = (edges[:-1] < z1) & (edges[1:] > z0)
            sub = out[m]
            sub[:, layers] = self.classes.index(o.class_name)
            out[m] = sub
        return out

    def objects_of_class(self, class_name: str) -> list:
        """The objects of one class."""
        return [o for o in self.objects if o.class_name == class_name]

    def room_of(self, xy) -> np.ndarray:
        """(...) room index of map-frame points (-1 outside rooms or the map)."""
        rc = self.grid.world_to_cell(xy)
        inside = self.grid.contains(rc)
        out = np.full(rc.shape[:-1], -1, dtype=np.int64)
        out[inside] = self.room_labels[rc[inside][:, 0], rc[inside][:, 1]]
        return out

    def __repr__(self) -> str:
        return (
            f"House({self.grid!r}, rooms={list(self.room_names)}, {len(self.objects)} objects, "
            f"inlet={int(self.inlet.sum())} cells, outlet={int(self.outlet.sum())} cells)"
        )


def segment_mask(grid: GridMap, p0, p1, *, width: float) -> np.ndarray:
    """(H, W) bool: cells whose centre lies within ``width`` of the segment p0–p1 (e.g. a window).

    Parameters
    ----------
    grid : GridMap
        The map whose cells are tested.
    p0, p1 : (float, float)
        The segment's ends (x, y), metres.
    width : float, keyword-only
        The distance from the segment, metres (> 0).

    Returns
    -------
    (H, W) ndarray of bool

    Raises
    ------
    TypeError
        ``grid`` is not a :class:`GridMap`, or an end or ``width`` is not made of real numbers.
    ValueError
        An end is not a finite (x, y) pair, or ``width`` is not positive and finite.

    Examples
    --------
    >>> g = GridMap(np.zeros((4, 6), bool), 1.0)
    >>> segment_mask(g, (1.0, 0.0), (4.0, 0.0), width=0.6).sum()
    np.int64(3)
    """
    if not isinstance(grid, GridMap):
        raise TypeError(f"grid must be a GridMap, got {type(grid).__name__} {grid!r}")
    a = real_pair(p0, "p0", "an (x, y)", "metres")
    b = real_pair(p1, "p1", "an (x, y)", "metres")
    width = positive(width, "width", "metres")
    c = grid.cell_centres()
    d = b - a
    with np.errstate(over="ignore", invalid="ignore"):  # a segment ~1e154 m away: no cell is near it (NaN <= w)
        t = np.clip(((c - a) @ d) / max(d @ d, 1e-300), 0.0, 1.0)
        dist = np.linalg.norm(c - (a + t[..., None] * d), axis=-1)
        return dist <= width


# ---- the embedded default house ------------------------------------------------------------------------------
_RES = 0.1
_SIZE = (10.0, 12.0)  # x, y extent in metres
_T = 0.2  # wall thickness

# Walls as [x0, x1) x [y0, y1) rectangles in metres; doors are cut out afterwards.
_WALLS = [
    (0.0, 10.0, 0.0, _T), (0.0, 10.0, 12.0 - _T, 12.0), (0.0, _T, 0.0, 12.0), (10.0 - _T, 10.0, 0.0, 12.0),
    (0.0, 10.0, 5.0, 5.2),  # living room / kitchen | hallway
    (5.8, 6.0, 0.0, 5.2),  # living room | kitchen
    (0.0, 10.0, 6.8, 7.0),  # hallway | bedroom, bathroom, bedroom 2
    (5.6, 5.8, 6.8, 12.0),  # bedroom | bathroom
    (7.6, 7.8, 6.8, 12.0),  # bathroom | bedroom 2
]
_DOORS = [
    (2.0, 3.0, 5.0, 5.2),  # living room - hallway
    (7.0, 8.0, 5.0, 5.2),  # kitchen - hallway
    (5.8, 6.0, 3.6, 4.6),  # living room - kitchen
    (1.6, 2.6, 6.8, 7.0),  # hallway - bedroom
    (6.4, 7.2, 6.8, 7.0),  # hallway - bathroom
    (8.4, 9.2, 6.8, 7.0),  # hallway - bedroom 2
]
_INLET = (8.2, 9.4, 12.0 - _T, 12.0)  # window in bedroom 2's outer wall
_OUTLET = (1.0, 2.4, 0.0, _T)  # window in the living room's outer wall
_ROOMS = [  # (room, rectangle)
    ("Kitchen", (6.0, 9.8, 0.2, 5.0)),
    ("LivingRoom", (0.2, 5.8, 0.2, 5.0)),
    ("Hallway", (0.2, 9.8, 5.2, 6.8)),
    ("Bedroom", (0.2, 5.6, 7.0, 11.8)),
    ("Bathroom", (5.8, 7.6, 7.0, 11.8)),
    ("Bedroom", (7.8, 9.8, 7.0, 11.8)),
]
# Objects: (class, [x0, x1) x [y0, y1), (z_min, z_max), jitter group, (max |dx|, max |dy|) in metres).
# Objects of one jitter group move together (a table and its chairs); later objects overwrite earlier cells.
_OBJECTS = [
    # kitchen
    ("countertop", (6.0, 9.8, 0.2, 0.8), (0.0, 0.9), None, (0.0, 0.0)),
    ("countertop", (9.2, 9.8, 0.8, 2.4), (0.0, 0.9), None, (0.0, 0.0)),
    ("oven", (7.2, 7.8, 0.2, 0.8), (0.0, 0.9), "oven", (0.3, 0.0)),
    ("sink", (8.5, 9.1, 0.25, 0.75), (0.6, 0.9), "ksink", (0.1, 0.0)),
    ("toaster", (6.3, 6.6, 0.3, 0.6), (0.9, 1.1), "toaster", (0.2, 0.0)),
    ("microwave", (9.25, 9.75, 1.4, 1.9), (0.9, 1.2), "micro", (0.0, 0.3)),
    ("refrigerator", (9.1, 9.8, 4.2, 4.9), (0.0, 1.8), None, (0.0, 0.0)),
    ("dining table", (7.0, 8.4, 2.2, 3.2), (0.0, 0.75), "table", (0.2, 0.2)),
    ("chair", (7.2, 7.6, 1.7, 2.1), (0.0, 0.9), "table", (0.2, 0.2)),
    ("chair", (7.8, 8.2, 1.7, 2.1), (0.0, 0.9), "table", (0.2, 0.2)),
    ("chair", (7.2, 7.6, 3.3, 3.7), (0.0, 0.9), "table", (0.2, 0.2)),
    ("chair", (7.8, 8.2, 3.3, 3.7), (0.0, 0.9), "table", (0.2, 0.2)),
    # living room
    ("couch", (0.3, 1.2, 1.6, 3.6), (0.0, 0.8), "couch", (0.0, 0.3)),
    ("tv", (5.4, 5.8, 1.6, 2.8), (0.5, 1.3), "couch", (0.0, 0.3)),
    ("chair", (3.8, 4.3, 0.5, 1.0), (0.0, 0.9), "lchair", (0.3, 0.2)),
    ("potted plant", (0.3, 0.7, 4.4, 4.9), (0.0, 1.0), None, (0.0, 0.0)),
    ("potted plant", (5.2, 5.7, 0.3, 0.8), (0.0, 1.0), None, (0.0, 0.0)),
    # hallway
    ("potted plant", (9.3, 9.7, 5.3, 5.7), (0.0, 1.0), None, (0.0, 0.0)),
    # bathroom
    ("toilet", (6.9, 7.5, 11.0, 11.7), (0.0, 0.8), "toilet", (0.0, 0.1)),
    ("sink", (5.9, 6.4, 10.0, 10.6), (0.7, 0.9), "bsink", (0.0, 0.3)),
    # bedroom
    ("bed", (2.0, 4.0, 9.6, 11.7), (0.0, 0.6), "bed", (0.3, 0.0)),
    ("tv", (3.4, 4.6, 7.0, 7.3), (0.6, 1.4), "btv", (0.3, 0.0)),
    ("chair", (4.8, 5.3, 7.3, 7.8), (0.0, 0.9), None, (0.0, 0.0)),
    ("potted plant", (0.3, 0.7, 11.2, 11.7), (0.0, 1.0), None, (0.0, 0.0)),
    # bedroom 2
    ("bed", (7.9, 8.9, 9.0, 11.0), (0.0, 0.6), "bed2", (0.0, 0.3)),
    ("chair", (9.3, 9.7, 7.6, 8.0), (0.0, 0.9), None, (0.0, 0.0)),
]


def _rect_mask(centres: np.ndarray, rect) -> np.ndarray:
    x0, x1, y0, y1 = rect
    x, y = centres[..., 0], centres[..., 1]
    return (x >= x0) & (x < x1) & (y >= y0) & (y < y1)


def default_house(seed: int = 0) -> House:
    """The embedded default house: 10 m x 12 m at 0.1 m cells (120 rows x 100 columns, origin (0, 0)).

    Living room and kitchen (south), a hallway across the middle, bedroom, bathroom and a second bedroom
    (north); 0.2 m walls with doors; an inlet window in the second bedroom's north wall and an outlet window in
    the living room's south wall. Objects (classes of :data:`HOUSE_CLASSES`) sit per room; ``seed`` jitters
    their positions by whole cells within fixed bounds that keep doors and windows clear. Every free cell has a
    room (doorways belong to the nearest room).

    Parameters
    ----------
    seed : int
        Seed of the object-position jitter; the same seed gives the same house.

    Returns
    -------
    House

    Raises
    ------
    TypeError
        ``seed`` is not an integer.

    Examples
    --------
    >>> h = default_house(seed=0)
    >>> h.grid.shape, h.room_names
    ((120, 100), ('Kitchen', 'Bathroom', 'Bedroom', 'LivingRoom', 'Hallway'))
    >>> [o.class_name for o in h.objects_of_class("oven")]
    ['oven']
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"seed must be an integer, got {seed!r}")
    return _default_house(int(seed))


@lru_cache(maxsize=8)
def _default_house(seed: int) -> House:
    """The house of :func:`default_house`, built once per seed in a process (a House is immutable: its arrays are
    read-only), so the runs of a grid share it."""
    w, h = int(round(_SIZE[0] / _RES)), int(round(_SIZE[1] / _RES))
    centres = GridMap(np.zeros((h, w), bool), _RES).cell_centres()
    walls = np.zeros((h, w), bool)
    for r in _WALLS:
        walls |= _rect_mask(centres, r)
    for r in _DOORS:
        walls &= ~_rect_mask(centres, r)
    inlet = _rect_mask(centres, _INLET)
    outlet = _rect_mask(centres, _OUTLET)
    walls &= ~(inlet | outlet)
    grid = GridMap(walls, _RES, (0.0, 0.0))

    labels = np.full((h, w), -1, dtype=np.int64)
    for name, rect in _ROOMS:
        labels[_rect_mask(centres, rect)] = HOUSE_ROOMS.index(name)
    # doorways and windows: the nearest labelled cell's room
    unlabelled = grid.free & (labels < 0)
    _, (ri, ci) = ndi.distance_transform_edt(labels < 0, return_indices=True)
    labels[unlabelled] = labels[ri[unlabelled], ci[unlabelled]]
    labels[grid.occupancy] = -1

    rng = np.random.default_rng(seed)
    shifts: dict = {}
    objects = []
    for cls, (x0, x1, y0, y1), z, group, (jx, jy) in _OBJECTS:
        if group is not None and group not in shifts:  # whole-cell jitter, shared by a group
            nx, ny = int(round(jx / _RES)), int(round(jy / _RES))
            shifts[group] = (rng.integers(-nx, nx + 1) * _RES, rng.integers(-ny, ny + 1) * _RES)
        dx, dy = shifts[group] if group is not None else (0.0, 0.0)
        fp = box_footprint(((x0 + x1) / 2 + dx, (y0 + y1) / 2 + dy), (x1 - x0, y1 - y0))
        objects.append(SceneObject(cls, fp, z, f"{cls}_{len(objects)}"))
    house = House(grid, labels, HOUSE_ROOMS, tuple(objects), inlet, outlet)
    _check_default_layout(house)
    return house


def _check_default_layout(house: House) -> None:
    """Internal consistency of the default layout: objects stay in free cells of one room, doors clear."""
    g = house.grid
    centres = g.cell_centres()
    door = np.zeros(g.shape, bool)
    for r in _DOORS:
        x0, x1, y0, y1 = r
        door |= _rect_mask(centres, (x0 - 0.3, x1 + 0.3, y0 - 0.3, y1 + 0.3))  # door plus clearance
    door |= ndi.binary_dilation(house.inlet | house.outlet, iterations=3)
    for o in house.objects:
        m = o.mask(g)
        if (m & g.occupancy).any() or (m & door).any() or len(np.unique(house.room_labels[m])) != 1:
            raise RuntimeError(f"default house layout broken by {o!r}")  # a bug in the layout table, not input
