"""The experiment on a world file: run_search(world_spec=...), the source region as p(s), a mapper's beliefs
instead of the camera, and `psgsl experiment --world`."""

import json

import numpy as np
import pytest
import yaml

from psgsl_pgm import fuse, load_world, semantic_source_probability
from psgsl_pgm.cli._main import main
from psgsl_pgm.experiment import VARIANTS, ExperimentConfig, run_search
from psgsl_pgm.sim import GridMap, SceneObject, box_footprint, save_objects, save_room_map, save_ros_map

FAST = ExperimentConfig(warm_up=20.0, speed=0.5, turn_time=0.5)


def write_flat(d, **over):
    """A 5 m x 3 m flat at 0.1 m: a kitchen (west, with an oven) and a room (east) joined by a door."""
    g = GridMap(np.zeros((30, 50), bool), 0.1)
    x, y = g.cell_centres()[..., 0], g.cell_centres()[..., 1]
    walls = (x < 0.2) | (x > 4.8) | (y < 0.2) | (y > 2.8) | ((x > 2.4) & (x < 2.6) & ~((y > 1.0) & (y < 2.0)))
    save_ros_map(g.with_occupancy(walls), d / "map.yaml")
    save_room_map(np.where(walls, -1, np.where(x < 2.5, 0, 1)), ["Kitchen", "Bedroom"], d / "rooms.yaml")
    save_objects([SceneObject("oven", box_footprint((1.0, 0.5), (0.4, 0.4)), (0.0, 0.9)),
                  SceneObject("bed", box_footprint((4.0, 2.2), (1.0, 0.8)), (0.0, 0.6))], d / "objects.yaml")
    (d / "ontology.yaml").write_text("Gases:\n  - gas: smoke\n    probs: {oven: 0.6, microwave: 0.3, other: 0.1}\n")
    (d / "rooms_p.yaml").write_text("number_classes: 10\nroom_categories:\n  Kitchen: {oven: 0.3}\n")
    world = {"map": "map.yaml", "rooms": "rooms.yaml", "objects": "objects.yaml", "ontology": "ontology.yaml",
             "room_classes": "rooms_p.yaml", "gas": "smoke",
             "wind": {"speed": 0.2, "windows": [{"role": "inlet", "from": [0.1, 1.0], "to": [0.1, 2.0]},
                                                {"role": "outlet", "from": [4.9, 1.0], "to": [4.9, 2.0]}]},
             "start": [1.5, 1.5], "sources": {"stove": "oven", "corner": [4.2, 0.6]}}
    world.update(over)
    (d / "world.yaml").write_text(yaml.safe_dump(world))
    return d / "world.yaml"


def test_run_search_on_a_world_file_keeps_p_s_in_the_source_region(tmp_path):
    spec = load_world(write_flat(tmp_path))
    r = run_search("stove", 0, world_spec=spec, config=FAST, snapshot_at=(0.0, 1.0))
    house = spec.house()
    np.testing.assert_allclose(r.source_xy, [1.0, 0.5])
    region = spec.region_mask(house)
    for post in r.snapshots.values():
        assert post.shape == (3,) + house.shape
        assert np.all(post[:, ~region] == 0)
        np.testing.assert_allclose(post.sum(axis=(1, 2)), 1.0, rtol=1e-9)
    assert np.isfinite(r.error).all() and r.n_steps > 5
    assert r.config["world"] == str(spec.path)


def test_a_mappers_beliefs_replace_the_camera(tmp_path):
    rng = np.random.default_rng(3)
    beliefs = rng.dirichlet(np.ones(3), size=(30, 50))
    np.savez(tmp_path / "beliefs.npz", probs=beliefs, classes=np.array(["stove", "microwave", "background"]))
    spec = load_world(write_flat(tmp_path, semantic_map="beliefs.npz"))
    assert spec.summary()["semantic_map"] == [30, 50, 3]
    r = run_search("stove", 1, world_spec=spec, config=FAST, snapshot_at=(0.0,))
    region = spec.region_mask(spec.house()).astype(float)
    ont = spec.ontology
    p_z = semantic_source_probability(beliefs, ont.source_likelihood("smoke"), ont.class_prior)
    p_g = region / region.sum()  # before the first reading: the estimator's prior
    np.testing.assert_allclose(r.snapshots[0][1], fuse(p_g, p_z), rtol=1e-9, atol=1e-15)


def test_experiment_command_with_a_world(tmp_path, capsys):
    world = write_flat(tmp_path, sources={"stove": "oven"})  # without --sources: the world's sources
    out = tmp_path / "out"
    code = main(["experiment", "--world", str(world), "--seeds", "1", "--estimators", "infotaxis", "--workers", "1",
                 "--out", str(out), "--quiet"])
    assert code == 0
    assert "sources stove, 1 seeds, gas 'smoke'" in capsys.readouterr().out
    assert set(json.loads((out / "summary.json").read_text())) == {"stove/infotaxis"}
    assert set(json.loads((out / "stove-infotaxis" / "summary.json").read_text())) >= set(VARIANTS)
    assert (out / "stove-infotaxis" / "progression.png").stat().st_size > 0
    # the stored run carries its world's content: another world in the same output directory is refused
    (tmp_path / "w2").mkdir()
    other = write_flat(tmp_path / "w2", sources={"stove": "oven"}, start=[1.5, 1.2])
    assert main(["experiment", "--world", str(other), "--seeds", "1", "--estimators", "infotaxis", "--workers", "1",
                 "--out", str(out), "--quiet"]) == 2
    assert "world.start: [1.5, 1.5] → [1.5, 1.2]" in capsys.readouterr().err


def test_experiment_command_bad_world_one_line_exit_2(tmp_path, capsys):
    world = write_flat(tmp_path, start=[0.0, 0.0])
    assert main(["experiment", "--world", str(world), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "world.yaml: key 'start'" in err[0]
    assert not (tmp_path / "o").exists()
    world = write_flat(tmp_path)
    assert main(["experiment", "--world", str(world), "--sources", "toaster", "--out", str(tmp_path / "o"),
                 "--quiet"]) == 2
    err = capsys.readouterr().err  # an unknown name: the world's own sources are listed
    assert "source 'toaster' is neither a source of the world nor an object class of the house" in err
    assert "the world's sources: ['corner', 'stove']" in err
    assert not (tmp_path / "o").exists()
