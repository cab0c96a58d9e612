"""The plume model on the map: factorised advection-diffusion operator and adjoint Green's functions.

G(x | s) is the mean concentration at sensor cell x (s/m², per unit emission rate) due to a source in cell s.
With A c = q / h² (see :mod:`._operator`), G(x | s) = (A⁻¹)_{x s} / h². For one sensor cell x the whole row
over all candidate sources s is one *adjoint* solve, Aᵀ y = e_x, G(x | ·) = y / h²: the sparse LU factors of
A are computed once and ``splu(A).solve(e_x, trans="T")`` reuses them (two triangular solves). Rows are cached
per sensor cell (least-recently-used).
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np
import scipy.sparse.linalg as spla

from .._shared._validate import bool_mask, positive
from .._shared._validate import index as as_index
from ..geometry._grid import GridMap
from ._operator import advection_diffusion_operator
from ._wind_input import as_wind_field

__all__ = ["PlumeModel"]

_SOLVE_CHUNK = 64  # adjoint right-hand sides solved together


def _outlets(outlets, grid: GridMap) -> np.ndarray:
    """(H, W) read-only bool mask of the outlet cells (none by default); they must be free."""
    if outlets is None:
        out = np.zeros(grid.shape, dtype=bool)
        out.flags.writeable = False
        return out
    out = bool_mask(outlets, "outlets", grid.shape)
    if (out & grid.occupancy).any():
        r, c = np.argwhere(out & grid.occupancy)[0]
        raise ValueError(f"outlets must be free cells, got an outlet on occupied cell {(int(r), int(c))}")
    return out


def _as_rng(rng) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        return np.random.default_rng(int(rng))
    raise TypeError(f"rng must be a numpy Generator or an integer seed, got {type(rng).__name__} {rng!r}")


class PlumeModel:
    """Steady advection-diffusion-decay plume on an occupancy grid, with cached adjoint Green's functions.

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
        True = occupied (no-flux wall).
    resolution : float
        Cell side h in metres.
    origin : (2,) array_like of float, default (0, 0)
        Map-frame (x, y) of the lower-left corner of cell (0, 0).
    wind : (H, W, 2) ndarray of float, optional
        Cell-centred wind (u_x, u_y) in m/s (e.g. the simulated potential flow), or an object with such a
        ``.velocity`` array (``sim.WindField``); ``None`` = still air. Ignored on occupied cells.
    outlets : (H, W) ndarray of bool, optional
        Free cells that absorb gas (windows/doors to the outside): c = 0 there.
    diffusivity : float, default 0.05
        Eddy diffusivity D in m²/s.
    lifetime : float, default 20.0
        Particle lifetime τ in s (Vergassola's finite lifetime: for a thresholded hit sensor, the time a puff
        stays above the detection threshold; it also makes a closed room well posed).
    encounter_scale : float, default 0.4
        κ in m²/s: the expected number of sensor encounters in one sample is κ G(x | s); see
        :func:`vergassola_encounter_scale` for κ = R Δt 2π D / ln(λ/a) from physical quantities and
        :func:`fit_encounter_scale` for a maximum-likelihood fit to readings around a known source.

    boundary : {"wall", "open"}, default "wall"
        The map border: no-flux wall, or absorbing free space.
    scheme : {"exponential", "upwind"}, default "exponential"
        Face-flux scheme of the advection term (see :func:`advection_diffusion_operator`).
    cache_size : int, default 512
        Number of sensor cells whose Green's-function rows are kept (least recently used first out; each
        row is H·W float64, so 512 rows of the 120 x 100 default house take 49 MB).

    Notes
    -----
    The defaults are illustrative, not calibrated: with D = 0.05 m²/s, τ = 20 s and κ = 0.4 m²/s, a source in
    open space with a 0.1 m/s wind gives P(hit) ≈ 0.56 one metre downwind and ≈ 0.11 one metre upwind
    (h = 0.1 m). Calibrate D, τ and κ on readings around known sources before drawing conclusions
    (:func:`fit_plume_parameters`).

    Examples
    --------
    >>> import numpy as np
    >>> occ = np.zeros((20, 30), bool)
    >>> wind = np.zeros((20, 30, 2)); wind[..., 0] = 0.2
    >>> m = PlumeModel(occ, resolution=0.1, wind=wind, diffusivity=0.02, lifetime=30.0)
    >>> g = m.green((2.05, 1.05))           # G(x | s) for every candidate source s, shape (H, W)
    >>> r, c = np.unravel_index(np.argmax(g), g.shape)
    >>> bool(c <= 20)                        # the most likely emitters sit upwind of (or at) the sensor
    True
    >>> bool(np.all(m.hit_probability((2.05, 1.05)) <= 1.0))
    True
    """

    def __init__(
        self,
        occupancy,
        *,
        resolution,
        origin=(0.0, 0.0),
        wind=None,
        outlets=None,
        diffusivity: float = 0.05,
        lifetime: float = 20.0,
        encounter_scale: float = 0.4,
        boundary: str = "wall",
        scheme: str = "exponential",
        cache_size: int = 512,
    ):
        self.geometry = GridMap(occupancy, resolution, origin)  # the map (psgsl_pgm.GridMap)
        if self.geometry.occupancy.all():
            raise ValueError("occupancy has no free cell: there is nowhere for a source or a sensor to be")
        self.outlets = _outlets(outlets, self.geometry)
        self.wind = as_wind_field(wind, self.geometry.shape, self.geometry.free)
        self.diffusivity = positive(diffusivity, "diffusivity", "m²/s")
        self.lifetime = positive(lifetime, "lifetime", "s")
        self.encounter_scale = positive(encounter_scale, "encounter_scale", "m²/s")
        self.cache_size = as_index(cache_size, "cache_size")
        self.boundary = boundary
        self.scheme = scheme
        A, index = advection_diffusion_operator(
            self.geometry,
            self.wind,
            outlets=self.outlets,
            diffusivity=self.diffusivity,
            lifetime=self.lifetime,
            boundary=boundary,
            scheme=scheme,
        )
        self._A = A
        index.flags.writeable = False
        self._index = index
        self._index_flat = index.ravel()
        self._active_flat = np.flatnonzero(self._index_flat >= 0)
        self._lu_factors = None  # SuperLU factors of A, on first use (_lu)
        self._cache: OrderedDict[int, np.ndarray] = OrderedDict()
        self.n_solves = 0  # adjoint right-hand sides solved so far (for benchmarks)

    @classmethod
    def from_grid_map(cls, grid_map, wind=None, *, outlets=None, **kwargs) -> "PlumeModel":
        """Build from any object with ``.occupancy``, ``.resolution`` and ``.origin`` (e.g. ``sim.GridMap``).

        ``wind`` is an (H, W, 2) array_like in m/s (or ``None``); other keywords as in the constructor.
        """
        missing = [a for a in ("occupancy", "resolution", "origin") if not hasattr(grid_map, a)]
        if missing:
            raise TypeError(
                f"grid_map must have .occupancy, .resolution and .origin; {type(grid_map).__name__} lacks "
                f"{', '.join('.' + m for m in missing)}"
            )
        return cls(grid_map.occupancy, resolution=grid_map.resolution, origin=grid_map.origin, wind=wind,
                   outlets=outlets, **kwargs)

    # --- geometry -------------------------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the map."""
        return self.geometry.shape

    @property
    def operator(self):
        """(n, n) scipy.sparse.csc_matrix A over the active cells (a copy)."""
        return self._A.copy()

    @property
    def active_index(self) -> np.ndarray:
        """(H, W) int64: row/column of each cell in :attr:`operator`; −1 on occupied and outlet cells."""
        return self._index

    @property
    def _lu(self):
        """The sparse LU factorisation of A, computed on first use: a model replaced before its first solve (the
        closed loop's prior-wind model, replaced at the first wind reading) never pays for it."""
        if self._lu_factors is None and self._A.shape[0] > 0:
            self._lu_factors = spla.splu(self._A)
        return self._lu_factors

    @property
    def factor(self):
        """The ``scipy.sparse.linalg.SuperLU`` factorisation of A (``None`` if no cell is active)."""
        return self._lu

    def cell_of(self, position, name: str = "position") -> tuple[int, int]:
        """(row, col) of the free cell containing map-frame ``position`` (x, y); ValueError otherwise."""
        return self.geometry.cell_of(position, name)

    # --- Green's functions ----------------------------------------------------------------------------------
    def _solve(self, rhs: np.ndarray, trans: str) -> np.ndarray:
        """Solve A y = rhs (trans="N") or Aᵀ y = rhs (trans="T") for (n,) or (n, k) rhs; clip round-off < 0."""
        y = self._lu.solve(rhs, trans=trans)
        self.n_solves += 1 if rhs.ndim == 1 else rhs.shape[1]
        np.maximum(y, 0.0, out=y)  # A⁻¹ ≥ 0 exactly (M-matrix); LU round-off can leave −1e-20-sized values
        return y

    def green_rows(self, cells) -> np.ndarray:
        """G(x_k | s) for sensor cells x_k and all candidate sources s, flattened over the map.

        Parameters
        ----------
        cells : (K,) array_like of int
            Flat (row-major) indices of free sensor cells.

        Returns
        -------
        G : (K, H*W) ndarray of float64
            s/m² per unit emission rate; zero for sources in occupied or outlet cells and for sensors in
            outlet cells. Rows are cached per sensor cell.
        """
        flat = np.asarray(cells, dtype=np.int64).reshape(-1)
        n_cells = self.shape[0] * self.shape[1]
        if flat.size and (flat.min() < 0 or flat.max() >= n_cells):
            raise ValueError(f"cells must be flat indices in [0, {n_cells}), got range [{flat.min()}, {flat.max()}]")
        if flat.size and self.geometry.occupancy.ravel()[flat].any():
            bad = int(flat[self.geometry.occupancy.ravel()[flat]][0])
            raise ValueError(f"sensor cell {divmod(bad, self.shape[1])} is occupied")
        out = np.zeros((flat.size, n_cells))
        todo = []
        for k, cell in enumerate(flat.tolist()):  # loop over requested sensor cells (a handful per update)
            row = self._cache.get(cell)
            if row is not None:
                self._cache.move_to_end(cell)
                out[k] = row
            elif self._index_flat[cell] >= 0:
                todo.append(k)
        h2 = self.geometry.resolution**2
        for start in range(0, len(todo), _SOLVE_CHUNK):
            ks = todo[start : start + _SOLVE_CHUNK]
            rhs = np.zeros((self._A.shape[0], len(ks)))
            rhs[self._index_flat[flat[ks]], np.arange(len(ks))] = 1.0  # e_x
            y = self._solve(rhs, "T")  # Aᵀ y = e_x  ->  y_s = (A⁻¹)_{x s}
            out[np.asarray(ks)[:, None], self._active_flat[None, :]] = (y / h2).T  # G(x|s) = (A⁻¹)_{xs} / h²
        if self.cache_size:
            for k in todo:
                row = out[k].copy()
                row.flags.writeable = False
                self._cache[int(flat[k])] = row
            while len(self._cache) > self.cache_size:
                self._cache.popitem(last=False)
        return out

    def green(self, position) -> np.ndarray:
        """G(x | s) over all candidate sources s for the sensor at map-frame ``position``.

        Returns
        -------
        G : (H, W) ndarray of float64
            Mean concentration at the sensor (s/m² per unit emission rate) for a source in each cell.
        """
        r, c = self.cell_of(position)
        return self.green_rows([r * self.shape[1] + c])[0].reshape(self.shape)

    def concentration(self, source) -> np.ndarray:
        """Forward solution: mean concentration field c(· | s) of a unit source at map-frame ``source``.

        Returns
        -------
        c : (H, W) ndarray of float64
            s/m² per unit emission rate (zero on occupied and outlet cells, and everywhere if the source
            cell is an outlet).
        """
        r, c = self.cell_of(source, "source")
        rhs = np.zeros(self._A.shape[0])
        j = self._index[r, c]
        if j >= 0:
            rhs[j] = 1.0  # e_s; an outlet source emits nothing
        return self._field(rhs)

    def _field(self, rhs: np.ndarray) -> np.ndarray:
        """(H, W) c = A⁻¹ q / h² of the emission q over the active cells (zero elsewhere), one forward solve."""
        out = np.zeros(self.shape[0] * self.shape[1])
        if rhs.any():
            out[self._active_flat] = self._solve(rhs, "N") / self.geometry.resolution**2  # c = A⁻¹ q / h²
        return out.reshape(self.shape)

    def mean_concentration(self, source_probs) -> np.ndarray:
        r"""The mean concentration at every cell x for a source distributed over the map:
        :math:`\bar c(x) = \sum_s p(s)\, G(x \mid s)`, one forward solve (superposition).

        With A c = q / h², :math:`\bar c = A^{-1} p / h^2`: the field of the distributed source p, where the
        rows of :meth:`green_rows` would need one adjoint solve per cell x.

        Parameters
        ----------
        source_probs : (H, W) array_like of float
            Non-negative weights p(s) of the candidate sources (a posterior, or any distributed emission);
            weights on occupied and outlet cells emit nothing.

        Returns
        -------
        c : (H, W) ndarray of float64
            s/m² per unit emission rate; zero on occupied and outlet cells.

        Raises
        ------
        ValueError
            If ``source_probs`` is not (H, W), or holds a negative or non-finite value.

        Examples
        --------
        >>> import numpy as np
        >>> m = PlumeModel(np.zeros((6, 8), bool), resolution=0.25)
        >>> p = np.zeros((6, 8)); p[2, 3] = 0.25; p[4, 6] = 0.75
        >>> c = m.mean_concentration(p)
        >>> bool(np.allclose(c.ravel()[2 * 8 + 1], 0.25 * m.green_rows([17])[0, 19] + 0.75 * m.green_rows([17])[0, 38]))
        True
        """
        w = np.asarray(source_probs, dtype=np.float64)
        if w.shape != self.shape:
            raise ValueError(f"source_probs must have the map's shape {self.shape}, got {w.shape}")
        if not (np.isfinite(w).all() and (w >= 0).all()):
            raise ValueError("source_probs must be finite and non-negative")
        return self._field(w.ravel()[self._active_flat])  # c̄ = A⁻¹ p / h²

    def hit_probability(self, position) -> np.ndarray:
        """P(hit at ``position`` | s) = 1 − exp(−κ G(x | s)) for every candidate source s, shape (H, W)."""
        return -np.expm1(-self.encounter_scale * self.green(position))  # Poisson: 1 − exp(−κ G)

    def sample_hits(self, positions, source, *, rng) -> np.ndarray:
        """Synthetic independent hit/miss readings drawn from the model for a source at ``source``.

        Parameters
        ----------
        positions : (n, 2) array_like of float
            Sensor positions (x, y) in metres.
        source : (2,) array_like of float
            Source position in metres.
        rng : numpy.random.Generator or int
            Random generator or seed.

        Returns
        -------
        hits : (n,) ndarray of bool
        """
        gen = _as_rng(rng)
        pos = np.asarray(positions, dtype=np.float64)
        if pos.ndim != 2 or pos.shape[1] != 2:
            raise ValueError(f"positions must have shape (n, 2) (x, y in metres), got {pos.shape}")
        field = self.concentration(source)
        cells = np.array([self.cell_of(p) for p in pos], dtype=np.int64).reshape(-1, 2)
        p_hit = -np.expm1(-self.encounter_scale * field[cells[:, 0], cells[:, 1]])  # 1 − exp(−κ c)
        return gen.random(len(pos)) < p_hit
