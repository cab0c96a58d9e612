"""Command-line side of the grid runner (:mod:`psgsl_pgm.runs._runner`): ``--scheduler``, the Ctrl-C line, the
argument types of counts and budgets (``--seeds``, ``--workers``, ... with their size guards), and the world and
sources of a grid (``--world``, ``--sources``).

Used by ``psgsl experiment`` and ``psgsl search``::

    add_scheduler_argument(parser)                      # --scheduler {local, tcp://HOST:PORT}
    try:
        run_experiment(..., scheduler=args.scheduler)
    except GridInterrupted as exc:
        return interrupted(args, exc, where=out / "runs")  # one line on stderr, exit code 130 (SIGTERM: 143)
"""

from __future__ import annotations

import argparse
import math
import os
import shlex
import signal
import sys

__all__ = ["DEFAULT_SOURCES", "EXIT_INTERRUPTED", "EXIT_TERMINATED", "MAX_SEEDS", "MAX_WORKERS",
           "add_found_arguments", "add_gas_argument", "gas_setting", "add_missed_hits_argument", "add_ontology_argument", "add_scheduler_argument",
           "add_workers_argument", "add_world_arguments", "add_world_model_argument", "interrupted", "missed_hit_rate", "positive_float",
           "positive_int", "seed_count", "seed_range", "unit_float", "worker_count", "world_model", "world_sources"]

#: Exit code after Ctrl-C (128 + SIGINT), as shells report it.
EXIT_INTERRUPTED = 130

#: Exit code after SIGTERM (128 + SIGTERM), as shells report a process it ended.
EXIT_TERMINATED = 128 + signal.SIGTERM

#: Size guards of the command line: more seeds than this is years of runs, more workers than this no machine has.
MAX_SEEDS = 10_000
MAX_WORKERS = 1024

#: The sources of ``psgsl experiment`` and ``psgsl search`` in the embedded house when ``--sources`` is not given.
DEFAULT_SOURCES = ("oven", "bed", "5.0,6.0")


def positive_int(text, maximum=None):
    """argparse type: an integer >= 1 (and <= ``maximum``)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    if maximum is not None and value > maximum:
        raise argparse.ArgumentTypeError(f"expected a positive integer of at most {maximum}, got {text!r}")
    return value


def positive_float(text):
    """argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def unit_float(text):
    """argparse type: a number in [0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number in [0, 1], got {text!r}") from None
    if not 0 <= value <= 1:
        raise argparse.ArgumentTypeError(f"expected a number in [0, 1], got {text!r}")
    return value


def missed_hit_rate(text) -> float:
    """The value of ``--missed-hit-rate``: a number in [0, 1); anything else is a :class:`ValueError` naming the
    option (the command reports it in one line, exit code 2, before any output)."""
    try:
        value = float(str(text).strip())
    except ValueError:
        value = math.nan
    if not 0 <= value < 1:
        raise ValueError(f"--missed-hit-rate must be a number in [0, 1), got {str(text)!r}")
    return value


def add_missed_hits_argument(parser) -> None:
    """``--missed-hit-rate``, shared by ``psgsl experiment`` and ``psgsl search``: δ of the hit model (checked by
    :func:`missed_hit_rate` when the command runs)."""
    parser.add_argument("--missed-hit-rate", default="0", metavar="DELTA",
                        help="the Infotaxis estimator's probability that a reading misses the plume whatever the "
                        "model predicts, so that one reading without a hit costs a source at most -log((1 - eps) "
                        "DELTA) nats, eps the false-hit rate, 0.01 (default: 0, the hit model without it)")


def add_ontology_argument(parser) -> None:
    """``--off-ontology``, shared by ``psgsl experiment`` and ``psgsl search``: the robot's ε."""
    parser.add_argument("--off-ontology", type=unit_float, default=0.0, metavar="EPS",
                        help="the robot's prior probability that a source is off its ontology (emitted by whatever "
                        "is in its cell), mixed into p(o | s): 0 uses the ontology as it stands (default: 0)")


def add_world_model_argument(parser) -> None:
    """``--world-model``, shared by ``psgsl experiment``, ``psgsl search`` and ``psgsl benchmark`` (checked by
    :func:`world_model` when the command runs)."""
    parser.add_argument("--world-model", default=None, metavar="MODEL",
                        help="the simulated world: 'ideal' (built from the robot's own assumptions), 'realistic' "
                        "(CFD wind, MOX gas sensor, occluding camera with persistent errors, localisation error) or "
                        "'ideal+' components of these: cfd-wind, mox, camera, pose (default: the world file's "
                        "'model', else ideal)")


def add_gas_argument(parser) -> None:
    """``--gas``, shared by ``psgsl experiment`` and ``psgsl search`` (checked by :func:`gas_setting`)."""
    parser.add_argument("--gas", default=None, metavar="GAS",
                        help="the source's gas: a gas of the world's ontology, told to the robot, or 'unknown': each "
                        "episode's gas is drawn from the ontology's gases and the robot infers it with its "
                        "electronic nose (default: the world file's 'gas', else smoke)")


def gas_setting(args, spec) -> dict:
    """``{"gas": name}`` for :class:`psgsl_pgm.experiment.ExperimentConfig` from ``--gas`` (else the world file's
    ``gas``), or ``{}`` for the default; a gas the ontology lacks is a :class:`ValueError` naming ``--gas`` (one
    line, exit 2, nothing written)."""
    gas = getattr(args, "gas", None)
    if gas is None:
        return {"gas": spec.gas} if spec is not None and spec.gas else {}
    if spec is not None:
        gases = spec.ontology.gases
    else:
        from ..sim._house_ontology import house_ontology

        gases = house_ontology().gases
    if gas != "unknown" and gas not in gases:
        raise ValueError(f"--gas {gas}: not a gas of the ontology {list(gases)} nor 'unknown'")
    return {"gas": gas}


def world_model(text):
    """The value of ``--world-model`` (its canonical name), or None when not given; a bad name is a
    :class:`ValueError` naming the option (the command reports it in one line, exit code 2, before any output)."""
    if text is None:
        return None
    from ..sim._world_model import WorldModel

    try:
        model = WorldModel.parse(text)
        model.check_available()  # a missing solver: one line, before any output
    except (ValueError, TypeError, ImportError) as exc:
        raise ValueError(f"--world-model {text}: {exc}") from None
    return model.name


def seed_count(text):
    """argparse type of ``--seeds``: 1 to :data:`MAX_SEEDS`."""
    return positive_int(text, MAX_SEEDS)


def seed_range(first, count: int) -> range:
    """The seeds of ``--first-seed N --seeds S``: N, …, N + S − 1.

    ``first`` is the option's text (or an int); anything but an integer >= 0 is a :class:`ValueError` naming
    ``--first-seed`` (the command reports it in one line, exit code 2, before any output). Seeds are stored as
    int64, so the last one must stay below 2**63.
    """
    text = str(first).strip()
    try:
        value = int(text, 10)
    except ValueError:
        raise ValueError(f"--first-seed must be an integer >= 0, got {str(first)!r}") from None
    if value < 0:
        raise ValueError(f"--first-seed must be an integer >= 0, got {str(first)!r}")
    if value + count - 1 >= 2**63:
        raise ValueError(f"--first-seed + --seeds - 1 must be below 2**63 (seeds are stored as int64), got "
                         f"{str(first)!r} and {count}")
    return range(value, value + count)


def add_found_arguments(parser) -> None:
    """``--found-radius`` and ``--clearance`` (m), shared by ``psgsl search`` and ``psgsl world check``: what
    counts as found and which cells are drivable (None: the closed loop's and the world file's defaults)."""
    parser.add_argument("--found-radius", type=positive_float, default=None, metavar="M",
                        help="a source counts as found within this distance of it (of its object's footprint), m "
                        "(default: the closed loop's, 0.5)")
    parser.add_argument("--clearance", type=positive_float, default=None, metavar="M",
                        help="the robot's distance from walls, furniture and windows: which cells are drivable, m "
                        "(default: the world file's 'clearance', else 0.25)")


def add_split_arguments(parser) -> None:
    """``--split``, ``--seeds`` and ``--first-seed``, shared by ``psgsl search`` and ``psgsl experiment`` (read by
    :func:`split_seeds`)."""
    from ..search._split import SPLITS, TEST_SEEDS

    parser.add_argument("--split", choices=SPLITS, default="dev",
                        help=f"development seeds (dev: N..N+S-1) or the test seeds, run once per release (test: "
                        f"{TEST_SEEDS.start}-{TEST_SEEDS.stop - 1}; no --first-seed) (default: %(default)s)")
    parser.add_argument("--seeds", type=seed_count, default=None,
                        help=f"number of seeds S, at most {MAX_SEEDS}: seeds N..N+S-1 (default: 10; with --split "
                        f"test the first S test seeds, default all {len(TEST_SEEDS)})")
    parser.add_argument("--first-seed", default=None, metavar="N",
                        help="first seed N of the dev split, an integer >= 0 (default: 0)")


def split_seeds(args) -> range:
    """The seeds of ``--split``, ``--seeds`` and ``--first-seed`` (:func:`psgsl_pgm.search._split.house_seeds`):
    ValueError (one line, exit 2) for a test split with ``--first-seed``, too many seeds or a bad first seed."""
    from ..search._split import house_seeds

    if args.split == "test":
        return house_seeds("test", seeds=args.seeds, first_seed=args.first_seed)
    seeds = seed_range("0" if args.first_seed is None else args.first_seed, 10 if args.seeds is None else args.seeds)
    return house_seeds("dev", seeds=len(seeds), first_seed=seeds.start)


def add_end_argument(parser) -> None:
    """``--end``, shared by ``psgsl search`` and ``psgsl benchmark``: how a closed-loop run ends
    (:class:`psgsl_pgm.search.SearchConfig` ``end``)."""
    parser.add_argument("--end", choices=("declare", "reach"), default="declare",
                        help="declare: a run ends at the robot's first declaration, a success when within 1 m of the "
                        "source; reach: when the robot first passes within the found radius of the source (the rule "
                        "of earlier results) (default: %(default)s)")


def add_world_arguments(parser) -> None:
    """``--world`` and ``--sources``, shared by ``psgsl experiment`` and ``psgsl search`` (read by
    :func:`world_sources`)."""
    parser.add_argument("--world", default=None, help="world file: your own house (see docs/guide/own-house.md); "
                        "default: the embedded house")
    parser.add_argument("--sources", nargs="+", default=None,
                        help="object class names, 'x,y' positions or the world file's source names (default: the "
                        f"world's sources; for the embedded house {' '.join(DEFAULT_SOURCES)})")


def world_sources(args):
    """The world file, source names and sources of a grid command: ``(spec, names, sources)``.

    ``spec`` is the :class:`psgsl_pgm.sim.WorldSpec` of ``args.world`` (None: the embedded house); ``names`` are
    ``args.sources``, else the world file's sources, else :data:`DEFAULT_SOURCES`; ``sources`` are the names
    parsed by :func:`psgsl_pgm.experiment.parse_source`. Raises ValueError for a bad world file, a world file
    that names no sources (and no ``--sources``) or a bad source: one line, exit 2, nothing written.
    """
    from ..experiment import parse_source

    spec = None
    if args.world is not None:
        from ..sim import check_free_cells, load_world

        spec = load_world(args.world)
    names = args.sources
    if names is None:
        names = list(spec.sources) if spec is not None else list(DEFAULT_SOURCES)
        if not names:
            raise ValueError(f"{args.world}: the world file names no 'sources'; give --sources")
    if spec is not None:
        check_free_cells(spec)  # a map too fine for the runs' memory: one line naming 'resolution', nothing run
    return spec, names, [parse_source(s) for s in names]


def worker_count(text):
    """argparse type of ``--workers``: 1 to :data:`MAX_WORKERS`."""
    return positive_int(text, MAX_WORKERS)


def add_workers_argument(parser) -> None:
    """Add ``--workers`` (:func:`worker_count`; default: two processes, or one on a one-core machine), shared by
    every command that runs a grid."""
    parser.add_argument("--workers", type=worker_count, default=min(2, os.cpu_count() or 1),
                        help=f"worker processes, at most {MAX_WORKERS} (default: %(default)s)")


def add_scheduler_argument(parser) -> None:
    """Add ``--scheduler`` (default: the local process pool of ``--workers`` processes)."""
    parser.add_argument(
        "--scheduler", default=None, metavar="ADDRESS",
        help="run on dask.distributed (extra psgsl-pgm[dask]): 'local' = a LocalCluster of --workers processes, "
             "or the address of a running 'dask scheduler' (e.g. tcp://127.0.0.1:8786); default: a local pool",
    )


def interrupted(args, exc, *, where) -> int:
    """Print the one-line report of a stopped grid (runs done, where, how to resume) on stderr; return 128 + the
    signal: :data:`EXIT_INTERRUPTED` after Ctrl-C, :data:`EXIT_TERMINATED` after SIGTERM."""
    argv = getattr(args, "argv", None)
    again = shlex.join(["psgsl", *argv]) if argv else f"psgsl {args.command} with the same arguments"
    how = "in-progress runs abandoned" if exc.immediate else "runs in progress were finished"
    signum = getattr(exc, "signum", signal.SIGINT)
    what = "interrupted" if signum == signal.SIGINT else f"terminated by {signal.Signals(signum).name}"
    print(f"psgsl {args.command}: {what}: {exc.done} of {exc.total} runs done in {where} ({how}); "
          f"resume with: {again}", file=sys.stderr, flush=True)
    return 128 + int(signum)
