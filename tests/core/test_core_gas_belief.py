"""p(γ | ζ_1:t) from classified readings: enumeration, the bins, the guards."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from psgsl_pgm import GasBelief

GASES = ("smoke", "ethanol", "ammonia")


def _confusion(rng, bins=3, m=3):
    c = rng.random((bins, m, m)) + np.eye(m) * np.arange(1, bins + 1)[:, None, None]  # stronger bins: more diagonal
    return c / c.sum(axis=2, keepdims=True)


def test_belief_equals_enumeration_over_every_reading_sequence():
    """p(γ | ζ_1:t) ∝ p(γ) Π_u p(ζ_u | γ, b_u), against a sum over the joint of γ and the readings."""
    rng = np.random.default_rng(0)
    conf, edges = _confusion(rng), np.array([0.0, 0.5, 1.0, np.inf])
    prior = np.array([0.5, 0.3, 0.2])
    strengths = (0.2, 0.7, 3.0)
    for labels in itertools.product((*GASES, None), repeat=3):
        belief = GasBelief(GASES, conf, edges, prior=prior)
        for z, s in zip(labels, strengths):
            belief.update(z, s)
        joint = prior.copy()  # p(γ, ζ_1:3) by the chain rule, reading by reading
        for z, b in zip(labels, range(3)):
            if z is not None:
                joint = joint * conf[b, :, GASES.index(z)]
        np.testing.assert_allclose(belief.probs, joint / joint.sum(), rtol=1e-12, atol=0)
        assert belief.n_readings == sum(z is not None for z in labels)


def test_strength_bins():
    belief = GasBelief(GASES, _confusion(np.random.default_rng(1)), [0.0, 0.5, 1.0, np.inf])
    assert [belief.bin_of(s) for s in (0.0, 0.49, 0.5, 0.99, 1.0, 1e9)] == [0, 0, 1, 1, 2, 2]


def test_repeated_right_readings_converge():
    conf = np.array([[[0.6, 0.2, 0.2], [0.2, 0.6, 0.2], [0.2, 0.2, 0.6]]])
    belief = GasBelief(GASES, conf, [0.0, np.inf])
    for _ in range(20):
        belief.update("ammonia", 1.0)
    assert belief.probs[2] > 0.999999 and abs(belief.probs.sum() - 1) < 1e-15


def test_guards_name_the_argument():
    conf = _confusion(np.random.default_rng(2))
    edges = [0.0, 0.5, 1.0, np.inf]
    bad = conf.copy()
    bad[0, 0, 0] += 0.1
    with pytest.raises(ValueError, match="confusion"):
        GasBelief(GASES, bad, edges)
    with pytest.raises(ValueError, match="confusion must have shape"):
        GasBelief(GASES, conf[:, :2, :2], edges)
    with pytest.raises(ValueError, match="edges"):
        GasBelief(GASES, conf, [0.0, 1.0, 0.5, np.inf])
    with pytest.raises(ValueError, match="prior"):
        GasBelief(GASES, conf, edges, prior=[0.5, 0.5])
    belief = GasBelief(GASES, conf, edges)
    with pytest.raises(ValueError, match="label must be one of"):
        belief.update("chlorine", 1.0)
    with pytest.raises(ValueError, match="strength"):
        belief.update("smoke", float("nan"))
    impossible = np.zeros((1, 2, 2))
    impossible[0, :, 0] = 1.0
    with pytest.raises(ValueError, match="impossible"):
        GasBelief(("a", "b"), impossible, [0.0, np.inf]).update("b", 1.0)
