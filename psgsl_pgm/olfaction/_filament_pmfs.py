"""PMFS as published: a probabilistic hit map from the readings against hit maps simulated with filaments.

Ojeda, Monroy & Gonzalez-Jimenez, "Robotic Gas Source Localization with Probabilistic Mapping and Online
Dispersion Simulation", IEEE Transactions on Robotics 40, 2024 (arXiv:2304.08879); the ``PMFS`` algorithm of
MAPIRlab/GasSourceLocalization.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import dijkstra
from scipy.special import expit

from .._shared._validate import index, positive, unit_interval
from ._base import Observation, OlfactoryEstimator, _check_model
from ._gmrf_wind import GMRFWind
from ._hitmap import HitProbabilityMap
from ._plume import PlumeModel

__all__ = ["FilamentPMFS"]


def _logit(p):
    return np.log(p) - np.log1p(-p)


class FilamentPMFS(OlfactoryEstimator):
    r"""PMFS (probabilistic mapping from simulation): the source posterior :math:`p(s \mid g)` over the map's cells.

    Three parts, as in the paper (Sec. III-V of Ojeda et al. 2024):

    1. **Wind map.** Every anemometer reading enters a GMRF over the free cells (:class:`GMRFWind`); its MAP
       estimate û is the wind the simulations use. The simulator's wind is never read.
    2. **Measured hit map.** Per cell c a binary Bayes filter of "a reading here is a hit" in log-odds, with
       PMFS's kernel: a reading at cell r updates ℓ_c += logit(clamp(lerp(p0, v, w_r(c)))) − logit(p0), with
       v = 0.6 after a hit and v = 0.05 after a miss (PMFS's ``HitProbKernel`` uses v = p0 after a miss, so that a
       miss only raises the confidence and ĥ, once raised by hits nearby, never falls: upwind of the source the
       kernel's reach then outvotes the misses), w_r(c) ∈ [0, 1] the anisotropic Gaussian stretched along the measured
       wind and evaluated at the geodesic displacement (:meth:`HitProbabilityMap.kernel`; semi-axes σ + k‖w‖
       and σ / (1 + k‖w‖/σ)) and clamp to [0.001, 0.999]. :math:`\hat h_c = \sigma(\ell_c)`. Confidence:
       :math:`\omega_c \mathrel{+}= e^{-d_{rc}^2 / (2 \sigma_\omega^2)}`, :math:`d_{rc}` the geodesic distance,
       :math:`\mathrm{conf}_c = 1 - e^{-\omega_c / m^2}`.
    3. **Simulated hit maps and the update.** The free cells are split into square candidate regions of side
       ``region_size``; at each refresh every region with prior mass is simulated, and then, as PMFS refines its
       quadtree, the best ``refine_fraction`` of them by the score below are split into four children of half
       the side, which are simulated and replace their parent. From the free cell nearest each region's
       centre, filaments are released on û (``filaments_per_step`` per step of dt, moved by the local wind plus
       Gaussian noise of std sqrt(2 D dt) per axis — D the robot's calibrated diffusivity of its plume model —,
       a move into a wall skipped, outlets and the border removing; the project's compiled filament step,
       :mod:`psgsl_pgm.kernels._filaments`). After ``warmup_steps`` steps, ``record_steps`` more are recorded:
       :math:`h_c(k)` is the fraction of them in which the block of side ``hit_block`` holding c held a
       filament. Then (PMFS's ``weightedDifference``)

       .. math:: p(s \mid g) \propto p(s) \prod_c \big[1 - \mathrm{conf}_c
                 + \mathrm{conf}_c \big(1 - \gamma\, |\hat h_c - h_c(k(s))|\big)\big]^\lambda

       with k(s) the region of s, γ = ``discrimination`` (PMFS's ``sourceDiscriminationPower``, 1) and λ = ``tempering``
       (1: PMFS itself). The product runs over the cells with positive confidence. Every factor is
       :math:`\ge 1 - \mathrm{conf}_c > 0`, so no cell vetoes a source; like PMFS the posterior is recomputed from the
       hit map after each reading, not multiplied up.

    The simulations are refreshed on the current wind estimate at the first reading and then every
    ``refresh`` readings (PMFS's ``stepsSourceUpdate`` = 10); between refreshes a reading only updates the
    hit map and the score. Regions with zero prior mass are not simulated. Costs (the embedded house,
    0.1 m cells, 120 regions of 1 m, one core of a 2-core AMD EPYC): a refresh with the defaults ≈ 0.8 s
    (about 5.5 ms per simulated region, 200 steps of up to 400 filaments, plus the refined children), a reading
    between refreshes a few milliseconds (one Dijkstra of the kernel's reach and a K × N' score, N' the
    confident cells). The cost of a refresh grows with filaments_per_step × (warmup_steps + record_steps)² per
    region in a house without outlets (the filaments stay): PMFS's own 5 filaments per step and 150 + 200 steps
    on 480 regions of 0.5 m take ≈ 22 s.
    ``hit_probability`` and ``information_gain`` predict a reading by the simulated hit maps,
    :math:`P(\text{hit at } x \mid s) = h_x(k(s))`, once simulated (before that by the plume model).

    A property of the published hit map worth knowing: the log-odds filter saturates (ĥ → 1 wherever several
    hits overlap) and the kernel spreads a hit upwind as far as downwind, so with stops denser than the kernel's
    reach close to the source, ĥ upwind of the source rises and sources upwind of the true one fit better (in a
    corridor with stops 0.3 m apart the posterior sits one region upwind; 0.5 m apart it holds the source's
    region, ``tests/olfaction/test_olfaction_field_methods.py``).

    Deviations from the published code, and why: a lattice of square regions refined once instead of a
    quadtree refined until its leaves are single cells (bounded cost in the closed loop); filaments released at
    one point per region instead of uniformly
    over it (the compiled step has one release point); the confidence's spatial weight unnormalised, in metres
    (PMFS's Gaussian density in cells).

    Parameters
    ----------
    model : PlumeModel
        The robot's map (occupancy, outlets) and its calibrated diffusivity D (m²/s); its wind is not used.
    prior : (H, W) array_like, optional, keyword-only
        p(s); uniform over free cells by default.
    seed : int, default 0, keyword-only
        Seeds the simulations (refresh i draws from ``SeedSequence([seed, i])``).
    region_size : float, default 1.0, keyword-only
        Side of the candidate regions, m (rounded to an even number of cells).
    refine_fraction : float, default 0.1, keyword-only
        Fraction of the regions (by score) split into four and simulated again at each refresh (0: none).
    hit_block : float, default 0.3, keyword-only
        Side of the blocks on which simulated filaments count as a hit, m (the sensor's reach).
    dt : float, default 0.2, keyword-only
        Simulation step, s (PMFS's ``deltaTime``).
    warmup_steps, record_steps : int, default 100, 100, keyword-only
        Steps before recording and recorded steps (PMFS: at most 500 warm-up, ``iterationsToRecord`` 200).
    filaments_per_step : int, default 2, keyword-only
        Filaments released per step (PMFS: 5).
    diffusivity : float, optional, keyword-only
        D in m²/s for the filaments' noise; default the model's.
    refresh : int, default 10, keyword-only
        Readings between simulation refreshes.
    discrimination : float, default 1.0, keyword-only
        γ ∈ (0, 1].
    tempering : float, default 1.0, keyword-only
        λ > 0.
    prior_hit : float, default 0.1, keyword-only
        p0 (PMFS's ``hitPriorProbability``).
    hit_value : float, default 0.6, keyword-only
        v after a hit at the kernel's centre.
    miss_value : float, default 0.05, keyword-only
        v after a miss at the kernel's centre (``prior_hit``: PMFS's code).
    kernel_sigma, kernel_stretch : float, default 0.2, 0.5, keyword-only
        σ (m) and k (s) of the hit kernel (PMFS's ``kernel_sigma``, ``kernel_stretch_constant``, there in its
        map cells).
    confidence_sigma, confidence_weight : float, default 0.15, 0.5, keyword-only
        σ_ω (m) and m of the confidence (PMFS's ``confidence_sigma_spatial`` = 0.5 of its cells, here 0.5 of a
        0.3 m hit block, and ``confidence_measurement_weight``). On the calibration runs of the house (never
        evaluated) σ_ω = 0.5 m, the value read as metres, gives a MAP error of 2.8-4.6 m on four runs; 0.15 m
        gives 0.75-3.3 m (the analytic-plume estimator: 0.5-1.8 m).
    wind : dict, optional, keyword-only
        Options of :class:`GMRFWind`.

    Examples
    --------
    >>> import numpy as np
    >>> occ = np.zeros((10, 30), bool)
    >>> model = PlumeModel(occ, resolution=0.2, boundary="open")
    >>> est = FilamentPMFS(model, region_size=0.6, seed=3)
    >>> _ = est.update((1.0, 1.0), False, wind=(0.5, 0.0))
    >>> p = est.update((3.0, 1.0), True, wind=(0.5, 0.0))
    >>> bool(abs(p.sum() - 1) < 1e-12), est.n_simulations > 0
    (True, True)
    """

    def __init__(self, model: PlumeModel, *, prior=None, seed: int = 0, region_size: float = 1.0,
                 refine_fraction: float = 0.1, hit_block: float = 0.3, dt: float = 0.2, warmup_steps: int = 100,
                 record_steps: int = 100, filaments_per_step: int = 2, diffusivity: float | None = None,
                 refresh: int = 10,
                 discrimination: float = 1.0, tempering: float = 1.0, prior_hit: float = 0.1,
                 hit_value: float = 0.6, miss_value: float = 0.05, kernel_sigma: float = 0.2,
                 kernel_stretch: float = 0.5, confidence_sigma: float = 0.15, confidence_weight: float = 0.5,
                 wind: dict | None = None):
        _check_model(model)
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
            raise TypeError(f"seed must be an integer, got {seed!r}")
        self.seed = int(seed)
        res = model.geometry.resolution
        self.region_size = positive(region_size, "region_size", "m")
        self.refine_fraction = unit_interval(refine_fraction, "refine_fraction")
        self.hit_block = positive(hit_block, "hit_block", "m")
        self.dt = positive(dt, "dt", "s")
        self.warmup_steps = index(warmup_steps, "warmup_steps")
        self.record_steps = index(record_steps, "record_steps", minimum=1)
        self.filaments_per_step = index(filaments_per_step, "filaments_per_step", minimum=1)
        self.diffusivity = model.diffusivity if diffusivity is None else positive(diffusivity, "diffusivity", "m²/s")
        self.refresh = index(refresh, "refresh", minimum=1)
        self.discrimination = unit_interval(discrimination, "discrimination", low_open=True)
        self.tempering = positive(tempering, "tempering")
        self.prior_hit = unit_interval(prior_hit, "prior_hit", low_open=True, high_open=True)
        self.hit_value = unit_interval(hit_value, "hit_value", low_open=True, high_open=True)
        self.miss_value = unit_interval(miss_value, "miss_value", low_open=True, high_open=True)
        self.confidence_sigma = positive(confidence_sigma, "confidence_sigma", "m")
        self.confidence_weight = positive(confidence_weight, "confidence_weight")
        self._kernel = HitProbabilityMap(model.geometry, prior_hit=self.prior_hit, kernel_sigma=kernel_sigma,
                                         kernel_stretch=kernel_stretch)
        self._wind = GMRFWind(model.geometry, **(wind or {}))
        geo = model.geometry
        h, w = geo.shape
        rows, cols = np.indices((h, w))
        free = geo.free.ravel()
        centres = geo.cell_centres().reshape(-1, 2)

        def lattice(side_cells):
            """(region of each free cell (dense), release cell of each region) of squares of ``side_cells``."""
            lab = ((rows // side_cells) * (-(-w // side_cells)) + cols // side_cells).ravel()[free]
            _, dense = np.unique(lab, return_inverse=True)
            flat_free = np.flatnonzero(free)
            release = np.empty(dense.max() + 1 if dense.size else 0, np.int64)
            for k in range(release.size):
                cells = flat_free[dense == k]
                m = centres[cells].mean(axis=0)
                release[k] = cells[np.argmin(((centres[cells] - m) ** 2).sum(axis=1))]
            return dense, release

        rs = 2 * max(int(round(self.region_size / res / 2)), 1)  # even: the children tile their parent
        self._coarse, self._coarse_release = lattice(rs)  # PMFS's first level
        self._fine, self._fine_release = lattice(max(rs // 2, 1))  # its children (each inside one coarse region)
        self.n_regions = self._coarse_release.size
        hb = max(int(round(self.hit_block / res)), 1)
        block = ((rows // hb) * (-(-w // hb)) + cols // hb).ravel()
        ub, binv = np.unique(block, return_inverse=True)
        self._block = binv.astype(np.int64)
        self._n_blocks = ub.size
        self._graph = geo.free_space_graph()
        super().__init__(model, prior=prior)

    @classmethod
    def from_model(cls, model: PlumeModel, **options) -> "FilamentPMFS":
        """The estimator on ``model`` (the same as the constructor; for symmetry with the other estimators)."""
        return cls(model, **options)

    def replace_model(self, model: PlumeModel) -> np.ndarray:
        """Take a plume model of the same map (e.g. one solved on a refreshed mean-wind estimate) without
        re-assimilating the readings: this estimator's update does not use the model's wind (it keeps its own GMRF
        wind map; its diffusivity was fixed at construction)."""
        self._adopt_model(model)
        return self.posterior

    # --- state ----------------------------------------------------------------------------------------------
    def _reset_state(self) -> None:
        n = self.geometry.shape[0] * self.geometry.shape[1]
        self._wind.reset()
        self._log_odds = np.zeros(n)  # ℓ_c − logit(p0)
        self._omega = np.zeros(n)
        self._sim = None  # (K', n_blocks) simulated hit frequencies of the regions of the last refresh
        self._assign = None  # (n_free,) row of _sim of each free cell's region
        self._n_refresh = 0
        self.n_simulations = 0
        self._terms = None  # _ScoreTerms of the current simulations (the score's per-cell terms, kept)

    def _simulate(self, wind_field: np.ndarray, release: np.ndarray, rng) -> np.ndarray:
        """(len(release), n_blocks) hit frequencies of filaments released at the flat cells ``release`` on
        ``wind_field`` (H, W, 2)."""
        from ..kernels._pmfs_sim import record_hits

        geo = self.geometry
        h, w = geo.shape
        ox, oy = (float(v) for v in geo.origin)
        vel = np.ascontiguousarray(wind_field.reshape(-1, 2))
        walls = np.ascontiguousarray(geo.occupancy.ravel())
        stays = np.pad(~self.model.outlets, 1).ravel()
        centres = self._centres
        cap = self.filaments_per_step * (self.warmup_steps + self.record_steps) + 2
        noise = float(np.sqrt(2.0 * self.diffusivity * self.dt))
        sim = np.zeros((len(release), self._n_blocks))
        for k, cell in enumerate(np.asarray(release, np.int64).tolist()):
            pos, births, cells = np.empty((cap, 2)), np.empty(cap), np.empty((cap, 2), np.int64)
            counts = record_hits(rng, self.warmup_steps, self.record_steps, pos, births, cells, vel, self.dt,
                                 self.filaments_per_step / self.dt, noise, float(centres[cell, 0]),
                                 float(centres[cell, 1]), cell // w, cell % w, walls, stays, h, w, ox, oy,
                                 float(geo.resolution), self._block, self._n_blocks)
            sim[k] = counts / self.record_steps
            self.n_simulations += 1
        return sim

    def _refresh(self, wind_field: np.ndarray, log_odds: np.ndarray, omega: np.ndarray):
        """PMFS's two-level simulation: every coarse region with prior mass, then the children of the best
        ``refine_fraction`` of them by score. Returns ``(sim (K', n_blocks), region of each free cell (n_free,))``."""
        rng = np.random.default_rng(np.random.SeedSequence([self.seed, self._n_refresh]))
        mass = np.isfinite(self._log_prior[self.geometry.free.ravel()])
        coarse = np.unique(self._coarse[mass])  # coarse regions with prior mass
        sim = np.zeros((self.n_regions, self._n_blocks))
        sim[coarse] = self._simulate(wind_field, self._coarse_release[coarse], rng)
        assign = self._coarse.copy()
        n_refine = int(np.ceil(self.refine_fraction * coarse.size))
        if n_refine:
            score = self._score(sim[coarse], assign, log_odds, omega)
            best = coarse[np.argsort(-score, kind="stable")[:n_refine]]
            cells = np.isin(self._coarse, best) & mass
            children = np.unique(self._fine[cells])
            sim_child = self._simulate(wind_field, self._fine_release[children], rng)
            slot = np.full(self._fine_release.size, -1, np.int64)
            slot[children] = self.n_regions + np.arange(children.size)
            assign[cells] = slot[self._fine[cells]]
            sim = np.concatenate([sim, sim_child])
        return sim, assign

    def _measurement(self, obs: Observation):
        """(ℓ − logit p0, ω) after ``obs`` (copies)."""
        r, c = obs.cell
        flat = r * self.geometry.shape[1] + c
        wind = obs.wind if obs.wind is not None else tuple(self._wind.field()[r, c])
        kern = self._kernel.kernel((r, c), wind)  # w_r(c) ∈ [0, 1], geodesic, 0 beyond the cut-off
        v = self.hit_value if obs.hit else self.miss_value
        p = np.clip(self.prior_hit + (v - self.prior_hit) * kern, 0.001, 0.999)
        log_odds = self._log_odds + (_logit(p) - _logit(self.prior_hit))
        dist = dijkstra(self._graph, directed=False, indices=flat, limit=4.0 * self.confidence_sigma)
        near = np.isfinite(dist)
        omega = self._omega.copy()
        omega[near] += np.exp(-0.5 * (dist[near] / self.confidence_sigma) ** 2)
        return log_odds, omega

    def _score(self, sim: np.ndarray, assign, log_odds: np.ndarray, omega: np.ndarray) -> np.ndarray:
        """(K,) Σ_c log[1 − conf_c γ abs(ĥ_c − h_c(k))] over the cells with positive confidence, for the rows
        of ``sim`` ((K, n_blocks) hit frequencies); ``assign`` is unused (the rows are the candidates).

        Evaluated in log space as log[(1 − conf) + conf ((1 − γ) + γ (1 − abs(ĥ − h)))], with
        log(1 − conf) = −ω/m², log ĥ = −log(1 + e^{−ℓ}), log(1 − ĥ) = −log(1 + e^{ℓ}) and
        1 − abs(ĥ − h) = (1 − ĥ) + h where ĥ ≥ h, (1 − h) + ĥ elsewhere: every factor stays positive and finite
        however confident a cell and however saturated its ĥ (PMFS's product would round to zero)."""
        cells, x, ell = self._score_cells(log_odds, omega)
        with np.errstate(divide="ignore"):  # log 0 = −inf enters logaddexp only beside a finite term
            log_sim, log_not_sim = np.log(sim), np.log1p(-sim)
        return self._score_terms(sim, log_sim, log_not_sim, self._block[cells], x, ell).sum(axis=1)

    def _score_cells(self, log_odds: np.ndarray, omega: np.ndarray):
        """The cells the score runs over (flat, the free cells with positive confidence), their ω/m² and ℓ."""
        x = omega / self.confidence_weight ** 2
        cells = np.flatnonzero((x > 0) & self.geometry.free.ravel())
        return cells, x[cells], log_odds[cells] + _logit(self.prior_hit)

    def _score_terms(self, sim, log_sim, log_not_sim, blocks, x, ell) -> np.ndarray:
        """(K, len(blocks)) the terms log[(1 − conf) + conf (...)] of :meth:`_score` of the cells in the blocks
        ``blocks`` with ω/m² ``x`` and log-odds ``ell``, for the rows of ``sim`` (``log_sim``, ``log_not_sim``: its
        log and log(1 − ·), (K, n_blocks)). Elementwise: a cell's column depends on its own inputs only."""
        log_conf = np.log(-np.expm1(-x))
        ell = ell[None, :]
        log_h, log_not_h = -np.logaddexp(0.0, -ell), -np.logaddexp(0.0, ell)  # log ĥ, log(1 − ĥ)
        h_sim = sim[:, blocks]
        log_sim, log_not_sim = log_sim[:, blocks], log_not_sim[:, blocks]
        log_close = np.where(expit(ell) >= h_sim, np.logaddexp(log_not_h, log_sim),
                             np.logaddexp(log_not_sim, log_h))  # log(1 − abs(ĥ − h))
        g = self.discrimination
        log_g = np.logaddexp(np.log1p(-g), np.log(g) + log_close) if g < 1 else log_close
        return np.logaddexp(-x[None, :], log_conf[None, :] + log_g)

    def _score_kept(self, sim: np.ndarray, log_odds: np.ndarray, omega: np.ndarray, rows=None) -> np.ndarray:
        """:meth:`_score` of ``sim`` (or of its rows ``rows``), the same numbers, with the per-cell terms kept
        between calls for as long as ``sim`` is the same array: a reading changes ℓ and ω only near it, and only
        the cells whose inputs changed (or that are new to the sum) are computed again."""
        t = self._terms
        if t is None or t.sim is not sim:
            t = self._terms = _ScoreTerms(self, sim)
        cells, x, ell = self._score_cells(log_odds, omega)
        return t.score(cells, x, ell, rows)

    def _propose(self, obs: Observation):
        wind = self._wind
        if obs.wind is not None:  # the wind map takes the reading first
            wind = GMRFWind.__new__(GMRFWind)
            wind.__dict__.update(self._wind.__dict__)
            wind._count, wind._sum = self._wind._count.copy(), self._wind._sum.copy()
            wind.add(obs.position, obs.wind)
        log_odds, omega = self._measurement(obs)
        n = len(self._observations) + 1
        sim, assign, n_refresh = self._sim, self._assign, self._n_refresh
        if sim is None or (n - 1) % self.refresh == 0:
            sim, assign = self._refresh(wind.field(), log_odds, omega)
            n_refresh += 1
        score = self._score_kept(sim, log_odds, omega)
        log_lik = np.zeros(self._log_prior.size)
        log_lik[self.geometry.free.ravel()] = self.tempering * score[assign]
        return log_lik, (wind, log_odds, omega, sim, assign, n_refresh)

    def _accept(self, obs: Observation, payload) -> None:
        self._wind, self._log_odds, self._omega, self._sim, self._assign, self._n_refresh = payload

    # --- read-out -------------------------------------------------------------------------------------------
    def _hit_likelihood_rows(self, flat_cells: np.ndarray) -> np.ndarray:
        """(K', H·W) P(hit at x | s) = h_x(k(s)) from the simulated hit maps; the plume model's before any."""
        if self._sim is None:
            return super()._hit_likelihood_rows(flat_cells)
        n = self.geometry.shape[0] * self.geometry.shape[1]
        out = np.zeros((len(flat_cells), n))
        free = self.geometry.free.ravel()
        blocks = self._block[np.asarray(flat_cells, np.int64)]
        out[:, free] = self._sim[:, blocks].T[:, self._assign]
        return out

    @property
    def wind_estimate(self) -> np.ndarray:
        """(H, W, 2) the GMRF wind map û in m/s from the readings so far."""
        return self._wind.field()

    @property
    def hit_map(self) -> np.ndarray:
        """(H, W) the measured hit probability ĥ = σ(ℓ)."""
        return expit(self._log_odds + _logit(self.prior_hit)).reshape(self.geometry.shape)

    @property
    def confidence(self) -> np.ndarray:
        r"""(H, W) :math:`\mathrm{conf} = 1 - e^{-\omega / m^2}`."""
        return (-np.expm1(-self._omega / self.confidence_weight ** 2)).reshape(self.geometry.shape)

    def hit_variance(self) -> np.ndarray:
        r"""(H, W) how much the simulated sources disagree about a reading at each cell: PMFS's
        ``varianceOfHitProb``, the weighted variance over the first-level regions k of the last refresh,

        .. math:: \operatorname{Var}_c = \frac{\sum_k w_k (h_c(k) - \bar h_c)^2}{\sum_k w_k}, \qquad
                  \bar h_c = \frac{\sum_k w_k h_c(k)}{\sum_k w_k},

        with :math:`w_k \propto \prod_c \big[1 - \mathrm{conf}_c + \mathrm{conf}_c \big(1 - \gamma\,
        |\hat h_c - h_c(k)|\big)\big]`, each region's score under the current hit
        map and confidence (PMFS weighs by the score at the refresh; the two differ by the readings since), scaled
        so that the largest is 1. Zeros before the first refresh and on occupied cells. PMFS's navigation
        (:mod:`psgsl_pgm.search._pmfs_nav`) drives to where this, times 1 − conf, is largest.
        """
        out = np.zeros(self.geometry.shape[0] * self.geometry.shape[1])
        if self._sim is None:
            return out.reshape(self.geometry.shape)
        free = self.geometry.free.ravel()
        mass = np.isfinite(self._log_prior[free])
        coarse = np.unique(self._coarse[mass])  # the first level: every region with prior mass
        sim = self._sim[coarse]
        score = self._score_kept(self._sim, self._log_odds, self._omega, rows=coarse)  # = _score(sim, ...)
        w = np.exp(score - score.max())
        h = sim[:, self._block[free]]  # (K, n_free) h_c(k)
        mean = (w @ h) / w.sum()
        out[free] = (w @ (h - mean) ** 2) / w.sum()
        return out.reshape(self.geometry.shape)

    def simulated_hit_map(self, position) -> np.ndarray:
        """(H, W) the simulated hit frequency h_c(k) of the region k holding ``position`` (x, y) m (the last
        refresh; zeros before the first)."""
        r, c = self.model.cell_of(position)
        if self._sim is None:
            return np.zeros(self.geometry.shape)
        k = self._assign[np.searchsorted(np.flatnonzero(self.geometry.free.ravel()), r * self.geometry.shape[1] + c)]
        return self._sim[k][self._block].reshape(self.geometry.shape)


class _ScoreTerms:
    """The per-cell terms of :meth:`FilamentPMFS._score` for one set of simulations, kept with the inputs (ω/m²,
    ℓ) they were computed from: a call recomputes only the columns whose inputs changed, gathers the columns of
    its cells in their order into a (K, N') array of the layout :meth:`FilamentPMFS._score`'s own has and sums
    it the same way, so that the score has the same bits.

    Parameters
    ----------
    est : FilamentPMFS
        The estimator.
    sim : (K, n_blocks) ndarray
        The simulated hit frequencies (kept by reference: the terms are valid for this array only).
    """

    __slots__ = ("sim", "_est", "_log_sim", "_log_not_sim", "_pos", "_terms", "_x", "_ell")

    def __init__(self, est: FilamentPMFS, sim: np.ndarray):
        self.sim, self._est = sim, est
        with np.errstate(divide="ignore"):
            self._log_sim, self._log_not_sim = np.log(sim), np.log1p(-sim)
        free = est.geometry.free.ravel()
        self._pos = np.full(free.size, -1, np.int64)
        self._pos[free] = np.arange(int(free.sum()))  # column of each free cell
        self._terms = np.empty((sim.shape[0], int(free.sum())))
        self._x = np.full(int(free.sum()), np.nan)  # inputs of each column (NaN: not computed)
        self._ell = np.full(int(free.sum()), np.nan)

    def score(self, cells: np.ndarray, x: np.ndarray, ell: np.ndarray, rows=None) -> np.ndarray:
        """(K,) the score over ``cells`` (flat) with inputs ``x``, ``ell`` (or (len(rows),) for rows ``rows``)."""
        col = self._pos[cells]
        bits = np.uint64
        stale = ~((self._x[col].view(bits) == x.view(bits)) & (self._ell[col].view(bits) == ell.view(bits)))  # NaN: new
        if stale.any():
            c = col[stale]
            with np.errstate(divide="ignore"):
                self._terms[:, c] = self._est._score_terms(self.sim, self._log_sim, self._log_not_sim,
                                                           self._est._block[cells[stale]], x[stale], ell[stale])
            self._x[c], self._ell[c] = x[stale], ell[stale]
        # the columns gathered as _score gathers its blocks (sim[:, blocks] of a C-ordered array): the result has
        # the same memory layout, so numpy's sum over axis 1 adds in the same order (sequentially along a row for
        # that layout, not pairwise)
        terms = self._terms if rows is None else self._terms[np.asarray(rows)]
        return terms[:, col].sum(axis=1)
