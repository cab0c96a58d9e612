"""Localisation error: the robot is not exactly where it believes it is.

A robot that localises itself in its map with a particle filter on laser scans (AMCL, the ROS navigation
stack's localiser) carries a pose error that stays bounded — every scan pulls the estimate back towards the
map — but is correlated in time: it persists while the robot sees the same walls. The simulator models the
offset e = (e_x, e_y, e_θ) between the pose the robot believes and its true pose as three independent
Ornstein-Uhlenbeck processes with stationary standard deviations σ (each position axis, map frame) and σ_θ
(heading), and one correlation time τ:

.. math:: de = -e / τ \\, dt + \\sqrt{2 / τ}\\, \\mathrm{diag}(σ, σ, σ_θ)\\, dW,

sampled exactly on a time step dt: e_{k+1} = a e_k + \\sqrt{1 - a^2}\\, \\mathrm{diag}(σ, σ, σ_θ)\\, n_k with
a = exp(−dt / τ) and n_k ~ N(0, I), so that e_k ~ N(0, diag(σ², σ², σ_θ²)) at every step and
corr(e_k, e_{k+m}) = a^m = exp(−m dt / τ).

The robot's true pose is its believed pose minus the offset: (x, y, θ)_true = (x, y, θ)_believed − e.
:class:`psgsl_pgm.sim.World` applies it (:func:`psgsl_pgm.sim.make_world`'s ``localisation``); robot-side code
only ever sees believed poses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from .._shared._validate import index, positive

__all__ = ["LocalisationError"]


@dataclass(frozen=True)
class LocalisationError:
    """Bounded, time-correlated localisation error of an AMCL-like localiser (see the module docstring).

    Reported accuracies of laser-based Monte Carlo localisation on indoor robots lie around 0.05–0.15 m in
    position and 2–5° in heading (AMCL baselines in Peng et al., "An improved AMCL algorithm based on laser
    scanning match in a complex and unstructured environment", Complexity 2018, doi:10.1155/2018/2327637; Monte
    Carlo localisation measured against motion capture in Röwekämper et al., "On the position accuracy of
    mobile robot localization based on particle filters combined with scan matching", IROS 2012, which reaches
    millimetres only at taught-in poses with an added scan matcher). The defaults take the middle of that
    range: σ = 0.1 m per axis (0.14 m radial RMS), σ_θ = 3°. No published correlation time exists for an
    AMCL error; the default τ = 30 s keeps an error over several stops of the search (a stop every 5–10 s at
    0.25 m/s), a slowly varying bias that averages away far less than white noise would.

    Parameters
    ----------
    sigma : float
        Stationary standard deviation of the position offset along each map axis, metres (>= 0).
    heading_sigma : float
        Stationary standard deviation of the heading offset, radians (>= 0, below π/4).
    tau : float
        Correlation time of the offset, seconds (> 0).

    Examples
    --------
    >>> import numpy as np
    >>> err = LocalisationError(sigma=0.1, heading_sigma=0.05, tau=30.0)
    >>> e = err.sample(4, 0.1, rng=np.random.default_rng(0))
    >>> e.shape, round(err.coefficient(30.0), 4)  # a = exp(-1) over one correlation time
    ((4, 3), 0.3679)
    """

    sigma: float = 0.1
    heading_sigma: float = float(np.deg2rad(3.0))
    tau: float = 30.0

    def __post_init__(self):
        object.__setattr__(self, "sigma", positive(self.sigma, "LocalisationError.sigma", "metres",
                                                   allow_zero=True))
        h = positive(self.heading_sigma, "LocalisationError.heading_sigma", "radians", allow_zero=True)
        if h >= np.pi / 4:  # a localiser that far off in heading is lost, not drifting
            raise ValueError(f"LocalisationError.heading_sigma must be below π/4 radians, got {self.heading_sigma!r}")
        object.__setattr__(self, "heading_sigma", h)
        object.__setattr__(self, "tau", positive(self.tau, "LocalisationError.tau", "seconds"))

    @property
    def std(self) -> np.ndarray:
        """(3,) stationary standard deviations (σ, σ, σ_θ): metres, metres, radians."""
        return np.array([self.sigma, self.sigma, self.heading_sigma])

    def coefficient(self, dt: float) -> float:
        """a = exp(−dt / τ), the offset's autocorrelation over ``dt`` seconds."""
        dt = positive(dt, "dt", "seconds")
        return float(np.exp(-dt / self.tau))

    def stationary(self, *, rng) -> np.ndarray:
        """(3,) one offset drawn from the stationary law N(0, diag(σ², σ², σ_θ²)) (three normal draws)."""
        return rng.standard_normal(3) * self.std

    def advance(self, state, n: int, dt: float, *, rng) -> np.ndarray:
        """(n, 3) the offsets of the next ``n`` steps of ``dt`` seconds after ``state`` (3,), exactly.

        Three normal draws per step, in step order: advancing by n₁ then n₂ steps gives the same offsets as
        advancing by n₁ + n₂ at once.
        """
        n = index(n, "n")
        a = self.coefficient(dt)
        state = np.asarray(state, dtype=np.float64)
        if state.shape != (3,) or not np.isfinite(state).all():
            raise ValueError(f"state must be a finite (e_x, e_y, e_θ) of shape (3,), got shape {state.shape}")
        if n == 0:
            return np.zeros((0, 3))
        kicks = rng.standard_normal((n, 3)) * (np.sqrt(1.0 - a * a) * self.std)
        # e_k = a e_{k-1} + kick_k from e_0 = state
        return lfilter([1.0], [1.0, -a], kicks, axis=0, zi=(a * state)[None, :])[0]

    def sample(self, n: int, dt: float, *, rng) -> np.ndarray:
        """(n, 3) a stationary run of ``n`` offsets ``dt`` seconds apart (the first from the stationary law)."""
        n = index(n, "n", minimum=1)
        first = self.stationary(rng=rng)
        return np.concatenate([first[None, :], self.advance(first, n - 1, dt, rng=rng)])
