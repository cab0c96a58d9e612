r"""Particle filter over the source position and its release rate: p(s | g) from weighted samples."""

from __future__ import annotations

import numpy as np

from .._shared._validate import index, positive, real_pair, unit_interval
from ._base import Observation, OlfactoryEstimator
from ._plume import PlumeModel

__all__ = ["ParticleFilter"]

_NODES = 32  # Gauss–Legendre nodes in log q of the prior predictive (planning rows)


class ParticleFilter(OlfactoryEstimator):
    r"""Sequential importance resampling over the source's position :math:`x_s` and release rate q (Gordon, Salmond &
    Smith 1993, IEE Proc. F 140:107–113; for gas sources e.g. Li, Meng, Wang & Zeng 2011, Auton. Robots 30:281–292), on
    the grid plume model of :class:`GridInfotaxis`.

    **State and prior.** N particles :math:`\theta_i = (x_i, y_i, \log q_i)` with weights :math:`w_i`. :math:`x_i` is a
    point in metres; it is drawn from the prior :math:`p(s)` over cells (times the factors given to :meth:`condition`),
    uniformly inside its cell; :math:`\log q_i` is uniform on :math:`[\log q_\text{min}, \log q_\text{max}]`
    (``release_rates``; q multiplies the plume model's encounter scale κ, so q = 1 is the model's own source strength,
    and the prior is scale-free over a factor q_max/q_min).

    **Likelihood.** A reading g at sensor x with the Poisson-encounter model of :class:`GridInfotaxis`, the
    source's strength scaling the expected encounters:

    .. math:: P(\text{hit} \mid \theta) = \varepsilon + (1 - \varepsilon)\big(1 - e^{-q \kappa G(x \mid s)}\big),
              \qquad P(\text{miss} \mid \theta) = (1 - \varepsilon)\, e^{-q \kappa G(x \mid s)},

    G the adjoint Green's function at the cell s of :math:`x_s`, ε the false-hit rate; each factor tempered by β
    as in :class:`GridInfotaxis`:

    .. math:: w_i \leftarrow w_i\, P(g \mid \theta_i)^\beta

    **Resampling and roughening.** When the effective sample size :math:`1 / \sum_i w_i^2` falls below
    ``resample_below`` · N the particles are resampled systematically (one uniform :math:`u \sim U[0, 1/N)`, the i-th
    pointer at :math:`u + i/N` along the cumulative weights; Kitagawa 1996) and roughened (Gordon et al. 1993): each
    coordinate d ∈ {x, y, log q} gets Gaussian noise of standard deviation :math:`\sigma_d = K E_d N^{-1/3}`,
    :math:`E_d` the particles' range in d, K = ``roughening``. A jitter that leaves the support (an occupied cell, off
    the map, a cell the prior or a "not found" factor rules out) is not applied; log q is reflected into its interval.

    :math:`p(s \mid g)` **on the grid** is the particles' weight per cell,

    .. math:: p(s = c \mid g) = \sum_{i:\, x_i \in c} w_i;

    cells without a particle have probability 0. With many particles and little roughening it tends to the grid
    posterior :math:`\int p(s, q \mid g)\, dq` of the same model (checked in the tests).

    **"Not found" and the semantic fusion.** :meth:`condition` multiplies each particle's weight by the factor of its
    cell, :math:`P(\bar F \mid s_i)`, then resamples as after a reading; the grid posterior is formed from the
    particles, so the fusion :math:`p(s \mid g, z) \propto p(s \mid g)\, p(s \mid z)` and the semantic variants are
    those of every estimator. When a reading or a factor leaves no particle with positive weight, the filter restarts: N
    new particles from the prior times every factor so far, weighted by the likelihood of every reading so far
    (importance sampling from that proposal), then resampled.

    **Random numbers.** Every draw comes from a generator seeded by (``seed``, the number of updates so far): the
    filter is reproducible, and :meth:`replace_model` (a re-solved plume after the wind estimate moved) replays
    the readings and factors in order with the same draws.

    **Planning.** :meth:`hit_probability` and :meth:`information_gain` use the prior predictive over q,
    :math:`P(\text{hit} \mid s) = \varepsilon + (1 - \varepsilon)\big(1 - \mathbb{E}_q\, e^{-q \kappa G}\big)`
    (Gauss–Legendre in log q), fixed for a plume model as the closed loop's cached rows need.

    Parameters
    ----------
    model : PlumeModel
    prior : (H, W) array_like of float, optional, keyword-only
        :math:`p(s)`; uniform over the free cells by default.
    n_particles : int, keyword-only
        N.
    release_rates : (2,) tuple of float, keyword-only
        (q_min, q_max), 0 < q_min ≤ q_max, relative to the model's source strength.
    tempering : float, keyword-only
        β ∈ (0, 1].
    false_hit_rate : float, keyword-only
        ε ∈ [0, 1).
    roughening : float, keyword-only
        K ≥ 0 (0: no roughening).
    resample_below : float, keyword-only
        In (0, 1]: resample when the effective sample size falls below this fraction of N (1: after every update).
    seed : int, keyword-only

    Examples
    --------
    >>> import numpy as np
    >>> wind = np.zeros((10, 16, 2)); wind[..., 0] = 0.2
    >>> model = PlumeModel(np.zeros((10, 16), bool), resolution=0.25, wind=wind, diffusivity=0.02, lifetime=30.0)
    >>> pf = ParticleFilter(model, n_particles=500, tempering=1.0, seed=1)
    >>> p = pf.update((3.1, 1.3), True)
    >>> p.shape, bool(abs(p.sum() - 1) < 1e-12)
    ((10, 16), True)
    >>> bool(pf.expected_position()[0] < 3.1)   # a hit in a wind along +x: the source is upwind
    True
    """

    def __init__(self, model: PlumeModel, *, prior=None, n_particles: int = 4000, release_rates=(0.25, 4.0),
                 tempering: float = 0.5, false_hit_rate: float = 0.01, roughening: float = 0.2,
                 resample_below: float = 0.5, seed: int = 0):
        self.n_particles = index(n_particles, "n_particles", minimum=1)
        rates = real_pair(release_rates, "release_rates", "a (q_min, q_max)", "relative to the model's source")
        if not (0 < rates[0] <= rates[1] and np.isfinite(rates).all()):
            raise ValueError(f"release_rates must be (q_min, q_max) with 0 < q_min <= q_max, got {tuple(rates)}")
        self.release_rates = (float(rates[0]), float(rates[1]))
        self.tempering = unit_interval(tempering, "tempering", low_open=True)
        self.false_hit_rate = unit_interval(false_hit_rate, "false_hit_rate", high_open=True)
        self.roughening = positive(roughening, "roughening", allow_zero=True)
        self.resample_below = unit_interval(resample_below, "resample_below", low_open=True)
        self.seed = index(seed, "seed")
        super().__init__(model, prior=prior)

    @classmethod
    def from_model(cls, model: PlumeModel, **kwargs) -> "ParticleFilter":
        """The filter on an existing :class:`PlumeModel` (the constructor; for symmetry with the other estimators)."""
        return cls(model, **kwargs)

    # --- particles ------------------------------------------------------------------------------------------
    @property
    def particles(self) -> np.ndarray:
        """(N, 3) copy of the particles (x m, y m, q)."""
        return np.column_stack([self._x, np.exp(self._logq)])

    @property
    def weights(self) -> np.ndarray:
        """(N,) copy of the normalised weights."""
        return self._w.copy()

    def release_rate_mean(self) -> float:
        r"""Posterior mean of q, :math:`\sum_i w_i q_i`."""
        return float(self._w @ np.exp(self._logq))

    def _rng(self, tag: int) -> np.random.Generator:
        return np.random.default_rng([self.seed, 0x9A27, len(self._events), tag])  # the filter's own streams

    def _cells(self, x) -> np.ndarray:
        """Flat cell of each point (−1 off the map)."""
        g = self.geometry
        rc = np.floor((x - np.asarray(g.origin)[None, :]) / g.resolution).astype(np.int64)[:, ::-1]
        h, w = g.shape
        inside = (rc[:, 0] >= 0) & (rc[:, 0] < h) & (rc[:, 1] >= 0) & (rc[:, 1] < w)
        return np.where(inside, rc[:, 0] * w + rc[:, 1], -1)

    def _draw(self, rng, n: int):
        """n particles from the prior times the factors so far; uniform within their cells."""
        log_p = self._support()
        p = np.exp(log_p - log_p.max())
        p /= p.sum()
        cells = rng.choice(p.size, size=n, p=p)
        g = self.geometry
        w = g.shape[1]
        corner = np.asarray(g.origin)[None, :] + g.resolution * np.column_stack([cells % w, cells // w])
        x = corner + g.resolution * rng.random((n, 2))
        lo, hi = np.log(self.release_rates)
        return x, lo + (hi - lo) * rng.random(n)

    def _log_likelihood(self, obs: Observation, cells, logq) -> np.ndarray:
        """(n,) β log P(g | θ) of one reading for particles in ``cells`` with rates exp(``logq``)."""
        r, c = obs.cell
        green = self.model.green_rows([r * self.geometry.shape[1] + c])[0]
        mu = np.exp(logq) * self.model.encounter_scale * green[cells]
        eps = self.false_hit_rate
        if obs.hit:
            with np.errstate(divide="ignore"):
                ell = np.log(-np.expm1(-mu) + eps * np.exp(-mu))
        else:
            ell = np.log1p(-eps) - mu
        return self.tempering * ell

    def _resample_and_roughen(self, rng) -> None:
        n = self.n_particles
        u = (rng.random() + np.arange(n)) / n  # systematic resampling
        cum = np.cumsum(self._w)
        cum[-1] = 1.0
        pick = np.minimum(np.searchsorted(cum, u, side="right"), n - 1)
        x, logq = self._x[pick], self._logq[pick]
        if self.roughening > 0 and n > 1:
            state = np.column_stack([x, logq])
            sigma = self.roughening * (state.max(axis=0) - state.min(axis=0)) * n ** (-1.0 / 3.0)
            moved = state + sigma[None, :] * rng.standard_normal(state.shape)
            lo, hi = np.log(self.release_rates)
            if hi > lo:  # reflected into [lo, hi]
                y = np.mod(moved[:, 2] - lo, 2.0 * (hi - lo))
                q = lo + np.where(y > hi - lo, 2.0 * (hi - lo) - y, y)
            else:
                q = np.full(n, lo)
            cells = self._cells(moved[:, :2])
            ok = cells >= 0
            ok[ok] = np.isfinite(self._support()[cells[ok]]) & self.geometry.free.ravel()[cells[ok]]
            x = np.where(ok[:, None], moved[:, :2], x)
            logq = q
        self._x, self._logq = x, logq
        self._w = np.full(n, 1.0 / n)

    def _reweight(self, log_factor, rng) -> None:
        """w_i ← w_i exp(log_factor_i), normalised; a restart when no weight is left; resampled and roughened when
        the effective sample size is below ``resample_below`` · N."""
        with np.errstate(divide="ignore"):
            logw = np.log(self._w) + log_factor
        top = np.max(logw)
        if not np.isfinite(top):
            self._restart(rng)
            return
        w = np.exp(logw - top)
        self._w = w / w.sum()
        if 1.0 / np.sum(self._w**2) < self.resample_below * self.n_particles:
            self._resample_and_roughen(rng)

    def _restart(self, rng) -> None:
        """N particles from the prior times every factor so far, weighted by every reading so far."""
        x, logq = self._draw(rng, self.n_particles)
        cells = self._cells(x)
        logw = np.zeros(self.n_particles)
        for kind, item in self._events:
            if kind == "obs":
                logw += self._log_likelihood(item, cells, logq)
        top = np.max(logw)
        if not np.isfinite(top):
            raise ValueError("no particle of the prior times the \"not found\" factors explains the readings "
                             "(use a positive false_hit_rate)")
        self._x, self._logq = x, logq
        w = np.exp(logw - top)
        self._w = w / w.sum()
        self._resample_and_roughen(rng)

    def _grid_log_posterior(self) -> np.ndarray:
        cells = self._cells(self._x)
        mass = np.bincount(cells, weights=self._w, minlength=self.geometry.shape[0] * self.geometry.shape[1])
        with np.errstate(divide="ignore"):
            return np.log(mass)

    # --- the estimator's interface ----------------------------------------------------------------------------
    def _reset_state(self) -> None:
        self._events = []
        self._x, self._logq = self._draw(self._rng(0), self.n_particles)
        self._w = np.full(self.n_particles, 1.0 / self.n_particles)

    def _initial_log_posterior(self) -> np.ndarray:
        """After :meth:`reset`: N fresh particles from the prior (the same ones every time)."""
        return self._grid_log_posterior()

    def _propose(self, obs: Observation):
        raise NotImplementedError("ParticleFilter updates through update()")  # pragma: no cover

    def _accept(self, obs: Observation, payload) -> None:
        raise NotImplementedError("ParticleFilter updates through update()")  # pragma: no cover

    def _apply(self, kind: str, item) -> None:
        """One reading (``"obs"``) or one factor (``"cond"``): reweight the particles (and resample)."""
        rng = self._rng(1)
        self._events.append((kind, item))
        if kind == "obs":
            self._reweight(self._log_likelihood(item, self._cells(self._x), self._logq), rng)
        else:
            self._reweight(item[self._cells(self._x)], rng)

    def update(self, position, hit, wind=None) -> np.ndarray:
        """Assimilate one reading (:meth:`OlfactoryEstimator.update`) by reweighting the particles."""
        obs = self._observation(position, hit, wind)
        state = (self._x, self._logq, self._w, list(self._events))
        try:
            self._apply("obs", obs)
        except ValueError:
            self._x, self._logq, self._w, self._events = state  # the reading was not applied
            raise
        self._observations.append(obs)
        self._set_log_posterior(self._grid_log_posterior())
        return self.posterior

    def _condition(self, log_likelihood) -> None:
        ll = self._as_log_likelihood(log_likelihood)
        self._check_some_mass(self._support() + ll)
        state = (self._x, self._logq, self._w, list(self._events), self._log_other)
        self._log_other = ll.copy() if self._log_other is None else self._log_other + ll
        try:
            self._apply("cond", ll.copy())
        except ValueError:
            self._x, self._logq, self._w, self._events, self._log_other = state
            raise
        self._set_log_posterior(self._grid_log_posterior())

    def replace_model(self, model: PlumeModel) -> np.ndarray:
        """Replay every reading and factor, in order and with the same draws, on a new plume model of the same map
        (:meth:`OlfactoryEstimator.replace_model`)."""
        self._adopt_model(model)
        events = self._events
        self._log_other = None
        self._reset_state()
        for kind, item in events:
            if kind == "cond":
                self._log_other = item.copy() if self._log_other is None else self._log_other + item
            self._apply(kind, item)
        self._set_log_posterior(self._grid_log_posterior())
        return self.posterior

    def _hit_likelihood_rows(self, flat_cells: np.ndarray) -> np.ndarray:
        lo, hi = np.log(self.release_rates)
        t, v = np.polynomial.legendre.leggauss(_NODES)
        q = np.exp(0.5 * (hi - lo) * t + 0.5 * (hi + lo))
        mu = self.model.encounter_scale * self.model.green_rows(flat_cells)  # (K, H·W)
        miss = np.zeros_like(mu)
        for qk, vk in zip(q, v / 2.0):  # E_q e^{−qκG}, log q uniform on [lo, hi]
            miss += vk * np.exp(-qk * mu)
        eps = self.false_hit_rate
        return eps + (1.0 - eps) * (1.0 - miss)
