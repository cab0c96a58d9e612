"""Simulated-house performance (not a test): the 550 s house simulation of the issue, and ratios to
baselines measured in the same run.

* ``gas 550 s``: default house, perturbed potential flow, smoke from the oven, 5500 filament steps at
  dt = 0.1 s (10 filaments/s) — the issue's target is <= 10 s on one core;
* ``gas + sensor 550 s``: the same, plus one concentration query per step at a robot moving along a path
  through kitchen, living room and hallway (what the experiment does);
* per-step cost of the full filament step (wind lookup, noise, wall/outlet checks) vs the bare NumPy
  advection ``x + u(x) dt + noise`` of the same population (the lower bound);
* per-query cost with the line-of-sight cache (cold: a new sensor cell; warm: the sensor cell seen before,
  as while the robot stands still) vs exact line of sight recomputed for every filament;
* setup: house, wind (60 snapshots), one camera frame + belief update.

Run: ``python benchmarks/bench_sim.py [--seconds 550] [--repeats 3]``. Best of several repeats, on an
otherwise idle machine (pin one core with ``taskset -c 0`` for the one-core figure).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from psgsl_pgm.sim import (
    Camera,
    DetectorModel,
    FilamentModel,
    SemanticMap,
    cells_clear,
    default_house,
    make_wind,
    take_frame,
)


def best_of(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def robot_path(n):
    """Waypoints kitchen -> living room -> hallway, sampled at n steps (x, y in metres)."""
    way = np.array([[8.5, 2.0], [7.5, 4.2], [6.2, 4.1], [4.0, 3.0], [2.5, 4.5], [2.5, 6.0], [8.0, 6.0]])
    seg = np.linalg.norm(np.diff(way, axis=0), axis=1)
    s = np.linspace(0, seg.sum(), n)
    cum = np.concatenate([[0], np.cumsum(seg)])
    i = np.minimum(np.searchsorted(cum, s, side="right") - 1, len(seg) - 1)
    t = ((s - cum[i]) / seg[i])[:, None]
    return way[i] * (1 - t) + way[i + 1] * t


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=550.0)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    steps = int(round(args.seconds / 0.1))

    t_house = best_of(lambda: default_house(0), args.repeats)
    house = default_house(0)
    t_wind = best_of(lambda: make_wind(house.grid, house.inlet, house.outlet, duration=600.0, seed=0), args.repeats)
    wind = make_wind(house.grid, house.inlet, house.outlet, duration=600.0, seed=0)
    source = house.objects_of_class("oven")[0].center
    path = robot_path(steps)

    def gas_only():
        gas = FilamentModel(house.grid, wind, source, outlet=house.outlet, seed=0)
        gas.step(steps)
        return gas

    def gas_and_sensor():
        gas = FilamentModel(house.grid, wind, source, outlet=house.outlet, seed=0)
        for k in range(steps):
            gas.step()
            gas.concentration(path[k])
        return gas

    t_gas = best_of(gas_only, args.repeats)
    t_both = best_of(gas_and_sensor, args.repeats)
    gas = gas_only()

    # per step: full step vs bare advection, on the population reached at the end of the run
    def full_steps():
        g = FilamentModel(house.grid, wind, source, outlet=house.outlet, seed=1)
        g.positions, g.births, g._cells = gas.positions.copy(), gas.births.copy(), gas._cells.copy()
        g.time, g._step, g.n_released = gas.time, gas._step, gas.n_released
        g.step(200)

    vel = wind.velocities[0]
    rng = np.random.default_rng(0)

    def bare_steps():
        x = gas.positions.copy()
        for _ in range(200):
            c = house.grid.world_to_cell(x)
            c = np.clip(c, 0, np.array(house.shape) - 1)
            x = x + vel[c[:, 0], c[:, 1]] * 0.1 + rng.normal(0, 0.02, x.shape)

    t_full = best_of(full_steps, args.repeats) / 200
    t_bare = best_of(bare_steps, args.repeats) / 200

    # per query: cached vs exact line of sight recomputed each time
    queries = path[::50]

    def cached():
        gas._los._tables.clear()
        for q in queries:
            gas.concentration(q)

    p = gas.params

    def uncached():
        s2 = p.sigma0**2 + p.gamma * (gas.time - gas.births)
        for q in queries:
            d2 = ((gas.positions - q) ** 2).sum(axis=1)
            near = np.flatnonzero(d2 < p.cutoff**2 * s2)
            qc = house.grid.world_to_cell(q)
            ok = cells_clear(house.grid.occupancy, np.broadcast_to(qc, (near.size, 2)), gas._cells[near])
            near = near[ok]
            np.sum(p.ppm_center * (p.sigma0**2 / s2[near]) ** 1.5 * np.exp(-d2[near] / (2 * s2[near])))

    def warm():
        for q in queries:
            gas.concentration(q)

    t_cached = best_of(cached, args.repeats) / len(queries)
    cached()
    t_warm = best_of(warm, args.repeats) / len(queries)
    t_uncached = best_of(uncached, args.repeats) / len(queries)

    det = DetectorModel.default()
    cam = Camera()
    prior = np.full(len(det.classes), 0.3 / (len(det.classes) - 1))
    prior[-1] = 0.7
    smap = SemanticMap.from_prior(house.shape, prior, det.classes)
    frng = np.random.default_rng(0)

    def frame():
        smap.update(take_frame(house, (7.6, 3.8, -np.pi / 2), camera=cam, detector=det, rng=frng))

    t_frame = best_of(frame, args.repeats)

    print(f"simulated time {args.seconds:g} s = {steps} steps at dt 0.1 s; {gas.n_released} filaments released, "
          f"{gas.n_filaments} alive at the end ({gas.n_removed} left by the outlet)")
    print(f"  gas {args.seconds:g} s:               {t_gas:7.2f} s   (target <= 10 s)")
    print(f"  gas + sensor {args.seconds:g} s:      {t_both:7.2f} s   ({steps} concentration queries)")
    print(f"  filament step:          {t_full * 1e3:7.3f} ms = {t_full / t_bare:5.1f} x bare advection "
          f"({t_bare * 1e3:.3f} ms, {gas.n_filaments} filaments)")
    print(f"  concentration query:    {t_warm * 1e3:7.3f} ms warm / {t_cached * 1e3:.3f} ms cold LOS cache = "
          f"{t_uncached / t_warm:5.1f} x / {t_uncached / t_cached:.1f} x faster than exact LOS for every filament "
          f"({t_uncached * 1e3:.3f} ms)")
    print(f"  setup: house {t_house * 1e3:.1f} ms, wind (60 snapshots) {t_wind * 1e3:.1f} ms, "
          f"camera frame + belief update {t_frame * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
