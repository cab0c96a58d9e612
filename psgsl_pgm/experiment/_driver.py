"""The experiment grid (sources × seeds × estimators): parallel, resumable, aggregated into figures and tables."""

from __future__ import annotations

import itertools
from functools import lru_cache
from pathlib import Path

from .._grid_runner import GridJob, run_grid
from ..sim import default_house
from ._config import ESTIMATORS, ExperimentConfig, parse_source, source_label
from ._store import load_run, run_path, write_run
from ._summary import format_table, summarize, write_csv, write_summary

__all__ = ["DEMO_SEEDS", "SNAPSHOTS", "experiment_jobs", "run_demo", "run_experiment", "write_outputs"]

#: Seeds of ``psgsl demo`` (a few; ``psgsl experiment`` reports ≥ 10).
DEMO_SEEDS = tuple(range(4))

#: Search fractions of the progression figure's snapshots.
SNAPSHOTS = (0.0, 0.25, 0.5, 0.75, 1.0)


@lru_cache(maxsize=4)
def _world(path):
    """The world of a world file, loaded once per process (None: the embedded house)."""
    from ..sim import default_world, load_world

    return default_world() if path is None else load_world(path)


def search_in_world(source, seed, estimator, *, world=None, **kwargs):
    """:func:`run_search` in the world of the world file ``world`` (a path, picklable for worker processes)."""
    from . import _run

    return _run.run_search(source, seed, estimator, world_spec=_world(world), **kwargs)


def _stored_config_check(expected: dict):
    def check(job: GridJob) -> None:
        stored = load_run(job.path).config
        if stored != expected:
            raise ValueError(f"{job.path} was computed with another configuration ({stored}); use a new output "
                             "directory or delete the stored runs")
    return check


def experiment_jobs(sources, seeds, estimators, *, out, config: ExperimentConfig, world=None) -> list:
    """The grid's jobs (:class:`psgsl_pgm._grid_runner.GridJob`): one :func:`run_search` per (source, estimator,
    seed) in the world file ``world`` (None: the embedded house), its result to :func:`run_path`; the smallest
    seed keeps the progression figure's snapshots."""
    first = min(seeds)
    return [GridJob(run_path(out, source, estimator, seed), search_in_world, (source, seed, estimator),
                    {"config": config, "snapshot_at": SNAPSHOTS if seed == first else (), "world": world})
            for source, estimator, seed in itertools.product(sources, estimators, seeds)]


def run_experiment(sources=("oven",), seeds=range(10), estimators=("infotaxis",), *, out, workers: int = 2,
                   config: ExperimentConfig | None = None, progress: bool = True, flat: bool = False,
                   scheduler: str | None = None, world=None) -> dict:
    """Run every (source, seed, estimator) not yet on disk, then aggregate everything in ``out``.

    Parameters
    ----------
    sources : sequence of str
        Source specifications (:func:`parse_source`; with a world file also its source names).
    seeds : iterable of int
    estimators : sequence of {"infotaxis", "pmfs"}
    out : path, keyword-only
        Output directory; finished runs live in ``out/runs`` and are never redone (resumable); a stored run
        with another configuration is an error, not silently mixed in.
    workers : int, keyword-only
        Worker processes of the local pool (1 = run in this process) or of ``scheduler="local"``.
    config : ExperimentConfig, optional, keyword-only
    progress : bool, keyword-only
        Show a tqdm progress bar (on stderr).
    flat : bool, keyword-only
        See :func:`write_outputs`.
    scheduler : None, "local" or str, optional, keyword-only
        Where the runs go (:func:`psgsl_pgm._grid_runner.run_grid`): the local pool (None), a dask LocalCluster
        of ``workers`` processes ("local"), or a running dask scheduler (``"tcp://HOST:PORT"``). Every backend
        gives bit-identical runs.
    world : str or Path, optional, keyword-only
        A world file (:func:`psgsl_pgm.load_world`); default: the embedded house. Loaded and checked here, before
        any run, and once more in every worker process.

    Returns
    -------
    dict
        ``{"source/estimator": summary}`` (see :func:`summarize`), also written to ``out/summary.json``.

    Raises
    ------
    psgsl_pgm._grid_runner.GridInterrupted
        On Ctrl-C; the finished runs are on disk and the same call resumes.
    """
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
    world = None if world is None else str(Path(world).resolve())
    from ._run import run_config

    expected = run_config(config, _world(world))  # a bad world file fails here, before any output is written
    out = Path(out)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    jobs = experiment_jobs(sources, seeds, estimators, out=out, config=config, world=world)
    run_grid(jobs, write=write_run, check_done=_stored_config_check(expected), scheduler=scheduler, workers=workers,
             progress=progress, desc="search runs")
    return write_outputs(out, sources, seeds, estimators, flat=flat, world=world)


def write_outputs(out, sources, seeds, estimators, *, flat: bool = False, world=None) -> dict:
    """Aggregate the stored runs of the grid into summaries, CSV and figures.

    With ``flat=True`` (the demo: one source, one estimator) everything goes straight into ``out``; otherwise
    into ``out/<source>-<estimator>/``, plus ``out/summary.json`` and ``out/metrics.csv`` over all groups.
    ``world`` is the runs' world file (default: the embedded house), whose house the figures draw.
    """
    import matplotlib.pyplot as plt

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
            spec = _world(None if world is None else str(Path(world).resolve()))
            house = spec.house(shown.seed)
            fig = plot_progression(shown, house, exploration_tour(house, start=spec.start_for(house)))
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
