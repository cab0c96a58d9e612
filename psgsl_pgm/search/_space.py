"""Where the robot can go and what it can see from there: the free-space graph, candidate poses, and cached
per-position views and geodesic distances.

Candidate poses of a decision: the cells of a fixed lattice (spacing ``spacing``) that are navigable and within
``horizon`` metres of the robot *along the free-space graph*, and optionally those of a coarser lattice
(``far_spacing``) over the rest of the reachable free space, each with ``n_headings`` camera headings.

Views: the camera sees F_p = field_of_view(p) ∩ free (what :meth:`psgsl_pgm.sim.Camera.visible` returns). The
line of sight does not depend on the heading: it comes from the core's :class:`psgsl_pgm.ViewCache` of the
house and camera (shared by every run in the process: walls do not move, and the camera's occupancy is the
same for every seed), and is split into the heading sectors by the same cone test as
:func:`psgsl_pgm.field_of_view`.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict, deque

import numpy as np
from scipy import ndimage as ndi
from scipy.sparse.csgraph import connected_components, dijkstra

from .._shared._memo import ContentCache, content_digest
from ..geometry._fov import ViewCache
from ..geometry._grid import free_space_graph

__all__ = ["FreeSpace"]

_TILE = 5  # cells per side of the tiles of FreeSpace.view_bound

#: Per-position views shared by every FreeSpace of the same map, free cells, camera and headings in the process
#: (each run of a grid builds its own FreeSpace; walls do not move): at most four maps, least recently used dropped.
_SHARED_VIEWS: OrderedDict = OrderedDict()
_SHARED_VIEWS_MAX = 4


def _shared_views(key) -> dict:
    hit = _SHARED_VIEWS.get(key)
    if hit is None:
        hit = _SHARED_VIEWS[key] = {}
        if len(_SHARED_VIEWS) > _SHARED_VIEWS_MAX:
            _SHARED_VIEWS.popitem(last=False)
    else:
        _SHARED_VIEWS.move_to_end(key)
    return hit


#: Whole free spaces (:meth:`FreeSpace.shared`) of the houses met last in the process, keyed by their content.
_SHARED_SPACES = ContentCache(maxsize=2)


class FreeSpace:
    """Navigation and view geometry of a house for the closed loop.

    Parameters
    ----------
    house : psgsl_pgm.sim.House
    camera : psgsl_pgm.sim.Camera
    clearance : float, keyword-only
        Minimum distance of the robot's cells from walls, furniture and windows, m (the tour's default).
    spacing : float, keyword-only
        Lattice spacing of candidate positions, m.
    n_headings : int, keyword-only
        Camera headings per candidate position, 2π k / n_headings.
    distance_cache : int, keyword-only
        Geodesic distance maps kept (one (H·W,) float64 per position).

    Attributes
    ----------
    nav : (H, W) bool
        Cells the robot may occupy.
    graph : scipy.sparse.csr_matrix
        :func:`psgsl_pgm.geometry._grid.free_space_graph` of ``nav``: over row-major flat cell indices (edges only
        between ``nav`` cells, no corner cutting), weights in metres.
    headings : (n_headings,) ndarray
    lattice : (H, W) bool
        Navigable lattice cells (candidate positions), with the finder cells of :meth:`cover` once it is called.
    tile : (H·W,) ndarray of int
        The tile of each cell for the policies' bounds: the free cells of a block of 5 × 5 cells form a tile
        (numbered 0 … ``n_tiles`` − 1), every other cell is in tile ``n_tiles``.
    """

    def __init__(self, house, camera, *, clearance: float = 0.25, spacing: float = 0.5, n_headings: int = 8,
                 distance_cache: int = 1024):
        self.house = house
        self.camera = camera
        grid = house.grid
        self.grid = grid
        self.resolution = float(grid.resolution)
        blocked = house.robot_obstacles
        self.nav = ~blocked & (ndi.distance_transform_edt(~blocked) * self.resolution > clearance)
        self.graph = free_space_graph(self.nav, self.resolution)  # the core's graph, over flat cell indices
        step = max(1, int(round(spacing / self.resolution)))
        lat = np.zeros(self.nav.shape, bool)
        lat[step // 2 :: step, step // 2 :: step] = True
        self.lattice = self._base_lattice = lat & self.nav
        self._lattice_spacing = step * self.resolution
        self._finders: dict = {}  # (found radius, detection content) -> (K,) finder cells of cover()
        self._covered_for = None
        self.headings = 2 * np.pi * np.arange(int(n_headings)) / int(n_headings)
        self.centres = grid.cell_centres().reshape(-1, 2)
        self.free = grid.free.ravel()
        # geodesic distance to a non-navigable cell: via its nearest navigable cell, then straight
        dist, (ri, ci) = ndi.distance_transform_edt(~self.nav, return_indices=True)
        self._nearest_nav = (ri * self.nav.shape[1] + ci).ravel()
        self._offset = np.linalg.norm(self.centres - self.centres[self._nearest_nav], axis=1)
        self._dist_cache: OrderedDict = OrderedDict()
        self._reach_cache: OrderedDict = OrderedDict()
        self._candidate_keys: deque = deque()  # the cached candidate sets, oldest first
        self._discs: dict = {}
        self._gathers: OrderedDict = OrderedDict()  # candidate set -> the tiles of its views (view_bound)
        self._dist_cache_max = int(distance_cache)
        # tiles: the free cells of each block of _TILE × _TILE cells (numbered 0 … T − 1, every one non-empty), and
        # tile T holding every other cell; the cells sorted by tile, for per-tile reductions
        rows, cols = np.indices(self.nav.shape)
        block = ((rows // _TILE) * -(-self.nav.shape[1] // _TILE) + cols // _TILE).ravel()
        used, index = np.unique(block[self.free], return_inverse=True)
        self.n_tiles = int(used.size)
        self.tile = np.full(self.free.size, self.n_tiles, dtype=np.int64)
        self.tile[self.free] = index
        self._tile_order = np.argsort(self.tile, kind="stable")[: int(self.free.sum())]
        self._tile_starts = np.searchsorted(self.tile[self._tile_order], np.arange(self.n_tiles))
        self._sight = ViewCache.shared(grid.occupancy, max_range=camera.max_range, half_angle=camera.half_angle,
                                       min_range=camera.min_range, resolution=grid.resolution, origin=grid.origin)
        # cell -> (flat cells, (n_headings, m) bool sectors): what they depend on names the shared dict
        digest = hashlib.sha1(np.ascontiguousarray(grid.occupancy).tobytes())
        digest.update(np.ascontiguousarray(self.free).tobytes())
        self._views: dict = _shared_views((digest.hexdigest(), self.nav.shape, self.resolution,
                                           tuple(np.asarray(grid.origin, dtype=np.float64).ravel().tolist()),
                                           float(camera.max_range), float(camera.half_angle),
                                           float(camera.min_range), self.headings.tobytes()))
        self._component = None  # connected component of every cell in the graph (computed on first use)

    @classmethod
    def shared(cls, house, camera, *, clearance: float = 0.25, spacing: float = 0.5,
               n_headings: int = 8) -> "FreeSpace":
        """The free space of ``house`` for ``camera`` shared by every run of the process in a house of the same
        content (walls, furniture, windows, grid frame), camera range and options: its drivable cells, geodesic
        distances, views, finder cells and findable masks are computed once per house and process, not per run.

        Every cache of a free space holds a function of that content alone (and of the detection model it is
        given, :meth:`cover`, :meth:`findable`), so a shared space gives a run the same numbers as a new one. The
        two spaces used last are kept.
        """
        grid = house.grid
        key = content_digest(grid.occupancy, grid.free, house.robot_obstacles, float(grid.resolution),
                             tuple(np.asarray(grid.origin, dtype=np.float64).ravel().tolist()),
                             float(camera.max_range), float(camera.half_angle), float(camera.min_range),
                             float(clearance), float(spacing), int(n_headings))
        return _SHARED_SPACES.get(key, lambda: cls(house, camera, clearance=clearance, spacing=spacing,
                                                   n_headings=n_headings))

    # --- cells and positions ------------------------------------------------------------------------------
    def cell_of(self, xy) -> int:
        """Flat index of the cell holding ``xy``."""
        r, c = (int(v) for v in self.grid.world_to_cell(np.asarray(xy, dtype=np.float64)))
        return r * self.nav.shape[1] + c

    def snap(self, xy) -> int:
        """Flat index of the navigable cell nearest to ``xy``."""
        return int(self._nearest_nav[self.cell_of(xy)])

    def position(self, cells) -> np.ndarray:
        """(..., 2) cell centres of flat indices."""
        return self.centres[np.asarray(cells)]

    # --- geodesics ---------------------------------------------------------------------------------------
    def reach(self, cell: int, horizon: float):
        """Geodesic distances (H·W,) from ``cell`` (inf beyond ``horizon``) and Dijkstra predecessors (cached,
        read-only; the graph never changes)."""
        key = (int(cell), float(horizon))
        hit = self._reach_cache.get(key)
        if hit is None:
            hit = dijkstra(self.graph, indices=key[0], limit=key[1], return_predecessors=True)
            for a in hit:
                a.flags.writeable = False
            self._reach_cache[key] = hit
            if len(self._reach_cache) > self._dist_cache_max:
                self._reach_cache.popitem(last=False)
        else:
            self._reach_cache.move_to_end(key)
        return hit

    @staticmethod
    def path(pred: np.ndarray, target: int) -> np.ndarray:
        """Flat cells from the Dijkstra source to ``target`` (inclusive), from the predecessor array."""
        out = [int(target)]
        while pred[out[-1]] >= 0:
            out.append(int(pred[out[-1]]))
        return np.array(out[::-1])

    def offset(self, cell: int) -> float:
        """m from ``cell``'s centre straight to its nearest navigable cell's centre (0 on navigable cells)."""
        return float(self._offset[int(cell)])

    def distances(self, cell: int) -> np.ndarray:
        """(H·W,) geodesic distance (m) from navigable ``cell`` to every cell (cached; inf if unreachable)."""
        cell = int(cell)
        d = self._dist_cache.get(cell)
        if d is None:
            on_graph = dijkstra(self.graph, indices=cell)
            d = on_graph[self._nearest_nav] + self._offset
            d.flags.writeable = False
            self._dist_cache[cell] = d
            if len(self._dist_cache) > self._dist_cache_max:
                self._dist_cache.popitem(last=False)
        else:
            self._dist_cache.move_to_end(cell)
        return d

    def tile_distance_floor(self, cell: int):
        """A lower bound of the finite geodesic distances from navigable ``cell`` over each tile (cached).

        Returns
        -------
        floor : (T + 1,) ndarray
            Entry t ≤ the least distance to a free cell of tile t, entry T = 0 (below).
        order : (T + 1,) ndarray of int
            The tiles sorted by ``floor``, ascending (stable).

        floor[t] ≤ min over the free cells s of tile t of d(s) = :meth:`distances` (``cell``)[s], taken as 0 where
        it is infinite (the convention of the policies); floor[T] (every cell that is not free) is 0. On the graph
        (8 neighbours, edges of h and h√2 m, no corner cutting) a path from ``cell`` to the navigable cell n(s)
        is at least the octile distance h (max(Δr, Δc) + (√2 − 1) min(Δr, Δc)); then d(s) ≥ octile + offset(s).
        Times 1 − 1e-9, far below the relative rounding of a Dijkstra sum over fewer than 10⁶ edges (≤ 1e-10).
        No Dijkstra: O(H·W) array operations.
        """
        cell = int(cell)
        key = ("floor", cell)
        hit = self._discs.get(key)
        if hit is None:
            if self._component is None:
                self._component = connected_components(self.graph, directed=False)[1]
            w = self.nav.shape[1]
            r0, c0 = divmod(cell, w)
            rn, cn = np.divmod(self._nearest_nav, w)
            dr, dc = np.abs(rn - r0), np.abs(cn - c0)
            octile = self.resolution * (np.maximum(dr, dc) + (np.sqrt(2.0) - 1.0) * np.minimum(dr, dc))
            low = (octile + self._offset) * (1.0 - 1e-9)
            low[self._component[self._nearest_nav] != self._component[cell]] = 0.0  # unreachable: d taken as 0
            floor = np.zeros(self.n_tiles + 1)
            floor[:-1] = np.minimum.reduceat(low[self._tile_order], self._tile_starts)
            hit = (floor, np.argsort(floor, kind="stable"))
            for v in hit:
                v.flags.writeable = False
            self._discs[key] = hit
        return hit

    def far_lattice(self, spacing: float) -> np.ndarray:
        """(H, W) bool: navigable cells of a lattice of ``spacing`` m (cached), the targets beyond the horizon."""
        key = ("far", float(spacing))
        hit = self._discs.get(key)
        if hit is None:
            step = max(1, int(round(float(spacing) / self.resolution)))
            lat = np.zeros(self.nav.shape, bool)
            lat[step // 2 :: step, step // 2 :: step] = True
            hit = lat & self.nav
            hit.flags.writeable = False
            self._discs[key] = hit
        return hit

    def cover(self, detection) -> np.ndarray:
        """Make the near candidates able to find every source the robot can find at all.

        The lattice alone is not enough: a drivable cell within r of an object's footprint (or of a floor cell)
        need not lie on the lattice — near furniture and walls the lattice's nearest drivable cells can be farther
        than r from it — and a planner whose stops never come within r of the source finds it only by chance on
        the way. So, for every hypothesis c (a free cell, or a cell of an object's footprint) that some drivable
        cell finds under ``detection``'s rule (:class:`psgsl_pgm.search.DetectionModel`) and no lattice cell
        does, the lattice gains one *finder cell*: the drivable cell nearest to c's found region R(c) among those
        that find c (ties: the lowest flat index), taken greedily in flat order of the hypotheses still uncovered
        (each finder covers every hypothesis it finds, so an object's whole footprint needs one). Afterwards every
        hypothesis found from a drivable cell is found from a lattice cell (tested).

        Finder cells fill the gaps that walls and furniture cut into the lattice. On open floor the lattice finds
        every point source iff r is at least half its diagonal, spacing / √2; with a smaller r the lattice itself
        is too coarse for point sources (a finer ``spacing`` is the remedy, not a finder cell at every drivable
        cell), and only object footprints — every cell of one found together — get finder cells.

        The finder cells are candidates beyond the horizon too (:meth:`candidates`): a far target then carries
        the P_f of the stop that finds the hypotheses there. The finder cells depend on the geometry and r only;
        they are computed once per found radius, and calling ``cover`` with another radius replaces them (the
        lattice is the base lattice plus the finder cells of the last radius, so a shared space gives every run of
        that radius the same candidates).

        Parameters
        ----------
        detection : psgsl_pgm.search.DetectionModel
            The loop's detection model on this house's grid.

        Returns
        -------
        (K,) ndarray of int
            The finder cells (flat indices), read-only.
        """
        r = float(detection.found_radius)
        if detection.shape != self.nav.shape:
            raise ValueError(f"detection must be on this space's grid of shape {self.nav.shape}, got shape "
                             f"{detection.shape}")
        key = (r, detection.content_key)  # the finder cells of this house's footprints and radius
        finders = self._finders.get(key)
        if finders is None:
            finders = self._finder_cells(detection)
            finders.flags.writeable = False
            self._finders[key] = finders
        if self._covered_for != key:
            lattice = self._base_lattice.copy()
            lattice.ravel()[finders] = True
            if not np.array_equal(lattice, self.lattice):
                for key in [k for k in self._discs if k[0] == "candidates"]:  # cached sets of the old lattice
                    del self._discs[key]
                self._candidate_keys.clear()
            self.lattice = lattice
            self._covered_for = key
        return finders

    def findable(self, detection, cell: int) -> np.ndarray:
        """(H·W,) bool, read-only: the hypotheses that some drivable cell reachable from ``cell`` finds under
        ``detection``'s rule (:class:`psgsl_pgm.search.DetectionModel`: within its found radius of the
        hypothesis's found region).

        A source elsewhere can never be found — ``psgsl search`` and ``psgsl world check`` refuse one before any
        run (:func:`psgsl_pgm.search.check_findable`) — so the closed loop's robot, which searches for a source it
        can find, conditions its belief on this set before its first decision (p(s) ∝ p(s) [s findable]): without
        it, mass on a cell no stop can rule out (behind furniture, in a gap narrower than the robot) stays in the
        belief for good, and the planners shuttle beside it. Depends on the robot's map, its clearance and the
        found radius only; cached per radius and connected component of the free space.
        """
        if detection.shape != self.nav.shape:
            raise ValueError(f"detection must be on this space's grid of shape {self.nav.shape}, got shape "
                             f"{detection.shape}")
        if self._component is None:
            self._component = connected_components(self.graph, directed=False)[1]
        part = int(self._component[int(cell)])
        key = ("findable", float(detection.found_radius), detection.content_key, part)
        hit = self._discs.get(key)
        if hit is None:
            nav = np.flatnonzero(self.nav.ravel() & (self._component == part))
            hit = np.zeros(self.nav.size, bool)
            for start in range(0, nav.size, 4096):  # bounded memory in large homes
                hit |= detection.rows(self.centres[nav[start : start + 4096]]).getnnz(axis=0) > 0
            hit.flags.writeable = False
            self._discs[key] = hit
        return hit

    def _finder_cells(self, detection) -> np.ndarray:
        """The finder cells of :meth:`cover` (loops over the finder cells only: tens per house)."""
        lattice = np.flatnonzero(self._base_lattice.ravel())
        covered = detection.rows(self.centres[lattice]).getnnz(axis=0) > 0
        hypotheses = detection.owner >= 0
        if detection.found_radius >= self._lattice_spacing * np.sqrt(0.5):  # open floor: the lattice finds it all
            hypotheses = hypotheses | self.free
        todo = hypotheses & ~covered
        if not todo.any():
            return np.empty(0, dtype=np.int64)
        # only drivable cells within r of an uncovered hypothesis's found region can find it (the distance test
        # here only preselects, with a margin; the rule itself is detection.rows')
        near = todo.copy()
        for j in np.unique(detection.owner[todo & (detection.owner >= 0)]).tolist():  # uncovered objects
            near |= detection.footprints[j]
        reach = ndi.distance_transform_edt(~near.reshape(self.nav.shape)) * self.resolution
        nav = np.flatnonzero(self.nav.ravel() & (reach.ravel() <= detection.found_radius + 2 * self.resolution))
        by_row = detection.rows(self.centres[nav])  # (n_near, H·W): what each such drivable cell finds
        by_col = by_row.tocsc()
        todo &= by_col.getnnz(axis=0) > 0  # findable at all
        out = []
        start = 0
        while True:
            rest = np.flatnonzero(todo[start:])
            if rest.size == 0:
                break
            c = start = start + int(rest[0])
            rows = by_col.indices[by_col.indptr[c] : by_col.indptr[c + 1]]  # drivable cells that find c, sorted
            region = self.centres[detection.region_mask(c).ravel()]
            d2 = ((self.centres[nav[rows]][:, None, :] - region[None, :, :]) ** 2).sum(axis=-1).min(axis=1)
            k = int(rows[int(np.argmin(d2))])  # first minimum: the lowest flat index among equals
            out.append(int(nav[k]))
            todo[by_row.indices[by_row.indptr[k] : by_row.indptr[k + 1]]] = False
        return np.array(sorted(out), dtype=np.int64)

    def candidates(self, cell: int, horizon: float, far_spacing: float | None = None):
        """Candidate positions of a decision at ``cell``.

        Parameters
        ----------
        cell : int
            The robot's flat cell.
        horizon : float
            m (geodesic) within which the candidates are the lattice of ``spacing``.
        far_spacing : float, optional
            Beyond ``horizon``: every navigable cell of a lattice of this spacing in the whole reachable free
            space, and every finder cell of :meth:`cover`, at its geodesic distance (None: none beyond the
            horizon).

        Returns
        -------
        cells : (K,) ndarray of int
            The candidate cells other than the robot's own — the robot
            always moves, as in the open-space POMDP (staying would repeat a gas reading that the estimators
            treat as independent of the last one, an over-count the scoring per unit time would reward) —
            or the robot's own cell alone when no other is within reach. Near ones first (lattice order),
            then the far ones (lattice order).
        drive : (K,) ndarray
            Their geodesic distances, m.
        pred : (H·W,) ndarray
            Dijkstra predecessors from ``cell`` (for :meth:`path`).

        The three arrays are cached per cell and settings, and read-only.
        """
        key = ("candidates", int(cell), float(horizon), None if far_spacing is None else float(far_spacing))
        hit = self._discs.get(key)
        if hit is not None:  # the same geometry every time the robot is back in this cell
            return hit
        dist, pred = self.reach(cell, horizon if far_spacing is None else np.inf)
        near = np.isfinite(dist) & (dist <= horizon)
        lat = np.flatnonzero(self.lattice.ravel() & near)
        if far_spacing is not None:
            targets = self.far_lattice(far_spacing) | (self.lattice & ~self._base_lattice)  # and the finder cells
            far = np.flatnonzero(targets.ravel() & np.isfinite(dist) & ~near)
            lat = np.concatenate([lat, far])
        cells = lat[lat != cell]
        if cells.size == 0:
            cells = np.array([int(cell)])
        hit = (cells, dist[cells], pred)
        for a in hit[:2]:
            a.flags.writeable = False
        if len(self._candidate_keys) >= self._dist_cache_max:
            self._discs.pop(self._candidate_keys.popleft(), None)
        self._candidate_keys.append(key)
        self._discs[key] = hit
        return hit

    def disc(self, cell: int, radius: float) -> np.ndarray:
        """Flat indices of the cells whose centre lies within ``radius`` of ``cell``'s centre (cached)."""
        key = (int(cell), float(radius))
        hit = self._discs.get(key)
        if hit is None:
            h, w = self.nav.shape
            r0, c0 = divmod(int(cell), w)
            reach = int(np.ceil(radius / self.resolution)) + 1
            rows, cols = np.mgrid[max(0, r0 - reach) : min(h, r0 + reach + 1), max(0, c0 - reach) : min(w, c0 + reach + 1)]
            flat = (rows * w + cols).ravel()
            d2 = ((self.centres[flat] - self.centres[int(cell)]) ** 2).sum(axis=-1)
            hit = flat[d2 <= radius**2]
            hit.flags.writeable = False
            self._discs[key] = hit
        return hit

    # --- views -------------------------------------------------------------------------------------------
    def view(self, cell: int):
        """Cells the camera sees from ``cell``'s centre at each heading.

        Returns
        -------
        flat : (m,) ndarray of int
            Free cells in line of sight within the camera's range (any heading).
        sectors : (n_headings, m) ndarray of bool
            Which of them are inside the opening angle at each of :attr:`headings`.
        """
        cell = int(cell)
        hit = self._views.get(cell)
        if hit is not None:
            return hit
        x, y = self.centres[cell]
        rows, cols = self._sight.sight(divmod(cell, self.nav.shape[1]))
        around = (x, y, 0.0)
        keep = self._sight.cone(around, rows, cols, any_heading=True) & self.free[rows * self.nav.shape[1] + cols]
        rows, cols = rows[keep], cols[keep]
        flat = rows.astype(np.int64) * self.nav.shape[1] + cols
        sectors = np.stack([self._sight.cone((x, y, h), rows, cols) for h in self.headings])
        flat.flags.writeable = False
        sectors.flags.writeable = False
        self._views[cell] = (flat, sectors)
        return flat, sectors

    def view_gain(self, gain_flat: np.ndarray, cells) -> np.ndarray:
        """φ_O = Σ_{n ∈ F_p} I(S; O_n) for every candidate cell × heading, (K, n_headings)."""
        out = np.empty((len(cells), len(self.headings)))
        for k, cell in enumerate(np.asarray(cells).tolist()):  # loop over candidate positions (tens)
            flat, sectors = self.view(cell)
            out[k] = sectors @ gain_flat[flat]
        return out

    def view_bound(self, gain_flat: np.ndarray, cells) -> np.ndarray:
        """(K,) an upper bound of abs(φ_O) at every heading of each candidate cell: Σ abs(gain) over the tiles of
        :data:`_TILE` × :data:`_TILE` cells that its view touches, times 1 + 1e-9 (far above the relative
        rounding of either sum, ≤ 1e-12 for views of fewer than a million cells). Not finite when the gains are
        not."""
        sums = self.tile_sums(np.abs(gain_flat))
        index, starts, nz = self._view_gather(cells)
        out = np.zeros(nz.size)
        if index.size:
            out[nz] = np.add.reduceat(sums[index], starts)
        return out * (1.0 + 1e-9)

    def _view_gather(self, cells):
        """The tiles of the views of ``cells`` for :meth:`view_bound`, one gather: (their concatenation, the start
        of each non-empty view in it, which views are non-empty), cached per candidate set (the robot comes back
        to its stops, and a cell's candidates are the same every time)."""
        cells = np.asarray(cells)
        key = (cells.dtype.str, cells.tobytes())
        hit = self._gathers.get(key)
        if hit is not None:
            self._gathers.move_to_end(key)
            return hit
        tiles = [self._view_tiles(c) for c in cells.tolist()]
        sizes = np.array([t.size for t in tiles], dtype=np.int64)
        nz = sizes > 0
        index = np.concatenate(tiles) if sizes.sum() else np.empty(0, np.int64)
        starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])[nz]
        hit = (index, starts, nz)
        for a in hit:
            a.flags.writeable = False
        self._gathers[key] = hit
        if len(self._gathers) > self._dist_cache_max:
            self._gathers.popitem(last=False)
        return hit

    def tile_sums(self, values) -> np.ndarray:
        """(T + 1,) the sum of (H·W,) ``values`` over each tile (the last: every cell that is not free)."""
        return np.bincount(self.tile, weights=values, minlength=self.n_tiles + 1)

    def tile_extremes(self, rows):
        """((M, T), (M, T)) the minimum and the maximum of (M, H·W) ``rows`` over the free cells of each tile."""
        vals = np.asarray(rows)[:, self._tile_order]
        return (np.minimum.reduceat(vals, self._tile_starts, axis=1),
                np.maximum.reduceat(vals, self._tile_starts, axis=1))

    def _view_tiles(self, cell: int) -> np.ndarray:
        """The tiles that the view of ``cell`` touches (cached with the view)."""
        hit = self._discs.get(("tiles", cell))
        if hit is None:
            hit = np.unique(self.tile[self.view(cell)[0]])
            hit.flags.writeable = False
            self._discs[("tiles", cell)] = hit
        return hit
