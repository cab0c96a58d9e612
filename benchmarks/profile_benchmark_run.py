"""Where the CPU time of a ``psgsl benchmark`` run goes: a per-part wall/CPU breakdown and a cProfile (not a test).

A benchmark run (:func:`psgsl_pgm.search.run_benchmark`) pays for more than its episode. This script runs the
pieces the way the benchmark does, in one process, and times each:

* **preparation** (the parent, once per house): the house generation (:func:`psgsl_pgm.sim.generate_house` and its
  world file), loading the world file, findability (:func:`psgsl_pgm.search._episodes.findable_sources`) and the
  episode draws;
* **runs** (a worker, :func:`psgsl_pgm.search._benchmark.benchmark_episode`): ``--seeds`` episodes in the same
  house, each run by every arm of ``--policies`` × ``--variants`` (the benchmark's arms: the tour with the first
  variant only), in a row, as the worker of a grid takes them (the first pays for what the later ones may find
  cached). Each run's wall and CPU time (``time.process_time``), then its parts, measured
  again under cProfile with a CPU clock: the world's construction and in it the wind solve, the free space (its
  drivable cells), the geodesic costs (Dijkstra from a cell), the far lattice, the cover of the finder cells and
  the findable mask, the camera frames and gas readings of the stops, the estimator update, the posteriors (the
  semantic term, eq. (20), and the fusion), the information gain (φ_G and φ_O) and the planner (the rest of a
  decision). Parts are inclusive (a part's time contains that of the parts listed under it); each is given as
  CPU seconds under the profiler and as its share of the profiled run, applied to the unprofiled CPU time
  (the profiler's overhead falls on Python calls, so shares of Python-heavy parts are upper bounds);
* **the first compile of the kernels**: a short episode in a fresh process with an empty numba cache and again with
  it filled (``--no-compile`` skips it);
* the cProfile's top functions by own time (``--top``), and the whole profile written to ``--pstats``.

The output names the CPU (``lscpu``) and the BLAS kernel (threadpoolctl). The BLAS is limited to one thread, as in
the grid's workers. Run: ``python benchmarks/profile_benchmark_run.py [--house 0] [--seeds 3] [--policies infotaxis]
[--variants semantics+rooms] [--budget 1000] [--world-model ideal] [--top 30] [--pstats run.pstats]
[--no-compile]``, one core: ``taskset -c 0 nice python benchmarks/profile_benchmark_run.py``.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import platform
import pstats
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np  # noqa: F401  (loaded before threadpoolctl looks for numpy's BLAS)

#: the parts of a run: (label, depth, ((file suffix, function name), ...)); a part's time is the cumulative time of
#: the outermost calls of its functions (cProfile's cumulative time counts recursive calls once)
PARTS = (
    ("world file load", 0, (("sim/_worldfile.py", "load_world"),)),
    ("world construction", 0, (("sim/_worldfile.py", "make_world"),)),
    ("wind solve", 1, (("sim/_wind.py", "make_wind"), ("sim/_lbm.py", "cfd_wind"))),
    ("free space (drivable cells)", 0, (("search/_space.py", "__init__"),)),
    ("cover (finder cells)", 0, (("search/_space.py", "cover"),)),
    ("findable mask", 0, (("search/_space.py", "findable"),)),
    ("geodesic costs (Dijkstra)", 0, (("search/_space.py", "distances"),)),
    ("far lattice", 0, (("search/_space.py", "far_lattice"),)),
    ("stops: sensing (drive, readings, frames)", 0, (("experiment/_step.py", "visit"),)),
    ("stops: estimator update", 0, (("experiment/_step.py", "observe"), ("experiment/_step.py", "condition"))),
    ("stops: posteriors", 0, (("experiment/_step.py", "posteriors"),)),
    ("semantic term p(s | z)", 1, (("core/_semantic.py", "semantic_source_probability"),)),
    ("stops: decisions", 0, (("search/_choose.py", "choose"),)),
    ("information gain φ_G", 1, (("search/_policies.py", "olfactory_gain"),
                                 ("search/_policies.py", "_olfactory_bound"))),
    ("information gain φ_O", 1, (("search/_policies.py", "_semantic_gain"), ("search/_space.py", "view_gain"),
                                 ("search/_space.py", "view_bound"))),
    ("candidates", 1, (("search/_space.py", "candidates"),)),
    ("stops: record (metrics, credible region)", 0, (("search/_stepper.py", "_record"),)),
)


def one_blas_thread() -> None:
    """Hold the BLAS to one thread in this process, as in the grid's workers (threadpoolctl; nothing without it)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        return
    threadpool_limits(limits=1, user_api="blas")


def machine() -> str:
    """The CPU's model name (lscpu) and the BLAS libraries with their kernels (threadpoolctl)."""
    cpu = platform.processor() or platform.machine()
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        fields = dict(line.split(":", 1) for line in out.splitlines() if ":" in line)
        cpu = (f"{fields.get('Model name', cpu).strip()} (family {fields.get('CPU family', '?').strip()}, model "
               f"{fields.get('Model', '?').strip()}), {fields.get('CPU(s)', '?').strip()} CPUs, "
               f"avx512f={'avx512f' in fields.get('Flags', '')}")
    except (OSError, subprocess.CalledProcessError):
        pass
    try:
        from threadpoolctl import threadpool_info

        blas = "; ".join(f"{d.get('internal_api')} {d.get('version')} {d.get('architecture')} "
                         f"({d.get('num_threads')} thread(s))"
                         for d in threadpool_info() if d.get("user_api") == "blas")
    except ImportError:
        blas = "threadpoolctl not installed"
    return f"CPU: {cpu}\nBLAS: {blas}"


def _timed(fn, *args, **kw):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0, time.process_time() - c0


def _part_seconds(stats: pstats.Stats) -> dict:
    """Cumulative CPU seconds of each part of :data:`PARTS` in a profile (the outermost calls of its functions)."""
    raw = stats.stats  # {(file, line, name): (cc, nc, tt, ct, callers)}
    out = {}
    for label, _, keys in PARTS:
        funcs = {f for f in raw if any(f[0].replace(os.sep, "/").endswith(s) and f[2] == n for s, n in keys)}
        total = 0.0
        for f in funcs:
            cc, nc, tt, ct, callers = raw[f]
            # the time reached from callers outside the part's own functions (no double count of part in part)
            outside = sum(v[3] for caller, v in callers.items() if caller not in funcs)
            total += outside if callers else ct
        out[label] = total
    return out


def _compile_cost(policy: str, variant: str) -> tuple:
    """(wall s, CPU s of the child) of a 20-s episode in a fresh process with an empty numba cache, then with it
    filled."""
    code = ("import time; t = time.perf_counter(); from psgsl_pgm.search import SearchConfig, run_closed_loop; "
            f"run_closed_loop('oven', 0, {policy!r}, {variant!r}, search=SearchConfig(time_budget=20.0)); "
            "print(time.perf_counter() - t, time.process_time())")
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache, "OPENBLAS_NUM_THREADS": "1"}
        out = []
        for _ in range(2):
            res = subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True, text=True)
            out.append(tuple(float(v) for v in res.stdout.split()[-2:]))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--house", type=int, default=0, help="generated home (dev split seed)")
    ap.add_argument("--seeds", type=int, default=3, help="episodes run in a row in the house")
    ap.add_argument("--policies", nargs="+", default=["infotaxis"])
    ap.add_argument("--variants", nargs="+", default=["semantics+rooms"])
    ap.add_argument("--budget", type=float, default=1000.0, help="time budget per run, s of simulated time")
    ap.add_argument("--world-model", default="ideal")
    ap.add_argument("--top", type=int, default=30)
    ap.add_argument("--pstats", default=None, help="write the runs' profile here (pstats format)")
    ap.add_argument("--no-compile", action="store_true")
    a = ap.parse_args(argv)
    one_blas_thread()
    print(machine())
    from dataclasses import replace

    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.runs._key import digest, world_key
    from psgsl_pgm.search import SearchConfig
    from psgsl_pgm.search._benchmark import benchmark_episode
    from psgsl_pgm.search._episodes import draw_episode, findable_sources
    from psgsl_pgm.sim import generate_house, load_world

    config = ExperimentConfig(world_model=a.world_model)
    search = SearchConfig(time_budget=a.budget)
    with tempfile.TemporaryDirectory() as out:
        out = Path(out)
        gen, w_gen, c_gen = _timed(generate_house, a.house)
        path, w_write, c_write = _timed(gen.write, out / f"h{a.house:05d}", gas="smoke")
        spec, w_load, c_load = _timed(load_world, path)
        found, w_find, c_find = _timed(findable_sources, spec, found_radius=search.found_radius)
        from psgsl_pgm.search._benchmark import benchmark_arms

        arms = benchmark_arms(a.policies, a.variants, "right-ontology")
        episodes, w_draw, c_draw = _timed(lambda: [draw_episode(spec, a.house, s, gases=("smoke",), off_rate=0.1,
                                                                sources=found) for s in range(a.seeds)])
        print(f"\nhouse {a.house}: grid {spec.house().shape}, {gen.n_rooms} rooms, {gen.area:.0f} m²; world model "
              f"{a.world_model}; arms {', '.join(f'{p}/{v}' for p, v in arms)}, budget {a.budget:.0f} s")
        print("preparation (the parent, once per house)            wall s    CPU s")
        for label, w, c in (("house generation", w_gen, c_gen), ("world file written", w_write, c_write),
                            ("world file loaded", w_load, c_load), ("findability", w_find, c_find),
                            (f"{a.seeds} episode draws", w_draw, c_draw)):
            print(f"  {label:<50}{w:7.3f}  {c:7.3f}")
        wdig = digest(world_key(path))

        def job(s, policy, variant):
            ep = episodes[s]
            return benchmark_episode(tuple(ep["xy"]), s, policy, variant, "infotaxis", world=str(path),
                                     world_digest=wdig, config=replace(config, gas=ep["gas"]), search=search,
                                     label={"house": path.parent.name, "condition": "right-ontology", "episode": ep})

        print("\nruns, one after another in this process (as a grid worker takes them)")
        cpus = []
        for s in range(a.seeds):
            for policy, variant in arms:
                run, w, c = _timed(job, s, policy, variant)
                cpus.append(c)
                print(f"  seed {s} {policy}/{variant}: {run.time_to_find:7.1f} s simulated, {run.n_steps:3d} stops, "
                      f"found {run.found!s:5}, declared {run.declared!s:5}: wall {w:6.3f} s, CPU {c:6.3f} s "
                      f"({run.time_to_find / max(c, 1e-9):,.0f}x real time per CPU s)")
        print(f"  CPU per run: median {statistics.median(cpus):.3f} s, first {cpus[0]:.3f} s, "
              f"later median {statistics.median(cpus[1:]) if len(cpus) > 1 else float('nan'):.3f} s")

        prof = cProfile.Profile(time.process_time)
        c0 = time.process_time()
        prof.enable()
        for s in range(a.seeds):
            for policy, variant in arms:
                job(s, policy, variant)
        prof.disable()
        profiled = time.process_time() - c0
        stats = pstats.Stats(prof)
        parts = _part_seconds(stats)
        plain = sum(cpus)
        print(f"\nparts of the same {len(cpus)} runs under cProfile (CPU clock; {profiled:.3f} s profiled, "
              f"{plain:.3f} s without the profiler, run again after the above: caches warm)")
        print(f"  {'part':<46}{'profiled CPU s':>15}{'share':>8}{'≈ CPU s':>10}")
        for label, depth, _ in PARTS:
            t = parts[label]
            print(f"  {'  ' * depth + label:<46}{t:15.3f}{t / profiled:8.1%}{t / profiled * plain:10.3f}")
        if a.pstats:
            stats.dump_stats(a.pstats)
        buf = io.StringIO()
        pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(a.top)
        print(f"\ntop {a.top} functions by own CPU time (profiled):")
        print("\n".join(line for line in buf.getvalue().splitlines()[6:] if line.strip()))
    if not a.no_compile:
        (cold, cold_cpu), (warm, warm_cpu) = _compile_cost(*arms[0])
        print(f"\nfirst compile: a 20-s episode in a fresh process, empty numba cache {cold:.1f} s wall "
              f"({cold_cpu:.1f} s CPU), cache filled {warm:.1f} s ({warm_cpu:.1f} s CPU): "
              f"{cold_cpu - warm_cpu:.1f} s of CPU compiling, paid once per machine (numba's cache=True)")


if __name__ == "__main__":
    main()
