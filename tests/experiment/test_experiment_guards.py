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
