"""GADEN's filament gas-dispersion model in 2-D, vectorised over filaments.

Each time step (as GADEN's ``filament_simulator``): new filaments are released at the source at
``release_rate``; every filament moves by the local wind (nearest cell of the snapshot in force) times dt
plus isotropic Gaussian noise; a move whose path crosses a wall is skipped (the filament stays), a filament
that ends in an outlet cell or leaves the map is removed. A filament born at t_b has

    σ²(t) = σ0² + γ (t − t_b)

and the concentration at a point x is (GADEN's player, with the filament's line of sight to x):

    C(x) = Σ_f ppm_centre · (σ0 / σ_f)³ · exp(−|x − x_f|² / 2σ_f²)    over filaments with |x − x_f| < 5 σ_f.

Line of sight is between the centres of the query cell and the filament's cell (exact traversal, cached per
query cell; see :mod:`psgsl_pgm.geometry._sight`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from .._shared._validate import positive
from ..geometry._grid import GridMap
from ..geometry._sight import LineOfSightCache
from ._fileio import number, read_yaml_mapping
from ._wind import WindField, WindSequence

__all__ = ["FilamentParams", "FilamentModel", "read_gaden_config"]


@dataclass(frozen=True)
class FilamentParams:
    """Parameters of the filament model (defaults: the lab's house scenario, GADEN ``B1.yaml``).

    Parameters
    ----------
    dt : float
        Time step, s (GADEN ``time_step``).
    release_rate : float
        Filaments released per second (``num_filaments_sec``).
    ppm_center : float
        Concentration at a new filament's centre, ppm (``ppm_filament_center``).
    sigma0 : float
        Initial filament radius σ0, m (``filament_initial_std``, 10 cm).
    gamma : float
        Growth rate γ of σ², m²/s (``filament_growth_gamma``, 15 cm²/s).
    noise_std : float
        Std of the per-step position noise per axis, m (``filament_noise_std``).
    cutoff : float
        Filaments farther than ``cutoff`` σ from a point do not contribute (GADEN: 5).
    """

    dt: float = 0.1
    release_rate: float = 10.0
    ppm_center: float = 10.0
    sigma0: float = 0.10
    gamma: float = 15e-4
    noise_std: float = 0.02
    cutoff: float = 5.0

    def __post_init__(self):
        for f in fields(self):
            object.__setattr__(self, f.name, self.checked(f.name, getattr(self, f.name), f"FilamentParams.{f.name}"))

    @staticmethod
    def checked(name: str, value, label: str) -> float:
        """``value`` of field ``name`` as a float: positive for dt, sigma0 and cutoff, else non-negative (bools,
        strings, 10**400 refused); messages call it ``label``."""
        return positive(value, label, allow_zero=name not in ("dt", "sigma0", "cutoff"))


_GADEN_KEYS = {  # GADEN key -> (field, scale to SI)
    "time_step": ("dt", 1.0),
    "num_filaments_sec": ("release_rate", 1.0),
    "ppm_filament_center": ("ppm_center", 1.0),
    "filament_initial_std": ("sigma0", 1e-2),  # cm -> m
    "filament_growth_gamma": ("gamma", 1e-4),  # cm²/s -> m²/s
    "filament_noise_std": ("noise_std", 1.0),
}


def read_gaden_config(yaml_path) -> tuple[FilamentParams, np.ndarray]:
    """Filament parameters and source position from a GADEN simulation YAML (e.g. the lab's ``B1.yaml``).

    Only the keys above and ``source_x``/``source_y``/``source_z`` are read; GADEN's other keys (paths,
    playback options) are ignored.

    Returns
    -------
    params : FilamentParams
    source : (3,) ndarray
        (x, y, z) in metres.
    """
    path, data = read_yaml_mapping(yaml_path)
    where = str(path)
    kwargs = {}
    for key, (name, scale) in _GADEN_KEYS.items():
        if key in data:
            value = number(where, key, data[key], nonnegative=True) * scale
            label = f"{where}: key '{key}'" + ("" if scale == 1.0 else " (in SI units)")
            kwargs[name] = FilamentParams.checked(name, value, label)
    missing = [k for k in ("source_x", "source_y") if k not in data]
    if missing:
        raise ValueError(f"{where}: missing required key(s) {missing}")
    src = np.array([number(where, k, data[k]) if k in data else 0.0 for k in ("source_x", "source_y", "source_z")])
    return FilamentParams(**kwargs), src


class FilamentModel:
    """A running filament simulation.

    Parameters
    ----------
    grid : GridMap
        Walls (occupied cells) stop filaments.
    wind : WindSequence or WindField
        Piecewise-constant wind (a single field is constant).
    source : (2,) array_like
        Release point (x, y) in metres; must be in a free cell.
    params : FilamentParams, keyword-only
    outlet : (H, W) ndarray of bool, optional, keyword-only
        Cells that remove filaments.
    seed : int, keyword-only
        Seed of the position noise.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.sim import GridMap, WindField, FilamentModel
    >>> g = GridMap(np.zeros((20, 40), bool), 0.1)
    >>> wind = WindField(g, np.broadcast_to([0.2, 0.0], (20, 40, 2)))
    >>> gas = FilamentModel(g, wind, (1.0, 1.0), seed=0)
    >>> gas.run(10.0)
    >>> gas.n_filaments, bool(gas.concentration([[2.5, 1.0]])[0] > gas.concentration([[0.5, 1.0]])[0])
    (100, True)
    """

    def __init__(self, grid: GridMap, wind, source, *, params: FilamentParams | None = None, outlet=None,
                 seed: int = 0):
        if not isinstance(grid, GridMap):
            raise TypeError(f"grid must be a GridMap, got {type(grid).__name__}")
        if isinstance(wind, WindField):
            wind = WindSequence((wind,), 1e9)
        if not isinstance(wind, WindSequence):
            raise TypeError(f"wind must be a WindSequence or WindField, got {type(wind).__name__}")
        if wind.grid.shape != grid.shape:
            raise ValueError(f"wind grid {wind.grid.shape} does not match the map {grid.shape}")
        self.params = params if params is not None else FilamentParams()
        if not isinstance(self.params, FilamentParams):
            raise TypeError(f"params must be FilamentParams, got {type(self.params).__name__}")
        self.grid = grid
        self.wind = wind
        src = np.asarray(source, dtype=np.float64).ravel()
        if src.size not in (2, 3) or not np.all(np.isfinite(src)):
            raise ValueError(f"source must be a finite (x, y) point, got {source!r}")
        self.source = src[:2].copy()
        if grid.is_occupied(self.source):
            raise ValueError(f"source ({self.source[0]:g}, {self.source[1]:g}) lies in an occupied cell or outside the map")
        if outlet is None:
            outlet = np.zeros(grid.shape, bool)
        outlet = np.asarray(outlet, dtype=bool)
        if outlet.shape != grid.shape:
            raise ValueError(f"outlet must be an (H, W) = {grid.shape} mask, got {outlet.shape}")
        self.outlet = outlet
        self._walls = grid.occupancy
        self._walls_flat = self._walls.ravel()
        self._stays_flat = np.pad(~outlet, 1).ravel()  # free of outlets, inside the map: the filament stays
        self._origin = np.array(grid.origin)
        self._source_cell = grid.world_to_cell(self.source)[None]
        self._rng = np.random.default_rng(seed)
        # one int8 table per cached sensor cell: at most ~32 MB of tables on large maps
        self._los = LineOfSightCache(self._walls, capacity=int(np.clip(2**25 // self._walls.size, 8, 256)))
        self.time = 0.0
        self._step = 0
        self.positions = np.zeros((0, 2))
        self.births = np.zeros(0)
        self._cells = np.zeros((0, 2), dtype=np.int64)
        self.n_released = 0
        self.n_removed = 0

    @property
    def n_filaments(self) -> int:
        """Number of live filaments."""
        return self.births.size

    # --- dynamics ---------------------------------------------------------------------------------------
    # Per step the filaments are whole arrays: flat cell indices with take and boolean selections with
    # compress (much cheaper than fancy indexing of (F, 2) arrays), and the per-filament arithmetic is
    # the same element-wise IEEE operations in the same order as the plain formulas in the docstrings.
    def _cells_of(self, xy) -> np.ndarray:
        """(n, 2) int64 (row, col) of (n, 2) points, as :meth:`GridMap.world_to_cell` (no validation)."""
        return np.floor((xy - self._origin) / self.grid.resolution).astype(np.int64)[:, ::-1]

    def _walls_at(self, r, q) -> np.ndarray:
        """Whether cells (r, q) are walls; indices outside the map are clipped to its border."""
        h, w = self._walls.shape
        flat = np.minimum(np.maximum(r, 0), h - 1) * w + np.minimum(np.maximum(q, 0), w - 1)
        return self._walls_flat.take(flat)

    def _blocked_short(self, p0, p1, c0, c1) -> np.ndarray:
        """Moves of less than one cell per axis: is any cell on the path (after the first) a wall?

        The end cell, and for a diagonal move the cell of the boundary crossed first (column boundary at
        fraction t_x of the move, row boundary at t_y; both at a corner).
        """
        r0, q0, r1, q1 = c0[:, 0], c0[:, 1], c1[:, 0], c1[:, 1]
        blocked = self._walls_at(r1, q1)
        i = ((r1 != r0) & (q1 != q0)).nonzero()[0]  # diagonal moves
        if i.size:
            a, b, ci0, ci1 = p0.take(i, axis=0), p1.take(i, axis=0), c0.take(i, axis=0), c1.take(i, axis=0)
            corner = self._origin + np.maximum(ci0, ci1)[:, ::-1] * self.grid.resolution  # boundaries crossed
            t = (corner - a) / (b - a)  # (t_x, t_y)
            tx, ty = t[:, 0], t[:, 1]
            blocked[i] |= (((tx <= ty) & self._walls_at(ci0[:, 0], ci1[:, 1]))
                           | ((ty <= tx) & self._walls_at(ci1[:, 0], ci0[:, 1])))
        return blocked

    def _blocked(self, p0, p1, c0) -> tuple[np.ndarray, np.ndarray]:
        """(blocked, end cells) for moves p0 -> p1 starting in cells c0.

        A move of less than one cell per axis is checked as it is (:meth:`_blocked_short`); a longer one (jets
        at windows) as n sub-moves of less than one cell per axis, sub-move k ending at a + (b − a) min(k / n, 1):
        it is blocked if the first sub-move that meets a wall or leaves the map meets a wall. Every (sub-)move
        is checked in one pass.
        """
        f = p0.shape[0]
        c1 = self._cells_of(p1)
        d = np.abs(p1 - p0)
        steps = np.ceil(np.maximum(d[:, 0], d[:, 1]) / (0.999 * self.grid.resolution))
        long_ = (steps > 1).nonzero()[0]
        if not long_.size:
            return self._blocked_short(p0, p1, c0, c1), c1
        n = steps[long_].astype(np.int64)
        a, b, ca = p0.take(long_, axis=0), p1.take(long_, axis=0), c0.take(long_, axis=0)
        m = a.shape[0]
        k = np.arange(1, int(n.max()) + 1)[:, None]
        ends = (a + (b - a) * np.minimum(k / n, 1.0)[..., None]).reshape(-1, 2)  # (K·m, 2), sub-move-major
        cells = self._cells_of(ends)
        blocked = self._blocked_short(np.concatenate([p0, a, ends[:-m]]), np.concatenate([p1, ends]),
                                      np.concatenate([c0, ca, cells[:-m]]), np.concatenate([c1, cells]))
        wall = blocked[f:].reshape(-1, m)
        event = wall | ~self.grid.contains(cells).reshape(-1, m)  # met a wall, or left the map
        blocked = blocked[:f]
        blocked[long_] = wall[np.argmax(event, axis=0), np.arange(m)]  # the first event (none: not blocked)
        return blocked, c1

    def release(self, count: int) -> None:
        """Add ``count`` filaments at the source, born now."""
        if count <= 0:
            return
        self.positions = np.concatenate([self.positions, np.repeat(self.source[None], count, axis=0)])
        self.births = np.concatenate([self.births, np.full(count, self.time)])
        self._cells = np.concatenate([self._cells, np.repeat(self._source_cell, count, axis=0)])
        self.n_released += count

    def step(self, n: int = 1) -> None:
        """Advance ``n`` time steps."""
        p = self.params
        h, w = self.grid.shape
        stays = self._stays_flat
        for _ in range(int(n)):
            # releases so that floor(t · rate) filaments exist after time t (exact for any rate)
            self.release(math.floor((self._step + 1) * p.dt * p.release_rate + 1e-9) - self.n_released)
            vel = self.wind.velocities[self.wind.index(self.time)].reshape(-1, 2)
            x0, c0 = self.positions, self._cells
            disp = vel.take(c0[:, 0] * w + c0[:, 1], axis=0) * p.dt
            disp += self._rng.normal(0.0, p.noise_std, size=c0.shape)
            pos = x0 + disp
            blocked, cells = self._blocked(x0, pos, c0)
            i = blocked.nonzero()[0]
            if i.size:  # a move into a wall is skipped
                pos[i] = x0[i]
                cells[i] = c0[i]
            # outlets and the border remove: a table of the cells that keep a filament, with a removing border
            r = np.minimum(np.maximum(cells[:, 0] + 1, 0), h + 1)
            q = np.minimum(np.maximum(cells[:, 1] + 1, 0), w + 1)
            keep = stays.take(r * (w + 2) + q)
            kept = int(np.count_nonzero(keep))
            if kept < keep.size:
                self.n_removed += keep.size - kept
                pos, cells = pos.compress(keep, axis=0), cells.compress(keep, axis=0)
                self.births = self.births.compress(keep)
            self.positions, self._cells = pos, cells
            self._step += 1
            self.time = self._step * p.dt

    def run(self, seconds: float) -> None:
        """Advance by ``seconds`` (rounded to whole steps)."""
        if not (np.isfinite(seconds) and seconds >= 0):
            raise ValueError(f"seconds must be a non-negative number, got {seconds!r}")
        self.step(int(round(seconds / self.params.dt)))

    # --- concentration --------------------------------------------------------------------------------------
    def sigma(self) -> np.ndarray:
        """(F,) current filament radii σ, m: σ² = σ0² + γ (t − t_birth)."""
        p = self.params
        return np.sqrt(p.sigma0**2 + p.gamma * (self.time - self.births))

    def concentration(self, points) -> np.ndarray:
        """Concentration (ppm) at map-frame points.

        Parameters
        ----------
        points : (n, 2) or (2,) array_like
            (x, y) in metres, inside the map.

        Returns
        -------
        (n,) or () ndarray
        """
        pts = np.asarray(points, dtype=np.float64)
        single = pts.ndim == 1
        pts = pts.reshape(-1, 2)
        rc = self._cells_of(pts)
        h, w = self.grid.shape
        if not ((rc[:, 0] >= 0) & (rc[:, 0] < h) & (rc[:, 1] >= 0) & (rc[:, 1] < w)).all():
            raise ValueError(f"points must lie inside the map {self.grid.extent}")
        p = self.params
        s2 = p.sigma0**2 + p.gamma * (self.time - self.births)  # σ² = σ0² + γ (t − t_b)
        amp = p.ppm_center * (p.sigma0**2 / s2) ** 1.5  # ppm_centre (σ0/σ)³
        reach2 = p.cutoff**2 * s2
        fx, fy = self.positions[:, 0], self.positions[:, 1]
        out = np.zeros(len(pts))
        for i, ((x, y), rcq) in enumerate(zip(pts.tolist(), rc)):
            dx, dy = fx - x, fy - y
            d2 = dx * dx + dy * dy  # |x − x_f|²
            near = (d2 < reach2).nonzero()[0]
            if near.size == 0:
                continue
            near = near[self._los.clear_from(rcq, self._cells.take(near, axis=0))]
            out[i] = np.sum(amp[near] * np.exp(-d2[near] / (2 * s2[near])))
        return out[0] if single else out

    def concentration_field(self, *, stride: int = 1) -> np.ndarray:
        """(H, W) concentration at cell centres (every ``stride``-th cell, the rest nan; walls 0).

        For plotting; costs one point query per computed cell.
        """
        if not isinstance(stride, (int, np.integer)) or stride < 1:
            raise ValueError(f"stride must be a positive integer, got {stride!r}")
        h, w = self.grid.shape
        out = np.full((h, w), np.nan)
        rr, cc = np.mgrid[0:h:stride, 0:w:stride]
        rc = np.stack([rr.ravel(), cc.ravel()], axis=-1)
        free = ~self._walls[rc[:, 0], rc[:, 1]]
        out[rc[~free, 0], rc[~free, 1]] = 0.0
        out[rc[free, 0], rc[free, 1]] = self.concentration(self.grid.cell_to_world(rc[free]))
        return out
