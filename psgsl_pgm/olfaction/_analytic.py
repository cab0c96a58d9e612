"""Open-space plume of Vergassola, Villermaux & Shraiman (2007), *Infotaxis as a strategy for searching
without gradients*, Nature 445, 406–409 (Methods): the 2-D analytic solution used to validate the grid model.

For a source emitting R particles/s at r0 in unbounded 2-D space with uniform wind w, eddy diffusivity D and
lifetime τ, the mean concentration is

    c(r | r0) = R / (2π D) · exp(w·(r − r0) / (2D)) · K0(|r − r0| / λ),
    λ = sqrt(D τ / (1 + |w|² τ / (4D))),

and a sensor of radius a ≪ λ encounters particles at the rate R(r | r0) = 2π D c / ln(λ/a), i.e.

    R(r | r0) = R / ln(λ/a) · exp(w·(r − r0) / (2D)) · K0(|r − r0| / λ).

Vergassola et al. write the exponent as V (y0 − y) / (2D): their wind blows towards −y (w = (0, −V)), so that
exp(w·(r − r0)/(2D)) = exp(V (y0 − y)/(2D)) and the plume extends downwind.
"""

from __future__ import annotations

import numpy as np
from scipy.special import k0

from .._shared._validate import positive as _positive
from .._shared._validate import real_pair

__all__ = [
    "correlation_length",
    "vergassola_concentration",
    "vergassola_encounter_rate",
    "vergassola_encounter_scale",
]



def _wind_vector(wind) -> np.ndarray:
    return real_pair(wind, "wind", "a (u_x, u_y)", "m/s")


def correlation_length(*, diffusivity: float, lifetime: float, wind_speed: float = 0.0) -> float:
    """λ = sqrt(D τ / (1 + V² τ / (4D))) in metres (Vergassola et al. 2007, Methods).

    The distance over which a patch of gas released at the source stays correlated in the advection-diffusion
    model with decay: the plume's reach across the wind.

    Parameters
    ----------
    diffusivity : float, keyword-only
        Effective (turbulent) diffusivity D, m²/s, > 0.
    lifetime : float, keyword-only
        Lifetime τ of a gas patch before it decays, s, > 0.
    wind_speed : float, default 0.0, keyword-only
        Mean wind speed V, m/s, >= 0.

    Returns
    -------
    length : float
        λ in metres.

    Raises
    ------
    TypeError
        An argument is not a real number.
    ValueError
        ``diffusivity`` or ``lifetime`` is not positive and finite, or ``wind_speed`` is negative or not finite.

    Examples
    --------
    >>> round(correlation_length(diffusivity=1.0, lifetime=4.0, wind_speed=0.0), 12)
    2.0
    """
    d = _positive(diffusivity, "diffusivity")
    t = _positive(lifetime, "lifetime")
    v = _positive(wind_speed, "wind_speed", "m/s", allow_zero=True)
    return float(np.sqrt(d * t / (1.0 + v * v * t / (4.0 * d))))


def vergassola_concentration(displacement, *, wind, diffusivity: float, lifetime: float) -> np.ndarray:
    """Mean concentration per unit emission rate, c(r | r0) / R, in s/m².

    Parameters
    ----------
    displacement : (..., 2) array_like of float
        r − r0: sensor position minus source position, in metres.
    wind : (2,) array_like of float
        Uniform wind (u_x, u_y) in m/s.
    diffusivity, lifetime : float
        D in m²/s and τ in s.

    Returns
    -------
    c : (...) ndarray of float64
        exp(w·(r − r0)/(2D)) K0(‖r − r0‖/λ) / (2π D); +inf at zero displacement (logarithmic singularity).

    Raises
    ------
    ValueError
        ``diffusivity`` or ``lifetime`` is not a positive number, ``wind`` is not a finite (2,) vector, or
        ``displacement`` is not of shape (..., 2).

    Examples
    --------
    >>> c = vergassola_concentration([[1.0, 0.0], [-1.0, 0.0]], wind=(0.5, 0.0), diffusivity=0.5, lifetime=10.0)
    >>> bool(c[0] > c[1])  # downwind of the source (r - r0 along +x) is richer than upwind
    True
    """
    d = _positive(diffusivity, "diffusivity")
    t = _positive(lifetime, "lifetime")
    w = _wind_vector(wind)
    dx = np.asarray(displacement, dtype=np.float64)
    if dx.ndim == 0 or dx.shape[-1] != 2:
        raise ValueError(f"displacement must have shape (..., 2) (r - r0 in metres), got shape {dx.shape}")
    lam = correlation_length(diffusivity=d, lifetime=t, wind_speed=float(np.hypot(*w)))
    r = np.hypot(dx[..., 0], dx[..., 1])
    advective = np.exp((dx @ w) / (2.0 * d))  # exp(w·(r − r0)/(2D))
    return advective * k0(r / lam) / (2.0 * np.pi * d)  # c/R = exp(...) K0(|r − r0|/λ) / (2πD)


def vergassola_encounter_rate(
    displacement, *, wind, diffusivity: float, lifetime: float, emission_rate: float, sensor_radius: float
) -> np.ndarray:
    """Encounter rate R(r | r0) = R / ln(λ/a) · exp(w·(r − r0)/(2D)) · K0(‖r − r0‖/λ), in 1/s.

    Parameters
    ----------
    displacement : (..., 2) array_like of float
        r − r0 in metres.
    wind : (2,) array_like of float
        Uniform wind in m/s.
    diffusivity, lifetime, emission_rate, sensor_radius : float
        D (m²/s), τ (s), R (1/s) and the sensor radius a (m, with a < λ).

    Returns
    -------
    rate : (...) ndarray of float64

    Raises
    ------
    ValueError
        A parameter is not a positive number, ``sensor_radius`` is not smaller than the correlation length λ, or
        ``wind`` or ``displacement`` is refused (see :func:`vergassola_concentration`).

    Examples
    --------
    >>> from psgsl_pgm.olfaction import vergassola_encounter_rate
    >>> rate = vergassola_encounter_rate([[1.0, 0.0], [-1.0, 0.0]], wind=(0.5, 0.0), diffusivity=0.5, lifetime=10.0,
    ...                                  emission_rate=1.0, sensor_radius=0.05)
    >>> rate.round(4)                                          # 1 m downwind and 1 m upwind, hits per second
    array([0.3361, 0.1236])
    """
    lam = correlation_length(
        diffusivity=diffusivity, lifetime=lifetime, wind_speed=float(np.hypot(*_wind_vector(wind)))
    )
    a = _positive(sensor_radius, "sensor_radius")
    if a >= lam:
        raise ValueError(f"sensor_radius must be smaller than the correlation length λ = {lam:g} m, got {a!r}")
    rate = _positive(emission_rate, "emission_rate")
    c = vergassola_concentration(displacement, wind=wind, diffusivity=diffusivity, lifetime=lifetime)
    return 2.0 * np.pi * float(diffusivity) * rate * c / np.log(lam / a)  # R(r|r0) = 2πD R c / ln(λ/a)


def vergassola_encounter_scale(
    *,
    emission_rate: float,
    sample_time: float,
    diffusivity: float,
    lifetime: float,
    wind_speed: float,
    sensor_radius: float,
) -> float:
    """κ such that the expected number of encounters in one sample is κ · G, G in s/m² per unit emission.

    κ = R Δt 2π D / ln(λ/a) (m²), from R(r | r0) = 2π D c / ln(λ/a) with c = R G (Vergassola, Villermaux &
    Shraiman 2007, Nature 445:406-409, Methods). The hit probability of one sample is then
    P(hit) = 1 − exp(−κ G) (Poisson encounters).

    Parameters
    ----------
    emission_rate : float, keyword-only
        The source's release rate R, in patches per second, > 0.
    sample_time : float, keyword-only
        The duration Δt of one sensor reading, s, > 0.
    diffusivity : float, keyword-only
        Effective diffusivity D, m²/s, > 0.
    lifetime : float, keyword-only
        Patch lifetime τ, s, > 0.
    wind_speed : float, keyword-only
        Mean wind speed V, m/s, >= 0 (it shortens λ, :func:`correlation_length`).
    sensor_radius : float, keyword-only
        The sensor's size a, m, > 0 and smaller than λ.

    Returns
    -------
    kappa : float
        The encounter scale κ, m² (so that κ G is a number of encounters).

    Raises
    ------
    TypeError
        An argument is not a real number.
    ValueError
        An argument is not positive and finite (``wind_speed``: negative), or ``sensor_radius`` >= λ.

    Examples
    --------
    >>> k = vergassola_encounter_scale(emission_rate=1.0, sample_time=1.0, diffusivity=0.5, lifetime=10.0,
    ...                                wind_speed=0.0, sensor_radius=0.01)
    >>> bool(np.isclose(k, np.pi / np.log(correlation_length(diffusivity=0.5, lifetime=10.0) / 0.01), rtol=1e-12))
    True
    """
    lam = correlation_length(diffusivity=diffusivity, lifetime=lifetime, wind_speed=wind_speed)
    a = _positive(sensor_radius, "sensor_radius")
    if a >= lam:
        raise ValueError(f"sensor_radius must be smaller than the correlation length λ = {lam:g} m, got {a!r}")
    r = _positive(emission_rate, "emission_rate")
    dt = _positive(sample_time, "sample_time")
    return float(r * dt * 2.0 * np.pi * float(diffusivity) / np.log(lam / a))  # κ = R Δt 2πD / ln(λ/a)
