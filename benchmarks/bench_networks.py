"""pgmpy exact inference vs the closed form, measured in the same process (not a test).

* Network A, p(S | evidence): exact (fixed elimination order and pgmpy's default "greedy" contraction) vs
  ``SemanticGSLProblem.closed_form_posterior()`` at n = 9, 100, 400 cells (targets: n = 400 ≤ 1 s);
* Network B, chain encoding, all n marginals p(S_i = yes | ·) (one query per target) at n = 25, 100
  (target: n = 100 ≤ 15 s on 2 cores), both elimination strategies;
* the table encoding's limit: build time, CPD size and all-marginals time for n = 8 … 20 (n > 20 is refused);
* where exact inference stops: the size at which the evidence probability of Network A leaves the float64
  normal range (``check_scale`` raises; pgmpy alone would return NaN a little later).

Every exact result is compared with the closed form (max relative error printed). Run:
``python benchmarks/bench_networks.py [--quick]``. Best of several repeats for the fast cases.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from pgmpy.inference import VariableElimination

from psgsl_pgm.networks import (
    MIN_EVIDENCE,
    SemanticGSLProblem,
    build_network_a,
    build_network_b,
    exact_source_posterior,
    log_evidence,
    network_evidence,
)


def best_of(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def rel_error(a, b):
    mask = b > 0
    assert np.array_equal(a > 0, mask)
    return float(np.max(np.abs(a[mask] / b[mask] - 1)))


def problem(n, seed=0, k=4, m=1):
    return SemanticGSLProblem.random(np.random.default_rng(seed), n, k, m, max_observations=2)


def bench_a(sizes, repeats):
    print("\nNetwork A: p(S | z, g) — pgmpy VariableElimination vs closed form")
    print(f"{'n':>5} {'build s':>9} {'fixed s':>9} {'greedy s':>9} {'closed s':>10} {'fixed/closed':>13} "
          f"{'rel err':>9}")
    for n in sizes:
        p = problem(n)
        t_build, model = best_of(lambda: build_network_a(p), 1)
        t_fixed, exact = best_of(lambda: exact_source_posterior(model, p, elimination_order="fixed"), repeats)
        t_greedy, greedy = best_of(lambda: exact_source_posterior(model, p, elimination_order="greedy"), repeats)
        t_closed, closed = best_of(p.closed_form_posterior, max(repeats, 5))
        err = max(rel_error(exact, closed), rel_error(greedy, closed))
        print(f"{n:>5} {t_build:>9.3f} {t_fixed:>9.3f} {t_greedy:>9.3f} {t_closed:>10.5f} "
              f"{t_fixed / t_closed:>13.0f} {err:>9.1e}")


def bench_b_chain(sizes, m=1):
    print(f"\nNetwork B (chain), all n marginals, one query per S_i (m = {m} gas types)")
    print(f"{'n':>5} {'build s':>9} {'fixed s':>9} {'greedy s':>9} {'closed s':>10} {'rel err':>9}")
    for n in sizes:
        p = problem(n, seed=1, m=m)
        t_build, model = best_of(lambda: build_network_b(p, "chain"), 1)
        t_fixed, exact = best_of(lambda: exact_source_posterior(model, p, elimination_order="fixed"), 1)
        t_greedy, greedy = best_of(lambda: exact_source_posterior(model, p, elimination_order="greedy"), 1)
        t_closed, closed = best_of(p.closed_form_posterior, 5)
        err = max(rel_error(exact, closed), rel_error(greedy, closed))
        print(f"{n:>5} {t_build:>9.3f} {t_fixed:>9.3f} {t_greedy:>9.3f} {t_closed:>10.5f} {err:>9.1e}")


def bench_table(sizes):
    print("\nNetwork B (table): the 2^n-column CPD of α; all n marginals ('auto' = greedy contraction)")
    print(f"{'n':>5} {'alpha MB':>9} {'build s':>9} {'all marg s':>11} {'rel err':>9}")
    for n in sizes:
        p = problem(n, seed=2)
        t_build, model = best_of(lambda: build_network_b(p, "table"), 1)
        t_query, exact = best_of(lambda: exact_source_posterior(model, p), 1)
        mb = model.get_cpds("alpha").values.nbytes / 2**20
        print(f"{n:>5} {mb:>9.1f} {t_build:>9.3f} {t_query:>11.3f} {rel_error(exact, p.closed_form_posterior()):>9.1e}")
    try:
        build_network_b(problem(21), "table")
    except ValueError as exc:
        print(f"   21  refused: {exc}")


def underflow_limit():
    print("\nWhere exact inference stops (Network A, k = 4, 0–2 observations per cell, random problems)")
    for seed in range(3):
        lo, hi = 10, 4000
        while hi - lo > 1:  # smallest n with p(evidence) < MIN_EVIDENCE (log_evidence is monotone here)
            mid = (lo + hi) // 2
            if log_evidence(problem(mid, seed=seed), "A") < np.log(MIN_EVIDENCE):
                hi = mid
            else:
                lo = mid
        print(f"  seed {seed}: exact queries refused from n ≈ {hi} cells (evidence probability < {MIN_EVIDENCE:g})")
        if seed == 0:
            first_refused = hi
    # what pgmpy alone returns (no guard) from that size on
    for n in (first_refused, first_refused + 40, first_refused + 80):
        p = problem(n, seed=0)
        model = build_network_a(p)
        with np.errstate(all="ignore"):
            raw = VariableElimination(model).query(["S"], evidence=network_evidence(model),
                                                   show_progress=False).values
        state = "NaN" if np.any(np.isnan(raw)) else f"finite, rel err {rel_error(raw, p.closed_form_posterior()):.1e}"
        print(f"  seed 0, n = {n}: log10 p(evidence) = {log_evidence(p, 'A') / np.log(10):.0f}; raw pgmpy: {state}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes, one repeat")
    args = parser.parse_args(argv)
    print(f"CPU count: {os.cpu_count()}, OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')}")
    if args.quick:
        bench_a([9, 100], 1)
        bench_b_chain([25])
        bench_table([8, 12])
        return
    bench_a([9, 100, 400], 3)
    bench_b_chain([25, 100])
    bench_b_chain([25, 100], m=3)
    bench_table([8, 12, 16, 18, 20])
    underflow_limit()


if __name__ == "__main__":
    main()
