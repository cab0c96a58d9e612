"""The closed loop's stepping object: driven from outside with a policy's own decisions it is the loop itself."""

import numpy as np
import pytest

from psgsl_pgm.search import SearchConfig, run_closed_loop
from psgsl_pgm.search._choose import choose
from psgsl_pgm.search._stepper import ClosedLoopEpisode

ARRAYS = ("time", "position", "heading", "hit", "path_length", "error", "map_error", "spread", "region_area",
          "region_hit", "hpd_level", "path", "final_posterior")


@pytest.mark.parametrize("policy, variant, source, seed", [("greedy", "semantics+rooms", "oven", 2),
                                                           ("surge-cast", "olfaction", "bed", 3)])
def test_outside_decisions_replay_the_loop(policy, variant, source, seed):
    search = SearchConfig(time_budget=100.0)
    run = run_closed_loop(source, seed, policy, variant, search=search)
    ep = ClosedLoopEpisode(source, seed, None, variant, "infotaxis", search=search)
    ep.take(ep.first_move())
    while not ep.done:
        ep.take(ep.move_to(choose(policy, ep.situation())))
    out = ep.result()
    assert out.policy == "external" and out.n_steps == run.n_steps > 1
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(out, name), getattr(run, name), err_msg=name)
    assert (out.declared, out.declared_correct, out.found) == (run.declared, run.declared_correct, run.found)


def test_an_episode_without_a_policy_asks_for_moves_and_ends():
    ep = ClosedLoopEpisode("oven", 0, None, "olfaction", "infotaxis", search=SearchConfig(time_budget=30.0))
    ep.take(ep.planned_move())  # the first stop needs no policy
    with pytest.raises(ValueError, match="no policy of its own"):
        ep.planned_move()
    while not ep.done:
        sit = ep.situation()
        ep.take(ep.move_to(choose("greedy", sit)))
    assert ep.time >= 30.0 or ep.declaration is not None
    with pytest.raises(ValueError, match="has ended"):
        ep.take(ep.first_move())


def test_bad_names_are_refused():
    with pytest.raises(ValueError, match="policy must be one of"):
        ClosedLoopEpisode("oven", 0, "nope")
    with pytest.raises(ValueError, match="variant must be one of"):
        ClosedLoopEpisode("oven", 0, None, "nope")
