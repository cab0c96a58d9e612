"""The estimators on the simulator's default house (psgsl_pgm.sim), through ``from_grid_map``.

1. Readings drawn from the plume model on the sim's map, wind and outlet: both estimators localise.
2. Readings from the sim's GADEN-like filament gas (unsteady wind, thresholded sensor), with κ fitted on a
   separate calibration run: both put the mass in the right room. The grid model only knows the *mean* wind,
   so the position error is larger than with model-drawn readings (measured 1.1-4.3 m); only the room is
   asserted.
"""

from __future__ import annotations

import numpy as np
import pytest
from .olfaction_maps import lattice_stops

from psgsl_pgm import sim  # the project's own simulator: an import error here is a failure, not a skip
from psgsl_pgm.olfaction import GridInfotaxis, PlumeModel, PMFSEstimator, fit_encounter_scale


def _stops(house, step=5, margin=1):
    """Robot stops every ``step`` cells, at least ``margin`` cells from walls, furniture and windows."""
    g = house.grid
    return lattice_stops(house.robot_obstacles, step=step, resolution=g.resolution, margin=margin,
                         origin=g.origin)


def _err(xy, source):
    return float(np.hypot(xy[0] - source[0], xy[1] - source[1]))


@pytest.fixture(scope="module")
def house_and_wind():
    house = sim.default_house(0)
    wind = sim.make_wind(house.grid, house.inlet, house.outlet, mean_speed=0.2, perturbation=0.0, seed=0)
    return house, wind.mean().velocity


@pytest.mark.slow  # 6-9 s each source
@pytest.mark.parametrize("source_class", ["oven", "bed"])
def test_default_house_with_model_readings(house_and_wind, source_class):
    """120 x 100 cells at 0.1 m; 799 stops 0.3 m apart (≈ 30-50 hits). Measured over seeds 0-3 and the
    oven, bed and toilet: mean error ≤ 0.56 m (Infotaxis) and ≤ 0.67 m (PMFS), room mass ≥ 0.999. Asserted
    for seeds 0-1: < 0.6 m and < 0.75 m, ≥ 99 % of the mass in the source's room."""
    house, wind = house_and_wind
    model = PlumeModel.from_grid_map(house.grid, wind, outlets=house.outlet, diffusivity=0.03, lifetime=30.0,
                                     encounter_scale=0.5)
    source = house.objects_of_class(source_class)[0].center
    room = house.room_labels == house.room_of(source)
    stops = _stops(house, step=3)
    cells = house.grid.world_to_cell(stops)
    for seed in range(2):
        hits = model.sample_hits(stops, source, rng=seed)
        ests = [GridInfotaxis.from_model(model), PMFSEstimator.from_model(model)]
        for x, g, (r, c) in zip(stops, hits, cells):
            for e in ests:
                e.update(x, g, wind[r, c])
        assert _err(ests[0].expected_position(), source) < 0.6
        assert _err(ests[1].expected_position(), source) < 0.75
        for e in ests:
            assert e.posterior[room].sum() > 0.99


@pytest.mark.slow
def test_default_house_with_filament_readings():
    """Oven source, unsteady wind (the sim's default 30 % perturbation), ≈ 270 stops 0.5 m apart, ≈ 20-30 hits.

    Model: mean wind, D = 0.03 m²/s, τ = 30 s, κ fitted on the seed-1 run (≈ 1.5). Measured on seeds 0, 2, 3:
    kitchen mass 1.000 (Infotaxis) and ≥ 0.996 (PMFS); position errors 1.1-4.3 m (the model lacks the
    unsteady meander). With D = 0.01, τ = 100 (the calibration-likelihood optimum) PMFS misses the kitchen on
    seed 2 (mass 0.01) while Infotaxis still finds it: the parameters must be calibrated over several runs.
    """

    def survey(seed):
        world = sim.make_world(seed=seed, source="oven", warm_up=60.0)
        stops = _stops(world.house)
        readings = [(x, world.sense_gas(x).hit, world.sense_wind(x)) for x in stops]
        return world, readings

    cal_world, cal = survey(1)  # calibration run: source known, fit κ by maximum likelihood
    kw = dict(diffusivity=0.03, lifetime=30.0)
    cal_model = PlumeModel.from_grid_map(cal_world.house.grid, cal_world.wind.mean().velocity,
                                         outlets=cal_world.house.outlet, **kw)
    kappa = fit_encounter_scale(cal_model, [r[0] for r in cal], [r[1] for r in cal], cal_world.source,
                                false_hit_rate=0.01)
    assert 0.5 < kappa < 5
    for seed in (0, 2, 3):
        world, readings = survey(seed)
        model = PlumeModel.from_grid_map(world.house.grid, world.wind.mean().velocity, outlets=world.house.outlet,
                                         encounter_scale=kappa, **kw)
        ests = [GridInfotaxis.from_model(model), PMFSEstimator.from_model(model)]
        for x, g, w in readings:
            for e in ests:
                e.update(x, g, w)
        kitchen = world.house.room_labels == world.house.room_of(world.source)
        assert sum(g for _, g, _ in readings) >= 10
        for e in ests:
            assert e.posterior[kitchen].sum() > 0.95
