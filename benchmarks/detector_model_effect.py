"""What the robot's own detector model changes: the validation experiment run twice on the same seeds, once with
the detector model the robot estimates from reference houses and once with the simulator's (not a test).

The robot reads its camera's labels through a confusion matrix, a false-positive rate and a detection curve.
By default (``ExperimentConfig(detector_model="estimated")``) these are counted on frames of reference houses
that are never evaluated (``psgsl_pgm.experiment.robot_detector_model``); ``detector_model="simulator"`` hands
the robot the model that made the detections, so data are made and read with one model. Both runs share every
observation (the detections themselves do not depend on how the robot reads them), so the differences are paired
by seed. Only the semantic variants read the camera; the script checks that ``olfaction`` is bit-identical.

First the two models side by side: the largest and the mean absolute difference of their confusion matrices
p(label | class), their detection curves' p_max, near and scale, and their false-positive rates. Then, per
source × estimator × semantic variant: the final error and the error averaged over the search, mean of each
model and the paired difference simulator − estimated with its Student-t 95 % interval over seeds (errors are not
censored), and the calibration at the end of the tour (coverage of the 90 % region, its mean area, the median HPD
level of the source's cell) for each model.

Run: ``python benchmarks/detector_model_effect.py OUT [--seeds 10] [--first-seed 0] [--estimators infotaxis analytic-plume]
[--sources oven bed 5,6] [--workers 2]``; the runs go to ``OUT/estimated`` and ``OUT/simulator`` (resumable, as
``psgsl experiment``). Seeds 0–9 are the validation page's: its ``estimated`` rows are that page's table.
"""

from __future__ import annotations

import argparse
from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy import stats

from psgsl_pgm.experiment import ExperimentConfig, run_experiment
from psgsl_pgm.experiment._config import VARIANTS
from psgsl_pgm.experiment._store import load_run
from psgsl_pgm.experiment._robot_models import robot_detector_model
from psgsl_pgm.experiment._summary import aligned
from psgsl_pgm.sim import default_world

MODELS = ("estimated", "simulator")


def _runs(folder: Path) -> dict:
    """{(source, estimator, seed): RunResult} of ``folder/runs``."""
    out = {}
    for path in sorted((folder / "runs").glob("*.npz")):
        run = load_run(path)
        out[run.source, run.estimator, run.seed] = run
    return out


def paired_t(diff) -> tuple:
    """Mean and Student-t 95 % interval of paired differences (one per seed)."""
    diff = np.asarray(diff, dtype=np.float64)
    m = float(diff.mean())
    if diff.size < 2:
        return m, (float("nan"), float("nan"))
    half = float(stats.t.ppf(0.975, diff.size - 1) * diff.std(ddof=1) / np.sqrt(diff.size))
    return m, (m - half, m + half)


def compare(folders: dict) -> list:
    """One row per (source, estimator, variant) of the semantic variants, over the seeds both folders hold.

    Raises ValueError if the ``olfaction`` variant differs between the two models on any run (it must not read
    the camera)."""
    runs = {model: _runs(folders[model]) for model in MODELS}
    keys = sorted(set(runs["estimated"]) & set(runs["simulator"]))
    groups = defaultdict(list)
    for key in keys:
        a, b = runs["estimated"][key], runs["simulator"][key]
        if not np.array_equal(a.error[:, 0], b.error[:, 0]):
            raise ValueError(f"olfaction differs between the detector models in run {key}")
        groups[key[:2]].append((a, b))
    rows = []
    grids = {"final_error": [1.0], "mean_error": np.linspace(0.0, 1.0, 101)}
    for (source, estimator), pairs in sorted(groups.items()):
        # (runs, 3): the error at the end and averaged over the search, per model, every variant at once
        errors = {name: [aligned([p[m] for p in pairs], "error", grid).mean(axis=1) for m in (0, 1)]
                  for name, grid in grids.items()}
        for v, variant in enumerate(VARIANTS):
            if variant == "olfaction":
                continue
            row = {"source": source, "estimator": estimator, "variant": variant, "n": len(pairs)}
            for name, (est, sim) in errors.items():
                row[name] = (float(est[:, v].mean()), float(sim[:, v].mean()), paired_t(sim[:, v] - est[:, v]))
            for m, model in enumerate(MODELS):
                final = [p[m] for p in pairs]
                row[model] = (float(np.mean([r.region_hit[-1, v] for r in final])),
                              float(np.mean([r.region_area[-1, v] for r in final])),
                              float(np.median([r.hpd_level[-1, v] for r in final])))
            rows.append(row)
    return rows


def models_line() -> str:
    """The robot's estimated detector model against the simulator's (the embedded house's detector)."""
    sim = default_world().make_world(0, "oven", warm_up=1.0).detector
    est = robot_detector_model(sim.classes)
    d = np.abs(sim.confusion - est.confusion)
    return (f"robot's detector model (estimated) against the simulator's: confusion |Δ| max {d.max():.3f}, "
            f"mean {d.mean():.4f}; p_max {est.p_max:.3f} / {sim.p_max:.3f}; near {est.near:.3f} / {sim.near:.3f} m; "
            f"scale {est.scale:.3f} / {sim.scale:.3f} m; false positives {est.false_positive:.4f} / "
            f"{sim.false_positive:.4f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--estimators", nargs="+", default=["infotaxis", "analytic-plume"])
    ap.add_argument("--sources", nargs="+", default=["oven", "bed", "5,6"])
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    folders = {model: args.out / model for model in MODELS}
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    for model in MODELS:
        run_experiment(args.sources, seeds, args.estimators, out=folders[model], workers=args.workers,
                       config=ExperimentConfig(detector_model=model), progress=False)
    print(models_line() + "\n")
    print("| source / estimator | variant | n | final error, m: estimated / simulator | difference [95 % CI] "
          "| mean error over the search, m: estimated / simulator | difference [95 % CI] "
          "| coverage / region m² / HPD level, estimated | the same, simulator |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in compare(folders):
        fe, me = r["final_error"], r["mean_error"]
        print(f"| {r['source']} / {r['estimator']} | {r['variant']} | {r['n']} | {fe[0]:.3f} / {fe[1]:.3f} "
              f"| {fe[2][0]:+.3f} [{fe[2][1][0]:+.3f}, {fe[2][1][1]:+.3f}] | {me[0]:.3f} / {me[1]:.3f} "
              f"| {me[2][0]:+.3f} [{me[2][1][0]:+.3f}, {me[2][1][1]:+.3f}] "
              f"| {r['estimated'][0]:.2f} / {r['estimated'][1]:.1f} / {r['estimated'][2]:.2f} "
              f"| {r['simulator'][0]:.2f} / {r['simulator'][1]:.1f} / {r['simulator'][2]:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
