"""Settings of the validation experiment, and the source specifications it accepts."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np

from .._validate import positive, real_pair

__all__ = ["ESTIMATORS", "ExperimentConfig", "VARIANTS", "parse_source"]

#: The three variants of the paper's Fig. error-chart, in the order they are reported.
VARIANTS = ("olfaction", "semantics", "semantics+rooms")

#: Olfactory estimators p(s | g) the experiment can run.
ESTIMATORS = ("infotaxis", "pmfs")

_MAY_BE_ZERO = frozenset({"warm_up", "turn_time", "false_hit_rate"})


@dataclass(frozen=True)
class ExperimentConfig:
    """Every knob of one search run (defaults = the reported experiment).

    Parameters
    ----------
    gas : str
        Target gas γ (a gas of :func:`house_ontology`); its source likelihood p(o | s, γ) drives the semantic term.
    warm_up : float
        Seconds of release before the robot starts (the plume develops).
    speed : float
        Robot speed between stops, m/s (the gas keeps evolving while it drives).
    turn_time : float
        Seconds per camera heading at a look-around waypoint.
    diffusivity, lifetime, encounter_scale : float
        Plume model of the olfactory estimators: D (m²/s), τ (s), κ (m²/s). D and τ are the values the olfaction
        module's house tests use; κ is fitted by maximum likelihood on calibration runs
        (:func:`calibrate_encounter_scale` on :data:`CALIBRATION_RUNS`, seeds and sources disjoint from the
        evaluation, gives 2.3589; stored to three significant digits).
    tempering, false_hit_rate : float
        β and ε of :class:`psgsl_pgm.olfaction.GridInfotaxis`.
    stops : int, optional
        Follow only the first ``stops`` stops of the tour (default: the whole tour). For quick checks and tests
        of the grid machinery; never part of a reported experiment.
    """

    gas: str = "smoke"
    warm_up: float = 60.0
    speed: float = 0.25
    turn_time: float = 1.0
    diffusivity: float = 0.03
    lifetime: float = 30.0
    encounter_scale: float = 2.36
    tempering: float = 0.5
    false_hit_rate: float = 0.01
    stops: int | None = None

    def __post_init__(self):
        if not isinstance(self.gas, str):
            raise TypeError(f"gas must be a gas name (str), got {type(self.gas).__name__}")
        if self.stops is not None and (isinstance(self.stops, bool) or not isinstance(self.stops, (int, np.integer))
                                       or self.stops < 1):
            raise ValueError(f"stops must be a positive integer or None (the whole tour), got {self.stops!r}")
        for f in fields(self):
            if f.name in ("gas", "stops"):
                continue
            v = positive(getattr(self, f.name), f.name, allow_zero=f.name in _MAY_BE_ZERO)  # bools, strings refused
            object.__setattr__(self, f.name, v)
        if not self.tempering <= 1 or not self.false_hit_rate < 1:
            raise ValueError(f"need tempering in (0, 1] and false_hit_rate in [0, 1), got {self.tempering!r}, "
                             f"{self.false_hit_rate!r}")

    def to_dict(self) -> dict:
        """The settings as a dict (stored with every run). ``stops`` appears only when set, so a whole-tour
        configuration has the same dict as before the option existed (its stored runs still resume)."""
        d = asdict(self)
        if d["stops"] is None:
            del d["stops"]
        else:
            d["stops"] = int(d["stops"])
        return d


def parse_source(spec) -> str | tuple:
    """A source specification: an object class name (``"oven"``: the centre of the house's first oven) or a
    position ``"x,y"`` in metres (a string or a pair of numbers).

    Examples
    --------
    >>> parse_source("oven"), parse_source("2.5,6.0"), parse_source((1, 2))
    ('oven', (2.5, 6.0), (1.0, 2.0))
    """
    if isinstance(spec, str):
        text = spec.strip()
        if "," in text:
            parts = text.split(",")
            try:
                xy = tuple(float(p) for p in parts)
            except ValueError:
                raise ValueError(f"a source position must read 'x,y' in metres, got {spec!r}") from None
            if len(xy) != 2 or not all(np.isfinite(xy)):
                raise ValueError(f"a source position must read 'x,y' in metres, got {spec!r}")
            return xy
        if not text:
            raise ValueError("a source must be an object class name or 'x,y', got an empty string")
        try:
            float(text)
        except ValueError:
            pass
        else:
            raise ValueError(f"a source must be an object class name or 'x,y' in metres, got the single number {spec!r}")
        return text
    if isinstance(spec, bytes):
        raise TypeError(f"a source must be an object class name (str) or an (x, y) position, got bytes {spec!r}")
    xy = real_pair(spec, "source", "an (x, y)", "metres")  # booleans, complex, strings inside: refused
    return (float(xy[0]), float(xy[1]))


def source_label(spec) -> str:
    """File-name-safe label of a source specification (``oven``, ``2.5_6.0``)."""
    s = parse_source(spec)
    if isinstance(s, str):
        return "".join(ch if ch.isalnum() else "-" for ch in s)
    return f"{s[0]:g}_{s[1]:g}"
