"""The closed loop in the realistic world, every part of the world's truth guarded at once: the CFD wind field, the
detector's parameters, the MOX sensor's parameters and the true pose are read only by the simulator (and the true
pose by the success rule)."""

import numpy as np
import pytest

from psgsl_pgm.experiment import ExperimentConfig
from psgsl_pgm.search import SearchConfig, run_closed_loop
from psgsl_pgm.sim import LocalisationError, MOXSensor, default_world
from tests.experiment.test_experiment_robot_models import (_LoopMOX, _SimulatorOnlyDetector, _SimulatorOnlyWind,
                                                           guard_true_pose)


@pytest.mark.slow
def test_no_robot_code_reads_the_realistic_worlds_truth():
    pytest.importorskip("lbmpy")
    config = ExperimentConfig(world_model="realistic")
    world = default_world().make_world(100, "oven", warm_up=60.0, model=config.world_model)
    assert isinstance(world.gas_sensor, MOXSensor) and isinstance(world.localisation, LocalisationError)
    assert world.gas.grid.occupancy.sum() > world.house.grid.occupancy.sum()  # filaments go round furniture
    world.wind = _SimulatorOnlyWind(world.wind)
    world.detector = _SimulatorOnlyDetector(world.detector)
    world.gas_sensor = _LoopMOX()  # the same sensor (defaults), its parameters readable by the simulator only

    def oracle(frame):  # the success rule maps the believed path to the true one
        return frame.f_globals.get("__name__") == "psgsl_pgm.search._stepper" and frame.f_code.co_name == "_found_on"

    world = guard_true_pose(world, allow=oracle)
    run = run_closed_loop("oven", 100, "infotaxis", "semantics+rooms", config=config, world=world,
                          search=SearchConfig(time_budget=120.0))
    assert run.n_steps >= 3 and np.isfinite(run.error).all() and run.hit.dtype == bool
