"""``psgsl search``: the closed-loop grid in the simulated house, or (``--open-space``) the open-space benchmark."""

from __future__ import annotations

import json
import os
from pathlib import Path

from ._grid import (
    MAX_SEEDS,
    add_end_argument,
    add_split_arguments,
    add_found_arguments,
    add_gas_argument,
    add_missed_hits_argument,
    missed_hit_rate,
    add_ontology_argument,
    add_scheduler_argument,
    add_workers_argument,
    add_world_arguments,
    add_world_model_argument,
    split_seeds,
    interrupted,
    positive_float,
    positive_int,
    seed_count,
    gas_setting,
    world_model,
    world_sources,
)

__all__ = ["add_parser", "run"]

_SETTINGS = ((1.0, 1.0), (2.0, 2.0), (3.0, 1.0))


def add_parser(subparsers):
    """Register ``psgsl search``."""
    from ..experiment import ESTIMATORS, VARIANTS
    from ..search import OPEN_SPACE_POLICIES, POLICIES, SCORES
    from ..search._split import SPLITS, TEST_SEEDS

    p = subparsers.add_parser("search", help="closed-loop search: policies × variants in the house (resumable), "
                              "or --open-space: the Loisy & Eloy benchmark")
    add_world_arguments(p)
    p.add_argument("--policies", nargs="+", choices=POLICIES,
                   default=["tour", "infotaxis", "space-aware-infotaxis", "semantic-modes", "nearest-object"],
                   help="policies; the semantics-alone baselines semantic-modes and nearest-object run only with "
                   "semantic variants (default: %(default)s)")
    p.add_argument("--variants", nargs="+", choices=VARIANTS, default=["olfaction", "semantics+rooms"],
                   help="information variants (default: %(default)s)")
    p.add_argument("--estimators", nargs="+", choices=ESTIMATORS, default=["infotaxis"],
                   help="olfactory estimators (default: %(default)s)")
    add_split_arguments(p)
    p.add_argument("--budget", type=positive_float, default=1000.0,
                   help="time budget per run, s of simulated time (default: %(default)s)")
    p.add_argument("--score", choices=SCORES, default="per-time",
                   help="how infotaxis and space-aware infotaxis score a pose: gain per second, or gain alone "
                   "(default: %(default)s)")
    add_found_arguments(p)
    add_end_argument(p)
    add_ontology_argument(p)
    add_missed_hits_argument(p)
    add_world_model_argument(p)
    add_gas_argument(p)
    add_workers_argument(p)
    add_scheduler_argument(p)
    p.add_argument("--out", default="psgsl-search", help="output directory (default: %(default)s)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.add_argument("--record", action="store_true", help="also write each run's episode beside it: runs/<run>.bag/ "
                   "(ROS 2 bag, read by psgsl replay) and runs/<run>.mcap (Foxglove); needs the ros extra")
    p.add_argument("--open-space", action="store_true",
                   help="run the open-space benchmark instead (writes OUT/open_space.json)")
    p.add_argument("--open-policies", nargs="+", choices=OPEN_SPACE_POLICIES,
                   default=["infotaxis", "space-aware-infotaxis"], help="open-space policies (default: %(default)s)")
    p.add_argument("--episodes", type=positive_int, default=1000,
                   help="open-space episodes per policy and setting (default: %(default)s)")
    p.add_argument("--setting", nargs=2, type=positive_float, action="append", metavar=("LAMBDA_OVER_DX", "R_DT"),
                   help="open-space setting (repeatable; default: (1, 1), (2, 2), (3, 1))")
    p.set_defaults(func=run)
    return p


def _open_space(args) -> int:
    from ..search import open_space_benchmark

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for lam, r in args.setting or _SETTINGS:
        for pol in args.open_policies:
            res = open_space_benchmark(pol, lambda_over_dx=lam, r_dt=r, episodes=args.episodes, seed=0)
            res = {k: (v.tolist() if hasattr(v, "tolist") else v) for k, v in res.items()}
            rows.append(res)
            print(f"{pol:>22}  λ/Δx = {lam:g}, R·Δt = {r:g}, N = {res['n']}: mean T = {res['mean_steps']:.2f} "
                  f"± {res['sem']:.2f} (s.e., {res['episodes']} episodes), median {res['median']:g}, "
                  f"P(not found) = {res['p_not_found']:.3g}", flush=True)
    path = out / "open_space.json"
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    print(f"written to {path}")
    return 0


def _num(value, fmt: str) -> str:
    """A number in ``fmt``, or "n/a" where there is none (e.g. no interval from a single run)."""
    return "n/a" if value is None else format(value, fmt)


def format_search_table(summary: dict) -> str:
    """One line per ``"<policy>/<variant>"``: success rate [Wilson 95 %], RMST [95 % CI], Kaplan–Meier median,
    final coverage of the 90 % region, runs."""
    lines = [f"{'policy/variant':<36} {'success [95% CI]':>22} {'RMST, s [95% CI]':>24} {'median':>7} "
             f"{'false':>6} {'cov90':>6} {'n':>3}"]
    for key, s in summary.items():
        sr, r = s["success_rate"], s["rmst"]
        lo, hi = r["ci95"]
        lines.append(f"{key:<36} {sr['value']:6.2f} [{sr['ci95'][0]:.2f}, {sr['ci95'][1]:.2f}]      "
                     f"{r['value']:7.1f} [{_num(lo, '6.1f')}, {_num(hi, '6.1f')}] "
                     f"{_num(s['time_to_find']['median'], '7.1f'):>7} "
                     f"{_num((s.get('false_declaration_rate') or {}).get('value'), '6.2f'):>6} "
                     f"{s['coverage90']['final']:6.2f} "
                     f"{s['n_runs']:3d}")
    lines.append("(success: a declaration within 1 m of the source (--end reach: passing within the found radius); "
                 "RMST: restricted mean time to success within the budget, Kaplan-Meier, Greenwood 95 % CI; median: "
                 "Kaplan-Meier, n/a when not reached; false: wrong declarations of those made; cov90: runs whose 90 % "
                 "region holds the source at the end)")
    return "\n".join(lines)


def run(args) -> int:
    """Run ``psgsl search``; returns the exit code (bad input: one line on stderr, exit 2)."""
    from ._usage import reporting_usage_errors

    return reporting_usage_errors(_run, args)


def _run(args) -> int:
    if args.open_space:
        return _open_space(args)
    from ..experiment import ExperimentConfig
    from ..runs._runner import GridInterrupted
    from ..search import SearchConfig
    from ..search._grid import run_search_grid

    # a bad --first-seed, a test split with --first-seed or too many seeds, dev seeds in the test set: one line,
    # exit 2, nothing written
    seeds = split_seeds(args)
    spec, _, sources = world_sources(args)  # a bad world file or source: one line, exit 2, nothing written
    gas = gas_setting(args, spec)  # --gas, else the world file's; a gas the ontology lacks: exit 2
    config = ExperimentConfig(off_ontology=args.off_ontology, missed_hit_rate=missed_hit_rate(args.missed_hit_rate),
                              world_model=world_model(args.world_model), **gas)
    clearance = args.clearance if args.clearance is not None or spec is None else spec.clearance
    geometry = {k: v for k, v in (("found_radius", args.found_radius), ("clearance", clearance)) if v is not None}
    from ..search import check_findable
    from ..sim import default_world

    # a source the robot can never find is refused before any run (in the first seed's house)
    check_findable(spec if spec is not None else default_world(), seeds[0], sources=sources, **geometry)
    if args.record:
        from ._replay import check_record_extra

        check_record_extra()
    try:
        search = SearchConfig(time_budget=args.budget, score=args.score, end=args.end, **geometry)
        summaries = run_search_grid(sources, args.policies, args.variants, args.estimators, seeds,
                                    out=args.out, workers=args.workers, search=search, config=config,
                                    progress=not args.quiet, figures=not args.no_figures, scheduler=args.scheduler,
                                    world=args.world, record=args.record)
    except GridInterrupted as exc:
        return interrupted(args, exc, where=Path(args.out) / "runs")
    model = config.world_model or (spec.model if spec is not None else "ideal")
    print(f"split {args.split}: seeds {seeds.start}-{seeds.stop - 1}; world model {model}")
    for key, summary in summaries.items():
        print(f"source/estimator {key}")
        print(format_search_table(summary))
        print()
    print(f"written to {args.out}: summary.json, runs.csv, one folder per source and estimator (summary.json, "
          "paired.json when runs are paired, runs.csv, survival.png, paths.png), runs/")
    return 0
