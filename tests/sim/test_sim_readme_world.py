"""The user guide's world-file example (docs/guide/own-house.md) is a valid world file: written next to files it
names, it loads and checks."""

import re
from pathlib import Path

import numpy as np
import yaml

from psgsl_pgm import load_world
from psgsl_pgm.sim import GridMap, SceneObject, box_footprint, save_objects, save_room_map, save_ros_map
from psgsl_pgm.search import findability

README = Path(__file__).resolve().parents[2] / "docs" / "guide" / "own-house.md"  # the guide's page


def readme_world() -> str:
    text = README.read_text(encoding="utf-8")
    section = text[text.index("# Your own house"):]
    return re.search(r"```yaml\n(.*?)```", section, flags=re.S).group(1)


def test_the_readme_world_file_loads(tmp_path):
    example = readme_world()
    data = yaml.safe_load(example)
    assert set(data) >= {"map", "resolution", "rooms", "objects", "ontology", "room_classes", "source_region", "wind",
                         "start", "sources"}
    # the files it names: a 8.7 m x 11.4 m flat in the lab's frame, one room, an oven at B1
    g = GridMap(np.zeros((228, 174), bool), 0.05, (-7.55, -7.88))
    c = g.cell_centres()
    x, y = c[..., 0], c[..., 1]
    walls = (x < -7.45) | (x > 1.05) | (y < -7.78) | (y > 3.42)
    save_ros_map(g.with_occupancy(walls), tmp_path / data["map"])
    save_room_map(np.where(walls, -1, 0), ["Kitchen"], tmp_path / data["rooms"])
    save_objects([SceneObject("oven", box_footprint((-0.6, 1.95), (0.6, 0.6)), (0.0, 0.9))],
                 tmp_path / data["objects"])
    (tmp_path / data["ontology"]).write_text("Gases:\n  - gas: smoke\n    probs: {oven: 0.4, microwave: 0.3, "
                                             "other: 0.005}\n")
    (tmp_path / data["room_classes"]).write_text("number_classes: 81\nroom_categories:\n  Kitchen: {oven: 0.2}\n")
    (tmp_path / "world.yaml").write_text(example)
    spec = load_world(tmp_path / "world.yaml")
    s = spec.summary()
    assert (s["grid"]["rows"], s["grid"]["cols"]) == (114, 87)
    b1 = s["sources"]["B1"]
    assert (b1["position"], b1["room"]) == ([-0.6, 1.95], "Kitchen")
    # B1 lies in the oven's footprint: found within 0.5 m of its 6 x 6 working cells of 0.1 m
    f = findability(spec)["B1"]
    assert (b1["object"], f["object"], f["target_cells"], f["findable"]) == ("oven_0", "oven_0", 36, True)
    assert s["sources"]["oven"]["position"] == [-0.6, 1.95]
    assert [w["role"] for w in s["windows"]] == ["inlet", "outlet"]
    assert s["start"] == [-3.0, -3.3]
