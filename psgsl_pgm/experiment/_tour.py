"""The exploration tour shared by every variant: one path through the rooms with regular stops.

The paper compares its variants on *the same path with the same observations* (Sec. "Validation"). The tour is
therefore planned from the map alone — never from the gas or the semantic beliefs — so that it is identical
for every source, estimator and variant:

1. navigable cells: free, not furniture or a window, at least ``clearance`` from any of them;
2. waypoints: a lattice with ``waypoint_spacing`` inside every room *area* (a connected piece of one room
   category; the two bedrooms are two areas);
3. order: from ``start``, go to the nearest unvisited area (geodesic distance), sweep its waypoints
   nearest-first, repeat;
4. path: 8-connected geodesic shortest paths without corner cutting between consecutive waypoints (the
   core's :func:`psgsl_pgm.geometry._grid.free_space_graph`, ``scipy.sparse.csgraph``);
5. stops: every ``stop_spacing`` metres of path; the camera looks along the direction of travel, and turns
   through four headings at every waypoint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage as ndi
from scipy.sparse.csgraph import dijkstra

from .._shared._memo import ContentCache, content_digest
from ..geometry._grid import free_space_graph

__all__ = ["Tour", "exploration_tour", "shared_tour"]

#: Tours of the houses met last in the process (shared_tour), keyed by what exploration_tour reads.
_SHARED_TOURS = ContentCache(maxsize=8)


@dataclass(frozen=True, eq=False)
class Tour:
    """A planned tour.

    Attributes
    ----------
    stops : (n, 2) ndarray
        Stop positions (x, y) in metres, in visiting order.
    headings : tuple of (m_j,) ndarray
        Camera headings (radians) at each stop; one (travel direction) or four (at a waypoint).
    path : (p, 2) ndarray
        The whole path (x, y) through cell centres, for drawing.
    distance : (n,) ndarray
        Path length travelled when reaching each stop, metres.
    waypoint : (n,) ndarray of bool
        Whether the stop is a waypoint (look-around stop).
    path_index : (n,) ndarray of int
        Index of each stop in ``path``.
    """

    stops: np.ndarray
    headings: tuple
    path: np.ndarray
    distance: np.ndarray
    waypoint: np.ndarray
    path_index: np.ndarray

    def __len__(self) -> int:
        return len(self.stops)

    def first(self, n: int) -> "Tour":
        """The tour cut after its first ``n`` stops (the same path, for drawing)."""
        n = int(n)
        return Tour(self.stops[:n], self.headings[:n], self.path, self.distance[:n], self.waypoint[:n],
                    self.path_index[:n])


def _path(pred: np.ndarray, target: int) -> list:
    out = [target]
    while pred[out[-1]] >= 0:
        out.append(int(pred[out[-1]]))
    return out[::-1]


def exploration_tour(house, *, start=(0.8, 6.0), waypoint_spacing: float = 1.6, stop_spacing: float = 0.5,
                     clearance: float = 0.25) -> Tour:
    """Plan the exploration tour through every room of ``house`` (see the module docstring).

    Parameters
    ----------
    house : psgsl_pgm.sim.House
    start : (2,) array_like, keyword-only
        Start position (x, y), metres (default: the west end of the default house's hallway).
    waypoint_spacing : float, keyword-only
        Lattice spacing of the waypoints inside each room area, metres.
    stop_spacing : float, keyword-only
        Path length between stops, metres.
    clearance : float, keyword-only
        Minimum distance of the path from walls, furniture and windows, metres.

    Returns
    -------
    Tour

    Raises
    ------
    ValueError
        A spacing or ``clearance`` that is not a positive number, or a ``start`` that is not a navigable position.

    Examples
    --------
    >>> from psgsl_pgm.sim import default_house
    >>> tour = exploration_tour(default_house(0))
    >>> len(tour) > 100, bool(tour.waypoint[0])
    (True, True)
    """
    for name, value in (("waypoint_spacing", waypoint_spacing), ("stop_spacing", stop_spacing),
                        ("clearance", clearance)):
        if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive number of metres, got {value!r}")
    grid = house.grid
    res = grid.resolution
    blocked = house.robot_obstacles
    nav = ~blocked & (ndi.distance_transform_edt(~blocked) * res > clearance)
    graph = free_space_graph(nav, res)  # over row-major flat cell indices
    idx = np.arange(nav.size).reshape(nav.shape)
    start_rc = tuple(int(v) for v in grid.world_to_cell(np.asarray(start, dtype=np.float64)))
    if not (0 <= start_rc[0] < nav.shape[0] and 0 <= start_rc[1] < nav.shape[1]) or not nav[start_rc]:
        raise ValueError(f"start {tuple(start)} must be a navigable position of the house (cell {start_rc})")
    # waypoints: a lattice per room area, reachable from the start
    reach = np.isfinite(dijkstra(graph, indices=int(idx[start_rc]))).nonzero()[0]
    reachable = np.zeros(nav.shape, bool)
    reachable[np.isin(idx, reach)] = True
    step = max(1, int(round(waypoint_spacing / res)))
    lattice = np.zeros(nav.shape, bool)
    lattice[step // 2 :: step, step // 2 :: step] = True
    areas = []
    for k in range(len(house.room_names)):
        pieces, n = ndi.label(house.room_labels == k)
        for j in range(1, n + 1):
            area = (pieces == j) & reachable
            if not (area & nav).any():
                continue
            # lattice points snapped to the nearest navigable cell of the area (furniture displaces them)
            _, (ri, ci) = ndi.distance_transform_edt(~(area & nav), return_indices=True)
            lat = np.argwhere(lattice & (house.room_labels == k) & (pieces == j))
            snapped = np.stack([ri[lat[:, 0], lat[:, 1]], ci[lat[:, 0], lat[:, 1]]], axis=-1)
            near = np.linalg.norm(snapped - lat, axis=-1) <= step / 2
            pts = np.unique(snapped[near], axis=0)
            if len(pts) == 0:  # a small area: its most interior navigable cell
                dist = ndi.distance_transform_edt(area)
                pts = np.array([np.unravel_index(int(np.argmax(dist)), area.shape)])
            areas.append(idx[pts[:, 0], pts[:, 1]])
    # order: nearest unvisited area, then its waypoints nearest-first; one geodesic solve per waypoint
    current = int(idx[start_rc])
    nodes, is_wp = [current], [True]
    remaining, todo = list(range(len(areas))), []
    while remaining or todo:
        d, pred = dijkstra(graph, indices=current, return_predecessors=True)
        if not todo:
            nearest = min(remaining, key=lambda a: d[areas[a]].min())
            remaining.remove(nearest)
            todo = list(areas[nearest])
        nxt = int(min(todo, key=lambda v: d[v]))
        todo.remove(nxt)
        if nxt == current:
            continue
        seg = _path(pred, nxt)[1:]
        nodes.extend(seg)
        is_wp.extend([False] * (len(seg) - 1) + [True])
        current = nxt
    path = grid.cell_to_world(np.stack(np.unravel_index(np.array(nodes), nav.shape), axis=-1))
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    is_wp = np.array(is_wp)
    # stops: every stop_spacing of arc length, plus every waypoint
    marks = np.floor(arc / stop_spacing + 1e-9)
    keep = np.flatnonzero(np.concatenate([[True], marks[1:] > marks[:-1]]) | is_wp)
    stops, wp = path[keep], is_wp[keep]
    ahead = np.vstack([stops[1:], 2 * stops[-1:] - stops[-2:-1]])  # the next stop (past the last: straight on)
    travel = np.arctan2(ahead[:, 1] - stops[:, 1], ahead[:, 0] - stops[:, 0])
    headings = tuple(t + np.arange(4) * (np.pi / 2) if w else np.array([t]) for t, w in zip(travel, wp))
    return Tour(stops=stops, headings=headings, path=path, distance=arc[keep], waypoint=wp, path_index=keep)


def shared_tour(house, *, start=(0.8, 6.0), clearance: float = 0.25) -> Tour:
    """:func:`exploration_tour` of ``house`` from ``start``, computed once per house content, start and clearance
    in the process and shared by every run (its arrays read-only).

    The key is what the tour reads: the robot's obstacles, the grid's frame, the rooms and the arguments.
    """
    grid = house.grid
    xy = tuple(float(v) for v in np.asarray(start, dtype=np.float64).ravel())
    key = content_digest(house.robot_obstacles, house.room_labels, len(house.room_names), grid.shape,
                         float(grid.resolution), tuple(np.asarray(grid.origin, dtype=np.float64).ravel().tolist()),
                         xy, float(clearance))

    def make():
        tour = exploration_tour(house, start=start, clearance=clearance)
        for a in (tour.stops, tour.path, tour.distance, tour.waypoint, tour.path_index, *tour.headings):
            a.flags.writeable = False
        return tour

    return _SHARED_TOURS.get(key, make)
