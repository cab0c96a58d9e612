"""Camera field of view, detector statistics, and the class-belief map (exact Bayes, convergence, rooms, voxels)."""

import numpy as np
import pytest
from scipy.special import logsumexp

from psgsl_pgm import Ontology, semantic_source_probability
from psgsl_pgm.sim import (
    HOUSE_CLASSES,
    HOUSE_ROOMS,
    NOTHING,
    OTHER,
    Camera,
    DetectorModel,
    SemanticMap,
    default_house,
    take_frame,
)


def _prior(classes, other=0.7):
    k = len(classes)
    p = np.full(k, (1 - other) / (k - 1))
    p[list(classes).index(OTHER)] = other
    return p


# ---- field of view -------------------------------------------------------------------------------------------
def test_fov_never_sees_through_walls(house):
    """From anywhere in the west bedroom, in any direction, nothing of the bathroom or the east bedroom is
    seen (a straight line would have to cross the hallway wall twice), and only free cells are reported."""
    h = house
    cam = Camera(max_range=9.0, half_angle=np.pi)
    rng = np.random.default_rng(0)
    bed = HOUSE_ROOMS.index("Bedroom")
    west = (h.room_labels == bed) & (h.grid.cell_centres()[..., 0] < 5.6)
    east = (h.room_labels == bed) & ~west
    bath = h.room_labels == HOUSE_ROOMS.index("Bathroom")
    cells = np.argwhere(west & ~h.furniture)
    for rc in cells[rng.choice(len(cells), 12, replace=False)]:
        x, y = h.grid.cell_to_world(rc) + rng.uniform(-0.04, 0.04, 2)
        vis = cam.visible(h.grid, (x, y, rng.uniform(-np.pi, np.pi)))
        assert not (vis & (bath | east)).any()
        assert not (vis & h.grid.occupancy).any()
        assert vis.sum() > 50  # it does see its own room


def test_fov_respects_range_and_angle(house):
    h = house
    cam = Camera(max_range=3.0, half_angle=np.deg2rad(30), min_range=0.5)
    pose = (3.0, 2.5, 0.0)  # living room, looking east
    vis = cam.visible(h.grid, pose)
    xy = h.grid.cell_centres()[vis]
    d = np.hypot(xy[:, 0] - 3.0, xy[:, 1] - 2.5)
    ang = np.arctan2(xy[:, 1] - 2.5, xy[:, 0] - 3.0)
    assert vis.sum() > 100
    assert (d <= 3.0 + 1e-9).all() and (d >= 0.5 - 1e-9).all() and (np.abs(ang) <= np.deg2rad(30) + 1e-9).all()


# ---- detector ------------------------------------------------------------------------------------------------
def test_default_confusion_structure():
    det = DetectorModel.default()
    c = det.confusion
    lab = list(det.labels)
    assert lab[-1] == NOTHING and len(lab) == len(HOUSE_CLASSES)
    np.testing.assert_allclose(c.sum(axis=1), 1.0, rtol=0, atol=1e-12)
    oven = HOUSE_CLASSES.index("oven")
    assert c[oven, lab.index("oven")] == pytest.approx(0.85)
    assert c[oven, lab.index("microwave")] == pytest.approx(c[oven, lab.index("toaster")])
    assert c[oven, lab.index("microwave")] > 10 * c[oven, lab.index("bed")] > 0
    sink = HOUSE_CLASSES.index("sink")
    assert c[sink, lab.index("toilet")] > 10 * c[sink, lab.index("oven")]
    fridge = HOUSE_CLASSES.index("refrigerator")
    assert c[fridge, lab.index("refrigerator")] == pytest.approx(0.98)
    np.testing.assert_allclose(c[HOUSE_CLASSES.index(OTHER)], 1 / (len(HOUSE_CLASSES) - 1))


def test_detector_statistics_match_configuration():
    """Label frequencies over many draws vs. the configured table: within 5 binomial standard errors."""
    det = DetectorModel.default(p_max=0.8, near=1.0, scale=2.0, false_positive=0.05)
    rng = np.random.default_rng(0)
    n = 100_000
    k = len(HOUSE_CLASSES)
    for cls in ("oven", "sink", OTHER, "tv"):
        i = HOUSE_CLASSES.index(cls)
        for d in (0.5, 3.0):
            labels = det.sample(np.full(n, i), np.full(n, d), rng)
            freq = np.bincount(labels, minlength=k) / n
            p = det.table(d)[i]
            se = np.sqrt(p * (1 - p) / n)
            assert np.all(np.abs(freq - p) <= 5 * se + 1e-12), (cls, d)
    pd = det.detection_probability([0.5, 1.0, 3.0, 5.0])
    np.testing.assert_allclose(pd, 0.8 * np.exp(-np.maximum(np.array([0.5, 1.0, 3.0, 5.0]) - 1.0, 0) / 2.0))
    oven = HOUSE_CLASSES.index("oven")
    # p(nothing | oven, d) = 1 - p_d(d); p(some label | other) = false_positive
    assert det.table(3.0)[oven, -1] == pytest.approx(1 - 0.8 * np.exp(-1.0))
    assert det.table(3.0)[HOUSE_CLASSES.index(OTHER), -1] == pytest.approx(0.95)


def test_likelihood_is_the_table_column():
    det = DetectorModel.default()
    rng = np.random.default_rng(1)
    labels = rng.integers(0, len(HOUSE_CLASSES), 50)
    dist = rng.uniform(0, 5, 50)
    lik = det.likelihood(labels, dist)
    for z, d, row in zip(labels, dist, lik):
        np.testing.assert_allclose(row, det.table(d)[:, z], rtol=1e-14)
    with pytest.raises(ValueError, match="labels"):
        det.likelihood(np.array([len(HOUSE_CLASSES)]), np.array([1.0]))


def test_detector_model_validation():
    with pytest.raises(ValueError, match="other"):
        DetectorModel(("oven", "sink"), np.full((2, 1), 1.0))
    with pytest.raises(ValueError, match="shape"):
        DetectorModel(("oven", OTHER), np.full((2, 2), 0.5))
    with pytest.raises(ValueError, match="false_positive"):
        DetectorModel.default(false_positive=1.5)


# ---- belief map ----------------------------------------------------------------------------------------------
def test_belief_update_is_exact_bayes(house):
    """After several frames, every cell's belief equals prior × Π p(z | o), normalised (log-space reference)."""
    h = house
    det = DetectorModel.default()
    cam = Camera()
    prior = _prior(det.classes)
    smap = SemanticMap.from_prior(h.shape, prior, det.classes)
    rng = np.random.default_rng(2)
    logp = np.broadcast_to(np.log(prior), h.shape + prior.shape).copy()
    for pose in [(7.6, 3.5, -np.pi / 2), (7.0, 2.0, 0.0), (7.6, 3.5, -np.pi / 2), (4.0, 3.0, 0.3)]:
        f = take_frame(h, pose, camera=cam, detector=det, rng=rng)
        smap.update(f)
        for (r, c), lik in zip(f.cells, f.likelihood):
            logp[r, c] += np.log(lik)
    ref = np.exp(logp - logsumexp(logp, axis=-1, keepdims=True))
    np.testing.assert_allclose(smap.probs, ref, rtol=1e-10, atol=1e-300)
    assert smap.n_frames == 4


def test_beliefs_converge_to_true_classes(house):
    h = house
    det = DetectorModel.default()
    cam = Camera(max_range=4.0)
    prior = _prior(det.classes)
    smap = SemanticMap.from_prior(h.shape, prior, det.classes)
    rng = np.random.default_rng(3)
    pose = (7.6, 3.8, -np.pi / 2)  # kitchen, looking at the oven wall
    seen = cam.visible(h.grid, pose)
    truth = h.class_map
    assert seen.sum() > 200 and set(HOUSE_CLASSES[i] for i in np.unique(truth[seen])) >= {"oven", "sink", "chair"}
    worst = []
    for n in range(1, 121):
        smap.update(take_frame(h, pose, camera=cam, detector=det, rng=rng))
        if n % 40 == 0:  # belief in the true class, worst cell in view
            worst.append(smap.probs[seen][np.arange(seen.sum()), truth[seen]].min())
    np.testing.assert_array_equal(smap.most_likely()[seen], truth[seen])
    assert worst[0] < worst[1] < worst[2] and worst[2] > 0.999
    np.testing.assert_allclose(smap.probs[~seen], np.broadcast_to(prior, ((~seen).sum(), len(prior))), rtol=1e-12)


def test_room_prior_from_ontology_table(house):
    h = house
    classes = HOUSE_CLASSES
    prior = _prior(classes, other=0.8)
    table = np.tile(prior, (2, 1))
    table[0] = 0.0
    table[0, classes.index("oven")] = 0.3
    table[0, classes.index(OTHER)] = 0.7  # a "kitchen" row
    ont = Ontology(classes, ["smoke"], np.full((1, len(classes)), 1 / len(classes)), class_prior=prior,
                   rooms=["kitchen", "bathroom"], room_table=table)
    from psgsl_pgm.sim import reindex

    labels = reindex(h.room_labels, h.room_names, ont.rooms)
    smap = SemanticMap.from_rooms(labels, ont.room_table, ont.class_prior, ont.classes)
    kitchen = h.room_labels == HOUSE_ROOMS.index("Kitchen")
    bath = h.room_labels == HOUSE_ROOMS.index("Bathroom")
    np.testing.assert_allclose(smap.probs[kitchen], np.broadcast_to(table[0], (kitchen.sum(), len(classes))), rtol=1e-12)
    np.testing.assert_allclose(smap.probs[bath], np.broadcast_to(table[1], (bath.sum(), len(classes))), rtol=1e-12)
    rest = ~kitchen & ~bath
    np.testing.assert_allclose(smap.probs[rest], np.broadcast_to(prior, (rest.sum(), len(classes))), rtol=1e-12)


def test_voxel_map_converges_and_reduces_to_columns(house):
    h = house
    det = DetectorModel.default()
    cam = Camera(height=1.0, vertical_half_angle=np.deg2rad(40))
    edges = np.array([0.0, 0.5, 1.0, 1.5])
    prior = _prior(det.classes)
    vmap = SemanticMap.from_prior(h.shape + (3,), prior, det.classes)
    rng = np.random.default_rng(4)
    pose = (8.0, 3.0, -0.6)  # kitchen, towards the microwave on the counter
    frames = [take_frame(h, pose, camera=cam, detector=det, rng=rng, layer_edges=edges) for _ in range(60)]
    for f in frames:
        vmap.update(f)
    f = frames[0]
    truth = h.voxel_class_map(edges)
    seen = np.zeros(truth.shape, bool)
    seen[f.cells[:, 0], f.cells[:, 1], f.layers] = True
    # near cells: the low layer is below the vertical field of view
    near = np.hypot(*(h.grid.cell_centres() - pose[:2]).transpose(2, 0, 1)) < 0.55
    assert seen[..., 1].sum() > 100 and not (seen[..., 0] & near).any()
    np.testing.assert_array_equal(vmap.most_likely()[seen], truth[seen])
    mw = h.grid.world_to_cell(h.objects_of_class("microwave")[0].center)
    assert seen[mw[0], mw[1], 1] and HOUSE_CLASSES[vmap.most_likely()[mw[0], mw[1], 1]] == "microwave"
    # reduction to 2-D columns with the core
    lik = np.full(len(HOUSE_CLASSES), 0.01)
    lik[HOUSE_CLASSES.index("microwave")] = 0.5
    src = semantic_source_probability(vmap.probs, lik / lik.sum(), prior, column_axis=2)
    assert src.shape == h.shape and src.sum() == pytest.approx(1.0)
    with pytest.raises(ValueError, match="voxel"):
        SemanticMap.from_prior(h.shape, prior, det.classes).update(frames[0])


def test_miscalibrated_model_and_class_order(house):
    """Frames can be generated by one detector and interpreted with another model; a detector with another
    class order sees the same truth (names are matched)."""
    h = house
    order = tuple(reversed(HOUSE_CLASSES))
    det = DetectorModel.default(order, false_positive=0.0, p_max=1.0, near=100.0, leak=0.0, correct=1.0)
    f = take_frame(h, (7.6, 3.8, -np.pi / 2), camera=Camera(), detector=det, rng=np.random.default_rng(0))
    names = np.array(det.labels)[f.labels]
    truth = np.array(HOUSE_CLASSES)[h.class_map[f.cells[:, 0], f.cells[:, 1]]]
    np.testing.assert_array_equal(names, np.where(truth == OTHER, NOTHING, truth))
    model = DetectorModel.default(order)
    g = take_frame(h, (7.6, 3.8, -np.pi / 2), camera=Camera(), detector=det, model=model,
                   rng=np.random.default_rng(0))
    np.testing.assert_allclose(g.likelihood, model.likelihood(g.labels, g.distance))
    with pytest.raises(ValueError, match="classes"):
        take_frame(h, (7.6, 3.8, 0.0), camera=Camera(), detector=det, model=DetectorModel.default(),
                   rng=np.random.default_rng(0))
