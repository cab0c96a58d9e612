"""What the robot's localisation error costs the closed loop: the same seeds searched twice, once with the robot
exactly where it believes and once with an AMCL-like error (:class:`psgsl_pgm.sim.LocalisationError`, defaults
σ = 0.1 m per axis, σ_θ = 3°, τ = 30 s), not a test.

Per seed, one closed-loop search of the embedded house for each world (same policy, variant, estimator and
search settings). The two runs share the seed but not their observations (the robot senses from other true
poses), so the episodes diverge after the first reading. Printed: success and restricted mean search time (the
time to find, the budget when not found) of each, the paired difference error − ideal with its Student-t 95 %
interval over seeds, and, for each search the error left unfound, whether its believed path came within reach
of the source — the robot then ruled the source out with its "not found here" update while its true path had
not been there.

Run: ``python benchmarks/localisation_effect.py [--seeds 20] [--first-seed 0] [--source oven]
[--policy infotaxis] [--variant semantics+rooms] [--estimator infotaxis] [--budget 1000] [--miss-probability 0]
[--sigma 0.1] [--heading-deg 3] [--tau 30]`` (about 2–5 s per search on one core).
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy import stats

from psgsl_pgm.experiment import ExperimentConfig, parse_source
from psgsl_pgm.search import DetectionModel, SearchConfig, run_closed_loop
from psgsl_pgm.sim import LocalisationError, default_world


def paired(ideal, erred) -> tuple:
    """Mean of the paired differences ``erred − ideal`` (one per seed) and its Student-t 95 % interval."""
    d = np.asarray(erred, dtype=np.float64) - np.asarray(ideal, dtype=np.float64)
    m = float(d.mean())
    if d.size < 2:
        return m, (float("nan"), float("nan"))
    half = float(stats.t.ppf(0.975, d.size - 1) * d.std(ddof=1) / np.sqrt(d.size))
    return m, (m - half, m + half)


def search_pair(seed: int, args) -> dict:
    """One seed's two searches: {"ideal": (found, t), "error": (found, t), "believed_within_reach": bool}."""
    spec = default_world()
    search = SearchConfig(time_budget=args.budget, miss_probability=args.miss_probability)
    error = LocalisationError(sigma=args.sigma, heading_sigma=float(np.deg2rad(args.heading_deg)), tau=args.tau)
    out = {"seed": seed}
    for name, loc in (("ideal", None), ("error", error)):
        world = spec.make_world(seed, parse_source(args.source), warm_up=ExperimentConfig().warm_up,
                                localisation=loc)
        run = run_closed_loop(args.source, seed, args.policy, args.variant, args.estimator, search=search,
                              world=world)
        out[name] = (bool(run.found), float(run.time_to_find))
        if name == "error":
            detection = DetectionModel.from_house(world.house, search.found_radius)
            truth = detection.source_cell(world.source, world.source_object, world.house)
            out["believed_within_reach"] = bool(detection.found(run.path, truth).any())
    return out


def summary(rows) -> dict:
    """Success rates, restricted mean search times and their paired difference over ``rows`` of
    :func:`search_pair`; the unfound searches with error whose believed path came within reach."""
    ideal_t = [r["ideal"][1] for r in rows]
    error_t = [r["error"][1] for r in rows]
    return {"n": len(rows),
            "success": (float(np.mean([r["ideal"][0] for r in rows])), float(np.mean([r["error"][0] for r in rows]))),
            "rmst": (float(np.mean(ideal_t)), float(np.mean(error_t))),
            "rmst_difference": paired(ideal_t, error_t),
            "median": (float(np.median(ideal_t)), float(np.median(error_t))),
            "ruled_out": [r["seed"] for r in rows if not r["error"][0] and r["believed_within_reach"]],
            "unfound": [r["seed"] for r in rows if not r["error"][0]]}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--first-seed", type=int, default=0)
    p.add_argument("--source", default="oven")
    p.add_argument("--policy", default="infotaxis")
    p.add_argument("--variant", default="semantics+rooms")
    p.add_argument("--estimator", default="infotaxis")
    p.add_argument("--budget", type=float, default=1000.0)
    p.add_argument("--miss-probability", type=float, default=0.0)
    p.add_argument("--sigma", type=float, default=0.1)
    p.add_argument("--heading-deg", type=float, default=3.0)
    p.add_argument("--tau", type=float, default=30.0)
    args = p.parse_args(argv)
    rows = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        rows.append(search_pair(seed, args))
        r = rows[-1]
        print(f"seed {seed:3d}  ideal {'found' if r['ideal'][0] else 'unfound':7s} {r['ideal'][1]:7.1f} s   "
              f"error {'found' if r['error'][0] else 'unfound':7s} {r['error'][1]:7.1f} s", flush=True)
    s = summary(rows)
    d, (lo, hi) = s["rmst_difference"]
    print(f"{s['n']} seeds, {args.source}, {args.policy} / {args.variant} / {args.estimator}, budget {args.budget:g} s, "
          f"m = {args.miss_probability:g}, σ = {args.sigma:g} m, σ_θ = {args.heading_deg:g}°, τ = {args.tau:g} s")
    print(f"success        ideal {s['success'][0]:.2f}   error {s['success'][1]:.2f}")
    print(f"RMST (s)       ideal {s['rmst'][0]:.1f}   error {s['rmst'][1]:.1f}   error − ideal {d:+.1f} "
          f"[{lo:+.1f}, {hi:+.1f}] (95 %)")
    print(f"median (s)     ideal {s['median'][0]:.1f}   error {s['median'][1]:.1f}")
    print(f"unfound with error: seeds {s['unfound']}; of these, believed path within reach of the source "
          f"(ruled out by 'not found here'): {s['ruled_out']}")


if __name__ == "__main__":
    main()
