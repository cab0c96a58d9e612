"""The experiment grid (sources × seeds × estimators): parallel, resumable, aggregated into figures and tables."""

from __future__ import annotations

import itertools
import multiprocessing as mp
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from ._config import ESTIMATORS, ExperimentConfig, parse_source, source_label
from ._store import load_run, run_path, save_run
from ._summary import format_table, summarize, write_csv, write_summary

__all__ = ["DEMO_SEEDS", "SNAPSHOTS", "run_demo", "run_experiment", "write_outputs"]

#: Seeds of ``psgsl demo`` (a few; ``psgsl experiment`` reports ≥ 10).
DEMO_SEEDS = tuple(range(4))

#: Search fractions of the progression figure's snapshots.
SNAPSHOTS = (0.0, 0.25, 0.5, 0.75, 1.0)


def _job(args):
    source, seed, estimator, config, path, snapshots = args
    from ._run import run_search

    result = run_search(source, seed, estimator, config=config, snapshot_at=snapshots)
    save_run(result, path)
    return str(path)


def run_experiment(sources=("oven",), seeds=range(10), estimators=("infotaxis",), *, out, workers: int = 2,
                   config: ExperimentConfig | None = None, progress: bool = True, flat: bool = False) -> dict:
    """Run every (source, seed, estimator) not yet on disk, then aggregate everything in ``out``.

    Parameters
    ----------
    sources : sequence of str
        Source specifications (:func:`parse_source`).
    seeds : iterable of int
    estimators : sequence of {"infotaxis", "pmfs"}
    out : path, keyword-only
        Output directory; finished runs live in ``out/runs`` and are never redone (resumable); a stored run
        with another configuration is an error, not silently mixed in.
    workers : int, keyword-only
        Worker processes (1 = run in this process).
    config : ExperimentConfig, optional, keyword-only
    progress : bool, keyword-only
        Show a tqdm progress bar (on stderr).
    flat : bool, keyword-only
        See :func:`write_outputs`.

    Returns
    -------
    dict
        ``{"source/estimator": summary}`` (see :func:`summarize`), also written to ``out/summary.json``.
    """
    from tqdm.auto import tqdm

    config = ExperimentConfig() if config is None else config
    sources = [parse_source(s) for s in sources]
    seeds = [int(s) for s in seeds]
    estimators = list(estimators)
    bad = [e for e in estimators if e not in ESTIMATORS]
    if bad:
        raise ValueError(f"estimators must be among {ESTIMATORS}, got {bad}")
    if not (sources and seeds and estimators):
        raise ValueError("need at least one source, one seed and one estimator")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    out = Path(out)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    first = min(seeds)
    jobs = []
    for source, estimator, seed in itertools.product(sources, estimators, seeds):
        path = run_path(out, source, estimator, seed)
        if path.exists():
            stored = load_run(path).config
            if stored != config.to_dict():
                raise ValueError(f"{path} was computed with another configuration ({stored}); use a new output "
                                 "directory or delete the stored runs")
            continue
        jobs.append((source, seed, estimator, config, path, SNAPSHOTS if seed == first else ()))
    bar = tqdm(total=len(jobs), desc="search runs", unit="run", disable=not progress or not jobs)
    if workers == 1 or len(jobs) <= 1:
        for job in jobs:
            _job(job)
            bar.update()
    else:
        ctx = mp.get_context("spawn")  # no fork of a threaded process
        with ProcessPoolExecutor(max_workers=min(workers, len(jobs)), mp_context=ctx) as pool:
            for fut in as_completed([pool.submit(_job, j) for j in jobs]):
                fut.result()
                bar.update()
    bar.close()
    return write_outputs(out, sources, seeds, estimators, flat=flat)


def write_outputs(out, sources, seeds, estimators, *, flat: bool = False) -> dict:
    """Aggregate the stored runs of the grid into summaries, CSV and figures.

    With ``flat=True`` (the demo: one source, one estimator) everything goes straight into ``out``; otherwise
    into ``out/<source>-<estimator>/``, plus ``out/summary.json`` and ``out/metrics.csv`` over all groups.
    """
    import matplotlib.pyplot as plt

    from ..sim import default_house
    from ._figures import plot_error_chart, plot_progression, plot_room_types
    from ._tour import exploration_tour

    out = Path(out)
    summaries, all_runs = {}, []
    for source, estimator in itertools.product(sources, estimators):
        runs = [load_run(run_path(out, source, estimator, s)) for s in seeds]
        all_runs += runs
        group = out if flat else out / f"{source_label(source)}-{estimator}"
        group.mkdir(parents=True, exist_ok=True)
        summary = summarize(runs)
        summary.update(source=runs[0].source, estimator=estimator)
        summaries[f"{runs[0].source}/{estimator}"] = summary
        write_summary(summary, group / "summary.json")
        write_csv(runs, group / "metrics.csv")
        fig = plot_error_chart(runs)
        fig.savefig(group / "error-chart.png", dpi=120)
        plt.close(fig)
        shown = min(runs, key=lambda r: r.seed)
        if shown.snapshots:
            house = default_house(shown.seed)
            fig = plot_progression(shown, house, exploration_tour(house))
            fig.savefig(group / "progression.png", dpi=110)
            plt.close(fig)
            start = shown.snapshots[min(shown.snapshots)]
            fig = plot_room_types(start[1], start[2], house, source=shown.source_xy)
            fig.savefig(group / "room-types.png", dpi=110)
            plt.close(fig)
        (group / "summary.txt").write_text(
            format_table(summary, title=f"source {runs[0].source}, estimator {estimator}") + "\n", encoding="utf-8")
    if not flat:
        write_summary(summaries, out / "summary.json")
        write_csv(all_runs, out / "metrics.csv")
    return summaries


def run_demo(out, *, seeds=DEMO_SEEDS, workers: int = 2, estimator: str = "infotaxis", progress: bool = True) -> dict:
    """``psgsl demo``: the embedded house, smoke from the kitchen oven, a few seeds; outputs flat in ``out``.

    Returns the summary (see :func:`summarize`) that is also written to ``out/summary.json``.
    """
    seeds = [int(s) for s in seeds]
    out = Path(out)
    config = ExperimentConfig()
    summaries = run_experiment(("oven",), seeds, (estimator,), out=out, workers=workers, config=config,
                               progress=progress, flat=True)
    return summaries[f"oven/{estimator}"]
