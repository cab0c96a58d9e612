"""PMFS-style hit-probability map: per-cell Beta posterior of the hit probability with a confidence.

After Ojeda, Monroy & Gonzalez-Jimenez, PMFS (Probabilistic Mapping of Filament Sources; the ``PMFS``
algorithm of MAPIRlab/GasSourceLocalization): each reading is spread from the robot's cell to the cells
around it with a Gaussian kernel that is stretched along the measured wind (semi-axes σ + k‖w‖ along the wind
and σ / (1 + k‖w‖/σ) across it, as in PMFS) and evaluated at the *geodesic* displacement — the straight
displacement rescaled to the shortest free-space path length (8-connected, no corner cutting), so that
evidence does not cross walls. PMFS then runs a log-odds binary filter per cell; here the kernel weight
w_k(c) of reading k at cell c is used as a fractional Bernoulli observation of that cell's hit probability
h_c with a Beta(p0 m0, (1 − p0) m0) prior, giving the conjugate posterior mean and an effective count

    ĥ_c = (p0 m0 + Σ_k w_k(c) g_k) / (m0 + Σ_k w_k(c)),     n_c = Σ_k w_k(c),

(a Nadaraya–Watson estimate of the hit frequency shrunk to p0). Unlike the log-odds filter, misses lower ĥ
and ĥ converges to the local hit frequency — the quantity a simulated plume predicts. The confidence follows
PMFS' form 1 − exp(−ω / ω0), with ω the accumulated kernel weight: conf_c = 1 − exp(−n_c / n0).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import dijkstra

from .._shared._validate import positive as _positive
from ..geometry._grid import GridMap
from ._wind_input import as_wind_vector

__all__ = ["HitProbabilityMap"]


class HitProbabilityMap:
    """Per-cell hit probability ĥ and confidence from kernel-spread hit/miss readings (PMFS-style).

    Parameters
    ----------
    geometry : psgsl_pgm.GridMap
        The map.
    prior_hit : float, default 0.1
        p0 ∈ (0, 1): prior mean hit probability (PMFS' ``hitPriorProbability``).
    prior_strength : float, default 1.0
        m0 > 0: pseudo-count of the Beta prior. With the defaults one hit at a cell gives ĥ = 0.55 (PMFS uses
        0.6 for the cell of a hit) and one miss ĥ = 0.05.
    kernel_sigma : float, default 0.3
        σ in metres: kernel width in still air.
    kernel_stretch : float, default 1.0
        k in seconds: the along-wind semi-axis is σ + k ‖w‖, the cross-wind one σ / (1 + k ‖w‖ / σ).
    confidence_scale : float, default 0.5
        n0: conf = 1 − exp(−n / n0) for an accumulated kernel weight n.
    cutoff : float, default 3.0
        Readings reach cells up to ``cutoff`` × the along-wind semi-axis away (geodesic distance).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import GridMap
    >>> hm = HitProbabilityMap(GridMap(np.zeros((5, 5), bool), 0.1))
    >>> hm.observe((2, 2), True)
    >>> round(float(hm.hit_probability[2, 2]), 3), float(hm.hit_probability[0, 0]) < 0.55
    (0.55, True)
    """

    def __init__(
        self,
        geometry: GridMap,
        *,
        prior_hit: float = 0.1,
        prior_strength: float = 1.0,
        kernel_sigma: float = 0.3,
        kernel_stretch: float = 1.0,
        confidence_scale: float = 0.5,
        cutoff: float = 3.0,
    ):
        if not isinstance(geometry, GridMap):
            raise TypeError(f"geometry must be a psgsl_pgm.GridMap, got {type(geometry).__name__}")
        self.geometry = geometry
        self.prior_hit = _positive(prior_hit, "prior_hit")
        if not self.prior_hit < 1:
            raise ValueError(f"prior_hit must lie in (0, 1), got {prior_hit!r}")
        self.prior_strength = _positive(prior_strength, "prior_strength")
        self.kernel_sigma = _positive(kernel_sigma, "kernel_sigma")
        if isinstance(kernel_stretch, (bool, str, bytes)) or not np.isfinite(float(kernel_stretch)):
            raise TypeError(f"kernel_stretch must be a non-negative number of seconds, got {kernel_stretch!r}")
        if float(kernel_stretch) < 0:
            raise ValueError(f"kernel_stretch must be non-negative, got {kernel_stretch!r}")
        self.kernel_stretch = float(kernel_stretch)
        self.confidence_scale = _positive(confidence_scale, "confidence_scale")
        self.cutoff = _positive(cutoff, "cutoff")
        self._graph = geometry.free_space_graph()
        self._centres = geometry.cell_centres().reshape(-1, 2)
        self.reset()

    def reset(self) -> None:
        """Back to the prior: ĥ = p0 and zero confidence everywhere."""
        n = self.geometry.shape[0] * self.geometry.shape[1]
        self._hits = np.zeros(n)  # Σ_k w_k(c) g_k
        self._weight = np.zeros(n)  # n_c = Σ_k w_k(c)

    def copy(self) -> "HitProbabilityMap":
        """Independent copy sharing the (immutable) graph."""
        new = object.__new__(HitProbabilityMap)
        new.__dict__.update(self.__dict__)
        new._hits = self._hits.copy()
        new._weight = self._weight.copy()
        return new

    def kernel(self, cell, wind=None) -> np.ndarray:
        """Weights w(c) ∈ [0, 1] of a reading at ``cell`` on every map cell (flat, H*W); 0 behind walls.

        Parameters
        ----------
        cell : tuple of int
            (row, col) of the free sensor cell.
        wind : (2,) array_like of float, optional
            Wind (u_x, u_y) in m/s orienting the kernel; isotropic when ``None`` or zero.
        """
        r, c = self.geometry.check_cell(cell)
        wind = as_wind_vector(wind)
        w_cols = self.geometry.shape[1]
        src = r * w_cols + c
        speed = 0.0 if wind is None else float(np.hypot(wind[0], wind[1]))
        s = self.kernel_sigma
        s_along = s + self.kernel_stretch * speed  # PMFS: σ + k|w|
        s_across = s / (1.0 + self.kernel_stretch * speed / s)  # PMFS: σ / (1 + k|w|/σ)
        geo = dijkstra(self._graph, directed=False, indices=src, limit=self.cutoff * s_along)
        reach = np.flatnonzero(np.isfinite(geo))
        d = self._centres[reach] - self._centres[src]
        eucl = np.hypot(d[:, 0], d[:, 1])
        scale = np.divide(geo[reach], eucl, out=np.ones_like(eucl), where=eucl > 0)
        d *= scale[:, None]  # straight direction, geodesic length
        if speed > 0:
            e = np.array([wind[0], wind[1]], dtype=np.float64) / speed
            along, across = d @ e, d @ np.array([-e[1], e[0]])
        else:
            along, across = d[:, 0], d[:, 1]
        out = np.zeros(self.geometry.shape[0] * w_cols)
        out[reach] = np.exp(-0.5 * ((along / s_along) ** 2 + (across / s_across) ** 2))  # anisotropic Gaussian
        return out

    def observe(self, cell, hit: bool, wind=None) -> None:
        """Add one reading at ``cell`` (row, col) spread by :meth:`kernel`."""
        if not isinstance(hit, (bool, np.bool_)):
            raise TypeError(f"hit must be a bool, got {type(hit).__name__} {hit!r}")
        w = self.kernel(cell, wind)
        self._weight += w
        if hit:
            self._hits += w

    @property
    def hit_probability(self) -> np.ndarray:
        """(H, W) ĥ = (p0 m0 + Σ w g) / (m0 + Σ w): posterior mean hit probability per cell."""
        m0, p0 = self.prior_strength, self.prior_hit
        return ((p0 * m0 + self._hits) / (m0 + self._weight)).reshape(self.geometry.shape)

    @property
    def confidence(self) -> np.ndarray:
        """(H, W) conf = 1 − exp(−n / n0) ∈ [0, 1), n the accumulated kernel weight."""
        return (-np.expm1(-self._weight / self.confidence_scale)).reshape(self.geometry.shape)

    @property
    def weight(self) -> np.ndarray:
        """(H, W) accumulated kernel weight n_c (effective number of readings)."""
        return self._weight.reshape(self.geometry.shape).copy()
