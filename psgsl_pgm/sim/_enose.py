r"""An electronic nose in the simulated world: which gas is it?

A gas reading says *how much* gas there is; it does not say *which* gas. An electronic nose does, imperfectly: an
array of metal-oxide sensors with overlapping, gas-specific sensitivities, and a classifier that names the gas
whose stored response pattern the array's response resembles most (Persaud & Dodd 1982, Nature 299:352–355;
Gardner & Bartlett 1994, Sens. Actuators B 18:210–211).

**Response.** Sensor j of the array answers gas γ at the window-mean concentration x (ppm) with

.. math:: r_j = A_{j\gamma}\,(x / x_\text{ref})^{\beta} + \varepsilon_j, \qquad \varepsilon_j \sim N(0, \sigma^2),

the power law of a metal-oxide sensor's steady-state response (Clifford & Tuma 1982, Sensors and Actuators
3:233–254; β ≈ 0.5, Yamazoe & Shimanoe 2008, Sens. Actuators B 128:566–573), in units of the response at
x_ref = 1 ppm. The columns of A are the gases' response *patterns*, each of unit length, so that the strength
‖r‖ of a reading depends on the concentration and the noise, not on the gas. The default array
(:data:`ENOSE_SENSORS`) is modelled on four Figaro sensors of household e-noses — TGS2600 (air contaminants,
combustion gases), TGS2602 (ammonia, VOCs), TGS2611 (methane), TGS2620 (alcohols, solvents) — with relative
sensitivities chosen from the datasheets' orders of magnitude so that the patterns overlap (a smoke pattern and
an ethanol pattern are at cosine 0.83): illustrative values, not a calibration of those parts.

**Classifier.** The device names the gas γ whose pattern has the largest inner product with r (nearest pattern
in angle, the patterns being of equal length), and reports the reading's strength ‖r‖; below its detection
limit it names none (``label`` None). Weak readings classify worse: the noise then turns r away from its
gas's pattern. The device's patterns and noise are the simulator's; the robot never reads them and counts the
confusion p(ζ | γ, strength) on reference exposures of its own device
(:func:`psgsl_pgm.experiment.robot_gas_confusion`).

The world owns an e-nose only when asked (``make_world(enose=...)``); it then classifies the gas sensor's window
(:meth:`psgsl_pgm.sim.World.sniff`) with its own random stream, so every other stream draws as without it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._shared._validate import names, positive

__all__ = ["ENOSE_GASES", "ENOSE_SENSORS", "ElectronicNose", "Smell", "draw_gas"]

#: The sensors of the default array (module docstring).
ENOSE_SENSORS: tuple[str, ...] = ("TGS2600", "TGS2602", "TGS2611", "TGS2620")

#: The gases the default array has patterns for; the house ontology's gases (``psgsl_pgm/data/house_gases.yaml``).
ENOSE_GASES: tuple[str, ...] = ("smoke", "ethanol", "ammonia", "natural gas")

#: Relative sensitivity of each sensor (rows, :data:`ENOSE_SENSORS`) to each gas (columns, :data:`ENOSE_GASES`),
#: before the columns are scaled to unit length (module docstring).
_SENSITIVITY = np.array([
    # smoke ethanol ammonia natural gas
    [1.00, 0.45, 0.30, 0.30],   # TGS2600: combustion gases (CO, H2) first
    [0.60, 0.60, 1.00, 0.10],   # TGS2602: ammonia and VOCs
    [0.20, 0.20, 0.10, 1.00],   # TGS2611: methane
    [0.50, 1.00, 0.30, 0.35],   # TGS2620: alcohols and solvents
])


@dataclass(frozen=True)
class Smell:
    """One classified reading of the electronic nose.

    Attributes
    ----------
    label : str or None
        The gas the device names, ζ; None below its detection limit (no classification).
    strength : float
        ‖r‖, the length of the array's response (units of the response at 1 ppm).
    """

    label: str | None
    strength: float


def draw_gas(gases, seed: int) -> str:
    """The episode's gas when it is unknown to the robot: one of ``gases``, uniformly, from a stream of ``seed``
    of its own (no other stream of the world draws differently).

    Parameters
    ----------
    gases : sequence of str
        The ontology's gases.
    seed : int
        The episode's seed.

    Returns
    -------
    str

    Raises
    ------
    TypeError
        ``gases`` is not a sequence of names (e.g. one str), or ``seed`` is not an integer.
    ValueError
        ``gases`` is empty or repeats a name.

    Examples
    --------
    >>> draw_gas(("smoke", "ethanol"), 0) in ("smoke", "ethanol")
    True
    """
    gases = names(gases, "gases")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"seed must be an integer, got {seed!r}")
    rng = np.random.default_rng(np.random.SeedSequence([int(seed)], spawn_key=(0x6A5,)))
    return gases[int(rng.integers(len(gases)))]


class ElectronicNose:
    """A metal-oxide sensor array and its nearest-pattern classifier (module docstring).

    Parameters
    ----------
    gases : tuple of str, keyword-only
        The gases the device knows (default :data:`ENOSE_GASES`, with the default array's patterns).
    sensitivity : (n_sensors, n_gases) array_like, optional, keyword-only
        Relative sensitivities, non-negative, no all-zero column (scaled to unit columns); default: the default
        array's, which needs the default ``gases``.
    exponent : float, keyword-only
        β of the power-law response (> 0).
    noise_std : float, keyword-only
        σ of each sensor's additive noise, in units of the response at 1 ppm (> 0).
    detection_limit : float, keyword-only
        The strength ‖r‖ below which the device names no gas (> 0).

    Examples
    --------
    >>> nose = ElectronicNose()
    >>> rng = np.random.default_rng(0)
    >>> nose.classify(20.0, "ammonia", rng).label        # a strong reading is named right
    'ammonia'
    >>> nose.classify(0.0, "ammonia", rng).label is None  # clean air, mostly below the limit
    True
    """

    def __init__(self, *, gases=ENOSE_GASES, sensitivity=None, exponent: float = 0.5, noise_std: float = 0.15,
                 detection_limit: float = 0.45):
        self.gases = names(gases, "gases")
        if sensitivity is None:
            if self.gases != ENOSE_GASES:
                raise ValueError(f"sensitivity is required for gases other than the default array's {ENOSE_GASES}, "
                                 f"got gases {self.gases}")
            sensitivity = _SENSITIVITY
        a = np.asarray(sensitivity, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != len(self.gases) or not np.isfinite(a).all() or (a < 0).any():
            raise ValueError(f"sensitivity must be a finite, non-negative (n_sensors, {len(self.gases)}) array, got "
                             f"shape {a.shape}")
        norms = np.linalg.norm(a, axis=0)
        if (norms == 0).any():
            raise ValueError("sensitivity: every gas needs a sensor that responds to it (a column of zeros)")
        self._patterns = a / norms  # unit columns
        self.exponent = positive(exponent, "exponent")
        self.noise_std = positive(noise_std, "noise_std", "response units")
        self.detection_limit = positive(detection_limit, "detection_limit", "response units")

    @property
    def n_sensors(self) -> int:
        return self._patterns.shape[0]

    def respond(self, concentration, gas: str, rng) -> np.ndarray:
        """(..., n_sensors) responses r to ``gas`` at ``concentration`` (ppm, any shape, ≥ 0), noise from ``rng``."""
        x = np.asarray(concentration, dtype=np.float64)
        if not np.isfinite(x).all() or (x < 0).any():
            raise ValueError("concentration must be finite and non-negative, ppm")
        if gas not in self.gases:
            raise ValueError(f"gas must be one of the e-nose's gases {self.gases}, got {gas!r}")
        signal = x[..., None] ** self.exponent * self._patterns[:, self.gases.index(gas)]
        return signal + self.noise_std * rng.standard_normal(signal.shape)

    def decide(self, response) -> tuple[np.ndarray, np.ndarray]:
        """The classifier on responses (..., n_sensors): ``(label index, strength)``, index −1 below the limit."""
        r = np.asarray(response, dtype=np.float64)
        strength = np.linalg.norm(r, axis=-1)
        label = np.argmax(r @ self._patterns, axis=-1)
        return np.where(strength >= self.detection_limit, label, -1), strength

    def classify(self, concentration: float, gas: str, rng) -> Smell:
        """One classified reading of ``gas`` at ``concentration`` ppm (:class:`Smell`)."""
        label, strength = self.decide(self.respond(float(concentration), gas, rng))
        i = int(label)
        return Smell(None if i < 0 else self.gases[i], float(strength))

    def __repr__(self) -> str:
        return (f"ElectronicNose(gases={self.gases}, exponent={self.exponent:g}, noise_std={self.noise_std:g}, "
                f"detection_limit={self.detection_limit:g})")
