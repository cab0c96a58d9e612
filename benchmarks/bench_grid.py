"""Throughput of the experiment grid: runs per minute on the local pool vs a dask LocalCluster (same runs).

    python benchmarks/bench_grid.py [--runs 8] [--workers 2] [--stops N]

Each backend computes the same grid (oven, infotaxis and pmfs, seeds 0…) into its own temporary directory
through :func:`psgsl_pgm.runs._runner.run_grid`; the wall time covers the grid only (start-up of the pool or
cluster included, aggregation and figures excluded). The arrays of the two backends' run files are compared
bit for bit.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")


def _grid(out, n_runs, stops):
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._driver import experiment_jobs

    seeds = range((n_runs + 1) // 2)
    jobs = experiment_jobs(["oven"], list(seeds), ["infotaxis", "analytic-plume"], out=out, config=ExperimentConfig(stops=stops))
    return jobs[:n_runs]


def _identical(x: bytes, y: bytes) -> bool:
    import io

    import numpy as np

    with np.load(io.BytesIO(x)) as p, np.load(io.BytesIO(y)) as q:
        return p.files == q.files and all(p[k].dtype == q[k].dtype and p[k].tobytes() == q[k].tobytes()
                                          for k in p.files)


def main(argv=None) -> None:
    from psgsl_pgm.runs._runner import run_grid
    from psgsl_pgm.experiment._store import write_run

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=8)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--stops", type=int, default=None, help="cut the tour (default: the whole tour)")
    args = parser.parse_args(argv)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, scheduler in (("local pool", None), ("dask LocalCluster", "local")):
            out = Path(tmp) / name.replace(" ", "-")
            jobs = _grid(out, args.runs, args.stops)
            t0 = time.perf_counter()
            run_grid(jobs, write=write_run, scheduler=scheduler, workers=args.workers)
            wall = time.perf_counter() - t0
            results[name] = (wall, {j.path.name: j.path.read_bytes() for j in jobs})
            print(f"{name:>18}: {len(jobs)} runs in {wall:6.1f} s = {60 * len(jobs) / wall:5.1f} runs/min "
                  f"({args.workers} workers)", flush=True)
        (_, a), (_, b) = results.values()
        same = a.keys() == b.keys() and all(_identical(a[k], b[k]) for k in a)
        print(f"run arrays bit-identical between the backends: {same}")
        print(f"load average at the end: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
