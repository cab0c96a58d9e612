"""Furniture of generated homes: objects per room type from the generator's p(o | room) table.

The table is ``psgsl_pgm/data/furniture.yaml`` (written from the reference house, the embedded default house;
see the file's header): per room type, items with a probability of being present, a count range, a box size,
a height range and a placement rule (against a wall, or free in the room). :func:`furnish` places every item
of every room by rejection sampling, keeping an item only if

* its footprint lies inside its room (not on a wall), clear of other objects by one cell, 0.7 m from doors,
  0.5 m from windows and 0.6 m from the robot's start;
* afterwards every room still has a cell the robot can reach from the start, and every object placed so far
  still has a reachable cell within :data:`FIND_MARGIN` of its footprint (the robot's cells: free, not
  furniture or a window, more than ``clearance`` from each, the rule of :func:`psgsl_pgm.sim.navigable`;
  reachable: 4-connected to the start's cell). The search's own rule (within ``found_radius`` = 0.5 m) then
  holds with a 0.1-m margin: every object can be a findable source.

An item that does not fit after :data:`TRIES` draws is left out (a small room holds less).
"""

from __future__ import annotations

from functools import lru_cache
from importlib import resources

import numpy as np
from scipy import ndimage as ndi

from .._shared._validate import check_keys
from ..geometry._grid import GridMap
from ..io._yaml import load_yaml
from ._classes import HOUSE_CLASSES
from ._floorplan import RES, ROOM_TYPES
from ._objects import SceneObject, box_footprint

__all__ = ["FIND_MARGIN", "TRIES", "furnish", "furniture_table"]

#: m: every object keeps a reachable robot cell this close to its footprint.
FIND_MARGIN = 0.4
#: Placement draws per item.
TRIES = 25
_ITEM_KEYS = ("class", "p", "count", "size", "height", "place")


@lru_cache(maxsize=1)
def furniture_table() -> dict:
    """The generator's p(o | room) table: ``{room type: [item dict, ...]}`` (``psgsl_pgm/data/furniture.yaml``)."""
    with resources.as_file(resources.files("psgsl_pgm") / "data" / "furniture.yaml") as path:
        data = load_yaml(path)
    where = str(path)
    check_keys(where, data, optional=ROOM_TYPES)
    out = {}
    for room, items in data.items():
        checked = []
        for i, it in enumerate(items):
            check_keys(f"{where}: {room}[{i}]", it, required=_ITEM_KEYS)
            if it["class"] not in HOUSE_CLASSES or it["place"] not in ("wall", "free"):
                raise ValueError(f"{where}: {room}[{i}]: class {it['class']!r} or place {it['place']!r} unknown")
            checked.append(dict(it))
        out[room] = tuple(checked)
    return out


def _inside(rect, shape) -> tuple:
    """A room's inside [x0, x1) × [y0, y1) in metres: the rectangle without its walls (two cells on the outline)."""
    c0, c1, r0, r1 = rect
    rows, cols = shape
    return ((c0 + (2 if c0 == 0 else 1)) * RES, (c1 - (2 if c1 == cols else 1)) * RES,
            (r0 + (2 if r0 == 0 else 1)) * RES, (r1 - (2 if r1 == rows else 1)) * RES)


def _draw_box(rng, item, inside):
    """(centre, size) of one placement draw, or None when the room is too small for the item."""
    x0, x1, y0, y1 = inside
    long, short = (float(v) for v in item["size"])
    gap = 0.02  # off the wall face, so that the box's cells are the room's
    if item["place"] == "wall":
        side = int(rng.integers(4))
        along = (x0, x1) if side < 2 else (y0, y1)
        if along[1] - along[0] < long + 2 * gap:
            return None
        t = rng.uniform(along[0] + long / 2 + gap, along[1] - long / 2 - gap)
        if side == 0:
            return (t, y0 + short / 2 + gap), (long, short)
        if side == 1:
            return (t, y1 - short / 2 - gap), (long, short)
        if side == 2:
            return (x0 + short / 2 + gap, t), (short, long)
        return (x1 - short / 2 - gap, t), (short, long)
    size = (long, short) if rng.random() < 0.5 else (short, long)
    m = 0.5  # free items keep 0.5 m from the walls
    if x1 - x0 < size[0] + 2 * m or y1 - y0 < size[1] + 2 * m:
        return None
    return (rng.uniform(x0 + m + size[0] / 2, x1 - m - size[0] / 2),
            rng.uniform(y0 + m + size[1] / 2, y1 - m - size[1] / 2)), size


def _reachable(blocked: np.ndarray, start_rc, clearance: float) -> np.ndarray:
    """(H, W) bool: robot cells 4-connected to the start's cell (empty when the start is not a robot cell)."""
    nav = ~blocked & (ndi.distance_transform_edt(~blocked) * RES > clearance)
    lab, _ = ndi.label(nav)
    k = lab[start_rc]
    return lab == k if k > 0 else np.zeros_like(nav)


def furnish(rng, plan, windows: np.ndarray, start_xy, *, clearance: float = 0.25, table=None) -> list:
    """Objects for every room of ``plan`` (see the module docstring).

    Parameters
    ----------
    rng : numpy.random.Generator
    plan : FloorPlan
    windows : (H, W) ndarray of bool
        Window cells (the robot may not enter them).
    start_xy : (2,) array_like
        The robot's start, m.
    clearance : float, keyword-only
        The robot's distance from walls, furniture and windows, m.
    table : dict, optional, keyword-only
        Default :func:`furniture_table`.

    Returns
    -------
    list of SceneObject
        Named ``<class>_<k>``, in placement order (rooms in plan order, items in table order).
    """
    table = furniture_table() if table is None else table
    grid = GridMap(plan.walls, RES)
    shape = plan.shape
    centres = grid.cell_centres()
    walls = plan.walls | windows
    doors = np.zeros(shape, bool)
    for c0, c1, r0, r1 in plan.doors:
        doors[r0:r1, c0:c1] = True
    start_rc = tuple(int(v) for v in grid.world_to_cell(np.asarray(start_xy, dtype=np.float64)))
    keep_out = (ndi.binary_dilation(doors, iterations=7) | ndi.binary_dilation(windows, iterations=5)
                | (np.hypot(*(centres - np.asarray(start_xy, dtype=np.float64)).transpose(2, 0, 1)) < 0.6))
    insides = []
    for _, rect in plan.rooms:
        x0, x1, y0, y1 = _inside(rect, shape)
        insides.append((centres[..., 0] > x0) & (centres[..., 0] < x1) & (centres[..., 1] > y0) & (centres[..., 1] < y1))
    furniture = np.zeros(shape, bool)
    objects, masks = [], []
    for room_i, (room_type, rect) in enumerate(plan.rooms):
        inside = _inside(rect, shape)
        for item in table.get(room_type, ()):
            if rng.random() >= float(item["p"]):
                continue
            lo, hi = (int(v) for v in item["count"])
            for _ in range(int(rng.integers(lo, hi + 1))):
                for _ in range(TRIES):
                    box = _draw_box(rng, item, inside)
                    if box is None:
                        break
                    obj = SceneObject(item["class"], box_footprint(*box), tuple(float(v) for v in item["height"]),
                                      f"{item['class']}_{len(objects)}")
                    m = obj.mask(grid)
                    if (m & ~insides[room_i]).any() or (m & keep_out).any() or (m & ndi.binary_dilation(furniture)).any():
                        continue
                    reach = _reachable(walls | furniture | m, start_rc, clearance)
                    if not all((reach & ins).any() for ins in insides):
                        continue
                    near = ndi.distance_transform_edt(~reach) * RES
                    if any(near[mm].min() > FIND_MARGIN for mm in masks + [m]):
                        continue
                    objects.append(obj)
                    masks.append(m)
                    furniture |= m
                    break
    return objects
