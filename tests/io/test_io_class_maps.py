"""A mapper's class beliefs from files: .npy, .npz with class names, Voxeland instance maps (JSON)."""

import json

import numpy as np
import pytest

from psgsl_pgm import semantic_source_probability
from psgsl_pgm.io._class_maps import read_class_beliefs, voxeland_class_beliefs
from psgsl_pgm.sim import GridMap

CLASSES = ("oven", "microwave", "other")
PRIOR = np.array([0.1, 0.1, 0.8])


def test_npy_in_the_ontology_order(tmp_path):
    p = np.random.default_rng(0).dirichlet(np.ones(3), size=(4, 5))
    np.save(tmp_path / "b.npy", p)
    np.testing.assert_array_equal(read_class_beliefs(tmp_path / "b.npy", CLASSES), p)
    np.save(tmp_path / "bad.npy", p[..., :2])
    with pytest.raises(ValueError, match=r"bad\.npy: class beliefs must have shape \(\.\.\., 3\)"):
        read_class_beliefs(tmp_path / "bad.npy", CLASSES)
    np.save(tmp_path / "neg.npy", p * 2)
    with pytest.raises(ValueError, match=r"neg\.npy"):
        read_class_beliefs(tmp_path / "neg.npy", CLASSES)


def test_npz_columns_matched_by_name_unlisted_into_other(tmp_path):
    rng = np.random.default_rng(1)
    p = rng.dirichlet(np.ones(4), size=(3, 2))
    np.savez(tmp_path / "b.npz", probs=p, classes=np.array(["Microwave", "bed", "stove", "background"]))
    # a class the ontology lacks is refused, naming the closest known names, unless lumped knowingly
    with pytest.raises(ValueError, match=r"b\.npz: array 'classes': class the ontology does not list: 'bed' "
                                         r"\(known: oven, microwave, other\); .*other_classes=\"lump\""):
        read_class_beliefs(tmp_path / "b.npz", CLASSES)
    got = read_class_beliefs(tmp_path / "b.npz", CLASSES, other_classes="lump")
    np.testing.assert_allclose(got, np.stack([p[..., 2], p[..., 0], p[..., 1] + p[..., 3]], -1), rtol=1e-12)
    # background is part of "other" without lumping: stove (an alias of oven), microwave, background
    np.savez(tmp_path / "e.npz", probs=p[..., :3] / p[..., :3].sum(-1, keepdims=True),
             classes=np.array(["background", "stove", "microwave"]))
    q = p[..., :3] / p[..., :3].sum(-1, keepdims=True)
    np.testing.assert_allclose(read_class_beliefs(tmp_path / "e.npz", CLASSES),
                               np.stack([q[..., 1], q[..., 2], q[..., 0]], -1), rtol=1e-12)
    np.savez(tmp_path / "c.npz", probs=p)
    with pytest.raises(ValueError, match=r"c\.npz: an \.npz of class beliefs needs arrays 'probs' and 'classes'"):
        read_class_beliefs(tmp_path / "c.npz", CLASSES)
    np.savez(tmp_path / "d.npz", probs=p, classes=np.array(["oven", "stove", "a", "b"]))
    with pytest.raises(ValueError, match=r"class 'stove' appears twice"):
        read_class_beliefs(tmp_path / "d.npz", CLASSES)


def voxeland(tmp_path, instances):
    path = tmp_path / "voxeland_instanceMap.json"
    path.write_text(json.dumps({"instances": instances}))
    return path


def test_voxeland_dirichlet_means_in_boxes_prior_elsewhere(tmp_path):
    grid = GridMap(np.zeros((4, 5), bool), 0.5, (0.0, 0.0))
    path = voxeland(tmp_path, {
        "0": {"bbox": {"center": [0.75, 0.75, 0.25], "size": [1.0, 1.0, 0.5]},
              "results": {"oven": 6.0, "microwave": 2.0, "chair": 2.0}, "n_observations": 5},
        "1": {"bbox": {"center": [1.25, 0.75, 0.75], "size": [0.5, 0.5, 0.5]},
              "results": {"fridge": 1.0, "microwave": 3.0}, "n_observations": 2},
        "2": {"bbox": {"center": [2.0, 1.5, 0.5], "size": [0.5, 0.5, 0.5]},
              "results": {"oven": 9.0}, "n_observations": 0},  # never observed: no evidence
    })
    with pytest.raises(ValueError, match=r"key 'instances\.0\.results': class the ontology does not list: 'chair'"):
        read_class_beliefs(path, CLASSES, grid=grid, class_prior=PRIOR)
    b = read_class_beliefs(path, CLASSES, grid=grid, class_prior=PRIOR, other_classes="lump")
    assert b.shape == (4, 5, 2, 3)  # layers of 0.5 m from z = 0 to 1
    inst0 = np.array([6.0, 2.0, 2.0]) / 10  # chair -> other
    for r, c in ((1, 1), (1, 2), (2, 1), (2, 2)):  # cells whose centre lies in box 0 (x, y in [0.25, 1.25])
        np.testing.assert_allclose(b[r, c, 0], inst0, rtol=1e-12)
    np.testing.assert_allclose(b[1, 2, 1], [0.0, 0.75, 0.25], rtol=1e-12)  # box 1 only, layer 1
    np.testing.assert_allclose(b[3, 4, 0], PRIOR, rtol=1e-12)
    np.testing.assert_allclose(b[1, 1, 1], PRIOR, rtol=1e-12)  # above box 0
    np.testing.assert_allclose(b[3, 4], PRIOR[None].repeat(2, 0), rtol=1e-12)  # box 2 ignored
    # overlapping boxes add their alphas
    both = voxeland_class_beliefs({"instances": {
        "a": {"bbox": {"center": [0.25, 0.25, 0.25], "size": [0.5, 0.5, 0.5]}, "results": {"oven": 1.0},
              "n_observations": 1},
        "b": {"bbox": {"center": [0.25, 0.25, 0.25], "size": [0.5, 0.5, 0.5]}, "results": {"microwave": 3.0},
              "n_observations": 1}}}, CLASSES, grid=grid, class_prior=PRIOR, other_classes="lump")
    np.testing.assert_allclose(both[0, 0, 0], [0.25, 0.75, 0.0], rtol=1e-12)
    # the voxel columns reduce to cells (Sec. "Voxelized Scene Representations")
    s = semantic_source_probability(b, [0.6, 0.3, 0.1], PRIOR, column_axis=2)
    assert s.shape == (4, 5) and s[1, 1] > s[3, 4]


@pytest.mark.parametrize("instances, message", [
    ({"0": {"bbox": {"center": [0, 0, 0]}, "results": {"oven": 1}, "n_observations": 1}}, r"'instances\.0\.bbox'"),
    ({"0": {"bbox": {"center": [0, 0, 0], "size": [1, 1, 0]}, "results": {"oven": 1}, "n_observations": 1}},
     r"'instances\.0\.bbox\.size' must be positive"),
    ({"0": {"bbox": {"center": [0, 0], "size": [1, 1, 1]}, "results": {"oven": 1}, "n_observations": 1}},
     r"'instances\.0\.bbox\.center' must be \[x, y, z\]"),
    ({"0": {"bbox": {"center": [0, 0, 0], "size": [1, 1, 1]}, "results": {"oven": -1}, "n_observations": 1}},
     r"'instances\.0\.results\.oven' must be a finite alpha >= 0"),
    ({"0": {"bbox": {"center": [0, 0, 0], "size": [1, 1, 1]}, "results": {"oven": 1}, "n_observations": 1.5}},
     r"'instances\.0\.n_observations' must be a whole number"),
    ({"0": {"bbox": {"center": [0, 0, 0], "size": [1, 1, 1]}, "results": {"oven": 1}}}, r"'instances\.0' lacks 'n_observations'"),
])
def test_bad_voxeland_files_name_file_and_key(tmp_path, instances, message):
    grid = GridMap(np.zeros((4, 5), bool), 0.5)
    with pytest.raises(ValueError, match=r"voxeland_instanceMap\.json: key " + message):
        read_class_beliefs(voxeland(tmp_path, instances), CLASSES, grid=grid, class_prior=PRIOR)
    (tmp_path / "x.json").write_text("{not json")
    with pytest.raises(ValueError, match=r"x\.json: not a readable JSON file"):
        read_class_beliefs(tmp_path / "x.json", CLASSES, grid=grid, class_prior=PRIOR)


def test_estimate_with_npz_and_voxeland(tmp_path, capsys):
    pytest.importorskip("matplotlib", reason="the sim extra is not installed (pip install 'psgsl-pgm[sim]')")
    pytest.importorskip("PIL", reason="the sim extra is not installed (pip install 'psgsl-pgm[sim]')")
    from psgsl_pgm import Ontology, fuse
    from psgsl_pgm.cli._main import main
    from psgsl_pgm.sim import save_ros_map

    (tmp_path / "o.yaml").write_text("Gases:\n  - gas: smoke\n    probs: {oven: 0.6, microwave: 0.3, other: 0.1}\n")
    ont = Ontology.from_yaml(tmp_path / "o.yaml")
    grid = GridMap(np.zeros((4, 5), bool), 0.5)
    save_ros_map(grid, tmp_path / "map.yaml")
    olf = np.full((4, 5), 1 / 20)
    np.save(tmp_path / "g.npy", olf)
    path = voxeland(tmp_path, {"0": {"bbox": {"center": [0.75, 0.75, 0.25], "size": [1.0, 1.0, 0.5]},
                                     "results": {"oven": 6.0, "microwave": 2.0}, "n_observations": 5}})
    args = ["estimate", "--ontology", str(tmp_path / "o.yaml"), "--class-probs", str(path), "--olfactory",
            str(tmp_path / "g.npy"), "--out", str(tmp_path / "s.npy")]
    assert main(args) == 2 and "needs --map" in capsys.readouterr().err
    assert main(args + ["--map", str(tmp_path / "map.yaml")]) == 0
    beliefs = read_class_beliefs(path, ont.classes, grid=grid, class_prior=ont.class_prior)
    want = fuse(olf, semantic_source_probability(beliefs, ont.source_likelihood("smoke"), ont.class_prior,
                                                 column_axis=2))
    np.testing.assert_allclose(np.load(tmp_path / "s.npy"), want, rtol=1e-12)
    p = np.random.default_rng(2).dirichlet(np.ones(2), size=(4, 5))
    np.savez(tmp_path / "b.npz", probs=p, classes=np.array(["stove", "background"]))
    assert main(args[:4] + [str(tmp_path / "b.npz")] + args[5:]) == 0
    full = np.stack([p[..., 0], np.zeros((4, 5)), p[..., 1]], -1)
    want = fuse(olf, semantic_source_probability(full, ont.source_likelihood("smoke"), ont.class_prior))
    np.testing.assert_allclose(np.load(tmp_path / "s.npy"), want, rtol=1e-12)


def test_a_misspelt_class_is_an_error_naming_the_close_names(tmp_path, capsys):
    """'ovne' would move the oven's mass to 'other' (the result changes by tens of percent): refused, unless the
    user lumps unknown classes knowingly; COCO aliases still match."""
    from psgsl_pgm.cli._main import main

    (tmp_path / "o.yaml").write_text("Gases:\n  - gas: smoke\n    probs: {oven: 0.6, microwave: 0.3, other: 0.1}\n")
    p = np.random.default_rng(4).dirichlet(np.ones(3), size=(4, 5))
    np.save(tmp_path / "g.npy", np.full((4, 5), 1 / 20))
    args = ["estimate", "--ontology", str(tmp_path / "o.yaml"), "--class-probs", str(tmp_path / "b.npz"),
            "--olfactory", str(tmp_path / "g.npy"), "--out", str(tmp_path / "s.npy")]
    np.savez(tmp_path / "b.npz", probs=p, classes=np.array(["ovne", "microwave", "other"]))
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "class the ontology does not list: 'ovne' — did you mean 'oven'?" in err
    assert not (tmp_path / "s.npy").exists()
    assert main(args + ["--other-classes"]) == 0  # lumped knowingly: ovne's column is "other"
    lumped = np.load(tmp_path / "s.npy")
    np.savez(tmp_path / "b.npz", probs=p, classes=np.array(["cooker", "microwave", "other"]))  # COCO alias of oven
    assert main(args) == 0
    right = np.load(tmp_path / "s.npy")
    assert np.abs(right - lumped).max() > 1e-3  # the typo would have changed the result
    with pytest.raises(ValueError, match=r"classes the ontology does not list: 'ovne' — did you mean 'oven'\?; "
                                         r"'micowave' — did you mean 'microwave'\?"):
        read_class_beliefs(_npz(tmp_path, p, ["ovne", "micowave", "other"]), CLASSES)


def _npz(tmp_path, p, names):
    np.savez(tmp_path / "n.npz", probs=p, classes=np.array(names))
    return tmp_path / "n.npz"


def test_other_classes_is_keyword_only_and_validated(tmp_path):
    p = np.full((2, 2, 3), 1 / 3)
    path = _npz(tmp_path, p, ["oven", "microwave", "other"])
    with pytest.raises(ValueError, match=r"other_classes must be one of \['error', 'lump'\], got 'Lump'"):
        read_class_beliefs(path, CLASSES, other_classes="Lump")
    with pytest.raises(TypeError, match=r"other_classes must be one of \['error', 'lump'\], got bool True"):
        read_class_beliefs(path, CLASSES, other_classes=True)
    with pytest.raises(TypeError):
        read_class_beliefs(path, CLASSES, None, None, "lump")  # keyword-only
    grid = GridMap(np.zeros((4, 5), bool), 0.5)
    with pytest.raises(ValueError, match=r"other_classes must be one of"):
        voxeland_class_beliefs({"instances": {}}, CLASSES, grid=grid, class_prior=PRIOR, other_classes="other")
