"""Settings of the validation experiment, and the source specifications it accepts."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields

import numpy as np

from .._shared._validate import positive, real_pair
from ..olfaction._infotaxis import _parameter_grid
from ..runs._key import OMIT_DEFAULT

__all__ = ["ESTIMATORS", "ESTIMATOR_NAMING", "ExperimentConfig", "PARAMETER_GRID", "UNKNOWN_GAS", "VARIANTS",
           "parse_source", "stored_estimator_name"]

#: The three variants of the paper's Fig. error-chart, in the order they are reported.
VARIANTS = ("olfaction", "semantics", "semantics+rooms")

#: Olfactory estimators p(s | g) the experiment can run: ``analytic-plume`` is the PMFS-family score on an analytic
#: advection-diffusion plume (:class:`psgsl_pgm.olfaction.PMFSEstimator`); ``pmfs`` is PMFS as published, with
#: filament simulations on the GMRF wind estimate (:class:`psgsl_pgm.olfaction.FilamentPMFS`); ``grgsl`` is
#: MAPIR's grid-based GSL (:class:`psgsl_pgm.olfaction.GrGSL`).
ESTIMATORS = ("infotaxis", "analytic-plume", "particle-filter", "pmfs", "grgsl")

#: Version of the estimator names written with every stored run (the ``estimator_naming`` field). Runs stored
#: without the field were written when ``"pmfs"`` named the analytic-plume estimator.
ESTIMATOR_NAMING = 2
_LEGACY_NAMES = {"pmfs": "analytic-plume"}


def stored_estimator_name(name: str, naming) -> str:
    """The current name of the estimator of a stored run: ``name`` as stored, ``naming`` its file's
    ``estimator_naming`` field (None when absent). A run stored without the field and named ``"pmfs"`` was made
    with the analytic-plume estimator and is read as ``"analytic-plume"``.

    >>> stored_estimator_name("pmfs", None), stored_estimator_name("pmfs", 2)
    ('analytic-plume', 'pmfs')
    """
    if naming is None:
        return _LEGACY_NAMES.get(name, name)
    return name


#: The ``gas`` of a run whose gas the robot is not told (:class:`ExperimentConfig`).
UNKNOWN_GAS = "unknown"

#: (D m²/s, τ s, κ m²/s, weight) of the plume parameters marginalised by the grid Infotaxis estimator
#: (:attr:`ExperimentConfig.parameter_grid`), fitted by :func:`psgsl_pgm.experiment.calibrate`.
PARAMETER_GRID = ((0.004, 284.0, 0.821, 0.308), (0.0131, 284.0, 0.821, 0.597), (0.04, 284.0, 1.642, 0.096))

_MAY_BE_ZERO = frozenset({"warm_up", "turn_time", "false_hit_rate", "missed_hit_rate", "wind_refresh", "off_ontology"})

#: How the robot reads its camera's labels: with its detector model estimated on reference houses, or with the
#: simulator's own (for measuring what the estimate changes).
DETECTOR_MODELS = ("estimated", "simulator")


@dataclass(frozen=True)
class ExperimentConfig:
    """Every knob of one search run (defaults = the reported experiment).

    Parameters
    ----------
    gas : str
        Target gas γ (a gas of :func:`house_ontology`); its source likelihood p(o | s, γ) drives the semantic term.
        ``"unknown"`` (:data:`UNKNOWN_GAS`): the episode's gas is drawn from the ontology's gases and not told to
        the robot, which infers it from its electronic nose and uses the gas mixture of the semantic term
        (:class:`psgsl_pgm.experiment.VariantPosteriors`).
    warm_up : float
        Seconds of release before the robot starts (the plume develops).
    speed : float
        Robot speed between stops, m/s (the gas keeps evolving while it drives).
    turn_time : float
        Seconds per camera heading at a look-around waypoint.
    diffusivity, lifetime, encounter_scale : float
        Plume model of the olfactory estimators: D (m²/s), τ (s), κ (m²/s), fitted by maximum likelihood of the
        hit model on calibration runs (:func:`calibrate` on :data:`CALIBRATION_RUNS`: seeds and sources disjoint
        from the evaluation, the wind estimated from the runs' own anemometer readings) — D = 0.01312,
        τ = 284.0, κ = 0.8213 over 1491 readings, stored to three significant digits.
    tempering : float
        β of :class:`psgsl_pgm.olfaction.GridInfotaxis`, from the same fit: the Pearson residuals of the hit model
        have pooled lag-1 autocorrelation ρ = 0.5414 along the calibration tours, β = (1 − ρ)/(1 + ρ) = 0.2976
        (the effective number of independent readings per reading of an AR(1) sequence). Chosen instead for
        coverage of the 90 % region on the 20 grid calibration runs (:func:`coverage_tempering`, the experiment's
        per-step code, ``benchmarks/calibration_coverage.py``) β = 0.261, its bootstrap interval 0.16–0.49
        holding this value, which is therefore kept.
    pmfs_tempering : float
        λ, the exponent of the score of :class:`psgsl_pgm.olfaction.PMFSEstimator` (estimator ``analytic-plume``;
        the field keeps its stored name), fitted by the log score of the
        known sources on the same calibration runs (:func:`pmfs_tempering`: 0.3801); for coverage of the 90 %
        region λ = 0.314, bootstrap interval 0.28–0.70 holding this value.
    filament_pmfs_tempering : float
        λ of :class:`psgsl_pgm.olfaction.FilamentPMFS` (estimator ``pmfs``), fitted the same way on the same runs
        (``benchmarks/calibrate_pmfs.py``: 0.0152; the mean log posterior of the true cell −8.07 against −74.7 at
        λ = 1, PMFS itself, and −8.85 for a uniform posterior over the house's free cells).
    false_hit_rate : float
        ε of :class:`psgsl_pgm.olfaction.GridInfotaxis` (held fixed in the fit).
    missed_hit_rate : float
        δ in [0, 1) of :class:`psgsl_pgm.olfaction.GridInfotaxis`: the probability that a reading misses the plume
        whatever the model predicts, so that one reading without a hit costs a candidate source at most
        −log((1 − ε)δ) nats. 0 (the default): the hit model without it — on the calibration runs its
        maximum-likelihood value (:func:`psgsl_pgm.olfaction.fit_plume_parameters` with ``fit_missed_hits=True``)
        is 0.
    parameter_grid : tuple of (D, τ, κ, weight), or None
        The plume parameters :class:`psgsl_pgm.olfaction.GridInfotaxis` marginalises over, with their population
        weights fitted on the calibration runs (:func:`calibrate`: the marginal maximum-likelihood mixing
        distribution of the run-level θ on the grid D ∈ {0.004, 0.0131, 0.04} m²/s × τ = 284 s ×
        κ ∈ {0.41, 0.821, 1.64} m²/s at the tempering β, components below 10⁻³ dropped, weights to three
        digits; :data:`PARAMETER_GRID`). ``None`` (the default): the single (D, τ, κ) above. The analytic-plume estimator uses the
        single (D, τ, κ) either way. The grid is not the default: on held-out seeds it brings the final coverage
        of the 90 % region into 0.80–0.97 in 5 of the 9 Infotaxis cells of the fixed tour (3 with the single
        fit), not in all, and costs about 5× the estimator's time per reading.
    wind_refresh : float
        The plume is re-solved with the robot's current wind estimate after its 1st, 2nd, 4th, 8th, … anemometer
        reading when the estimate's coefficients moved by more than this fraction (in norm) since the last solve.
    detector_model : {"estimated", "simulator"}
        How camera labels are read: with the detector model estimated on reference houses (the robot's own), or
        with the simulator's detector (to measure what the estimate changes).
    off_ontology : float
        ε in [0, 1]: the robot's prior probability that the source is off its ontology (emitted by whatever is in
        its cell), mixed into its p(o | s, γ) by :meth:`psgsl_pgm.Ontology.source_likelihood` — for the semantic
        term and φ_O alike. 0 (the default): the ontology as it stands.
    world_model : str, optional
        The simulated world's model (:class:`psgsl_pgm.sim.WorldModel`): ``ideal``, ``realistic`` or
        ``ideal+COMPONENT…``; None (the default): the world file's ``model`` (``ideal`` for the embedded house).
        The robot's models are the same in every world: only what the world does differs.
    stops : int, optional
        Follow only the first ``stops`` stops of the tour (default: the whole tour). For quick checks and tests
        of the grid machinery; never part of a reported experiment.
    """

    gas: str = "smoke"
    warm_up: float = 60.0
    speed: float = 0.25
    turn_time: float = 1.0
    diffusivity: float = 0.0131
    lifetime: float = 284.0
    encounter_scale: float = 0.821
    tempering: float = 0.298
    pmfs_tempering: float = 0.380
    filament_pmfs_tempering: float = field(default=0.0152, metadata={OMIT_DEFAULT: True})
    false_hit_rate: float = 0.01
    missed_hit_rate: float = field(default=0.0, metadata={OMIT_DEFAULT: True})
    parameter_grid: tuple | None = None
    wind_refresh: float = 0.05
    detector_model: str = "estimated"
    off_ontology: float = field(default=0.0, metadata={OMIT_DEFAULT: True})
    world_model: str | None = field(default=None, metadata={OMIT_DEFAULT: True})
    stops: int | None = None

    def __post_init__(self):
        if not isinstance(self.gas, str):
            raise TypeError(f"gas must be a gas name (str), got {type(self.gas).__name__}")
        if self.stops is not None and (isinstance(self.stops, bool) or not isinstance(self.stops, (int, np.integer))
                                       or self.stops < 1):
            raise ValueError(f"stops must be a positive integer or None (the whole tour), got {self.stops!r}")
        if self.parameter_grid is not None:  # rows (D, τ, κ, weight), as given (normalised by the estimator)
            _parameter_grid(self.parameter_grid)  # refuses a bad grid by name
            object.__setattr__(self, "parameter_grid", tuple(tuple(float(v) for v in row)
                                                             for row in self.parameter_grid))
        for f in fields(self):
            if f.name in ("gas", "stops", "detector_model", "parameter_grid", "world_model"):
                continue
            v = positive(getattr(self, f.name), f.name, allow_zero=f.name in _MAY_BE_ZERO)  # bools, strings refused
            object.__setattr__(self, f.name, v)
        if self.world_model is not None:  # the canonical name, so that one model has one run key
            from ..sim._world_model import WorldModel

            object.__setattr__(self, "world_model", WorldModel.parse(self.world_model).name)
        if self.detector_model not in DETECTOR_MODELS:
            raise ValueError(f"detector_model must be one of {DETECTOR_MODELS}, got {self.detector_model!r}")
        if not self.off_ontology <= 1:
            raise ValueError(f"off_ontology must lie in [0, 1], got {self.off_ontology!r}")
        if not self.missed_hit_rate < 1:
            raise ValueError(f"need missed_hit_rate in [0, 1), got {self.missed_hit_rate!r}")
        if not self.tempering <= 1 or not self.false_hit_rate < 1:
            raise ValueError(f"need tempering in (0, 1] and false_hit_rate in [0, 1), got {self.tempering!r}, "
                             f"{self.false_hit_rate!r}")

    def to_dict(self) -> dict:
        """The settings as a dict (stored with every run). ``stops``, ``parameter_grid`` and ``off_ontology``
        appear only when set, so a configuration without them has the same dict as before the options existed
        (its stored runs still resume)."""
        d = asdict(self)
        for f in fields(self):  # options added later, left out at their default (as in their run keys)
            if f.metadata.get(OMIT_DEFAULT) and d[f.name] == f.default:
                del d[f.name]
        if d["parameter_grid"] is None:
            del d["parameter_grid"]
        else:
            d["parameter_grid"] = [list(row) for row in d["parameter_grid"]]
        if d["stops"] is None:
            del d["stops"]
        else:
            d["stops"] = int(d["stops"])
        return d


def parse_source(spec) -> str | tuple:
    """A source specification: an object class name (``"oven"``: the centre of the house's first oven) or a
    position ``"x,y"`` in metres (a string or a pair of numbers).

    Parameters
    ----------
    spec : str or (2,) array_like of float
        ``"oven"``, ``"2.5,6.0"`` or ``(2.5, 6.0)``.

    Returns
    -------
    str or (2,) tuple of float
        The class name, or the position (x, y) in metres.

    Raises
    ------
    TypeError
        Neither a string nor a pair of numbers (bytes, a boolean, a complex number).
    ValueError
        An empty string, a single number, or a position that does not read as two finite numbers.

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
