"""psgsl/House-v0: registration, the gymnasium API check, seeding, the action slots and the reward's accounting."""

import subprocess
import sys

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from psgsl_pgm.gym import ENV_ID, HouseEnv  # noqa: E402  (importing it registers the environment)
from psgsl_pgm.search import SearchConfig  # noqa: E402

SHORT = SearchConfig(time_budget=60.0)


def _same(a: dict, b: dict) -> bool:
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in a)


def test_registered_by_the_gym_module_only():
    code = "import sys, psgsl_pgm, psgsl_pgm.search; print('gymnasium' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
    assert ENV_ID in gymnasium.registry
    env = gymnasium.make(ENV_ID, world="house", search=SHORT)
    assert isinstance(env.unwrapped, HouseEnv)


# the readings (gas, wind), the candidates' drives and the elapsed time have no finite bound: check_env's advice
# about infinite Box limits is a warning, not a failure of the API
@pytest.mark.filterwarnings("ignore:.*Box observation space (minimum|maximum) value is:UserWarning")
def test_passes_gymnasiums_check():
    from gymnasium.utils.env_checker import check_env

    check_env(HouseEnv(world="house", seeds=1, search=SHORT), skip_render_check=True)


def test_a_seed_gives_the_same_episode():
    def play(seed):
        env = HouseEnv(houses=2, seeds=2, search=SearchConfig(time_budget=40.0))
        obs, info = env.reset(seed=seed)
        out = [(obs, 0.0)]
        done = False
        while not done:
            obs, r, term, trunc, info = env.step(0)
            out.append((obs, r))
            done = term or trunc
        return info, out

    (i1, a), (i2, b) = play(7), play(7)
    assert (i1["house"], i1["seed"], i1["source"]) == (i2["house"], i2["seed"], i2["source"])
    assert len(a) == len(b) and all(_same(x, y) and r == s for (x, r), (y, s) in zip(a, b))
    assert i1["house"] in range(2) and i1["seed"] in range(2)


def test_options_pick_the_episode_and_the_spaces_hold_the_observation():
    env = HouseEnv(world="house", search=SHORT, slots=8, belief_size=16)
    obs, info = env.reset(seed=0, options={"seed": 3, "source": "bed"})
    assert (info["seed"], info["house"]) == (3, None) and "source" not in info  # no truth during the episode
    assert env.observation_space.contains(obs)
    assert obs["belief"].shape == (16, 16) and abs(float(obs["belief"].sum()) - 1.0) < 1e-5
    assert obs["candidates"].shape == (8, 5) and info["action_mask"].shape == (8,)
    assert info["time"] > 0  # the look-around at the start is part of the reset
    with pytest.raises(ValueError, match="options may hold"):
        env.reset(options={"house": 1, "colour": 2})


def test_an_empty_slot_takes_the_candidate_it_wraps_to():
    env1, env2 = HouseEnv(world="house", search=SHORT, slots=256), HouseEnv(world="house", search=SHORT, slots=256)
    _, info = env1.reset(seed=5)
    env2.reset(seed=5)
    mask = info["action_mask"]
    k = int(mask.sum())
    assert 0 < k < 256 and mask[:k].all() and not mask[k:].any()
    o1, r1, *_ = env1.step(255)
    o2, r2, *_ = env2.step(255 % k)
    assert _same(o1, o2) and r1 == r2


def test_the_reward_is_the_time_and_the_declaration():
    env = HouseEnv(world="house", search=SearchConfig(time_budget=400.0), time_cost=0.5, correct_bonus=3.0,
                   wrong_penalty=4.0)
    _, info = env.reset(seed=0, options={"seed": 1, "source": "oven"})
    t0, total, steps = info["time"], 0.0, 0
    while True:
        _, r, term, trunc, info = env.step(0)  # the best P_f per second
        total, steps = total + r, steps + 1
        if term or trunc:
            break
    expected = -0.5 * (info["time"] - t0)
    if term:
        expected += 3.0 if info["declared_correct"] else -4.0
    else:
        assert info["time"] >= 400.0
    assert total == pytest.approx(expected, rel=1e-12, abs=1e-9)
    run = env.episode_run()
    assert run.n_steps == steps + 1 and run.declared == term
    with pytest.raises(ValueError, match="call reset"):
        env.step(0)


def test_bad_input_names_what_was_expected():
    with pytest.raises(ValueError, match="world must be one of"):
        HouseEnv(world="castle")
    with pytest.raises(ValueError, match="end must be 'declare'"):
        HouseEnv(search=SearchConfig(end="reach"))
    with pytest.raises(ValueError, match="test split"):
        HouseEnv(houses=3, first_house=9_999)  # reaches into the test homes
    env = HouseEnv(world="house", search=SHORT, slots=4)
    with pytest.raises(ValueError, match="before step"):
        env.step(0)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"slot in \[0, 4\)"):
        env.step(4)
    with pytest.raises(TypeError, match="integer slot"):
        env.step(1.5)


def test_the_episode_setting_is_the_episode_a_reset_runs():
    env = HouseEnv(houses=2, seeds=2, search=SHORT)
    s = env.episode_setting(house=1, seed=1)
    _, info = env.reset(seed=0, options={"house": 1, "seed": 1})
    assert (info["house"], info["seed"]) == (s["house"], s["seed"]) == (1, 1)
    assert s["config"].gas in s["world_spec"].ontology.gases
    truth = env.unwrapped._episode.world.source
    np.testing.assert_allclose(truth, s["source"])


def test_a_repeated_episode_reuses_the_geometry_and_is_the_same_episode():
    def play(env, actions):
        obs, _ = env.reset(seed=0, options={"seed": 2, "source": "bed"})
        out = [obs]
        for a in actions:
            obs, _, term, trunc, _ = env.step(a)
            out.append(obs)
            if term or trunc:
                break
        return out

    actions = [3, 0, 7, 1, 12, 5, 0, 2]
    warm = HouseEnv(world="house", search=SHORT)
    play(warm, actions[::-1])  # other moves first: the shared FreeSpace caches other cells
    space = warm._spaces[(None, 2)]
    again = play(warm, actions)
    assert warm._episode.space is space
    fresh = play(HouseEnv(world="house", search=SHORT), actions)
    assert len(again) == len(fresh) > 2 and all(_same(a, b) for a, b in zip(again, fresh))
