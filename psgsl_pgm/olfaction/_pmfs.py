"""The analytic-plume estimator, a PMFS-style source posterior: the observed hit map against the hit map each candidate source would produce."""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from .._shared._validate import positive, unit_interval
from ._base import Observation, OlfactoryEstimator, _check_model
from ._hitmap import HitProbabilityMap
from ._plume import PlumeModel

__all__ = ["PMFSEstimator"]

_HITMAP_KEYS = ("prior_hit", "prior_strength", "kernel_sigma", "kernel_stretch", "confidence_scale", "cutoff")


class PMFSEstimator(OlfactoryEstimator):
    r"""Source posterior of the PMFS family (Ojeda, Monroy & Gonzalez-Jimenez) on an analytic plume: estimator
    ``analytic-plume``. PMFS as published, with filament simulations, is :class:`FilamentPMFS` (``pmfs``).

    PMFS keeps a map of hit probabilities with a confidence (:class:`HitProbabilityMap`) and scores every
    candidate source s by how well the hit map it would produce, :math:`h_c(s)`, agrees with the estimate
    :math:`\hat h_c`, each cell weighted by its confidence (PMFS ``Simulations::weightedDifference``), the PMFS
    score:

    .. math:: p(s \mid g) \propto p(s) \prod_c \big[1 - \gamma\, \mathrm{conf}_c\, |\hat h_c - h_c(s)|\big]

    computed as a sum of ``log1p`` terms. Every factor lies in :math:`[1 - \gamma, 1]`, so no single cell can
    veto a source: the score is a bounded pseudo-likelihood, and the posterior is recomputed from the current
    hit map after each reading rather than multiplied up over time. Its sharpness is still not a probability
    statement (it grows with the number of compared cells): the exponent λ (``tempering``) rescales it,
    :math:`p(s \mid g) \propto p(s) \big(\prod_c [\dots]\big)^\lambda`, and is fitted on calibration runs
    (:func:`score_tempering`).

    Simplifications with respect to PMFS, and why:

    * PMFS obtains h_c(s) by simulating filaments from (quadtree regions of) candidate sources in the estimated wind and
      counting their visits per cell. We use the expected value of that frequency under the Poisson-encounter
      advection-diffusion model shared with :class:`GridInfotaxis`, :math:`h_c(s) = 1 - e^{-\kappa G(c \mid s)}`, which
      is deterministic and, through the adjoint Green's function, available for *all* candidates s at once (one solve
      per compared cell, cached).
    * The product runs over the cells the robot has measured in (its stops), where the hit map is most
      confident, instead of over all free cells: that keeps the cost at one adjoint solve per stop. Cells
      between stops only carry kernel-interpolated copies of the same readings, and their confidence is lower.
    * The hit map's per-cell filter is a Beta posterior instead of PMFS' log-odds filter, so that misses lower
      :math:`\hat h` (see :class:`HitProbabilityMap`).

    The measured wind orients and stretches the hit-map kernel, as in PMFS; when a reading comes without wind,
    the model's wind field at the sensor cell is used. The estimator is deterministic.

    Because every factor is bounded and saturates with its cell's confidence, repeated readings at one cell move
    the posterior less and less, unlike a Bayes update (whose factors :math:`P(g \mid s)` multiply up). A
    planner that expects :math:`I(S; \text{hit})` from a reading here expects information this estimator never
    takes in: :meth:`reading_log_ratio` gives the factor its update would actually apply, so that the closed
    loop's :math:`\varphi_G` is
    the expected entropy drop under this update (the policies of :mod:`psgsl_pgm.search`).

    Parameters
    ----------
    occupancy : (H, W) ndarray of bool
        True = occupied.
    resolution : float
        Cell side in metres.
    origin : (2,) array_like of float, default (0, 0)
        Map-frame (x, y) of the lower-left corner of cell (0, 0).
    wind : (H, W, 2) ndarray of float, optional
        Wind field (u_x, u_y) in m/s used by the plume model.
    outlets : (H, W) ndarray of bool, optional
        Absorbing free cells.
    prior : (H, W) array_like of float, optional
        Prior :math:`p(s)`; uniform over free cells by default.
    discrimination : float, default 0.9
        γ ∈ (0, 1): PMFS' ``sourceDiscriminationPower``; γ < 1 keeps every factor positive.
    tempering : float, default 1.0
        λ > 0, the exponent of the score: :math:`p(s \mid g) \propto p(s) \big(\prod_c [\dots]\big)^\lambda`. The PMFS
        score is a pseudo-likelihood whose sharpness is not a probability statement; λ rescales it so that its posterior
        is calibrated (fitted by the log score of known sources on calibration runs in the experiment); 1 is PMFS
        itself.
    prior_hit, prior_strength, kernel_sigma, kernel_stretch, confidence_scale, cutoff
        Options of :class:`HitProbabilityMap`.
    **plume : keyword arguments
        ``diffusivity``, ``lifetime``, ``encounter_scale``, ``boundary``, ``scheme``, ``cache_size`` of
        :class:`PlumeModel`.

    Examples
    --------
    >>> import numpy as np
    >>> occ = np.zeros((12, 16), bool)
    >>> wind = np.zeros((12, 16, 2)); wind[..., 0] = 0.3
    >>> est = PMFSEstimator(occ, resolution=0.25, wind=wind, boundary="open", diffusivity=0.02)
    >>> stops = [(x, y) for x in np.arange(0.6, 4.0, 0.5) for y in np.arange(0.35, 3.0, 0.5)]
    >>> hits = est.model.sample_hits(stops, (1.1, 1.6), rng=1)   # synthetic readings, source at (1.1, 1.6)
    >>> for x, g in zip(stops, hits):
    ...     p = est.update(x, g)
    >>> x, y = est.expected_position()
    >>> bool(abs(p.sum() - 1) < 1e-12), bool(np.hypot(x - 1.1, y - 1.6) < 0.5)
    (True, True)
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
        discrimination: float = 0.9,
        tempering: float = 1.0,
        **kwargs,
    ):
        hitmap = {k: kwargs.pop(k) for k in _HITMAP_KEYS if k in kwargs}
        model = PlumeModel(occupancy, resolution=resolution, origin=origin, wind=wind, outlets=outlets, **kwargs)
        self._configure(model, discrimination, hitmap, tempering)
        super().__init__(model, prior=prior)

    @classmethod
    def from_model(cls, model: PlumeModel, *, prior=None, discrimination: float = 0.9, tempering: float = 1.0,
                   **hitmap) -> "PMFSEstimator":
        """Estimator on an existing :class:`PlumeModel` (shares its factorisation and Green's-function cache)."""
        _check_model(model)
        self = cls.__new__(cls)
        self._configure(model, discrimination, hitmap, tempering)
        OlfactoryEstimator.__init__(self, model, prior=prior)
        return self

    @classmethod
    def from_grid_map(cls, grid_map, wind=None, *, outlets=None, prior=None, **kwargs) -> "PMFSEstimator":
        """Estimator on any object with ``.occupancy``, ``.resolution``, ``.origin`` (e.g. ``sim.GridMap``).

        ``wind`` is the (H, W, 2) wind field in m/s; remaining keywords as in the constructor.
        """
        opts = {k: kwargs.pop(k) for k in ("discrimination", "tempering") + _HITMAP_KEYS if k in kwargs}
        model = PlumeModel.from_grid_map(grid_map, wind, outlets=outlets, **kwargs)
        return cls.from_model(model, prior=prior, **opts)

    def _configure(self, model: PlumeModel, discrimination, hitmap: dict, tempering=1.0) -> None:
        unknown = set(hitmap) - set(_HITMAP_KEYS)
        if unknown:
            raise TypeError(f"unexpected keyword argument(s) {sorted(unknown)}; hit-map options are {_HITMAP_KEYS}")
        self.discrimination = unit_interval(discrimination, "discrimination", low_open=True, high_open=True)
        self.tempering = positive(tempering, "tempering")
        self._hitmap = HitProbabilityMap(model.geometry, **hitmap)

    # --- state ----------------------------------------------------------------------------------------------
    def _reset_state(self) -> None:
        self._hitmap.reset()
        self._cells: list[int] = []  # flat sensor cells compared, in first-visit order
        self._slot: dict[int, int] = {}
        n = self.geometry.shape[0] * self.geometry.shape[1]
        self._pred = np.empty((16, n))  # rows h_c(s) = 1 − exp(−κ G(c | s)) for the compared cells
        self._h_used = np.empty(0)  # ĥ_c and conf_c behind the current score
        self._conf_used = np.empty(0)
        self._score = np.zeros(n)  # Σ_c log[1 − γ conf_c |ĥ_c − h_c(s)|]
        self._kernels: dict[int, np.ndarray] = {}  # hit-map kernels in the model's wind, per flat cell
        self._new_rows: OrderedDict[int, _NewCellRows] = OrderedDict()  # h_x(s) and x's factors, cells not compared
        self._kernel_model = self.model
        self._tables = None  # _RatioTables of the current state (reading_log_ratio)

    def _log_factors(self, rows: np.ndarray, h_obs: np.ndarray, conf: np.ndarray) -> np.ndarray:
        """Σ over the given compared cells of log[1 − γ conf_c |ĥ_c − h_c(s)|], for every s."""
        factor = self.discrimination * conf[:, None] * np.abs(h_obs[:, None] - self._pred[rows])
        return np.log1p(-factor).sum(axis=0)  # log Π_c [1 − γ conf_c |ĥ_c − h_c(s)|]  (PMFS score)

    def _propose(self, obs: Observation):
        r, c = obs.cell
        flat = r * self.geometry.shape[1] + c
        wind = obs.wind if obs.wind is not None else tuple(self.model.wind[r, c])
        hitmap = self._hitmap.copy()
        hitmap.observe((r, c), obs.hit, wind)
        k = len(self._cells)
        new = flat not in self._slot
        if new:
            if k == self._pred.shape[0]:
                self._pred = np.concatenate([self._pred, np.empty_like(self._pred)])  # grow (amortised)
            self._pred[k] = -np.expm1(-self.model.encounter_scale * self.model.green_rows([flat])[0])  # h_c(s)
        cells = self._cells + [flat] if new else self._cells
        h_obs = hitmap.hit_probability.ravel()[cells]  # ĥ_c
        conf = hitmap.confidence.ravel()[cells]  # conf_c
        # only the compared cells within the reading's kernel change: update the score by their difference
        changed = np.flatnonzero((h_obs[:k] != self._h_used) | (conf[:k] != self._conf_used))
        score = self._score.copy()
        if changed.size:
            score -= self._log_factors(changed, self._h_used[changed], self._conf_used[changed])
            score += self._log_factors(changed, h_obs[changed], conf[changed])
        if new:
            score += self._log_factors(np.array([k]), h_obs[k:], conf[k:])
        return self.tempering * score, (hitmap, new, flat, score, h_obs, conf)

    def _accept(self, obs: Observation, payload) -> None:
        hitmap, new, flat, score, h_obs, conf = payload
        self._hitmap = hitmap
        self._score = score
        self._h_used, self._conf_used = h_obs, conf
        self._tables = None  # the hit map moved: the current factors change
        if new:
            self._slot[flat] = len(self._cells)
            self._cells.append(flat)
            self._new_rows.pop(flat, None)

    def reading_log_ratio(self, positions) -> np.ndarray:
        r"""How one more reading would move the posterior: :math:`\lambda [S'(s) - S(s)]` for a miss and for a hit
        at each position.

        With :math:`S(s) = \sum_c \log\big[1 - \gamma\, \mathrm{conf}_c\, |\hat h_c - h_c(s)|\big]` the current
        score and :math:`S'_g(s)` the score after one reading :math:`g \in \{\text{miss}, \text{hit}\}` at x (the
        hit map updated by its kernel, x added to the compared cells if new), :meth:`update` turns
        :math:`p(s \mid g)` into

        .. math:: p(s \mid g, g_x) \propto p(s \mid g)\, L_g(s), \qquad L_g = e^{\lambda [S'_g - S]}

        This is the estimator's own update, written as a factor on the current posterior (the "not found" factors and a
        fused semantic term multiply both sides alike). For a Bayesian estimator :math:`L_g(s)` would be
        :math:`P(g \mid s)`; for PMFS it is the pseudo-likelihood the recomputed score implies, which is what the closed
        loop must expect a reading to do (the policies of :mod:`psgsl_pgm.search`). The kernel is oriented by the
        model's wind at x (the wind the reading will bring is not known before it); the state is not changed.

        Only the compared cells within the kernel's reach change, so the cost is two logs (miss, hit) per free
        cell for each of them and for x itself; their current factors are computed once per state of the
        estimator and shared by every position (:class:`_RatioTables`), and the kernels and the rows h_x(s) of
        cells not compared yet are cached per cell until the plume model changes.

        Parameters
        ----------
        positions : (n, 2) array_like of float
            Sensor positions (x, y) in metres (free cells).

        Returns
        -------
        log_ratio : (n, 2, H, W) ndarray of float64
            [:, 0] for a miss, [:, 1] for a hit; −inf nowhere (every PMFS factor is ≥ 1 − γ > 0), 0 on cells that
            are not free (their posterior is 0 anyway).
        """
        cells = self._flat_cells(positions)
        n = self.geometry.shape[0] * self.geometry.shape[1]
        out = np.zeros((len(cells), 2, n))
        hm = self._hitmap
        m0, p0, n0 = hm.prior_strength, hm.prior_hit, hm.confidence_scale
        gamma, lam = self.discrimination, self.tempering
        compared = np.asarray(self._cells, dtype=np.int64)
        if self._kernel_model is not self.model:
            self._kernels.clear()
            self._new_rows.clear()
            self._kernel_model = self.model
        tables = self._ratio_tables(compared)
        buf = np.empty(n)  # one row of factors at a time (no (m, H·W) temporaries)
        rows_of = self._new_rows  # least recently asked first
        missing = list(dict.fromkeys(f for f in cells.tolist() if f not in self._slot and f not in rows_of))
        for f in cells.tolist():
            if f in rows_of:
                rows_of.move_to_end(f)
        if missing:  # the rows h_x(s) of new cells: their adjoint solves together (the same numbers per column)
            for f, g_row in zip(missing, self.model.green_rows(missing)):
                rows_of[f] = _NewCellRows(-np.expm1(-self.model.encounter_scale * g_row))
        while len(rows_of) > max(2 * len(cells), 64):  # this call's cells and about as many more
            rows_of.popitem(last=False)
        # λ [Σ_c log(1 − γ conf'_c |ĥ'_c − h_c(s)|) − Σ_c log(1 − γ conf_c |ĥ_c − h_c(s)|)] over the compared cells
        # c in x's kernel (and x), each sum accumulated row by row from 0 in slot order, x last: the additions of
        # numpy's sum over the first axis of the stacked rows (for more than one column; a map of one cell has
        # at most two rows, which numpy's pairwise sum also adds in order)
        for k, flat in enumerate(cells.tolist()):
            w = self._kernels.get(flat)
            if w is None:
                r, c = divmod(flat, self.geometry.shape[1])
                w = self._kernels[flat] = hm.kernel((r, c), tuple(self.model.wind[r, c]))
            slots = np.flatnonzero(w[compared] > 0) if compared.size else np.zeros(0, np.int64)
            new = flat not in self._slot
            if not slots.size and not new:
                continue  # no factor changes: λ (0 − 0) = 0
            at = compared[slots]
            if new:  # x joins the compared cells with its own row h_x(s)
                at = np.append(at, flat)
                x_rows = self._new_rows[flat]
            weight = hm._weight[at]
            weight_new = weight + w[at]
            conf_new = -np.expm1(-weight_new / n0)
            old = tables.old_sum(slots, new) if slots.size else None  # Σ of the current factors (0 without any)
            coef = -gamma * conf_new[: slots.size]  # −γ conf'_c
            for g in (0, 1):
                h_new = (p0 * m0 + hm._hits[at] + g * w[at]) / (m0 + weight_new)
                dst = out[k, g]
                if new and not slots.size:  # x's own factor alone: λ [(0 + x's factor) − 0]
                    dst += x_rows.factor(g, h_new[-1], conf_new[-1], gamma)
                    dst -= 0.0
                    dst *= lam
                    continue
                for i, slot in enumerate(slots.tolist()):  # log1p(−γ conf'_c abs(ĥ'_c − h_c(s))), one row at a time
                    np.subtract(h_new[i], self._pred[slot], out=buf)
                    np.abs(buf, out=buf)
                    np.multiply(coef[i], buf, out=buf)
                    np.log1p(buf, out=buf)
                    dst += buf
                if new:
                    dst += x_rows.factor(g, h_new[-1], conf_new[-1], gamma)
                dst -= old
                dst *= lam
        out[:, :, ~self.geometry.free.ravel()] = 0.0
        return out.reshape((len(cells), 2) + self.geometry.shape)

    def _ratio_tables(self, compared: np.ndarray) -> "_RatioTables":
        """The :class:`_RatioTables` of the current hit map, compared cells and plume model (built once per state)."""
        t = self._tables
        if t is None or t.model is not self.model or t.hitmap is not self._hitmap or t.n_compared != compared.size:
            t = self._tables = _RatioTables(self, compared)
        return t

    @property
    def score(self) -> np.ndarray:
        r"""(H, W) the untempered PMFS score :math:`\sum_c \log\big[1 - \gamma\, \mathrm{conf}_c\,
        |\hat h_c - h_c(s)|\big]` of every candidate s (a copy)."""
        return self._score.reshape(self.geometry.shape).copy()

    @property
    def hit_map(self) -> HitProbabilityMap:
        """The current :class:`HitProbabilityMap` (ĥ and confidence)."""
        return self._hitmap

    @property
    def compared_cells(self) -> np.ndarray:
        """(K, 2) int64 (row, col) of the cells whose hit estimates enter the score."""
        return np.array([divmod(f, self.geometry.shape[1]) for f in self._cells], dtype=np.int64).reshape(-1, 2)


class _RatioTables:
    """What :meth:`PMFSEstimator.reading_log_ratio` shares between candidate positions in one state of the
    estimator: the current factor of each compared cell c, log[1 − γ conf_c abs(ĥ_c − h_c(s))] for every s. It
    does not depend on the candidate; its row is computed the first time a candidate's kernel reaches c, with
    the same floating-point operations per element as a candidate's own rows, and reused.

    Parameters
    ----------
    est : PMFSEstimator
        The estimator, in the state the tables describe.
    compared : (K,) ndarray of int64
        Flat indices of its compared cells, in slot order.
    """

    __slots__ = ("model", "hitmap", "n_compared", "_est", "_compared", "_old", "_done")

    def __init__(self, est: PMFSEstimator, compared: np.ndarray):
        self.model, self.hitmap, self.n_compared = est.model, est._hitmap, compared.size
        self._est, self._compared = est, compared
        self._old = np.empty((compared.size, est.geometry.shape[0] * est.geometry.shape[1]))
        self._done = np.zeros(compared.size, bool)

    def old_sum(self, slots: np.ndarray, new: bool) -> np.ndarray:
        """(H·W,) the sum of the current factors of ``slots``, a zero row added last when ``new``: the rows added
        one by one to 0 in slot order, as numpy sums the stacked rows over their first axis (a new array)."""
        todo = slots[~self._done[slots]]
        if todo.size:
            est, hm = self._est, self.hitmap
            m0, p0, n0 = hm.prior_strength, hm.prior_hit, hm.confidence_scale
            at = self._compared[todo]
            weight = hm._weight[at]
            h_old = (p0 * m0 + hm._hits[at]) / (m0 + weight)
            conf_old = -np.expm1(-weight / n0)
            rows = est._pred[todo]
            self._old[todo] = np.log1p(-est.discrimination * conf_old[:, None] * np.abs(h_old[:, None] - rows))
            self._done[todo] = True
        acc = np.zeros(self._old.shape[1])
        for s in slots.tolist():
            acc += self._old[s]
        if new:
            acc += 0.0
        return acc


class _NewCellRows:
    """A cell x not compared yet, for :meth:`PMFSEstimator.reading_log_ratio`: its row h_x(s) and the factor rows
    log[1 − γ conf_x abs(ĥ_x − h_x(s))] of a miss and of a hit there, kept with the ĥ_x, conf_x (and γ) they
    were computed for: while the hit map at x does not move, a later state asks for the same numbers (the same
    operations on the same inputs) and gets them without a log. The estimator keeps these for the cells of its
    last calls only (least recently asked dropped first).

    Parameters
    ----------
    row : (H·W,) ndarray of float64
        h_x(s) = 1 − exp(−κ G(x | s)).
    """

    __slots__ = ("row", "_key", "_factor")

    def __init__(self, row: np.ndarray):
        self.row = row
        self._key: list = [None, None]  # per outcome g: (ĥ_x, conf_x, γ) of the cached factor
        self._factor: list = [None, None]

    def factor(self, g: int, h: float, conf: float, discrimination: float) -> np.ndarray:
        """(H·W,) log[1 − γ conf abs(h − h_x(s))] for outcome ``g`` (cached; do not modify)."""
        key = (float(h), float(conf), float(discrimination))
        if self._key[g] != key:
            self._factor[g] = np.log1p(-discrimination * np.float64(conf) * np.abs(np.float64(h) - self.row))
            self._key[g] = key
        return self._factor[g]
