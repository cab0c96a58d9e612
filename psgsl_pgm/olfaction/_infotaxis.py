"""Grid Infotaxis: Bayesian hit/miss source posterior from the grid plume model (Vergassola et al. 2007)."""

from __future__ import annotations

import numpy as np
from scipy.special import entr

from .._shared._validate import as_float_array, describe, unit_interval
from ..kernels._logsumexp import logsumexp
from ._base import Observation, OlfactoryEstimator
from ._plume import PlumeModel

__all__ = ["GridInfotaxis"]


def _parameter_grid(grid) -> np.ndarray:
    """``parameter_grid`` as a read-only (J, 4) float64 array of rows (D, τ, κ, weight), weights normalised."""
    g = as_float_array(grid, "parameter_grid", dtype=np.float64)
    if g.ndim != 2 or g.shape[1] != 4 or g.shape[0] < 1:
        raise ValueError(f"parameter_grid must be (J, 4) rows (diffusivity, lifetime, encounter_scale, weight) with "
                         f"J >= 1, got {describe(g)}")
    g = g.astype(np.float64)
    if not np.isfinite(g).all() or (g[:, :3] <= 0).any() or (g[:, 3] < 0).any() or not g[:, 3].sum() > 0:
        raise ValueError("parameter_grid must hold positive finite (diffusivity, lifetime, encounter_scale) and "
                         "non-negative weights with a positive sum")
    g[:, 3] /= g[:, 3].sum()
    g.flags.writeable = False
    return g


class GridInfotaxis(OlfactoryEstimator):
    r"""Infotaxis posterior :math:`p(s \mid g)` with the likelihood of a grid advection-diffusion plume.

    Each reading at sensor cell x multiplies the posterior by the likelihood of every candidate source s,

    .. math::

        P(\text{hit} \mid s) = \varepsilon + (1 - \varepsilon)(1 - \delta)\big(1 - e^{-\kappa G(x \mid s)}\big)

        P(\text{miss} \mid s) = (1 - \varepsilon)\big[\delta + (1 - \delta)\, e^{-\kappa G(x \mid s)}\big]

    i.e. Poisson encounters with mean :math:`\kappa G(x \mid s)` in one sample (Vergassola et al. 2007: encounter rate
    :math:`R(r \mid r_0) \propto c(r \mid r_0)`), with G the adjoint Green's function of :class:`PlumeModel` (walls
    no-flux, outlets absorbing, the map's wind field), a false-hit probability ε (sensor noise, and model mismatch:
    without it one hit where the model predicts G = 0 for the true source — e.g. a gust through a door the mean flow
    does not carry — would exclude the true source for ever) and a missed-hit probability δ, its mirror image: with
    probability δ the plume of this reading is not where the mean flow puts it (a gust that carries it away, a wind
    estimate that is wrong here), and only a false hit can register. Without δ one reading without a hit where the model
    predicts κG ≫ 1 costs the true source κG nats; with δ a miss costs at most −log δ. δ = 0 (the default) is the model
    without it, bit for bit. The log-likelihoods are accumulated,

    .. math:: \log p(s \mid g_{1:n}) = \log p(s) + \beta \sum_k \log P(g_k \mid s) - \log Z,

    and normalised with ``logsumexp``.

    **Tempering (β).** The product over readings assumes they are independent given s. Hits from one real
    (or filament-simulated) plume are not: the model's P(hit | s) is the *ensemble* mean over plume
    realisations, while consecutive stops of one robot sample the *same* meandering plume, whose intermittent
    puffs are correlated over seconds and over the plume width. A run of n correlated readings carries the
    information of n_eff < n independent ones, so the naive product is over-confident — it collapses onto
    one cell long before the evidence supports that, and a collapsed p(s | g) would veto the semantic factor
    p(s | z) in eq. (11). We use the power (tempered / "coarsened") likelihood, raising
    each factor to β = n_eff / n ∈ (0, 1] (Grünwald's "safe Bayes"; Miller & Dunson 2019, JASA 114, 1113), so
    that the posterior contracts as if only βn readings were independent. The default β = 0.5 assumes each
    reading shares roughly half of its information with its neighbours along the path (stops about one plume
    correlation length apart); estimate it from data instead where there are readings around known sources:
    :func:`ar1_tempering` turns the lag-1 autocorrelation ρ of the hit model's residuals into
    :math:`\beta = (1 - \rho)/(1 + \rho)` (the validation experiment does so on its calibration runs); β = 1
    recovers Vergassola's exact update and is right for readings that are independent draws from the model
    (as in the tests). The estimator is further meant to be called once per
    stop (one reading per stop — several readings at one stop sample the same puffs): that convention, not
    β, removes the strongest correlation, so β need not be tiny. The estimator is deterministic (no random
    numbers); synthetic readings come from :meth:`PlumeModel.sample_hits` with an explicit seed.

    **Plume parameters marginalised (``parameter_grid``).** One (D, τ, κ) for every run and every place is a
    point estimate of something that varies: fitted run by run on calibration tours, the maximum-likelihood
    diffusivity of a source in the fast flow of a corridor is a third of that of a source in a room (the plume
    there stays narrow), and κ̂ varies fourfold between runs. A point estimate that is wrong for *this* run
    makes every reading a little more surprising under the true source than under a cell beside it, and the
    posterior settles, confidently, beside the source. With a grid :math:`\theta_j = (D_j, \tau_j, \kappa_j)`
    and prior weights :math:`\pi_j` (the population distribution of θ over calibration runs,
    :func:`mixture_weights`) the posterior is the Bayesian model average with θ a run-level unknown,

    .. math:: p(s \mid g_{1:n}) \propto p(s) \sum_j \pi_j \prod_k P_{\theta_j}(g_k \mid s)^\beta,

    i.e. the posterior over θ is updated online, jointly with s (:math:`p(\theta_j \mid s, g) \propto \pi_j \prod_k
    P_{\theta_j}(g_k \mid s)^\beta`), and the readings decide which plume this run has. It is exact (a log-sum-exp over
    j of the accumulated per-component log-likelihoods); it costs one plume factorisation and one adjoint solve per
    reading per distinct (D, τ) of the grid (κ is free: it only scales G). Without a grid the model's own (D, τ, κ) is
    the single component, and the update is the one above. For planning, :meth:`hit_probability` and
    :meth:`information_gain` use the prior predictive :math:`\sum_j \pi_j P_{\theta_j}(\text{hit} \mid s)` — fixed for a
    plume model, so the closed loop's per-cell cache of hit rows stays valid — not the run's posterior over θ.

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
        Prior :math:`p(s)`; uniform over free cells by default.
    tempering : float, default 0.5
        β ∈ (0, 1], exponent of every reading's likelihood (see above).
    false_hit_rate : float, default 0.01
        ε ∈ [0, 1): probability of a hit whatever the source. With ε = 0 a hit that no candidate can explain
        raises ValueError.
    missed_hit_rate : float, default 0.0
        δ ∈ [0, 1): probability that a reading misses the plume whatever the model predicts (see above); fitted
        with the plume parameters by :func:`fit_plume_parameters` (``fit_missed_hits=True``).
    parameter_grid : (J, 4) array_like of float, optional
        Rows (D m²/s, τ s, κ m²/s, prior weight π_j ≥ 0) of the plume parameters to marginalise over (see
        above; weights are normalised). ``None``: the single component (D, τ, κ) of the plume model. The
        model passed in gives the map, the wind and the outlets; a row with its (D, τ) shares its Green's
        functions.
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
        missed_hit_rate: float = 0.0,
        parameter_grid=None,
        **plume,
    ):
        model = PlumeModel(occupancy, resolution=resolution, origin=origin, wind=wind, outlets=outlets, **plume)
        self._configure(tempering, false_hit_rate, parameter_grid, missed_hit_rate)
        super().__init__(model, prior=prior)

    @classmethod
    def from_model(
        cls, model: PlumeModel, *, prior=None, tempering: float = 0.5, false_hit_rate: float = 0.01,
        missed_hit_rate: float = 0.0, parameter_grid=None,
    ) -> "GridInfotaxis":
        """Estimator on an existing :class:`PlumeModel` (shares its factorisation and Green's-function cache)."""
        self = cls.__new__(cls)
        self._configure(tempering, false_hit_rate, parameter_grid, missed_hit_rate)
        OlfactoryEstimator.__init__(self, model, prior=prior)
        return self

    @classmethod
    def from_grid_map(cls, grid_map, wind=None, *, outlets=None, prior=None, **kwargs) -> "GridInfotaxis":
        """Estimator on any object with ``.occupancy``, ``.resolution``, ``.origin`` (e.g. ``sim.GridMap``).

        ``wind`` is the (H, W, 2) wind field in m/s; remaining keywords as in the constructor.
        """
        opts = {k: kwargs.pop(k) for k in ("tempering", "false_hit_rate", "missed_hit_rate", "parameter_grid")
                if k in kwargs}
        model = PlumeModel.from_grid_map(grid_map, wind, outlets=outlets, **kwargs)
        return cls.from_model(model, prior=prior, **opts)

    def _configure(self, tempering, false_hit_rate, parameter_grid=None, missed_hit_rate=0.0) -> None:
        self.tempering = unit_interval(tempering, "tempering", low_open=True, high_open=False)
        self.false_hit_rate = unit_interval(false_hit_rate, "false_hit_rate", low_open=False, high_open=True)
        self.missed_hit_rate = unit_interval(missed_hit_rate, "missed_hit_rate", low_open=False, high_open=True)
        self.parameter_grid = None if parameter_grid is None else _parameter_grid(parameter_grid)
        self._components_of = None  # the plume model the components were built on

    def _build_components(self) -> None:
        """One plume model per distinct (D, τ) of the grid on the current model's map and wind (the model itself
        where they coincide), and per component j its model, κ_j and log π_j."""
        base = self.model
        if self.parameter_grid is None:
            models, index = [base], [0]
            kappa, log_w = np.array([base.encounter_scale]), np.zeros(1)
        else:
            g = self.parameter_grid
            models, index, where = [], [], {}
            for d, tau in g[:, :2]:
                key = (float(d), float(tau))
                if key not in where:
                    where[key] = len(models)
                    models.append(base if key == (base.diffusivity, base.lifetime) else PlumeModel(
                        base.geometry.occupancy, resolution=base.geometry.resolution, origin=base.geometry.origin,
                        wind=base.wind, outlets=base.outlets, diffusivity=key[0], lifetime=key[1],
                        encounter_scale=base.encounter_scale, boundary=base.boundary, scheme=base.scheme,
                        cache_size=base.cache_size))
                index.append(where[key])
            kappa = g[:, 2].copy()
            with np.errstate(divide="ignore"):  # a zero weight: log 0 = −inf, that component never counts
                log_w = np.log(g[:, 3])
        self._models = models
        self._component_model = np.array(index, dtype=np.int64)
        self._kappa = kappa
        self._log_weights = log_w
        self._components_of = base

    def _component_rows(self, flat_cells) -> np.ndarray:
        """(J, K, H·W) κ_j G_j(x_k | s) of every component j for sensor cells x_k."""
        rows = np.stack([m.green_rows(flat_cells) for m in self._models])  # (M, K, H·W)
        out = rows[self._component_model]  # (J, K, H·W), a new array
        out *= self._kappa[:, None, None]
        return out

    def _mix(self, loglik: np.ndarray) -> np.ndarray:
        """log Σ_j π_j exp(L_j(s)) of per-component log-likelihoods (J, H·W); L_0 itself for one component."""
        if loglik.shape[0] == 1:
            return loglik[0]
        with np.errstate(divide="ignore"):
            return logsumexp(self._log_weights[:, None] + loglik, axis=0)

    @property
    def n_components(self) -> int:
        """J, the number of (D, τ, κ) components marginalised over (1 without a ``parameter_grid``)."""
        return 1 if self.parameter_grid is None else self.parameter_grid.shape[0]

    @property
    def plume_models(self) -> tuple:
        """The plume models of the distinct (D, τ) of the grid (the estimator's model first if it is one)."""
        return tuple(self._models)

    def parameter_posterior(self) -> np.ndarray:
        """(J,) p(θ_j | g) = Σ_s p(s | g) p(θ_j | s, g), the posterior over the grid's components (sums to 1)."""
        if self.n_components == 1:
            return np.ones(1)
        a = self._log_weights[:, None] + self._loglik
        with np.errstate(divide="ignore", invalid="ignore"):
            resp = np.exp(a - logsumexp(a, axis=0))  # p(θ_j | s, g)
        resp = np.where(np.isfinite(resp), resp, 0.0)
        return resp @ self._post

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
            May be −inf (hit with ε = 0 where G = 0); never NaN. With a ``parameter_grid``, the predictive
            log Σ_j p(θ_j | s, g) P_θj(g | s) given the readings so far.
        """
        r, c = self.model.cell_of(position)
        flat = r * self.geometry.shape[1] + c
        ell = self._log_likelihood_flat(flat, bool(hit))
        if ell.shape[0] > 1:  # weights p(θ_j | s, g) ∝ π_j exp(L_j(s))
            a = self._log_weights[:, None] + self._loglik
            with np.errstate(divide="ignore", invalid="ignore"):
                ell = logsumexp(a + ell, axis=0) - logsumexp(a, axis=0)
            ell = np.where(np.isnan(ell), -np.inf, ell)  # a cell no component allows
        else:
            ell = ell[0]
        return ell.reshape(self.geometry.shape)

    def _log_likelihood_flat(self, flat_cell: int, hit: bool) -> np.ndarray:
        """(J, H·W) log P_θj(g | s) of one reading at ``flat_cell`` for every component j and source s."""
        mu = self._component_rows([flat_cell])[:, 0]  # expected encounters κ_j G_j(x|s)
        eps, delta = self.false_hit_rate, self.missed_hit_rate
        if delta == 0.0:
            if hit:
                with np.errstate(divide="ignore"):  # ε = 0 and G = 0 -> log 0 = −inf, intended
                    return np.log(-np.expm1(-mu) + eps * np.exp(-mu))  # log[ε + (1−ε)(1 − e^{−κG})]
            return np.log1p(-eps) - mu  # log[(1−ε) e^{−κG}]
        if hit:
            with np.errstate(divide="ignore"):  # log[ε + (1−ε)(1−δ)(1 − e^{−κG})]
                return np.log(eps + (1.0 - eps) * (1.0 - delta) * -np.expm1(-mu))
        # log[(1−ε)(δ + (1−δ)e^{−κG})], never below log(1−ε) + log δ
        return np.log1p(-eps) + np.logaddexp(np.log(delta), np.log1p(-delta) - mu)

    def _hit_likelihood_rows(self, flat_cells: np.ndarray) -> np.ndarray:
        # P_θj(hit | s) = ε + (1 − ε)((1 − δ)(1 − e^{−κG})), each step in place on the new (J, K, H·W) array
        p = self._component_rows(flat_cells)
        np.negative(p, out=p)
        np.expm1(p, out=p)
        np.negative(p, out=p)
        p *= 1.0 - self.missed_hit_rate
        p *= 1.0 - self.false_hit_rate
        p += self.false_hit_rate
        if p.shape[0] == 1:
            return p[0]
        return np.tensordot(np.exp(self._log_weights), p, axes=1)  # prior predictive Σ_j π_j P_θj(hit | s)

    def information_gain_bound(self, posterior) -> np.ndarray:
        r"""An upper bound of :meth:`information_gain` at every cell x at once, with no row of the plume operator's
        inverse.

        A reading's hit is the gas's own hit (probability :math:`r_x(s) = (1 - \delta) \sum_j \pi_j
        (1 - e^{-\kappa_j G_j(x \mid s)})` for a source s) or a false hit (ε, whatever the source), so the
        predictive of :meth:`hit_probability` is :math:`P_x(s) = f(r_x(s))`, :math:`f(r) = \varepsilon +
        (1 - \varepsilon) r`. With :math:`h(r) = H_b(f(r))` concave, :math:`h(r) \ge (1 - r)\, h(0) + r\, h(1)`
        on [0, 1] and :math:`h(1) = 0`, so

        .. math:: I(S; \text{hit}_x) = h(\bar r_x) - \sum_s p(s)\, h(r_x(s)) \le g(\bar r_x) = h(\bar r_x) -
                  (1 - \bar r_x)\, H_b(\varepsilon), \qquad \bar r_x = \sum_s p(s)\, r_x(s),

        and g is concave with its maximum at :math:`r^\ast`, :math:`f(r^\ast) = 1 / (1 + e^{-H_b(\varepsilon) /
        (1 - \varepsilon)})` (½ for ε = 0). The mean :math:`\bar r_x` is bounded by Jensen's inequality
        (:math:`1 - e^{-\kappa G}` is concave in G),

        .. math:: \bar r_x \le U_x = (1 - \delta) \sum_j \pi_j \big(1 - e^{-\kappa_j \bar c_j(x)}\big),
                  \qquad \bar c_j(x) = \sum_s p(s)\, G_j(x \mid s),

        one forward solve per plume model for every x (:meth:`PlumeModel.mean_concentration`), where the exact
        gain takes one adjoint solve per x. The bound is :math:`g(\min(U_x, r^\ast))`, U raised by 1e-6 of itself
        and the bound by 1e-9, far above the rounding of the forward solve against the rows (≲ 1e-12 relative).

        Parameters
        ----------
        posterior : (H, W) array_like of float
            The distribution p(s) to average over (non-negative, summing to 1).

        Returns
        -------
        bound : (H, W) ndarray of float64
            Nats; ≥ :meth:`information_gain` with the same ``posterior`` at every free cell.

        Raises
        ------
        ValueError
            If ``posterior`` is not (H, W), or not a distribution (finite, non-negative, summing to 1).

        Examples
        --------
        >>> import numpy as np
        >>> est = GridInfotaxis(np.zeros((6, 8), bool), resolution=0.25, wind=np.full((6, 8, 2), (0.2, 0.0)))
        >>> p = est.update((0.6, 0.9), True)
        >>> gain = est.information_gain(est.geometry.cell_centres().reshape(-1, 2), posterior=p)
        >>> bool(np.all(gain <= est.information_gain_bound(p).ravel()))
        True
        """
        if self._components_of is not self.model:
            self._build_components()
        post = self._distribution(posterior)  # Jensen and the chord need Σ p = 1
        c = np.stack([m.mean_concentration(post).ravel() for m in self._models])[self._component_model]  # c̄_j
        u = np.exp(self._log_weights) @ -np.expm1(-self._kappa[:, None] * c)  # Σ_j π_j (1 − e^{−κ_j c̄_j})
        u *= (1.0 - self.missed_hit_rate) * (1.0 + 1e-6)  # U ≥ r̄
        eps = self.false_hit_rate
        h0 = float(entr(eps) + entr(1.0 - eps))  # h(0) = H_b(ε)
        r_star = (1.0 / (1.0 + np.exp(-h0 / (1.0 - eps))) - eps) / (1.0 - eps)
        r = np.minimum(u, r_star)
        q = eps + (1.0 - eps) * r  # f(r)
        bound = entr(q) + entr(1.0 - q) - (1.0 - r) * h0 + 1e-9  # g(min(U, r*))
        return np.maximum(bound, 0.0).reshape(self.geometry.shape)

    # --- state ----------------------------------------------------------------------------------------------
    def _reset_state(self) -> None:
        if self._components_of is not self.model:  # first use, or a re-solved model (replace_model)
            self._build_components()
        self._loglik = np.zeros((len(self._kappa), self.geometry.shape[0] * self.geometry.shape[1]))

    def _propose(self, obs: Observation):
        r, c = obs.cell
        ell = self._log_likelihood_flat(r * self.geometry.shape[1] + c, obs.hit)
        loglik = self._loglik + self.tempering * ell  # β Σ_k log P_θj(g_k | s), per component
        return self._mix(loglik), loglik

    def _accept(self, obs: Observation, payload) -> None:
        self._loglik = payload

    @property
    def log_likelihood_total(self) -> np.ndarray:
        """(H, W) accumulated tempered log-likelihood β Σ_k log P(g_k | s); with a ``parameter_grid`` the
        marginal log Σ_j π_j Π_k P_θj(g_k | s)^β."""
        return self._mix(self._loglik).reshape(self.geometry.shape).copy()
