"""The exploration tour and the house ontology of the validation experiment."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from psgsl_pgm.experiment import exploration_tour, house_ontology
from psgsl_pgm.sim import HOUSE_CLASSES, HOUSE_ROOMS, default_house


@pytest.fixture(scope="module")
def tour(house):
    return exploration_tour(house)


def test_tour_is_a_connected_collision_free_path_with_regular_stops(house, tour):
    res = house.grid.resolution
    cells = house.grid.world_to_cell(tour.path)
    assert not house.robot_obstacles[cells[:, 0], cells[:, 1]].any()
    steps = np.linalg.norm(np.diff(tour.path, axis=0), axis=1)
    assert steps.max() <= np.sqrt(2) * res + 1e-12  # 8-connected, no jumps
    # clearance 0.25 m from walls, furniture and windows along the whole path
    clearance = ndi.distance_transform_edt(~house.robot_obstacles) * res
    assert clearance[cells[:, 0], cells[:, 1]].min() > 0.25
    gaps = np.diff(tour.distance)
    assert gaps.min() > 0 and gaps.max() <= 0.5 + np.sqrt(2) * res + 1e-9  # a stop every 0.5 m of path
    assert len(tour.headings) == len(tour) == len(tour.waypoint) == len(tour.distance)
    np.testing.assert_array_equal(tour.path[tour.path_index], tour.stops)
    assert all(len(h) == (4 if w else 1) for h, w in zip(tour.headings, tour.waypoint))


def test_tour_visits_every_room_area(house, tour):
    rooms = house.room_of(tour.stops)
    for k, name in enumerate(house.room_names):
        pieces, n = ndi.label(house.room_labels == k)
        for j in range(1, n + 1):
            rc = house.grid.world_to_cell(tour.stops)
            assert (pieces[rc[:, 0], rc[:, 1]] == j).any(), f"{name} area {j} is never visited"
    assert set(rooms) == set(range(len(house.room_names)))


def test_tour_is_deterministic_and_depends_on_the_map_only(house, tour):
    again = exploration_tour(default_house(0))
    np.testing.assert_array_equal(again.stops, tour.stops)
    assert all(np.array_equal(a, b) for a, b in zip(again.headings, tour.headings))


def test_tour_rejects_bad_options(house):
    with pytest.raises(ValueError, match="navigable"):
        exploration_tour(house, start=(0.05, 0.05))
    with pytest.raises(ValueError, match="stop_spacing must be a positive"):
        exploration_tour(house, stop_spacing=0.0)
    with pytest.raises(ValueError, match="clearance"):
        exploration_tour(house, clearance=float("nan"))


def test_house_ontology_counts_the_reference_houses():
    ont = house_ontology(reference_seeds=(10_000, 10_001), pseudo_count=0.5)
    assert ont.classes == HOUSE_CLASSES and ont.rooms == HOUSE_ROOMS
    # independent count: loop over rooms and classes with boolean masks
    counts = np.zeros((len(HOUSE_ROOMS), len(HOUSE_CLASSES)))
    for seed in (10_000, 10_001):
        h = default_house(seed)
        for r in range(len(HOUSE_ROOMS)):
            for c in range(len(HOUSE_CLASSES)):
                counts[r, c] += np.sum((h.room_labels == r) & (h.class_map == c))
    expected_rooms = (counts + 0.5) / (counts + 0.5).sum(axis=1, keepdims=True)
    expected_prior = (counts.sum(0) + 0.5) / (counts.sum() + 0.5 * len(HOUSE_CLASSES))
    np.testing.assert_allclose(ont.room_table, expected_rooms, rtol=1e-12)
    np.testing.assert_allclose(ont.class_prior, expected_prior, rtol=1e-12)
    smoke = ont.source_likelihood("smoke")
    assert smoke[ont.class_index("oven")] == pytest.approx(0.40) and smoke.sum() == pytest.approx(1.0, rel=1e-12)
    # the reference houses are not the evaluation houses
    assert not set(range(10_000, 10_010)) & set(range(100))


def test_house_ontology_rejects_bad_options():
    with pytest.raises(ValueError, match="pseudo_count"):
        house_ontology(pseudo_count=0.0)
    with pytest.raises(ValueError, match="reference_seeds"):
        house_ontology(reference_seeds=())
