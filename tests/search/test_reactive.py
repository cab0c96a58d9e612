"""The reactive baselines ``surge-cast`` and ``spiral``: gas hits and anemometer readings only, no p(s | g)."""

from types import SimpleNamespace

import numpy as np
import pytest

from psgsl_pgm import GridMap
from psgsl_pgm.cli._main import main
from psgsl_pgm.olfaction import Observation, PlumeModel
from psgsl_pgm.search import FreeSpace, Situation, choose, run_closed_loop
from psgsl_pgm.search._policies import check_semantics_alone
from psgsl_pgm.search._reactive import _STATE, CAST_LEG, GAP, STEP, SURGE, _Spiral
from psgsl_pgm.sim import Camera

SOURCE = np.array([2.0, 3.0])
WIND = 0.2  # m/s along +x


@pytest.fixture(scope="module")
def open_room():
    """A 12 m × 6 m empty room (walls on the border), its free space and a plume in a uniform wind."""
    occ = np.zeros((60, 120), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    house = SimpleNamespace(grid=GridMap(occ, 0.1, (0.0, 0.0)), robot_obstacles=occ)
    space = FreeSpace(house, Camera())
    wind = np.zeros(occ.shape + (2,))
    wind[..., 0] = WIND
    model = PlumeModel(occ, resolution=0.1, wind=wind, diffusivity=0.02, lifetime=60.0, encounter_scale=0.4)
    return space, model, model.concentration(SOURCE)


def _situation(space, observations, cell, cache):
    beliefs = SimpleNamespace(estimator=SimpleNamespace(observations=observations))
    return Situation(None, beliefs, "olfaction", space, cell, 0.0, 0.25, 1.0, 1.0, 2.0, 0.5, cache)


def _search(open_room, policy, seed, *, start=(10.0, 1.5), stops=80):
    """A closed loop in the open room: hits drawn from the plume (1 − exp(−κ c)), a noisy anemometer. Returns the
    number of stops until the path passes within 0.5 m of the source (None: not within ``stops``) and the path."""
    space, model, conc = open_room
    rng = np.random.default_rng(seed)
    observations, cache = [], {}
    cell = space.snap(start)
    path = [space.position(cell)]
    for k in range(stops):
        pos = space.position(cell)
        r, c = model.cell_of(pos)
        hit = bool(rng.random() < -np.expm1(-model.encounter_scale * conc[r, c]))
        wind = (WIND + 0.02 * rng.standard_normal(), 0.02 * rng.standard_normal())
        observations.append(Observation(tuple(pos), (r, c), hit, wind))
        dec = choose(policy, _situation(space, observations, cell, cache))
        pts = space.position(dec.path)
        path.extend(pts[1:])
        assert dec.drive <= STEP + 1e-9 and dec.cell != cell  # at most a metre between readings, always moving
        if (np.linalg.norm(pts - SOURCE, axis=1) <= 0.5).any():
            return k + 1, np.array(path)
        cell = dec.cell
    return None, np.array(path)


def test_surge_cast_reaches_the_source_of_a_plume_in_uniform_wind(open_room):
    # 8 m downwind of the source and 1.5 m to its side; hits have P ≈ 0.1-0.3 there: every run surges up the plume
    found = [_search(open_room, "surge-cast", seed)[0] for seed in range(8)]
    assert all(n is not None for n in found), found
    assert max(found) <= 60  # about 8 m upwind at a metre per stop, with the casts between the surges


def test_spiral_alone_stays_near_the_start_in_the_same_budget(open_room):
    # the control: without upwind surges the same 80 stops find the source in none of the runs (the spiral does find
    # it in 2 of 6 such runs within 400 stops: hits re-centre it, more often nearer the source)
    found = [_search(open_room, "spiral", seed)[0] for seed in range(4)]
    assert found == [None] * 4


def _obs(pos, hit, wind=(WIND, 0.0)):
    return Observation(tuple(float(v) for v in pos), (0, 0), hit, wind)


def test_a_hit_surges_upwind_by_the_anemometer_and_a_miss_casts_crosswind_widening(open_room):
    space = open_room[0]
    cache = {}
    at = space.snap((6.0, 3.0))
    x0 = space.position(at)
    obs = [_obs(x0, True, (0.0, -0.3))]  # wind towards −y: upwind is +y
    dec = choose("surge-cast", _situation(space, obs, at, cache))
    np.testing.assert_allclose(space.position(dec.cell), x0 + [0.0, SURGE], atol=0.06)
    # a miss at the surge's end: cast crosswind (±x here) about it, sides alternating, legs widening
    at = dec.cell
    x1 = space.position(at)
    obs.append(_obs(x1, False, (0.0, -0.3)))
    state = None
    offsets = []
    for _ in range(4):
        dec = choose("surge-cast", _situation(space, obs, at, cache))
        state = cache[_STATE]
        offsets.append(float((state.waypoint() - x1)[0]))
        at = dec.cell
        obs.append(_obs(space.position(at), False, (0.0, -0.3)))
    legs = sorted(set(np.round(offsets, 6)), key=abs)
    np.testing.assert_allclose(np.abs(legs), CAST_LEG * np.arange(1, len(legs) + 1))
    assert all(np.sign(a) != np.sign(b) for a, b in zip(legs, legs[1:]))
    assert state.mode == "cast"


def test_spiral_widens_by_its_gap_per_turn_and_recentres_on_a_hit(open_room):
    space = open_room[0]
    cache = {}
    at = space.snap((6.0, 3.0))
    centre = space.position(at)
    obs = [_obs(centre, False)]
    radii = []
    for _ in range(12):
        dec = choose("spiral", _situation(space, obs, at, cache))
        st = cache[_STATE].spiral
        radii.append((st.theta, float(np.linalg.norm(st.point() - centre))))
        at = dec.cell
        obs.append(_obs(space.position(at), False))
    theta, rho = np.array(radii).T
    np.testing.assert_allclose(rho, GAP * theta / (2 * np.pi), atol=1e-9)  # Archimedean: ρ = bθ/2π
    assert np.all(np.diff(theta) >= 0) and theta[-1] > theta[0]  # a waypoint is kept until it is reached
    arc = np.unique(np.round(_Spiral.arc(theta), 9))
    np.testing.assert_allclose(np.diff(arc), STEP * np.round(np.diff(arc) / STEP), atol=1e-9)  # STEP apart
    hit_at = space.position(at)
    obs[-1] = _obs(hit_at, True)
    choose("spiral", _situation(space, obs, at, cache))
    st = cache[_STATE].spiral
    np.testing.assert_allclose(st.centre, hit_at)
    np.testing.assert_allclose(_Spiral.arc(st.theta), STEP)  # the first waypoint of the new spiral: STEP along it


@pytest.mark.parametrize("policy", ["surge-cast", "spiral"])
def test_reactive_policies_refuse_semantic_variants_in_one_line(policy):
    with pytest.raises(ValueError, match=f"'{policy}'.*'olfaction' only, got 'semantics\\+rooms'"):
        check_semantics_alone(policy, "semantics+rooms")
    with pytest.raises(ValueError, match="'olfaction' only"):
        run_closed_loop("oven", 0, policy, "semantics")
    check_semantics_alone(policy, "olfaction")


def test_cli_refuses_a_reactive_policy_with_only_semantic_variants(tmp_path, capsys):
    code = main(["search", "--policies", "surge-cast", "--variants", "semantics+rooms", "--seeds", "1",
                 "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "'olfaction' only" in err[0]
    with pytest.raises(SystemExit) as exc:  # argparse: usage and one error line naming the valid policies
        main(["search", "--policies", "zigzag", "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert "invalid choice: 'zigzag'" in capsys.readouterr().err and not (tmp_path / "out").exists()


def test_a_search_grid_runs_reactive_policies_with_olfaction_only(tmp_path):
    from psgsl_pgm.search import run_search_grid

    summary = run_search_grid(["oven"], ["surge-cast", "spiral"], ["olfaction", "semantics+rooms"], ["infotaxis"], [0],
                              out=tmp_path / "out", search=_short(), figures=False, progress=False, workers=1)
    runs = sorted(p.name for p in (tmp_path / "out" / "runs").iterdir())
    assert len(runs) == 2 and all("olfaction" in r and "semantics" not in r for r in runs), runs
    assert summary
    from psgsl_pgm.search import load_search_run  # each stored run carries the CPU it took (methods' CPU/decision)

    cpu = [load_search_run(p).config["cpu_seconds"] for p in sorted((tmp_path / "out" / "runs").iterdir())]
    assert all(isinstance(c, float) and 0 < c < 600 for c in cpu), cpu


def test_the_benchmark_refuses_reactive_policies_without_the_olfaction_variant(tmp_path):
    from psgsl_pgm.search import run_benchmark

    with pytest.raises(ValueError, match="'olfaction' only"):
        run_benchmark(out=tmp_path / "b", policies=("spiral",), variants=("semantics+rooms",))
    assert not (tmp_path / "b").exists()


def test_surge_cast_in_the_house_runs_on_the_robot_s_readings_only():
    run = run_closed_loop("oven", 0, "surge-cast", "olfaction", search=_short())
    assert run.policy == "surge-cast" and run.n_steps > 5
    steps = np.linalg.norm(np.diff(run.position[1:], axis=0), axis=1)  # after the look-around at the start
    assert np.all(steps <= STEP + 1e-9) and np.all(steps > 0)


def _short():
    from psgsl_pgm.search import SearchConfig

    return SearchConfig(time_budget=60.0)
