"""Common interface of the olfactory estimators p(s | g): posterior in log space over all map cells."""

from __future__ import annotations

import abc
from dataclasses import dataclass

import numpy as np
from scipy.special import entr

from .._shared._validate import as_float_array
from ..kernels._logsumexp import logsumexp
from ._plume import PlumeModel
from ._wind_input import as_wind_vector

__all__ = ["Observation", "OlfactoryEstimator"]


@dataclass(frozen=True)
class Observation:
    """One olfactory reading at a robot stop.

    Attributes
    ----------
    position : tuple of float
        Sensor (x, y) in metres.
    cell : tuple of int
        Grid cell (row, col) of the sensor.
    hit : bool
        Binary gas detection.
    wind : tuple of float or None
        Anemometer (u_x, u_y) in m/s, if given.
    """

    position: tuple[float, float]
    cell: tuple[int, int]
    hit: bool
    wind: tuple[float, float] | None


def _check_model(model) -> None:
    """TypeError unless ``model`` is a :class:`PlumeModel`."""
    if not isinstance(model, PlumeModel):
        raise TypeError(f"model must be a PlumeModel, got {type(model).__name__}")


def _as_hit(hit) -> bool:
    if isinstance(hit, (bool, np.bool_)):
        return bool(hit)
    if isinstance(hit, (int, np.integer)) and hit in (0, 1):
        return bool(hit)
    raise TypeError(f"hit must be a bool (or 0/1), got {type(hit).__name__} {hit!r}")


class OlfactoryEstimator(abc.ABC):
    r"""Posterior :math:`p(s \mid g)` over the cells of a map, updated one reading at a time.

    The posterior covers every cell of the (H, W) map, is exactly zero on occupied cells, sums to one and is
    kept internally as a log posterior (log-likelihood accumulation, ``logsumexp`` normalisation). It is the
    olfactory factor of eq. (11) of the paper, to be fused with the semantic term by :func:`psgsl_pgm.fuse`:

    .. math:: p(s_c \mid g, z) \propto p(s_c \mid g) \cdot p(s_c \mid z)

    The bookkeeping of :math:`p(s \mid g)` lives here, once for every estimator: the prior in log space
    (normalised, −inf on occupied cells), the posterior

    .. math:: \log p(s \mid g, \bar F) = \log p(s) + \log L(s) + \sum \log P(\bar F \mid s) - \log Z

    normalised with ``logsumexp`` when first read, the "not found" factors :math:`P(\bar F \mid s)` of
    :meth:`condition` kept through later readings, and the checks that no update leaves every cell at
    probability zero. Subclasses implement :meth:`_propose` (the log-likelihood :math:`\log L(s)` of every
    reading so far, after one more, without changing state) and :meth:`_accept` (commit it); :meth:`update`
    rejects a reading that would leave no cell with positive probability (ValueError, state unchanged), so the
    posterior never holds NaN.

    Parameters
    ----------
    model : PlumeModel
        The plume model of the map (shared between estimators to share its factorisation and cache).
    prior : (H, W) array_like of float, optional
        Non-negative prior :math:`p(s)` (normalised here; zeroed on occupied cells). Default: uniform over free
        cells.
    """

    def __init__(self, model: PlumeModel, *, prior=None):
        _check_model(model)
        self.model = model
        self.geometry = model.geometry
        free = self.geometry.free.ravel()
        if prior is None:
            log_prior = np.where(free, 0.0, -np.inf)
        else:
            p = as_float_array(prior, "prior", dtype=np.float64)
            if p.shape != self.geometry.shape:
                raise ValueError(f"prior must have the map's shape {self.geometry.shape}, got {p.shape}")
            p = p.astype(np.float64).ravel()
            if not np.isfinite(p).all() or (p < 0).any():
                raise ValueError("prior must be finite and non-negative")
            p = np.where(free, p, 0.0)
            if not (p.sum() > 0):
                raise ValueError("prior must put positive mass on at least one free cell")
            with np.errstate(divide="ignore"):
                log_prior = np.log(p)
        self._log_prior = log_prior - logsumexp(log_prior)
        self._log_prior.flags.writeable = False
        self._centres = self.geometry.cell_centres().reshape(-1, 2)
        self.reset()

    # --- state ----------------------------------------------------------------------------------------------
    def reset(self) -> None:
        """Forget all readings: the posterior returns to the prior."""
        self._observations: list[Observation] = []
        self._log_other = None  # Σ of the log-likelihoods given to condition() (None: none given)
        self._reset_state()
        self._set_log_posterior(self._initial_log_posterior())

    def _initial_log_posterior(self) -> np.ndarray:
        """The flat (unnormalised) log posterior before any reading: the prior."""
        return self._log_prior.copy()

    def _support(self) -> np.ndarray:
        """(H·W,) log p(s) + Σ log P(F̄ | s): the prior times the factors given to :meth:`condition` so far (−inf
        outside the support)."""
        return self._log_prior if self._log_other is None else self._log_prior + self._log_other

    @abc.abstractmethod
    def _reset_state(self) -> None:
        """Clear subclass state."""

    @abc.abstractmethod
    def _propose(self, obs: Observation):
        """Return (flat log-likelihood log L(s) of every reading so far and ``obs``, payload); must not change
        state. The prior and the "not found" factors are added by the caller."""

    @abc.abstractmethod
    def _accept(self, obs: Observation, payload) -> None:
        """Commit the state change computed by :meth:`_propose`."""

    def _set_log_posterior(self, log_post: np.ndarray) -> None:
        """Set the unnormalised flat log posterior; it is normalised when first read (:attr:`_log_post`), so a
        posterior replaced before anyone reads it (a "not found" factor and then the next reading) costs none."""
        log_post = log_post.copy()
        log_post[~self.geometry.free.ravel()] = -np.inf
        self._unnormalised = log_post
        self._normalised = None

    @property
    def _log_post(self) -> np.ndarray:
        """Flat normalised log posterior (read-only)."""
        return self._normalise()[0]

    @property
    def _post(self) -> np.ndarray:
        """Flat posterior (read-only)."""
        return self._normalise()[1]

    def _normalise(self):
        if self._normalised is None:
            log_post = self._unnormalised
            log_post -= logsumexp(log_post)  # normalise in log space
            log_post.flags.writeable = False
            post = np.exp(log_post)
            post.flags.writeable = False
            self._normalised = (log_post, post)
            self._unnormalised = None
        return self._normalised

    def update(self, position, hit, wind=None) -> np.ndarray:
        """Assimilate one reading and return the new posterior.

        Parameters
        ----------
        position : (2,) array_like of float
            Sensor (x, y) in metres; must fall in a free cell of the map.
        hit : bool
            Whether the gas sensor detected gas (binary hit/miss).
        wind : (2,) array_like of float, optional
            Anemometer reading (u_x, u_y) in m/s at the sensor.

        Returns
        -------
        posterior : (H, W) ndarray of float64
            p(s | g) after this reading (read-only view; see :attr:`posterior`).
        """
        obs = self._observation(position, hit, wind)
        log_target, payload = self._propose(obs)
        log_target = self._log_prior + log_target
        if self._log_other is not None:
            log_target = log_target + self._log_other
        finite = np.isfinite(log_target) & self.geometry.free.ravel()
        if np.isnan(log_target).any():
            raise FloatingPointError("internal error: NaN in the log posterior")  # never expected
        if not finite.any():
            raise ValueError(
                f"the reading {'hit' if obs.hit else 'miss'} at {obs.position} has zero likelihood for every "
                "candidate source under the model (use a positive false_hit_rate); the reading was not applied"
            )
        self._accept(obs, payload)
        self._observations.append(obs)
        self._set_log_posterior(log_target)
        return self.posterior

    def _observation(self, position, hit, wind) -> Observation:
        """The checked :class:`Observation` of one reading (its cell must be free)."""
        return Observation(
            position=tuple(float(v) for v in np.asarray(position, dtype=np.float64)),
            cell=self.model.cell_of(position),
            hit=_as_hit(hit),
            wind=as_wind_vector(wind),
        )

    def _adopt_model(self, model: PlumeModel) -> None:
        """Take ``model`` as the plume model after checking that it is one of the same map (same shape, same
        walls); nothing is re-assimilated."""
        _check_model(model)
        if model.geometry.shape != self.geometry.shape or not np.array_equal(model.geometry.occupancy,
                                                                             self.geometry.occupancy):
            raise ValueError(f"model must be on the same map ({self.geometry.shape} cells, same walls)")
        self.model = model

    def replace_model(self, model: PlumeModel) -> np.ndarray:
        """Re-assimilate every reading so far under a new plume model of the same map (e.g. one solved with a
        refreshed wind estimate) and return the new posterior.

        The prior and the factors given to :meth:`condition` are kept; the subclass state is rebuilt by replaying
        the stored observations in order, so the result equals a fresh estimator on ``model`` fed the same
        readings and conditioned on the same observations.
        Cost: one adjoint solve per distinct sensor cell visited, on ``model``'s (empty) cache.
        """
        self._adopt_model(model)
        self._reset_state()
        log_post = self._log_prior.copy()
        for obs in self._observations:
            log_lik, payload = self._propose(obs)
            self._accept(obs, payload)
            log_post = self._log_prior + log_lik
        if self._log_other is not None:  # p(s | g, F̄) ∝ p(s | g) P(F̄ | s): the "not found" factors stay
            log_post = log_post + self._log_other
        self._set_log_posterior(log_post)
        return self.posterior

    def condition(self, log_likelihood) -> np.ndarray:
        r"""Multiply :math:`p(s \mid g)` by the likelihood of an observation other than a gas reading, and keep
        it.

        The closed loop's "not found here" :math:`\bar F`
        (:meth:`psgsl_pgm.search.DetectionModel.not_found_log_likelihood`):

        .. math:: p(s \mid g, \bar F) \propto p(s \mid g)\, P(\bar F \mid s)

        The factor stays in the posterior through later readings (it is added to every later proposal) and is
        forgotten by :meth:`reset`. Since it depends on s only, fusing the result with :math:`p(s \mid z)`
        (eq. (11)) gives every variant the update exactly once.

        Parameters
        ----------
        log_likelihood : (H, W) or (H·W,) array_like of float
            :math:`\log P(\text{observation} \mid s = c)` for every cell: finite or −inf (probability 0), never
            NaN or +inf.

        Returns
        -------
        posterior : (H, W) ndarray of float64
            The conditioned posterior (read-only view).
        """
        self._condition(log_likelihood)
        return self.posterior

    def recondition(self, log_likelihood) -> np.ndarray:
        """Replace every factor given to :meth:`condition` by ``log_likelihood`` (their new sum) and re-assimilate
        the readings: the posterior a fresh estimator would hold after the same readings and that one factor.

        The closed loop's several-source search (:mod:`psgsl_pgm.search._several`) uses it to drop the factors of
        a declared source and remove its region. Same shapes and values as :meth:`condition`.
        """
        ll = self._as_log_likelihood(log_likelihood)
        if not np.isfinite((self._log_prior + ll)[self.geometry.free.ravel()]).any():
            raise ValueError("log_likelihood rules out every cell the prior allows")
        self._log_other = ll.copy()
        return self.replace_model(self.model)

    def _condition(self, log_likelihood) -> None:
        """:meth:`condition` without reading the conditioned posterior back: it is normalised when first read,
        and the closed loop's next reading replaces it unread (one log-sum-exp and one exp of the map saved per
        stop; the same numbers whenever it is read)."""
        ll = self._as_log_likelihood(log_likelihood)
        log_target = self._log_post + ll
        self._check_some_mass(log_target)
        self._log_other = ll.copy() if self._log_other is None else self._log_other + ll
        self._set_log_posterior(log_target)

    def _as_log_likelihood(self, log_likelihood) -> np.ndarray:
        """``log_likelihood`` of :meth:`condition` checked and flattened: (H·W,) float64, finite or −inf."""
        ll = as_float_array(log_likelihood, "log_likelihood", dtype=np.float64)
        n = self.geometry.shape[0] * self.geometry.shape[1]
        if ll.size != n or ll.shape not in (self.geometry.shape, (n,)):
            raise ValueError(f"log_likelihood must have the map's shape {self.geometry.shape} (or ({n},)), "
                             f"got {ll.shape}")
        ll = ll.astype(np.float64).ravel()
        if np.isnan(ll).any() or (ll == np.inf).any():
            raise ValueError("log_likelihood must be finite or -inf (no NaN, no +inf)")
        return ll

    def _check_some_mass(self, log_target: np.ndarray) -> None:
        """ValueError when the flat log posterior ``log_target`` of a factor is −inf on every free cell."""
        if not np.isfinite(log_target[self.geometry.free.ravel()]).any():
            raise ValueError("the observation has zero likelihood for every cell with positive probability; "
                             "it was not applied")

    # --- read-out -------------------------------------------------------------------------------------------
    @property
    def posterior(self) -> np.ndarray:
        """(H, W) float64 p(s | g): sums to 1, zero on occupied cells (read-only)."""
        return self._post.reshape(self.geometry.shape)

    @property
    def log_conditioning(self) -> np.ndarray:
        """(H, W) float64 Σ of the log-likelihoods given to :meth:`condition` since the last :meth:`reset` (0 where
        none; −inf where an observation ruled a cell out): the "not found" factors P(F̄ | s) in log space."""
        n = self.geometry.shape
        out = np.zeros(n) if self._log_other is None else self._log_other.reshape(n).copy()
        out.flags.writeable = False
        return out

    @property
    def log_posterior(self) -> np.ndarray:
        """(H, W) float64 log p(s | g), −inf on occupied cells (read-only)."""
        return self._log_post.reshape(self.geometry.shape)

    @property
    def prior(self) -> np.ndarray:
        """(H, W) float64 prior p(s) (normalised)."""
        return np.exp(self._log_prior).reshape(self.geometry.shape)

    @property
    def observations(self) -> tuple[Observation, ...]:
        """Readings assimilated since the last :meth:`reset`."""
        return tuple(self._observations)

    @property
    def n_observations(self) -> int:
        """Number of readings assimilated since the last :meth:`reset`."""
        return len(self._observations)

    def map_cell(self) -> tuple[int, int]:
        """(row, col) of the most probable source cell (first one on ties)."""
        return tuple(int(v) for v in np.unravel_index(int(np.argmax(self._log_post)), self.geometry.shape))

    def map_position(self) -> tuple[float, float]:
        """Map-frame (x, y) centre of the most probable source cell."""
        return self.geometry.centre_of(self.map_cell())

    def expected_position(self) -> tuple[float, float]:
        """Posterior mean E[s] (x, y) in metres (the paper's reported source estimate)."""
        m = self._post @ self._centres
        return (float(m[0]), float(m[1]))

    def position_spread(self) -> float:
        """Posterior standard deviation sqrt(E|s − E[s]|²) in metres (the paper's error bars)."""
        d = self._centres - np.asarray(self.expected_position())
        return float(np.sqrt(self._post @ np.einsum("ij,ij->i", d, d)))

    def entropy(self) -> float:
        """H(S) of the posterior in nats."""
        return float(entr(self._post).sum())

    # --- information gain -----------------------------------------------------------------------------------
    def _hit_likelihood_rows(self, flat_cells: np.ndarray) -> np.ndarray:
        """(K, H*W) P(hit at x_k | s) used for predictions; default: the plume model's 1 − exp(−κ G)."""
        return -np.expm1(-self.model.encounter_scale * self.model.green_rows(flat_cells))

    def _flat_cells(self, positions) -> np.ndarray:
        pos = np.asarray(positions, dtype=np.float64)
        if pos.ndim != 2 or pos.shape[1] != 2:
            raise ValueError(f"positions must have shape (n, 2) (x, y in metres), got {pos.shape}")
        grid = self.model.geometry
        h, w = grid.shape
        if np.isfinite(pos).all():  # every position at once; any that is refused, one by one for its message
            rc = grid.world_to_cell(pos)
            r, c = rc[:, 0], rc[:, 1]
            inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
            if inside.all() and not grid.occupancy[r, c].any():
                return r * w + c
        return np.array([r * w + c for r, c in (self.model.cell_of(p, "positions[i]") for p in pos)], np.int64)

    def hit_probability(self, positions) -> np.ndarray:
        """Predictive P(hit at x | s) of one reading at each candidate position x, for every candidate source s.

        Parameters
        ----------
        positions : (n, 2) array_like of float
            Sensor positions (x, y) in metres (free cells).

        Returns
        -------
        p : (n, H, W) ndarray of float64
            The estimator's hit model (untempered; with false hits for :class:`GridInfotaxis`).
        """
        return self._hit_likelihood_rows(self._flat_cells(positions)).reshape((-1,) + self.geometry.shape)

    def _distribution(self, posterior) -> np.ndarray:
        """``posterior`` as an (H, W) float64 distribution over the map's cells; ValueError otherwise."""
        post = np.asarray(posterior, dtype=np.float64)
        if post.shape != self.geometry.shape:
            raise ValueError(f"posterior must have the map's shape {self.geometry.shape}, got {post.shape}")
        if not (np.isfinite(post).all() and (post >= 0).all() and abs(post.sum() - 1.0) < 1e-9):
            raise ValueError("posterior must be a distribution over the map's cells (finite, >= 0, sums to 1)")
        return post

    def information_gain(self, positions, *, posterior=None) -> np.ndarray:
        r"""Expected information about S from one hit/miss reading at each candidate position,
        :math:`I(S; \text{hit}_x)`.

        .. math:: I(S; \text{hit}_x) = H_b\Big(\sum_s p(s)\, P_x(s)\Big) - \sum_s p(s)\, H_b(P_x(s))

        with the binary entropy :math:`H_b` and :math:`P_x(s) = P(\text{hit at } x \mid s)` the estimator's
        predictive hit probability (untempered; with false hits for :class:`GridInfotaxis`), in nats: the
        olfactory term :math:`\varphi_G(p)` of the objective of eq. (29) of the paper,
        :math:`\varphi(p) = \varphi_G(p) + \varphi_O(p)` (Sec. "Information Gain Optimization").

        Parameters
        ----------
        positions : (n, 2) array_like of float
            Candidate sensor positions (x, y) in metres (free cells).
        posterior : (H, W) array_like, optional, keyword-only
            The distribution :math:`p(s)` of S under which to evaluate (default: this estimator's
            :math:`p(s \mid g)`); e.g. the fused :math:`p(s \mid g, z)` when the robot also uses semantics.

        Returns
        -------
        gain : (n,) ndarray of float64
            Non-negative, at most ln 2.
        """
        flat = self._flat_cells(positions)
        post = self._post if posterior is None else self._distribution(posterior).ravel()
        p_hit = self._hit_likelihood_rows(flat)  # (n, H*W)
        p_bar = p_hit @ post  # predictive P(hit at x)
        h_bin = entr(p_hit) + entr(1.0 - p_hit)  # H_b(P_x(s))
        gain = entr(p_bar) + entr(1.0 - p_bar) - h_bin @ post  # I = H_b(p̄) − E_s[H_b]
        return np.maximum(gain, 0.0)  # round-off can give −1e-17
