"""The experiment grid (sources × seeds × estimators): parallel, resumable, aggregated into figures and tables."""

from __future__ import annotations

import itertools
from functools import lru_cache
from pathlib import Path

from ..runs._key import digest, run_key, world_key
from ..runs._runner import GridJob, atomic_write, grid_folder, run_grid
from ..sim import default_house
from ._config import ESTIMATORS, ExperimentConfig, parse_source, source_label
from ._store import load_run, read_run_key, run_path, write_run
from ._summary import format_table, summarize, write_csv, write_summary

__all__ = ["DEMO_SEEDS", "SNAPSHOTS", "experiment_jobs", "experiment_key", "run_demo", "run_experiment",
           "stored_runs", "write_outputs"]

#: Seeds of ``psgsl demo`` (a few; ``psgsl experiment`` reports ≥ 10).
DEMO_SEEDS = tuple(range(4))

#: Search fractions of the progression figure's snapshots.
SNAPSHOTS = (0.0, 0.25, 0.5, 0.75, 1.0)


@lru_cache(maxsize=4)
def _world_of(path, world_digest: str):
    """The world of a world file (None: the embedded house) whose run-key part has ``world_digest``; loaded once
    per process and content."""
    from ..sim import default_world, load_world

    spec = default_world() if path is None else load_world(path)
    if digest(world_key(path)) != world_digest:  # hashed after loading: what was loaded is what was keyed
        raise ValueError(f"{path or 'the embedded house'}: the world file or a file it names changed after the "
                         "runs were keyed; run the command again")
    return spec


def _world(path, world_digest: str | None = None):
    """The world of the world file ``path`` (None: the embedded house) as its files are now, or — with
    ``world_digest`` — as they were when a grid was keyed (ValueError if they changed since)."""
    return _world_of(path, digest(world_key(path)) if world_digest is None else world_digest)


def search_in_world(source, seed, estimator, *, world=None, world_digest=None, record=None, **kwargs):
    """:func:`run_search` in the world of the world file ``world`` (a path, picklable for worker processes;
    ``world_digest``: see :func:`_world`). The run's config records the start the robot used. With ``record``
    (a path without suffix) the episode is also written as ``<record>.bag/`` and ``<record>.mcap``
    (:class:`psgsl_pgm.experiment._record.EpisodeRecorder`)."""
    from . import _run

    recorder = None
    if record is not None:
        from ._record import EpisodeRecorder

        recorder = EpisodeRecorder()
    result = _run.run_search(source, seed, estimator, world_spec=_world(world, world_digest), recorder=recorder,
                             **kwargs)
    result.config["start"] = [float(v) for v in result.position[0]]
    if recorder is not None:
        from ._config import ESTIMATOR_NAMING, VARIANTS

        spec = parse_source(source)
        meta = {"world": world, "source": spec if isinstance(spec, str) else list(spec), "seed": int(seed),
                "estimator": estimator, "estimator_naming": ESTIMATOR_NAMING,
                "config": {k: v for k, v in result.config.items() if k != "start"}}
        recorder.write(record, variants=VARIANTS, meta=meta)
    return result


def experiment_jobs(sources, seeds, estimators, *, out, config: ExperimentConfig, world=None,
                    world_digest=None, record: bool = False) -> list:
    """The grid's jobs (:class:`psgsl_pgm.runs._runner.GridJob`): one :func:`run_search` per (source, estimator,
    seed) in the world file ``world`` (None: the embedded house), its result to :func:`run_path`; the smallest
    seed keeps the progression figure's snapshots. ``record``: each run also writes its episode beside it
    (``runs/<run>.bag/``, ``runs/<run>.mcap``)."""
    first = min(seeds)
    jobs = []
    for source, estimator, seed in itertools.product(sources, estimators, seeds):
        path = run_path(out, source, estimator, seed)
        kwargs = {"config": config, "snapshot_at": SNAPSHOTS if seed == first else (), "world": world,
                  "world_digest": world_digest}
        if record:
            kwargs["record"] = str(path.with_suffix(""))
        jobs.append(GridJob(path, search_in_world, (source, seed, estimator), kwargs))
    return jobs


def experiment_key(config: ExperimentConfig, world_part: dict, *, flat: bool = False, source=None,
                   estimator=None) -> dict:
    """The run key (:mod:`psgsl_pgm.runs._key`) of an experiment's stored runs: the world's content, the
    :class:`ExperimentConfig`, the package version and the folder's layout (``flat``: one source and estimator
    written straight into the folder, as ``psgsl demo`` does)."""
    layout = {"flat": True, "source": source_label(source), "estimator": estimator} if flat else {"flat": False}
    return run_key("experiment", world_part, experiment=config, layout=layout)


def run_experiment(sources=("oven",), seeds=range(10), estimators=("infotaxis",), *, out, workers: int = 2,
                   config: ExperimentConfig | None = None, progress: bool = True, flat: bool = False,
                   scheduler: str | None = None, world=None, record: bool = False) -> dict:
    """Run every (source, seed, estimator) not yet on disk, then aggregate everything in ``out``.

    Parameters
    ----------
    sources : sequence of str
        Source specifications (:func:`parse_source`; with a world file also its source names).
    seeds : iterable of int
    estimators : sequence of {"infotaxis", "analytic-plume", "particle-filter", "pmfs", "grgsl"}
    out : path, keyword-only
        Output directory; finished runs live in ``out/runs`` and are never redone (resumable). The folder holds
        one configuration: a stored run whose run key (the world file's content and the bytes of every file it
        names, ``config``, the package version; :mod:`psgsl_pgm.runs._key`) differs is refused, naming each
        differing setting, before anything is created; a second process on the same folder is refused
        (:func:`psgsl_pgm.runs._runner.grid_folder`).
    workers : int, keyword-only
        Worker processes of the local pool (1 = run in this process) or of ``scheduler="local"``.
    config : ExperimentConfig, optional, keyword-only
    progress : bool, keyword-only
        Show a tqdm progress bar (on stderr).
    flat : bool, keyword-only
        See :func:`write_outputs`.
    scheduler : None, "local" or str, optional, keyword-only
        Where the runs go (:func:`psgsl_pgm.runs._runner.run_grid`): the local pool (None), a dask LocalCluster
        of ``workers`` processes ("local"), or a running dask scheduler (``"tcp://HOST:PORT"``). Every backend
        gives bit-identical runs.
    world : str or Path, optional, keyword-only
        A world file (:func:`psgsl_pgm.load_world`); default: the embedded house. Loaded and checked here, before
        any run, and once more in every worker process.
    record : bool, keyword-only
        Also write every run's episode beside it: ``runs/<run>.bag/`` (a ROS 2 bag that ``psgsl replay`` reads)
        and ``runs/<run>.mcap`` (Foxglove); needs the ``ros`` extra. Runs already stored are not re-run.

    Returns
    -------
    dict
        ``{"source/estimator": summary}`` (see :func:`summarize`) over every run stored in ``out`` (also those of
        earlier calls with other sources or seeds), also written to ``out/summary.json``.

    Raises
    ------
    psgsl_pgm.runs._runner.GridInterrupted
        On Ctrl-C; the finished runs are on disk and the same call resumes.

    Examples
    --------
    Each run is a whole tour (about a minute), so a grid is shown in ``docs/guide/scaling-out.md`` and
    ``docs/guide/robot-data.md`` (``psgsl experiment``). What the call refuses it refuses before any run starts:

    >>> from psgsl_pgm.experiment import run_experiment
    >>> try:
    ...     run_experiment(estimators=("kalman",), out="never-created")
    ... except ValueError as err:
    ...     print(str(err).startswith("estimators must be among"))
    True
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
    if flat and (len(sources) != 1 or len(estimators) != 1):
        raise ValueError(f"flat=True writes one source and one estimator, got sources {sources} and estimators "
                         f"{estimators}")
    world = None if world is None else str(Path(world).resolve())
    world_part = world_key(world)
    world_digest = digest(world_part)
    _world(world, world_digest)  # a bad world file fails here, before any output is written
    key = experiment_key(config, world_part, flat=flat, source=sources[0], estimator=estimators[0])

    def write(result, fh) -> None:
        result.config["key"] = key  # what a later call is checked against
        write_run(result, fh)

    with grid_folder(out, key, read_key=read_run_key) as out:
        jobs = experiment_jobs(sources, seeds, estimators, out=out, config=config, world=world,
                               world_digest=world_digest, record=record)
        run_grid(jobs, write=write, scheduler=scheduler, workers=workers, progress=progress, desc="search runs")
        return write_outputs(out, flat=flat, world=world)


def stored_runs(out) -> dict:
    """Every run stored in ``out/runs``, by group: ``{(source, estimator): [RunResult, ...]}`` (seeds in order;
    groups by source label, then in the order of :data:`ESTIMATORS`)."""
    groups: dict = {}
    for path in sorted((Path(out) / "runs").glob("*.npz")):
        r = load_run(path)
        groups.setdefault((r.source, r.estimator), []).append(r)
    order = sorted(groups, key=lambda g: (source_label(g[0]), ESTIMATORS.index(g[1]) if g[1] in ESTIMATORS else 99))
    return {g: sorted(groups[g], key=lambda r: r.seed) for g in order}


def write_outputs(out, *, flat: bool = False, world=None) -> dict:
    """Aggregate every run stored in ``out/runs`` into summaries, CSV and figures.

    The runs are those :func:`~psgsl_pgm.experiment._driver.stored_runs` finds. With ``flat=True`` (the demo: one
    source, one estimator) everything goes straight into ``out``; otherwise into ``out/<source>-<estimator>/``,
    plus ``out/summary.json`` and ``out/metrics.csv`` over all groups. Each group gets ``summary.json``,
    ``summary.txt`` (:func:`format_table`), ``metrics.csv``, ``error-chart.png`` and, when its first run kept
    snapshots, ``progression.png`` and ``room-types.png``.

    Parameters
    ----------
    out : str or path-like
        The experiment's output folder, holding ``runs/``.
    flat : bool, default False, keyword-only
        Write one group straight into ``out``.
    world : str or path-like, optional, keyword-only
        The runs' world file, whose house the figures draw; the embedded house when None.

    Returns
    -------
    dict
        ``{"<source>/<estimator>": summary}``, each as :func:`summarize` returns it plus ``source`` and
        ``estimator``.

    Raises
    ------
    ValueError
        No runs are stored in ``out/runs``, or ``flat=True`` with runs of more than one source and estimator.

    Examples
    --------
    After :func:`run_experiment` (or ``psgsl experiment --out DIR``) has stored its runs, ``write_outputs(DIR)``
    returns ``{"oven/infotaxis": summary, ...}``; drawing the figures takes seconds, so ``docs/guide/robot-data.md``
    runs it (``psgsl experiment``). A folder without runs is refused:

    >>> import tempfile
    >>> from psgsl_pgm.experiment import write_outputs
    >>> with tempfile.TemporaryDirectory() as out:
    ...     try:
    ...         write_outputs(out)
    ...     except ValueError as err:
    ...         print(str(err).startswith("no runs stored in"))
    True
    """
    import matplotlib.pyplot as plt

    from ._figures import plot_error_chart, plot_progression, plot_room_types
    from ._tour import exploration_tour

    out = Path(out)
    summaries, all_runs = {}, []
    groups = stored_runs(out)
    if not groups:
        raise ValueError(f"no runs stored in {out / 'runs'}")
    if flat and len(groups) != 1:
        raise ValueError(f"{out / 'runs'} holds runs of {len(groups)} sources × estimators; flat=True writes one")
    for (source, estimator), runs in groups.items():
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
        table = format_table(summary, title=f"source {runs[0].source}, estimator {estimator}") + "\n"
        atomic_write(group / "summary.txt", lambda text, fh: fh.write(text.encode("utf-8")), table)
    if not flat:
        write_summary(summaries, out / "summary.json")
        write_csv(all_runs, out / "metrics.csv")
    return summaries


def run_demo(out, *, seeds=DEMO_SEEDS, workers: int = 2, estimator: str = "infotaxis", progress: bool = True) -> dict:
    """``psgsl demo``: the embedded house, smoke from the kitchen oven, a few seeds; outputs flat in ``out``.

    The runs are stored under ``out/runs`` (resumable: a run already stored is not repeated), and
    :func:`write_outputs` writes the summary, the CSV and the figures straight into ``out``.

    Parameters
    ----------
    out : str or path-like
        The output folder (made if missing).
    seeds : sequence of int, default (0, 1, 2, 3), keyword-only
        The houses' seeds, one run each.
    workers : int, default 2, keyword-only
        Processes that run the searches (>= 1).
    estimator : str, default "infotaxis", keyword-only
        The olfactory estimator, a name of :data:`ESTIMATORS`.
    progress : bool, default True, keyword-only
        Show a progress bar on stderr.

    Returns
    -------
    dict
        The summary (see :func:`summarize`) that is also written to ``out/summary.json``.

    Raises
    ------
    ValueError
        ``estimator`` is not one of :data:`ESTIMATORS`, ``seeds`` is empty, or ``workers`` is not a positive
        integer.

    Examples
    --------
    About a minute per seed (``psgsl demo``, ``docs/getting-started.md``), so the call is not run here;
    ``run_demo("psgsl-demo", seeds=(0,), workers=1, progress=False)["n_runs"]`` is 1. Its arguments are checked
    before any run:

    >>> from psgsl_pgm.experiment import run_demo
    >>> try:
    ...     run_demo("never-created", estimator="kalman")
    ... except ValueError as err:
    ...     print(str(err).startswith("estimators must be among"))
    True
    """
    seeds = [int(s) for s in seeds]
    out = Path(out)
    config = ExperimentConfig()
    summaries = run_experiment(("oven",), seeds, (estimator,), out=out, workers=workers, config=config,
                               progress=progress, flat=True)
    return summaries[f"oven/{estimator}"]
