"""The closed loop with a localisation error: without one the episode is today's bit for bit; with one the robot
records the poses it believes, only the success rule reads the true path, and the policies never do."""

import numpy as np

from psgsl_pgm.experiment import ExperimentConfig, parse_source
from psgsl_pgm.search import SearchConfig, run_closed_loop
from psgsl_pgm.sim import LocalisationError, default_world
from tests.experiment.test_experiment_robot_models import guard_true_pose

ARRAYS = ("time", "position", "heading", "hit", "path_length", "error", "map_error", "spread", "region_area",
          "region_hit", "hpd_level", "path", "final_posterior")


def _world(seed, source="oven", **kw):
    return default_world().make_world(seed, parse_source(source), warm_up=ExperimentConfig().warm_up, **kw)


def _assert_same_run(a, b):
    assert (a.found, a.time_to_find, a.driven, a.geodesic) == (b.found, b.time_to_find, b.driven, b.geodesic)
    for name in ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes(), name


def test_without_localisation_error_the_episode_is_todays_bit_for_bit(house_space):
    _, space = house_space
    search = SearchConfig(time_budget=25.0)
    args = ("oven", 0, "infotaxis", "semantics+rooms")
    today = run_closed_loop(*args, search=search, space=space)
    _assert_same_run(today, run_closed_loop(*args, search=search, space=space, world=_world(0, localisation=None)))
    zero = LocalisationError(sigma=0.0, heading_sigma=0.0)
    _assert_same_run(today, run_closed_loop(*args, search=search, space=space, world=_world(0, localisation=zero)))


def test_with_error_the_robot_records_the_poses_it_believes(house_space):
    _, space = house_space
    search = SearchConfig(time_budget=40.0)
    args = ("oven", 0, "tour", "semantics+rooms")
    plain = run_closed_loop(*args, search=search, space=space)
    world = _world(0, localisation=LocalisationError(sigma=0.15, heading_sigma=0.05))
    run = run_closed_loop(*args, search=search, space=space, world=world)
    # the same plan, driven and recorded in the frame the robot believes ...
    np.testing.assert_array_equal(run.position, plain.position)
    np.testing.assert_array_equal(run.path, plain.path)
    # ... while it sensed elsewhere: other readings, another posterior
    assert not np.array_equal(run.final_posterior, plain.final_posterior)


class _Shifted:
    """A world whose robot is truly ``shift`` metres from where it believes (for the success rule only), and
    that records the times the rule asked about."""

    def __init__(self, world, shift):
        self._world, self._shift, self.asked = world, np.asarray(shift, dtype=np.float64), []

    def __getattr__(self, name):
        return getattr(self._world, name)

    def true_positions(self, points, *, times=None):
        self.asked.append((self._world.time, np.array(times, dtype=np.float64, ndmin=1)))
        return self._world.true_positions(points, times=times) + self._shift


def test_the_success_rule_reads_the_true_path(house_space):
    """A point source 1.2 m from the start: not found within a 1 s budget from where the robot believes it is,
    found at t = 0 when its true start is at the source."""
    _, space = house_space
    search = SearchConfig(time_budget=1.0)
    args = ("2.0,6.05", 0, "tour", "olfaction")
    plain = run_closed_loop(*args, search=search, space=space)
    assert not plain.found
    shifted = _Shifted(_world(0, "2.0,6.05"), (1.2, 0.05))
    run = run_closed_loop(*args, search=search, space=space, world=shifted)
    assert run.found and run.time_to_find == 0.0
    np.testing.assert_array_equal(run.position[0], plain.position[0])  # recorded where it believes it is
    # the rule asks at the times the robot passes the path's points: from now on, in order
    far = _Shifted(_world(0, "2.0,6.05"), (30.0, 30.0))  # off the map: never found
    run = run_closed_loop("2.0,6.05", 0, "tour", "olfaction", search=SearchConfig(time_budget=40.0), space=space,
                          world=far)
    assert not run.found and len(far.asked) > 2
    for now, times in far.asked:
        assert times[0] == now and (np.diff(times) > 0).all()


def test_no_policy_reads_the_true_pose(house_space):
    """Only the success rule (``_found_on`` of the loop's stepping object) may map the robot's path to the true one."""
    _, space = house_space

    def oracle(frame):
        return frame.f_globals.get("__name__") == "psgsl_pgm.search._stepper" and frame.f_code.co_name == "_found_on"

    world = guard_true_pose(_world(1, "bed", localisation=LocalisationError()), allow=oracle)
    run = run_closed_loop("bed", 1, "infotaxis", "semantics", search=SearchConfig(time_budget=30.0), space=space,
                          world=world)
    assert run.n_steps >= 2
