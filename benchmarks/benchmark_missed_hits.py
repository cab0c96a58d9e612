"""Arms of a ``psgsl benchmark`` folder re-run with a missed-hit rate δ, paired with the stored runs (not a test).

Every stored run of the chosen arms (``--arms policy/variant``, the ``--condition``) is run again — the same
home, episode, seed and settings, read from the run's stored config — with ``ExperimentConfig(missed_hit_rate=δ)``
(:class:`psgsl_pgm.olfaction.GridInfotaxis`: one reading without a hit then costs a source at most
−log((1 − ε)δ) nats). The new runs go to ``OUT/missed-hits-<δ>/`` (each file written atomically; a run already
there is kept, so the script resumes). Per arm, against the stored runs of the same episodes: runs found, the RMST
ratio new / stored with its 95 % nested bootstrap interval (homes, then seeds: the benchmark's primary statistic),
the paired RMST difference with its bootstrap interval and sign-flip p-value, the runs whose posterior put the
true source at an HPD level ≥ 0.9999 at some stop (the prior before the first reading left out), and the final
coverage of the 90 % region with its mean area.

Run: ``python benchmarks/benchmark_missed_hits.py bench-50x5 --delta 0.0071 --arms infotaxis/olfaction
infotaxis/semantics+rooms [--workers 2]`` (δ = 0.0071: the maximum-likelihood δ of
``benchmarks/calibration_missed_hits.py --homes 20`` on reference homes with the online wind estimate).
"""

from __future__ import annotations

import argparse
import json
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

FIELDS = ("found", "time_to_find", "hpd_level", "region_hit", "region_area")
RULED_OUT = 0.9999


def rerun(stored: Path, out: Path, delta: float, folder: Path) -> Path:
    """Run the episode of the stored run ``stored`` again with δ; its measures to ``out`` (atomically)."""
    if out.exists():
        return out
    from threadpoolctl import threadpool_limits

    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.search import SearchConfig
    from psgsl_pgm.search._grid import closed_loop_in_world

    z = np.load(stored)
    cfg = json.loads(str(z["config"]))
    experiment = dict(cfg["experiment"], missed_hit_rate=delta)
    search = dict(cfg["search"], start=tuple(cfg["search"]["start"]))
    world = folder / "houses" / cfg["benchmark"]["house"] / "world.yaml"
    with threadpool_limits(limits=1, user_api="blas"):  # as the grid's workers run
        run = closed_loop_in_world(tuple(z["source_xy"]), int(z["seed"]), str(z["policy"]), str(z["variant"]),
                                   str(z["estimator"]), world=str(world), config=ExperimentConfig(**experiment),
                                   search=SearchConfig(**search))
    tmp = out.with_name(out.stem + ".partial.npz")
    np.savez(tmp, **{k: getattr(run, k) for k in FIELDS})
    os.replace(tmp, out)
    return out


def _measures(z) -> tuple:
    level = z["hpd_level"][1:]
    return (float(z["time_to_find"]), bool(z["found"]), bool(level.size and level.max() >= RULED_OUT),
            bool(z["region_hit"][-1]), float(z["region_area"][-1]))


def main(argv=None) -> None:
    from psgsl_pgm.search._survival import nested_bootstrap, paired_comparison

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, help="a psgsl benchmark output folder")
    ap.add_argument("--delta", type=float, required=True)
    ap.add_argument("--arms", nargs="+", required=True, help="policy/variant")
    ap.add_argument("--condition", default="right-ontology")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    if not 0 < args.delta < 1:
        raise SystemExit(f"--delta must lie in (0, 1), got {args.delta}")
    if args.workers < 1:
        raise SystemExit(f"--workers must be at least 1, got {args.workers}")
    new = args.folder / f"missed-hits-{args.delta:g}"
    new.mkdir(exist_ok=True)
    stored = {arm: sorted((args.folder / "runs").glob(f"*__{args.condition}__{arm.replace('/', '__')}__*.npz"))
              for arm in args.arms}
    jobs = [(p, new / p.name) for files in stored.values() for p in files]
    if args.workers == 1:  # in this process
        for stored_run, out in jobs:
            rerun(stored_run, out, args.delta, args.folder)
    elif jobs:
        with ProcessPoolExecutor(args.workers) as pool:
            list(pool.map(rerun, *zip(*jobs), [args.delta] * len(jobs), [args.folder] * len(jobs)))
    budget = None
    print(f"| arm | runs | found, stored → δ = {args.delta:g} | RMST ratio δ / stored [95 % nested bootstrap] | "
          "RMST difference, s [95 % bootstrap], sign-flip p | source at HPD level ≥ 0.9999 | final coverage | "
          "region, m² |\n|---|---|---|---|---|---|---|---|")
    for arm, files in stored.items():
        old = np.array([_measures(np.load(p)) for p in files])
        now = np.array([_measures(np.load(new / p.name)) for p in files])
        if budget is None:
            budget = float(json.loads(str(np.load(files[0])["config"]))["search"]["time_budget"])
        homes = [p.name.split("__")[0] for p in files]
        ratio = nested_bootstrap(np.stack([now[:, 0], old[:, 0]]), homes, lambda v: v[0].mean() / v[1].mean())
        diff = paired_comparison(now[:, 0], old[:, 0], budget)
        print(f"| {arm} | {len(files)} | {int(old[:, 1].sum())} → {int(now[:, 1].sum())} | {ratio['value']:.3f} "
              f"[{ratio['ci95'][0]:.3f}, {ratio['ci95'][1]:.3f}] | {diff['value']:+.1f} [{diff['ci95'][0]:+.1f}, "
              f"{diff['ci95'][1]:+.1f}], p = {diff['p_value']:.3f} | {int(old[:, 2].sum())} → {int(now[:, 2].sum())} | "
              f"{old[:, 3].mean():.2f} → {now[:, 3].mean():.2f} | {old[:, 4].mean():.1f} → {now[:, 4].mean():.1f} |")


if __name__ == "__main__":
    main()
