"""Why the closed-loop runs of a benchmark folder that did not find their source missed it.

For every run of the chosen policies that did not find its source, from the run's stops and final belief
(``position``, ``final_posterior`` of ``runs/*.npz``) and the home's geometry:

* **limit cycle** — the last 30 stops lie at three positions or fewer (then also: the time from the first stop of
  the final cycle to the last decision, and the share of hits among the cycle's readings);
* **P_f reachable** — the largest probability of finding the source, P_f(p) = (1 − m) Σ_{c found at p} p(c)
  (:class:`psgsl_pgm.search.DetectionModel`), over every drivable cell reachable from the last stop;
* **P_f candidates** — the same over the candidates of the last decision, made at the last stop but one (the
  last stop is the one it chose, reached at the budget): :meth:`FreeSpace.candidates` with the finder cells of
  :meth:`FreeSpace.cover`, the default :class:`psgsl_pgm.search.SearchConfig`, under the final belief;
* **V_now** — space-aware infotaxis's value at the last stop (``_SpaceAware.value`` of
  ``psgsl_pgm.search._policies``, from the expected geodesic distance past the found radius and the entropy H in
  bits), 0 for a belief the last stop would find and positive otherwise;
* **unfindable mass** — the share of the final belief on hypotheses that no drivable cell reachable from the last
  stop finds at all (behind furniture, in a gap narrower than the robot): no stop can rule them out, so this
  mass stays in the belief whatever the robot does;
* **source ruled out** — the first stop at which the posterior put the true source at an HPD
  level ≥ 0.9999, its time and its distance from the source (below).

A run counts as *blind* when some reachable cell would find more than half of the belief's mass while no
candidate finds more than 0.1 of it, and as *refused* when a candidate would find at least half of it.

Then, over every run of those policies (found or not), per policy and variant: the runs whose posterior put the
true source at an HPD level of at least 0.9999 at some stop (the belief before the first reading, the prior, is
left out: its flat cells all sit at level 1) — the source all but ruled out — how many of them were found, how many
still had it there at the end, and the median distance of the robot's closest approach to the source up to that
stop.

Usage::

    python benchmarks/bench_misses.py bench-50x5                       # generated homes (OUT/houses/*/world.yaml)
    python benchmarks/bench_misses.py bench-B --world house_B/world.yaml  # one world file
    python benchmarks/bench_misses.py closed-loop-analytic-plume --world psgsl_pgm/data/worlds/house.yaml  # psgsl search
"""

from __future__ import annotations

import argparse
import collections
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from scipy.special import entr

from psgsl_pgm.search import DetectionModel, FreeSpace, SearchConfig
from psgsl_pgm.search._policies import _SpaceAware
from psgsl_pgm.sim import Camera, load_world

CYCLE_STOPS = 30  # the stops a limit cycle is judged on
CYCLE_POSITIONS = 3  # at most this many distinct positions among them


def classify(npz: Path, space: FreeSpace, detection: DetectionModel, search: SearchConfig) -> dict:
    """The measures of the module docstring for one run that did not find its source."""
    z = np.load(npz)
    post = z["final_posterior"].ravel()
    stops = z["position"][:, :2]
    last = space.snap(stops[-1])
    dist = space.distances(last)
    reach = np.flatnonzero(space.nav.ravel() & np.isfinite(dist))
    decided = space.snap(stops[-2]) if len(stops) > 1 else last  # where the last decision was made
    cells, _, _ = space.candidates(decided, search.horizon, search.far_spacing)

    def p_f(cells):  # the policies' P_f (DetectionModel.found_probability)
        return detection.found_probability(post, detection.cell_rows(cells, space.centres[cells]))

    ok = np.isfinite(dist)
    # the space-aware policy's own value (_SpaceAware.value reads only ℓ and the bits of one found disc)
    scale = SimpleNamespace(ell=2.0 * search.found_radius,
                            disc_bits=np.log2(np.pi * search.found_radius**2 / space.resolution**2))
    past = np.maximum(dist[ok] - search.found_radius, 0.0)  # the distance past the found radius
    v_now = float(_SpaceAware.value(scale, float(post[ok] @ past), float(entr(post).sum() / np.log(2))))
    findable = space.findable(detection, last)  # found from some drivable cell reachable from the last stop
    positions = {tuple(np.round(p, 3)) for p in stops[-CYCLE_STOPS:]}
    cycle = len(positions) <= CYCLE_POSITIONS
    first = len(stops) - 1  # the final cycle: the longest run of stops, up to the last decision, among its positions
    while cycle and first > 1 and tuple(np.round(stops[first - 1], 3)) in positions:
        first -= 1
    return {
        "cycle": cycle,
        "cycle_time": float(z["time"][-2] - z["time"][first]) if cycle else 0.0,
        "cycle_hits": float(z["hit"][first:-1].mean()) if cycle else 0.0,
        "pf_reach": float(p_f(reach).max()),
        "pf_cand": float(p_f(cells).max()),
        "v_now": v_now,
        "unfindable": float(post[~findable].sum()),
    }


RULED_OUT = 0.9999  # an HPD level of the true source at which the posterior has all but excluded it


def ruled_out(run) -> tuple | None:
    """(found, still ruled out at the end, closest approach up to then (m), the stop, its time (s), its distance
    from the source (m)) of a run whose posterior put the true source at an HPD level ≥ :data:`RULED_OUT` at some
    stop (the prior before the first reading left out); None otherwise."""
    level = run["hpd_level"][1:]
    if level.size == 0 or level.max() < RULED_OUT:
        return None
    i = int(np.argmax(level >= RULED_OUT)) + 1
    d = np.linalg.norm(run["position"][: i + 1, :2] - run["source_xy"], axis=1)
    return bool(run["found"]), bool(level[-1] >= RULED_OUT), float(d.min()), i, float(run["time"][i]), float(d[i])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path, help="a psgsl benchmark or psgsl search output folder")
    ap.add_argument("--world", type=Path, help="the world file of a one-world benchmark or of a psgsl search folder "
                    "(the embedded house: psgsl_pgm/data/worlds/house.yaml; default: OUT/houses)")
    ap.add_argument("--policies", nargs="+", default=["infotaxis", "space-aware-infotaxis"])
    args = ap.parse_args(argv)
    search = SearchConfig()
    geometry = {}
    counts = collections.Counter()
    excluded = collections.defaultdict(list)
    for npz in sorted((args.out / "runs").glob("*.npz")):
        run = np.load(npz)
        policy = str(run["policy"])  # stored with the run: benchmark and search folders name their files differently
        if policy not in args.policies:
            continue
        arm = policy, str(run["variant"])
        excluded[arm].append(ruled_out(run))
        if bool(run["found"]):
            continue
        home = "world" if args.world is not None else npz.name.split("__")[0]  # a benchmark run file: home first
        seed = int(run["seed"])  # the embedded house's furniture varies with the seed (a world file's does not)
        if (home, seed) not in geometry:
            world = args.world if args.world is not None else args.out / "houses" / home / "world.yaml"
            house = load_world(world).house(seed)
            space = FreeSpace(house, Camera(), clearance=search.clearance, spacing=search.spacing,
                              n_headings=search.n_headings)
            detection = DetectionModel.from_house(house, search.found_radius,
                                                  miss_probability=search.miss_probability or 0.0)
            space.cover(detection)
            geometry[home, seed] = space, detection
        m = classify(npz, *geometry[home, seed], search)
        kind = ("refused" if m["pf_cand"] >= 0.5 else
                "blind" if m["pf_reach"] > 0.5 and m["pf_cand"] <= 0.1 else "spread")
        counts[policy, "limit cycle" if m["cycle"] else "moving", kind] += 1
        out = ruled_out(run)
        print(f"{npz.stem}: cycle {m['cycle']}"
              + (f" (its last {m['cycle_time']:.0f} s, hits {m['cycle_hits']:.2f})" if m["cycle"] else "")
              + f", P_f reachable {m['pf_reach']:.3f}, candidates {m['pf_cand']:.3f}, V_now {m['v_now']:.2f}, "
              f"unfindable mass {m['unfindable']:.3f}, source ruled out "
              + ("never" if out is None else f"from stop {out[3]} ({out[4]:.1f} s, {out[5]:.2f} m from the source)"))
    print("\n| policy | end | belief | runs |\n|---|---|---|---|")
    for (policy, end, kind), n in sorted(counts.items()):
        print(f"| {policy} | {end} | {kind} | {n} |")
    print(f"\n| policy / variant | runs | source at HPD level ≥ {RULED_OUT} | of them found | "
          "still there at the end | closest approach before, median m |\n|---|---|---|---|---|---|")
    for (policy, variant), rows in sorted(excluded.items()):
        hit = [r for r in rows if r is not None]
        near = f"{np.median([r[2] for r in hit]):.2f}" if hit else "–"
        print(f"| {policy}/{variant} | {len(rows)} | {len(hit)} | {sum(r[0] for r in hit)} | "
              f"{sum(r[1] for r in hit)} | {near} |")


if __name__ == "__main__":
    main()
