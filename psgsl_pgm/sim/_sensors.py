"""Gas sensor (window average, first-order response, noise, hit/miss) and anemometer models."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from scipy.signal import lfilter

from .._shared._validate import positive as check_positive

__all__ = ["GasSensor", "GasReading", "Anemometer"]


def _check_fields(obj, *, positive=()):
    """Every field a finite number, > 0 for the fields named in ``positive`` and >= 0 for the others."""
    for f in fields(obj):
        name = f"{type(obj).__name__}.{f.name}"
        object.__setattr__(obj, f.name, check_positive(getattr(obj, f.name), name, allow_zero=f.name not in positive))


@dataclass(frozen=True)
class GasReading:
    """One gas-sensor reading.

    Attributes
    ----------
    value : float
        Sensor output averaged over the window, ppm.
    hit : bool
        ``value >= threshold``.
    state : float
        Sensor output at the end of the window (the first-order lag's state, to continue from).
    """

    value: float
    hit: bool
    state: float


@dataclass(frozen=True)
class GasSensor:
    """A gas sensor sampled every time step and read as hit/miss over a short window.

    The output follows the true concentration x with a first-order lag of time constant τ
    (``response_time``; exact discretisation y_k = y_{k-1} + (1 − e^{−dt/τ}) (x_k − y_{k-1}), y = x for
    τ = 0), plus Gaussian noise per sample (clipped at 0 ppm); the reading is the window mean, a hit when it
    reaches ``threshold``.

    Parameters
    ----------
    threshold : float
        Hit threshold, ppm (> 0).
    window : float
        Averaging window, s (> 0).
    response_time : float
        τ, s (0 = ideal sensor).
    noise_std : float
        Std of the additive per-sample noise, ppm.

    Examples
    --------
    >>> s = GasSensor(threshold=1.0, window=1.0)
    >>> r = s.read([0.0, 2.0, 2.0, 2.0], dt=0.25)
    >>> r.value, r.hit
    (1.5, True)
    """

    threshold: float = 1.0
    window: float = 1.0
    response_time: float = 0.0
    noise_std: float = 0.0

    def __post_init__(self):
        _check_fields(self, positive=("threshold", "window"))

    def samples(self, dt: float) -> int:
        """Number of time steps in one window."""
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        return max(1, int(round(self.window / dt)))

    def response(self, concentrations, dt: float, *, initial: float = 0.0, rng=None) -> np.ndarray:
        """(n,) sensor output for true concentrations sampled every ``dt`` seconds."""
        x = np.asarray(concentrations, dtype=np.float64).ravel()
        if not np.all(np.isfinite(x)) or (x.size and x.min() < 0):
            raise ValueError("concentrations must be finite and non-negative (ppm)")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        if self.response_time > 0:
            a = 1.0 - np.exp(-dt / self.response_time)
            # y_k = y_{k-1} + a (x_k − y_{k-1}) = (1 − a) y_{k-1} + a x_k, from y_0 = initial
            y = lfilter([a], [1.0, -(1.0 - a)], x, zi=[(1.0 - a) * float(initial)])[0]
        else:
            y = x.copy()
        if self.noise_std > 0:
            if rng is None:
                raise ValueError("a noisy sensor (noise_std > 0) needs rng=np.random.default_rng(seed)")
            y = np.maximum(y + rng.normal(0.0, self.noise_std, size=y.shape), 0.0)
        return y

    def read(self, concentrations, dt: float, *, initial: float = 0.0, rng=None) -> GasReading:
        """Average the response over the given samples (one window) into a :class:`GasReading`."""
        y = self.response(concentrations, dt, initial=initial, rng=rng)
        if y.size == 0:
            raise ValueError("read needs at least one concentration sample")
        value = float(y.mean())
        return GasReading(value, bool(value >= self.threshold), float(y[-1]))


@dataclass(frozen=True)
class Anemometer:
    """2-D anemometer: the local wind plus isotropic Gaussian noise (m/s per axis).

    Examples
    --------
    >>> import numpy as np
    >>> Anemometer(noise_std=0.0).read([0.2, -0.1], rng=np.random.default_rng(0))
    array([ 0.2, -0.1])
    """

    noise_std: float = 0.02

    def __post_init__(self):
        _check_fields(self)

    def read(self, wind, *, rng) -> np.ndarray:
        """(..., 2) noisy wind for true wind (..., 2)."""
        w = np.asarray(wind, dtype=np.float64)
        if w.ndim == 0 or w.shape[-1] != 2:
            raise ValueError(f"wind must have shape (..., 2), got {w.shape}")
        if self.noise_std == 0:
            return w.copy()
        return w + rng.normal(0.0, self.noise_std, size=w.shape)
