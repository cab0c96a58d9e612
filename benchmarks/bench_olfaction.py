"""Olfactory estimators: factorisation and update times vs grid size, as ratios to one sparse solve.

For house-like grids (rooms separated by walls with doors, an outlet, a uniform draught) of growing size:

* ``factor``: operator assembly + sparse LU (``PlumeModel`` construction);
* ``solve``: one adjoint solve ``splu(A).solve(e_x, trans="T")`` — the baseline;
* Infotaxis update at a new sensor cell (one solve + likelihood + normalisation) and at a cached one;
* analytic-plume (PMFS-family) update at a new cell after 50 earlier stops (hit-map kernel, Dijkstra, score over K = 51 cells);
* information gain for 20 candidate positions (cached).

Run: ``python benchmarks/bench_olfaction.py [--sizes 50x60 100x120 200x240] [--repeats 5]``. Best of several
repeats; run on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from psgsl_pgm.olfaction import GridInfotaxis, PlumeModel, PMFSEstimator

RES = 0.1


def best_of(fn, repeats, setup=None):
    times = []
    for _ in range(repeats):
        state = setup() if setup else None
        t0 = time.perf_counter()
        fn(state)
        times.append(time.perf_counter() - t0)
    return min(times)


def house(h, w):
    """Border walls, a 3 x 3 grid of rooms with 1 m doors, an outlet window, a uniform 0.1 m/s draught."""
    occ = np.zeros((h, w), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    for k in (1, 2):
        r, c = k * h // 3, k * w // 3
        occ[r, :] = True
        occ[:, c] = True
        for j in range(3):  # one door per wall segment
            mid_c, mid_r = (2 * j + 1) * w // 6, (2 * j + 1) * h // 6
            occ[r, mid_c - 5 : mid_c + 5] = False
            occ[mid_r - 5 : mid_r + 5, c] = False
    outlets = np.zeros_like(occ)
    outlets[h // 6 - 5 : h // 6 + 5, -1] = True
    occ[outlets] = False
    wind = np.zeros((h, w, 2))
    wind[..., 0] = 0.1
    return occ, wind, outlets


def free_positions(occ, n, rng):
    cells = np.argwhere(~occ)
    pick = cells[rng.choice(len(cells), size=n, replace=False)]
    return (pick[:, ::-1] + 0.5) * RES


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", nargs="+", default=["50x60", "100x120", "200x240"])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    print(f"best of {args.repeats}; times in ms; ratios relative to one adjoint solve of the same grid")
    head = (f"{'grid':>9} {'cells':>7} {'factor':>8} {'solve':>7} | {'inf new':>8} {'ratio':>6} | {'inf cached':>10} "
            f"{'ratio':>6} | {'pmfs new':>8} {'ratio':>6} | {'gain x20':>8}")
    print(head)
    for size in args.sizes:
        h, w = (int(v) for v in size.split("x"))
        occ, wind, outlets = house(h, w)
        kw = dict(resolution=RES, wind=wind, outlets=outlets, diffusivity=0.03, lifetime=20.0)
        t_factor = best_of(lambda _: PlumeModel(occ, **kw), args.repeats)
        model = PlumeModel(occ, **kw)
        n = model.operator.shape[0]
        idx = model.active_index[~occ & ~outlets]

        def one_solve(j):
            e = np.zeros(n)
            e[j] = 1.0
            model.factor.solve(e, trans="T")

        t_solve = best_of(one_solve, args.repeats, setup=lambda: int(rng.choice(idx)))
        positions = free_positions(occ, 400, rng)
        it = iter(range(len(positions)))

        def fresh_infotaxis():
            m = PlumeModel(occ, **kw)
            return GridInfotaxis.from_model(m), positions[next(it) % len(positions)]

        t_new = best_of(lambda s: s[0].update(s[1], True), args.repeats, setup=fresh_infotaxis)
        est = GridInfotaxis.from_model(model)
        est.update(positions[0], True)
        t_cached = best_of(lambda _: est.update(positions[0], False), args.repeats)

        def pmfs_after_50():
            m = PlumeModel(occ, **kw)
            p = PMFSEstimator.from_model(m)
            hits = rng.random(50) < 0.3
            for x, g in zip(positions[:50], hits):
                p.update(x, g)
            return p, positions[50 + rng.integers(300)]

        t_pmfs = best_of(lambda s: s[0].update(s[1], True), args.repeats, setup=pmfs_after_50)
        cand = positions[:20]
        est.information_gain(cand)  # fill the cache
        t_gain = best_of(lambda _: est.information_gain(cand), args.repeats)
        print(
            f"{size:>9} {int((~occ).sum()):7d} {t_factor * 1e3:8.1f} {t_solve * 1e3:7.2f} | {t_new * 1e3:8.2f} "
            f"{t_new / t_solve:6.1f} | {t_cached * 1e3:10.2f} {t_cached / t_solve:6.2f} | {t_pmfs * 1e3:8.2f} "
            f"{t_pmfs / t_solve:6.1f} | {t_gain * 1e3:8.2f}"
        )


if __name__ == "__main__":
    main()
