"""Gas sensors with published dynamics: a metal-oxide (MOX) sensor and a photo-ionisation detector (PID).

Both have the interface of :class:`GasSensor` (``window``, ``samples(dt)``, ``response(...)``, ``idle(...)``,
``read(concentrations, dt, *, initial, rng)`` → :class:`GasReading`), so :meth:`World.sense_gas` drives them
unchanged. Unlike :class:`GasSensor` they do not decide hits: their reading carries the window's samples
(``trace``) and ``hit=None``, and the robot decides (:class:`psgsl_pgm.olfaction.HitRule`).

Between two readings the robot drives and turns; the world does not know the path, so the sensing element is
taken to be in clean air then (:meth:`MOXSensor.idle`): its response relaxes with the recovery time constant and
its baseline keeps drifting. A robot that crosses a plume while driving would arrive with a higher response.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from .._shared._validate import positive as check_positive
from .._shared._validate import real_number
from ._sensors import GasReading

__all__ = ["MOXSensor", "MOXState", "PIDSensor"]


@dataclass(frozen=True)
class MOXState:
    """What a :class:`MOXSensor` (or :class:`PIDSensor`) continues from.

    Attributes
    ----------
    level : float
        The lagged response y above the baseline: excess conductance G/G_air − 1 (MOX), ppm (PID).
    drift : float
        The baseline's offset d from its value at the first reading: G_air/G_0 − 1 (MOX), ppm (PID).
    """

    level: float = 0.0
    drift: float = 0.0


def _state(initial, name: str) -> MOXState:
    if isinstance(initial, MOXState):
        return initial
    level = real_number(initial, name, what="a MOXState or a response level")
    if level < 0:
        raise ValueError(f"{name} must be a non-negative response level, got {initial!r}")
    return MOXState(level, 0.0)


def _samples(concentrations, dt) -> tuple[np.ndarray, float]:
    x = np.asarray(concentrations, dtype=np.float64).ravel()
    if not np.all(np.isfinite(x)) or (x.size and x.min() < 0):
        raise ValueError("concentrations must be finite and non-negative (ppm)")
    if isinstance(dt, (bool, np.bool_)) or not isinstance(dt, (int, float, np.integer, np.floating)) \
            or not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
    return x, float(dt)


def _lag(target: np.ndarray, dt: float, rise: float, recovery: float, y0: float) -> np.ndarray:
    """(n,) asymmetric first-order lag of ``target``: the exact step of y' = (u − y) / τ per sample, with
    τ = ``rise`` while u > y and τ = ``recovery`` otherwise (u held constant over the step)."""
    a_rise = -np.expm1(-dt / rise) if rise > 0 else 1.0
    a_rec = -np.expm1(-dt / recovery) if recovery > 0 else 1.0
    y = np.empty_like(target)
    prev = float(y0)
    for k, u in enumerate(target):  # a window is a few tens of samples
        prev += (a_rise if u > prev else a_rec) * (u - prev)
        y[k] = prev
    return y


def _walk(state: MOXState, n: int, dt: float, rate: float, std: float, rng) -> np.ndarray:
    """(n,) baseline offsets d_k = d_{k−1} + rate dt + std √dt η_k from ``state.drift``."""
    if std > 0:
        steps = rate * dt + std * np.sqrt(dt) * rng.standard_normal(n)
    else:
        steps = np.full(n, rate * dt)
    return state.drift + np.cumsum(steps)


def _check(obj, *, positive=(), signed=()):
    for f in fields(obj):
        name = f"{type(obj).__name__}.{f.name}"
        v = getattr(obj, f.name)
        v = real_number(v, name) if f.name in signed else check_positive(v, name, allow_zero=f.name not in positive)
        object.__setattr__(obj, f.name, v)


def _need_rng(rng, what: str):
    if rng is None:
        raise ValueError(f"a sensor with {what} needs rng=np.random.default_rng(seed)")
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng must be a numpy Generator (np.random.default_rng(seed)), got {type(rng).__name__}")


@dataclass(frozen=True)
class MOXSensor:
    """A metal-oxide gas sensor: power-law sensitivity, slow asymmetric first-order dynamics, noise and drift.

    **Sensitivity.** In steady state the sensing resistance R_s falls with the concentration c (ppm) as
    R_s / R_air = (1 + c / c_k)^(−α), i.e. the conductance rises to G / G_air = (1 + c / c_k)^α. Above the knee
    c_k this is the datasheet's straight line in log-log, R_s / R_0 = A c^(−α); below it the response goes
    smoothly to zero instead of being cut at the clean-air value. The excess y_ss(c) = (1 + c / c_k)^α − 1.

    **Dynamics.** The response y follows y_ss with a first-order lag whose time constant is τ_r
    (``rise_time``) while y_ss > y (gas arriving) and τ_d (``recovery_time``) otherwise, stepped exactly per
    sample: y_k = y_ss,k + (y_{k−1} − y_ss,k) e^(−dt/τ). A step from clean air to c therefore gives
    y(t) = y_ss(c) (1 − e^(−t/τ_r)), and its removal y(t) = y_0 e^(−t/τ_d).

    **Output.** Each sample is v_k = (1 + d_k)(1 + y_k) + σ_n ξ_k: the conductance relative to the clean-air
    conductance at the first reading, G / G_0 (dimensionless, 1 in clean air without drift), with the baseline
    offset d a seeded random walk, d_k = d_{k−1} + μ dt + σ_d √dt η_k, and white Gaussian noise ξ. The reading's
    ``value`` is the window mean, ``trace`` the samples, ``hit`` None (the robot decides).

    Sources. The defaults are Figaro's TGS2620 exposed to ethanol, as in GADEN's simulated MOX sensor (Monroy,
    Hernandez-Bennetts, Fan, Lilienthal, Gonzalez-Jimenez, "GADEN: A 3D gas dispersion simulator for mobile
    robot olfaction in realistic environments", Sensors 17(7):1479, 2017; ``simulated_gas_sensor`` in
    github.com/MAPIRlab/gaden): τ_r = 2.96 s, τ_d = 15.71 s (their values from real experiments), and the
    datasheet fit R_s / R_0 = 62.32 c^(−0.7155) with R_air / R_0 = 21, so α = 0.7155 and
    c_k = (62.32 / 21)^(1/0.7155) = 4.57 ppm. That recovery is several times slower than the rise, and that a
    first-order model with separate rise and decay constants describes it, is the characterisation of Monroy,
    Gonzalez-Jimenez, Blanco, "Overcoming the slow recovery of MOX gas sensors through a system modeling
    approach", Sensors 12(10):13664-13680, 2012. :meth:`tgs2600` and :meth:`tgs2611` give GADEN's other two
    sensors. Noise and drift are this model's assumptions (the datasheets give neither per second):
    σ_n = 0.002 per sample (0.2 % of the clean-air conductance, ~2σ for 0.1 ppm of ethanol at the TGS2620's
    sensitivity) and σ_d = 5·10⁻⁴ s^(−1/2) (≈ 1.6 % of baseline wander over 1000 s, the size of the
    temperature and humidity dependence of R_air in the Figaro datasheets over minutes indoors); μ = 0.

    Parameters
    ----------
    window : float
        Averaging window of one reading, s (> 0).
    rise_time, recovery_time : float
        τ_r and τ_d, s (≥ 0; 0 = no lag).
    sensitivity : float
        α, the power-law exponent (> 0).
    knee : float
        c_k, ppm (> 0).
    noise_std : float
        σ_n, per sample, in units of G_0 (≥ 0).
    drift_std : float
        σ_d, baseline random walk, per √s (≥ 0).
    drift_rate : float
        μ, linear baseline drift, per s (any sign).

    Examples
    --------
    >>> import numpy as np
    >>> s = MOXSensor(noise_std=0.0, drift_std=0.0)
    >>> r = s.read(np.full(10, 4.57), 0.1)            # 1 s at the knee concentration from clean air
    >>> r.hit is None, round(r.value, 3), r.trace.shape
    (True, 1.106, (10,))
    """

    window: float = 1.0
    rise_time: float = 2.96
    recovery_time: float = 15.71
    sensitivity: float = 0.7155
    knee: float = (62.32 / 21.0) ** (1.0 / 0.7155)  # 4.574 ppm, see the docstring
    noise_std: float = 0.002
    drift_std: float = 5e-4
    drift_rate: float = 0.0

    def __post_init__(self):
        _check(self, positive=("window", "sensitivity", "knee"), signed=("drift_rate",))

    @classmethod
    def _from_fit(cls, a: float, b: float, air: float, rise: float, recovery: float, **kwargs) -> MOXSensor:
        """From a datasheet fit R_s / R_0 = a c^b (b < 0) and R_air / R_0 = ``air``: α = −b, c_k = (a / air)^(−1/b)."""
        return cls(rise_time=rise, recovery_time=recovery, sensitivity=-b, knee=(a / air) ** (-1.0 / b), **kwargs)

    @classmethod
    def tgs2620(cls, **kwargs) -> MOXSensor:
        """Figaro TGS2620 in ethanol (the defaults; GADEN: R_s/R_0 = 62.32 c^−0.7155, R_air/R_0 = 21,
        τ_r = 2.96 s, τ_d = 15.71 s). ``kwargs`` set the other fields."""
        return cls._from_fit(62.32, -0.7155, 21.0, 2.96, 15.71, **kwargs)

    @classmethod
    def tgs2600(cls, **kwargs) -> MOXSensor:
        """Figaro TGS2600 in ethanol (GADEN: R_s/R_0 = 0.6796 c^−0.3196, R_air/R_0 = 1, τ_r = 4.8 s,
        τ_d = 18.75 s)."""
        return cls._from_fit(0.6796, -0.3196, 1.0, 4.8, 18.75, **kwargs)

    @classmethod
    def tgs2611(cls, **kwargs) -> MOXSensor:
        """Figaro TGS2611 in ethanol (GADEN: R_s/R_0 = 51.11 c^−0.3658, R_air/R_0 = 8.8, τ_r = 3.44 s,
        τ_d = 6.35 s)."""
        return cls._from_fit(51.11, -0.3658, 8.8, 3.44, 6.35, **kwargs)

    def steady_state(self, concentration) -> np.ndarray:
        """y_ss(c) = (1 + c / c_k)^α − 1, the excess conductance in steady state at ``concentration`` ppm."""
        c = np.asarray(concentration, dtype=np.float64)
        if not np.all(np.isfinite(c)) or (c.size and c.min() < 0):
            raise ValueError("concentration must be finite and non-negative (ppm)")
        return np.expm1(self.sensitivity * np.log1p(c / self.knee))

    def samples(self, dt: float) -> int:
        """Number of time steps in one window."""
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        return max(1, int(round(self.window / dt)))

    def _noisy(self) -> bool:
        return self.noise_std > 0 or self.drift_std > 0

    def _run(self, concentrations, dt, initial, rng):
        x, dt = _samples(concentrations, dt)
        state = _state(initial, "initial")
        if self._noisy():
            _need_rng(rng, "noise or drift")
        y = _lag(self.steady_state(x), dt, self.rise_time, self.recovery_time, state.level)
        d = _walk(state, x.size, dt, self.drift_rate, self.drift_std, rng)
        v = (1.0 + d) * (1.0 + y)
        if self.noise_std > 0:
            v = v + self.noise_std * rng.standard_normal(x.size)
        return v, y, d

    def response(self, concentrations, dt: float, *, initial=0.0, rng=None) -> np.ndarray:
        """(n,) output samples G / G_0 for concentrations (ppm) sampled every ``dt`` seconds, from ``initial``
        (a :class:`MOXState`, or a response level with no drift)."""
        return self._run(concentrations, dt, initial, rng)[0]

    def idle(self, state, seconds: float, *, rng=None) -> MOXState:
        """The state after ``seconds`` in clean air without a reading: y → y e^(−t/τ_d), and the baseline's
        random walk advanced by t (one draw)."""
        st = _state(state, "state")
        t = check_positive(seconds, "seconds", allow_zero=True)
        level = st.level * np.exp(-t / self.recovery_time) if self.recovery_time > 0 else 0.0
        drift = st.drift + self.drift_rate * t
        if self.drift_std > 0 and t > 0:
            _need_rng(rng, "drift")
            drift += self.drift_std * np.sqrt(t) * rng.standard_normal()
        return MOXState(float(level), float(drift))

    def read(self, concentrations, dt: float, *, initial=0.0, rng=None) -> GasReading:
        """One window: the mean of the output samples, the samples themselves, ``hit=None`` and the
        :class:`MOXState` to continue from."""
        v, y, d = self._run(concentrations, dt, initial, rng)
        if v.size == 0:
            raise ValueError("read needs at least one concentration sample")
        return GasReading(float(v.mean()), None, MOXState(float(y[-1]), float(d[-1])), v)


@dataclass(frozen=True)
class PIDSensor:
    """A photo-ionisation detector: ppm output, a fast symmetric first-order lag, noise and optional drift.

    The output follows the concentration with one time constant τ (rise and recovery alike, exact step per
    sample as in :class:`MOXSensor`), plus a baseline offset d (a seeded random walk, default none) and white
    Gaussian noise, clipped at 0 ppm as the instrument displays: v_k = max(0, y_k + d_k + σ_n ξ_k). The reading's
    ``value`` is the window mean, ``trace`` the samples, ``hit`` None (the robot decides).

    Source: the RAE Systems (Honeywell) MiniRAE Lite PID, the PID of GADEN's simulated sensors: response time
    T90 = 2 s and resolution 0.1 ppm (isobutylene) in its datasheet. A first-order lag reaches 90 % at
    τ ln 10, so τ = 2 / ln 10 = 0.87 s. The datasheet gives no noise figure: σ_n = 0.1 ppm (one resolution
    step) is assumed; the gas is read at the lamp's response factor 1 (ppm as given).

    Parameters
    ----------
    window : float
        Averaging window of one reading, s (> 0).
    response_time : float
        τ, s (≥ 0).
    noise_std : float
        σ_n per sample, ppm (≥ 0).
    drift_std : float
        σ_d, baseline random walk, ppm per √s (≥ 0).

    Examples
    --------
    >>> import numpy as np
    >>> r = PIDSensor(noise_std=0.0).read(np.full(10, 2.0), 0.1)
    >>> r.hit is None, round(r.value, 3)
    (True, 0.879)
    """

    window: float = 1.0
    response_time: float = 2.0 / np.log(10.0)
    noise_std: float = 0.1
    drift_std: float = 0.0

    def __post_init__(self):
        _check(self, positive=("window",))

    def samples(self, dt: float) -> int:
        """Number of time steps in one window."""
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        return max(1, int(round(self.window / dt)))

    def _run(self, concentrations, dt, initial, rng):
        x, dt = _samples(concentrations, dt)
        state = _state(initial, "initial")
        if self.noise_std > 0 or self.drift_std > 0:
            _need_rng(rng, "noise or drift")
        y = _lag(x, dt, self.response_time, self.response_time, state.level)
        d = _walk(state, x.size, dt, 0.0, self.drift_std, rng)
        v = y + d
        if self.noise_std > 0:
            v = v + self.noise_std * rng.standard_normal(x.size)
        return np.maximum(v, 0.0), y, d

    def response(self, concentrations, dt: float, *, initial=0.0, rng=None) -> np.ndarray:
        """(n,) output samples, ppm."""
        return self._run(concentrations, dt, initial, rng)[0]

    def idle(self, state, seconds: float, *, rng=None) -> MOXState:
        """The state after ``seconds`` in clean air without a reading (y → y e^(−t/τ), drift advanced)."""
        st = _state(state, "state")
        t = check_positive(seconds, "seconds", allow_zero=True)
        level = st.level * np.exp(-t / self.response_time) if self.response_time > 0 else 0.0
        drift = st.drift
        if self.drift_std > 0 and t > 0:
            _need_rng(rng, "drift")
            drift += self.drift_std * np.sqrt(t) * rng.standard_normal()
        return MOXState(float(level), float(drift))

    def read(self, concentrations, dt: float, *, initial=0.0, rng=None) -> GasReading:
        """One window: the mean of the samples (ppm), the samples, ``hit=None`` and the state to continue from."""
        v, y, d = self._run(concentrations, dt, initial, rng)
        if v.size == 0:
            raise ValueError("read needs at least one concentration sample")
        return GasReading(float(v.mean()), None, MOXState(float(y[-1]), float(d[-1])), v)
