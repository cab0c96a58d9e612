"""GrGSL: MAPIR's grid-based gas source localization from local gas and wind readings.

Ojeda, Monroy & Gonzalez-Jimenez, "Information-Driven Gas Source Localization Exploiting Gas and Wind Local
Measurements for Autonomous Mobile Robots", IEEE Robotics and Automation Letters 6(2), 2021; the ``GrGSL``
algorithm of MAPIRlab/GasSourceLocalization.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import dijkstra

from .._shared._validate import positive
from ._base import Observation, OlfactoryEstimator, _check_model
from ._plume import PlumeModel

__all__ = ["GrGSL"]


class GrGSL(OlfactoryEstimator):
    r"""GrGSL's cell-wise source probability from binary gas readings and the local wind direction.

    Each reading at cell r multiplies :math:`p(s \mid g)` by a factor :math:`f_r(s)` and renormalises (Sec. III
    of the paper; GrGSL's ``estimateProbabilitiesfromGasAndWind``):

    * **Hit with significant wind** (‖w‖ > ``wind_threshold``): the source is upwind. Every cell q on the ring
      of cells at Chebyshev distance k from r gets :math:`f = e^{-\Delta^2 / (2 \sigma_\text{hit}^2)}`, Δ the
      angle between the direction r → q and the upwind direction −w/‖w‖ (wrapped to (−π, π]); the cells inside
      the ring get f(Δ = 0).
    * **Miss**: the source is more likely towards the last hit: the same with Δ the angle between r → q and
      r → (position of the last hit; the first reading's position before any hit), :math:`\sigma_\text{miss}`,
      and the cells inside the ring get f(Δ = π).
    * **Hit without significant wind**: no update (GrGSL's optional diffusion term is off by default).

    Every other cell takes the factor of the ring cell its shortest free path from r (8-connected, no corner
    cutting, walls blocking) leaves the ring through, so a wall sends the evidence around it (GrGSL propagates
    the ring's values over the navigation map, keeping the shortest path's). Cells no path reaches take the
    smallest factor of the update. In log space the update is

    .. math:: \log p(s \mid g_{1:t}) = \log p(s \mid g_{1:t-1}) - \frac{\Delta_t(s)^2}{2 \sigma_t^2} + \text{const}

    (the Gaussian's normalisation and GrGSL's normalisation of the factors cancel).

    GrGSL runs on a coarsened copy of the map (its ``scale``) with the ring two coarse cells away; here it
    runs on the map's own cells with the ring at k = round(``ring_radius`` / resolution) cells, the same
    geometry at the map's resolution. The wind is the anemometer reading (m/s, map frame); a reading without
    one counts as no significant wind.

    Parameters
    ----------
    model : PlumeModel
        The robot's map (its wind and plume parameters are not used).
    prior : (H, W) array_like, optional, keyword-only
        :math:`p(s)`; uniform over free cells by default.
    ring_radius : float, default 0.5, keyword-only
        Radius of the ring in metres (GrGSL: two cells of its coarse map).
    hit_std, miss_std : float, default 1.0, 2.0, keyword-only
        :math:`\sigma_\text{hit}` and :math:`\sigma_\text{miss}` in radians (GrGSL's ``stdev_hit``, ``stdev_miss``).
    wind_threshold : float, default 0.05, keyword-only
        Wind speed in m/s above which a hit's wind direction is used (GrGSL's ``th_wind_present``).

    Examples
    --------
    >>> import numpy as np
    >>> est = GrGSL(PlumeModel(np.zeros((9, 9), bool), resolution=0.25), ring_radius=0.5)
    >>> p = est.update((1.1, 1.1), True, wind=(0.3, 0.0))       # wind towards +x: the source is at smaller x
    >>> bool(p[4, 0] > p[4, 8]), bool(abs(p.sum() - 1) < 1e-12)
    (True, True)
    """

    def __init__(self, model: PlumeModel, *, prior=None, ring_radius: float = 0.5, hit_std: float = 1.0,
                 miss_std: float = 2.0, wind_threshold: float = 0.05):
        _check_model(model)
        self.ring_radius = positive(ring_radius, "ring_radius", "m")
        self.hit_std = positive(hit_std, "hit_std", "rad")
        self.miss_std = positive(miss_std, "miss_std", "rad")
        self.wind_threshold = positive(wind_threshold, "wind_threshold", "m/s", allow_zero=True)
        self.ring = max(int(round(self.ring_radius / model.geometry.resolution)), 1)
        self._graph = model.geometry.free_space_graph()
        super().__init__(model, prior=prior)

    @classmethod
    def from_model(cls, model: PlumeModel, **options) -> "GrGSL":
        """The estimator on ``model`` (the same as the constructor; for symmetry with the other estimators)."""
        return cls(model, **options)

    def replace_model(self, model: PlumeModel) -> np.ndarray:
        """Take a plume model of the same map (e.g. one solved on a refreshed mean-wind estimate) without
        re-assimilating the readings: this estimator's update does not use the model's wind (it reads the
        anemometer only)."""
        self._adopt_model(model)
        return self.posterior

    def _reset_state(self) -> None:
        self._last_hit = None  # (x, y) of the last hit; the first reading's position until one
        self._first = None
        self._loglik = np.zeros(self.geometry.shape[0] * self.geometry.shape[1])  # Σ_t log f_t(s)

    def log_factor(self, cell, direction: float, std: float, inner: float) -> np.ndarray:
        r"""(H·W,) :math:`\log f(s) = -\Delta(s)^2 / (2\, \mathrm{std}^2)` of one update at ``cell`` (row, col), Δ the
        angle between the direction cell → ring cell and ``direction`` (radians, map frame), ``inner`` the Δ of the
        cells inside the ring; every other cell takes its ring cell's value along its shortest free path (see the
        class)."""
        geo = self.geometry
        h, w = geo.shape
        r0, c0 = geo.check_cell(cell)
        src = r0 * w + c0
        rows, cols = np.divmod(np.arange(h * w), w)
        cheb = np.maximum(np.abs(rows - r0), np.abs(cols - c0))
        centres = self._centres
        d = centres - centres[src]
        delta = np.angle(np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) - direction)))  # wrapped to (−π, π]
        own = np.where(cheb < self.ring, -0.5 * (inner / std) ** 2, -0.5 * (delta / std) ** 2)
        _, pred = dijkstra(self._graph, directed=False, indices=src, return_predecessors=True)
        stop = cheb <= self.ring
        idx = np.arange(h * w)
        reached = (pred >= 0) | (idx == src)
        anc = np.where(stop | ~reached, idx, pred)
        while True:  # pointer jumping to the ring cell each path leaves the ring through
            nxt = np.where(stop[anc], anc, anc[anc])
            if np.array_equal(nxt, anc):
                break
            anc = nxt
        out = own[anc]
        far = ~reached & ~stop
        free = geo.free.ravel()
        if far.any():
            out[far] = out[free & ~far].min() if (free & ~far).any() else 0.0
        return out

    def _propose(self, obs: Observation):
        first = self._first if self._first is not None else obs.position
        last = self._last_hit if self._last_hit is not None else first
        if obs.hit:
            speed = 0.0 if obs.wind is None else float(np.hypot(*obs.wind))
            if speed <= self.wind_threshold:
                factor = None  # no significant wind: GrGSL does not update
            else:
                factor = self.log_factor(obs.cell, float(np.arctan2(-obs.wind[1], -obs.wind[0])), self.hit_std, 0.0)
            last = obs.position
        else:
            direction = float(np.arctan2(last[1] - obs.position[1], last[0] - obs.position[0]))
            factor = self.log_factor(obs.cell, direction, self.miss_std, np.pi)
        loglik = self._loglik if factor is None else self._loglik + factor
        return loglik, (loglik, last if (obs.hit or self._last_hit is not None) else None, first)

    def _accept(self, obs: Observation, payload) -> None:
        self._loglik, self._last_hit, self._first = payload
