"""Closed-loop search speed, as ratios to one semantic-term evaluation measured in the same
process (not a test).

* one decision: ``choose("infotaxis", ...)`` for ``semantics+rooms`` on the embedded house — φ_G (one I(S; hit)
  per candidate position, under the fused posterior) + φ_O (semantic_information_gain over the map, summed
  over the field of view of every candidate pose) + P_f (the detection model) over every candidate pose of
  the default :class:`SearchConfig` (the 0.5-m lattice and the finder cells of :meth:`FreeSpace.cover` within
  the 2-m horizon, the 1-m lattice over the rest of the free space) — median over repeats with warm caches
  (views, Green's rows and found regions depend on the geometry and the run only), and the first (cold) decision; the same for the 2-m horizon alone. The
  target is ≤ 20 ms per decision with warm caches;
* one semantic-term evaluation p(s | z) on the same map (eq. (20)): the unit of the ratio;
* one 1000-s house episode (``infotaxis/semantics+rooms``, seed 0, never found: found_radius = 1 mm): its real-time
  factor (1000 s of simulated time / wall time, best and median of ``--episodes`` runs of the same seeded
  episode on the prepared geometry), and the split of one run into gas simulation (the filament steps while
  driving and turning), gas readings (the sensor windows: their filament steps and concentration sums), camera
  frames, belief updates (p(s | g) and the class-belief map), posteriors (the variant's p(s | g, z) at each
  stop), decisions (φ_G + φ_O over the candidates) and the rest (shares of the wall time);
* with ``--world-model`` (e.g. ``realistic``), the episode rows in that world (:class:`psgsl_pgm.sim.WorldModel`)
  on the embedded house, its CFD wind solved and cached before the timed runs (each run still loads it);
* with ``--house large``, the episode rows in a large generated home instead (:func:`psgsl_pgm.sim.generate_house`
  seed 101, 190 m², 136 × 140 cells; source the microwave; a home of the many-house benchmark's kind and size,
  not one of the generator's reference seeds): the same never-found 1000-s ``infotaxis/semantics+rooms``
  episode, and the ``tour`` policy's, each with its split;
* the first-call cost: a short episode in a fresh process with an empty numba cache (compiling every kernel
  it calls) and again with the cache filled (loading them);
* space-aware infotaxis in large generated homes (``--homes 101,102,103``, ``--home-area`` m², of
  :func:`psgsl_pgm.sim.generate_house`, the homes of ``psgsl benchmark``): per home, one decision for
  ``semantics+rooms`` after the first stop with warm caches (best of ``--repeats``) and cold (a fresh
  :class:`FreeSpace` and run cache: Green's rows, geodesic distances and views all computed; best of 3), and the
  decisions of a seeded ``--home-budget``-s episode (never found; the first in its home: no views kept from
  another run): their mean and total, the share of the decisions in the cost of a benchmark episode. The same for the embedded house.

Every episode row also gives the process CPU time (best of the runs), the measure that stays meaningful on a
shared machine. One core: run it as ``taskset -c 0 python benchmarks/bench_search.py``; the BLAS is limited to
one thread here (threadpoolctl), as in the grid's workers. Run: ``python benchmarks/bench_search.py
[--repeats 20] [--episodes 5] [--house {embedded,large}] [--no-episode] [--no-compile] [--homes 101,102,103]
[--home-area 190] [--home-budget 300] [--only-homes] [--world-model realistic]`` on an otherwise idle core (``--homes ''`` skips the homes).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def _median_ms(fn, repeats):
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def _episode_rows(args, kw, n_runs, unit):
    """Print the real-time factor of one never-found episode (best and median wall time, best CPU time over
    ``n_runs``) and the split of one more run into its parts."""
    from psgsl_pgm.experiment._step import VariantPosteriors
    from psgsl_pgm.search import _stepper, run_closed_loop
    from psgsl_pgm.sim import World, _filaments

    walls, cpus = [], []
    for _ in range(max(1, n_runs)):
        t0, c0 = time.perf_counter(), time.process_time()
        run = run_closed_loop(*args, **kw)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    best, median, cpu = min(walls), statistics.median(walls), min(cpus)
    print(f"one {run.time_to_find:.0f}-s {args[2]}/{args[3]} episode ({run.n_steps} stops), {len(walls)} runs: "
          f"best {best:.3f} s ({run.time_to_find / best:,.0f}x real time), median {median:.3f} s "
          f"({run.time_to_find / median:,.0f}x real time), best CPU {cpu:.3f} s ({run.time_to_find / cpu:,.0f}x), "
          f"median CPU {statistics.median(cpus):.3f} s ({run.time_to_find / statistics.median(cpus):,.0f}x); "
          f"{best / unit * 1e3:,.0f} semantic terms")
    cold = []
    for _ in range(max(1, n_runs)):  # the first run of a house in a process: its per-house caches empty
        _clear_house_caches()
        c0 = time.process_time()
        run_closed_loop(*args, **kw)
        cold.append(time.process_time() - c0)
    print(f"  the same with the per-house caches emptied before each run (the first run of a house in a worker; "
          f"the repeated runs above also share the plume model of their first wind reading, as the arms of one "
          f"episode do): "
          f"median CPU {statistics.median(cold):.3f} s ({run.time_to_find / statistics.median(cold):,.0f}x)")
    # the episode's parts (none calls another), timed by wrapping them; the rest is the loop itself,
    # credible regions, metrics, the "not found" update, the world's construction
    parts = (("gas simulation", _filaments.FilamentModel, "step"),
             ("gas readings", _filaments.FilamentModel, "sample"),
             ("camera frames", World, "camera_frame"),
             ("belief updates", VariantPosteriors, "observe"),
             ("posteriors", VariantPosteriors, "posteriors"),
             ("decisions", _stepper, "choose"))
    spent = {label: 0.0 for label, _, _ in parts}
    saved = [(owner, name, getattr(owner, name)) for _, owner, name in parts]

    def timed(label, fn):
        def wrapper(*args, **kw):
            t = time.perf_counter()
            try:
                return fn(*args, **kw)
            finally:
                spent[label] += time.perf_counter() - t
        return wrapper

    for (label, owner, name), (_, _, fn) in zip(parts, saved):
        setattr(owner, name, timed(label, fn))
    try:
        t0 = time.perf_counter()
        run_closed_loop(*args, **kw)
        wall = time.perf_counter() - t0
    finally:
        for owner, name, fn in saved:
            setattr(owner, name, fn)
    split = ", ".join(f"{label} {t / wall:.0%}" for label, t in spent.items())
    print(f"  split of one run ({wall:.3f} s): {split}, the rest {1 - sum(spent.values()) / wall:.0%}")


def _clear_house_caches():
    """Empty what a process keeps per house content (the shared free spaces, views, detection models, tours,
    potential flows, the plume models of a first wind reading, the embedded world and houses); a prepared
    ``space`` passed to a run keeps its own."""
    from psgsl_pgm.experiment import _step, _tour
    from psgsl_pgm.search import _detection, _space
    from psgsl_pgm.sim import _house, _wind, _worldfile

    for cache in (_space._SHARED_SPACES, _space._SHARED_VIEWS, _detection._SHARED_MODELS, _tour._SHARED_TOURS,
                  _wind._UNSCALED_FLOWS, _worldfile._DEFAULT_WORLDS, _step._FIRST_PLUMES):
        cache.clear()
    _house._default_house.cache_clear()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--episodes", type=int, default=5)
    ap.add_argument("--house", choices=("embedded", "large"), default="embedded",
                    help="the episode rows' home: the embedded house or a large generated one")
    ap.add_argument("--no-episode", action="store_true")
    ap.add_argument("--no-compile", action="store_true")
    ap.add_argument("--homes", default="101,102,103", help="generated homes (seeds, comma-separated; '' for none)")
    ap.add_argument("--home-area", type=float, default=190.0)
    ap.add_argument("--home-budget", type=float, default=300.0)
    ap.add_argument("--only-homes", action="store_true", help="skip everything but the homes' space-aware lines")
    ap.add_argument("--world-model", default=None,
                    help="the episode rows in this world model (psgsl_pgm.sim.WorldModel, e.g. realistic; its CFD "
                    "wind solved and cached before the timed runs)")
    a = ap.parse_args(argv)
    try:
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=1, user_api="blas")
    except ImportError:
        print("threadpoolctl not installed: the BLAS may use several threads")

    if a.only_homes:
        _space_aware_homes(a)
        return
    from psgsl_pgm import semantic_source_probability
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors, visit
    from psgsl_pgm.search import DetectionModel, FreeSpace, SearchConfig, Situation, choose
    from psgsl_pgm.sim import make_world

    config = ExperimentConfig()
    world = make_world(seed=0, source="oven", warm_up=config.warm_up)
    space = FreeSpace(world.house, world.camera)
    beliefs = VariantPosteriors(world, "infotaxis", config)
    cell = space.snap((3.0, 6.0))
    stop = space.position(cell)
    reading, wind, frames = visit(world, stop, (0.0, np.pi / 2, np.pi, 1.5 * np.pi), config)
    beliefs.observe(stop, reading, wind, frames)
    post = beliefs.posteriors(("semantics+rooms",))[0]
    defaults = SearchConfig()
    detection = DetectionModel.from_house(world.house, defaults.found_radius)
    space.cover(detection)  # the finder cells, as the closed loop does before its first decision
    sit = Situation(post, beliefs, "semantics+rooms", space, cell, 0.0, config.speed, config.turn_time,
                    world.gas_sensor.window, defaults.horizon, defaults.found_radius, {}, defaults.score, detection,
                    defaults.far_spacing)
    near = Situation(**{**sit.__dict__, "far_spacing": None})
    n_near = len(space.candidates(cell, defaults.horizon)[0])
    n_cand = len(space.candidates(cell, defaults.horizon, defaults.far_spacing)[0])
    t0 = time.perf_counter()
    choose("infotaxis", sit)
    cold = 1e3 * (time.perf_counter() - t0)
    decision = _median_ms(lambda: choose("infotaxis", sit), a.repeats)
    sap = _median_ms(lambda: choose("space-aware-infotaxis", sit), a.repeats)
    decision_near = _median_ms(lambda: choose("infotaxis", near), a.repeats)
    sap_near = _median_ms(lambda: choose("space-aware-infotaxis", near), a.repeats)
    m = beliefs.maps["semantics+rooms"]
    unit = _median_ms(lambda: semantic_source_probability(m.probs, beliefs.likelihood, beliefs.class_prior), a.repeats)
    print(f"house grid {world.house.shape}, {n_cand} candidate positions ({n_near} within the horizon) × "
          f"{len(space.headings)} headings")
    print(f"one semantic term p(s | z):              {unit:8.2f} ms (median)")
    print(f"one infotaxis decision (φ_G + φ_O), warm: {decision:8.2f} ms = {decision / unit:6.1f} semantic terms")
    print(f"one space-aware decision, warm:          {sap:8.2f} ms = {sap / unit:6.1f} semantic terms")
    print(f"first decision (views computed), cold:   {cold:8.2f} ms = {cold / unit:6.1f} semantic terms")
    print(f"within the horizon only, warm: infotaxis {decision_near:.2f} ms, space-aware {sap_near:.2f} ms")
    if not a.no_episode:
        never = SearchConfig(found_radius=1e-3)
        if a.house == "embedded" and a.world_model is not None:
            from psgsl_pgm.sim import default_world

            model_config = ExperimentConfig(world_model=a.world_model)
            t0 = time.perf_counter()
            model_world = default_world().make_world(0, "oven", warm_up=config.warm_up, model=a.world_model)
            print(f"world model {model_config.world_model}: world built in {time.perf_counter() - t0:.1f} s (the CFD "
                  "wind solved or loaded from its cache)")
            episodes = ((("oven", 0, "infotaxis", "semantics+rooms"),
                         {"search": never, "space": FreeSpace(model_world.house, model_world.camera),
                          "config": model_config}),)
        elif a.house == "embedded":
            episodes = ((("oven", 0, "infotaxis", "semantics+rooms"), {"search": never, "space": space}),)
        else:
            from psgsl_pgm.sim import generate_house

            spec = generate_house(101, area=190.0).world()
            big = spec.make_world(0, "microwave", warm_up=config.warm_up)
            big_space = FreeSpace(big.house, big.camera)
            print(f"large generated home: grid {big.house.shape}, {int(big.house.grid.free.sum())} free cells")
            kw = {"search": never, "space": big_space, "world_spec": spec}
            episodes = ((("microwave", 0, "infotaxis", "semantics+rooms"), kw),
                        (("microwave", 0, "tour", "semantics+rooms"), kw))
        for args, kw in episodes:
            _episode_rows(args, kw, a.episodes, unit)
    if not a.no_compile:
        code = ("import time; t = time.perf_counter(); from psgsl_pgm.search import SearchConfig, run_closed_loop; "
                "run_closed_loop('oven', 0, 'infotaxis', 'semantics+rooms', search=SearchConfig(time_budget=20.0)); "
                "print(time.perf_counter() - t)")
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache, "OPENBLAS_NUM_THREADS": "1"}
            cold, warm = (float(subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True,
                                               text=True).stdout.split()[-1]) for _ in range(2))
        print(f"first call, a 20-s episode in a fresh process: {cold:.1f} s with an empty numba cache (compiling), "
              f"{warm:.1f} s with it filled: {cold - warm:.1f} s of compilation")
    _space_aware_homes(a)


def _space_aware_homes(a):
    """Space-aware infotaxis decisions in the embedded house and in large generated homes (module docstring)."""
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors, visit
    from psgsl_pgm.search import DetectionModel, FreeSpace, SearchConfig, Situation, _space, _stepper, run_closed_loop
    from psgsl_pgm.search._choose import choose
    from psgsl_pgm.sim import default_world
    from psgsl_pgm.sim._generate import generate_house

    config, defaults = ExperimentConfig(), SearchConfig()
    homes = [int(h) for h in a.homes.split(",") if h.strip()]
    for home in [None] + homes:
        if home is None:
            spec, source, name = default_world(), "oven", "embedded house"
        else:
            g = generate_house(home, area=a.home_area)
            spec = g.world()
            objects = list(g.house.objects)
            source = tuple(float(v) for v in objects[len(objects) // 2].center)  # a fixed object of the home
            name = f"home {home} ({g.area:.0f} m², {g.n_rooms} rooms)"
        world = spec.make_world(0, source, warm_up=config.warm_up)

        def situation(space, cache):
            beliefs = VariantPosteriors(world, "infotaxis", config, setting=spec, variants=("semantics+rooms",))
            cell = space.snap(spec.start_for(world.house))
            stop = space.position(cell)
            reading, wind, frames = visit(world, stop, (0.0, np.pi / 2, np.pi, 1.5 * np.pi), config)
            beliefs.observe(stop, reading, wind, frames)
            post = beliefs.posteriors(("semantics+rooms",))[0]
            detection = DetectionModel.from_house(world.house, defaults.found_radius)
            space.cover(detection)  # the finder cells, as the closed loop does before its first decision
            return Situation(post, beliefs, "semantics+rooms", space, cell, 0.0, config.speed, config.turn_time,
                             world.gas_sensor.window, defaults.horizon, defaults.found_radius, cache, defaults.score,
                             detection, defaults.far_spacing)

        colds = []
        for _ in range(3):  # cold: a fresh geometry (Dijkstra, views) and run cache (Green's rows), best of 3
            _space._SHARED_VIEWS.clear()  # the views a process keeps per map
            _space._SHARED_SPACES.clear()
            sit = situation(FreeSpace(world.house, world.camera), {})
            t0 = time.perf_counter()
            choose("space-aware-infotaxis", sit)
            colds.append(1e3 * (time.perf_counter() - t0))
        n_cand = len(sit.space.candidates(sit.cell, sit.horizon, sit.far_spacing)[0])
        warm = []
        for _ in range(max(1, a.repeats)):
            t0 = time.perf_counter()
            choose("space-aware-infotaxis", sit)
            warm.append(1e3 * (time.perf_counter() - t0))
        spent = []

        def timed(policy, s):
            t0 = time.perf_counter()
            try:
                return choose(policy, s)
            finally:
                spent.append(time.perf_counter() - t0)

        saved = _stepper.choose
        _stepper.choose = timed
        _space._SHARED_VIEWS.clear()  # the first episode in this home
        _space._SHARED_SPACES.clear()
        try:
            t0 = time.perf_counter()
            run_closed_loop(source, 0, "space-aware-infotaxis", "semantics+rooms",
                            world_spec=None if home is None else spec,
                            search=SearchConfig(found_radius=1e-3, time_budget=a.home_budget))
            wall = time.perf_counter() - t0
        finally:
            _stepper.choose = saved
        print(f"space-aware, {name}, grid {world.house.shape}, {n_cand} candidate positions: decision warm "
              f"{min(warm):.2f} ms (best of {len(warm)}), cold {min(colds):.0f} ms (best of 3); a {a.home_budget:.0f}-s "
              f"episode: {len(spent)} decisions, mean {1e3 * np.mean(spent):.1f} ms, {sum(spent):.2f} s of its "
              f"{wall:.2f} s ({sum(spent) / wall:.0%})")


if __name__ == "__main__":
    main()
