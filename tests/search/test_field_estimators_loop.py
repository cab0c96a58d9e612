"""PMFS as published and GrGSL as the closed loop's p(s | g): fused with the semantic term unchanged, reproducible."""

import numpy as np
import pytest

from psgsl_pgm import fuse
from psgsl_pgm.experiment import ExperimentConfig
from psgsl_pgm.experiment._step import VariantPosteriors, visit
from psgsl_pgm.olfaction import FilamentPMFS, GrGSL
from psgsl_pgm.search import SearchConfig, run_closed_loop
from psgsl_pgm.sim import make_world


@pytest.mark.parametrize("name, cls", [("pmfs", FilamentPMFS), ("grgsl", GrGSL)])
def test_the_semantic_fusion_runs_on_the_estimator_unchanged(name, cls):
    config = ExperimentConfig(warm_up=5.0)
    world = make_world(seed=0, warm_up=5.0)
    beliefs = VariantPosteriors(world, name, config)
    assert isinstance(beliefs.estimator, cls)
    for stop in ((0.8, 6.0), (2.0, 6.0)):
        beliefs.observe(stop, *visit(world, np.array(stop), (0.0, np.pi), config))
    p_g = beliefs.estimator.posterior
    assert beliefs.estimator.n_observations == 2
    post = beliefs.posteriors()
    np.testing.assert_array_equal(post[0], p_g)
    for k, v in ((1, "semantics"), (2, "semantics+rooms")):
        np.testing.assert_array_equal(post[k], fuse(p_g, beliefs.semantic(v)))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["pmfs", "grgsl"])
def test_a_closed_loop_with_semantics_and_rooms_is_reproducible(name):
    search = SearchConfig(time_budget=60.0)
    a = run_closed_loop("oven", 0, "infotaxis", "semantics+rooms", name, search=search)
    b = run_closed_loop("oven", 0, "infotaxis", "semantics+rooms", name, search=search)
    assert a.estimator == name and a.n_steps >= 1
    np.testing.assert_array_equal(a.position, b.position)
    np.testing.assert_array_equal(a.final_posterior, b.final_posterior)
    assert abs(float(a.final_posterior.sum()) - 1) < 1e-5
