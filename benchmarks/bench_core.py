"""Core performance as ratios against baselines measured in the same process (not a test).

* closed form + fusion on n = 1e6 cells × k = 80 classes vs the bare NumPy lower bound
  ``class_probs.reshape(-1, k) @ w`` (a memory-bound GEMV), float64 and float32, validation on (default)
  and off;
* semantic_information_gain at n = 1e6 vs the closed form, and at n = 1e4 vs a naive per-cell
  recomputation (O(n² k));
* peak extra memory (tracemalloc, NumPy allocations) relative to the input array.

Run: ``python benchmarks/bench_core.py [--cells 1000000] [--classes 80]``. Take the best of several repeats,
on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np

from psgsl_pgm import fuse, semantic_information_gain, semantic_source_probability


def best_of(fn, repeats):
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def peak_bytes(fn):
    tracemalloc.start()
    tracemalloc.reset_peak()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def naive_gain(q, lik, prior, cells):
    """I(S; O_c) for the first ``cells`` cells by rebuilding the posterior for every outcome: O(n k) each."""
    rho = lik / prior
    u = q @ rho
    out = np.empty(cells)
    for c in range(cells):
        h = []
        for i in range(q.shape[1]):
            new = u.copy()
            new[c] = rho[i]
            p = new / new.sum()
            h.append(-(p[p > 0] * np.log(p[p > 0])).sum())
        p = u / u.sum()
        out[c] = -(p * np.log(p)).sum() - q[c] @ np.array(h)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=1_000_000)
    ap.add_argument("--classes", type=int, default=80)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    n, k = args.cells, args.classes
    rng = np.random.default_rng(0)
    lik = rng.dirichlet(np.ones(k))
    prior = rng.dirichlet(np.ones(k) * 5)
    olf64 = rng.dirichlet(np.ones(n))
    print(f"n = {n:,} cells, k = {k} classes; best of {args.repeats}")
    for dtype in (np.float64, np.float32):
        q = rng.dirichlet(np.ones(k) * 0.5, size=n).astype(dtype)
        w = (lik / prior).astype(dtype)
        olf = olf64.astype(dtype)
        t_gemv = best_of(lambda: q.reshape(-1, k) @ w, args.repeats)
        t_cf = best_of(lambda: fuse(olf, semantic_source_probability(q, lik, prior)), args.repeats)
        t_cf_nv = best_of(lambda: fuse(olf, semantic_source_probability(q, lik, prior, validate=False)), args.repeats)
        print(f"[{np.dtype(dtype).name}] GEMV bound {t_gemv * 1e3:7.1f} ms | closed form + fusion "
              f"{t_cf * 1e3:7.1f} ms = {t_cf / t_gemv:4.2f}× (validated), {t_cf_nv / t_gemv:4.2f}× (validate=False)")
        if dtype == np.float64:
            t_ig = best_of(lambda: semantic_information_gain(q, lik, prior, olfactory=olf), max(2, args.repeats // 3))
            t_ig_x = best_of(lambda: semantic_information_gain(q, lik, prior, olfactory=olf, predictive="exact"),
                             max(2, args.repeats // 3))
            print(f"[{np.dtype(dtype).name}] information gain: paper {t_ig * 1e3:7.1f} ms = {t_ig / t_cf:4.2f}× the "
                  f"closed form; exact {t_ig_x * 1e3:7.1f} ms = {t_ig_x / t_cf:4.2f}×")
            for name, fn in [("closed form + fusion", lambda: fuse(olf, semantic_source_probability(q, lik, prior))),
                             ("information gain", lambda: semantic_information_gain(q, lik, prior, olfactory=olf))]:
                print(f"[{np.dtype(dtype).name}] peak extra memory, {name}: {peak_bytes(fn) / q.nbytes:4.2f}× "
                      f"the input ({q.nbytes / 2**20:.0f} MiB)")
        del q
    m = 10_000
    q = rng.dirichlet(np.ones(k) * 0.5, size=m)
    t_fast = best_of(lambda: semantic_information_gain(q, lik, prior), 3)
    t0 = time.perf_counter()
    ref = naive_gain(q, lik, prior, 200)
    t_naive = (time.perf_counter() - t0) * m / 200  # O(n) per cell: extrapolate 200 of the 10,000 cells
    np.testing.assert_allclose(semantic_information_gain(q, lik, prior)[:200], ref, rtol=1e-6, atol=1e-14)
    print(f"information gain at n = {m:,}: all cells {t_fast * 1e3:.1f} ms vs naive per-cell recomputation "
          f"{t_naive:.1f} s (extrapolated from 200 cells) = {t_naive / t_fast:,.0f}× faster")


if __name__ == "__main__":
    main()
