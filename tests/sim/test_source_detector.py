import numpy as np
import pytest

from psgsl_pgm.experiment._robot_models import robot_source_miss_probability
from psgsl_pgm.sim import SourceDetector, WorldModel, make_world


def test_the_detector_never_fires_out_of_reach_and_misses_at_its_rate():
    rng = np.random.default_rng(1)
    d = SourceDetector(miss_probability=0.3)
    assert not any(d.detects(False, rng) for _ in range(100))
    fired = np.mean([d.detects(True, rng) for _ in range(4000)])
    assert abs(fired - 0.7) < 4 * np.sqrt(0.21 / 4000)
    perfect = SourceDetector()
    state = rng.bit_generator.state
    assert perfect.detects(True, rng) and rng.bit_generator.state == state  # draws nothing


def test_bad_detectors_are_refused():
    with pytest.raises(ValueError, match="miss_probability"):
        SourceDetector(miss_probability=1.0)
    with pytest.raises(TypeError, match="source_detector"):
        make_world(source_detector=0.2)


def test_the_robot_counts_its_detector_s_misses():
    assert robot_source_miss_probability("ideal") == 0.0
    m = robot_source_miss_probability("realistic", passes=2000)
    p = WorldModel.parse("realistic").source_detector().miss_probability
    assert m != p and abs(m - p) < 4 * np.sqrt(p * (1 - p) / 2000)  # a count, not the parameter
    with pytest.raises(ValueError, match="passes"):
        robot_source_miss_probability("ideal", passes=0)


def test_a_world_s_detector_has_its_own_stream():
    a = make_world(seed=3)
    b = make_world(seed=3, source_detector=SourceDetector(miss_probability=0.5))
    fired = [b.detect_source(True) for _ in range(20)]
    assert 0 < sum(fired) < 20
    ra, rb = a.sense_gas((1.0, 6.0)), b.sense_gas((1.0, 6.0))
    assert ra.value == rb.value and ra.hit == rb.hit  # the other streams draw as without it
    np.testing.assert_array_equal(a.sense_wind((1.0, 6.0)), b.sense_wind((1.0, 6.0)))
