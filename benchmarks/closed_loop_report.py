"""Markdown tables of a closed-loop grid (the output folder of ``psgsl search``), for docs/results/closed-loop.md.

    python benchmarks/closed_loop_report.py OUT [--min-runs N]

Reads ``OUT/<source>-<estimator>/summary.json`` and ``paired.json`` (written by ``psgsl search``; re-written
from every stored run by :func:`psgsl_pgm.search.write_search_outputs`) and prints, per estimator, one table row
per source × policy/variant: runs found with the Wilson interval, RMST with its Greenwood interval, the
Kaplan–Meier median, the final error, the coverage of the 90 % region at ¼, ½, ¾ and the end with its mean
area, and the median HPD level of the true source; then every paired RMST difference with its bootstrap
interval, sign-flip p-value and Holm-adjusted p-value, every comparison but the primary one marked exploratory and
one on fewer than 20 paired seeds flagged. Groups with fewer than ``--min-runs`` runs are left out.

Then, from the stored runs (``OUT/runs/*.npz``), the closed loop's final credible region against the fixed tour's
at the same elapsed time on the same seed: a closed-loop run ends when it finds the source, so its "final"
posterior holds fewer readings than the tour's final one. For each closed-loop run whose seed has a tour run (same
variant; ``psgsl search`` runs the tour with olfaction alone unless asked for more) still
searching at the closed-loop run's last stop (time t), the tour's region is the one after its last stop at or
before t. Mean area and coverage of both over those pairs.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

#: Below this many paired seeds a comparison is flagged (as the benchmark's report does).
MIN_PAIRS = 20

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


def paired_line(name: str, v: dict) -> str:
    """One comparison of ``paired.json`` as a list item: difference, interval, p-values, n, and whether it is the
    primary comparison or exploratory (flagged when fewer than :data:`MIN_PAIRS` seeds are paired)."""
    d = v["rmst_difference"]
    tag = " — **primary**" if v.get("primary") else " — exploratory"
    if v["n"] < MIN_PAIRS:
        tag += f" — fewer than {MIN_PAIRS} paired seeds: the interval is unreliable"
    return (f"  * {name}: {d['value']:+.0f} s [{d['ci95'][0]:+.0f}, {d['ci95'][1]:+.0f}], "
            f"p = {v['p_value']:.4f}, p_Holm = {v['p_holm']:.4f} (n = {v['n']}){tag}")


def matched_tour(runs_dir, estimator: str, *, min_pairs: int = 1) -> dict:
    """Closed-loop final regions against the tour's at the same elapsed time, paired on seeds.

    Parameters
    ----------
    runs_dir : path
        The ``runs`` folder of a ``psgsl search`` output.
    estimator : str
        Only runs of this estimator.
    min_pairs : int
        Groups with fewer pairs are left out.

    Returns
    -------
    dict
        ``{(source, "policy/variant"): {"n", "time_median", "area", "coverage", "tour_area", "tour_coverage"}}``:
        over the pairs, the median time t of the closed-loop run's last stop, the mean area (m²) and coverage of
        its 90 % region there, and the same for the tour run of the same source, variant and seed after its last
        stop at or before t. A pair needs the tour still searching at t (not found by t); others are left out.
    """
    groups = defaultdict(dict)
    for path in sorted(Path(runs_dir).glob("*.npz")):
        with np.load(path) as z:
            if str(z["estimator"]) != estimator:
                continue
            source = path.name.split("__", 1)[0]
            run = {k: z[k] for k in ("time", "region_area", "region_hit")}
            run["found"], run["time_to_find"] = bool(z["found"]), float(z["time_to_find"])
            groups[(source, str(z["policy"]), str(z["variant"]))][int(z["seed"])] = run
    out = {}
    order = list(SOURCES)
    for (source, policy, variant), by_seed in sorted(groups.items(), key=lambda kv: (
            order.index(kv[0][0]) if kv[0][0] in order else len(order), kv[0])):
        if policy == "tour":
            continue
        tours = groups.get((source, "tour", variant), {})
        pairs = []
        for seed, run in by_seed.items():
            tour = tours.get(seed)
            t = float(run["time"][-1])
            if tour is None or (tour["found"] and tour["time_to_find"] <= t):
                continue  # no tour run on this seed, or the tour had stopped searching by t
            i = int(np.searchsorted(tour["time"], t, side="right")) - 1  # its last stop at or before t
            pairs.append((t, run["region_area"][-1], run["region_hit"][-1],
                          tour["region_area"][i], tour["region_hit"][i]))
        if len(pairs) < min_pairs:
            continue
        t, area, hit, tour_area, tour_hit = np.array(pairs, dtype=float).T
        out[(source, f"{policy}/{variant}")] = {
            "n": len(pairs), "time_median": float(np.median(t)), "area": float(area.mean()),
            "coverage": float(hit.mean()), "tour_area": float(tour_area.mean()),
            "tour_coverage": float(tour_hit.mean()),
        }
    return out


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
                print(paired_line(k, v))
        matched = matched_tour(args.out / "runs", est, min_pairs=args.min_runs)
        if matched:
            print("\nThe 90 % region at the closed-loop run's end and the tour's at the same elapsed time, same seeds "
                  "(pairs with the tour still searching then):\n")
            print("| source | policy / variant | pairs | elapsed time, median s | region m² / coverage, closed loop "
                  "| region m² / coverage, tour at that time |")
            print("|---|---|---|---|---|---|")
            last = None
            for (label, key), m in matched.items():
                name = SOURCES.get(label, label) if label != last else ""
                last = label
                print(f"| {name} | {key} | {m['n']} | {m['time_median']:.0f} | {m['area']:.1f} / {m['coverage']:.2f} "
                      f"| {m['tour_area']:.1f} / {m['tour_coverage']:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
