"""The many-house benchmark (``psgsl benchmark``): closed-loop searches in generated homes, or in one world file,
with sources drawn as they occur, under three ontology conditions; a resumable grid on the project's runner.

Layout of ``out``::

    houses/h00000/world.yaml ...        each generated home as a world file (psgsl world check runs on it)
    worlds/<house>__<condition>.yaml    the world of each condition (the robot's ontology differs)
    episodes.json                       every episode's gas and source (psgsl_pgm.search._episodes)
    runs/<house>__<condition>__<policy>__<variant>__<estimator>__seed<s>.npz   one file per finished run
    report.md, summary.json, figures    (psgsl_pgm.search._bench_report)

**Which runs.** For every seed s, house h and condition: every policy × variant, except that the ``tour`` runs
with the first variant only (its path does not depend on the beliefs), ``semantic-modes`` and ``nearest-object``
(semantics alone) only with semantic variants, and the ``olfaction`` variant and the ``tour`` only under
``right-ontology``: neither reads the robot's ontology (the olfactory posterior and the tour's path do not depend on it), so the other conditions
share those runs (the report says so). Jobs are submitted seed by seed, so that an interrupted grid leaves every
house with about the same seeds.

**Keys.** A run depends on its house (the world file's content, checked per run), its episode, both configs and
the package version. The folder's run key (:mod:`psgsl_pgm.runs._key`) holds the configs, the off-ontology rate,
the gases and — for a world file — that world's content: a resumed benchmark with other settings is refused
before anything runs. More houses or seeds extend a folder; fewer report on a part of it.
"""

from __future__ import annotations

import itertools
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import yaml

from .._shared._validate import index, unit_interval
from ..experiment._config import ESTIMATORS, VARIANTS, ExperimentConfig
from ..runs._key import digest, run_key, world_key
from ._episodes import CONDITIONS, check_condition, draw_episode, draw_sources, findable_sources, robot_ontology
from ._grid import closed_loop_in_world
from ._settings import SearchConfig
from ._policies import POLICIES, SEMANTICS_ALONE, check_estimator
from ._reactive import REACTIVE
from ._split import benchmark_sample, check_split
from ._stepper import SEVERAL_ESTIMATORS
from ._store import read_run_key, write_search_run

__all__ = ["BENCHMARK_POLICIES", "BENCHMARK_VARIANTS", "benchmark_arms", "benchmark_episode",
           "check_sources_per_episode", "run_benchmark"]

#: The benchmark's default policies: the four closed-loop baselines and semantics alone.
BENCHMARK_POLICIES = ("tour", "greedy", "infotaxis", "space-aware-infotaxis", "semantic-modes", "nearest-object")
#: The default variants: the olfactory estimator alone, and fused with semantics and the room map.
BENCHMARK_VARIANTS = ("olfaction", "semantics+rooms")


def benchmark_arms(policies, variants, condition: str) -> list:
    """The (policy, variant) pairs run under ``condition`` (module docstring, "Which runs")."""
    out = []
    for p in policies:
        for v in (variants[:1] if p == "tour" else variants):
            if (p in SEMANTICS_ALONE and v == "olfaction") or (p in REACTIVE and v != "olfaction"):
                continue
            if condition != "right-ontology" and (p == "tour" or v == "olfaction"):
                continue
            out.append((p, v))
    return out


def _file_keys(data: dict, wpath: Path) -> dict:
    """The world file's data with every file it names as an absolute path (so a copy works from any folder)."""
    from ..sim._fileio import resolve
    from ..sim._worldfile import _FILE_KEYS

    data = dict(data)
    for key, words in _FILE_KEYS.items():
        v = data.get(key)
        if isinstance(v, str) and v.strip() and v not in words:
            data[key] = str(resolve(wpath, v, key).resolve())
    wind = data.get("wind")
    if isinstance(wind, dict) and "gaden_csv" in wind:
        csv = wind["gaden_csv"]
        wind = dict(wind)
        wind["gaden_csv"] = ([str(resolve(wpath, c, "wind.gaden_csv").resolve()) for c in csv]
                             if isinstance(csv, list) else str(resolve(wpath, csv, "wind.gaden_csv").resolve()))
        data["wind"] = wind
    return data


def _write_text(path: Path, text: str) -> None:
    from ..io._output import write_file_atomically

    write_file_atomically(path, lambda fh: fh.write(text.encode("utf-8")))


def condition_world(world_path: Path, world, condition: str, house: int, folder: Path, label: str) -> Path:
    """The world file of ``condition``: ``world_path`` itself for ``right-ontology``; otherwise a copy in ``folder``
    naming the same files (absolute paths) and the robot's ontology of :func:`robot_ontology`, written beside it."""
    from ..sim._fileio import read_yaml_mapping

    if condition == "right-ontology":
        return world_path
    wpath, data = read_yaml_mapping(world_path)
    data = _file_keys(data, wpath)
    ont = robot_ontology(world.ontology, condition, house=house)
    opath = folder / f"{label}__{condition}__ontology.yaml"
    _write_text(opath, ont.to_yaml())
    data["ontology"] = str(opath.resolve())
    data.pop("room_classes", None)  # the written ontology holds the rooms it keeps
    out = folder / f"{label}__{condition}.yaml"
    _write_text(out, f"# {condition} world of {world_path} (psgsl benchmark)\n" + yaml.safe_dump(data, sort_keys=False))
    return out


def benchmark_episode(source, seed, policy, variant, estimator, *, world, world_digest, config, search, label,
                      gas_type=None, extra_sources=(), extra_gas_types=None):
    """One run of the grid: :func:`closed_loop_in_world`, its config marked with the benchmark's ``label``
    (house, condition, episode) so that the report can group the stored runs, and the run's CPU seconds (measured by
    :func:`closed_loop_in_world`, moved under the label)."""
    told = {} if gas_type is None else {"gas_type": gas_type}  # the true gas of an episode the robot is not told
    if len(extra_sources):  # several sources
        told |= {"extra_sources": [tuple(x) for x in extra_sources]}
        if extra_gas_types is not None:
            told["extra_gas_types"] = list(extra_gas_types)
    run = closed_loop_in_world(source, seed, policy, variant, estimator, world=world, world_digest=world_digest,
                               config=config, search=search, **told)
    run.config["benchmark"] = dict(label, cpu_seconds=run.config.pop("cpu_seconds"))  # for planning; not in the key
    return run


def check_sources_per_episode(value):
    """``sources_per_episode`` checked: an int N in 1–3, a range "lo-hi" or (lo, hi) with 1 <= lo <= hi <= 3
    (a range of one value is that int); ValueError (TypeError) naming the argument otherwise.

    >>> check_sources_per_episode("1-3"), check_sources_per_episode(2), check_sources_per_episode("2-2")
    ((1, 3), 2, 2)
    """
    text = value
    if isinstance(value, str):
        parts = value.strip().split("-")
        try:
            nums = [int(p) for p in parts]
        except ValueError:
            nums = []
        if len(nums) not in (1, 2):
            raise ValueError(f"sources_per_episode must be N or a range lo-hi with 1 <= lo <= hi <= 3, got {text!r}")
        value = nums[0] if len(nums) == 1 else tuple(nums)
    if isinstance(value, (list, tuple)):
        if len(value) != 2 or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in value):
            raise ValueError(f"sources_per_episode must be N or a range (lo, hi) of integers, got {text!r}")
        lo, hi = int(value[0]), int(value[1])
        if not 1 <= lo <= hi <= 3:
            raise ValueError(f"sources_per_episode must be a range with 1 <= lo <= hi <= 3, got {text!r}")
        return lo if lo == hi else (lo, hi)
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"sources_per_episode must be an integer 1-3 or a range, got {text!r}")
    if not 1 <= int(value) <= 3:
        raise ValueError(f"sources_per_episode must be 1, 2 or 3 (or a range lo-hi within 1-3), got {text!r}")
    return int(value)


def _check_names(name: str, values, allowed) -> tuple:
    values = tuple(values)
    if not values:
        raise ValueError(f"{name} must name at least one of {allowed}")
    bad = [v for v in values if v not in allowed]
    if bad:
        raise ValueError(f"{name} must be among {allowed}, got {bad}")
    if len(set(values)) != len(values):
        raise ValueError(f"{name} must be distinct, got {list(values)}")
    return values


def _prepare_houses(out: Path, houses, *, gas: str, options: dict) -> dict:
    """Write every generated home as a world file under ``out/houses``; ``{label: path}``."""
    from ..sim._generate import generate_house

    paths = {}
    for h in houses:
        label = f"h{h:05d}"
        paths[label] = generate_house(h, **options).write(out / "houses" / label, gas=gas)
    return paths


def run_benchmark(*, out, houses: int = 0, seeds: int = 5, world=None, policies=BENCHMARK_POLICIES,
                  variants=BENCHMARK_VARIANTS, conditions=CONDITIONS, estimator: str = "infotaxis",
                  off_rate: float = 0.1, gases=("smoke",), first_house: int | None = None, house_options=None,
                  workers: int = 2, scheduler: str | None = None, config: ExperimentConfig | None = None,
                  search: SearchConfig | None = None, progress: bool = True, figures: bool = True,
                  command: str | None = None, split: str = "dev", gas_unknown: bool = False,
                  sources_per_episode=1) -> dict:
    """Run (or resume) the benchmark and write its report (module docstring).

    Parameters
    ----------
    out : path, keyword-only
        The benchmark's folder.
    houses : int, keyword-only
        Number of generated homes, seeds ``first_house`` … ``first_house + houses − 1`` of
        :func:`psgsl_pgm.sim.generate_house`; 0 with ``world``. With ``split="test"``: the first ``houses`` of the
        test homes (0: all of them).
    seeds : int, keyword-only
        Episodes per house, seeds 0 … seeds − 1; with ``split="test"`` the first ``seeds`` of the test seeds.
    world : path, optional, keyword-only
        A world file (e.g. the lab's house B) instead of generated homes; its ontology is the world's.
    policies, variants, conditions : sequences of str, keyword-only
        Of :data:`POLICIES`, :data:`psgsl_pgm.experiment.VARIANTS`, :data:`CONDITIONS`.
    estimator : str, keyword-only
    off_rate : float, keyword-only
        Probability of an off-ontology source per episode.
    gases : sequence of str, keyword-only
        The gases an episode draws from (uniformly).
    first_house : int, optional, keyword-only
        The first generated home of the development split (default 0); not with ``split="test"``.
    house_options : dict, optional, keyword-only
        ``n_rooms``, ``area``, ``room_types`` of :func:`psgsl_pgm.sim.generate_house` for every home (checked
        before anything is written: an impossible request is a ValueError naming the option).
    workers, scheduler : keyword-only
        The grid runner's backend (:func:`psgsl_pgm.runs._runner.run_grid`).
    config, search : optional, keyword-only
        Physics and estimator settings; closed-loop settings (the budget τ is ``search.time_budget``).
    progress, figures : bool, keyword-only
    command : str, optional, keyword-only
        The command line, quoted in the report.
    split : {"dev", "test"}, keyword-only
        The development or the test homes and seeds (:mod:`psgsl_pgm.search._split`); recorded in the report.
    gas_unknown : bool, keyword-only
        Do not tell the robot the episode's gas (drawn from ``gases``): it carries an electronic nose and infers
        p(γ | ζ_1:t) (``config.gas = "unknown"``, :func:`psgsl_pgm.search.run_closed_loop`); the report's arms
        gain ``gas_identified`` and ``time_to_gas``.
    sources_per_episode : int or (int, int), keyword-only
        Sources emitting at once in each episode: N in 1–3, or a range (lo, hi) from which each episode draws N
        uniformly (:func:`psgsl_pgm.search._episodes.draw_sources`). With more than one the robot declares
        sources one by one (``search.source_count_prior``, uniform on {1, 2, 3} unless given) and the report's
        arms gain ``several_sources``: per-source and "all found" success and RMST, and the false declarations.
        1 (the default): the one-source benchmark.

    Returns
    -------
    dict
        The report's summary (:func:`psgsl_pgm.search._bench_report.write_report`).

    Raises
    ------
    TypeError
        ``config`` or ``search`` is of the wrong type, or ``gas_unknown`` is not a bool.
    ValueError
        An unknown policy, variant, condition or estimator; ``conditions`` without ``"right-ontology"``; no arm left
        (semantics alone with ``olfaction`` only, a reactive policy without it); ``houses`` and ``world`` together,
        or neither; bad ``house_options`` (naming the option); ``gases`` not of the ontology; a bad
        ``sources_per_episode``; or ``out`` holds another configuration or is in use.

    Examples
    --------
    Even one episode of one arm takes about a second (the world's houses are prepared and the report written), so
    the benchmark is run in ``docs/guide/benchmark.md``. Its settings are checked before anything is written:

    >>> from psgsl_pgm.search import run_benchmark
    >>> try:
    ...     run_benchmark(out="never-created", houses=1, conditions=("no-rooms",))
    ... except ValueError as err:
    ...     print(str(err).startswith("conditions must include 'right-ontology'"))
    True
    """
    from ..runs._runner import GridJob, grid_folder, run_grid
    from ..sim._generated_ontology import GENERATOR_REFERENCE_SEEDS
    from ._bench_report import write_report

    config = ExperimentConfig() if config is None else config
    search = SearchConfig() if search is None else search
    if not isinstance(config, ExperimentConfig):
        raise TypeError(f"config must be an ExperimentConfig, got {type(config).__name__}")
    if not isinstance(search, SearchConfig):
        raise TypeError(f"search must be a SearchConfig, got {type(search).__name__}")
    policies = _check_names("policies", policies, POLICIES)
    variants = _check_names("variants", variants, VARIANTS)
    conditions = tuple(check_condition(c) for c in conditions)
    _check_names("conditions", conditions, CONDITIONS)
    if "right-ontology" not in conditions:
        raise ValueError(f"conditions must include 'right-ontology' (the other conditions share its olfaction and "
                         f"tour runs and are compared with it), got {list(conditions)}")
    if set(policies) <= set(SEMANTICS_ALONE) and variants == ("olfaction",):
        raise ValueError(f"policies {list(policies)}: semantics alone needs a semantic variant; variants are "
                         "['olfaction'] only")
    if set(policies) <= set(REACTIVE) and "olfaction" not in variants:
        raise ValueError(f"policies {list(policies)}: reactive policies run with variant 'olfaction' only; variants "
                         f"are {list(variants)}")
    if estimator not in ESTIMATORS:
        raise ValueError(f"estimator must be one of {ESTIMATORS}, got {estimator!r}")
    for p in policies:
        check_estimator(p, estimator)
    off_rate = unit_interval(off_rate, "off_rate")
    n_seeds = index(seeds, "seeds", minimum=1)
    n_houses = index(houses, "houses")
    if first_house is not None:
        first_house = index(first_house, "first_house")
    split = check_split(split)
    if world is not None and n_houses:
        raise ValueError(f"give houses or a world file, not both (houses={n_houses}, world={world})")
    house_range, seed_ids = benchmark_sample(split, houses=n_houses, seeds=n_seeds, first_house=first_house,
                                             world=world is not None)
    seed_ids = list(seed_ids)
    gases = tuple(gases)
    options = dict(house_options or {})
    unknown = sorted(set(options) - {"n_rooms", "area", "room_types"})
    if unknown:
        raise ValueError(f"house_options may hold n_rooms, area and room_types, got {unknown}")
    if world is None:
        from ..sim._generate import check_request

        n, a, t = check_request(house_range.start, options.get("n_rooms"), options.get("area"),
                                 options.get("room_types"))
        options = {k: v for k, v in (("n_rooms", n), ("area", a), ("room_types", t)) if v is not None}
        if len(house_range) < 1:
            raise ValueError("houses must be >= 1 (or give a world file)")
        house_ids = list(house_range)
        clash = sorted(set(house_ids) & set(GENERATOR_REFERENCE_SEEDS))
        if clash:
            raise ValueError(f"houses must not include the generator's reference seeds (they give the ontology's "
                             f"p(o | room)), got {clash[:3]}{'…' if len(clash) > 3 else ''}")
        world_part = {"world.generator": "psgsl_pgm.sim.generate_house"} | {
            f"world.generator.{k}": (list(v) if k == "room_types" else v) for k, v in options.items()}
    else:
        if options:
            raise ValueError(f"house_options shape generated homes; they do not apply to a world file, got {options}")
        world = Path(world).resolve()
        world_part = world_key(world)
        house_ids = [0]
    from ..sim import generated_ontology, load_world

    base_ontology = generated_ontology() if world is None else load_world(world).ontology
    bad = [g for g in gases if g not in base_ontology.gases]
    if not gases or bad:
        raise ValueError(f"gases must be gases of the ontology {list(base_ontology.gases)}, got {list(gases)}")
    if not isinstance(gas_unknown, (bool, np.bool_)):
        raise TypeError(f"gas_unknown must be True or False, got {gas_unknown!r}")
    if gas_unknown:
        config = replace(config, gas="unknown")  # the episode's gas goes to the world only (gas_type below)
    count = check_sources_per_episode(sources_per_episode)
    several = count != 1
    if several and search.source_count_prior is None:  # the robot expects 1-3 sources, uniformly
        search = replace(search, source_count_prior=(1 / 3, 1 / 3, 1 / 3))
    if several and estimator not in SEVERAL_ESTIMATORS:
        raise ValueError(f"estimator must be one of {SEVERAL_ESTIMATORS} with several sources per episode, got "
                         f"{estimator!r}")
    key = run_key("benchmark", world_part, experiment=config, search=search,
                  benchmark={"off_rate": off_rate, "gases": list(gases), "estimator": estimator}
                  | ({"sources_per_episode": list(count) if isinstance(count, tuple) else count} if several else {}))

    def write(run, fh) -> None:
        run.config["key"] = key
        write_search_run(run, fh)

    with grid_folder(out, key, read_key=read_run_key) as out:
        (out / "worlds").mkdir(exist_ok=True)
        if world is None:
            paths = _prepare_houses(out, house_ids, gas=gases[0], options=options)
        else:
            paths = {"world": world}
        labels = list(paths)
        specs = {lab: load_world(p) for lab, p in paths.items()}
        episodes, cond_paths = {}, {}
        for h, lab in zip(house_ids, labels):
            spec = specs[lab]
            found = findable_sources(spec, found_radius=search.found_radius)
            for s in seed_ids:
                episodes[f"{lab}/{s}"] = (draw_sources(spec, h, s, count=count, gases=gases, off_rate=off_rate,
                                                       sources=found) if several else
                                          draw_episode(spec, h, s, gases=gases, off_rate=off_rate, sources=found))
            for c in conditions:
                cond_paths[lab, c] = condition_world(paths[lab], spec, c, h, out / "worlds", lab)
        _write_text(out / "episodes.json", json.dumps(episodes, indent=1, sort_keys=True) + "\n")
        digests = {k: digest(world_key(p)) for k, p in cond_paths.items()}
        jobs = []
        for s, lab, c in itertools.product(seed_ids, labels, conditions):
            ep = episodes[f"{lab}/{s}"]
            cfg = config if gas_unknown else replace(config, gas=ep["gas"])
            told = {"gas_type": ep["gas"]} if gas_unknown else {}
            if ep.get("extra"):  # several sources (the robot told the gas is told the first source's)
                told |= {"extra_sources": [tuple(x["xy"]) for x in ep["extra"]]}
                if gas_unknown:
                    told["extra_gas_types"] = [x["gas"] for x in ep["extra"]]
            for p, v in benchmark_arms(policies, variants, c):
                name = f"{lab}__{c}__{p}__{v}__{estimator}__seed{s}.npz"
                jobs.append(GridJob(out / "runs" / name, benchmark_episode, (tuple(ep["xy"]), s, p, v, estimator),
                                    {"world": str(cond_paths[lab, c]), "world_digest": digests[lab, c],
                                     "config": cfg, "search": search, **told,
                                     "label": {"house": lab, "condition": c, "episode": ep}}))
        run_grid(jobs, write=write, scheduler=scheduler, workers=workers, progress=progress,
                 desc="benchmark runs")
        settings = {"split": split, "houses": labels, "seeds": seed_ids, "policies": list(policies),
                    "variants": list(variants), "conditions": list(conditions), "estimator": estimator,
                    "off_rate": off_rate, "gases": list(gases), "budget": search.time_budget,
                    "world": None if world is None else str(world), "command": command}
        if several:
            settings["sources_per_episode"] = list(count) if isinstance(count, tuple) else count
        return write_report(out, settings, figures=figures)
