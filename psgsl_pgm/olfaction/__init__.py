r"""Olfactory estimators :math:`p(s \mid g)` of the gas source location from hit/miss readings.

The estimators share one interface (:class:`OlfactoryEstimator`: ``update(position, hit, wind)``,
``posterior``, ``reset()``) and one plume model (:class:`PlumeModel`: steady advection-diffusion on the
occupancy grid (:class:`psgsl_pgm.GridMap`) with no-flux walls, absorbing outlets and the map's wind field, solved once with a sparse LU
factorisation; Green's functions for all candidate sources from one adjoint solve per sensor cell):

* :class:`GridInfotaxis` — Bayesian hit/miss posterior with Poisson encounters,
  :math:`P(\text{hit} \mid s) = 1 - e^{-\kappa G}` (Vergassola et al. 2007), tempered against correlated readings;
* :class:`PMFSEstimator` — the PMFS family (the paper's baseline, Sec. "Validation"): a hit-probability map
  with confidence compared with the hit map each candidate source would produce;
* :class:`FilamentPMFS` — PMFS as published (Ojeda et al. 2024): a GMRF wind map from the anemometer
  (:class:`GMRFWind`), hit maps simulated with filaments on it from candidate regions, compared with the
  measured hit map;
* :class:`GrGSL` — MAPIR's grid-based GSL (Ojeda et al. 2021): upwind after a hit, towards the last hit after a
  miss, propagated over the free space;
* :class:`ParticleFilter` — sequential importance resampling over the source's position and release rate on the
  same likelihood as :class:`GridInfotaxis`, :math:`p(s \mid g)` the particles' weight per cell.

Every posterior is the olfactory factor of eq. (11),
:math:`p(s_c \mid g, z) \propto p(s_c \mid g)\, p(s_c \mid z)`, and is combined with the semantic term by
:func:`psgsl_pgm.fuse`.

Hits are the robot's decision from its sensor's output (:class:`HitRule`: the rate of rise for a metal-oxide
sensor, the baseline-subtracted level for a fast one, each estimated online from the robot's own readings).

The open-space analytic solution of Vergassola et al. (:func:`vergassola_concentration`) validates the grid
model.
"""

from ._analytic import (
    correlation_length,
    vergassola_concentration,
    vergassola_encounter_rate,
    vergassola_encounter_scale,
)
from ._base import Observation, OlfactoryEstimator
from ._calibrate import (
    CalibrationRun,
    PlumeFit,
    ar1_tempering,
    encounter_scale_mle,
    fit_encounter_scale,
    fit_hit_model,
    fit_plume_parameters,
    hit_log_likelihood,
    hit_residuals,
    mixture_weights,
    profile_log_likelihood,
    score_tempering,
)
from ._filament_pmfs import FilamentPMFS
from ._gmrf_wind import GMRFWind
from ._grgsl import GrGSL
from ._hitmap import HitProbabilityMap
from ._hits import HIT_RULE_KINDS, HitRule
from ._infotaxis import GridInfotaxis
from ._operator import advection_diffusion_operator, bernoulli
from ._particle import ParticleFilter
from ._plume import PlumeModel
from ._pmfs import PMFSEstimator
from ._wind_estimate import MeanWindEstimator

__all__ = [
    "HIT_RULE_KINDS",
    "CalibrationRun",
    "FilamentPMFS",
    "GMRFWind",
    "GrGSL",
    "GridInfotaxis",
    "HitProbabilityMap",
    "HitRule",
    "MeanWindEstimator",
    "Observation",
    "OlfactoryEstimator",
    "PMFSEstimator",
    "ParticleFilter",
    "PlumeFit",
    "PlumeModel",
    "advection_diffusion_operator",
    "ar1_tempering",
    "bernoulli",
    "correlation_length",
    "encounter_scale_mle",
    "fit_encounter_scale",
    "fit_hit_model",
    "fit_plume_parameters",
    "hit_log_likelihood",
    "hit_residuals",
    "mixture_weights",
    "profile_log_likelihood",
    "score_tempering",
    "vergassola_concentration",
    "vergassola_encounter_rate",
    "vergassola_encounter_scale",
]
