"""Calibration of the hit model from readings around known sources: maximum-likelihood (D, τ, κ), and the
tempering from the residuals' autocorrelation."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize

from .._shared._validate import as_array, as_float_array, describe, positive, unit_interval
from ._plume import PlumeModel

__all__ = ["CalibrationRun", "PlumeFit", "ar1_tempering", "encounter_scale_mle", "fit_encounter_scale", "fit_hit_model",
           "fit_plume_parameters", "hit_log_likelihood", "hit_residuals", "mixture_weights", "profile_log_likelihood",
           "score_tempering"]


def fit_encounter_scale(model: PlumeModel, positions, hits, source, *, false_hit_rate: float = 0.0) -> float:
    """κ maximising Π_k P(g_k | s; κ) for readings g_k at ``positions`` around a *known* source.

    With c_k = G(x_k | s) from ``model`` and P(hit) = ε + (1 − ε)(1 − exp(−κ c_k)), the log-likelihood is
    concave in κ (log of a positive concave function, plus a linear term for misses), so the maximiser is the
    unique root of its derivative,

        Σ_hits (1 − ε) c_k e^{−κ c_k} / (ε + (1 − ε)(1 − e^{−κ c_k})) − Σ_misses c_k = 0,

    found with Brent's method on log κ. Use it on calibration runs of the simulator (source known), not on the
    evaluation runs. The model's own ``encounter_scale`` is ignored.

    Parameters
    ----------
    model : PlumeModel
    positions : (n, 2) array_like of float
        Sensor positions (x, y) in metres.
    hits : (n,) array_like of bool
        Readings.
    source : (2,) array_like of float
        Known source position in metres.
    false_hit_rate : float, default 0.0
        ε ∈ [0, 1).

    Returns
    -------
    kappa : float
        m²/s.

    Raises
    ------
    ValueError
        If the likelihood has no finite maximiser: no hit where the model predicts gas (κ → 0), or no miss
        where it does (κ → ∞).

    Examples
    --------
    The corridor of :func:`profile_log_likelihood`: readings near the source (at its west end, the wind blowing
    east) hit, far ones miss:

    >>> import numpy as np
    >>> from psgsl_pgm.olfaction import PlumeModel, fit_encounter_scale
    >>> model = PlumeModel(np.zeros((3, 40), bool), resolution=0.25, wind=np.tile([0.2, 0.0], (3, 40, 1)),
    ...                    diffusivity=0.01, lifetime=30.0)
    >>> x = np.arange(0.6, 10.0, 0.5)
    >>> kappa = fit_encounter_scale(model, np.c_[x, np.full(x.size, 0.4)], x < 4.0, (0.4, 0.4), false_hit_rate=0.01)
    >>> round(kappa, 4)
    0.153
    """
    if not isinstance(model, PlumeModel):
        raise TypeError(f"model must be a PlumeModel, got {type(model).__name__}")
    pos = as_float_array(positions, "positions", dtype=np.float64, ndim=2)
    if pos.shape[1] != 2 or not np.isfinite(pos).all():
        raise ValueError(f"positions must be (n, 2) finite positions (x, y in metres), got {describe(pos)}")
    g = _hits(hits, (len(pos),), "positions")
    eps = unit_interval(false_hit_rate, "false_hit_rate", high_open=True)
    field = model.concentration(source)
    cells = np.array([model.cell_of(p, "positions[i]") for p in pos], dtype=np.int64).reshape(-1, 2)
    return encounter_scale_mle(field[cells[:, 0], cells[:, 1]], g, false_hit_rate=eps)


def encounter_scale_mle(predicted, hits, *, false_hit_rate: float = 0.0) -> float:
    """κ maximising Π_k P(g_k; κ c_k) given predicted Green's-function values c_k = G(x_k | s_k).

    The maximiser of :func:`fit_encounter_scale` for readings whose predictions are already known — e.g. pooled
    over several calibration runs with different sources and maps.

    Parameters
    ----------
    predicted : (n,) array_like of float
        c_k ≥ 0, s/m² (``PlumeModel.concentration(source)`` at each sensor cell).
    hits : (n,) array_like of bool
    false_hit_rate : float, keyword-only
        ε ∈ [0, 1).

    Raises
    ------
    ValueError
        ``predicted`` is not (n,) finite and non-negative; ``hits`` is not (n,) bool; ``false_hit_rate`` is not in
        [0, 1); or the likelihood has no finite positive maximiser (no hit, or no miss, where gas is predicted; false
        hits alone explain the hits; no float64 scale fits).

    Examples
    --------
    >>> import numpy as np
    >>> k = encounter_scale_mle([1.0, 1.0, 1.0, 1.0], [True, False, False, False])
    >>> bool(abs(k - -np.log(0.75)) < 1e-12)          # 1 − exp(−κ) = 1/4: a quarter of the readings hit
    True
    """
    c = as_float_array(predicted, "predicted", dtype=np.float64)
    if c.ndim != 1 or not np.isfinite(c).all() or (c < 0).any():
        raise ValueError(f"predicted must be a (n,) array of finite non-negative values, got shape {c.shape}")
    g = _hits(hits, c.shape, "predicted")
    eps = unit_interval(false_hit_rate, "false_hit_rate", high_open=True)
    c_hit, c_miss = c[g & (c > 0)], c[~g]
    if c_hit.size == 0:
        raise ValueError("hits: no hit where the model predicts gas from this source (predicted > 0): the maximum-likelihood encounter scale is 0")
    with np.errstate(over="ignore"):
        miss_sum = float(c_miss.sum())
    if not miss_sum > 0:
        raise ValueError("hits: no miss where the model predicts gas from this source (predicted > 0): the maximum-likelihood encounter scale is ∞")
    root = _log_scale_root(c_hit, miss_sum, eps) if math.isfinite(miss_sum) else "rescale"
    if not isinstance(root, str):
        return float(np.exp(root))
    # out of the bracket e^±700, or sums beyond float64: the same fit on predicted / its largest hit (κ c is
    # what the likelihood sees), the scale divided back
    scale = float(c_hit.max())
    with np.errstate(over="ignore"):
        root = _log_scale_root(c_hit / scale, float(np.sum(c_miss / scale)), eps)
    if root == "zero":
        raise ValueError("predicted, hits and false_hit_rate: false hits alone explain the hits (the maximum-likelihood "
                         "encounter scale is 0)")
    with np.errstate(over="ignore"):
        kappa = np.exp(root) / scale if not isinstance(root, str) else math.inf
    if not (math.isfinite(kappa) and kappa > 0):
        raise ValueError(f"predicted: no float64 encounter scale explains these readings (predicted values where gas "
                         f"was hit are at most {scale:.3g}, where it was not {float(c_miss.max(initial=0.0)):.3g}); "
                         "give predicted in other units")
    return float(kappa)


def _log_scale_root(c_hit: np.ndarray, miss_sum: float, eps: float):
    """log κ where d log L / dκ = 0, bracketed within [-705, 705] and found with Brent's method; ``"zero"`` where
    the score is still ≤ 0 at κ = e^-705 (the maximum is at 0 or below the bracket), ``"large"`` where it is still
    ≥ 0 at κ = e^705."""

    def score(log_kappa: float) -> float:
        kappa = np.exp(log_kappa)
        with np.errstate(over="ignore"):  # κ c beyond float64: e = 0 and P(hit) = 1, the right limits
            x = -kappa * c_hit
        e = np.exp(x)
        p_hit = eps + (1.0 - eps) * -np.expm1(x)  # P(hit | s)
        # (1 − ε) c e / P(hit), whose limit where ε = 0 and κ c underflows to 0 is 1 / κ
        terms = np.divide((1.0 - eps) * c_hit * e, p_hit, out=np.full(c_hit.shape, 1.0 / kappa), where=p_hit > 0)
        return float(np.sum(terms) - miss_sum)  # d log L / dκ

    lo, hi = -5.0, 5.0
    while score(lo) <= 0:
        lo -= 10.0
        if lo < -700:
            return "zero"
    while score(hi) >= 0:
        hi += 10.0
        if hi > 700:
            return "large"
    return brentq(score, lo, hi, xtol=1e-13, rtol=1e-13)


def _hits(hits, shape: tuple, like: str) -> np.ndarray:
    """Readings as a bool array of ``shape`` (booleans, or integers 0/1), shaped like argument ``like``."""
    g = as_array(hits, "hits", "booleans (or 0/1)")
    if g.dtype != bool and not (np.issubdtype(g.dtype, np.integer) and np.isin(g, (0, 1)).all()):
        raise TypeError(f"hits must be booleans (or 0/1), got dtype {g.dtype}")
    g = g.astype(bool)
    if g.shape != shape:
        raise ValueError(f"hits must have shape {shape} like {like}, got {g.shape}")
    return g


@dataclass(frozen=True, eq=False)
class CalibrationRun:
    """The readings of one calibration run with a known source, and what the robot knew of the flow.

    Attributes
    ----------
    model : PlumeModel
        The map, outlets and the *estimated* mean wind of the run (its ``diffusivity``, ``lifetime`` and
        ``encounter_scale`` are ignored: the fit replaces them).
    source : (2,) tuple of float
        The known source position, metres.
    positions : (n, 2) ndarray of float
        Sensor positions of the readings, in the order taken.
    hits : (n,) ndarray of bool
    winds : (n, 2) ndarray of float or None
        The anemometer readings (u_x, u_y) m/s taken with them, if kept.
    """

    model: PlumeModel
    source: tuple
    positions: np.ndarray
    hits: np.ndarray
    winds: np.ndarray | None = None

    def __post_init__(self):
        if not isinstance(self.model, PlumeModel):
            raise TypeError(f"model must be a PlumeModel, got {type(self.model).__name__}")
        pos = as_float_array(self.positions, "positions", dtype=np.float64, ndim=2)
        if pos.shape[1] != 2 or not np.isfinite(pos).all():
            raise ValueError(f"positions must be (n, 2) finite positions (x, y in metres), got {describe(pos)}")
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "hits", _hits(self.hits, (len(pos),), "positions"))
        object.__setattr__(self, "source", tuple(float(v) for v in self.source))
        if self.winds is not None:
            w = as_float_array(self.winds, "winds", dtype=np.float64, ndim=2)
            if w.shape != pos.shape or not np.isfinite(w).all():
                raise ValueError(f"winds must be (n, 2) finite (u_x, u_y) like positions {pos.shape}, got {describe(w)}")
            object.__setattr__(self, "winds", w)
        cells = np.array([self.model.cell_of(p, "positions[i]") for p in pos], dtype=np.int64).reshape(-1, 2)
        object.__setattr__(self, "_cells", cells)

    def predicted(self, diffusivity: float, lifetime: float) -> np.ndarray:
        """(n,) c_n = G(x_n | s_true) under (D, τ) on this run's map and wind (one factorisation, one solve)."""
        m = self.model
        model = PlumeModel(m.geometry.occupancy, resolution=m.geometry.resolution, origin=m.geometry.origin,
                           wind=m.wind, outlets=m.outlets, diffusivity=diffusivity, lifetime=lifetime,
                           boundary=m.boundary, scheme=m.scheme, cache_size=0)
        field = model.concentration(self.source)
        return field[self._cells[:, 0], self._cells[:, 1]]


def hit_log_likelihood(predicted, hits, encounter_scale: float, false_hit_rate: float,
                       missed_hit_rate: float = 0.0) -> float:
    """The log-likelihood of gas readings under the hit model of :class:`GridInfotaxis`.

    Σ_n log P(g_n) with P(hit) = ε + (1 − ε)(1 − δ)(1 − exp(−κ c_n)) and
    P(miss) = (1 − ε)[δ + (1 − δ) exp(−κ c_n)].

    Parameters
    ----------
    predicted : (n,) array_like of float
        c_n, the plume model's mean concentration per unit emission at each reading (s/m², >= 0):
        :meth:`CalibrationRun.predicted`.
    hits : (n,) array_like of bool
        g_n, whether each reading was a hit (booleans or 0/1).
    encounter_scale : float
        κ, m²/s (>= 0): κ c_n is the expected number of encounters of the reading.
    false_hit_rate : float
        ε in [0, 1): the probability of a hit from no gas.
    missed_hit_rate : float, default 0.0
        δ in [0, 1): the probability that a reading misses the plume whatever the model predicts.

    Returns
    -------
    log_likelihood : float
        In nats; −inf when a hit is impossible under the model (ε = 0 and κ c_n = 0).

    Raises
    ------
    TypeError
        ``hits`` is not boolean (or 0/1), or a rate or κ is not a real number.
    ValueError
        ``predicted`` is not a 1-D array of finite non-negative values, ``hits`` has another shape, κ is negative,
        or a rate lies outside [0, 1).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.olfaction import hit_log_likelihood
    >>> ll = hit_log_likelihood([1.0, 1.0], [True, False], 0.5, 0.0)    # one hit, one miss, P(hit) = 1 − e^(−0.5)
    >>> bool(np.isclose(ll, np.log(1 - np.exp(-0.5)) - 0.5))
    True
    """
    c = as_float_array(predicted, "predicted", dtype=np.float64)
    if c.ndim != 1 or not np.isfinite(c).all() or (c < 0).any():
        raise ValueError(f"predicted must be a (n,) array of finite non-negative values, got shape {c.shape}")
    g = _hits(hits, c.shape, "predicted")
    encounter_scale = positive(encounter_scale, "encounter_scale", "m²/s", allow_zero=True)
    false_hit_rate = unit_interval(false_hit_rate, "false_hit_rate", high_open=True)
    missed_hit_rate = unit_interval(missed_hit_rate, "missed_hit_rate", high_open=True)
    mu = encounter_scale * c
    if missed_hit_rate == 0.0:
        with np.errstate(divide="ignore"):
            ll_hit = np.log(-np.expm1(-mu) + false_hit_rate * np.exp(-mu))
        ll_miss = np.log1p(-false_hit_rate) - mu
    else:
        ll_hit, ll_miss = _hit_model_terms(mu, false_hit_rate, missed_hit_rate)[:2]
    return float(np.where(g, ll_hit, ll_miss).sum())


def _hit_model_terms(mu, eps: float, delta: float):
    """Per reading: log P(hit), log P(miss) and their derivatives in log κ and in δ, for μ = κ c (n,)."""
    e = np.exp(-mu)
    one_minus_e = -np.expm1(-mu)
    p_hit = eps + (1.0 - eps) * (1.0 - delta) * one_minus_e  # P(hit) ≥ ε
    with np.errstate(divide="ignore"):
        ll_hit = np.log(p_hit)
        log_q = np.logaddexp(np.log(delta) if delta > 0 else -np.inf, np.log1p(-delta) - mu)  # q = δ + (1 − δ)e^{−μ}
    ll_miss = np.log1p(-eps) + log_q
    with np.errstate(divide="ignore", invalid="ignore"):
        d_hit_k = np.where(p_hit > 0, (1.0 - eps) * (1.0 - delta) * mu * e / p_hit, 0.0)
        d_hit_d = np.where(p_hit > 0, -(1.0 - eps) * one_minus_e / p_hit, 0.0)
        w = np.exp(np.log1p(-delta) - mu - log_q)  # (1 − δ)e^{−μ} / q ∈ [0, 1]
        d_miss_k = -mu * w
        d_miss_d = np.exp(np.minimum(np.log(one_minus_e) - log_q, 700.0))  # (1 − e^{−μ}) / q
    return ll_hit, ll_miss, d_hit_k, d_miss_k, d_hit_d, d_miss_d


def fit_hit_model(predicted, hits, *, false_hit_rate: float = 0.0) -> tuple:
    """Maximum-likelihood (κ, δ) of the hit model for readings with predicted c_k = G(x_k | s_k).

    P(hit) = ε + (1 − ε)(1 − δ)(1 − e^{−κc}) and P(miss) = (1 − ε)[δ + (1 − δ)e^{−κc}] (:class:`GridInfotaxis`
    with ``missed_hit_rate`` δ). With δ the log-likelihood is no longer concave in κ (a miss term is the log of a
    sum of exponentials), so the maximum is searched by L-BFGS-B on (log κ, δ), δ ∈ [0, 1 − 10⁻⁹], with the
    analytic gradient, from (κ̂₀, 0) — κ̂₀ the maximiser with δ = 0 (:func:`encounter_scale_mle`) — and from
    (κ̂₀, 0.05); the better of the two, and never worse than (κ̂₀, 0), is returned. δ̂ = 0 exactly, with κ̂ = κ̂₀,
    when the boundary is the maximum: no miss is more surprising than the model with δ = 0 can afford.

    Parameters
    ----------
    predicted : (n,) array_like of float
        c_k ≥ 0, s/m².
    hits : (n,) array_like of bool
    false_hit_rate : float, keyword-only
        ε ∈ [0, 1), held fixed.

    Returns
    -------
    (kappa, delta, log_likelihood) : tuple of float
        κ̂ (m²/s), δ̂ and the maximised Σ_k log P(g_k) (nats).

    Raises
    ------
    ValueError
        ``predicted`` is not (n,) finite and non-negative, ``hits`` is not (n,) bool, ``false_hit_rate`` is not
        in [0, 1), or no finite κ fits with δ = 0 (see :func:`encounter_scale_mle`).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> c = rng.uniform(0, 5, 4000)
    >>> p_hit = 0.01 + 0.99 * 0.9 * (1 - np.exp(-0.8 * c))   # κ = 0.8, δ = 0.1, ε = 0.01
    >>> kappa, delta, _ = fit_hit_model(c, rng.random(4000) < p_hit, false_hit_rate=0.01)
    >>> bool(abs(kappa - 0.8) < 0.1), bool(abs(delta - 0.1) < 0.03)
    (True, True)
    """
    c = as_float_array(predicted, "predicted", dtype=np.float64, ndim=1)
    if not (np.isfinite(c).all() and (c >= 0).all()):
        raise ValueError(f"predicted must be finite and >= 0, got {describe(c)}")
    g = _hits(hits, c.shape, "predicted")
    eps = unit_interval(false_hit_rate, "false_hit_rate", high_open=True)
    kappa0 = encounter_scale_mle(c, g, false_hit_rate=eps)

    def nll(x):
        kappa, delta = math.exp(x[0]), float(x[1])
        ll_hit, ll_miss, dhk, dmk, dhd, dmd = _hit_model_terms(kappa * c, eps, delta)
        value = -float(np.where(g, ll_hit, ll_miss).sum())
        grad = -np.array([np.where(g, dhk, dmk).sum(), np.where(g, dhd, dmd).sum()])
        return value, grad

    bounds = [(math.log(kappa0) - 20.0, math.log(kappa0) + 20.0), (0.0, 1.0 - 1e-9)]
    best = (math.log(kappa0), 0.0)
    best_value = nll(best)[0]
    for start in (best, (math.log(kappa0), 0.05)):
        res = minimize(nll, np.array(start), jac=True, method="L-BFGS-B", bounds=bounds,
                       options={"ftol": 1e-15, "gtol": 1e-10, "maxiter": 500})
        if res.x[1] == 0.0:  # on the boundary δ = 0, where κ̂₀ is the exact maximiser (a root, not an iterate)
            continue
        if np.isfinite(res.fun) and res.fun < best_value:
            best, best_value = (float(res.x[0]), float(res.x[1])), float(res.fun)
    return math.exp(best[0]), best[1], -best_value


@dataclass(frozen=True)
class PlumeFit:
    """Maximum-likelihood plume parameters (D m²/s, τ s, κ m²/s), the maximised log-likelihood (nats) and the
    missed-hit rate δ of the hit model (0 unless fitted: :func:`fit_plume_parameters` with
    ``fit_missed_hits=True``)."""

    diffusivity: float
    lifetime: float
    encounter_scale: float
    log_likelihood: float
    missed_hit_rate: float = 0.0


def profile_log_likelihood(runs, diffusivity: float, lifetime: float, *, false_hit_rate: float = 0.0):
    """max_κ log L(D, τ, κ) over all readings of ``runs``: returns ``(κ̂, log L)``.

    κ enters the likelihood only through κ c_n, and for fixed (D, τ) the maximiser is the unique root of a
    monotone score (:func:`encounter_scale_mle`), so the profile over κ is exact.

    Parameters
    ----------
    runs : sequence of CalibrationRun
        Calibration runs with known sources; their readings are pooled.
    diffusivity : float
        D, m²/s (> 0), of the plume model the readings are predicted with.
    lifetime : float
        τ, s (> 0).
    false_hit_rate : float, default 0.0, keyword-only
        ε in [0, 1).

    Returns
    -------
    kappa : float
        κ̂, the maximum-likelihood encounter scale at (D, τ), m²/s.
    log_likelihood : float
        The maximised log-likelihood, nats (:func:`hit_log_likelihood` at κ̂).

    Raises
    ------
    ValueError
        The pooled readings hold no hit, or no miss, where the model predicts gas from the source (κ̂ would be 0 or
        infinite), false hits alone explain the hits, D or τ is not positive, or ε lies outside [0, 1).

    Examples
    --------
    A corridor run, 10 m of free cells, the source at its west end and the wind blowing east: readings near the
    source hit, far ones miss.

    >>> import numpy as np
    >>> from psgsl_pgm.olfaction import CalibrationRun, PlumeModel, profile_log_likelihood
    >>> model = PlumeModel(np.zeros((3, 40), bool), resolution=0.25, wind=np.tile([0.2, 0.0], (3, 40, 1)),
    ...                    diffusivity=0.01, lifetime=30.0)
    >>> x = np.arange(0.6, 10.0, 0.5)
    >>> run = CalibrationRun(model, (0.4, 0.4), np.c_[x, np.full(x.size, 0.4)], x < 4.0)
    >>> kappa, ll = profile_log_likelihood([run], 0.01, 30.0, false_hit_rate=0.01)
    >>> bool(kappa > 0 and ll < 0)
    True
    """
    c = np.concatenate([r.predicted(diffusivity, lifetime) for r in runs])
    g = np.concatenate([r.hits for r in runs])
    kappa = encounter_scale_mle(c, g, false_hit_rate=false_hit_rate)
    return kappa, hit_log_likelihood(c, g, kappa, false_hit_rate)


def fit_plume_parameters(runs, *, false_hit_rate: float = 0.0, diffusivities=(0.003, 0.01, 0.03, 0.1, 0.3),
                         lifetimes=(3.0, 10.0, 30.0, 100.0, 300.0, 1000.0), refine: bool = True,
                         fit_missed_hits: bool = False) -> PlumeFit:
    """Maximum-likelihood (D, τ, κ) of the hit model on calibration runs with known sources.

    The likelihood is Π_n P(g_n | s_true; D, τ, κ) with P(hit) = ε + (1 − ε)(1 − exp(−κ G_{D,τ}(x_n | s_true)))
    (the hit model of :class:`GridInfotaxis`), G from the advection-diffusion-decay plume on each run's map with
    the run's *estimated* mean wind. κ is profiled out exactly (:func:`profile_log_likelihood`); (D, τ) are
    searched on the log grid ``diffusivities`` × ``lifetimes`` and the best grid point is refined by
    Nelder–Mead on (log D, log τ) (``refine``). One sparse LU factorisation and one forward solve per run and
    (D, τ).

    This is the one (D, τ, κ) that fits the pooled readings best. Pooled over hundreds of readings the profile
    likelihood is sharply peaked, but that sharpness is about the population average, not about any one run:
    fitted run by run, the parameters vary (D about three times smaller for a source in a corridor's fast
    flow, κ fourfold between runs). :class:`GridInfotaxis` therefore marginalises over a grid of (D, τ, κ)
    around this fit with population weights from :func:`mixture_weights` (``parameter_grid``); PMFS and the
    residual tempering (:func:`ar1_tempering`) use the point estimate.

    With ``fit_missed_hits`` the missed-hit rate δ of :class:`GridInfotaxis` is fitted too: at each (D, τ),
    (κ, δ) jointly by :func:`fit_hit_model` instead of κ alone — the profile over (κ, δ), with the same search over
    (D, τ).

    Parameters
    ----------
    runs : sequence of CalibrationRun
    false_hit_rate : float, keyword-only
        ε ∈ [0, 1), held fixed.
    diffusivities, lifetimes : sequence of float, keyword-only
        The starting grid, m²/s and s (positive).
    refine : bool, keyword-only
    fit_missed_hits : bool, keyword-only
        Fit δ as well (default: δ = 0, the hit model without missed hits).

    Returns
    -------
    PlumeFit

    Raises
    ------
    TypeError
        ``runs`` is empty or holds something other than :class:`CalibrationRun`, or ``fit_missed_hits`` is not a
        bool.
    ValueError
        ``false_hit_rate`` is not in [0, 1), or the grids are empty or hold a value that is not positive.

    Examples
    --------
    One calibration run in a corridor (the source at its west end, the wind blowing east), on a 2 x 2 grid of
    (D, τ) without the Nelder–Mead refinement:

    >>> import numpy as np
    >>> from psgsl_pgm.olfaction import CalibrationRun, PlumeModel, fit_plume_parameters
    >>> model = PlumeModel(np.zeros((3, 40), bool), resolution=0.25, wind=np.tile([0.2, 0.0], (3, 40, 1)),
    ...                    diffusivity=0.01, lifetime=30.0)
    >>> x = np.arange(0.6, 10.0, 0.5)
    >>> run = CalibrationRun(model, (0.4, 0.4), np.c_[x, np.full(x.size, 0.4)], x < 4.0)
    >>> fit = fit_plume_parameters([run], false_hit_rate=0.01, diffusivities=(0.01, 0.1), lifetimes=(10.0, 100.0),
    ...                            refine=False)
    >>> round(fit.diffusivity, 3), round(fit.lifetime, 1), round(fit.encounter_scale, 3)
    (0.01, 10.0, 0.571)
    """
    runs = list(runs)
    if not runs or not all(isinstance(r, CalibrationRun) for r in runs):
        raise TypeError("runs must be a non-empty sequence of CalibrationRun")
    eps = unit_interval(false_hit_rate, "false_hit_rate", high_open=True)
    ds = [positive(v, "diffusivities[i]", "m²/s") for v in diffusivities]
    ts = [positive(v, "lifetimes[i]", "s") for v in lifetimes]
    if not ds or not ts:
        raise ValueError("diffusivities and lifetimes must each hold at least one value")
    if not isinstance(fit_missed_hits, (bool, np.bool_)):
        raise TypeError(f"fit_missed_hits must be a bool, got {type(fit_missed_hits).__name__}")
    table = {}
    hits = np.concatenate([r.hits for r in runs])

    def profile(d, tau):  # (κ̂, log L, δ̂) at (D, τ)
        if not fit_missed_hits:
            return profile_log_likelihood(runs, d, tau, false_hit_rate=eps) + (0.0,)
        c = np.concatenate([r.predicted(d, tau) for r in runs])
        kappa, delta, ll = fit_hit_model(c, hits, false_hit_rate=eps)
        return kappa, ll, delta

    def nll(x):
        key = (round(float(x[0]), 12), round(float(x[1]), 12))
        if key not in table:
            try:
                table[key] = profile(float(np.exp(x[0])), float(np.exp(x[1])))
            except ValueError:  # no finite κ̂ (no hit where gas is predicted): the worst fit
                table[key] = (math.nan, -math.inf, math.nan)
        return -table[key][1]

    starts = [(math.log(d), math.log(t)) for d in ds for t in ts]
    best = min(starts, key=nll)
    if refine:
        res = minimize(nll, np.array(best), method="Nelder-Mead",
                       options={"xatol": 1e-3, "fatol": 1e-4, "maxiter": 200, "initial_simplex":
                                np.array(best) + np.array([[0.0, 0.0], [0.3, 0.0], [0.0, 0.3]])})
        best = tuple(res.x) if -res.fun >= -nll(best) else best
    kappa, ll, delta = table[(round(float(best[0]), 12), round(float(best[1]), 12))]
    return PlumeFit(float(np.exp(best[0])), float(np.exp(best[1])), float(kappa), float(ll), float(delta))


def hit_residuals(runs, fit: PlumeFit, *, false_hit_rate: float = 0.0) -> list:
    """Pearson residuals r_n = (g_n − p_n) / sqrt(p_n (1 − p_n)) of each run under ``fit`` (its δ included).

    p_n is the hit probability of reading n under the fitted hit model; the residuals' lag-one autocorrelation is
    what :func:`ar1_tempering` turns into the tempering exponent.

    Parameters
    ----------
    runs : sequence of CalibrationRun
        Calibration runs with known sources.
    fit : PlumeFit
        The plume parameters (D, τ, κ, δ), e.g. from :func:`fit_plume_parameters`.
    false_hit_rate : float, default 0.0, keyword-only
        ε in [0, 1).

    Returns
    -------
    residuals : list of (n_r,) ndarray of float64
        One array per run, in reading order (p_n clipped to [1e-12, 1 − 1e-12], so every residual is finite).

    Raises
    ------
    ValueError
        ``fit``'s D or τ is not positive (the plume model refuses them).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.olfaction import CalibrationRun, PlumeFit, PlumeModel, hit_residuals
    >>> model = PlumeModel(np.zeros((3, 40), bool), resolution=0.25, wind=np.tile([0.2, 0.0], (3, 40, 1)),
    ...                    diffusivity=0.01, lifetime=30.0)
    >>> x = np.arange(0.6, 10.0, 0.5)
    >>> run = CalibrationRun(model, (0.4, 0.4), np.c_[x, np.full(x.size, 0.4)], x < 4.0)
    >>> r = hit_residuals([run], PlumeFit(0.01, 30.0, 1.0, 0.0), false_hit_rate=0.01)
    >>> len(r), r[0].shape, bool(np.isfinite(r[0]).all())
    (1, (19,), True)
    """
    out = []
    for r in runs:
        c = r.predicted(fit.diffusivity, fit.lifetime)
        p = -np.expm1(-fit.encounter_scale * c)
        p = false_hit_rate + (1.0 - false_hit_rate) * ((1.0 - fit.missed_hit_rate) * p)
        p = np.clip(p, 1e-12, 1 - 1e-12)
        out.append((r.hits - p) / np.sqrt(p * (1 - p)))
    return out


def score_tempering(scores, log_priors, true_cells) -> float:
    """The exponent λ of a pseudo-likelihood score that maximises the log score of known sources.

    For calibration posteriors p_i(s; λ) ∝ exp(log p_i(s) + λ S_i(s)) with known true cells t_i, λ maximises
    Σ_i log p_i(t_i; λ) = Σ_i [λ S_i(t_i) + log p_i(t_i) − logsumexp_s(log p_i(s) + λ S_i(s))] — a proper
    scoring rule, so the fitted posteriors are neither over- nor under-confident on average; the objective is
    concave in λ (log-sum-exp is convex). Found by bounded Brent on log λ ∈ [−10, 5].

    Parameters
    ----------
    scores : sequence of (N,) array_like of float
        S_i over the candidate cells (finite where the prior is positive).
    log_priors : sequence of (N,) array_like of float
        log p_i(s) (−inf off the support).
    true_cells : sequence of int
        Flat index t_i of the true source cell (inside the support).

    Returns
    -------
    lam : float

    Raises
    ------
    ValueError
        A score and its log prior differ in shape, a true cell lies outside them or off the prior's support, or
        ``scores`` is empty.

    Examples
    --------
    Two calibration posteriors over three cells with the same score, their true sources in cells 2 and 1:

    >>> import numpy as np
    >>> from psgsl_pgm.olfaction import score_tempering
    >>> flat = np.log(np.full(3, 1 / 3))
    >>> round(score_tempering([[0.0, 1.0, 2.0], [0.0, 1.0, 2.0]], [flat, flat], [2, 1]), 3)
    0.834
    """
    from scipy.optimize import minimize_scalar
    from scipy.special import logsumexp

    items = []
    for i, (sc, lp, t) in enumerate(zip(scores, log_priors, true_cells)):
        sc = as_float_array(sc, f"scores[{i}]", dtype=np.float64).ravel()
        lp = as_float_array(lp, f"log_priors[{i}]", dtype=np.float64).ravel()
        t = int(t)
        if sc.shape != lp.shape or not 0 <= t < sc.size or not np.isfinite(lp[t]):
            raise ValueError(f"scores[{i}], log_priors[{i}] must have one shape with true_cells[{i}] inside the support")
        ok = np.isfinite(lp)
        items.append((np.where(ok, sc, 0.0), lp, t))
    if not items:
        raise ValueError("scores must hold at least one calibration posterior")

    def neg(log_lam):
        lam = np.exp(log_lam)
        return -sum(lam * sc[t] + lp[t] - logsumexp(lp + lam * sc) for sc, lp, t in items)

    res = minimize_scalar(neg, bounds=(-10.0, 5.0), method="bounded", options={"xatol": 1e-8})
    return float(np.exp(res.x))


def ar1_tempering(residuals):
    """Lag-1 autocorrelation ρ̂ of residual sequences and the tempering β = n_eff / n = (1 − ρ̂) / (1 + ρ̂).

    For an AR(1) sequence with lag-1 correlation ρ, the variance of the mean of n readings is that of
    n (1 − ρ) / (1 + ρ) independent ones (for large n): each correlated reading carries the information of
    β = (1 − ρ)/(1 + ρ) independent readings, the exponent of the tempered likelihood of :class:`GridInfotaxis`.
    ρ̂ is pooled over sequences (runs), each centred on its own mean,

        ρ̂ = Σ_runs Σ_n r̃_n r̃_{n+1} / Σ_runs Σ_n r̃_n²,     r̃ = r − mean(r),

    and clipped to [0, 1) (a negative estimate gives β = 1: no tempering is ever above 1).

    Parameters
    ----------
    residuals : sequence of (n_i,) array_like of float
        One residual sequence per run, in reading order (at least 2 readings in total pairs).

    Returns
    -------
    rho, beta : float

    Raises
    ------
    ValueError
        A residual sequence is not finite, or no sequence holds a pair of consecutive readings that vary.

    Examples
    --------
    >>> rho, beta = ar1_tempering([[1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0]])
    >>> round(rho, 12), round(beta, 12)
    (0.125, 0.777777777778)
    """
    num = den = 0.0
    pairs = 0
    for i, r in enumerate(residuals):
        x = as_float_array(r, f"residuals[{i}]", dtype=np.float64).ravel()
        if not np.isfinite(x).all():
            raise ValueError(f"residuals[{i}] must be finite")
        if x.size == 0:
            continue
        x = x - x.mean()
        num += float(x[:-1] @ x[1:])
        den += float(x @ x)
        pairs += x.size - 1
    if pairs < 1 or not den > 0:
        raise ValueError("residuals must hold at least one pair of consecutive readings that vary")
    rho = min(max(num / den, 0.0), 1.0 - 1e-12)
    return float(rho), float((1.0 - rho) / (1.0 + rho))


def mixture_weights(log_likelihoods, *, tempering: float = 1.0, tol: float = 1e-12, max_iter: int = 100000):
    """Prior weights π of a grid of plume parameters θ_j that maximise the marginal likelihood of calibration runs.

    Each run r has its own θ (a run-level unknown), drawn from the population distribution π over the grid; its
    readings around the known source have (tempered) likelihood exp(β ℓ_rj), ℓ_rj = Σ_n log P_θj(g_n | s_r).
    π maximises Σ_r log Σ_j π_j exp(β ℓ_rj) (the nonparametric maximum-likelihood mixing distribution on the
    grid; empirical Bayes), found by EM: π_j ← mean_r p(θ_j | run r), p(θ_j | r) ∝ π_j exp(β ℓ_rj). The
    objective is concave in π and every EM step increases it; at the maximum
    mean_r exp(β ℓ_rj) / Σ_i π_i exp(β ℓ_ri) ≤ 1 for every j, with equality where π_j > 0.
    These are the weights of :class:`GridInfotaxis`' ``parameter_grid``, whose posterior then carries the
    run's θ as an unknown updated with the readings.

    Parameters
    ----------
    log_likelihoods : (R, J) array_like of float
        ℓ_rj, untempered (−inf allowed where a component cannot explain a run, not for every component).
    tempering : float, keyword-only
        β ∈ (0, 1], as in the estimator.
    tol : float, keyword-only
        Stop when no weight moves by more than ``tol``.
    max_iter : int, keyword-only

    Returns
    -------
    weights : (J,) ndarray of float64
        Sums to 1.

    Raises
    ------
    ValueError
        ``log_likelihoods`` is not (R, J) with R, J >= 1, holds NaN or +inf, or has a run that no component
        explains (all -inf); ``tempering`` is not in (0, 1].

    Examples
    --------
    >>> w = mixture_weights([[0.0, -50.0], [-50.0, 0.0], [0.0, -50.0]])   # two runs prefer θ_0, one θ_1
    >>> [round(float(v), 6) for v in w]
    [0.666667, 0.333333]
    """
    from scipy.special import logsumexp

    ell = as_float_array(log_likelihoods, "log_likelihoods", dtype=np.float64, ndim=2)
    if ell.shape[0] < 1 or ell.shape[1] < 1:
        raise ValueError(f"log_likelihoods must be (R, J) with R, J >= 1, got {describe(ell)}")
    if np.isnan(ell).any() or (ell == np.inf).any():
        raise ValueError("log_likelihoods must be finite or -inf (no NaN, no +inf)")
    if not np.isfinite(ell).any(axis=1).all():
        raise ValueError("log_likelihoods: every run needs at least one component with a finite log-likelihood")
    beta = unit_interval(tempering, "tempering", low_open=True, high_open=False)
    a = beta * ell
    a = a - a.max(axis=1, keepdims=True)  # per-run shift: p(θ | r) is unchanged
    lik = np.exp(a)  # (R, J), max 1 per row
    w = np.full(ell.shape[1], 1.0 / ell.shape[1])
    for _ in range(int(max_iter)):
        resp = lik * w
        resp /= resp.sum(axis=1, keepdims=True)  # p(θ_j | run r)
        new = resp.mean(axis=0)
        done = np.abs(new - w).max() <= tol
        w = new
        if done:
            break
    return w / w.sum()
