"""Gas sensor (window average, first-order response, noise, hit/miss) and anemometer models."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

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
        Sensor output averaged over the window: ppm for :class:`GasSensor` and
        :class:`~psgsl_pgm.sim.PIDSensor`, the conductance relative to clean air for
        :class:`~psgsl_pgm.sim.MOXSensor`.
    hit : bool or None
        :class:`GasSensor`: ``value >= threshold``. None for a sensor that leaves the decision to the robot
        (:class:`~psgsl_pgm.sim.MOXSensor`, :class:`~psgsl_pgm.sim.PIDSensor`; the robot's rule is
        :class:`psgsl_pgm.olfaction.HitRule`).
    state : float or object
        What the sensor continues from at its next reading: the first-order lag's output at the end of the window
        (:class:`GasSensor`), or a richer state (:class:`~psgsl_pgm.sim.MOXState`).
    trace : (n,) ndarray or None
        The output samples of the window (one per time step), as the robot's driver logs them; None for
        :class:`GasSensor`, whose reading is its thresholded mean.
    """

    value: float
    hit: bool | None
    state: object
    trace: np.ndarray | None = field(default=None, compare=False, repr=False)


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

    def idle(self, state, seconds: float, *, rng=None):
        """The state after ``seconds`` without a reading: unchanged (the lag continues from where the last
        reading left it, wherever that was taken)."""
        return state

    def read(self, concentrations, dt: float, *, initial: float = 0.0, rng=None) -> GasReading:
        """Average the response over the given samples (one window) into a :class:`GasReading`."""
        y = self.response(concentrations, dt, initial=initial, rng=rng)
        if y.size == 0:
            raise ValueError("read needs at least one concentration sample")
        value = float(y.mean())
        return GasReading(value, bool(value >= self.threshold), float(y[-1]))


@dataclass(frozen=True)
class Anemometer:
    """2-D anemometer: the local wind, turned by a fixed direction error, plus a fixed offset and isotropic
    Gaussian noise, optionally rounded to a resolution.

    A reading is ``round(R(θ_e) w + b + ε)`` with R(θ_e) the rotation by ``direction_error``, b = ``bias`` and
    ε ~ N(0, ``noise_std``² I) per axis; rounding to ``resolution`` when it is positive. The defaults (no
    offset, no direction error, no rounding) are the ideal instrument with 0.02 m/s noise per axis;
    :meth:`datasheet` gives a named ultrasonic anemometer.

    Parameters
    ----------
    noise_std : float
        Std of the noise per axis, m/s.
    bias : (2,) tuple of float
        Constant offset added to the (x, y) reading, m/s.
    direction_error : float
        Constant rotation of the measured direction, degrees (counter-clockwise).
    resolution : float
        Output resolution, m/s (0: none).

    Examples
    --------
    >>> import numpy as np
    >>> Anemometer(noise_std=0.0).read([0.2, -0.1], rng=np.random.default_rng(0))
    array([ 0.2, -0.1])
    >>> Anemometer(noise_std=0.0, bias=(0.01, 0.0), direction_error=90.0).read([0.2, 0.0], rng=None).round(3)
    array([0.01, 0.2 ])
    """

    noise_std: float = 0.02
    bias: tuple = (0.0, 0.0)
    direction_error: float = 0.0
    resolution: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "noise_std", check_positive(self.noise_std, "Anemometer.noise_std", allow_zero=True))
        object.__setattr__(self, "resolution", check_positive(self.resolution, "Anemometer.resolution",
                                                              allow_zero=True))
        from .._shared._validate import real_number, real_pair

        object.__setattr__(self, "direction_error", real_number(self.direction_error, "Anemometer.direction_error",
                                                                unit="degrees"))
        b = real_pair(self.bias, "Anemometer.bias", "a (bx, by) offset", "m/s")
        object.__setattr__(self, "bias", (float(b[0]), float(b[1])))

    @classmethod
    def datasheet(cls) -> "Anemometer":
        """The Gill WindSonic 2-axis ultrasonic anemometer, from its datasheet, at indoor wind speeds.

        Gill Instruments, *WindSonic* ultrasonic wind sensor, product datasheet: wind speed accuracy ±2 % of
        the reading at 12 m/s, direction accuracy ±3° at 12 m/s, resolution 0.01 m/s (speed) and 1°
        (direction). The datasheet states accuracy at 12 m/s only; indoors (0.05–0.5 m/s) ±2 % of the reading is
        below 0.01 m/s, so what is left at these speeds is the output resolution. Assumed here:

        * noise 0.01 m/s per axis (one resolution step; the datasheet gives no noise figure);
        * a constant offset of 0.01 m/s on each axis (the ±2 % band scaled to 0.5 m/s, rounded up to the
          resolution; a zero offset that the datasheet does not rule out at low speed);
        * a constant direction error of +3° (the datasheet's bound, as from a mounting or calibration error);
        * the output rounded to 0.01 m/s.

        Examples
        --------
        >>> a = Anemometer.datasheet()
        >>> a.noise_std, a.bias, a.direction_error, a.resolution
        (0.01, (0.01, 0.01), 3.0, 0.01)
        """
        return cls(noise_std=0.01, bias=(0.01, 0.01), direction_error=3.0, resolution=0.01)

    def read(self, wind, *, rng) -> np.ndarray:
        """(..., 2) reading for true wind (..., 2), m/s."""
        w = np.asarray(wind, dtype=np.float64)
        if w.ndim == 0 or w.shape[-1] != 2:
            raise ValueError(f"wind must have shape (..., 2), got {w.shape}")
        if self.direction_error:
            a = np.deg2rad(self.direction_error)
            c, s = np.cos(a), np.sin(a)
            w = np.stack([c * w[..., 0] - s * w[..., 1], s * w[..., 0] + c * w[..., 1]], axis=-1)
        if self.bias != (0.0, 0.0):
            w = w + np.asarray(self.bias)
        if self.noise_std == 0:
            out = w.copy()
        else:
            out = w + rng.normal(0.0, self.noise_std, size=w.shape)
        if self.resolution > 0:
            out = np.round(out / self.resolution) * self.resolution
        return out
