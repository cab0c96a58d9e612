"""What the robot's off-ontology prior ε changes in the closed loop: paired comparisons of two ``psgsl search``
folders run on the same seeds, one with ``--off-ontology 0`` (BASE) and one with ``--off-ontology ε`` (OTHER).

    python benchmarks/off_ontology_report.py BASE OTHER [--budget 1000]

Reads ``runs.csv`` of both and prints one markdown row per source × policy/variant present in both: the RMST of
each, the paired RMST difference OTHER − BASE on common seeds (percentile bootstrap interval over seeds, sign-flip
p-value, Holm's adjustment over the rows), and the calibration of the final posterior in each (coverage of the 90 %
region, its mean area, the median HPD level of the true source). Then, per source, the semantic variants of
OTHER against BASE's ``olfaction`` (the cost or gain of semantics with ε against no semantics at all).
"""

from __future__ import annotations

import argparse
import csv
from collections import defaultdict
from pathlib import Path

import numpy as np

from psgsl_pgm.search._survival import holm, paired_comparison

SOURCES = {"oven": "oven", "bed": "bed (off-ontology)", "5,6": "floor point (off-ontology)"}


def _runs(folder: Path) -> dict:
    """{(source, policy, variant): {seed: row}} of ``folder/runs.csv``."""
    out = defaultdict(dict)
    with open(folder / "runs.csv", newline="", encoding="utf-8") as f:
        for row in csv.DictReader(f):
            out[(row["source"], row["policy"], row["variant"])][int(row["seed"])] = row
    return out


def _calibration(rows) -> str:
    hit = np.mean([float(r["final_region_hit"]) for r in rows])
    area = np.mean([float(r["final_region_area"]) for r in rows])
    level = np.median([float(r["final_hpd_level"]) for r in rows])
    return f"{hit:.2f} / {area:.1f} / {level:.2f}"


def _compare(a_rows: dict, b_rows: dict, tau: float):
    seeds = sorted(set(a_rows) & set(b_rows))
    ta = [min(float(a_rows[s]["time_to_find"]), tau) if a_rows[s]["found"] == "1" else tau for s in seeds]
    tb = [min(float(b_rows[s]["time_to_find"]), tau) if b_rows[s]["found"] == "1" else tau for s in seeds]
    return seeds, np.mean(ta), np.mean(tb), paired_comparison(ta, tb, tau)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base", type=Path)
    ap.add_argument("other", type=Path)
    ap.add_argument("--budget", type=float, default=1000.0)
    args = ap.parse_args(argv)
    base, other = _runs(args.base), _runs(args.other)
    rows, tests = [], []
    for key in sorted(set(base) & set(other), key=lambda k: (list(SOURCES).index(k[0]) if k[0] in SOURCES else 9, k)):
        seeds, r_other, r_base, cmp = _compare(other[key], base[key], args.budget)
        found = sum(other[key][s]["found"] == "1" for s in seeds), sum(base[key][s]["found"] == "1" for s in seeds)
        rows.append((key, len(seeds), found, r_base, r_other, cmp,
                     _calibration([base[key][s] for s in seeds]), _calibration([other[key][s] for s in seeds])))
        tests.append(cmp["p_value"])
    adjusted = holm(tests) if tests else []
    print("| source | policy / variant | n | found ε = 0 / ε | RMST ε = 0, s | RMST ε, s | difference ε − 0, s [95 % CI] "
          "| p (p_Holm) | coverage / region m² / HPD level, ε = 0 | the same, ε |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for (key, n, found, r_base, r_other, cmp, cal_base, cal_other), p_adj in zip(rows, adjusted):
        lo, hi = cmp["ci95"]
        print(f"| {SOURCES.get(key[0], key[0])} | {key[1]}/{key[2]} | {n} | {found[1]} / {found[0]} | {r_base:.0f} | "
              f"{r_other:.0f} | {cmp['value']:+.0f} [{lo:+.0f}, {hi:+.0f}] | {cmp['p_value']:.4f} ({p_adj:.4f}) | "
              f"{cal_base} | {cal_other} |")
    print()
    for source in SOURCES:
        for (src, policy, variant) in sorted(other):
            ref = base.get((src, policy, "olfaction"))
            if src != source or variant == "olfaction" or ref is None:
                continue
            seeds, r_other, r_ref, cmp = _compare(other[(src, policy, variant)], ref, args.budget)
            lo, hi = cmp["ci95"]
            print(f"* {SOURCES[source]}: {policy}/{variant} with ε − {policy}/olfaction: {cmp['value']:+.0f} s "
                  f"[{lo:+.0f}, {hi:+.0f}], p = {cmp['p_value']:.4f} (n = {len(seeds)})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
