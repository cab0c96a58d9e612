"""``psgsl benchmark``: closed-loop searches in many generated homes (or one world file), sources drawn as they
occur, three ontology conditions; a resumable grid and a report (``report.md``, ``summary.json``, figures)."""

from __future__ import annotations

import shlex
from pathlib import Path

from ._grid import (
    MAX_SEEDS,
    add_end_argument,
    add_found_arguments,
    add_scheduler_argument,
    add_workers_argument,
    add_world_model_argument,
    interrupted,
    positive_float,
    seed_count,
    world_model,
)

__all__ = ["add_parser", "run"]

#: More generated homes than this is months of runs on one machine.
MAX_HOUSES = 100_000


def _house_count(text):
    try:
        value = int(text)
    except ValueError:
        import argparse

        raise argparse.ArgumentTypeError(f"expected a number of houses >= 0, got {text!r}") from None
    if not 0 <= value <= MAX_HOUSES:
        import argparse

        raise argparse.ArgumentTypeError(f"expected a number of houses in [0, {MAX_HOUSES}], got {text!r}")
    return value


def add_parser(subparsers):
    """Register ``psgsl benchmark``."""
    from ..search._benchmark import BENCHMARK_POLICIES, BENCHMARK_VARIANTS
    from ..search._episodes import CONDITIONS
    from ..search._split import SPLITS, TEST_HOMES, TEST_SEEDS

    p = subparsers.add_parser("benchmark", help="closed-loop search in many generated homes (or one world file): "
                              "sources drawn from the ontology, right/wrong/no-rooms ontology, a report")
    p.add_argument("--split", choices=SPLITS, default="dev",
                   help=f"development homes and seeds (dev: homes N..N+H-1, seeds 0..S-1) or the test set, run once "
                   f"per release (test: homes {TEST_HOMES.start}-{TEST_HOMES.stop - 1}, seeds {TEST_SEEDS.start}-"
                   f"{TEST_SEEDS.stop - 1}; no --first-house) (default: %(default)s)")
    p.add_argument("--houses", type=_house_count, default=0,
                   help="generated homes H: psgsl_pgm.sim.generate_house seeds N..N+H-1 (0 with --world; with "
                   f"--split test the first H test homes, 0: all {len(TEST_HOMES)})")
    p.add_argument("--first-house", type=int, default=None, metavar="N",
                   help="first house seed N of the dev split (default: 0)")
    p.add_argument("--world", default=None,
                   help="a world file instead of generated homes (e.g. the lab's house B), reported apart")
    p.add_argument("--seeds", type=seed_count, default=5,
                   help=f"episodes per house S, at most {MAX_SEEDS}: seeds 0..S-1 (with --split test the first S "
                   f"test seeds, at most {len(TEST_SEEDS)}) (default: %(default)s)")
    p.add_argument("--policies", nargs="+", default=list(BENCHMARK_POLICIES),
                   help="closed-loop policies (default: %(default)s)")
    p.add_argument("--variants", nargs="+", default=list(BENCHMARK_VARIANTS),
                   help="information variants (default: %(default)s)")
    from ..experiment._config import ESTIMATORS

    p.add_argument("--estimator", choices=ESTIMATORS, default="infotaxis",
                   help="the olfactory estimator p(s | g) every run uses (default: %(default)s)")
    p.add_argument("--conditions", nargs="+", default=list(CONDITIONS),
                   help=f"ontology conditions among {', '.join(CONDITIONS)} (default: all)")
    p.add_argument("--off-rate", type=float, default=0.1,
                   help="probability of an off-ontology source (a free floor cell) per episode (default: %(default)s)")
    p.add_argument("--gases", nargs="+", default=None,
                   help="gases an episode draws from (default: smoke; with --gas unknown every gas of the ontology)")
    p.add_argument("--gas", choices=["told", "unknown"], default="told",
                   help="'unknown': the robot is not told the episode's gas and infers it with its electronic nose "
                   "(default: told)")
    p.add_argument("--sources-per-episode", default="1", metavar="N",
                   help="sources emitting at once per episode: 1-3, or a range such as 1-3 drawn per episode; with "
                   "more than one the robot declares them one by one (default: %(default)s)")
    p.add_argument("--budget", type=positive_float, default=1000.0,
                   help="time budget per run, s of simulated time (default: %(default)s)")
    p.add_argument("--rooms", type=int, default=None, metavar="N",
                   help="rooms of every generated home, 3-8 (default: drawn per house)")
    p.add_argument("--area", type=float, default=None, metavar="M2",
                   help="floor area of every generated home, 40-200 m² (default: drawn per house)")
    p.add_argument("--room-types", nargs="+", default=None, metavar="TYPE",
                   help="room types of every generated home, one per room (Kitchen Bathroom Bedroom LivingRoom "
                   "Hallway)")
    add_found_arguments(p)
    add_end_argument(p)
    add_workers_argument(p)
    add_scheduler_argument(p)
    add_world_model_argument(p)
    p.add_argument("--out", default="psgsl-benchmark", help="output directory (default: %(default)s)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``psgsl benchmark``; returns the exit code (bad input: one line on stderr, exit 2)."""
    from ._usage import reporting_usage_errors

    return reporting_usage_errors(_run, args)


def _run(args) -> int:
    from ..io._output import check_output_dir
    from ..runs._runner import GridInterrupted
    from ..search import SearchConfig
    from ..search._benchmark import check_sources_per_episode, run_benchmark
    from ..search._split import benchmark_sample

    try:
        count = check_sources_per_episode(args.sources_per_episode)
    except ValueError as exc:  # the option's name, as the user typed it
        raise ValueError(f"--sources-per-episode: {exc}") from None
    options = {k: v for k, v in (("n_rooms", args.rooms), ("area", args.area), ("room_types", args.room_types))
               if v is not None}
    if args.world is not None and options:
        raise ValueError("--rooms, --area and --room-types shape generated homes; they do not apply with --world")
    geometry = {k: v for k, v in (("found_radius", args.found_radius), ("clearance", args.clearance)) if v is not None}
    search = SearchConfig(time_budget=args.budget, end=args.end, **geometry)
    from ..experiment import ExperimentConfig

    config = ExperimentConfig(world_model=world_model(args.world_model))
    gases = args.gases
    if gases is None:  # the robot told: smoke; not told: any gas of the ontology
        if args.gas == "unknown":
            from ..sim import generated_ontology, load_world

            gases = list((generated_ontology() if args.world is None else load_world(args.world).ontology).gases)
        else:
            gases = ["smoke"]
    # a test split with --first-house, too many homes or seeds, dev homes in the test set: one line, exit 2,
    # before anything is written
    house_ids, seed_ids = benchmark_sample(args.split, houses=args.houses, seeds=args.seeds,
                                           first_house=args.first_house, world=args.world is not None)
    if args.world is not None:
        from ..sim import check_free_cells, load_world

        check_free_cells(load_world(args.world))  # a map too fine for the runs' memory: one line naming 'resolution'
    from ..search._policies import check_estimator

    for policy in args.policies:
        check_estimator(policy, args.estimator)  # e.g. pmfs-nav without pmfs: one line, before anything is written
    check_output_dir(args.out, subdirs=("runs",))  # unwritable: fails now, not after the runs
    what = args.world if args.world is not None else f"{len(house_ids)} generated homes"
    print(f"psgsl benchmark: {what} ({args.split} split), seeds {seed_ids.start}-{seed_ids.stop - 1}, policies "
          f"{' '.join(args.policies)}, variants "
          f"{' '.join(args.variants)}, conditions {' '.join(args.conditions)} -> {args.out}", flush=True)
    command = "psgsl " + " ".join(shlex.quote(a) for a in getattr(args, "argv", []))
    try:
        summary = run_benchmark(out=args.out, houses=args.houses, seeds=args.seeds, world=args.world,
                                policies=args.policies, variants=args.variants, conditions=args.conditions,
                                off_rate=args.off_rate, gases=gases, estimator=args.estimator, first_house=args.first_house,
                                house_options=options, workers=args.workers, scheduler=args.scheduler,
                                config=config, search=search, progress=not args.quiet, figures=not args.no_figures,
                                command=command, split=args.split, gas_unknown=args.gas == "unknown",
                                sources_per_episode=count)
    except GridInterrupted as exc:
        return interrupted(args, exc, where=Path(args.out) / "runs")
    p = summary["primary"]["result"]
    if p is not None:
        lo, hi = p["ci95"]
        print(f"primary: RMST ratio {summary['primary']['A']} / {summary['primary']['B']} "
              f"({summary['primary']['condition']}) = {p['value']:.3f} [{lo:.3f}, {hi:.3f}] (95 % nested bootstrap, "
              f"n = {p['n']} episodes in {p['houses']} houses)")
    houses = "" if args.world is not None else "houses/, "
    print(f"written to {args.out}: report.md, summary.json, survival.png, rmst.png, episodes.json, {houses}worlds/, "
          "runs/")
    return 0
