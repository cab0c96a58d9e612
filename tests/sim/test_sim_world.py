"""The World on one clock (readings, reproducibility, initial beliefs), the public API, and the docstring
examples of psgsl_pgm.sim."""


import numpy as np
import pytest

import psgsl_pgm
import psgsl_pgm.geometry._sight
import psgsl_pgm.sim as sim
from psgsl_pgm import Ontology
from psgsl_pgm.sim import HOUSE_CLASSES, HOUSE_ROOMS, OTHER, GasSensor, make_world


def test_world_clock_and_readings():
    w = make_world(seed=1, warm_up=30.0, gas_sensor=GasSensor(threshold=0.5, window=1.0))
    assert w.time == pytest.approx(30.0) and w.source_object.class_name == "oven"
    np.testing.assert_allclose(w.source, w.house.objects_of_class("oven")[0].center)
    r = w.sense_gas(w.source)  # fresh filaments every step: ~ppm_centre at least
    assert w.time == pytest.approx(31.0)
    assert r.hit and r.value >= 5.0
    far = w.sense_gas((2.0, 10.0))  # the west bedroom, upwind of the kitchen
    assert not far.hit and far.value == 0.0
    wind = np.array([w.sense_wind((5.0, 6.0)) for _ in range(200)])
    truth = w.wind_now().at((5.0, 6.0))
    np.testing.assert_allclose(wind.mean(axis=0), truth, atol=5 * 0.02 / np.sqrt(200))
    frame = w.camera_frame((7.6, 3.8, -np.pi / 2))
    assert frame.cells.shape[0] > 100 and frame.likelihood.shape == (frame.cells.shape[0], len(HOUSE_CLASSES))


def test_world_is_reproducible_per_seed():
    def run(seed):
        w = make_world(seed=seed, warm_up=20.0)
        out = [w.sense_gas((7.5, 1.2)).value for _ in range(5)]
        return out, w.camera_frame((7.6, 3.8, -np.pi / 2)).labels, w.gas.positions.copy()

    a, b, c = run(3), run(3), run(4)
    assert a[0] == b[0]
    np.testing.assert_array_equal(a[1], b[1])
    np.testing.assert_array_equal(a[2], b[2])
    assert a[0] != c[0]


def test_world_initial_beliefs_with_and_without_rooms():
    w = make_world(seed=0, warm_up=0.0)
    k = len(HOUSE_CLASSES)
    prior = np.full(k, 0.2 / (k - 1))
    prior[HOUSE_CLASSES.index(OTHER)] = 0.8
    flat = w.semantic_map(prior)
    np.testing.assert_allclose(flat.probs, np.broadcast_to(prior, w.house.shape + (k,)))
    kitchen_row = prior.copy()
    kitchen_row[HOUSE_CLASSES.index("oven")] += 0.1
    kitchen_row[HOUSE_CLASSES.index(OTHER)] -= 0.1
    ont = Ontology(HOUSE_CLASSES, ["smoke"], np.full((1, k), 1 / k), class_prior=prior, rooms=["kitchen"],
                   room_table=kitchen_row[None])
    rooms = w.semantic_map(ont.class_prior, room_table=ont.room_table, room_names=ont.rooms)
    kitchen = w.house.room_labels == HOUSE_ROOMS.index("Kitchen")
    np.testing.assert_allclose(rooms.probs[kitchen], np.broadcast_to(kitchen_row, (kitchen.sum(), k)), rtol=1e-12)
    np.testing.assert_allclose(rooms.probs[~kitchen], np.broadcast_to(prior, ((~kitchen).sum(), k)), rtol=1e-12)
    vox = w.semantic_map(prior, layers=3)
    assert vox.probs.shape == w.house.shape + (3, k)


def test_world_errors():
    with pytest.raises(ValueError, match="source class 'dragon'"):
        make_world(source="dragon", warm_up=0.0)
    with pytest.raises(ValueError, match="warm_up"):
        make_world(warm_up=-1.0)
    with pytest.raises(ValueError, match="occupied"):
        make_world(source=(0.05, 0.05), warm_up=0.0)


def test_public_names():
    for name in ("load_ros_map", "load_room_map", "default_house", "GridMap", "World", "make_world"):
        assert name in sim.__all__
    assert sorted(sim.__all__) == sorted(set(sim.__all__))
    for name in sim.__all__:  # every public name is defined, and is the project's own object
        obj = getattr(sim, name)
        if callable(obj):
            assert obj.__module__.startswith("psgsl_pgm."), (name, obj.__module__)
        else:  # the constants: class and room names, confusion groups, limits
            assert isinstance(obj, (str, tuple, int, float)) and not isinstance(obj, bool) and obj, (name, obj)
    assert sim.GridMap is psgsl_pgm.GridMap and sim.cells_clear is psgsl_pgm.geometry._sight.cells_clear
