"""Markdown tables of a closed-loop grid (the output folder of ``psgsl search``), for docs/results/closed-loop.md.

    python benchmarks/closed_loop_report.py OUT [--min-runs N]

Reads ``OUT/<source>-<estimator>/summary.json`` and ``paired.json`` (written by ``psgsl search``; re-written
from every stored run by :func:`psgsl_pgm.search.write_search_outputs`) and prints, per estimator, one table row
per source × policy/variant: runs found with the Wilson interval, RMST with its Greenwood interval, the
Kaplan–Meier median, the final error, the coverage of the 90 % region at ¼, ½, ¾ and the end with its mean
area, and the median HPD level of the true source; then every paired RMST difference with its bootstrap
interval, sign-flip p-value and Holm-adjusted p-value. Groups with fewer than ``--min-runs`` runs are left out.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

SOURCES = {"oven": "oven (kitchen)", "bed": "bed (bedroom, off-ontology)", "5_6": "floor point (5.0, 6.0), hallway"}


def _f(x, digits=0):
    return "n/a" if x is None else f"{x:.{digits}f}"


def _row(source, key, s):
    sr, r, cov = s["success_rate"], s["rmst"], s["coverage90"]
    n = s["n_runs"]
    found = round(sr["value"] * n)
    median = s["time_to_find"]["median"]
    return (f"| {source} | {key} | {found}/{n}, [{sr['ci95'][0]:.2f}, {sr['ci95'][1]:.2f}] | "
            f"{r['value']:.0f} [{r['ci95'][0]:.0f}, {r['ci95'][1]:.0f}] | {_f(median)} | "
            f"{s['final_error']['mean']:.2f} | {cov['quarter']:.2f} / {cov['half']:.2f} / "
            f"{cov['three_quarters']:.2f} / **{cov['final']:.2f}** | {s['region_area90']['mean']:.1f} | "
            f"{s['hpd_level']['median']:.2f} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--min-runs", type=int, default=10)
    args = ap.parse_args(argv)
    folders = sorted(p for p in args.out.iterdir() if (p / "summary.json").is_file())
    estimators = sorted({p.name.rsplit("-", 1)[1] for p in folders})
    for est in estimators:
        print(f"\n### Estimator: {est}\n")
        print("| source | policy / variant | found [Wilson 95 %] | RMST, s [95 % CI] | KM median, s | final error, m "
              "| coverage of the 90 % region at ¼ / ½ / ¾ / end | region, m² | HPD level, median |")
        print("|---|---|---|---|---|---|---|---|---|")
        for label, name in SOURCES.items():
            folder = args.out / f"{label}-{est}"
            if not (folder / "summary.json").is_file():
                continue
            summary = json.loads((folder / "summary.json").read_text())
            first = True
            for key, s in summary.items():
                if s["n_runs"] < args.min_runs:
                    continue
                print(_row(name if first else "", key, s))
                first = False
        print()
        for label, name in SOURCES.items():
            path = args.out / f"{label}-{est}" / "paired.json"
            if not path.is_file():
                continue
            paired = json.loads(path.read_text())
            rows = [(k, v) for k, v in paired.items() if v["n"] >= args.min_runs]
            if not rows:
                continue
            print(f"* {name}:")
            for k, v in rows:
                d = v["rmst_difference"]
                tag = " — **primary**" if v.get("primary") else ""
                print(f"  * {k}: {d['value']:+.0f} s [{d['ci95'][0]:+.0f}, {d['ci95'][1]:+.0f}], "
                      f"p = {v['p_value']:.4f}, p_Holm = {v['p_holm']:.4f} (n = {v['n']}){tag}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
