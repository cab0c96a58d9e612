"""The robot that is not told the gas: its counted e-nose confusion, its gas mixture, the episode's drawn gas."""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm.experiment import ExperimentConfig, VariantPosteriors, house_ontology, robot_gas_confusion
from psgsl_pgm.experiment._step import start_run
from psgsl_pgm.sim import ElectronicNose, Smell, draw_gas


def test_counted_confusion_is_a_distribution_and_weak_bins_are_worse():
    gases = house_ontology().gases
    conf, edges = robot_gas_confusion(tuple(gases))
    assert conf.shape == (len(edges) - 1, len(gases), len(gases))
    np.testing.assert_allclose(conf.sum(axis=2), 1.0, rtol=1e-12)
    diag = np.einsum("bgg->bg", conf)
    assert (diag[-1] > 0.98).all()                    # strong readings: named right
    assert (diag[0] < diag[-1] - 0.3).all()           # the weakest bin: much worse
    assert (np.diff(diag, axis=0) > -0.005).all()     # and the diagonal grows with the strength
    assert (conf > 0).all()                           # Dirichlet smoothing: no confusion is certain


def test_counted_confusion_is_counted_not_read():
    """More exposures, another seed: the table moves by its sampling error only (it is a count)."""
    gases = ("smoke", "ethanol")
    a, _ = robot_gas_confusion(gases, seed=0)
    b, _ = robot_gas_confusion(gases, seed=1)
    assert not np.array_equal(a, b) and np.abs(a - b).max() < 0.06


def test_confusion_guards():
    with pytest.raises(ValueError, match="gases must be gases the e-nose knows"):
        robot_gas_confusion(("smoke", "chlorine"))
    with pytest.raises(ValueError, match="exposures"):
        robot_gas_confusion(("smoke",), exposures=0)


def test_start_run_draws_the_gas_and_gives_the_world_an_enose():
    cfg = ExperimentConfig(gas="unknown", warm_up=2.0)
    *_, world = start_run("oven", 5, "infotaxis", cfg)
    assert isinstance(world.enose, ElectronicNose)
    assert world.gas_type == draw_gas(house_ontology().gases, 5)
    *_, world = start_run("oven", 5, "infotaxis", cfg, gas_type="ammonia")
    assert world.gas_type == "ammonia"
    with pytest.raises(ValueError, match="gas_type names the true gas"):
        start_run("oven", 5, "infotaxis", ExperimentConfig(warm_up=2.0), gas_type="ammonia")
    with pytest.raises(ValueError, match="gas_type must be one of"):
        start_run("oven", 5, "infotaxis", cfg, gas_type="chlorine")
    *_, told = start_run("oven", 5, "infotaxis", ExperimentConfig(warm_up=2.0))
    assert told.enose is None and told.gas_type is None


def test_the_semantic_term_is_the_gas_mixture_by_enumeration():
    """p(s | z, ζ) ∝ Σ_γ p(γ | ζ) p(s | z, γ)-weights, enumerated over γ and the classes of every cell (1e-10)."""
    cfg = ExperimentConfig(gas="unknown", warm_up=2.0)
    *_, world = start_run("oven", 0, "infotaxis", cfg)
    beliefs = VariantPosteriors(world, "infotaxis", cfg, variants=("semantics+rooms",))
    np.testing.assert_allclose(beliefs.gas_probs, 0.25, rtol=1e-15)
    for smell in (Smell("ammonia", 0.65), Smell("ammonia", 1.1), Smell(None, 0.2), Smell("smoke", 0.55)):
        beliefs.observe_smell(smell)
    p = beliefs.gas_probs
    assert p.argmax() == beliefs.gas_belief.gases.index("ammonia") and abs(p.sum() - 1) < 1e-12
    q = beliefs.maps["semantics+rooms"].probs  # (H, W, k)
    weights = sum(p[g] * (q / beliefs.class_prior) @ beliefs.likelihood[g] for g in range(len(p)))
    np.testing.assert_allclose(beliefs.semantic("semantics+rooms"), weights / weights.sum(), rtol=1e-10, atol=0)
    told = VariantPosteriors(world, "infotaxis", ExperimentConfig(gas="ammonia", warm_up=2.0),
                             variants=("semantics+rooms",))
    assert told.gas_probs is None and told.likelihood.ndim == 1
    told.observe_smell(Smell("smoke", 3.0))  # a told gas: nothing to infer
    assert told.gas_belief is None


def test_a_gas_the_ontology_lacks_is_refused():
    *_, world = start_run("oven", 0, "infotaxis", ExperimentConfig(warm_up=0.0))
    with pytest.raises(ValueError, match="gas must be one of the ontology's gases .* or 'unknown'"):
        VariantPosteriors(world, "infotaxis", ExperimentConfig(gas="chlorine"))


def test_the_fixed_tour_with_the_gas_unknown_changes_only_the_semantic_variants():
    """The e-nose draws from its own stream: p(s | g) (variant olfaction) is the told run's, bit for bit; the
    semantic variants use the mixture and differ."""
    from psgsl_pgm.experiment import run_search

    unknown = run_search("oven", 2, config=ExperimentConfig(gas="unknown", stops=4))
    told = run_search("oven", 2, config=ExperimentConfig(gas=draw_gas(house_ontology().gases, 2), stops=4))
    np.testing.assert_array_equal(unknown.error[:, 0], told.error[:, 0])
    np.testing.assert_array_equal(unknown.hit, told.hit)
    assert not np.array_equal(unknown.error[:, 2], told.error[:, 2])


def test_a_run_with_the_gas_unknown_is_not_recorded():
    from psgsl_pgm.experiment._record import EpisodeRecorder

    *_, world = start_run("oven", 0, "infotaxis", ExperimentConfig(gas="unknown", warm_up=0.0))
    with pytest.raises(ValueError, match="--record cannot record a run whose gas is unknown"):
        EpisodeRecorder().watch(world)
