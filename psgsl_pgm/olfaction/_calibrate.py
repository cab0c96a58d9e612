"""Maximum-likelihood calibration of the encounter scale κ from readings around a known source."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .._validate import as_array, as_float_array, describe, unit_interval
from ._plume import PlumeModel

__all__ = ["encounter_scale_mle", "fit_encounter_scale"]


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
