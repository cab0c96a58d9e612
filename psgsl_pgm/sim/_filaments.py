"""GADEN's filament gas-dispersion model in 2-D (the loops over the filaments compiled,
:mod:`psgsl_pgm.kernels._filaments`).

Each time step (as GADEN's ``filament_simulator``): new filaments are released at the source at
``release_rate``; every filament moves by the local wind (nearest cell of the snapshot in force) times dt
plus isotropic Gaussian noise; a move whose path crosses a wall is skipped (the filament stays), a filament
that ends in an outlet cell or leaves the map is removed. A filament born at t_b has

    σ²(t) = σ0² + γ (t − t_b)

and the concentration at a point x is (GADEN's player, with the filament's line of sight to x):

    C(x) = Σ_f ppm_centre · (σ0 / σ_f)³ · exp(−|x − x_f|² / 2σ_f²)    over filaments with |x − x_f| < 5 σ_f.

Line of sight is between the centres of the query cell and the filament's cell (exact traversal, cached per
query cell; see :mod:`psgsl_pgm.geometry._sight`). A gas sensor's window — n steps, each followed by a
concentration at the sensor — is one compiled pass (:meth:`FilamentModel.sample`).
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
    playback options) are ignored. Keys in GADEN's units are converted to SI.

    Parameters
    ----------
    yaml_path : str or path-like
        The GADEN simulation's YAML file.

    Returns
    -------
    params : FilamentParams
        The keys the file sets; :class:`FilamentParams`' defaults for the others.
    source : (3,) ndarray of float64
        (x, y, z) in metres (z = 0 when the file has no ``source_z``).

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        The file is not a YAML mapping, a value is not a non-negative number or out of its range, or
        ``source_x`` / ``source_y`` is missing; the message names the file and key.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import read_gaden_config
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "B1.yaml"
    ...     _ = path.write_text("{source_x: 2.5, source_y: 1.0, source_z: 0.5}")
    ...     params, source = read_gaden_config(path)
    >>> source.tolist()
    [2.5, 1.0, 0.5]
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
    # The per-filament loops are compiled (psgsl_pgm.kernels._filaments): the same IEEE operations in the same
    # order as the plain formulas in the docstrings, the noise drawn from this model's generator in the same order.
    def release(self, count: int) -> None:
        """Add ``count`` filaments at the source, born now."""
        if count <= 0:
            return
        self.positions = np.concatenate([self.positions, np.repeat(self.source[None], count, axis=0)])
        self.births = np.concatenate([self.births, np.full(count, self.time)])
        self._cells = np.concatenate([self._cells, np.repeat(self._source_cell, count, axis=0)])
        self.n_released += count

    def step(self, n: int = 1) -> None:
        """Advance ``n`` time steps.

        Per step: the filaments due by then are released at the source (⌊t · rate⌋ exist after time t); every
        filament moves by the wind of its cell (the snapshot in force) times dt plus Gaussian noise of
        ``noise_std`` per axis; a move that meets a wall is skipped (a move of more than one cell per axis, a jet
        at a window, is checked as sub-moves of less than one cell: the first sub-move that meets a wall or
        leaves the map decides); a filament that ends in an outlet or off the map is removed.
        """
        from ..kernels._filaments import steps

        n = int(n)
        if n > 0:
            self._advance(steps, n)

    def _due(self, n: int) -> int:
        """Filaments released by the next ``n`` steps (⌊(step + 1) dt · rate + 1e-9⌋ is non-decreasing)."""
        p = self.params
        return max(math.floor((self._step + n) * p.dt * p.release_rate + 1e-9) - self.n_released, 0)

    def _advance(self, kernel, n: int, *extra) -> None:
        """Run ``kernel`` (:mod:`psgsl_pgm.kernels._filaments`) over ``n`` steps on arrays with room for the
        filaments released meanwhile, then keep its survivors."""
        p = self.params
        h, w = self.grid.shape
        live = self.births.size
        capacity = live + self._due(n)
        pos = np.empty((capacity, 2))
        births = np.empty(capacity)
        cells = np.empty((capacity, 2), dtype=np.int64)
        pos[:live] = self.positions
        births[:live] = self.births
        cells[:live] = self._cells
        stack = self.wind.velocities
        velocities = np.ascontiguousarray(stack).reshape(stack.shape[0], -1, 2)
        (sr, sq), (ox, oy) = self._source_cell[0], self._origin
        live, self.n_released, removed = kernel(
            self._rng, n, self._step, float(self.time), self.n_released, pos, births, cells, live, velocities,
            float(self.wind.period), float(p.dt), float(p.release_rate), float(p.noise_std), float(self.source[0]),
            float(self.source[1]), int(sr), int(sq), self._walls_flat, self._stays_flat, h, w, float(ox), float(oy),
            float(self.grid.resolution), *extra)
        self.n_removed += removed
        self.positions, self.births, self._cells = pos[:live], births[:live], cells[:live]
        self._step += n
        self.time = self._step * p.dt

    def sample(self, point, n: int) -> np.ndarray:
        """Advance ``n`` time steps and return the concentration at ``point`` after each, (n,) ppm: the same
        numbers as ``n`` × (:meth:`step`, :meth:`concentration`), in one compiled pass (a gas sensor's window).

        Parameters
        ----------
        point : (2,) array_like
            (x, y) in metres, inside the map.
        n : int
            Time steps (samples), at least 1.
        """
        from ..kernels._filaments import sample

        n = int(n)
        if n < 1:
            raise ValueError(f"n must be a positive number of samples, got {n!r}")
        pts, cells = self._cells_inside(point)
        if len(pts) != 1:
            raise ValueError(f"point must be one (x, y) pair in metres, got shape {np.shape(point)}")
        (x, y), (r, c) = pts[0].tolist(), cells[0].tolist()
        p = self.params
        room = n * (self.births.size + self._due(n))  # every filament may reach the point after every step
        neg_arg, var, ends = np.empty(room), np.empty(room), np.empty(n, dtype=np.int64)
        self._advance(sample, n, x, y, r, c, p.sigma0**2, p.gamma, p.cutoff**2, self._walls, self._los.table((r, c)),
                      neg_arg, var, ends)
        return self._sums(neg_arg, var, ends)

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
        from ..kernels._filaments import near

        single = np.ndim(points) == 1
        pts, rc = self._cells_inside(points)
        p = self.params
        live = self.births.size
        pos = np.ascontiguousarray(self.positions, dtype=np.float64)
        births = np.ascontiguousarray(self.births, dtype=np.float64)
        cells = np.ascontiguousarray(self._cells, dtype=np.int64)
        neg_arg, var = np.empty(len(pts) * live), np.empty(len(pts) * live)
        ends = np.empty(len(pts), dtype=np.int64)
        end = 0
        for i, ((x, y), (r, c)) in enumerate(zip(pts.tolist(), rc.tolist())):
            end += near(pos, births, cells, live, x, y, r, c, float(self.time), p.sigma0**2, p.gamma, p.cutoff**2,
                        self._walls, self._los.table((r, c)), neg_arg[end:], var[end:])
            ends[i] = end
        out = self._sums(neg_arg, var, ends)
        return out[0] if single else out

    def _cells_inside(self, points):
        """((n, 2) points, (n, 2) int64 (row, col) of their cells) of map-frame points; ValueError off the map."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        rc = np.floor((pts - self._origin) / self.grid.resolution).astype(np.int64)[:, ::-1]
        h, w = self.grid.shape
        if not ((rc[:, 0] >= 0) & (rc[:, 0] < h) & (rc[:, 1] >= 0) & (rc[:, 1] < w)).all():
            raise ValueError(f"points must lie inside the map {self.grid.extent}")
        return pts, rc

    def _sums(self, neg_arg, var, ends) -> np.ndarray:
        """C = Σ_f ppm_centre (σ0/σ_f)³ exp(−|x − x_f|² / 2σ_f²) over each point's filaments (the kernels list
        −|x − x_f|² / 2σ_f² and σ_f², the points' runs ending at ``ends``): (len(ends),) ppm, numpy's exp, power and
        pairwise sum (elementwise, so the same numbers whichever filaments share the arrays)."""
        p = self.params
        n = int(ends[-1]) if len(ends) else 0
        terms = p.ppm_center * (p.sigma0**2 / var[:n]) ** 1.5 * np.exp(neg_arg[:n])  # ppm_centre (σ0/σ)³ exp(…)
        out = np.zeros(len(ends))
        start = 0
        for k, end in enumerate(ends.tolist()):  # one sum per point
            if end > start:
                out[k] = np.sum(terms[start:end])
            start = end
        return out

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
