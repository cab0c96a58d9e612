"""The robot's close-range source detector in the simulated world: does a pass near the source confirm it?

A robot that comes close to a leak can tell (a concentration far above anything the plume carries elsewhere, a
visible flame or a hissing valve, a handheld confirmation). The closed loop (:mod:`psgsl_pgm.search._loop`)
models it as one detection trial per move: a move whose path comes within the found radius of the source's
found region detects it with probability 1 − m and never detects a source that is not there (no false alarms).
The detector only reports; the robot decides where the source is (:mod:`psgsl_pgm.search._declare`).

The simulator holds the true miss probability m; the robot never reads it and estimates it by counting passes
on reference runs (``psgsl_pgm.experiment._robot_models.robot_source_miss_probability``).
"""

from __future__ import annotations

from .._shared._validate import unit_interval

__all__ = ["SourceDetector"]

#: Miss probability of the realistic world's detector. An assumption, not a measurement: one pass in five within
#: reach of a leak goes unnoticed (occluded, downwind of a gust, the robot turned away).
REALISTIC_MISS_PROBABILITY = 0.2


class SourceDetector:
    """A close-range detector that can miss (module docstring).

    Parameters
    ----------
    miss_probability : float, keyword-only
        m in [0, 1): probability that a move within reach of the source does not detect it (0: the ideal world's
        detector, which never misses).

    Examples
    --------
    >>> SourceDetector().miss_probability
    0.0
    >>> SourceDetector.realistic().miss_probability
    0.2
    """

    def __init__(self, *, miss_probability: float = 0.0):
        self.miss_probability = unit_interval(miss_probability, "miss_probability", high_open=True)

    @classmethod
    def realistic(cls) -> "SourceDetector":
        """The realistic world's detector (m = :data:`REALISTIC_MISS_PROBABILITY`)."""
        return cls(miss_probability=REALISTIC_MISS_PROBABILITY)

    def detects(self, within_reach: bool, rng) -> bool:
        """One trial: True with probability 1 − m when ``within_reach``, never otherwise. A detector that never
        misses draws nothing from ``rng``."""
        if not within_reach:
            return False
        if self.miss_probability == 0.0:
            return True
        return bool(rng.random() >= self.miss_probability)

    def __repr__(self) -> str:
        return f"SourceDetector(miss_probability={self.miss_probability:g})"
