"""Bad input raises ValueError/TypeError that names what was expected and what arrived; extremes stay finite."""

import numpy as np
import pytest

from psgsl_pgm import (
    Ontology,
    field_of_view,
    fuse,
    room_evidence,
    semantic_information_gain,
    semantic_source_probability,
    update_class_probs,
)

K = 3
Q = np.array([[0.2, 0.3, 0.5], [0.6, 0.2, 0.2]])
LIK = np.array([0.5, 0.5, 0.0])
PRIOR = np.full(K, 1 / 3)


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(class_probs=Q[:, :2]), ValueError, r"class_probs must have 3 classes.*\(2, 2\)"),
        (dict(class_probs=Q[0]), ValueError, r"cell axes"),
        (dict(class_probs=Q * 1.1), ValueError, r"class_probs must sum to 1 .*tolerance 1e-06.*1\.1"),
        (dict(class_probs=np.where(Q == 0.6, np.nan, Q)), ValueError, r"class_probs must be finite.*nan"),
        (dict(class_probs=np.array([[1.5, -0.5, 0.0], [1, 0, 0]])), ValueError, r"non-negative.*-0\.5"),
        (dict(class_probs=np.array([["a", "b", "c"]])), TypeError, r"class_probs must be a real numeric array"),
        (dict(source_likelihood=[0.5, 0.6, 0.0]), ValueError, r"source_likelihood.*sum to 1"),
        (dict(source_likelihood=np.ones((2, 2, 3))), ValueError, r"\(k,\) or \(m, k\)"),
        (dict(class_prior=[0.5, 0.5]), ValueError, r"class_prior must have shape \(3,\)"),
        (dict(class_prior=[0.0, 0.5, 0.5]), ValueError, r"class_prior is zero for classes \[0\]"),
        (dict(source_likelihood=np.ones((2, 3)) / 3), ValueError, r"gas_probs \(shape \(2,\).*required"),
        (dict(source_likelihood=np.ones((2, 3)) / 3, gas_probs=[1.0]), ValueError, r"gas_probs must have shape \(2,\)"),
        (dict(gas_probs=[1.0]), ValueError, r"gas_probs was given"),
        (dict(column_axis=1), ValueError, r"column_axis"),
        (dict(column_axis=1.0), TypeError, r"column_axis must be an int"),
        (dict(source_prior=[0.5, 0.6]), ValueError, r"source_prior must sum to 1"),
        (dict(source_prior=[1.0]), ValueError, r"source_prior must have the cells' shape \(2,\)"),
    ],
)
def test_semantic_source_probability_rejects(kwargs, error, match):
    args = dict(class_probs=Q, source_likelihood=LIK, class_prior=PRIOR) | kwargs
    pos = [args.pop(k) for k in ("class_probs", "source_likelihood", "class_prior")]
    with pytest.raises(error, match=match):
        semantic_source_probability(*pos, **args)


def test_beliefs_on_a_zero_prior_class_are_refused():
    prior = np.array([0.5, 0.5, 0.0])
    with pytest.raises(ValueError, match=r"mass .* on classes \[2\] whose class_prior is zero"):
        semantic_source_probability(np.array([[0.2, 0.3, 0.5]]), [0.5, 0.5, 0.0], prior)


def test_no_possible_source_is_an_error_not_nan():
    with pytest.raises(ValueError, match="no cell can hold the source"):
        semantic_source_probability(np.array([[0.0, 0.0, 1.0]]), LIK, PRIOR)


def test_fuse_rejects_and_names_conflicting_inputs():
    with pytest.raises(ValueError, match=r"posteriors\[0\] and posteriors\[2\] have no cell"):
        fuse([0.5, 0.5, 0.0, 0.0], [0.25] * 4, [0.0, 0.0, 0.5, 0.5])
    with pytest.raises(ValueError, match=r"posteriors\[1\] must have the shape"):
        fuse([0.5, 0.5], [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"sum to 1"):
        fuse([0.5, 0.6], [0.5, 0.5])
    with pytest.raises(ValueError, match="prior is zero at cell"):
        fuse([0.5, 0.5], [0.5, 0.5], prior=[1.0, 0.0])
    with pytest.raises(TypeError, match="at least one"):
        fuse()


def test_update_and_room_evidence_reject():
    with pytest.raises(ValueError, match="contradictory evidence at cell"):
        update_class_probs([[1.0, 0.0, 0.0]], [0.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="likelihood is zero for every class"):
        update_class_probs(PRIOR, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="must broadcast"):
        update_class_probs(np.tile(PRIOR, (2, 1)), np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"room_labels must lie in \[-1, 0\]"):
        room_evidence([0, 1], [[0.2, 0.3, 0.5]], PRIOR)
    with pytest.raises(TypeError, match="room_labels must be integer"):
        room_evidence(["kitchen"], [[0.2, 0.3, 0.5]], PRIOR)
    with pytest.raises(ValueError, match="class_prior is zero"):
        room_evidence([0], [[0.2, 0.3, 0.5]], [0.5, 0.5, 0.0])


def test_information_gain_and_fov_reject():
    with pytest.raises(ValueError, match="predictive must be 'paper' or 'exact'"):
        semantic_information_gain(Q, LIK, PRIOR, predictive="approx")
    with pytest.raises(ValueError, match=r"olfactory must have the cells' shape \(0, 3\) \(the cells of class_probs\)"):
        semantic_information_gain(np.zeros((0, 3, 3)), LIK, PRIOR, olfactory=np.full((2, 3), 1 / 6))
    with pytest.raises(ValueError, match=r"olfactory must have the cells' shape"):
        semantic_information_gain(Q, LIK, PRIOR, olfactory=[1.0])
    occ = np.zeros((4, 4), bool)
    with pytest.raises(ValueError, match="outside the map"):
        field_of_view(occ, (10, 1, 0), max_range=2, half_angle=1)
    with pytest.raises(ValueError, match="half_angle must be at most"):
        field_of_view(occ, (1, 1, 0), max_range=2, half_angle=4)
    with pytest.raises(ValueError, match=r"pose must be \(x, y, heading\)"):
        field_of_view(occ, (1, 1), max_range=2, half_angle=1)
    with pytest.raises(TypeError, match="occupancy must be boolean"):
        field_of_view(np.full((4, 4), 0.5), (1, 1, 0), max_range=2, half_angle=1)
    with pytest.raises(ValueError, match=r"outside the map \(extent 2e-323 × 2e-323"):  # no overflow warning either
        field_of_view(occ, (1, 1, 0), max_range=2, half_angle=1, resolution=5e-324)
    assert field_of_view(occ, (0, 0, 0), max_range=2, half_angle=np.pi, resolution=5e-324).all()  # 2 m: every cell


def test_tiny_probabilities_do_not_underflow():
    """Priors and beliefs of 1e-300 (ratios up to 1e300) give finite, normalised results."""
    prior = np.array([1e-300, 1 - 1e-300])
    lik = np.array([1.0, 0.0])
    q = np.array([[1e-300, 1 - 1e-300], [2e-300, 1 - 2e-300], [1e-310, 1.0]])
    p = semantic_source_probability(q, lik, prior)
    np.testing.assert_allclose(p, np.array([1.0, 2.0, 1e-10]) / (3 + 1e-10), rtol=1e-9)  # 1e-310 / 1e-300 = 1e-10
    gain = semantic_information_gain(q, lik, prior, predictive="exact")
    assert np.all(np.isfinite(gain)) and np.all(gain >= 0)
    post = update_class_probs(np.array([1e-300, 1.0]), np.array([1.0, 1e-300]))
    np.testing.assert_allclose(post, [0.5, 0.5])
    assert np.isfinite(fuse(*[np.full(10, 0.1)] * 400)).all()


def test_priors_whose_ratios_exceed_float64_stay_finite():
    """p(o | s) / p(o) beyond 1.8e308 (a prior of 7e-314): the ratio is scaled in log space, never inf or NaN."""
    lik = np.array([0.4, 0.25, 0.35, 0.0])
    prior = np.array([7.4e-314, 0.5, 0.5 - 7.4e-314, 0.0])
    q = np.array([[0.1, 0.5, 0.4, 0.0], [0.0, 0.5, 0.5, 0.0]])
    p = semantic_source_probability(q, lik, prior)
    np.testing.assert_allclose(p, [1.0, 0.6 * 7.4e-314 / (0.1 * 0.4)], rtol=1e-6)  # cell 0 weighs 0.1 · 0.4 / 7.4e-314
    gain = semantic_information_gain(q, lik, prior, predictive="exact")
    assert np.all(np.isfinite(gain)) and np.all(gain >= 0)
    table = np.array([[0.4, 0.3, 0.3, 0.0], [0.0, 0.5, 0.5, 0.0]])
    f = room_evidence([0, 1, -1], table, np.array([5e-324, 0.5, 0.5, 0.0]))
    np.testing.assert_array_equal(f[1:], [[0.0, 1.0, 1.0, 0.0], [1.0] * 4])  # rows in range: the plain quotient
    assert f[0, 0] == 1.0 and np.all(np.isfinite(f)) and f[0, 3] == 0.0


def test_ten_million_cells_stay_finite_and_normalised():
    n = 10_000_000
    q = np.empty((n, 2))
    q[:, 0] = np.linspace(0, 1, n)
    q[:, 1] = 1 - q[:, 0]
    p = semantic_source_probability(q, [1.0, 0.0], [0.5, 0.5])
    assert np.isfinite(p).all() and abs(p.sum() - 1) < 1e-12
    fused = fuse(p, np.full(n, 1.0 / n))
    np.testing.assert_allclose(fused, p, rtol=1e-12, atol=1e-300)


def test_ontology_rejects_bad_data(tmp_path):
    with pytest.raises(ValueError, match=r"unknown ontology keys \['colours'\]"):
        Ontology.from_dict({"classes": ["a"], "gases": {"g": {"a": 1.0}}, "colours": 1})
    with pytest.raises(ValueError, match=r"unknown class 'b' in gases.g"):
        Ontology.from_dict({"classes": ["a"], "gases": {"g": {"b": 1.0}}})
    with pytest.raises(ValueError, match=r"gases.g sums to 1.2 > 1"):
        Ontology.from_dict({"classes": ["a", "b"], "gases": {"g": {"a": 0.6, "b": 0.6}}})
    with pytest.raises(TypeError, match=r"gases.g.a must be a number"):
        Ontology.from_dict({"classes": ["a"], "gases": {"g": {"a": "high"}}})
    with pytest.raises(ValueError, match="lacks the required key 'gases'"):
        Ontology.from_dict({"classes": ["a"]})
    ont = Ontology.from_dict({"classes": ["a"], "gases": {"g": {"a": 1.0}}})
    with pytest.raises(ValueError, match=r"unknown gas 'smoke'; known: \['g'\]"):
        ont.source_likelihood("smoke")
    bad = tmp_path / "bad.yaml"
    bad.write_text("classes: [a\ngases: {")
    with pytest.raises(ValueError, match=r"bad.yaml: not valid YAML"):
        Ontology.from_yaml(bad)
    with pytest.raises(FileNotFoundError, match=r"missing.yaml: no such file"):
        Ontology.from_yaml(tmp_path / "missing.yaml")
