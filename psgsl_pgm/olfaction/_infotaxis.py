"""Grid Infotaxis: Bayesian hit/miss source posterior from the grid plume model (Vergassola et al. 2007)."""

from __future__ import annotations

import numpy as np

from .._shared._validate import unit_interval
from ._base import Observation, OlfactoryEstimator
from ._plume import PlumeModel

__all__ = ["GridInfotaxis"]


class GridInfotaxis(OlfactoryEstimator):
    """Infotaxis posterior p(s | g) with the likelihood of a grid advection-diffusion plume.

    Each reading at sensor cell x multiplies the posterior by the likelihood of every candidate source s,

        P(hit | s) = ε + (1 − ε) (1 − exp(−κ G(x | s))),     P(miss | s) = (1 − ε) exp(−κ G(x | s)),

    i.e. Poisson encounters with mean κ G(x | s) in one sample (Vergassola et al. 2007: encounter rate
    R(r | r0) ∝ c(r | r0)), with G the adjoint Green's function of :class:`PlumeModel` (walls no-flux, outlets
    absorbing, the map's wind field) and a false-hit probability ε (sensor noise, and model mismatch: without
    it one hit where the model predicts G = 0 for the true source — e.g. a gust through a door the mean flow
    does not carry — would exclude the true source for ever). The log-likelihoods are accumulated,

        log p(s | g_1..n) = log p(s) + β Σ_k log P(g_k | s) − log Z,

    and normalised with ``logsumexp``.

    **Tempering (β).** The product over readings assumes they are independent given s. Hits from one real
    (or filament-simulated) plume are not: the model's P(hit | s) is the *ensemble* mean over plume
    realisations, while consecutive stops of one robot sample the *same* meandering plume, whose intermittent
    puffs are correlated over seconds and over the plume width. A run of n correlated readings carries the
    information of n_eff < n independent ones, so the naive product is over-confident — it collapses onto
    one cell long before the evidence supports that, and a collapsed p(s | g) would veto the semantic factor
    p(s | z) in eq. ``combined-conditionals``. We use the power (tempered / "coarsened") likelihood, raising
    each factor to β = n_eff / n ∈ (0, 1] (Grünwald's "safe Bayes"; Miller & Dunson 2019, JASA 114, 1113), so
    that the posterior contracts as if only βn readings were independent. The default β = 0.5 assumes each
    reading shares roughly half of its information with its neighbours along the path (stops about one plume
    correlation length apart); estimate it from data instead where there are readings around known sources:
    :func:`ar1_tempering` turns the lag-1 autocorrelation ρ of the hit model's residuals into
    β = (1 − ρ)/(1 + ρ) (the validation experiment does so on its calibration runs); β = 1 recovers Vergassola's exact update and is right for readings that are
    independent draws from the model (as in the tests). The estimator is further meant to be called once per
    stop (one reading per stop — several readings at one stop sample the same puffs): that convention, not
    β, removes the strongest correlation, so β need not be tiny. The estimator is deterministic (no random
    numbers); synthetic readings come from :meth:`PlumeModel.sample_hits` with an explicit seed.

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
        True = occupied.
    resolution : float
        Cell side in metres.
    origin : (2,) array_like of float, default (0, 0)
        Map-frame (x, y) of the lower-left corner of cell (0, 0).
    wind : (H, W, 2) ndarray of float, optional
        Wind field (u_x, u_y) in m/s used by the plume model (``None`` = still air).
    outlets : (H, W) ndarray of bool, optional
        Absorbing free cells.
    prior : (H, W) array_like of float, optional
        Prior p(s); uniform over free cells by default.
    tempering : float, default 0.5
        β ∈ (0, 1], exponent of every reading's likelihood (see above).
    false_hit_rate : float, default 0.01
        ε ∈ [0, 1): probability of a hit whatever the source. With ε = 0 a hit that no candidate can explain
        raises ValueError.
    **plume : keyword arguments
        ``diffusivity``, ``lifetime``, ``encounter_scale``, ``boundary``, ``scheme``, ``cache_size`` of
        :class:`PlumeModel`.

    Notes
    -----
    The anemometer reading passed to :meth:`update` is validated and stored with the observation but does not
    enter the likelihood: the plume model uses the mean wind field it was built with — in the validation
    experiment the robot's own estimate from its anemometer readings (:class:`MeanWindEstimator`), the plume
    re-solved as the estimate moves (:meth:`replace_model`).

    Examples
    --------
    >>> import numpy as np
    >>> occ = np.zeros((10, 12), bool)
    >>> est = GridInfotaxis(occ, resolution=0.25, diffusivity=0.05, lifetime=20.0, tempering=1.0)
    >>> p = est.update((1.4, 1.1), True)
    >>> p.shape, bool(abs(p.sum() - 1) < 1e-12)
    ((10, 12), True)
    >>> est.map_cell()                       # in still air a hit points at the sensor's own cell
    (4, 5)
    >>> est.reset(); bool(np.allclose(est.posterior, 1 / 120))
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
        prior=None,
        tempering: float = 0.5,
        false_hit_rate: float = 0.01,
        **plume,
    ):
        model = PlumeModel(occupancy, resolution=resolution, origin=origin, wind=wind, outlets=outlets, **plume)
        self._configure(tempering, false_hit_rate)
        super().__init__(model, prior=prior)

    @classmethod
    def from_model(
        cls, model: PlumeModel, *, prior=None, tempering: float = 0.5, false_hit_rate: float = 0.01
    ) -> "GridInfotaxis":
        """Estimator on an existing :class:`PlumeModel` (shares its factorisation and Green's-function cache)."""
        self = cls.__new__(cls)
        self._configure(tempering, false_hit_rate)
        OlfactoryEstimator.__init__(self, model, prior=prior)
        return self

    @classmethod
    def from_grid_map(cls, grid_map, wind=None, *, outlets=None, prior=None, **kwargs) -> "GridInfotaxis":
        """Estimator on any object with ``.occupancy``, ``.resolution``, ``.origin`` (e.g. ``sim.GridMap``).

        ``wind`` is the (H, W, 2) wind field in m/s; remaining keywords as in the constructor.
        """
        opts = {k: kwargs.pop(k) for k in ("tempering", "false_hit_rate") if k in kwargs}
        model = PlumeModel.from_grid_map(grid_map, wind, outlets=outlets, **kwargs)
        return cls.from_model(model, prior=prior, **opts)

    def _configure(self, tempering, false_hit_rate) -> None:
        self.tempering = unit_interval(tempering, "tempering", low_open=True, high_open=False)
        self.false_hit_rate = unit_interval(false_hit_rate, "false_hit_rate", low_open=False, high_open=True)

    # --- likelihood -----------------------------------------------------------------------------------------
    def log_likelihood(self, position, hit) -> np.ndarray:
        """log P(g | s) of one reading for every candidate source s (untempered), shape (H, W).

        Parameters
        ----------
        position : (2,) array_like of float
            Sensor (x, y) in metres.
        hit : bool
            The reading.

        Returns
        -------
        loglik : (H, W) ndarray of float64
            May be −inf (hit with ε = 0 where G = 0); never NaN.
        """
        r, c = self.model.cell_of(position)
        flat = r * self.geometry.shape[1] + c
        return self._log_likelihood_flat(flat, bool(hit)).reshape(self.geometry.shape)

    def _log_likelihood_flat(self, flat_cell: int, hit: bool) -> np.ndarray:
        mu = self.model.encounter_scale * self.model.green_rows([flat_cell])[0]  # expected encounters κ G(x|s)
        eps = self.false_hit_rate
        if hit:
            with np.errstate(divide="ignore"):  # ε = 0 and G = 0 -> log 0 = −inf, intended
                return np.log(-np.expm1(-mu) + eps * np.exp(-mu))  # log[ε + (1−ε)(1 − e^{−κG})]
        return np.log1p(-eps) - mu  # log[(1−ε) e^{−κG}]

    def _hit_likelihood_rows(self, flat_cells: np.ndarray) -> np.ndarray:
        p = -np.expm1(-self.model.encounter_scale * self.model.green_rows(flat_cells))
        return self.false_hit_rate + (1.0 - self.false_hit_rate) * p  # P(hit | s) with false hits

    # --- state ----------------------------------------------------------------------------------------------
    def _reset_state(self) -> None:
        self._loglik = np.zeros(self.geometry.shape[0] * self.geometry.shape[1])

    def _propose(self, obs: Observation):
        r, c = obs.cell
        ell = self._log_likelihood_flat(r * self.geometry.shape[1] + c, obs.hit)
        loglik = self._loglik + self.tempering * ell  # β Σ_k log P(g_k | s)
        return self._log_prior + loglik, loglik

    def _accept(self, obs: Observation, payload) -> None:
        self._loglik = payload

    @property
    def log_likelihood_total(self) -> np.ndarray:
        """(H, W) accumulated tempered log-likelihood β Σ_k log P(g_k | s)."""
        return self._loglik.reshape(self.geometry.shape).copy()
