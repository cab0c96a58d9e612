"""What each of the ideal world's assumptions costs: the house's primary comparison re-run with each realistic
component switched on alone, and with all of them (not a test).

For every world model of ``--models`` (default: ``ideal``, each ``ideal+COMPONENT`` of
:data:`psgsl_pgm.sim.WORLD_COMPONENTS`, ``realistic``) this runs ``psgsl search`` on the embedded house with the
source in the oven, grid Infotaxis with olfaction alone and with semantics and the room map, and semantics alone
(``semantic-modes``), on the same seeds, into ``OUT/<model>/`` (resumable: a finished run is kept). Then it writes
``OUT/costs.md`` and ``OUT/costs.json``: per model and arm the runs found, the RMST of the time to find (Kaplan–Meier,
Greenwood interval), the final coverage of the 90 % region and its mean area; per model the primary comparison
(the paired RMST difference semantics+rooms − olfaction, percentile bootstrap over seeds, sign-flip p-value); and
which single component moved the primary comparison most from the ideal world's.

Run: ``python benchmarks/world_model_costs.py OUT --first-seed 100 --seeds 20 [--workers 2]`` (development seeds).
With ``--recalibrated MODEL=D,TAU,KAPPA,BETA`` (repeatable) it also runs MODEL with the olfactory estimator's
plume parameters and tempering fitted on calibration runs made in that world
(``python benchmarks/calibrate_olfaction.py --world-model MODEL --plume-only``: the robot calibrates where it
searches), reported as ``MODEL, recalibrated``. With ``--benchmark-homes N`` it also runs ``psgsl benchmark`` on generated homes 0 … N − 1 (right ontology,
Infotaxis, both variants) per model into ``OUT/benchmark-<model>/`` and reports the benchmark's primary RMST ratio.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ARMS = ("infotaxis/olfaction", "infotaxis/semantics+rooms", "semantic-modes/semantics+rooms")
PRIMARY = "infotaxis/semantics+rooms - infotaxis/olfaction"


def models() -> list:
    from psgsl_pgm.sim import WORLD_COMPONENTS

    return ["ideal"] + [f"ideal+{c}" for c in WORLD_COMPONENTS] + ["realistic"]


def run_search(out: Path, model: str, *, first_seed: int, seeds: int, workers: int, end: str = "declare") -> dict:
    """``psgsl search`` for one world model; (summary, paired) of the oven."""
    folder = out / model
    cmd = [sys.executable, "-m", "psgsl_pgm", "search", "--sources", "oven", "--policies", "infotaxis",
           "semantic-modes", "--variants", "olfaction", "semantics+rooms", "--first-seed", str(first_seed),
           "--seeds", str(seeds), "--world-model", model, "--workers", str(workers), "--out", str(folder),
           "--end", end, "--quiet", "--no-figures"]
    subprocess.run(cmd, check=True)
    summary = json.loads((folder / "summary.json").read_text())["oven/infotaxis"]
    paired = json.loads((folder / "oven-infotaxis" / "paired.json").read_text())
    return {"command": "psgsl " + " ".join(cmd[3:]), "summary": summary, "paired": paired.get(PRIMARY)}


def run_recalibrated(out: Path, model: str, plume: tuple, *, first_seed: int, seeds: int, workers: int,
                     end: str = "declare") -> dict:
    """The same grid as :func:`run_search` with the plume parameters (D, τ, κ) and tempering β fitted in ``model``."""
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.search import SearchConfig, run_search_grid

    d, tau, kappa, beta = plume
    config = ExperimentConfig(world_model=model, diffusivity=d, lifetime=tau, encounter_scale=kappa, tempering=beta)
    folder = out / f"{model}-recalibrated"
    run_search_grid(("oven",), ("infotaxis", "semantic-modes"), ("olfaction", "semantics+rooms"), ("infotaxis",),
                    range(first_seed, first_seed + seeds), out=folder, workers=workers, config=config,
                    search=SearchConfig(end=end), progress=False, figures=False)
    summary = json.loads((folder / "summary.json").read_text())["oven/infotaxis"]
    paired = json.loads((folder / "oven-infotaxis" / "paired.json").read_text())
    return {"command": f"run_search_grid(config={config!r})", "summary": summary, "paired": paired.get(PRIMARY)}


def run_benchmark(out: Path, model: str, *, homes: int, seeds: int, workers: int, end: str = "declare") -> dict:
    folder = out / f"benchmark-{model}"
    cmd = [sys.executable, "-m", "psgsl_pgm", "benchmark", "--houses", str(homes), "--seeds", str(seeds),
           "--policies", "infotaxis", "--variants", "olfaction", "semantics+rooms", "--conditions", "right-ontology",
           "--world-model", model, "--workers", str(workers), "--out", str(folder), "--end", end, "--quiet",
           "--no-figures"]
    subprocess.run(cmd, check=True)
    summary = json.loads((folder / "summary.json").read_text())
    return {"command": "psgsl " + " ".join(cmd[3:]), "primary": summary["primary"]}


def _arm_row(model: str, arm: str, s: dict) -> str:
    r = s["rmst"]
    lo, hi = r["ci95"]
    found = s["n_runs"] - s["time_to_find"]["not_found"]
    return (f"| {model} | {arm} | {found}/{s['n_runs']} | {r['value']:.0f} [{lo:.0f}, {hi:.0f}] | "
            f"{s['coverage90']['final']:.2f} | {s['region_area90']['mean']:.1f} |")


def report(out: Path, results: dict, bench: dict, *, first_seed: int, seeds: int, version: str) -> str:
    lines = [f"Embedded house, source in the oven, seeds {first_seed}–{first_seed + seeds - 1} (development split), "
             f"code {version}.", "",
             "| world model | arm | found | RMST, s [95 % CI] | cov90 final | 90 % region, m² |",
             "|---|---|---|---|---|---|"]
    for model, res in results.items():
        for arm in ARMS:
            if arm in res["summary"]:
                lines.append(_arm_row(model, arm, res["summary"][arm]))
    lines += ["", "Primary comparison: paired RMST difference, Infotaxis with semantics and rooms − olfaction alone "
              "(negative: semantics finds the source sooner).", "",
              "| world model | difference, s [95 % CI] | p (sign-flip) | shift from ideal, s |", "|---|---|---|---|"]
    base = results.get("ideal", {}).get("paired")
    shifts = {}
    for model, res in results.items():
        p = res["paired"]
        if p is None:
            continue
        d = p["rmst_difference"]
        shift = None if base is None else d["value"] - base["rmst_difference"]["value"]
        if model.startswith("ideal+") and "recalibrated" not in model and shift is not None:
            shifts[model] = shift
        lines.append(f"| {model} | {d['value']:.0f} [{d['ci95'][0]:.0f}, {d['ci95'][1]:.0f}] | {p['p_value']:.3g} | "
                     f"{'n/a' if shift is None else format(shift, '+.0f')} |")
    if shifts:
        top = max(shifts, key=lambda m: abs(shifts[m]))
        lines += ["", f"The component alone that moves the primary comparison most from the ideal world's: {top} "
                  f"({shifts[top]:+.0f} s)."]
    if bench:
        lines += ["", "Benchmark primary (RMST ratio semantics+rooms / olfaction, right ontology, nested bootstrap):",
                  "", "| world model | ratio [95 % CI] | episodes | homes |", "|---|---|---|---|"]
        for model, b in bench.items():
            r = b["primary"]["result"]
            if r is not None:
                lines.append(f"| {model} | {r['value']:.3f} [{r['ci95'][0]:.3f}, {r['ci95'][1]:.3f}] | {r['n']} | "
                             f"{r['houses']} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--first-seed", type=int, default=100)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--models", nargs="+", default=None)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--recalibrated", action="append", default=[], metavar="MODEL=D,TAU,KAPPA,BETA")
    ap.add_argument("--benchmark-homes", type=int, default=0)
    ap.add_argument("--benchmark-seeds", type=int, default=2)
    ap.add_argument("--end", choices=("declare", "reach"), default="declare",
                    help="how the runs end (psgsl search --end; default: %(default)s)")
    args = ap.parse_args(argv)
    names = args.models or models()
    args.out.mkdir(parents=True, exist_ok=True)
    results = {m: run_search(args.out, m, first_seed=args.first_seed, seeds=args.seeds, workers=args.workers,
                             end=args.end) for m in names}
    for item in args.recalibrated:
        model, _, values = item.partition("=")
        plume = tuple(float(v) for v in values.split(","))
        if len(plume) != 4:
            ap.error(f"--recalibrated takes MODEL=D,TAU,KAPPA,BETA, got {item!r}")
        results[f"{model}, recalibrated"] = run_recalibrated(args.out, model, plume, first_seed=args.first_seed,
                                                             seeds=args.seeds, workers=args.workers, end=args.end)
    bench = {m: run_benchmark(args.out, m, homes=args.benchmark_homes, seeds=args.benchmark_seeds,
                              workers=args.workers, end=args.end) for m in names} if args.benchmark_homes else {}
    version = subprocess.run(["git", "describe", "--always", "--dirty"], capture_output=True, text=True,
                             cwd=Path(__file__).parent).stdout.strip() or "unknown"
    text = report(args.out, results, bench, first_seed=args.first_seed, seeds=args.seeds, version=version)
    for name, data in (("costs.md", text), ("costs.json", json.dumps({"search": results, "benchmark": bench,
                                                                       "version": version}, indent=1))):
        tmp = args.out / (name + ".partial")
        tmp.write_text(data)
        os.replace(tmp, args.out / name)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
