"""Floor plans of generated homes: typed rooms, walls, doors and inlet/outlet windows on one 0.1-m grid.

A plan is drawn from a seeded generator in whole cells (no rounding of metres):

1. **Outline.** A rectangle of the requested floor area (outer wall included), aspect ratio uniform in
   [1, 1.6], sides in whole cells.
2. **Rooms.** Binary space partition: the largest room whose longer side can be cut is cut across that side at a
   uniform fraction in [0.35, 0.65] (never leaving a side under :data:`MIN_SIDE`), until there are ``n_rooms``.
3. **Types.** Rooms sorted by area take the types sorted by their usual size (living room, bedrooms, kitchen,
   hallway, bathrooms: :data:`SIZE_ORDER`).
4. **Walls.** 0.2 m: each room's one-cell boundary ring, plus a second ring along the outline.
5. **Doors.** 0.9 m openings on a random spanning tree of the rooms sharing a wall long enough for a door
   (every room reachable); the tree is drawn by Kruskal's rule on randomly ordered room pairs.
6. **Windows.** One inlet and one outlet in the outer wall of two rooms, 1.0–1.5 m wide, the outlet on the
   outer wall farthest from the inlet among three random candidates (the flow crosses the house).

A plan that cannot be drawn (no room left to cut, rooms not connected by long enough walls) is drawn again
from the same generator; the caller states the attempt limit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FloorPlan", "MIN_SIDE", "RES", "ROOM_TYPES", "SIZE_ORDER", "draw_plan", "room_type_sequence"]

#: Cell size of generated homes, m.
RES = 0.1
#: Smallest side of a room before walls, m (a room's inside is at least 1.9 m wide).
MIN_SIDE = 2.2
#: Room types of generated homes (the simulator's room categories).
ROOM_TYPES = ("Kitchen", "Bathroom", "Bedroom", "LivingRoom", "Hallway")
#: Types from the usually largest to the usually smallest room (step 3 of the module docstring).
SIZE_ORDER = ("LivingRoom", "Bedroom", "Kitchen", "Hallway", "Bathroom")
#: The types of a house of n rooms are the first n of this list.
_TYPE_SEQUENCE = ("LivingRoom", "Kitchen", "Bathroom", "Bedroom", "Hallway", "Bedroom", "Bedroom", "Bathroom")
_DOOR = 9  # cells
_MARGIN = 2  # cells between a door or window and a crossing wall


def room_type_sequence(n_rooms: int) -> tuple:
    """The default room types of an ``n_rooms`` house (3 ≤ n ≤ 8): living room, kitchen, bathroom, then
    bedroom, hallway, bedroom, bedroom, bathroom."""
    return _TYPE_SEQUENCE[:n_rooms]


@dataclass(frozen=True)
class FloorPlan:
    """A drawn plan, in cells of :data:`RES` (row = y, column = x, origin (0, 0)).

    Attributes
    ----------
    shape : (rows, cols)
    rooms : tuple of (type, (c0, c1, r0, r1))
        Each room's rectangle [c0, c1) × [r0, r1) in cells, walls included.
    walls : (H, W) ndarray of bool
        Walls with doors cut out (windows still walls).
    doors : tuple of (c0, c1, r0, r1)
        Door openings in cells.
    windows : tuple of (role, (x0, y0), (x1, y1))
        Window segments along the outer wall's centre line, through the centres of its end cells, m.
    """

    shape: tuple
    rooms: tuple
    walls: np.ndarray
    doors: tuple
    windows: tuple


def _split(rng, cols: int, rows: int, n: int, min_side: int):
    leaves = [(0, cols, 0, rows)]
    while len(leaves) < n:
        order = sorted(range(len(leaves)), key=lambda i: -(leaves[i][1] - leaves[i][0]) * (leaves[i][3] - leaves[i][2]))
        for i in order:
            c0, c1, r0, r1 = leaves[i]
            w, h = c1 - c0, r1 - r0
            axes = [0, 1] if w > h else [1, 0]
            if 0.8 < w / h < 1.25 and rng.random() < 0.5:
                axes.reverse()
            axis = next((a for a in axes if (w, h)[a] >= 2 * min_side), None)
            if axis is None:
                continue
            length = (w, h)[axis]
            lo, hi = max(min_side, int(np.ceil(0.35 * length))), min(length - min_side, int(0.65 * length))
            if lo > hi:
                lo, hi = min_side, length - min_side
            cut = int(rng.integers(lo, hi + 1))
            if axis == 0:
                leaves[i:i + 1] = [(c0, c0 + cut, r0, r1), (c0 + cut, c1, r0, r1)]
            else:
                leaves[i:i + 1] = [(c0, c1, r0, r0 + cut), (c0, c1, r0 + cut, r1)]
            break
        else:
            return None
    return leaves


def _shared_walls(leaves) -> list:
    """(i, j, axis, line, lo, hi): rooms i and j meet along column/row ``line`` over [lo, hi) cells."""
    out = []
    for i, a in enumerate(leaves):
        for j, b in enumerate(leaves[:i]):
            for p, q in ((a, b), (b, a)):
                if p[1] == q[0]:  # p left of q: vertical wall at column p[1]
                    lo, hi = max(p[2], q[2]), min(p[3], q[3])
                    if hi - lo >= _DOOR + 2 * _MARGIN:
                        out.append((i, j, 0, p[1], lo, hi))
                if p[3] == q[2]:  # p below q: horizontal wall at row p[3]
                    lo, hi = max(p[0], q[0]), min(p[1], q[1])
                    if hi - lo >= _DOOR + 2 * _MARGIN:
                        out.append((i, j, 1, p[3], lo, hi))
    return out


def _spanning_doors(rng, n: int, shared):
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    doors = []
    for k in rng.permutation(len(shared)):
        i, j, axis, line, lo, hi = shared[k]
        if find(i) == find(j):
            continue
        parent[find(i)] = find(j)
        start = int(rng.integers(lo + _MARGIN, hi - _MARGIN - _DOOR + 1))
        if axis == 0:
            doors.append((line - 1, line + 1, start, start + _DOOR))
        else:
            doors.append((start, start + _DOOR, line - 1, line + 1))
    return doors if len(doors) == n - 1 else None


def _outer_edges(leaves, cols: int, rows: int):
    """(room, side, lo, hi) of every room side on the outline, over [lo, hi) cells along it."""
    out = []
    for i, (c0, c1, r0, r1) in enumerate(leaves):
        if r0 == 0:
            out.append((i, "S", c0, c1))
        if r1 == rows:
            out.append((i, "N", c0, c1))
        if c0 == 0:
            out.append((i, "W", r0, r1))
        if c1 == cols:
            out.append((i, "E", r0, r1))
    return out


def _window(rng, edge, cols: int, rows: int, role: str):
    _, side, lo, hi = edge
    n = int(rng.integers(10, 16))  # 1.0-1.5 m
    n = min(n, hi - lo - 2 * (_MARGIN + 2))
    a = int(rng.integers(lo + _MARGIN + 2, hi - _MARGIN - 2 - n + 1))
    b = a + n - 1  # last cell
    along = (round((a + 0.5) * RES, 4), round((b + 0.5) * RES, 4))
    across = round({"S": 1, "N": rows - 1, "W": 1, "E": cols - 1}[side] * RES, 4)  # outer wall centre line
    if side in ("S", "N"):
        return (role, (along[0], across), (along[1], across))
    return (role, (across, along[0]), (across, along[1]))


def _edge_middle(edge, cols: int, rows: int) -> np.ndarray:
    _, side, lo, hi = edge
    mid = (lo + hi) / 2 * RES
    return np.array({"S": (mid, 0.0), "N": (mid, rows * RES), "W": (0.0, mid), "E": (cols * RES, mid)}[side])


def draw_plan(rng, area: float, types) -> FloorPlan | None:
    """One attempt at a plan of ``area`` m² (outline) with rooms of ``types``; None when this draw fails.

    Parameters
    ----------
    rng : numpy.random.Generator
    area : float
        m², outer wall included.
    types : sequence of str
        One room type of :data:`ROOM_TYPES` per room.
    """
    n = len(types)
    aspect = 1.0 + 0.6 * rng.random()
    cols = int(round(np.sqrt(area * aspect) / RES))
    rows = int(round(area / (cols * RES * RES)))
    min_side = int(round(MIN_SIDE / RES))
    leaves = _split(rng, cols, rows, n, min_side)
    if leaves is None:
        return None
    doors = _spanning_doors(rng, n, _shared_walls(leaves))
    if doors is None:
        return None
    edges = [e for e in _outer_edges(leaves, cols, rows) if e[3] - e[2] >= 10 + 2 * (_MARGIN + 2)]
    if len(edges) < 2:
        return None
    first = edges[int(rng.integers(len(edges)))]
    inlet = _window(rng, first, cols, rows, "inlet")
    others = [e for e in edges if e[:2] != first[:2]]
    picks = [others[k] for k in rng.choice(len(others), size=min(3, len(others)), replace=False)]
    centre = np.mean([inlet[1], inlet[2]], axis=0)
    far = max(picks, key=lambda e: float(np.linalg.norm(_edge_middle(e, cols, rows) - centre)))
    outlet = _window(rng, far, cols, rows, "outlet")

    walls = np.zeros((rows, cols), bool)
    walls[:2], walls[-2:], walls[:, :2], walls[:, -2:] = True, True, True, True
    for c0, c1, r0, r1 in leaves:
        walls[r0:r1, c0], walls[r0:r1, c1 - 1], walls[r0, c0:c1], walls[r1 - 1, c0:c1] = True, True, True, True
    for c0, c1, r0, r1 in doors:
        walls[r0:r1, c0:c1] = False
    order = sorted(range(n), key=lambda i: -(leaves[i][1] - leaves[i][0]) * (leaves[i][3] - leaves[i][2]))
    typed = sorted(types, key=SIZE_ORDER.index)
    rooms = [None] * n
    for i, t in zip(order, typed):
        rooms[i] = (t, leaves[i])
    return FloorPlan((rows, cols), tuple(rooms), walls, tuple(doors), (inlet, outlet))
