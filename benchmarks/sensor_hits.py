"""What the gas sensor changes: the robot's hits along the exploration tour and the closed loop's success, with the
ideal GasSensor, a MOXSensor and a PIDSensor on the same seeds (not a test).

The gas of a seed does not depend on the sensor (the sensor draws from its own random stream), so the ideal
sensor's reading — the window mean of the true concentration, no lag, no noise — is the concentration the other
two sensors were exposed to at the same stop. Per sensor:

* along the full exploration tour of the embedded house (oven source): stops, hits, hits where the ideal sensor
  hits (c ≥ 1 ppm), hits where 0 < c < 1 ppm, hits in clean air (c = 0); for the MOX, the ideal's hits it misses
  and how many of those with a falling response (least-squares slope of the window's samples ≤ 0);
* with ``--loop``: the closed loop (policy infotaxis, estimator infotaxis) for the variants given, found / runs
  and the mean time to find (the budget for a run that did not), at the estimators' missed-hit rates given.

Run: ``python benchmarks/sensor_hits.py [--seeds 10] [--loop] [--variants olfaction semantics+rooms]
[--missed-hit-rates 0 0.3]``. Seeds 0–9 give the numbers on the simulated-house guide page.
"""

from __future__ import annotations

import argparse

import numpy as np

from psgsl_pgm.experiment import ExperimentConfig
from psgsl_pgm.experiment._run import walk
from psgsl_pgm.experiment._tour import exploration_tour
from psgsl_pgm.sim import MOXSensor, PIDSensor, make_world

SENSORS = {"ideal": lambda: None, "mox": MOXSensor, "pid": PIDSensor}


def _slope(trace) -> float:
    i = np.arange(trace.size) - (trace.size - 1) / 2.0
    return float(i @ trace)


def tour_hits(seeds, *, stops: int | None = None, warm_up: float = 60.0) -> dict:
    """{sensor: counts summed over ``seeds``} along the exploration tour (its first ``stops`` stops if given)."""
    config = ExperimentConfig()
    out = {name: dict.fromkeys(("stops", "hits", "ideal", "below", "clean", "missed", "falling"), 0)
           for name in SENSORS}
    for seed in seeds:
        readings = {}
        for name, make in SENSORS.items():
            world = make_world(seed=int(seed), source="oven", warm_up=warm_up, gas_sensor=make())
            tour = exploration_tour(world.house)
            if stops is not None:
                tour = tour.first(stops)
            readings[name] = [r for _, _, r, _, _ in walk(world, tour, config, camera=False)]
        c = np.array([r.value for r in readings["ideal"]])  # the window-mean concentration at each stop, ppm
        for name, rs in readings.items():
            hit = np.array([r.hit for r in rs], dtype=bool)
            row = out[name]
            row["stops"] += hit.size
            row["hits"] += int(hit.sum())
            row["ideal"] += int((hit & (c >= 1.0)).sum())
            row["below"] += int((hit & (c > 0) & (c < 1.0)).sum())
            row["clean"] += int((hit & (c == 0)).sum())
            missed = (c >= 1.0) & ~hit
            row["missed"] += int(missed.sum())
            if name != "ideal":
                row["falling"] += sum(_slope(rs[j].trace) <= 0 for j in np.flatnonzero(missed))
    return out


def closed_loop(seeds, variants, missed_hit_rates) -> list:
    """Rows (sensor, variant, δ, found, runs, mean time to find) of the closed loop on ``seeds``."""
    from psgsl_pgm.search import run_closed_loop

    rows = []
    for delta in missed_hit_rates:
        config = ExperimentConfig(missed_hit_rate=float(delta))
        for variant in variants:
            for name, make in SENSORS.items():
                found, times = 0, []
                for seed in seeds:
                    world = make_world(seed=int(seed), source="oven", warm_up=config.warm_up, gas_sensor=make())
                    run = run_closed_loop("oven", int(seed), "infotaxis", variant, world=world, config=config)
                    found += bool(run.found)
                    times.append(run.time_to_find)
                rows.append((name, variant, float(delta), found, len(seeds), float(np.mean(times))))
    return rows


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--loop", action="store_true")
    p.add_argument("--variants", nargs="+", default=["olfaction", "semantics+rooms"])
    p.add_argument("--missed-hit-rates", nargs="+", type=float, default=[0.0])
    a = p.parse_args(argv)
    seeds = range(a.seeds)
    counts = tour_hits(seeds)
    print("sensor  stops  hits  at c>=1  at 0<c<1  at c=0  missed (c>=1)  of them falling")
    for name, r in counts.items():
        falling = r["falling"] if name != "ideal" else "-"
        print(f"{name:6s} {r['stops']:6d} {r['hits']:5d} {r['ideal']:8d} {r['below']:9d} {r['clean']:7d} "
              f"{r['missed']:14d} {falling!s:>16s}")
    if a.loop:
        print("\nsensor  variant          delta  found  mean time to find (s)")
        for name, variant, delta, found, n, t in closed_loop(seeds, a.variants, a.missed_hit_rates):
            print(f"{name:6s} {variant:16s} {delta:5.2f}  {found:2d}/{n:<2d}  {t:7.1f}")


if __name__ == "__main__":
    main()
