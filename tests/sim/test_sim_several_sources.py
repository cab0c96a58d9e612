"""A world with several sources: the plumes add up, the first source's plume is the one-source world's, and the
further sources are checked."""

import numpy as np
import pytest

from psgsl_pgm.sim import ElectronicNose, make_world


def test_plumes_add_up_and_the_first_is_the_one_source_worlds():
    one = make_world(seed=3, source="oven", warm_up=20.0)
    two = make_world(seed=3, source="oven", extra_sources=["couch"], warm_up=20.0)
    assert two.n_sources == 2 and one.n_sources == 1
    np.testing.assert_array_equal(two.gas.positions, one.gas.positions)  # the same draws for the first source
    np.testing.assert_array_equal(two.sources[0], one.source)
    assert [o.class_name for o in two.source_objects] == ["oven", "couch"]
    np.testing.assert_array_equal(two.sources[1], two.source_objects[1].center)
    pts = np.array([[7.0, 1.0], [two.sources[1][0], two.sources[1][1] + 0.35], [4.0, 6.0]])
    np.testing.assert_array_equal(two.concentration(pts),
                                  one.concentration(pts) + two.extra_gas[0].concentration(pts))
    assert two.extra_gas[0].concentration(pts[1:2])[0] > 0  # the couch's plume reaches beside it
    # a sensor window sums the plumes, each stepping with the clock
    r1, r2 = one.sense_gas(pts[1]), two.sense_gas(pts[1])
    assert two.time == one.time == two.extra_gas[0].time
    assert r2.value > r1.value


def test_the_e_nose_names_the_gas_that_brings_most_of_the_window():
    w = make_world(seed=1, source="oven", extra_sources=["couch"], enose=ElectronicNose(), gas_type="smoke",
                   extra_gas_types=["ammonia"], warm_up=60.0)
    assert w.gas_types == ("smoke", "ammonia")
    w.sense_gas((0.75, 2.65))  # beside the couch: its ammonia dominates
    assert w._window_means[1] > 10 * max(w._window_means[0], 1e-3)
    labels = [w.sniff().label for _ in range(20)]
    assert labels.count("ammonia") >= 15 and "smoke" not in labels


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"extra_sources": ["couch", "bed", "tv"]}, ValueError, "at most 2"),
    ({"extra_sources": "couch"}, TypeError, "extra_sources"),
    ({"extra_sources": ["couch"], "extra_gas_types": ["smoke"]}, ValueError, "extra_gas_types"),
    ({"extra_sources": ["sofa"]}, ValueError, "sofa"),
])
def test_bad_further_sources_name_the_argument(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        make_world(seed=0, source="oven", warm_up=0.0, **kwargs)
