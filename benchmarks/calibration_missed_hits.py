"""The missed-hit rate δ of the hit model, fitted on fixed tours in reference homes (not a test).

Tours of :func:`psgsl_pgm.experiment.exploration_tour` in generated homes of the generator's reference seeds
(1 000 000 + h, never evaluated by ``psgsl benchmark``), two sources per home (the first two kitchen appliances or
beds), the wind estimated from the run's own anemometer readings. The expected encounters at each reading are
computed under the plume of the embedded house's calibration (``ExperimentConfig``'s D, τ) with either the wind
estimate of the whole run (as :func:`psgsl_pgm.experiment.calibration_runs` does) or the *online* estimate the
robot holds at that reading (re-solved at readings 1, 2, 4, 8, …, as the closed loop does); for each, the
maximum-likelihood κ with δ = 0 and the joint (κ, δ) of :func:`psgsl_pgm.olfaction.fit_hit_model`, and the
log-likelihood at the configured κ with δ = 0, its worst miss and the misses where it predicts more than five
encounters.

Run: ``python benchmarks/calibration_missed_hits.py [--homes 5]``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from psgsl_pgm.experiment import ExperimentConfig, exploration_tour
from psgsl_pgm.experiment._robot_models import wind_basis
from psgsl_pgm.experiment._run import walk
from psgsl_pgm.olfaction import (MeanWindEstimator, PlumeModel, encounter_scale_mle, fit_hit_model,
                                 hit_log_likelihood)
from psgsl_pgm.sim import generate_house, load_world

SOURCES = ("oven", "stove", "toaster", "microwave", "refrigerator", "bed")


def tour_readings(spec, house_seed: int, source, config: ExperimentConfig):
    """(hits, expected encounters per reading / κ with the whole-run wind, the same with the online wind)."""
    world = spec.make_world(house_seed, tuple(source), warm_up=config.warm_up)
    house = world.house
    wind = MeanWindEstimator(wind_basis(house), house.grid)
    positions, hits, coefficients = [], [], []
    tour = exploration_tour(house, start=spec.start_for(house))
    for _, stop, reading, w, _ in walk(world, tour, config, camera=False):
        wind.add(stop, w)
        positions.append(stop)
        hits.append(reading.hit)
        coefficients.append(wind.coefficients.copy())

    def field(a):
        model = PlumeModel.from_grid_map(house.grid, wind.field(a), outlets=house.outlet,
                                         diffusivity=config.diffusivity, lifetime=config.lifetime, cache_size=0)
        return model, model.concentration(tuple(world.source))

    model, whole = field(None)
    cells = [model.cell_of(p) for p in positions]
    c_whole = np.array([whole[r, c] for r, c in cells])
    c_online = []
    for k, (r, c) in enumerate(cells):
        if k == 0 or not (k + 1) & k:  # readings 1, 2, 4, 8, ...: the closed loop's re-solves
            _, online = field(coefficients[k])
        c_online.append(online[r, c])
    return np.array(hits), c_whole, np.array(c_online)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--homes", type=int, default=5)
    args = ap.parse_args(argv)
    config = ExperimentConfig()
    eps = config.false_hit_rate
    hits, whole, online = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for h in range(args.homes):
            spec = load_world(generate_house(1_000_000 + h).write(Path(tmp) / f"h{h}"))
            objects = [o for o in spec.house(0).objects if o.class_name in SOURCES][:2]
            for k, obj in enumerate(objects):
                g, cw, co = tour_readings(spec, 7 + k, obj.center, config)
                hits.append(g), whole.append(cw), online.append(co)
                print(f"home {1_000_000 + h}, {obj.class_name}: {g.size} readings, {int(g.sum())} hits", flush=True)
    g = np.concatenate(hits)
    for name, c in (("whole-run wind", np.concatenate(whole)), ("online wind", np.concatenate(online))):
        kappa, delta, ll = fit_hit_model(c, g, false_hit_rate=eps)
        k0 = encounter_scale_mle(c, g, false_hit_rate=eps)
        mu = config.encounter_scale * c
        miss = np.log1p(-eps) - mu[~g]  # log P(miss) at the configured κ, δ = 0
        print(f"{name}: n = {g.size}, hits {int(g.sum())} | δ = 0: κ̂ = {k0:.4g}, log L = "
              f"{hit_log_likelihood(c, g, k0, eps):.2f} | joint: κ̂ = {kappa:.4g}, δ̂ = {delta:.4g}, log L = {ll:.2f}")
        print(f"    configured κ = {config.encounter_scale}, δ = 0: log L = "
              f"{hit_log_likelihood(c, g, config.encounter_scale, eps):.2f}, worst miss {miss.min():.1f} nats, "
              f"misses with κc > 5: {int((mu[~g] > 5).sum())}")


if __name__ == "__main__":
    main()
