"""
A PPO agent on the gymnasium environment
========================================

Train a PPO agent on ``psgsl/House-v0`` and compare it with infotaxis on held-out generated homes.

The agent (stable-baselines3 PPO, ``MultiInputPolicy`` on the environment's Dict observation, normalised with
``VecNormalize``) trains for ``--minutes`` of wall-clock time (at most 30) on development homes 0 … ``--houses``−1;
then it and infotaxis search the same held-out episodes: the first ``--eval-houses`` test homes with the first
``--eval-seeds`` test seeds each (:mod:`psgsl_pgm.search._split`), the same world, source, gas, variant, estimator
and time budget. Reported for both: the success rate (a right declaration) and the RMST of the time to a right
declaration, censored at the budget (:func:`psgsl_pgm.search._survival.rmst`). A third rule, the first slot at
every step (the candidate of the most P_f per second, no learning), shows what the agent adds to its action space.

Needs the ``rl`` extra (``pip install ".[rl]"``)::

    nice python examples/train_ppo.py --minutes 5 --out ppo.json

Not part of the example gallery (it trains for minutes); docs/guide/gym.md holds a result.
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np


def _cpu() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=30.0, help="wall-clock minutes of training, at most 30")
    ap.add_argument("--houses", type=int, default=50, help="development homes to train on")
    ap.add_argument("--eval-houses", type=int, default=5, help="test homes to evaluate on")
    ap.add_argument("--eval-seeds", type=int, default=2, help="test seeds per test home")
    ap.add_argument("--budget", type=float, default=1000.0, help="time budget of an episode, s")
    ap.add_argument("--variant", default="semantics+rooms")
    ap.add_argument("--threads", type=int, default=2, help="torch threads (the machine's cores)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None, help="write the result as JSON here")
    args = ap.parse_args(argv)
    if not 0 < args.minutes <= 30:
        ap.error(f"--minutes must lie in (0, 30], got {args.minutes}")

    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from psgsl_pgm.gym import HouseEnv
    from psgsl_pgm.search import SearchConfig, run_closed_loop
    from psgsl_pgm.search._split import benchmark_sample
    from psgsl_pgm.search._survival import rmst

    torch.set_num_threads(args.threads)
    search = SearchConfig(time_budget=args.budget)
    common = {"variant": args.variant, "search": search}

    class WallClock(BaseCallback):
        def __init__(self, seconds):
            super().__init__()
            self.seconds, self.t0, self.episodes = seconds, time.monotonic(), 0

        def _on_step(self) -> bool:
            self.episodes += int(np.sum(self.locals["dones"]))
            return time.monotonic() - self.t0 < self.seconds

    boxes = ["gas", "wind", "pose", "time", "belief", "candidates"]  # every key but the hit (Discrete)
    venv = VecNormalize(DummyVecEnv([lambda: HouseEnv(houses=args.houses, **common)]), norm_reward=False,
                        norm_obs_keys=boxes)
    venv.seed(args.seed)
    model = PPO("MultiInputPolicy", venv, n_steps=256, batch_size=64, n_epochs=4, seed=args.seed, verbose=0,
                device="cpu")
    clock = WallClock(60.0 * args.minutes)
    t0, c0 = time.monotonic(), time.process_time()
    model.learn(total_timesteps=10**9, callback=clock)
    trained = {"minutes": (time.monotonic() - t0) / 60.0, "cpu_minutes": (time.process_time() - c0) / 60.0,
               "timesteps": int(model.num_timesteps), "episodes": clock.episodes}
    venv.training = False

    houses, seeds = benchmark_sample("test", houses=args.eval_houses, seeds=args.eval_seeds)
    env = HouseEnv(split="test", houses=args.eval_houses, seeds=args.eval_seeds, **common)
    rows = []
    for h in houses:
        for s in seeds:
            setting = env.episode_setting(house=h, seed=s)
            run = run_closed_loop(setting["source"], s, "infotaxis", args.variant, "infotaxis",
                                  config=setting["config"], search=search, world_spec=setting["world_spec"])
            row = {"house": h, "seed": s, "source": list(setting["source"]),
                   "infotaxis": [run.succeeded, run.time_to_success, bool(run.declared)]}
            for name in ("ppo", "slot-0"):
                obs, info = env.reset(seed=args.seed, options={"house": h, "seed": s})
                done = False
                while not done:
                    if name == "ppo":
                        batch = venv.normalize_obs({k: np.asarray(v)[None] for k, v in obs.items()})
                        action, _ = model.predict(batch, deterministic=True)
                        action = int(np.asarray(action).ravel()[0])
                    else:  # the untrained reference: always the first slot (the most P_f per second)
                        action = 0
                    obs, _, term, trunc, info = env.step(action)
                    done = term or trunc
                agent = env.episode_run()
                row[name] = [agent.succeeded, agent.time_to_success, bool(agent.declared)]
            rows.append(row)
            print(rows[-1], flush=True)

    def summary(name):
        ok = np.array([r[name][0] for r in rows])
        t = np.array([r[name][1] for r in rows])
        r = rmst(t, ok, args.budget)
        return {"success": float(ok.mean()), "rmst": r["value"], "rmst_ci95": r["ci95"],
                "declared": float(np.mean([r[name][2] for r in rows]))}

    result = {"trained": trained, "cpu": _cpu(), "torch_threads": args.threads, "budget": args.budget,
              "variant": args.variant, "train_houses": args.houses, "eval_houses": list(houses),
              "eval_seeds": list(seeds), "ppo": summary("ppo"), "infotaxis": summary("infotaxis"),
              "slot-0": summary("slot-0"), "episodes": rows}
    print(json.dumps({k: v for k, v in result.items() if k != "episodes"}, indent=1))
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(result, fh, indent=1)
    return result


if __name__ == "__main__":
    main()
