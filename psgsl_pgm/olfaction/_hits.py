"""The robot's hit decision from its gas sensor's raw output, with baseline and noise estimated online.

A real robot does not get hits from its sensor: it gets a trace of output samples (a MOX sensor's conductance, a
PID's ppm) and decides. :class:`HitRule` does so from each reading's samples alone, learning what it needs —
the noise level, and for the level rule the baseline — from the readings it has seen, never from the sensor's
specification.

Which statistic, by sensor kind:

* ``"rise"`` (metal-oxide sensors). A MOX sensor recovers several times slower than it rises (τ_d ≈ 16 s against
  τ_r ≈ 3 s for a TGS2620). After a gas patch its response stays above any level threshold for ~τ_d ln(y/θ) —
  tens of seconds, i.e. the next several stops, which a level rule would all call hits although they are in
  clean air; and a new patch met while the response is still decaying does not lift the level much above
  where it was. The rate of rise sees both correctly: it is negative while the sensor recovers, and positive as
  soon as gas arrives, whatever the level. It also ignores the baseline: the drift of a MOX baseline (minutes to
  months) is orders of magnitude slower than a rise within one window, so no baseline has to be tracked. The
  statistic is the least-squares slope b of the window's samples against their index; the rule fires when
  b > k·σ̂ / √(Σ (i − ī)²), k standard errors above zero, with σ̂ the median over the readings so far of each
  window's residual standard deviation about its line (robust to the windows that hold a rise or a recovery;
  valid from the first reading, a t-test with n − 2 degrees of freedom). It treats the noise as white: a
  baseline random walk that moves the samples within one window as much as the noise does also tilts the slope,
  which the residuals understate. With :class:`psgsl_pgm.sim.MOXSensor`'s noise, false hits in clean air stay
  below 1 in 2000 readings up to four times its default drift (σ_d = 2·10⁻³ s^(−1/2)), and reach 1.6 % at ten
  times and 5.6 % at twenty (``tests/olfaction/test_olfaction_hits.py``). Its blind spot: a sensor sitting in
  steady gas for longer than a few τ_r shows no rise — at a stop the robot arrives from elsewhere, so its sensor
  has been recovering on the way.
* ``"level"`` (fast sensors, a PID). A PID recovers in about a second, faster than the robot drives between
  stops, so its level is current: the rule fires when the window mean exceeds the baseline b̂ by k·ŝ, with b̂ the
  median of the last ``memory`` window means that were not hits (clean air: it follows a drifting baseline, and
  a long stay in a plume does not raise it) and ŝ the larger of 1.4826 × their median absolute deviation (the
  spread of clean-air readings, drift included) and the median within-window standard deviation over √n (the
  noise of one window's mean, over the clean readings and this one). A reading in gas before any clean one would
  become the baseline: given the sensor's known clean-air output (``zero``: a PID is zeroed in fresh air before
  a run) the rule starts from it and decides from the first reading. Its blind spot: a jump of the baseline
  larger than the threshold would be taken for gas until the robot is restarted (a PID's zero does not jump).

No reading is a hit before ``warm_up`` readings have been seen (the estimates need some clean air).
"""

from __future__ import annotations

import numpy as np

from .._shared._validate import as_float_array, index, positive, real_number

__all__ = ["HIT_RULE_KINDS", "HitRule"]

#: The statistics a :class:`HitRule` can threshold.
HIT_RULE_KINDS = ("rise", "level")

_MAD_TO_STD = 1.4826  # σ of a normal distribution per median absolute deviation


class HitRule:
    """Online hit/miss decision from the samples of each gas reading (see the module docstring).

    Parameters
    ----------
    kind : {"rise", "level"}
        Threshold on the rate of rise within a window (metal-oxide sensors) or on the baseline-subtracted window
        mean (fast sensors).
    k : float, keyword-only
        Threshold in estimated standard errors (> 0).
    warm_up : int, keyword-only
        Readings seen before the first hit can be declared (≥ 1).
    memory : int, keyword-only
        Readings behind the level rule's baseline (≥ 1).
    zero : float, optional, keyword-only
        The level rule's clean-air output known before the first reading (0 ppm for a PID zeroed in fresh air
        before the run, as its manual prescribes), counted as its first clean reading.

    Attributes
    ----------
    n_readings : int
        Readings seen.
    noise : float
        σ̂, the estimated noise of one sample in the sensor's units (NaN before the first reading; the level rule's
        from the windows that were not hits).
    baseline : float
        b̂, the estimated clean-air level ("level" rule; NaN before the first clean reading or ``zero``, and for
        "rise").

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> rule = HitRule("rise")
    >>> [rule.decide(1.0 + 0.002 * rng.standard_normal(10)) for _ in range(5)]
    [False, False, False, False, False]
    >>> rule.decide(1.0 + 0.01 * np.arange(10) + 0.002 * rng.standard_normal(10))
    True
    """

    def __init__(self, kind: str, *, k: float = 5.0, warm_up: int = 3, memory: int = 30, zero: float | None = None):
        if kind not in HIT_RULE_KINDS:
            raise ValueError(f"kind must be one of {HIT_RULE_KINDS}, got {kind!r}")
        self.kind = kind
        self.k = positive(k, "k")
        self.warm_up = index(warm_up, "warm_up", minimum=1)
        self.memory = index(memory, "memory", minimum=1)
        if zero is not None and kind != "level":
            raise ValueError(f"zero is the level rule's clean-air output; the {kind!r} rule has no baseline")
        self._spread: list[float] = []  # "rise": per reading, the residual std about the window's line
        self._means: list[float] = []
        self._clean: list[float] = [] if zero is None else [real_number(zero, "zero")]
        self._clean_spread: list[float] = []  # "level": the window means and standard deviations that were not hits
        self._all_spread: list[float] = []

    @property
    def n_readings(self) -> int:
        return len(self._means)

    @property
    def noise(self) -> float:
        spread = self._spread if self.kind == "rise" else self._clean_spread
        return float(np.median(spread)) if spread else float("nan")

    @property
    def baseline(self) -> float:
        if not self._clean or self.kind != "level":
            return float("nan")
        return float(np.median(self._clean[-self.memory:]))

    def decide(self, trace) -> bool:
        """Whether the reading whose output samples are ``trace`` (n,) is a hit; the estimates learn from it.

        ``"rise"`` needs at least 3 samples per reading (a line and a residual).
        """
        v = as_float_array(trace, "trace", ndim=1)
        if not np.all(np.isfinite(v)):
            raise ValueError("trace must hold finite output samples")
        n = v.size
        if self.kind == "rise":
            if n < 3:
                raise ValueError(f"the rise rule needs a trace of at least 3 samples per reading, got {n}")
            i = np.arange(n, dtype=np.float64) - (n - 1) / 2.0
            sxx = float(i @ i)
            slope = float(i @ (v - v.mean())) / sxx
            resid = v - v.mean() - slope * i
            self._spread.append(float(np.sqrt(resid @ resid / (n - 2))))
            self._means.append(float(v.mean()))
            stat, scale = slope, self.noise / np.sqrt(sxx)
        else:
            if n < 1:
                raise ValueError("trace must hold at least one output sample")
            mean = float(v.mean())
            self._means.append(mean)
            std = float(v.std(ddof=1)) if n > 1 else 0.0
            clean = np.asarray(self._clean[-self.memory:])
            b = float(np.median(clean)) if clean.size else mean  # no clean reading yet: no hit
            mad = float(np.median(np.abs(clean - b))) if clean.size > 1 else 0.0
            self._all_spread.append(std)
            # the noise of one sample: from the clean windows and this one; a window whose samples are all equal
            # (an output clipped at zero) tells nothing of it, and without any other, all windows so far count
            stds = [x for x in self._clean_spread[-self.memory:] + [std] if x > 0] or \
                [x for x in self._all_spread if x > 0] or [0.0]
            stat, scale = mean - b, max(_MAD_TO_STD * mad, float(np.median(stds)) / np.sqrt(n))
        hit = self.n_readings > self.warm_up - 1 and (stat > self.k * scale if scale > 0 else stat > 0)
        if self.kind == "level" and not hit:
            self._clean.append(mean)
            self._clean_spread.append(std)
        return bool(hit)

    def __repr__(self) -> str:
        return f"HitRule({self.kind!r}, k={self.k:g}, {self.n_readings} readings, noise={self.noise:.3g})"
