"""Calibration runs in another world model: made in that world, hits decided as the robot decides them there."""

import numpy as np

from psgsl_pgm.experiment import ExperimentConfig, calibration_runs, exploration_tour
from psgsl_pgm.experiment._run import walk
from psgsl_pgm.sim import make_world


def test_calibration_runs_are_made_in_the_configured_world():
    ideal, = calibration_runs([(1000, "toilet")])
    # the ideal run is the tour walked in the simulated house as make_world builds it
    config = ExperimentConfig()
    world = make_world(seed=1000, source="toilet", warm_up=config.warm_up)
    steps = list(walk(world, exploration_tour(world.house), config, camera=False))
    assert np.array_equal(ideal.hits, [r.hit for _, _, r, _, _ in steps])
    assert np.array_equal(ideal.positions, [stop for _, stop, _, _, _ in steps])
    mox, = calibration_runs([(1000, "toilet")], config=ExperimentConfig(world_model="ideal+mox"))
    assert mox.hits.dtype == bool and mox.hits.shape == ideal.hits.shape  # the same tour, the robot's MOX hits
    assert np.array_equal(mox.positions, ideal.positions)
    assert not np.array_equal(mox.hits, ideal.hits)  # a slow sensor hits elsewhere than the ideal one
