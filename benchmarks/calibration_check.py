"""Calibration of the olfactory posteriors on held-out seeds, on the fixed tour.

    nice -n 5 python benchmarks/calibration_check.py --first-seed 200 --seeds 5 --out cal.json

For every (estimator, source, seed) it drives the exploration tour with the experiment's own per-step code
(:class:`psgsl_pgm.experiment.VariantPosteriors`) and records, per variant, whether the 90 % credible region
holds the true source cell at ¼, ½, ¾ of the tour and at its end, the region's area (m²), and the HPD level of the
true cell (the mass of the smallest highest-density region containing it); and, per stop, the hit model's
predicted P(hit | true source) with the observed hit and the stop's room (for the reliability diagram,
:func:`psgsl_pgm.experiment.plot_reliability`). Seeds must be ones never used for calibration (1000+) or for the
reference houses (10000+).
"""

import argparse
import json
import time

import numpy as np

from _tour_runs import add_run_arguments, start_tour_run
from psgsl_pgm.experiment import ExperimentConfig, VARIANTS
from psgsl_pgm.experiment._run import walk
from psgsl_pgm.search import credible_region


def hpd_level(post, cell):
    """Mass of the smallest highest-density region holding ``cell``: Σ_{c: p_c ≥ p_cell} p_c."""
    p = post[cell]
    return float(post[post >= p].sum())


def one_run(source, seed, estimator, config):
    config, world, tour, beliefs, cell = start_tour_run(source, seed, estimator, config)
    house = world.house
    n = len(tour)
    checkpoints = {int(round(f * n)): name for f, name in ((0.25, "quarter"), (0.5, "half"), (0.75, "three_quarters"),
                                                         (1.0, "final"))}
    out = {v: {} for v in VARIANTS}
    eps = config.false_hit_rate
    stops = []
    for j, stop, reading, wind, frames in walk(world, tour, config, camera=not beliefs.mapped):
        beliefs.observe(stop, reading, wind, frames)
        m = beliefs.model
        g = m.green(stop)[cell]  # G(x_stop | s_true)
        p_hit = eps + (1 - eps) * -np.expm1(-m.encounter_scale * g)
        r, c = house.grid.cell_of(stop)
        room = int(house.room_labels[r, c])
        stops.append((float(p_hit), bool(reading.hit), house.room_names[room] if room >= 0 else "none"))
        if j + 1 in checkpoints:
            post = beliefs.posteriors(VARIANTS)
            for v, p in zip(VARIANTS, post):
                region = credible_region(p, 0.9)
                out[v][checkpoints[j + 1]] = {"covered": bool(region[cell]),
                                              "area": float(region.sum() * house.grid.resolution ** 2),
                                              "hpd_level": hpd_level(p, cell)}
    return {"source": source, "seed": seed, "estimator": estimator, "variants": out, "stops": stops,
            "wind_solves": getattr(beliefs, "n_wind_solves", None)}


def main():
    ap = argparse.ArgumentParser()
    add_run_arguments(ap, first_seed=200, seeds=5)
    ap.add_argument("--detector-model", default=None, help="estimated | simulator (new code only)")
    a = ap.parse_args()
    kw = {} if a.detector_model is None else {"detector_model": a.detector_model}
    config = ExperimentConfig(**kw)
    runs = []
    t0 = time.perf_counter()
    for est in a.estimators:
        for src in a.sources:
            for seed in range(a.first_seed, a.first_seed + a.seeds):
                runs.append(one_run(src, seed, est, config))
                print(f"{est} {src} {seed} {time.perf_counter() - t0:.0f} s", flush=True)
                with open(a.out + ".tmp", "w") as f:
                    json.dump({"config": config.to_dict(), "runs": runs}, f)
    import os
    os.replace(a.out + ".tmp", a.out)


if __name__ == "__main__":
    main()
