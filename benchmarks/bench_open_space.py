"""Open-space benchmark: infotaxis and space-aware infotaxis on the Loisy & Eloy (2022)
source-tracking POMDP, episodes added in chunks until the relative standard error of the mean is ≤ 2 %.

    python benchmarks/bench_open_space.py [--out open_space.json] [--rel-sem 0.02] [--chunk 500]

Chunk k of a setting uses seed 1000 + k, so the result is reproducible from the number of chunks.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from psgsl_pgm.search import open_space_benchmark

SETTINGS = ((1.0, 1.0), (2.0, 2.0), (3.0, 1.0))
POLICIES = ("infotaxis", "space-aware-infotaxis")


def until(policy, lam, r, *, rel_sem, chunk, max_episodes):
    steps, p_nf, k, t0 = [], [], 0, time.perf_counter()
    while True:
        res = open_space_benchmark(policy, lambda_over_dx=lam, r_dt=r, episodes=chunk, seed=1000 + k)
        steps.append(res["steps"])
        p_nf.append(res["p_not_found"])
        k += 1
        s = np.concatenate(steps)
        cap = 20 * res["n"] ** 2
        ok = s[s < cap]
        mean, sem = ok.mean(), ok.std(ddof=1) / np.sqrt(ok.size)
        if sem / mean <= rel_sem or s.size >= max_episodes:
            return {"policy": policy, "lambda_over_dx": lam, "r_dt": r, "n": res["n"], "episodes": int(s.size),
                    "chunks": k, "mean_steps": float(mean), "sem": float(sem), "rel_sem": float(sem / mean),
                    "median": float(np.median(ok)), "p_not_found": float(np.mean(s >= cap)),
                    "seconds": time.perf_counter() - t0}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="open_space.json")
    ap.add_argument("--rel-sem", type=float, default=0.02)
    ap.add_argument("--chunk", type=int, default=500)
    ap.add_argument("--max-episodes", type=int, default=20000)
    a = ap.parse_args(argv)
    rows = []
    for lam, r in SETTINGS:
        for pol in POLICIES:
            row = until(pol, lam, r, rel_sem=a.rel_sem, chunk=a.chunk, max_episodes=a.max_episodes)
            rows.append(row)
            print(json.dumps(row), flush=True)
            with open(a.out, "w", encoding="utf-8") as fh:
                json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
