"""One search run: shared observation stream, data flow of the three variants, reproducibility."""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm import fuse, semantic_source_probability
from psgsl_pgm.experiment import ExperimentConfig, Tour, VARIANTS, error_and_spread, exploration_tour, run_search
from psgsl_pgm.experiment._calibration import CALIBRATION_RUNS, GRID_CALIBRATION_RUNS
from psgsl_pgm.experiment._driver import DEMO_SEEDS
from psgsl_pgm.sim import make_world


def _short(tour: Tour, n: int) -> Tour:
    return Tour(tour.stops[:n], tour.headings[:n], tour.path, tour.distance[:n], tour.waypoint[:n],
                tour.path_index[:n])


@pytest.fixture(scope="module")
def short_run():
    world = make_world(seed=5, source="oven", warm_up=60.0)
    tour = _short(exploration_tour(world.house), 40)
    return run_search("oven", 5, "infotaxis", world=world, tour=tour, snapshot_at=(0.0, 0.5, 1.0)), world


def test_metrics_are_those_of_the_kept_posteriors(short_run):
    run, world = short_run
    centres = world.house.grid.cell_centres()
    assert sorted(run.snapshots) == [0, 20, 40] and run.n_steps == 40
    for step, post in run.snapshots.items():
        assert post.shape == (3,) + world.house.shape
        np.testing.assert_allclose(post.sum(axis=(1, 2)), 1.0, rtol=1e-12)
        err, spread = error_and_spread(post, centres, world.source)
        np.testing.assert_allclose(run.error[step], err, rtol=1e-12)
        np.testing.assert_allclose(run.spread[step], spread, rtol=1e-12)


def test_calibration_is_that_of_the_kept_posteriors(short_run):
    """Region hit, area and HPD level at each kept step are those of that step's posterior, per variant."""
    from psgsl_pgm.experiment._metrics import credible_region, hpd_level

    run, world = short_run
    g = world.house.grid
    cell = int(np.ravel_multi_index(tuple(int(v) for v in g.world_to_cell(world.source)), world.house.shape))
    assert run.region_hit.shape == run.region_area.shape == run.hpd_level.shape == (run.n_steps + 1, 3)
    for step, post in run.snapshots.items():
        for v in range(3):
            region = credible_region(post[v], 0.9)
            assert run.region_hit[step, v] == region.ravel()[cell]
            assert run.region_area[step, v] == region.sum() * g.resolution**2
            assert run.hpd_level[step, v] == hpd_level(post[v], cell)
    assert not np.array_equal(run.hpd_level[0], run.hpd_level[-1])  # the stops move it


def test_before_any_frame_camera_semantics_is_uninformative(short_run):
    """Class beliefs at the prior β give p(s | z) uniform (ρ̄ = Σ β L / β = 1), so 'semantics' = 'olfaction'."""
    run, _ = short_run
    np.testing.assert_allclose(run.snapshots[0][1], run.snapshots[0][0], rtol=1e-12)
    assert run.error[0, 1] == pytest.approx(run.error[0, 0], rel=1e-12)
    # the room-category map pulls the start estimate towards the kitchen, i.e. towards the oven
    assert run.error[0, 2] < 0.6 * run.error[0, 0]


def test_run_equals_an_independent_pipeline_built_from_the_public_parts(short_run):
    """Rebuild the run from the same seed: walk the tour, the robot's wind estimate and detector model, olfactory
    estimator, two class-belief maps, eq. (20), fusion (eq. (11)) — the
    posteriors agree to 1e-12."""
    from dataclasses import replace

    from psgsl_pgm.experiment import house_ontology
    from psgsl_pgm.experiment._robot_models import robot_detector_model, wind_basis
    from psgsl_pgm.experiment._run import walk
    from psgsl_pgm.olfaction import GridInfotaxis

    run, _ = short_run
    cfg = ExperimentConfig()
    world = make_world(seed=5, source="oven", warm_up=cfg.warm_up)
    tour = _short(exploration_tour(world.house), 40)
    ont = house_ontology()
    assert world.detector.classes == ont.classes
    beta, lik = ont.class_prior, ont.source_likelihood("smoke")
    maps = [world.semantic_map(beta), world.semantic_map(beta, room_table=ont.room_table, room_names=ont.rooms)]
    # the robot's wind: least squares on the unit inlet->outlet potential flow, the plume re-solved (and every
    # reading re-assimilated by a fresh estimator) at readings 1, 2, 4, ... when the estimate moved by > 5 %
    basis = wind_basis(world.house)[0]
    detector = robot_detector_model()

    def estimator(a):
        return GridInfotaxis.from_grid_map(world.house.grid, a * basis, outlets=world.house.outlet,
                                           diffusivity=cfg.diffusivity, lifetime=cfg.lifetime,
                                           encounter_scale=cfg.encounter_scale, tempering=cfg.tempering,
                                           false_hit_rate=cfg.false_hit_rate, parameter_grid=cfg.parameter_grid)

    est, solved, num, den, seen = estimator(0.0), 0.0, 0.0, 0.0, []
    for j, stop, reading, wind, frames in walk(world, tour, cfg):
        r, c = world.house.grid.cell_of(stop)
        num += float(basis[r, c] @ wind)
        den += float(basis[r, c] @ basis[r, c])
        n = j + 1
        if n & (n - 1) == 0 and abs(num / den - solved) > cfg.wind_refresh * abs(num / den):
            solved = num / den
            est = estimator(solved)
            for x, h, w in seen:
                est.update(x, h, w)
        seen.append((stop, reading.hit, wind))
        p_g = est.update(stop, reading.hit, wind)
        for frame in frames:
            frame = replace(frame, likelihood=detector.likelihood(frame.labels, frame.distance))
            for m in maps:
                m.update(frame)
        if j + 1 == 20:
            mid = [p_g] + [fuse(p_g, semantic_source_probability(m.probs, lik, beta)) for m in maps]
            for v in range(3):
                np.testing.assert_allclose(run.snapshots[20][v], mid[v], rtol=1e-12, atol=1e-300)
    end = [p_g] + [fuse(p_g, semantic_source_probability(m.probs, lik, beta)) for m in maps]
    for v in range(3):
        np.testing.assert_allclose(run.snapshots[40][v], end[v], rtol=1e-12, atol=1e-300)


def test_the_observation_stream_does_not_depend_on_the_estimator():
    tour = _short(exploration_tour(make_world(seed=2, warm_up=0.0).house), 25)
    a = run_search("oven", 2, "infotaxis", tour=tour)
    b = run_search("oven", 2, "analytic-plume", tour=tour)
    np.testing.assert_array_equal(a.hit, b.hit)
    np.testing.assert_array_equal(a.time, b.time)
    np.testing.assert_array_equal(a.position, b.position)
    c = run_search("oven", 2, "infotaxis", tour=tour)  # reproducible
    np.testing.assert_array_equal(a.error, c.error)
    assert not np.array_equal(a.error[:, 0], b.error[:, 0])


def test_run_search_rejects_bad_arguments():
    with pytest.raises(ValueError, match="estimator must be one of"):
        run_search("oven", 0, "kalman")
    with pytest.raises(TypeError, match="seed must be an integer"):
        run_search("oven", 1.5)
    with pytest.raises(ValueError, match="source class 'piano' has no object"):
        run_search("piano", 0)
    with pytest.raises(ValueError, match="gas must be one of"):
        run_search("oven", 0, config=ExperimentConfig(gas="chlorine"), tour=None)
    with pytest.raises(ValueError, match="snapshot_at must hold fractions"):
        run_search("oven", 0, snapshot_at=(1.5,))
    with pytest.raises(ValueError, match="speed must be a positive finite number, got 0.0"):
        ExperimentConfig(speed=0.0)
    with pytest.raises(ValueError, match="a source position must read"):
        run_search("1,2,3", 0)


def test_calibration_runs_are_disjoint_from_evaluation_and_reference():
    seeds = {s for s, _ in CALIBRATION_RUNS}
    assert not seeds & set(range(100)) and not seeds & set(range(10_000, 10_010))
    assert not {src for _, src in CALIBRATION_RUNS} & {"oven", "bed", "5.0,6.0"}
    grid_seeds = {s for s, _ in GRID_CALIBRATION_RUNS}
    assert set(CALIBRATION_RUNS) <= set(GRID_CALIBRATION_RUNS) and len(grid_seeds) == len(GRID_CALIBRATION_RUNS)
    assert not grid_seeds & set(range(1000)) and not grid_seeds & set(range(10_000, 10_010))
    assert not {src for _, src in GRID_CALIBRATION_RUNS} & {"oven", "bed", "5.0,6.0"}
    assert set(DEMO_SEEDS) <= set(range(100))


@pytest.mark.slow
def test_stored_plume_parameters_and_tempering_are_the_calibrated_ones():
    """D, τ, κ and β in ExperimentConfig are calibrate()'s maximum-likelihood fit on CALIBRATION_RUNS (D = 0.01312,
    τ = 284.0, κ = 0.8213, β = 0.2976, PMFS λ = 0.3801) to their three stored digits."""
    from psgsl_pgm.experiment import calibrate
    from psgsl_pgm.experiment._config import PARAMETER_GRID

    cal = calibrate(coverage_runs=None)  # the coverage tempering has its own tests
    cfg = ExperimentConfig()
    assert cfg.diffusivity == pytest.approx(cal.plume.diffusivity, rel=5e-3)
    assert cfg.lifetime == pytest.approx(cal.plume.lifetime, rel=5e-3)
    assert cfg.encounter_scale == pytest.approx(cal.plume.encounter_scale, rel=5e-3)
    assert cfg.tempering == pytest.approx(cal.tempering, rel=5e-3)
    assert cfg.pmfs_tempering == pytest.approx(cal.pmfs_tempering, rel=5e-3)
    stored, fitted = np.array(PARAMETER_GRID), np.array(cal.parameter_grid)
    assert stored.shape == fitted.shape
    np.testing.assert_array_equal(stored[:, :3], fitted[:, :3])  # the grid points kept
    np.testing.assert_allclose(stored[:, 3], fitted[:, 3], atol=5e-4)  # their weights, to three digits


@pytest.mark.slow
def test_calibrate_encounter_scale_is_the_likelihood_maximiser_at_the_configs_plume():
    from psgsl_pgm.experiment import ExperimentConfig, calibrate_encounter_scale, calibration_runs
    from psgsl_pgm.olfaction import hit_log_likelihood

    config = ExperimentConfig(stops=40)
    runs = [(1000, "toilet")]
    kappa = calibrate_encounter_scale(runs, config=config)
    (data,) = calibration_runs(runs, config=config)
    c = data.predicted(config.diffusivity, config.lifetime)
    best = hit_log_likelihood(c, data.hits, kappa, config.false_hit_rate)
    for k in (kappa * 0.99, kappa * 1.01):  # a maximum, not any root of something else
        assert hit_log_likelihood(c, data.hits, k, config.false_hit_rate) < best
