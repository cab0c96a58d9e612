"""benchmarks/bench_misses.py reads each miss in the house of its own seed (the embedded house's furniture
varies with the seed) and reports the belief's mass that no stop can find."""

import numpy as np

from ._scripts import ROOT, load_script


def _script():
    return load_script("bench_misses")


def test_a_miss_is_classified_in_the_house_of_its_seed(tmp_path, capsys):
    from psgsl_pgm.sim import load_world

    world = ROOT / "psgsl_pgm" / "data" / "worlds" / "house.yaml"
    house = load_world(world).house(102)
    grid = house.grid
    post = np.zeros(house.shape, np.float32)
    # between the dining table and its chairs in seed 102's house: free, but no drivable cell within 0.5 m
    r, c = (int((v - o) / grid.resolution) for v, o in ((3.45, grid.origin[1]), (7.55, grid.origin[0])))
    assert grid.free[r, c]
    post[r, c] = 1.0
    runs = tmp_path / "runs"
    runs.mkdir()
    level = np.full(40, 0.5)
    level[[0, 31]] = 1.0, 0.99995  # the prior (flat: level 1, not counted), then the source all but ruled out
    np.savez(runs / "oven__space-aware-infotaxis__semantics__infotaxis__seed102.npz",
             policy="space-aware-infotaxis", variant="semantics", found=False, seed=102, final_posterior=post,
             position=np.array([[7.55, 4.15, 0.0], [7.65, 4.15, 0.0]] * 20), time=5.0 * np.arange(40),
             hit=np.arange(40) % 4 == 0, hpd_level=level, source_xy=np.array([7.55, 3.45]))
    _script().main([str(tmp_path), "--world", str(world)])
    out = capsys.readouterr().out.splitlines()
    line = next(x for x in out if x.startswith("oven__"))
    assert "unfindable mass 1.000" in line and "P_f reachable 0.000" in line
    # the cycle: stops 1..38 (record 0 is the start, before any reading) up to the last decision, made at stop 38:
    # 185 s; hits at stops 4, 8, …, 36: 9 of 38
    assert "cycle True (its last 185 s, hits 0.24)" in line
    # stop 31 at (7.65, 4.15): 0.71 m from the source; the closest approach before it, (7.55, 4.15): 0.70 m
    assert "source ruled out from stop 31 (155.0 s, 0.71 m from the source)" in line
    assert "| space-aware-infotaxis/semantics | 1 | 1 | 0 | 0 | 0.70 |" in out  # not found; level 0.5 at the end
