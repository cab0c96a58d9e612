"""Summarise calibration_check.py outputs (before / after) and draw the reliability diagram.

    python benchmarks/calibration_report.py before=before.json after=after.json --figure docs/figures/reliability.png
"""

import argparse
import json
from collections import defaultdict

import numpy as np

from psgsl_pgm.experiment import plot_reliability, reliability_table


def load(spec):
    """Runs of ``path[#estimator][,path[#estimator]...]`` (a ``#estimator`` keeps only that estimator's runs)."""
    runs = []
    for part in spec.split(","):
        path, _, est = part.partition("#")
        runs += [r for r in json.load(open(path))["runs"] if not est or r["estimator"] == est]
    return runs


def summary(spec):
    runs = load(spec)
    rows = defaultdict(list)
    for r in runs:
        for v, cps in r["variants"].items():
            rows[(r["estimator"], r["source"], v)].append(cps)
            rows[(r["estimator"], "all", v)].append(cps)
    out = {}
    for key, cps in rows.items():
        out[key] = {
            "n": len(cps),
            **{f"cov_{c}": float(np.mean([x[c]["covered"] for x in cps])) for c in ("quarter", "half", "three_quarters", "final")},
            "area": float(np.mean([x["final"]["area"] for x in cps])),
            "hpd_median": float(np.median([x["final"]["hpd_level"] for x in cps])),
        }
    stops = [s for r in runs for s in r["stops"]] if runs else []
    return out, stops


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("files", nargs="+", help="label=path.json[#estimator][,path.json[#estimator]...]")
    ap.add_argument("--figure")
    ap.add_argument("--title", default="Hit model on held-out seeds (fixed tour, true source)")
    a = ap.parse_args()
    curves = {}
    for item in a.files:
        label, path = item.split("=", 1)
        out, stops = summary(path)
        print(f"== {label}")
        print(f"{'estimator':10s} {'source':9s} {'variant':16s} n  cov¼  cov½  cov¾  final  area m²  HPD(med)")
        for (e, s, v), d in sorted(out.items()):
            print(f"{e:10s} {s:9s} {v:16s} {d['n']:2d} {d['cov_quarter']:.2f}  {d['cov_half']:.2f}  "
                  f"{d['cov_three_quarters']:.2f}  {d['cov_final']:.2f}  {d['area']:7.2f}  {d['hpd_median']:.3f}")
        p = np.array([s[0] for s in stops])
        g = np.array([s[1] for s in stops], dtype=bool)
        rooms = np.array([s[2] for s in stops])
        t = reliability_table(p, g)
        curves[label] = t
        print("reliability (all stops): bin n hits mean_pred observed [Wilson 95%]")
        for i in range(len(t["n"])):
            print(f"  [{t['edges'][i]:.2f},{t['edges'][i+1]:.2f}) {t['n'][i]:5d} {t['hits'][i]:5d} "
                  f"{t['mean_predicted'][i]:.3f} {t['observed'][i]:.3f} [{t['lower'][i]:.3f}, {t['upper'][i]:.3f}]")
        print("per room: n, mean predicted, observed")
        for room in sorted(set(rooms)):
            m = rooms == room
            print(f"  {room:12s} {m.sum():5d} {p[m].mean():.3f} {g[m].mean():.3f}")
        bed = np.array([r for r in rooms]) == "Bedroom"
        print(f"  Bedroom stops with predicted in [0.07, 0.88]: n = {int((bed & (p >= 0.07) & (p <= 0.88)).sum())}, "
              f"hit rate = {g[bed & (p >= 0.07) & (p <= 0.88)].mean() if (bed & (p >= 0.07) & (p <= 0.88)).any() else float('nan'):.3f}")
    if a.figure:
        plot_reliability(curves, a.figure, title=a.title)


if __name__ == "__main__":
    main()
