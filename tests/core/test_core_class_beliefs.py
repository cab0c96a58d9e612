"""psgsl_pgm.ClassBeliefMap: the robot's class beliefs in the core, with update_class_probs semantics."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from psgsl_pgm import ClassBeliefMap, room_evidence, semantic_source_probability, update_class_probs
from psgsl_pgm.sim import SemanticMap

CLASSES = ("oven", "sink", "other")
PRIOR = np.array([0.1, 0.2, 0.7])


@settings(max_examples=40, deadline=None)
@given(
    lik=arrays(np.float64, st.tuples(st.integers(1, 12), st.just(3)), elements=st.floats(1e-3, 1.0)),
    cells=arrays(np.int64, st.tuples(st.integers(1, 12), st.just(2)), elements=st.integers(0, 2)),
)
def test_updates_equal_repeated_update_class_probs(lik, cells):
    n = min(len(lik), len(cells))
    lik, cells = lik[:n], cells[:n]
    m = ClassBeliefMap.from_prior((3, 3), PRIOR, CLASSES)
    m.update(cells, lik)  # one call; a cell may appear several times
    ref = np.broadcast_to(PRIOR, (3, 3, 3)).copy()
    for (r, c), row in zip(cells, lik):  # the core's Bayes rule, one observation at a time
        ref[r, c] = update_class_probs(ref[r, c], row)
    np.testing.assert_allclose(m.probs, ref, rtol=1e-10, atol=1e-300)


def test_many_frames_accumulate_in_log_space():
    """400 observations whose likelihood ratios (1 : 1e-3 : 1e-3) take the other classes to 1e-1200."""
    m = ClassBeliefMap.from_prior((1, 2), PRIOR, CLASSES)
    lik = np.tile([[1.0, 1e-3, 1e-3]], (2, 1))
    for _ in range(200):
        m.update([[0, 0], [0, 0]], lik)  # 400 observations of cell (0, 0)
    logp = np.log(PRIOR) + 400 * np.log([1.0, 1e-3, 1e-3])
    expected = np.exp(logp - np.logaddexp.reduce(logp))
    np.testing.assert_allclose(m.probs[0, 0], expected, rtol=1e-10, atol=0)
    assert m.probs[0, 0, 0] == 1.0  # oven: the other classes are 1e-1200 below it
    for _ in range(200):  # as much evidence for "sink": back to the prior ratio oven : sink (a belief held in
        m.update([[0, 0], [0, 0]], np.tile([[1e-3, 1.0, 1e-3]], (2, 1)))  # probabilities would stay at oven)
    np.testing.assert_allclose(m.probs[0, 0], [1 / 3, 2 / 3, 0.0], rtol=1e-10, atol=1e-300)
    np.testing.assert_array_equal(m.probs[0, 1], PRIOR)  # untouched


def test_contradictory_evidence_is_refused_and_leaves_the_map_unchanged():
    m = ClassBeliefMap.from_prior((2, 2), [0.5, 0.5, 0.0], CLASSES)
    before = m.probs.copy()
    with pytest.raises(ValueError, match=r"contradictory evidence at cell \(1, 0\)"):
        m.update([[0, 0], [1, 0]], [[0.5, 0.5, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_array_equal(m.probs, before)
    assert not m.probs.flags.writeable


def test_rooms_voxels_and_the_column_reduction():
    labels = np.array([[0, -1], [1, 0]])
    table = np.array([[0.5, 0.1, 0.4], [0.05, 0.6, 0.35]])
    m = ClassBeliefMap.from_rooms(labels, table, PRIOR, CLASSES, layers=3)
    flat = update_class_probs(PRIOR, room_evidence(labels, table, PRIOR))
    np.testing.assert_allclose(m.probs, np.repeat(flat[:, :, None], 3, axis=2), rtol=1e-12)
    m.update([[0, 1], [0, 1]], [[0.9, 0.05, 0.05], [0.2, 0.2, 0.6]], layers=[2, 0])
    lik = np.array([0.6, 0.3, 0.1])
    np.testing.assert_allclose(m.source_probability(lik, PRIOR),
                               semantic_source_probability(m.probs, lik, PRIOR, column_axis=2), rtol=1e-12)
    with pytest.raises(ValueError, match="voxel observations"):
        m.update([[0, 0]], [[1.0, 1.0, 1.0]])


def test_frames_from_anything_with_cells_and_likelihoods_and_sim_semantic_map_is_one():
    from types import SimpleNamespace

    m = ClassBeliefMap.from_prior((2, 2), PRIOR, CLASSES)
    frame = SimpleNamespace(cells=np.array([[1, 1]]), likelihood=np.array([[0.8, 0.1, 0.1]]), layers=None,
                            classes=CLASSES)
    m.observe(frame)
    assert m.n_frames == 1 and m.most_likely()[1, 1] == 0
    with pytest.raises(ValueError, match="frame classes"):
        m.observe(SimpleNamespace(cells=frame.cells, likelihood=frame.likelihood, layers=None, classes=("a", "b", "c")))
    assert issubclass(SemanticMap, ClassBeliefMap)
    with pytest.raises(TypeError, match="frame must be a Frame"):
        SemanticMap.from_prior((2, 2), PRIOR, CLASSES).update(frame)


def test_bad_input():
    with pytest.raises(ValueError, match=r"class_probs must sum to 1"):
        ClassBeliefMap(np.full((2, 2, 3), 0.5), CLASSES)
    with pytest.raises(ValueError, match=r"k = 3 classes"):
        ClassBeliefMap(np.full((2, 2, 2), 0.5), CLASSES)
    with pytest.raises(TypeError, match="classes must be a sequence of class names"):
        ClassBeliefMap.from_prior((2, 2), PRIOR, "abc")
    m = ClassBeliefMap.from_prior((2, 2), np.float32([0.1, 0.2, 0.7]), CLASSES)  # float32 priors accepted
    with pytest.raises(ValueError, match=r"cells must lie inside the 2 x 2 map"):
        m.update([[2, 0]], [[1.0, 1.0, 1.0]])
    with pytest.raises(TypeError, match="cells must hold integer indices"):
        m.update([[0.5, 0]], [[1.0, 1.0, 1.0]])
    with pytest.raises(ValueError, match="one row per cell"):
        m.update([[0, 0]], [[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]])
