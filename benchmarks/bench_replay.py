"""Replaying a robot's bag vs simulating the same episode: a ratio measured in one run (not a test).

The episode: the robot follows the embedded house's exploration tour at 0.25 m/s (back and forth) for
``--minutes`` of simulated time, with a gas reading (one 0.1 s sensor window) and an anemometer reading at 10 Hz
and a camera frame at 1 Hz, and the experiment's per-step work after every reading (the three variants'
posteriors, their error, spread and 90 % region). Two timings:

* **simulate**: the simulator produces the readings and frames (filaments, sensor, camera) while the robot's
  beliefs are updated, as ``psgsl experiment`` does per stop;
* **replay**: the same episode, recorded as a ROS 2 bag (MCAP storage; 10 Hz /tf, gas and wind, 1 Hz
  Detection3DArray), read back and run through the same per-step code (``psgsl_pgm.experiment._replay.replay``).

The final posteriors of the two are compared (they must agree to 1e-12) and the ratio replay / simulate is
printed. Both are CPU times of this process (``time.process_time``): on a shared machine wall time measures the
neighbours. Run: ``python benchmarks/bench_replay.py [--minutes 20] [--seed 0]``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from psgsl_pgm.experiment import VARIANTS, ExperimentConfig, exploration_tour
from psgsl_pgm.experiment._record import EpisodeRecorder
from psgsl_pgm.experiment._replay import replay
from psgsl_pgm.experiment._run import step_metrics
from psgsl_pgm.experiment._step import VariantPosteriors
from psgsl_pgm.ros import write_bag
from psgsl_pgm.sim import default_world


def _path_at(tour, speed, t):
    """Position and heading on the tour path (back and forth) at times ``t``."""
    path = np.vstack([tour.path, tour.path[::-1][1:]])
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    s = (speed * np.asarray(t)) % arc[-1]
    i = np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(seg) - 1)
    f = np.where(seg[i] > 0, (s - arc[i]) / np.where(seg[i] > 0, seg[i], 1), 0.0)
    xy = path[i] + f[:, None] * (path[i + 1] - path[i])
    d = path[i + 1] - path[i]
    return xy, np.arctan2(d[:, 1], d[:, 0])


def simulate(seconds: float, seed: int, config: ExperimentConfig):
    spec = default_world()
    world = spec.make_world(seed, "oven", warm_up=config.warm_up)
    rec = EpisodeRecorder()
    watched = rec.watch(world)
    house = world.house
    tour = exploration_tour(house, start=spec.start_for(house))
    n = round(seconds * 10)
    xy, heading = _path_at(tour, config.speed, np.arange(n) * 0.1)
    t0 = time.process_time()
    beliefs = VariantPosteriors(watched, "infotaxis", config, setting=spec)
    centres, truth = house.grid.cell_centres(), world.source
    cell = int(np.ravel_multi_index(tuple(house.grid.world_to_cell(truth)), house.shape))
    post = beliefs.posteriors(VARIANTS)
    step_metrics(post, centres, truth, cell, house.grid.resolution**2)
    for k in range(n):
        reading = watched.sense_gas(xy[k], duration=0.1)  # one 0.1 s window: 10 Hz
        wind = watched.sense_wind(xy[k])
        frames = [watched.camera_frame((xy[k, 0], xy[k, 1], heading[k]))] if k % 10 == 0 else []  # 1 Hz
        beliefs.observe(xy[k], reading, wind, frames)
        post = beliefs.posteriors(VARIANTS)
        step_metrics(post, centres, truth, cell, house.grid.resolution**2)
    elapsed = time.process_time() - t0
    meta = {"source": "oven", "seed": seed, "estimator": "infotaxis", "config": config.to_dict()}
    return elapsed, rec.episode(variants=VARIANTS, meta=meta), post


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=20.0)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    config = ExperimentConfig()
    # warm both paths once (kernel compilation, the robot's detector model) on a 10 s episode
    with tempfile.TemporaryDirectory() as tmp:
        _, ep, _ = simulate(10.0, args.seed, config)
        replay(write_bag(Path(tmp) / "warm.bag", ep))
        t_sim, ep, post = simulate(args.minutes * 60, args.seed, config)
        t = time.perf_counter()
        bag = write_bag(Path(tmp) / "episode.bag", ep)
        t_write = time.perf_counter() - t
        t = time.process_time()
        res = replay(bag)
        t_replay = time.process_time() - t
        size = sum(p.stat().st_size for p in bag.iterdir())
    diff = float(np.max(np.abs(res.final - post) / np.maximum(np.abs(post), 1e-300)))
    print(f"episode: {args.minutes:g} min, {len(ep.gas)} gas and wind readings (10 Hz), {len(ep.frame_t)} camera "
          f"frames (1 Hz), bag {size / 1e6:.1f} MB (written in {t_write:.1f} s)")
    print(f"CPU time of this process: simulate + estimate {t_sim:.1f} s; read bag + estimate {t_replay:.1f} s; "
          f"ratio replay / simulate = {t_replay / t_sim:.2f} (target <= 2)")
    print(f"final posteriors, replay vs simulation: max relative difference {diff:.1e}")


if __name__ == "__main__":
    main()
