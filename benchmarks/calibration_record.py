"""Record the olfactory evidence of fixed-tour runs, so that credible regions can be evaluated at any tempering.

    nice -n 5 python benchmarks/calibration_record.py --first-seed 300 --seeds 20 --out rec300      # held out
    nice -n 5 python benchmarks/calibration_record.py --calibration --out rec_cal                    # calibration

Each (estimator, source, seed) runs the fixed tour with the experiment's own per-step code
(:class:`psgsl_pgm.experiment.VariantPosteriors`; Infotaxis with the single fit (D, τ, κ) of
:class:`ExperimentConfig`, or with ``--grid`` :data:`psgsl_pgm.experiment.PARAMETER_GRID`, whose middle row is
that fit) and stores, at ¼, ½, ¾ of the run's
time and at its end (:func:`psgsl_pgm.experiment._metrics.at_fractions`, as ``psgsl experiment`` does):

* Infotaxis: the *untempered* accumulated log-likelihood Σ_k log P_θj(g_k | s) of every grid component j, (J, H·W);
* analytic-plume: the untempered score S(s), (1, H·W);
* the estimator's log prior, p(s | z) of both semantic variants (held-out runs), the true cell.

A tempered posterior p(s | g) ∝ p(s) Σ_j π_j exp(β L_j(s)) (Infotaxis, any β and weights; one component: the
single fit) or p(s) exp(λ S(s)) (analytic-plume) is then exact arithmetic on the record
(:func:`psgsl_pgm.experiment.recorded_posterior`), and the stored posterior of the default configuration is
checked against it. ``--calibration`` runs :data:`psgsl_pgm.experiment.GRID_CALIBRATION_RUNS` (olfaction only,
no camera, as :func:`psgsl_pgm.experiment.calibration_runs`).
"""

import argparse
import os
import time

import numpy as np

from _tour_runs import add_run_arguments, start_tour_run
from psgsl_pgm.experiment import GRID_CALIBRATION_RUNS, PARAMETER_GRID, ExperimentConfig, VARIANTS
from psgsl_pgm.experiment._metrics import CALIBRATION_POINTS, at_fractions
from psgsl_pgm.experiment._run import walk


def one_run(source, seed, estimator, config, *, semantics: bool, grid: bool):
    grid_config = ExperimentConfig(**{**config.to_dict(), "parameter_grid": PARAMETER_GRID}) \
        if estimator == "infotaxis" and grid else config
    variants = VARIANTS if semantics else ("olfaction",)
    grid_config, world, tour, beliefs, cell = start_tour_run(source, seed, estimator, grid_config, variants=variants)
    house = world.house
    est = beliefs.estimator
    t0 = world.time
    times, states = [0.0], [None]
    for j, stop, reading, wind, frames in walk(world, tour, grid_config, camera=semantics and not beliefs.mapped):
        beliefs.observe(stop, reading, wind, frames)
        if estimator == "infotaxis":
            ell = est._loglik / est.tempering  # Σ_k log P_θj(g_k | s), untempered
        else:
            ell = est.score.ravel()[None, :]
        sem = (np.stack([beliefs.semantic(v).ravel() for v in VARIANTS[1:]]) if semantics
               else np.zeros((0, ell.shape[1])))
        states.append((ell.copy(), sem, est.posterior.ravel().copy()))
        times.append(world.time - t0)
    steps = at_fractions(np.array(times), np.arange(len(times)), list(CALIBRATION_POINTS.values()))
    steps = [int(s) for s in steps]
    if any(s == 0 for s in steps):
        raise RuntimeError("a checkpoint before the first reading")
    return {
        "loglik": np.stack([states[s][0] for s in steps]),  # (4, J, N)
        "semantic": np.stack([states[s][1] for s in steps]),  # (4, 2 or 0, N)
        "posterior": np.stack([states[s][2] for s in steps]),  # (4, N) of the recording configuration
        "log_prior": np.asarray(est._log_prior),
        "cell": int(cell[0] * house.shape[1] + cell[1]),
        "cell_area": float(house.grid.resolution ** 2),
        "tempering": float(est.tempering),
        "weights": np.ones(1) if getattr(est, "n_components", 1) == 1 else np.asarray(est.parameter_grid[:, 3]),
        "steps": np.array(steps),
    }


def main():
    ap = argparse.ArgumentParser()
    add_run_arguments(ap, first_seed=300, seeds=20)
    ap.add_argument("--calibration", action="store_true", help="the grid calibration runs, olfaction only")
    ap.add_argument("--olfaction-only", action="store_true", help="no camera, no semantic variants")
    ap.add_argument("--grid", action="store_true", help="Infotaxis with PARAMETER_GRID (about 3x the time)")
    a = ap.parse_args()
    config = ExperimentConfig()
    if a.calibration:
        jobs = [(src, seed) for seed, src in GRID_CALIBRATION_RUNS]
    else:
        jobs = [(src, seed) for seed in range(a.first_seed, a.first_seed + a.seeds) for src in a.sources]
    os.makedirs(a.out, exist_ok=True)
    t0 = time.perf_counter()
    for est in a.estimators:
        for src, seed in jobs:
            path = os.path.join(a.out, f"{est}_{src}_{seed}.npz")
            if os.path.exists(path):
                continue
            t1 = time.perf_counter()
            rec = one_run(src, seed, est, config, semantics=not (a.calibration or a.olfaction_only), grid=a.grid)
            np.savez_compressed(path + ".tmp.npz", estimator=est, source=src, seed=seed, **rec)
            os.replace(path + ".tmp.npz", path)
            print(f"{est} {src} {seed} {time.perf_counter() - t1:.0f} s (total {time.perf_counter() - t0:.0f} s)",
                  flush=True)


if __name__ == "__main__":
    main()
