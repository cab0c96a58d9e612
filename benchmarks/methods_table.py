"""The methods table of docs/results/methods.md from stored runs: one row per method, estimator and variant.

    python benchmarks/methods_table.py RUNS_DIR [RUNS_DIR ...] [--by source|house|all] [--budget 1000]

Every ``*.npz`` run below the given folders (``psgsl benchmark`` and ``psgsl search`` outputs) is read; runs are
grouped by (policy, estimator, variant) and, with ``--by source``, by the source (the embedded house's oven, bed
and floor point), with ``--by house`` by the generated home. Per group: correct declarations of runs; RMST(τ) of the time to a correct declaration with
Greenwood's 95 % interval (:func:`psgsl_pgm.search._survival.rmst`); wrong declarations of those made; the median
error of the declarations made, m; and the CPU per stop, s (the process time the benchmark measures for a whole
run, the simulated world included, over the run's stops; "—" for runs stored before the search command recorded
it).
"""

import argparse
import collections
from pathlib import Path

import numpy as np

from psgsl_pgm.search._store import load_search_run
from psgsl_pgm.search._survival import rmst


def _cpu_seconds(run):
    """The run's CPU seconds: ``psgsl benchmark`` stores them under ``benchmark``, ``psgsl search`` at the top of
    the config; None for runs stored before either recorded them."""
    value = (run.config.get("benchmark") or {}).get("cpu_seconds", run.config.get("cpu_seconds"))
    return None if value is None else float(value)


def _cell(runs, budget):
    n = len(runs)
    ok = sum(bool(r.succeeded) for r in runs)
    t = [min(float(r.time_to_success), budget) for r in runs]
    m = rmst(t, [bool(r.succeeded) for r in runs], budget)
    lo, hi = m["ci95"]
    err = [float(r.declared_error) for r in runs if r.declared]
    cpu = [s / max(len(r.time), 1) for r in runs if (s := _cpu_seconds(r)) is not None]
    rm = f"{m['value']:.0f}" if ok == 0 else f"{m['value']:.0f} [{max(lo, 0):.0f}, {min(hi, budget):.0f}]"
    e = f"{np.median(err):.2f}" if err else "—"
    c = f"{np.mean(cpu):.2f}" if cpu else "—"
    made = sum(bool(r.declared) for r in runs)
    wrong = f"{sum(bool(r.declared) and not bool(r.declared_correct) for r in runs)} of {made}" if made else "—"
    return f"{ok}/{n}, {rm}, {wrong}, {e}, {c}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folders", nargs="+", type=Path)
    ap.add_argument("--by", choices=["source", "house", "all"], default="all")
    ap.add_argument("--budget", type=float, default=1000.0)
    a = ap.parse_args(argv)
    groups = collections.defaultdict(list)
    for folder in a.folders:
        for f in sorted(folder.rglob("*.npz")):
            r = load_search_run(f)
            src = {"source": str(r.source), "house": (r.config.get("benchmark") or {}).get("house", "—"),
                   "all": "all"}[a.by]
            groups[(r.policy, r.estimator, r.variant, src)].append(r)
    sources = sorted({k[3] for k in groups})
    print("| policy | estimator | variant | " + " | ".join(sources) + " |")
    print("|---|---|---|" + "---|" * len(sources))
    for key in sorted({k[:3] for k in groups}):
        cells = [_cell(groups[key + (s,)], a.budget) if groups.get(key + (s,)) else "—" for s in sources]
        print(f"| {key[0]} | {key[1]} | {key[2]} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
