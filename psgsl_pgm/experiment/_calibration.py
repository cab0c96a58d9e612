"""Calibration of the olfactory estimators on runs that the evaluation never sees.

A calibration run is the fixed exploration tour in a house whose source is known (seeds 1000+, sources other
than the evaluated ones). From its readings alone — gas hits and the anemometer, never the simulated wind
field — :func:`calibrate` fits

* the plume parameters (D, τ, κ) by maximum likelihood of the hit model (:func:`psgsl_pgm.olfaction.
  fit_plume_parameters`), each run's plume solved with the mean wind the robot estimated from that run's
  anemometer readings (:class:`psgsl_pgm.olfaction.MeanWindEstimator`, all of its readings);
* the tempering β of :class:`psgsl_pgm.olfaction.GridInfotaxis` from the lag-1 autocorrelation of the hit
  model's Pearson residuals along each run at the fitted parameters (:func:`psgsl_pgm.olfaction.ar1_tempering`:
  β = n_eff / n = (1 − ρ̂)/(1 + ρ̂)).

The values stored as :class:`ExperimentConfig` defaults are this fit's, rounded to three significant digits;
``benchmarks/calibrate_olfaction.py`` re-makes it and a slow test re-derives them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..olfaction import (CalibrationRun, MeanWindEstimator, PlumeFit, PlumeModel, ar1_tempering,
                         fit_plume_parameters, hit_residuals)
from ..sim import make_world
from ._config import ExperimentConfig, parse_source
from ._robot_models import wind_basis
from ._run import walk
from ._tour import exploration_tour

__all__ = ["CALIBRATION_RUNS", "Calibration", "calibrate", "calibration_runs"]

#: (seed, source) of the calibration runs: seeds and sources disjoint from the evaluation's (oven, bed, the floor
#: point 5.0,6.0; seeds 0–999); two floor points in the bedrooms, where the dead-end rooms are.
CALIBRATION_RUNS = ((1000, "toilet"), (1001, "couch"), (1002, "tv"), (1003, "refrigerator"), (1004, "sink"),
                    (1005, "dining table"), (1006, "2.0,10.0"), (1007, "8.5,8.5"))


@dataclass(frozen=True)
class Calibration:
    """The fitted hit model: ``plume`` (D, τ, κ, log-likelihood), the residuals' pooled lag-1 autocorrelation
    ``rho`` and the tempering ``tempering`` = (1 − ρ)/(1 + ρ), and the number of readings ``n``."""

    plume: PlumeFit
    rho: float
    tempering: float
    n: int


def calibration_runs(runs=CALIBRATION_RUNS, *, config: ExperimentConfig | None = None) -> list:
    """The :class:`psgsl_pgm.olfaction.CalibrationRun` of each (seed, source): the tour's readings, and a plume
    model carrying the mean wind estimated from that run's own anemometer readings."""
    config = ExperimentConfig() if config is None else config
    runs = list(runs)
    if not runs:
        raise ValueError("runs must name at least one (seed, source) calibration run")
    out = []
    for seed, source in runs:
        world = make_world(seed=int(seed), source=parse_source(source), warm_up=config.warm_up)
        house = world.house
        wind = MeanWindEstimator(wind_basis(house), house.grid)
        positions, hits = [], []
        for _, stop, reading, w, _ in walk(world, exploration_tour(house), config, camera=False):
            wind.add(stop, w)
            positions.append(stop)
            hits.append(reading.hit)
        model = PlumeModel.from_grid_map(house.grid, wind.field(), outlets=house.outlet, cache_size=0)
        out.append(CalibrationRun(model, tuple(world.source), np.array(positions), np.array(hits)))
    return out


def calibrate(runs=CALIBRATION_RUNS, *, config: ExperimentConfig | None = None, **fit_options) -> Calibration:
    """Fit (D, τ, κ) and the tempering on calibration runs (module docstring).

    Parameters
    ----------
    runs : sequence of (int, str or (2,) array_like)
        (seed, source) pairs (default :data:`CALIBRATION_RUNS`).
    config : ExperimentConfig, optional, keyword-only
        ε, warm-up and robot timing; its plume parameters and tempering are ignored.
    **fit_options
        Passed to :func:`psgsl_pgm.olfaction.fit_plume_parameters` (grids, ``refine``).

    Returns
    -------
    Calibration
    """
    config = ExperimentConfig() if config is None else config
    data = calibration_runs(runs, config=config)
    fit = fit_plume_parameters(data, false_hit_rate=config.false_hit_rate, **fit_options)
    rho, beta = ar1_tempering(hit_residuals(data, fit, false_hit_rate=config.false_hit_rate))
    return Calibration(fit, rho, beta, int(sum(len(r.hits) for r in data)))
