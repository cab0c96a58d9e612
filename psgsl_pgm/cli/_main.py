"""Command line: ``psgsl`` (or ``python -m psgsl_pgm``).

``psgsl`` alone runs the demo. Subcommands: ``demo``, ``experiment``, ``estimate``, ``kitchen``, ``world check``,
``export-networks`` (each further subcommand registered from its own ``psgsl_pgm.cli._<name>`` module).

Errors (docs/guide/bad-input.md): every :class:`ValueError`, :class:`TypeError` and :class:`OSError` (so also
:class:`FileNotFoundError`) that a command raises — bad arguments, bad input files, an unwritable output — is
printed by :func:`main` as ONE line ``psgsl <command>: error: <message>`` on stderr, and the exit code is 2;
never a traceback. Output paths are checked before any work starts (:mod:`psgsl_pgm.io._output`). Subcommand
modules therefore just raise ValueError/TypeError with a clear message.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from . import _benchmark, _export, _live, _replay, _search, _world
from ._grid import (
    MAX_SEEDS,
    add_gas_argument,
    gas_setting,
    add_missed_hits_argument,
    missed_hit_rate,
    add_ontology_argument,
    add_scheduler_argument,
    add_workers_argument,
    add_world_arguments,
    add_split_arguments,
    add_world_model_argument,
    interrupted,
    positive_int,
    seed_count,
    split_seeds,
    world_model,
    world_sources,
)
from ._usage import UsageError as _UsageError

__all__ = ["build_parser", "error_line", "main"]


#: What :func:`main` reports as one line + exit code 2 (anything else is a bug and keeps its traceback).
_INPUT_ERRORS = (ValueError, TypeError, OSError)


def _kitchen(args) -> int:
    from ..core._kitchen import kitchen_example

    res = kitchen_example()
    ont = res["ontology"]
    row = ", ".join(f"{c} {p:g}" for c, p in zip(ont.classes, ont.source_likelihood("smoke")) if p > 0)
    print(f"The paper's kitchen ontology (smoke; p(o | s) = {row}) on six illustrative cells")
    print(f"{'cell':>14} {'p(s|z)':>8} {'p(s|g)':>8} {'p(s|g,z)':>9}")
    for name, s, g, f in zip(res["cells"], res["semantic"], res["olfactory"], res["fused"]):
        print(f"{name:>14} {s:8.4f} {g:8.4f} {f:9.4f}")
    return 0


def _demo(args) -> int:
    from ..experiment import DEMO_SEEDS, format_table, run_demo
    from ..io._output import check_output_dir
    from ..runs._runner import GridInterrupted

    check_output_dir(args.out, subdirs=("runs",))  # an unwritable --out fails now, not after the runs
    seeds = range(args.seeds) if args.seeds is not None else DEMO_SEEDS
    print(f"psgsl demo: smoke from the kitchen oven of the simulated house in the ideal world (built from the "
          f"robot's own assumptions; psgsl search --world-model realistic breaks them), {len(seeds)} seeds, "
          f"{args.workers} workers -> {args.out}", flush=True)
    try:
        summary = run_demo(args.out, seeds=seeds, workers=args.workers, progress=not args.quiet)
    except GridInterrupted as exc:
        return interrupted(args, exc, where=os.path.join(args.out, "runs"))
    print(format_table(summary, title="olfaction (grid Infotaxis) vs + camera semantics vs + room categories"))
    print(f"written to {args.out}: summary.json, summary.txt, metrics.csv, error-chart.png, progression.png, "
          "room-types.png, runs/")
    if not args.no_search:
        from pathlib import Path

        from ..search import DEMO_BUDGET, DEMO_SEARCH_SEEDS, run_search_demo
        from ._search import format_search_table

        out = Path(args.out) / "closed-loop"
        print(f"closed loop: the robot chooses where to go and look (infotaxis, φ = φ_G + φ_O), with and without "
              f"semantics, seed(s) {list(DEMO_SEARCH_SEEDS)}, {DEMO_BUDGET:g} s budget -> {out}", flush=True)
        try:
            search = run_search_demo(out, workers=args.workers, progress=not args.quiet)
        except GridInterrupted as exc:
            return interrupted(args, exc, where=os.path.join(out, "runs"))
        print(format_search_table(search))
        print(f"written to {out}: summary.json, runs.csv, oven-infotaxis/ (survival.png, paths.png, ...), runs/")
    return 0


def _experiment(args) -> int:
    from ..experiment import ExperimentConfig, check_sources, format_table, run_experiment
    from ..io._output import check_output_dir
    from ..runs._runner import GridInterrupted

    seeds = split_seeds(args)  # a bad --first-seed or a test split with one: one line, exit 2, nothing written
    spec, names, sources = world_sources(args)
    gas = gas_setting(args, spec)  # --gas, else the world file's; a gas the ontology lacks: exit 2
    config = ExperimentConfig(stops=args.stops, off_ontology=args.off_ontology,
                              missed_hit_rate=missed_hit_rate(args.missed_hit_rate),
                              world_model=world_model(args.world_model), **gas)
    if spec is not None:
        for s in sources:  # every source must exist in this world before any run starts
            spec.resolve_source(s, spec.house(0))
    else:
        check_sources(sources, seeds=seeds)  # unknown class, off the map: refused before any run
    check_output_dir(args.out, subdirs=("runs",))  # unwritable: fails now, not after the runs; creates nothing
    if args.record:
        _replay.check_record_extra()
    where = "the embedded house" if spec is None else args.world
    print(f"psgsl experiment: {where}, sources {', '.join(map(str, names))}, {_seeds_text(seeds)}, gas "
          f"{config.gas!r} -> {args.out}", flush=True)
    try:
        summaries = run_experiment(sources, seeds, args.estimators, out=args.out, workers=args.workers,
                                   progress=not args.quiet, config=config, scheduler=args.scheduler,
                                   world=args.world, record=args.record)
    except GridInterrupted as exc:
        return interrupted(args, exc, where=os.path.join(args.out, "runs"))
    for key, summary in summaries.items():
        print(format_table(summary, title=key))
        print()
    print(f"written to {args.out}: summary.json, metrics.csv, one folder per source and estimator, runs/")
    return 0


def _seeds_text(seeds: range) -> str:
    return f"{len(seeds)} seeds" + (f" from seed {seeds.start}" if seeds.start else "")


def _load_array(path, name):
    import numpy as np

    from ..io._npyfile import READ_ERRORS, load_npy

    try:
        arr = load_npy(path, name)
    except FileNotFoundError:
        raise _UsageError(f"{name}: no such file {path!r}") from None
    except READ_ERRORS as exc:
        raise _UsageError(f"{name}: {path!r} is not a .npy array ({' '.join(str(exc).split())})") from None
    if not isinstance(arr, np.ndarray):
        raise _UsageError(f"{name}: expected one array in a .npy file, got an archive in {path!r}")
    if arr.dtype.kind not in "fiu":  # the type contract: real numbers only (no bool, complex, text, dates)
        raise TypeError(f"{name}: expected an array of real numbers in {path!r}, got dtype {arr.dtype}")
    return arr


def _estimate(args) -> int:
    import numpy as np

    from ..core import Ontology, semantic_source_probability
    from .._shared._validate import as_float_array, check_distribution, check_nonnegative, check_sums
    from ..io._output import check_output_file

    out = check_output_file(args.out)  # before reading anything: a directory, a device or no folder is refused
    try:
        ontology = Ontology.from_yaml(args.ontology)
    except FileNotFoundError:
        raise _UsageError(f"--ontology: no such file {args.ontology!r}") from None
    except (ValueError, TypeError) as exc:  # the message starts with the file name
        raise type(exc)(f"--ontology: {exc}") from None
    olfactory = _load_array(args.olfactory, "--olfactory")
    if args.gas is None:
        if len(ontology.gases) != 1:
            raise _UsageError(f"--gas is required: the ontology has gases {list(ontology.gases)}")
        gas = ontology.gases[0]
    else:
        gas = args.gas
    if Path(args.class_probs).suffix.lower() == ".json":  # a Voxeland map: its columns, in bounded memory
        return _estimate_voxeland(args, ontology, gas, olfactory, out)
    if Path(args.class_probs).suffix.lower() == ".npz":
        class_probs = _read_beliefs(args, ontology)
    else:
        class_probs = _load_array(args.class_probs, "--class-probs")
    if class_probs.shape[-1:] != (len(ontology.classes),):
        raise _UsageError(f"--class-probs must have shape (..., {len(ontology.classes)}) for the ontology's classes "
                          f"{list(ontology.classes)}, got {class_probs.shape}")
    voxels = class_probs.ndim == 4 and olfactory.shape == class_probs.shape[:2]  # (H, W, L, k) voxels, (H, W) cells
    cells = class_probs.shape[:2] if voxels else class_probs.shape[:-1]
    if olfactory.shape != cells:
        raise _UsageError(f"--olfactory must have the map's shape {cells} (the cells of --class-probs), got "
                          f"{olfactory.shape}")
    check_distribution(as_float_array(class_probs, "--class-probs"), "--class-probs (p(o_c | z_c) per cell)")
    olf = check_nonnegative(as_float_array(olfactory, "--olfactory"), "--olfactory (p(s | g) per cell)")
    check_sums(np.sum(olf, dtype=np.float64), "--olfactory (p(s | g))", olf.dtype, over="over all cells")
    semantic = semantic_source_probability(class_probs, ontology.source_likelihood(gas), ontology.class_prior,
                                           column_axis=2 if voxels else None)  # voxel columns -> cells
    return _write_posterior(olfactory, semantic, gas, out)


def _write_posterior(olfactory, semantic, gas, out) -> int:
    import numpy as np

    from ..core import fuse
    from ..io._output import write_file_atomically

    posterior = fuse(olfactory, semantic)  # p(s | g, z) ∝ p(s | g) p(s | z), eq. (11)
    write_file_atomically(out, lambda fh: np.save(fh, posterior))  # exactly at --out: no ".npy" appended
    best = np.unravel_index(int(np.argmax(posterior)), posterior.shape)
    print(f"p(s | g, z) for {gas!r} over {posterior.size} cells -> {out}; most probable cell {tuple(map(int, best))} "
          f"(p = {posterior[best]:.4g})")
    return 0


def _estimate_voxeland(args, ontology, gas, olfactory, out) -> int:
    """``estimate`` from a Voxeland instance map: column weights a block of rows at a time (never the voxel array)."""
    import json

    import numpy as np

    from .._shared._validate import as_float_array, check_nonnegative, check_sums
    from ..core._voxeland import voxeland_column_weights

    grid = _map_grid(args)
    if olfactory.shape != grid.shape:
        raise _UsageError(f"--olfactory must have the map's shape {grid.shape} (--map at {grid.resolution:g} m), "
                          f"got {olfactory.shape}")
    olf = check_nonnegative(as_float_array(olfactory, "--olfactory"), "--olfactory (p(s | g) per cell)")
    check_sums(np.sum(olf, dtype=np.float64), "--olfactory (p(s | g))", olf.dtype, over="over all cells")
    try:
        data = json.loads(Path(args.class_probs).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise _UsageError(f"--class-probs: no such file {args.class_probs!r}") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{args.class_probs}: not a readable JSON file ({exc})") from None
    weights = voxeland_column_weights(data, ontology.classes, grid=grid, class_prior=ontology.class_prior,
                                      source_likelihood=ontology.source_likelihood(gas), where=args.class_probs,
                                      other_classes="lump" if args.other_classes else "error")
    total = np.sum(weights, dtype=np.float64)
    if not total > 0:
        raise ValueError(f"{args.class_probs}: no cell can hold a {gas!r} source (zero weight everywhere)")
    return _write_posterior(olfactory, weights / total, gas, out)  # p(s_c | z), eq. (20) summed over columns


def _map_grid(args):
    """The working grid: ``--map`` coarsened to ``--resolution`` (the map's own by default)."""
    from ..sim import load_ros_map
    from ..sim._resample import coarsen_factor, coarsen_occupancy

    if args.map is None:
        raise _UsageError("--class-probs: a Voxeland instance map (.json) needs --map (the ROS map it is read onto)")
    fine = load_ros_map(args.map)
    res = fine.resolution if args.resolution is None else args.resolution
    return coarsen_occupancy(fine, coarsen_factor(fine.resolution, res, where="--resolution"))


def _read_beliefs(args, ontology):
    """Class beliefs from an .npz (probs + classes)."""
    from ..io._class_maps import read_class_beliefs

    grid = None if args.map is None else _map_grid(args)
    return read_class_beliefs(args.class_probs, ontology.classes, grid=grid, class_prior=ontology.class_prior,
                              other_classes="lump" if args.other_classes else "error")


def build_parser() -> argparse.ArgumentParser:
    from ..experiment import ESTIMATORS

    parser = argparse.ArgumentParser(prog="psgsl", description="Probabilistic semantic gas source localization. "
                                     "Without a command: the demo.")
    parser.add_argument("--quiet", dest="top_quiet", action="store_true",
                        help="no progress bar (before a command: the same as that command's --quiet)")
    sub = parser.add_subparsers(dest="command")

    demo = sub.add_parser("demo", help="the validation experiment in small, then a small closed-loop "
                          "comparison (27–32 s on 2 idle cores; the first run also compiles the kernels)")
    demo.add_argument("--out", default="psgsl-demo", help="output directory (default: %(default)s)")
    demo.add_argument("--seeds", type=seed_count, default=None, help=f"number of seeds, at most {MAX_SEEDS} (default: 4)")
    add_workers_argument(demo)
    demo.add_argument("--quiet", action="store_true", help="no progress bar")
    demo.add_argument("--no-search", action="store_true", help="skip the closed-loop comparison")
    demo.set_defaults(func=_demo)

    exp = sub.add_parser("experiment", help="sources × seeds × estimators, parallel and resumable")
    add_world_arguments(exp)
    add_split_arguments(exp)
    exp.add_argument("--estimators", nargs="+", choices=ESTIMATORS, default=["infotaxis", "analytic-plume"],
                     help="olfactory estimators (default: %(default)s)")
    add_ontology_argument(exp)
    add_missed_hits_argument(exp)
    add_world_model_argument(exp)
    add_gas_argument(exp)
    add_workers_argument(exp)
    exp.add_argument("--out", default="psgsl-experiment", help="output directory (default: %(default)s)")
    add_scheduler_argument(exp)
    exp.add_argument("--stops", type=positive_int, default=None,
                     help="follow only the first N stops of the tour (quick checks; default: the whole tour)")
    exp.add_argument("--quiet", action="store_true", help="no progress bar")
    exp.add_argument("--record", action="store_true", help="also write each run's episode beside it: runs/<run>.bag/ "
                     "(ROS 2 bag, read by psgsl replay) and runs/<run>.mcap (Foxglove); needs the ros extra")
    exp.set_defaults(func=_experiment)

    est = sub.add_parser("estimate", help="fuse your own class beliefs and olfactory map: p(s | g, z)")
    est.add_argument("--ontology", required=True, help="ontology YAML (see Ontology.from_yaml)")
    est.add_argument("--class-probs", required=True,
                     help=".npy (..., k) in the ontology's class order, .npz (probs + classes by name), or Voxeland's "
                     "instance map .json (with --map): p(o_c | z_c) per cell")
    est.add_argument("--map", default=None, help="ROS map YAML whose grid a Voxeland .json is read onto")
    est.add_argument("--resolution", type=float, default=None, help="working cell size for --map, m "
                     "(default: the map's)")
    est.add_argument("--other-classes", action="store_true",
                     help="add classes of an .npz/.json that the ontology does not list to 'other' (default: such a "
                     "class is an error naming the closest known names)")
    est.add_argument("--olfactory", required=True, help=".npy (...): p(s | g) per cell")
    est.add_argument("--gas", default=None, help="gas name (default: the ontology's only gas)")
    est.add_argument("--out", required=True, help="file to write p(s | g, z) to, in .npy format, at exactly this path")
    est.set_defaults(func=_estimate)

    kitchen = sub.add_parser("kitchen", help="the paper's kitchen ontology on six illustrative cells")
    kitchen.set_defaults(func=_kitchen)
    _world.add_parser(sub)
    _export.add_parser(sub)
    _search.add_parser(sub)
    _replay.add_parser(sub)
    _live.add_parser(sub)
    _benchmark.add_parser(sub)
    return parser


def main(argv=None) -> int:
    """Entry point of ``psgsl``; returns the exit code (0 ok, 2 usage or input error)."""
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser.parse_args(argv)  # argparse prints usage + one line and exits 2 on bad syntax
    if args.command is None:
        argv = ["demo"] + (["--quiet"] if args.top_quiet else [])
        args = parser.parse_args(argv)
    elif args.top_quiet:
        args.quiet = True  # psgsl --quiet COMMAND: the command's own --quiet
    args.argv = argv  # for the resume hint after Ctrl-C
    from ..runs._runner import command_label

    try:
        with command_label(f"psgsl {args.command}"):  # progress bars say which command runs
            return args.func(args)
    except _INPUT_ERRORS as exc:
        print(f"psgsl {args.command}: error: {error_line(exc)}", file=sys.stderr)
        return 2


def error_line(exc: BaseException) -> str:
    """One line for an error: its message with line breaks folded (numpy arrays in messages span lines).

    An :class:`OSError` without a message of its own is told by its file name and reason.

    >>> error_line(ValueError("x must be positive,\\n got [[1]\\n [2]]"))
    'x must be positive, got [[1] [2]]'
    >>> error_line(FileNotFoundError(2, "No such file or directory", "a.npy"))
    "'a.npy': No such file or directory"
    """
    if isinstance(exc, OSError) and exc.strerror and not (exc.args and len(exc.args) == 1):
        target = f"{exc.filename!r}: " if exc.filename is not None else ""
        return f"{target}{exc.strerror}"
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
