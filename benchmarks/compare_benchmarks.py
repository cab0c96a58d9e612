"""Two arms of ``psgsl benchmark`` folders, paired by episode: one arm of two folders, or two arms of one.

    python benchmarks/compare_benchmarks.py A B [--arm infotaxis/semantics+rooms] [--arm-b ARM]
                                            [--condition right-ontology] [--time first|all] [--json]

A and B may be one folder (then give ``--arm-b``) or two that hold the same episodes (same houses and seeds: e.g.
the same command with and without ``--gas unknown``). Prints the runs of arm A in A and arm B in B paired by
(house, seed), their success rates and RMST(τ) of the time to success, the RMST difference A − B and ratio A / B
with 95 % nested percentile bootstrap intervals (houses, then seeds within a house; paired by episode), and how
many episodes were faster, slower or equal. ``--time all`` takes, in a several-source benchmark, the time until
every source of the episode was declared (censored at τ) instead of the first correct declaration. With
``--json`` the same as a JSON object.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def compare(a, b, *, arm: str = "infotaxis/semantics+rooms", arm_b: str | None = None,
            condition: str = "right-ontology", time: str = "first") -> dict:
    from psgsl_pgm.search._bench_report import _paired, _select, _table
    from psgsl_pgm.search._survival import nested_bootstrap

    if time not in ("first", "all"):
        raise ValueError(f"time must be 'first' or 'all', got {time!r}")
    arm_b = arm if arm_b is None else arm_b
    rows, budgets = [], []
    for folder, which in ((Path(a), arm), (Path(b), arm_b)):
        summary = folder / "summary.json"
        if not summary.is_file():
            raise ValueError(f"{folder}: not a benchmark folder (no summary.json)")
        settings = json.loads(summary.read_text())["settings"]
        budgets.append(float(settings["budget"]))
        picked = _select(_table(folder, settings), condition=condition, arm=which)
        if time == "all":
            if not all("several" in r for r in picked):
                raise ValueError(f"{folder}: --time all needs a several-source benchmark (--sources-per-episode)")
            picked = [r | {"t": r["several"]["t_all"], "found": r["several"]["all"]} for r in picked]
        rows.append(picked)
    if budgets[0] != budgets[1]:
        raise ValueError(f"the folders' budgets differ: {budgets[0]:g} s and {budgets[1]:g} s")
    keys, t = _paired(*rows)
    if len(keys) < 2:
        raise ValueError(f"fewer than 2 episodes of arm {arm!r} under {condition!r} in both folders"
                         + ("" if arm_b == arm else f" (arm B {arm_b!r})"))
    found = {name: {(r["house"], r["seed"]): r["found"] for r in rs} for name, rs in zip("AB", rows)}
    houses = [k[0] for k in keys]
    diff = nested_bootstrap(t, houses, lambda x: x[0].mean() - x[1].mean())
    ratio = nested_bootstrap(t, houses, lambda x: x[0].mean() / x[1].mean())
    return {"arm": arm, "arm_b": arm_b, "time": time, "condition": condition, "budget": budgets[0], "episodes": len(keys),
            "houses": len(set(houses)), "A": str(a), "B": str(b),
            "success": {n: float(np.mean([found[n][k] for k in keys])) for n in "AB"},
            "rmst": {"A": float(t[0].mean()), "B": float(t[1].mean())},
            "difference": {"value": diff["value"], "ci95": diff["ci95"]},
            "ratio": {"value": ratio["value"], "ci95": ratio["ci95"]},
            "faster_slower_equal": [int((t[0] < t[1]).sum()), int((t[0] > t[1]).sum()), int((t[0] == t[1]).sum())],
            "interval": diff["interval"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--arm", default="infotaxis/semantics+rooms")
    ap.add_argument("--arm-b", default=None, help="arm of B (default: --arm)")
    ap.add_argument("--condition", default="right-ontology")
    ap.add_argument("--time", choices=("first", "all"), default="first")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    try:
        r = compare(args.a, args.b, arm=args.arm, arm_b=args.arm_b, condition=args.condition, time=args.time)
    except ValueError as exc:
        print(f"compare_benchmarks: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(r, indent=1))
        return 0
    f, s, e = r["faster_slower_equal"]
    arms = r["arm"] if r["arm_b"] == r["arm"] else f"{r['arm']} − {r['arm_b']}"
    print(f"{arms} ({r['condition']}, time to {'every source' if r['time'] == 'all' else 'success'}), {r['episodes']} paired episodes in {r['houses']} houses, τ = {r['budget']:g} s")
    print(f"success A / B: {r['success']['A']:.2f} / {r['success']['B']:.2f}; "
          f"RMST A / B: {r['rmst']['A']:.0f} s / {r['rmst']['B']:.0f} s")
    d, q = r["difference"], r["ratio"]
    print(f"A − B: {d['value']:+.0f} s [{d['ci95'][0]:+.0f}, {d['ci95'][1]:+.0f}]; A / B: {q['value']:.3f} "
          f"[{q['ci95'][0]:.3f}, {q['ci95'][1]:.3f}] ({r['interval']})")
    print(f"episodes A faster / slower / equal: {f} / {s} / {e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
