"""Two ``psgsl benchmark`` folders of the same grid, run by run: are the runs the same bits, and what CPU did each take.

    python benchmarks/benchmark_cpu.py BEFORE AFTER [--json]

Made to measure a speed-up side by side: the same ``psgsl benchmark`` command run by two versions of the code (two
clones or git worktrees), one process per core at the same time (``taskset -c 0 ... --workers 1`` and
``taskset -c 1 ... --workers 1``), so that both meet the same machine. For every run file of BEFORE the run of the
same name in AFTER must hold the same arrays (NaN equal to NaN; the stored configuration, which holds the CPU
seconds, is left out). Prints the number of runs that differ, then the CPU seconds per run (the report's
"CPU s/run", ``config["benchmark"]["cpu_seconds"]``) of each arm — median and mean, before and after — and of all
runs, and the median of the per-run ratios after / before.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def _arm(name: str) -> str:
    """``policy/variant`` of a run file ``house__condition__policy__variant__estimator__seedN.npz``."""
    parts = name.split("__")
    if len(parts) < 6:
        raise ValueError(f"{name}: not a benchmark run file (house__condition__policy__variant__estimator__seed)")
    return f"{parts[2]}/{parts[3]}"


def _cpu(run) -> float:
    config = json.loads(str(run["config"]))
    try:
        return float(config["benchmark"]["cpu_seconds"])
    except (KeyError, TypeError):
        raise ValueError("a run without config['benchmark']['cpu_seconds'] (made before runs stored their CPU)")


def compare(before, after) -> dict:
    """Per run: same arrays? and the CPU seconds before and after; per arm and overall: median and mean."""
    before, after = Path(before), Path(after)
    files = sorted((before / "runs").glob("*.npz"))
    if not files:
        raise ValueError(f"{before}: no runs/*.npz (not a benchmark folder)")
    differ, rows = [], []
    for f in files:
        g = after / "runs" / f.name
        if not g.is_file():
            raise ValueError(f"{after}: has no run {f.name}")
        with np.load(f, allow_pickle=False) as a, np.load(g, allow_pickle=False) as b:
            keys = sorted(set(a.files) - {"config"})
            if keys != sorted(set(b.files) - {"config"}):
                differ.append(f.name)
            else:
                for k in keys:
                    x, y = a[k], b[k]
                    if not np.array_equal(x, y, equal_nan=x.dtype.kind in "fc" and y.dtype.kind in "fc"):
                        differ.append(f.name)
                        break
            rows.append((_arm(f.name), _cpu(a), _cpu(b)))
    arms = {}
    for arm, cb, ca in rows + [("all runs", cb, ca) for _, cb, ca in rows]:
        arms.setdefault(arm, []).append((cb, ca))
    out = {"runs": len(rows), "differing": differ, "arms": {}}
    for arm, pairs in arms.items():
        cb, ca = np.array(pairs).T
        out["arms"][arm] = {"n": len(pairs), "median_before": float(np.median(cb)), "median_after": float(np.median(ca)),
                            "mean_before": float(cb.mean()), "mean_after": float(ca.mean()),
                            "median_ratio": float(np.median(ca / cb))}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    try:
        res = compare(a.before, a.after)
    except (ValueError, OSError) as exc:
        print(f"benchmark_cpu: {exc}", file=sys.stderr)
        return 2
    if a.json:
        print(json.dumps(res, indent=1))
        return 0
    print(f"{res['runs']} runs; {len(res['differing'])} differ" + (": " + ", ".join(res["differing"][:5])
                                                                      if res["differing"] else " (the same bits)"))
    print(f"{'arm':<40}{'n':>4}  {'median before':>13} {'after':>7}  {'mean before':>11} {'after':>7}  {'ratio':>6}")
    for arm, r in res["arms"].items():
        print(f"{arm:<40}{r['n']:>4}  {r['median_before']:13.3f} {r['median_after']:7.3f}  {r['mean_before']:11.3f} "
              f"{r['mean_after']:7.3f}  {r['median_ratio']:6.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
