"""Calibration runs in another world model: made in that world, hits decided as the robot decides them there."""

import numpy as np

from psgsl_pgm.experiment import ExperimentConfig, calibration_runs


def test_calibration_runs_are_made_in_the_configured_world():
    ideal, = calibration_runs([(1000, "toilet")])
    same, = calibration_runs([(1000, "toilet")], config=ExperimentConfig(world_model="ideal"))
    assert np.array_equal(ideal.hits, same.hits) and np.array_equal(ideal.positions, same.positions)
    mox, = calibration_runs([(1000, "toilet")], config=ExperimentConfig(world_model="ideal+mox"))
    assert mox.hits.dtype == bool and mox.hits.shape == ideal.hits.shape  # the same tour, the robot's MOX hits
    assert np.array_equal(mox.positions, ideal.positions)
    assert not np.array_equal(mox.hits, ideal.hits)  # a slow sensor hits elsewhere than the ideal one
