"""Choose the tempering for coverage on recorded calibration runs, and evaluate it on recorded held-out runs.

    python benchmarks/calibration_coverage.py --fit rec_cal [rec_t200] --evaluate rec300 [--before 0.298,0.380]

Reads the records of ``benchmarks/calibration_record.py``. ``--fit``: for each estimator, the threshold β*_i of
every recorded calibration posterior (:func:`psgsl_pgm.experiment.coverage_threshold`) and the tempering that
gives the 90 % region a coverage of 0.90 (:func:`psgsl_pgm.experiment.coverage_tempering`, run bootstrap).
``--evaluate``: per estimator, source and variant, the coverage of the 90 % region at ¼, ½, ¾ and the end, its
mean area at the end (m²) and the median HPD level of the source cell, at the ``--before`` tempering (Infotaxis,
analytic-plume) and at the fitted one (or ``--after``) — exact arithmetic on the records
(:func:`psgsl_pgm.experiment.tempered_posterior`, then :func:`psgsl_pgm.core.fuse` with p(s | z) as the experiment
does).
"""

import argparse
import glob
import os
from collections import defaultdict

import numpy as np

from psgsl_pgm.core._fusion import fuse
from psgsl_pgm.experiment import VARIANTS
from psgsl_pgm.experiment._calibration import coverage_tempering, coverage_threshold, tempered_posterior
from psgsl_pgm.experiment._metrics import credible_region, hpd_level

CHECKS = ("quarter", "half", "three_quarters", "final")


def load(folders, estimator):
    out = []
    for d in folders:
        for f in sorted(glob.glob(os.path.join(d, f"{estimator}_*.npz"))):
            z = np.load(f)
            out.append({k: z[k] for k in z.files})
    return out


def fit(recs, label):
    th, groups = [], []
    for r in recs:
        for i in range(r["loglik"].shape[0]):
            th.append(coverage_threshold(r["log_prior"], r["loglik"][i], int(r["cell"]), weights=r["weights"]))
            groups.append(f"{r['source']}@{int(r['seed'])}")
    res = coverage_tempering(th, groups)
    b = np.array(th).reshape(-1, 4)
    print(f"{label}: {len(recs)} runs, tempering {res.tempering:.4f} (bootstrap 5-95 % {res.interval[0]:.3f}-"
          f"{res.interval[1]:.3f}), calibration coverage {res.coverage:.3f}; per checkpoint at it "
          f"{np.round((b > res.tempering).mean(axis=0), 3).tolist()}")
    return res.tempering


def evaluate(recs, beta):
    rows = defaultdict(list)
    for r in recs:
        cell = int(r["cell"])
        for i, check in enumerate(CHECKS):
            p_g = tempered_posterior(r["log_prior"], r["loglik"][i], beta, weights=r["weights"])
            posts = [p_g] + [fuse(p_g, r["semantic"][i][k]) for k in range(r["semantic"].shape[1])]
            for v, p in zip(VARIANTS, posts):
                region = credible_region(p, 0.9)
                rows[(str(r["source"]), v)].append((check, bool(region[cell]), float(region.sum() * r["cell_area"]),
                                                   hpd_level(p, cell)))
    out = {}
    for key, items in rows.items():
        cov = {c: np.mean([h for cc, h, _, _ in items if cc == c]) for c in CHECKS}
        final = [(a, lv) for cc, _, a, lv in items if cc == "final"]
        out[key] = (cov, float(np.mean([a for a, _ in final])), float(np.median([lv for _, lv in final])), len(final))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--fit", nargs="*", default=[])
    ap.add_argument("--evaluate", nargs="*", default=[])
    ap.add_argument("--before", default="0.298,0.380", help="Infotaxis β, analytic-plume λ before")
    ap.add_argument("--sweep", default=None, help="comma-separated temperings: final coverage and area at each")
    ap.add_argument("--after", default=None, help="Infotaxis β, analytic-plume λ after (default: the fitted ones)")
    a = ap.parse_args()
    before = dict(zip(("infotaxis", "analytic-plume"), map(float, a.before.split(","))))
    after = dict(zip(("infotaxis", "analytic-plume"), map(float, a.after.split(",")))) if a.after else {}
    for est in ("infotaxis", "analytic-plume"):
        if a.fit and est not in after:
            recs = load(a.fit, est)
            if recs:
                after[est] = fit(recs, est)
    for est in ("infotaxis", "analytic-plume"):
        recs = load(a.evaluate, est)
        if not recs or est not in after:
            continue
        if a.sweep:
            betas = [float(v) for v in a.sweep.split(",")]
            res = [evaluate(recs, v) for v in betas]
            print(f"\n{est}: final coverage / mean area m² at tempering " + ", ".join(f"{v:g}" for v in betas))
            for key in sorted(res[0], key=lambda k: (k[0], VARIANTS.index(k[1]))):
                print(f"| {key[0]} | {key[1]} | " + " | ".join(f"{r[key][0]['final']:.2f} / {r[key][1]:.1f}"
                                                            for r in res) + " |")
        b, c = evaluate(recs, before[est]), evaluate(recs, after[est])
        print(f"\n{est}: before {before[est]:.3f} -> after {after[est]:.3f}  "
              "(coverage ¼ / ½ / ¾ / end, mean area m², median HPD level; n runs)")
        for key in sorted(b, key=lambda k: (k[0], VARIANTS.index(k[1]))):
            fmt = lambda t: (" / ".join(f"{t[0][ch]:.2f}" for ch in CHECKS) + f", {t[1]:.1f}, {t[2]:.2f}")
            print(f"| {key[0]} | {key[1]} | {fmt(b[key])} | {fmt(c[key])} | n={b[key][3]}")


if __name__ == "__main__":
    main()
