"""What a worker computes once per house: a shared free space, tour and potential flow give a run the very numbers
a fresh one gives (keyed by content, not by object), and other content gets its own entry."""

import numpy as np
import pytest

from psgsl_pgm.experiment._tour import exploration_tour, shared_tour
from psgsl_pgm.search import DetectionModel
from psgsl_pgm.search._space import _SHARED_SPACES, FreeSpace
from psgsl_pgm.sim import Camera, default_house, potential_flow
from psgsl_pgm.sim import _wind
from psgsl_pgm.sim._house import _default_house


def _built_apart(seed):
    """The default house of ``seed`` built again (default_house keeps one per seed): equal content, another object."""
    return _default_house.__wrapped__(seed)


def test_a_shared_space_is_one_per_content_and_equals_a_new_one():
    _SHARED_SPACES.clear()
    a, b = default_house(0), _built_apart(0)  # equal content, two objects
    assert a is not b
    space = FreeSpace.shared(a, Camera())
    assert FreeSpace.shared(b, Camera()) is space
    assert FreeSpace.shared(a, Camera(), clearance=0.3) is not space  # other options, another space
    fresh = FreeSpace(b, Camera())
    for radius in (0.5, 0.36, 0.5):  # a shared space moves between radii as runs of both come
        det = DetectionModel.from_house(b, radius)
        np.testing.assert_array_equal(space.cover(det), fresh.cover(det))
        np.testing.assert_array_equal(space.lattice, fresh.lattice)
        cell = space.snap((3.0, 6.0))
        np.testing.assert_array_equal(space.findable(det, cell), fresh.findable(det, cell))
        np.testing.assert_array_equal(space.distances(cell), fresh.distances(cell))


def test_detection_content_key_names_the_footprints_and_radius():
    h = default_house(0)
    k = DetectionModel.from_house(h, 0.5).content_key
    assert DetectionModel.from_house(_built_apart(0), 0.5).content_key == k
    assert DetectionModel.from_house(h, 0.5, miss_probability=0.2).content_key == k  # misses do not move finders
    assert DetectionModel.from_house(h, 0.4).content_key != k
    assert DetectionModel(h.grid, 0.5).content_key != k  # no footprints


def test_a_shared_tour_is_the_tour_read_only():
    h = default_house(0)
    got, ref = shared_tour(h, start=(0.8, 6.0)), exploration_tour(h, start=(0.8, 6.0))
    assert shared_tour(_built_apart(0), start=(0.8, 6.0)) is got
    for x, y in ((got.stops, ref.stops), (got.path, ref.path), (got.distance, ref.distance),
                 (got.waypoint, ref.waypoint), (got.path_index, ref.path_index)):
        np.testing.assert_array_equal(x, y)
        assert not x.flags.writeable
    assert all(np.array_equal(x, y) for x, y in zip(got.headings, ref.headings))
    assert shared_tour(h, start=(3.0, 6.0)) is not got
    with pytest.raises(ValueError, match="clearance must be a positive number"):
        shared_tour(h, clearance=-1.0)


def test_the_cached_potential_flow_is_the_computed_one_bit_for_bit():
    h = default_house(0)
    _wind._UNSCALED_FLOWS.clear()
    first = potential_flow(h.grid, h.inlet, h.outlet, mean_speed=0.2)
    again = potential_flow(h.grid, h.inlet, h.outlet, mean_speed=0.2)  # from the cache
    assert len(_wind._UNSCALED_FLOWS) == 1
    for x, y in ((first.velocity, again.velocity), (first.u_faces, again.u_faces), (first.v_faces, again.v_faces)):
        np.testing.assert_array_equal(x, y)
    unit = potential_flow(h.grid, h.inlet, h.outlet, mean_speed=1.0)
    _wind._UNSCALED_FLOWS.clear()
    np.testing.assert_array_equal(unit.velocity, potential_flow(h.grid, h.inlet, h.outlet, mean_speed=1.0).velocity)
    with pytest.raises(ValueError, match="mean_speed must be a positive number"):
        potential_flow(h.grid, h.inlet, h.outlet, mean_speed=0.0)


def test_a_shared_detection_model_is_one_per_content_and_finds_what_a_new_one_finds():
    h = default_house(0)
    det = DetectionModel.shared(h, 0.5)
    assert DetectionModel.shared(_built_apart(0), 0.5) is det
    assert DetectionModel.shared(h, 0.5, miss_probability=0.2) is not det
    assert DetectionModel.shared(default_house(1), 0.5) is not det  # objects moved: other footprints
    fresh = DetectionModel.from_house(h, 0.5)
    path = np.array([[3.0, 6.0], [3.5, 6.0], [4.0, 6.2]])
    for _ in range(2):  # the second time from the caches
        np.testing.assert_array_equal(det.not_found_log_likelihood(path), fresh.not_found_log_likelihood(path))
        cells = [1234, 2345]
        for a, b in zip(det.cell_rows(cells, det.centres[cells]), fresh.cell_rows(cells, fresh.centres[cells])):
            np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="found_radius"):
        DetectionModel.shared(h, -1.0)


def test_the_default_house_and_world_are_built_once():
    from psgsl_pgm.sim import default_world

    assert default_house(3) is default_house(3) and default_house(3) is not default_house(4)
    assert default_world() is default_world()
    with pytest.raises(TypeError, match="seed must be an integer"):
        default_house(1.5)


def test_the_arms_of_an_episode_share_the_plume_model_of_the_first_wind_reading():
    from psgsl_pgm.experiment import _step
    from psgsl_pgm.search import SearchConfig
    from psgsl_pgm.search._stepper import ClosedLoopEpisode

    _step._FIRST_PLUMES.clear()
    models = []
    for policy, variant in (("infotaxis", "olfaction"), ("greedy", "semantics+rooms")):
        ep = ClosedLoopEpisode("oven", 3, policy, variant, search=SearchConfig(time_budget=30.0))
        ep.take(ep.first_move())  # the look-around at the start: one wind reading
        assert ep.beliefs.wind.n_readings == 1
        models.append(ep.beliefs.model)
    assert models[0] is models[1]
    other = ClosedLoopEpisode("oven", 4, "infotaxis", "olfaction", search=SearchConfig(time_budget=30.0))
    other.take(other.first_move())  # another seed: another wind, another model
    assert other.beliefs.model is not models[0]
