"""Class beliefs from a mapper (a world's ``semantic_map:``, ``--class-probs``) still get the room evidence in
``semantics+rooms``: p(o | z, room) ∝ p(o | z) p(o | room) / p(o), checked by hand per cell."""

from __future__ import annotations

import dataclasses

import numpy as np


def test_mapper_beliefs_get_the_room_evidence_in_semantics_plus_rooms(house):
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors
    from psgsl_pgm.sim import default_world, make_world

    spec = default_world()
    ont = spec.ontology
    assert len(ont.rooms) >= 2
    rng = np.random.default_rng(5)
    given = rng.dirichlet(np.full(len(ont.classes), 0.6), size=house.shape)  # a mapper's p(o | z), ontology order
    world = make_world(house, seed=0, warm_up=1.0)
    beliefs = VariantPosteriors(world, "infotaxis", ExperimentConfig(),
                                setting=dataclasses.replace(spec, class_beliefs=given))
    assert beliefs.mapped
    classes = list(world.detector.classes)
    order = [ont.classes.index(c) for c in classes]  # the maps hold the detector's class order
    q = given[..., order]
    beta = ont.class_prior[order]
    table = ont.room_table[:, order]
    table = table / table.sum(axis=1, keepdims=True)
    want = q.copy()
    in_a_room = np.zeros(house.shape, bool)
    for label, name in enumerate(house.room_names):
        if name not in ont.rooms:
            continue
        cells = house.room_labels == label
        in_a_room |= cells
        w = q[cells] * (table[ont.rooms.index(name)] / beta)
        want[cells] = w / w.sum(axis=1, keepdims=True)
    assert in_a_room.mean() > 0.25  # the evidence reaches a good part of the house
    np.testing.assert_allclose(np.asarray(beliefs.maps["semantics"].probs), q, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(beliefs.maps["semantics+rooms"].probs), want, rtol=1e-12, atol=1e-300)
    # and it reaches the posteriors: the two semantic variants differ
    plain, rooms = beliefs.posteriors(("semantics", "semantics+rooms"))
    assert np.max(np.abs(plain - rooms)) > 0.1 * plain.max()


def test_off_ontology_mixes_the_robots_ontology_and_keys_its_runs(house):
    """ExperimentConfig(off_ontology=ε): the robot's p(o | s, γ) is (1 − ε) p(o | s, γ) + ε β, so each cell's
    semantic weight is (1 − ε) Σ_i q_ci p(o_i | s) / β_i + ε, checked by hand; ε = 0 leaves the stored config
    as it was; a rate outside [0, 1] is refused by name."""
    import pytest

    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors
    from psgsl_pgm.sim import make_world

    from psgsl_pgm.experiment._step import visit

    world = make_world(house, seed=0, warm_up=1.0)
    plain = VariantPosteriors(world, "infotaxis", ExperimentConfig())
    mixed = VariantPosteriors(world, "infotaxis", ExperimentConfig(off_ontology=0.2))
    stop = (5.0, 6.0)  # the hallway: the camera sees the living room and the kitchen's door
    seen = visit(world, stop, np.linspace(0.0, 2 * np.pi, 8, endpoint=False), ExperimentConfig())
    plain.observe(stop, *seen)
    mixed.observe(stop, *seen)
    np.testing.assert_allclose(mixed.likelihood, 0.8 * plain.likelihood + 0.2 * plain.class_prior, rtol=1e-15)
    for variant in ("semantics", "semantics+rooms"):
        q = mixed.maps[variant].probs
        weight = 0.8 * (q @ (plain.likelihood / plain.class_prior)) + 0.2  # (1 − ε) r_c + ε
        np.testing.assert_allclose(mixed.semantic(variant), weight / weight.sum(), rtol=1e-10, atol=0)
        assert not np.allclose(plain.semantic(variant), mixed.semantic(variant), rtol=1e-3)
    assert "off_ontology" not in ExperimentConfig().to_dict()
    assert ExperimentConfig(off_ontology=0.2).to_dict()["off_ontology"] == 0.2
    for bad in (1.5, -0.1, float("nan")):
        with pytest.raises(ValueError, match="off_ontology"):
            ExperimentConfig(off_ontology=bad)
    with pytest.raises(TypeError, match="off_ontology"):
        ExperimentConfig(off_ontology=True)


def test_missed_hit_rate_reaches_the_estimator_and_keys_runs_only_when_set(house):
    """ExperimentConfig(missed_hit_rate=δ): the robot's GridInfotaxis gets δ (PMFS has no such rate); δ = 0 leaves
    the stored config as it was; a δ outside [0, 1) is refused by name."""
    import pytest

    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors
    from psgsl_pgm.sim import make_world

    world = make_world(house, seed=0, warm_up=1.0)
    assert VariantPosteriors(world, "infotaxis", ExperimentConfig(missed_hit_rate=0.05)).estimator.missed_hit_rate \
        == 0.05
    assert VariantPosteriors(world, "infotaxis", ExperimentConfig()).estimator.missed_hit_rate == 0.0
    assert "missed_hit_rate" not in ExperimentConfig().to_dict()
    assert ExperimentConfig(missed_hit_rate=0.05).to_dict()["missed_hit_rate"] == 0.05
    for bad in (1.0, -0.1, float("nan")):
        with pytest.raises(ValueError, match="missed_hit_rate"):
            ExperimentConfig(missed_hit_rate=bad)
    with pytest.raises(TypeError, match="missed_hit_rate"):
        ExperimentConfig(missed_hit_rate=True)

