"""The field's estimators in the closed loop: CPU per stop of ``analytic-plume`` and ``pmfs`` (not a test).

Runs the same seeded episodes several times in one process and reports the median CPU time
(``time.process_time``) per run and per stop, with a digest of each run (so that a change of speed can be checked
to leave the episodes unchanged: the digests must not move):

* generated home 0 of the dev split in the realistic world (``--world-model realistic``: CFD wind, MOX sensor,
  occluding camera, pose error), its first episode, ``infotaxis/olfaction`` with the estimator
  ``analytic-plume`` and with ``pmfs``;
* the embedded house, source ``oven``, seed 0: ``analytic-plume`` under ``infotaxis`` and ``pmfs`` under
  ``pmfs-nav`` (PMFS's own navigation).

Each case is run once first with a 20-s budget (numba kernels loaded, the house's CFD wind cached). The BLAS is
limited to one thread, as in the grid's workers. The output names the CPU (``lscpu``) and the BLAS kernel
(threadpoolctl). Run: ``taskset -c 0 python benchmarks/bench_estimators.py [--budget 400] [--repeats 3]``
(about 90 s of CPU with the defaults, the house's first CFD wind solve aside).
"""

from __future__ import annotations

import argparse
import hashlib
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from profile_benchmark_run import machine, one_blas_thread  # noqa: E402


def run_digest(run) -> str:
    """SHA-256 (first 16 hex digits) of what the robot did and ended with."""
    h = hashlib.sha256()
    for name in ("time", "position", "heading", "hit", "path_length", "map_error", "region_area", "region_hit",
                 "hpd_level", "path", "final_posterior"):
        a = np.ascontiguousarray(getattr(run, name))
        h.update(str((name, a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    h.update(repr((run.found, run.declared, run.time_to_declare)).encode())
    return h.hexdigest()[:16]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--budget", type=float, default=400.0, help="time budget per run, s of simulated time "
                    "(the embedded house: three quarters of it)")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args(argv)
    one_blas_thread()
    print(machine())
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.runs._key import digest, world_key
    from psgsl_pgm.search import SearchConfig, run_closed_loop
    from psgsl_pgm.search._benchmark import benchmark_episode
    from psgsl_pgm.search._episodes import draw_episode, findable_sources
    from psgsl_pgm.sim import generate_house, load_world

    with tempfile.TemporaryDirectory() as out:
        path = generate_house(0).write(Path(out) / "h00000", gas="smoke")
        spec = load_world(path)
        search = SearchConfig()
        ep = draw_episode(spec, 0, 0, gases=("smoke",), off_rate=0.1,
                          sources=findable_sources(spec, found_radius=search.found_radius))
        wdig = digest(world_key(path))
        config = ExperimentConfig(world_model="realistic")

        def home(estimator, policy, budget):
            return benchmark_episode(tuple(ep["xy"]), 0, policy, "olfaction", estimator, world=str(path),
                                     world_digest=wdig, config=replace(config, gas=ep["gas"]),
                                     search=SearchConfig(time_budget=budget),
                                     label={"house": path.parent.name, "condition": "right-ontology", "episode": ep})

        def house(estimator, policy, budget):
            return run_closed_loop("oven", 0, policy, "olfaction", estimator, search=SearchConfig(time_budget=budget))

        cases = (("generated home 0, realistic", home, "analytic-plume", "infotaxis", a.budget),
                 ("generated home 0, realistic", home, "pmfs", "infotaxis", a.budget),
                 ("embedded house", house, "analytic-plume", "infotaxis", 0.75 * a.budget),
                 ("embedded house", house, "pmfs", "pmfs-nav", 0.75 * a.budget))
        print(f"\n{'world':29s}{'estimator':16s}{'policy':11s}{'budget':>7s}{'stops':>7s}{'CPU/run':>9s}"
              f"{'CPU/stop':>10s}  runs' CPU s, digest")
        for where, fn, estimator, policy, budget in cases:
            fn(estimator, policy, 20.0)  # warm
            cpus, digests = [], set()
            for _ in range(a.repeats):
                t0 = time.process_time()
                run = fn(estimator, policy, budget)
                cpus.append(time.process_time() - t0)
                digests.add(run_digest(run))
            if len(digests) != 1:
                raise RuntimeError(f"{where} {estimator}: the same seeded run gave different results {digests}")
            med = statistics.median(cpus)
            print(f"{where:29s}{estimator:16s}{policy:11s}{budget:6.0f}s{run.n_steps:7d}{med:8.2f}s"
                  f"{1e3 * med / run.n_steps:8.0f}ms  {', '.join(f'{c:.2f}' for c in cpus)}, {digests.pop()}",
                  flush=True)


if __name__ == "__main__":
    main()
