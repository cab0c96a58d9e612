"""Calibration of the plume model's encounter scale κ on runs that the evaluation never sees."""

from __future__ import annotations

import numpy as np

from ..olfaction import PlumeModel, encounter_scale_mle
from ..sim import make_world
from ._config import ExperimentConfig, parse_source
from ._run import walk
from ._tour import exploration_tour

__all__ = ["CALIBRATION_RUNS", "calibrate_encounter_scale"]

#: (seed, source) of the calibration runs: seeds and source objects disjoint from the evaluation's.
CALIBRATION_RUNS = ((1000, "toilet"), (1001, "couch"), (1002, "tv"), (1003, "refrigerator"))


def calibrate_encounter_scale(runs=CALIBRATION_RUNS, *, config: ExperimentConfig | None = None) -> float:
    """Maximum-likelihood κ pooled over calibration runs with known sources.

    Each run drives the exploration tour in ``make_world(seed=seed, source=source)`` and records the hit/miss
    readings; with c_k = G(x_k | s_true) from the plume model (D, τ of ``config``; the run's mean wind), κ
    maximises Π_k P(g_k | κ c_k), P(hit) = ε + (1 − ε)(1 − exp(−κ c)), over all readings of all runs
    (:func:`psgsl_pgm.olfaction.encounter_scale_mle`).

    Parameters
    ----------
    runs : sequence of (int, str or (2,) array_like)
        (seed, source) pairs.
    config : ExperimentConfig, optional, keyword-only
        D, τ, ε, warm-up and robot timing; its ``encounter_scale`` is ignored.

    Returns
    -------
    kappa : float
        m²/s.
    """
    config = ExperimentConfig() if config is None else config
    runs = list(runs)
    if not runs:
        raise ValueError("runs must name at least one (seed, source) calibration run")
    predicted, hits = [], []
    for seed, source in runs:
        world = make_world(seed=int(seed), source=parse_source(source), warm_up=config.warm_up)
        model = PlumeModel.from_grid_map(world.house.grid, world.wind.mean().velocity, outlets=world.house.outlet,
                                         diffusivity=config.diffusivity, lifetime=config.lifetime)
        field = model.concentration(world.source)  # G(x | s_true) for every sensor cell x
        tour = exploration_tour(world.house)
        for _, stop, reading, _, _ in walk(world, tour, config, camera=False):
            r, c = model.cell_of(stop)
            predicted.append(field[r, c])
            hits.append(reading.hit)
    return encounter_scale_mle(np.array(predicted), np.array(hits), false_hit_rate=config.false_hit_rate)
