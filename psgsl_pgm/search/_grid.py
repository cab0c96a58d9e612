"""The closed-loop grid (sources × policies × variants × estimators × seeds): resumable runs, summaries,
paired differences, per-run CSV and figures (``psgsl search``)."""

from __future__ import annotations

import csv
import itertools
import json
import os
from pathlib import Path

import numpy as np

from ..experiment._config import ESTIMATORS, VARIANTS, ExperimentConfig, parse_source, source_label
from ..experiment._driver import _world
from ..experiment._metrics import calibration_summary, mean_ci
from ..io._json import json_safe
from ..runs._key import digest, run_key, world_key
from ._loop import SearchConfig, run_closed_loop
from ._metrics import declaration_summary, wilson_interval
from ._split import split_of_seeds
from ._policies import ESTIMATOR_OF, POLICIES, SEMANTICS_ALONE, check_estimator, check_semantics_alone
from ._reactive import REACTIVE
from ._store import load_search_run, read_run_key, search_run_path, write_search_run
from ._survival import holm, kaplan_meier, km_median, paired_comparison, rmst

__all__ = ["PRIMARY", "run_search_grid", "summarize_runs", "write_search_outputs"]


def search_key(config: ExperimentConfig, search: SearchConfig, world_part: dict) -> dict:
    """The run key (:mod:`psgsl_pgm.runs._key`) of the closed loop's stored runs: the world's content (its
    :func:`psgsl_pgm.runs._key.world_key`), both configs and the package version."""
    return run_key("search", world_part, experiment=config, search=search)


def closed_loop_in_world(source, seed, policy, variant, estimator, *, world=None, world_digest=None, record=None,
                         **kwargs):
    """:func:`run_closed_loop` in the world of the world file ``world`` (a resolved path, picklable for worker
    processes; None: the embedded house; ``world_digest``: the content it was keyed with, see
    :func:`psgsl_pgm.experiment._driver._world`). The stored run's config names the world file. With ``record``
    (a path without suffix) the episode is also written as ``<record>.bag/`` and ``<record>.mcap``. The run's
    config gains ``cpu_seconds``, the process time the episode took (the world's construction included; not part
    of the run key: a measurement, for the methods' CPU per decision)."""
    import time

    t0 = time.process_time()
    recorder = None
    if record is not None:
        from ..experiment._record import EpisodeRecorder

        recorder = EpisodeRecorder()
    if world is None:  # the embedded house: the loop's own default world (part of the package)
        run = run_closed_loop(source, seed, policy, variant, estimator, recorder=recorder, **kwargs)
    else:
        run = run_closed_loop(source, seed, policy, variant, estimator, world_spec=_world(world, world_digest),
                              recorder=recorder, **kwargs)
        run.config["world"] = str(world)
    if recorder is not None:
        spec = parse_source(source)
        meta = {"world": world, "source": spec if isinstance(spec, str) else list(spec), "seed": int(seed),
                "estimator": estimator, "policy": policy, "variant": variant,
                "config": dict(run.config["experiment"])}
        recorder.write(record, variants=(variant,), meta=meta)
    run.config["cpu_seconds"] = time.process_time() - t0
    return run


#: The comparison declared before the runs (docs/guide/closed-loop.md): in ``paired.json`` of source oven,
#: estimator infotaxis, it is marked ``"primary": true`` and tested alone at 5 %; every other comparison of a table
#: is secondary and Holm-adjusted within its table.
PRIMARY = {"source": "oven", "estimator": "infotaxis",
           "comparison": "infotaxis/semantics+rooms - infotaxis/olfaction"}


def _budget(runs) -> float:
    budgets = {float(r.config["search"]["time_budget"]) for r in runs}
    if len(budgets) != 1:
        raise ValueError(f"runs of one table must share one time budget, got {sorted(budgets)} s")
    return budgets.pop()


def summarize_runs(runs) -> dict:
    """Statistics of one policy × variant over its runs (see :func:`run_search_grid`).

    A run succeeds with a right declaration (:attr:`SearchRun.succeeded`; runs with ``end="reach"``: the find).
    Times to success are censored at the budget τ (:mod:`psgsl_pgm.search._survival`): ``km`` is the Kaplan–Meier
    curve of P(no success by t) with 95 % log(−log) Greenwood bands, ``rmst`` the restricted mean time to success
    RMST(τ) = ∫₀^τ S(t) dt with its 95 % Greenwood interval, ``time_to_find.median`` the Kaplan–Meier median (None
    when more than half of the runs do not succeed). ``declared_success``, ``declared_error`` and
    ``false_declaration_rate`` describe the declarations (:func:`psgsl_pgm.search._metrics.declaration_summary`);
    ``reach`` the secondary time of the first pass within the found radius of the source. ``coverage90``, ``region_area90`` and ``hpd_level`` measure the
    calibration of the declared credible region (:func:`psgsl_pgm.experiment._metrics.calibration_summary`);
    ``mean_error`` is the error averaged over the search time (:func:`_time_mean`). ``split`` is the seeds'
    split (:func:`psgsl_pgm.search._split.split_of_seeds`: ``"dev"``, ``"test"`` or ``"mixed"``).

    Parameters
    ----------
    runs : iterable of SearchRun
        The runs of one policy × variant (one per seed), all with the same time budget.

    Returns
    -------
    dict
        The statistics named above, plus ``n_runs``, ``end``, ``success_rate`` (with its 95 % Wilson interval),
        ``path_ratio``, ``final_error``, ``credible``, ``seeds`` and, for runs not told their gas, the gas
        statistics (:func:`gas_summary`).

    Raises
    ------
    ValueError
        The runs do not share one time budget, or there is no run.

    Examples
    --------
    One short run (a 20-s budget):

    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import SearchConfig, run_closed_loop, summarize_runs
    >>> run = run_closed_loop("oven", 0, "greedy", "olfaction", config=ExperimentConfig(warm_up=5.0),
    ...                       search=SearchConfig(time_budget=20.0))
    >>> s = summarize_runs([run])
    >>> s["n_runs"], s["success_rate"]["value"], s["rmst"]["tau"]     # not found in 20 s: RMST is the budget
    (1, 0.0, 20.0)
    """
    runs = list(runs)
    found = np.array([r.succeeded for r in runs])
    t = np.array([r.time_to_success for r in runs])
    n = len(runs)
    budget = _budget(runs)
    km = kaplan_meier(t, found)
    area = rmst(t, found, budget)
    ratio = np.array([r.path_ratio for r in runs])
    reached = np.array([r.found for r in runs])
    t_reach = np.array([r.time_to_find for r in runs])
    reach_area = rmst(t_reach, reached, budget)
    ends = sorted({r.end for r in runs})
    return {
        "n_runs": n,
        "end": ends[0] if len(ends) == 1 else "mixed",
        "success_rate": {"value": float(found.mean()), "ci95": wilson_interval(int(found.sum()), n)},
        "time_to_find": {"median": km_median(km), "not_found": int((~found).sum()), "budget": budget,
                         "note": "Kaplan-Meier median of the time to success (None: not reached within the budget)"},
        "rmst": {"value": area["value"], "ci95": area["ci95"], "tau": budget},
        **(declaration_summary([r.declared for r in runs], [r.declared_correct for r in runs],
                               [r.declared_error for r in runs]) if ends == ["declare"] else
           dict.fromkeys(("declared", "declared_success", "declared_error", "false_declaration_rate"))),
        "reach": {"success_rate": {"value": float(reached.mean()), "ci95": wilson_interval(int(reached.sum()), n)},
                  "rmst": {"value": reach_area["value"], "ci95": reach_area["ci95"], "tau": budget},
                  "note": "secondary: the first pass within the found radius of the source, which ends no run"},
        "km": km,
        "path_ratio": mean_ci(ratio),
        **calibration_summary(runs),
        "credible": float(runs[0].config["search"].get("credible", 0.9)),  # the mass of the region measured
        "final_error": mean_ci([r.error[-1] for r in runs], lower=0.0),
        "mean_error": mean_ci([_time_mean(r.time, r.error) for r in runs], lower=0.0),
        "seeds": [int(r.seed) for r in runs],
        "split": split_of_seeds(r.seed for r in runs),
        **gas_summary(runs, budget),
    }


def gas_summary(runs, budget: float) -> dict:
    """How well runs whose gas the robot was not told identified it: ``gas_identified`` (the fraction of runs
    whose most probable gas at the end, arg max p(γ | ζ_1:t), is the true one, with its 95 % Wilson interval) and
    ``time_to_gas`` (RMST(τ) of the time until p(true γ | ζ_1:t) ≥ 0.9, censored at the budget τ, with its 95 %
    Greenwood interval, and how many runs reached it). Empty when any run was told its gas."""
    runs = list(runs)
    if not runs or not all(r.gas_unknown for r in runs):
        return {}
    n = len(runs)
    ok = np.array([r.gas_identified for r in runs])
    timed = [r.time_to_gas() for r in runs]
    t = np.array([v[0] for v in timed])
    reached = np.array([v[1] for v in timed])
    area = rmst(t, reached, budget)
    return {"gas_identified": {"value": float(ok.mean()), "ci95": wilson_interval(int(ok.sum()), n)},
            "time_to_gas": {"value": area["value"], "ci95": area["ci95"], "tau": budget, "level": 0.9,
                            "reached": int(reached.sum()), "n_runs": n,
                            "note": "RMST of the time until p(true gas | e-nose readings) >= 0.9, censored at the budget"}}


def _time_mean(time, values) -> float:
    """Mean over the search time of a step function (each value holds until the next stop)."""
    if len(time) < 2 or time[-1] <= 0:
        return float(values[0])
    return float(np.sum(values[:-1] * np.diff(time)) / time[-1])


def _paired(groups: dict, *, source=None, estimator=None) -> dict:
    """Paired comparisons of the RMST (same seeds): every key vs the same policy with ``olfaction``, and vs
    ``tour`` (same variant if run, else ``tour/olfaction``).

    Each entry ``"A - B"`` holds ``rmst_difference`` = RMST_A(τ) − RMST_B(τ) in s (negative: A finds the source
    sooner) with its percentile-bootstrap interval over seeds, the sign-flip permutation ``p_value``, ``p_holm``
    (Holm's adjustment over the table's secondary comparisons; the primary comparison, :data:`PRIMARY`, is tested
    alone and keeps its p-value), ``primary``, ``exploratory`` (every comparison but the primary one: not declared
    before the runs, it suggests and does not confirm), ``n`` and the runs found by each side."""
    out = {}
    for key, runs in groups.items():
        policy, variant = key.split("/")
        refs = []
        if variant != "olfaction" and f"{policy}/olfaction" in groups:
            refs.append(f"{policy}/olfaction")
        if policy != "tour":
            refs.append(f"tour/{variant}" if f"tour/{variant}" in groups else "tour/olfaction")
        for ref in refs:
            if ref not in groups:
                continue
            a = {r.seed: r for r in runs}
            b = {r.seed: r for r in groups[ref]}
            seeds = sorted(set(a) & set(b))
            if len(seeds) < 2:
                continue
            budget = _budget([a[s] for s in seeds] + [b[s] for s in seeds])
            cmp = paired_comparison([a[s].time_to_success for s in seeds], [b[s].time_to_success for s in seeds],
                                    budget)
            name = f"{key} - {ref}"
            primary = (source, estimator, name) == (PRIMARY["source"], PRIMARY["estimator"], PRIMARY["comparison"])
            out[name] = {
                "rmst_difference": {"value": cmp["value"], "ci95": cmp["ci95"], "interval": cmp["interval"]},
                "p_value": cmp["p_value"], "test": cmp["test"], "primary": primary, "exploratory": not primary,
                "n": cmp["n"],
                "seeds": seeds, "found": {"A": int(sum(a[s].succeeded for s in seeds)),
                                          "B": int(sum(b[s].succeeded for s in seeds))},
                "direction": "A - B, s: negative when A succeeds sooner",
            }
    secondary = [k for k, v in out.items() if not v["primary"]]
    adjusted = holm([out[k]["p_value"] for k in secondary]) if secondary else []
    for k, p in zip(secondary, adjusted):
        out[k]["p_holm"] = float(p)
    for v in out.values():
        v.setdefault("p_holm", v["p_value"])  # the primary comparison: a family of one
    return out


def _write_json(obj, path: Path) -> None:
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(json.dumps(json_safe(obj), indent=2, sort_keys=True, allow_nan=False) + "\n", encoding="utf-8")
    os.replace(tmp, path)


_CSV = ("source", "estimator", "policy", "variant", "seed", "found", "time_to_find", "driven", "geodesic",
        "path_ratio", "n_steps", "final_error", "final_map_error", "final_spread", "final_region_area",
        "final_region_hit", "final_hpd_level", "mean_error", "end", "declared", "time_to_declare",
        "declared_x", "declared_y", "declared_error", "declared_correct", "succeeded", "time_to_success")


def _write_csv(runs, path: Path) -> None:
    tmp = path.with_name(path.name + ".part")
    with open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(_CSV)
        for r in runs:
            w.writerow([r.source, r.estimator, r.policy, r.variant, r.seed, int(r.found), f"{r.time_to_find:.6g}",
                        f"{r.driven:.6g}", f"{r.geodesic:.6g}", f"{r.path_ratio:.6g}", r.n_steps,
                        f"{r.error[-1]:.6g}", f"{r.map_error[-1]:.6g}", f"{r.spread[-1]:.6g}",
                        f"{r.region_area[-1]:.6g}", int(r.region_hit[-1]), f"{r.hpd_level[-1]:.6g}",
                        f"{_time_mean(r.time, r.error):.6g}", r.end, int(r.declared), f"{r.time_to_declare:.6g}",
                        f"{r.declared_xy[0]:.6g}", f"{r.declared_xy[1]:.6g}", f"{r.declared_error:.6g}",
                        int(r.declared_correct), int(r.succeeded), f"{r.time_to_success:.6g}"])
    os.replace(tmp, path)


def write_search_outputs(out, *, figures: bool = True, world=None) -> dict:
    """Aggregate every run stored in ``out/runs``: per source × estimator a folder with ``summary.json``
    (one entry per ``"<policy>/<variant>"``), ``paired.json`` (only when something is paired), ``runs.csv`` and
    figures; plus ``out/summary.json``
    (``{"<source>/<estimator>": {"<policy>/<variant>": ...}}``) and ``out/runs.csv`` over all of them.
    ``world`` is the runs' world file (default: the embedded house), whose house the path figures draw.

    Parameters
    ----------
    out : str or os.PathLike
        The grid's folder; its runs are read from ``out/runs/*.npz`` (:func:`load_search_run`).
    figures : bool, default True, keyword-only
        Also draw ``survival.png`` (:func:`plot_survival`) and ``paths.png`` (:func:`plot_paths`, the runs of
        the smallest seed) per source × estimator; needs the ``matplotlib`` extra.
    world : str or os.PathLike, optional, keyword-only
        The runs' world file, whose house the path figures draw; default: the embedded house.

    Returns
    -------
    dict
        ``{"<source>/<estimator>": {"<policy>/<variant>": summary}}`` (:func:`summarize_runs`), as written to
        ``out/summary.json``.

    Raises
    ------
    ValueError
        ``out/runs`` holds no run, a file there is not a search run, or the runs of one table do not share one
        time budget.

    Examples
    --------
    Aggregating a folder that holds one run (made by :func:`run_search_grid`):

    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import SearchConfig, run_search_grid, write_search_outputs
    >>> with tempfile.TemporaryDirectory() as out:
    ...     _ = run_search_grid(["oven"], ["greedy"], ["olfaction"], ["infotaxis"], [0], out=out, workers=1,
    ...                         config=ExperimentConfig(warm_up=5.0), search=SearchConfig(time_budget=20.0),
    ...                         progress=False, figures=False)
    ...     top = write_search_outputs(out, figures=False)
    ...     print(sorted(p.name for p in (Path(out) / "oven-infotaxis").iterdir()))
    ['runs.csv', 'summary.json']
    >>> top["oven/infotaxis"]["greedy/olfaction"]["success_rate"]["value"]
    0.0
    """
    out = Path(out)
    files = sorted((out / "runs").glob("*.npz"))
    runs = [load_search_run(f) for f in files]
    if not runs:
        raise ValueError(f"no search runs stored in {out / 'runs'}")
    groups: dict = {}
    for r in runs:
        groups.setdefault((r.source, r.estimator), {}).setdefault(f"{r.policy}/{r.variant}", []).append(r)
    order = {k: i for i, k in enumerate(f"{p}/{v}" for p in POLICIES for v in VARIANTS)}
    top = {}
    for (source, estimator), by_key in sorted(groups.items()):
        by_key = {k: sorted(by_key[k], key=lambda r: r.seed) for k in sorted(by_key, key=order.get)}
        folder = out / f"{source_label(source)}-{estimator}"
        folder.mkdir(parents=True, exist_ok=True)
        summary = json_safe({k: summarize_runs(v) for k, v in by_key.items()})
        _write_json(summary, folder / "summary.json")
        paired = _paired(by_key, source=source, estimator=estimator)
        if paired:  # nothing paired (one policy/variant, or fewer than 2 common seeds): no paired.json
            _write_json(paired, folder / "paired.json")
        _write_csv([r for v in by_key.values() for r in v], folder / "runs.csv")
        top[f"{source}/{estimator}"] = summary
        if figures:
            import matplotlib.pyplot as plt

            from ._figures import plot_paths, plot_survival

            fig = plot_survival(by_key, title=f"source {source}, estimator {estimator}")
            fig.savefig(folder / "survival.png", dpi=120)
            plt.close(fig)
            seed = min(r.seed for v in by_key.values() for r in v)
            shown = {k: next(r for r in v if r.seed == seed) for k, v in by_key.items() if any(r.seed == seed for r in v)}
            fig = plot_paths(shown, _world(world).house(seed),
                             title=f"source {source}, estimator {estimator}, seed {seed}")
            fig.savefig(folder / "paths.png", dpi=110)
            plt.close(fig)
    _write_json(top, out / "summary.json")
    _write_csv(runs, out / "runs.csv")
    return top


def _check_sources(sources, world_spec=None) -> None:
    """Fail before any work: a class name must have an object in the house, a position must be a free cell.
    With a world (:func:`psgsl_pgm.load_world`) its house is checked and its source names are resolved."""
    from ..sim import default_house

    house = default_house(0) if world_spec is None else world_spec.house(0)
    for spec in sources:
        spec = parse_source(spec)
        if world_spec is not None:
            spec = world_spec.source_spec(spec)
            if isinstance(spec, str):
                world_spec.resolve_source(spec, house)  # lumped classes ("other") resolved as the runs do
                continue
        if isinstance(spec, str):
            if not house.objects_of_class(spec):
                raise ValueError(f"source class {spec!r} has no object in the house; classes present: "
                                 f"{sorted({o.class_name for o in house.objects})}")
            continue
        r, c = (int(v) for v in house.grid.world_to_cell(np.asarray(spec, dtype=np.float64)))
        if not (0 <= r < house.shape[0] and 0 <= c < house.shape[1]) or not house.grid.free[r, c]:
            raise ValueError(f"source position {spec} must be a free point of the house (x in [0, "
                             f"{house.shape[1] * house.grid.resolution:g}], y in [0, "
                             f"{house.shape[0] * house.grid.resolution:g}] m)")


def run_search_grid(sources=("oven",), policies=("tour", "infotaxis"), variants=("olfaction", "semantics+rooms"),
                    estimators=("infotaxis",), seeds=range(10), *, out, workers: int = 2,
                    config: ExperimentConfig | None = None, search: SearchConfig | None = None,
                    progress: bool = True, figures: bool = True, grid=None, scheduler: str | None = None,
                    world=None, record: bool = False) -> dict:
    """Run every (source, policy, variant, estimator, seed) not yet on disk, then aggregate ``out``.

    Jobs are submitted seed by seed (all combinations of seed 0, then of seed 1, …), so that an interrupted grid
    leaves every combination with about the same number of seeds. ``grid`` (keyword-only) replaces the full
    product by an explicit sequence of ``(source, policy, variant, estimator, seed)`` tuples, run in that order
    (e.g. the tour with one variant only: its path does not depend on the variant). ``scheduler``: the grid
    runner's backend (:func:`psgsl_pgm.runs._runner.run_grid`: None = a local pool of ``workers`` processes,
    "local" = a dask LocalCluster, or a dask scheduler's address); Ctrl-C raises
    :class:`psgsl_pgm.runs._runner.GridInterrupted` with every finished run on disk. ``world`` (keyword-only):
    a world file (:func:`psgsl_pgm.load_world`; sources may then be its source names), loaded and checked
    before any output is written; default: the embedded house.

    Finished runs live in ``out/runs`` (one atomic file each) and are never redone. The folder holds one
    configuration: a stored run whose run key (the world file's content and the bytes of every file it names,
    both configs, the package version; :mod:`psgsl_pgm.runs._key`) differs is refused, naming each differing
    setting, before anything is created; a second process on the same folder is refused
    (:func:`psgsl_pgm.runs._runner.grid_folder`). Aggregation covers every run stored in ``out/runs``
    (:func:`write_search_outputs`). Returns the top-level summary. ``record`` (keyword-only): every run also
    writes its episode beside it, ``runs/<run>.bag/`` (a ROS 2 bag, MCAP storage) and ``runs/<run>.mcap``
    (Foxglove); needs the ``ros`` extra.

    Parameters
    ----------
    sources : sequence, default ("oven",)
        Source specs: object class names, the world file's source names, or (x, y) positions in m (free points
        of the house).
    policies : sequence of str, default ("tour", "infotaxis")
        Policies among :data:`POLICIES`.
    variants : sequence of str, default ("olfaction", "semantics+rooms")
        Map variants among :data:`psgsl_pgm.experiment.VARIANTS`.
    estimators : sequence of str, default ("infotaxis",)
        Estimators among :data:`psgsl_pgm.experiment.ESTIMATORS`.
    seeds : iterable of int, default range(10)
        The house and episode seeds.
    out : str or os.PathLike, keyword-only
        The grid's folder (created if missing).
    workers : int, default 2, keyword-only
        Worker processes of the local pool.
    config : psgsl_pgm.experiment.ExperimentConfig, optional, keyword-only
        The map's and sensors' settings; default ``ExperimentConfig()``.
    search : SearchConfig, optional, keyword-only
        The closed loop's settings (time budget, found radius, ...); default ``SearchConfig()``.
    progress : bool, default True, keyword-only
        Show a progress bar.
    figures : bool, default True, keyword-only
        Draw the figures when aggregating (:func:`write_search_outputs`).
    grid : sequence of tuple, optional, keyword-only
        Explicit ``(source, policy, variant, estimator, seed)`` runs, in order, in place of the product.
    scheduler : str, optional, keyword-only
        The grid runner's backend: None (a local pool), ``"local"`` (a dask LocalCluster) or a dask scheduler's
        address.
    world : str or os.PathLike, optional, keyword-only
        A world file; default: the embedded house.
    record : bool, default False, keyword-only
        Also record each run's episode as a ROS 2 bag and an MCAP file (needs the ``ros`` extra).

    Returns
    -------
    dict
        The top-level summary, ``{"<source>/<estimator>": {"<policy>/<variant>": summary}}``
        (:func:`write_search_outputs`).

    Raises
    ------
    ValueError
        A policy, variant or estimator is unknown; a list is empty; no run is left (e.g. semantics alone with the
        ``olfaction`` variant only, or a reactive policy without it); a grid entry is invalid; a source class has
        no object in the house or a source position is not a free point; the world file is bad; or ``out`` holds
        runs of another configuration or is in use by another process.
    psgsl_pgm.runs._runner.GridInterrupted
        On Ctrl-C, with every finished run on disk.

    Examples
    --------
    One run (one source, policy, variant, estimator and seed; a 20-s budget) in a temporary folder:

    >>> import tempfile
    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import SearchConfig, run_search_grid
    >>> with tempfile.TemporaryDirectory() as out:
    ...     top = run_search_grid(["oven"], ["greedy"], ["olfaction"], ["infotaxis"], [0], out=out, workers=1,
    ...                           config=ExperimentConfig(warm_up=5.0), search=SearchConfig(time_budget=20.0),
    ...                           progress=False, figures=False)
    >>> list(top), list(top["oven/infotaxis"]), top["oven/infotaxis"]["greedy/olfaction"]["n_runs"]
    (['oven/infotaxis'], ['greedy/olfaction'], 1)
    """
    config = ExperimentConfig() if config is None else config
    search = SearchConfig() if search is None else search
    sources = [parse_source(s) for s in sources]
    for name, values, allowed in (("policies", policies, POLICIES), ("variants", variants, VARIANTS),
                                  ("estimators", estimators, ESTIMATORS)):
        bad = [v for v in values if v not in allowed]
        if bad:
            raise ValueError(f"{name} must be among {allowed}, got {bad}")
    seeds = [int(s) for s in seeds]
    if not (sources and policies and variants and estimators and seeds):
        raise ValueError("need at least one source, policy, variant, estimator and seed")
    if grid is None:  # semantics alone has no olfaction variant, a reactive policy only it: those pairs are left out
        grid = [(so, p, v, e, se) for se, so, p, v, e in itertools.product(seeds, sources, policies, variants,
                                                                           estimators)
                if not (p in SEMANTICS_ALONE and v == "olfaction") and not (p in REACTIVE and v != "olfaction")
                and ESTIMATOR_OF.get(p, e) == e]  # a policy of one estimator's maps runs with that one
        if not grid:
            for p in policies:
                for e in estimators:
                    check_estimator(p, e)  # e.g. pmfs-nav with estimators other than pmfs only
            if set(policies) <= set(REACTIVE):
                raise ValueError(f"policies {list(policies)}: reactive policies run with variant 'olfaction' only; "
                                 f"variants are {list(variants)}")
            raise ValueError(f"policies {list(policies)}: semantics alone needs a semantic variant; variants are "
                             "['olfaction'] only")
    else:
        grid = [(parse_source(so), p, v, e, int(se)) for so, p, v, e, se in grid]
        for _, p, v, e, _ in grid:
            if p not in POLICIES or v not in VARIANTS or e not in ESTIMATORS:
                raise ValueError(f"grid entries must name a policy of {POLICIES}, a variant of {VARIANTS} and an "
                                 f"estimator of {ESTIMATORS}, got {(p, v, e)}")
            check_semantics_alone(p, v, where="grid entries: ")
            check_estimator(p, e, where="grid entries: ")
    world = None if world is None else str(Path(world).resolve())
    world_part = world_key(world)
    world_digest = digest(world_part)
    world_spec = None if world is None else _world(world, world_digest)  # a bad world file fails here
    _check_sources({g[0] for g in grid}, world_spec)
    key = search_key(config, search, world_part)
    from ..runs._runner import GridJob, grid_folder, run_grid

    def write(run, fh) -> None:
        run.config["key"] = key  # what a later call is checked against
        write_search_run(run, fh)

    with grid_folder(out, key, read_key=read_run_key) as out:
        jobs = []
        for source, policy, variant, estimator, seed in grid:
            path = search_run_path(out, source, policy, variant, estimator, seed)
            kwargs = {"config": config, "search": search, "world": world, "world_digest": world_digest}
            if record:
                kwargs["record"] = str(path.with_suffix(""))
            jobs.append(GridJob(path, closed_loop_in_world, (source, seed, policy, variant, estimator), kwargs))
        run_grid(jobs, write=write, scheduler=scheduler, workers=workers, progress=progress,
                 desc="closed-loop runs")
        return write_search_outputs(out, figures=figures, world=world)
