"""World files: load_world, the resampling rules, every bad key named, and `psgsl world check`."""

import subprocess
import sys

import numpy as np
import pytest
import yaml

from psgsl_pgm import load_world
from psgsl_pgm.cli._main import main
from psgsl_pgm.sim import (GridMap, SceneObject, box_footprint, default_house, default_world, read_gaden_wind_csv,
                           read_gaden_wind_snapshots, save_objects, save_room_map, save_ros_map)
from psgsl_pgm.sim._resample import coarsen_labels, coarsen_occupancy

ONTOLOGY = """Gases:
  - gas: smoke
    probs: {oven: 0.4, microwave: 0.3, other: 0.01}
"""


def write_house(d, *, fine=0.05):
    """A 6 m x 4 m two-room flat at ``fine`` m cells: walls, a door, a kitchen (west) and a living room (east)."""
    h, w = int(round(4 / fine)), int(round(6 / fine))
    g = GridMap(np.zeros((h, w), bool), fine)
    c = g.cell_centres()
    x, y = c[..., 0], c[..., 1]
    walls = (x < 0.2) | (x > 5.8) | (y < 0.2) | (y > 3.8) | ((x > 2.9) & (x < 3.1) & ~((y > 1.5) & (y < 2.5)))
    grid = g.with_occupancy(walls)
    save_ros_map(grid, d / "map.yaml")
    labels = np.where(walls, -1, np.where(x < 3.0, 0, 1))
    save_room_map(labels, ["Kitchen", "LivingRoom"], d / "rooms.yaml")
    save_objects([SceneObject("oven", box_footprint((1.0, 0.6), (0.6, 0.6)), (0.0, 0.9)),
                  SceneObject("fridge", box_footprint((2.4, 3.2), (0.6, 0.6)), (0.0, 1.8)),
                  SceneObject("sofa", box_footprint((4.5, 3.2), (1.6, 0.6)), (0.0, 0.8))], d / "objects.yaml")
    (d / "ontology.yaml").write_text(ONTOLOGY)
    return grid, labels


def world_dict(**over):
    data = {
        "map": "map.yaml", "resolution": 0.1, "rooms": "rooms.yaml", "objects": "objects.yaml",
        "ontology": "ontology.yaml", "source_region": "rooms",
        "wind": {"speed": 0.2, "windows": [{"role": "inlet", "from": [0.1, 1.5], "to": [0.1, 2.5]},
                                           {"role": "outlet", "from": [5.9, 1.0], "to": [5.9, 2.0]}]},
        "start": [2.0, 2.0], "sources": {"S1": [4.0, 1.0], "oven": "oven"},
    }
    data.update(over)
    return data


@pytest.fixture
def flat(tmp_path):
    _, labels = write_house(tmp_path)
    np.save(tmp_path / "fine_labels.npy", labels)
    (tmp_path / "world.yaml").write_text(yaml.safe_dump(world_dict()))
    return tmp_path


def test_load_world_and_its_summary(flat):
    spec = load_world(flat / "world.yaml")
    house = spec.house(seed=3)
    assert house is spec.house(seed=0)  # a file-defined house does not depend on the seed
    s = spec.summary()
    assert (s["grid"]["rows"], s["grid"]["cols"], s["grid"]["resolution"]) == (40, 60, 0.1)
    # rooms by majority of the 0.05 m cells: the areas of the fine masks within a few percent
    fine = np.load(flat / "fine_labels.npy")
    for i, name in enumerate(("Kitchen", "LivingRoom")):
        assert s["rooms"][name] == pytest.approx((fine == i).sum() * 0.05**2, rel=0.03)
    assert s["objects"] == {"oven": 1, "refrigerator": 1, "couch": 1}  # aliases: fridge, sofa
    assert s["unlisted_classes"] == ["couch", "refrigerator"]
    assert [w["role"] for w in s["windows"]] == ["inlet", "outlet"] and all(w["cells"] > 0 for w in s["windows"])
    oven = s["sources"]["oven"]
    assert (oven["position"], oven["room"], oven["object"]) == (pytest.approx([1.0, 0.6]), "Kitchen", "oven_0")
    assert s["sources"]["S1"]["room"] == "LivingRoom"
    assert s["ontology"]["rooms_at_class_prior"] == ["Kitchen", "LivingRoom"]  # no room classes given
    # objects of classes the ontology does not list are "other" for the semantic term
    assert sorted({o.class_name for o in house.objects}) == ["other", "oven"]
    assert house.classes == spec.ontology.classes


def test_resampling_rules():
    occ = np.zeros((4, 6), bool)
    occ[0, 0] = True  # one fine cell of a 2 x 2 block: the coarse cell is occupied ("any")
    g = coarsen_occupancy(GridMap(occ, 0.05, (1.0, 2.0)), 2)
    np.testing.assert_array_equal(g.occupancy, [[True, False, False], [False, False, False]])
    assert g.resolution == pytest.approx(0.1) and g.origin == (1.0, 2.0)
    lab = np.array([[0, 0, 1, 1, -1, 1], [0, 1, 1, 1, -1, -1], [-1, -1, 0, 1, 1, 1], [-1, 0, 1, 0, 1, 1]])
    np.testing.assert_array_equal(coarsen_labels(lab, 2, 2), [[0, 1, -1], [-1, 0, 1]])  # majority; ties low
    # a working resolution that is no whole multiple of the map's is refused
    with pytest.raises(ValueError, match="whole multiple"):
        from psgsl_pgm.sim._resample import coarsen_factor

        coarsen_factor(0.05, 0.12)


def test_start_defaults_to_the_navigable_cell_nearest_the_centre(flat):
    data = world_dict()
    del data["start"]
    (flat / "w2.yaml").write_text(yaml.safe_dump(data))
    spec = load_world(flat / "w2.yaml")
    start = spec.start_for(spec.house())
    # the map's centre (3, 2) is the door in the dividing wall; the nearest navigable cell lies in the doorway
    assert np.hypot(start[0] - 3.0, start[1] - 2.0) <= 0.15


@pytest.mark.parametrize("change, message", [
    ({"mapp": "map.yaml"}, r"world\.yaml: unknown key\(s\) \['mapp'\]"),
    ({"map": "none.yaml"}, r"world\.yaml: key 'map' names .*none\.yaml, which does not exist"),
    ({"resolution": 0.12}, r"world\.yaml: key 'resolution'.*whole multiple"),
    ({"resolution": "x"}, r"world\.yaml: field 'resolution' must be a number"),
    ({"ontology": "rooms.yaml"}, r"world\.yaml: key 'ontology'.*rooms\.yaml.*unknown ontology keys \['categories'\]"),
    ({"gas": "sewage"}, r"world\.yaml: key 'gas': 'sewage' is not a gas"),
    ({"source_region": "walls"}, r"world\.yaml: key 'source_region' names .*walls, which does not exist"),
    ({"start": [0.1, 0.1]}, r"world\.yaml: key 'start' \(0\.1, 0\.1\) is not navigable"),
    ({"start": [50, 0]}, r"world\.yaml: key 'start' \(50, 0\) is outside the map"),
    ({"sources": {"S": [3.05, 3.0]}}, r"world\.yaml: key 'sources\.S' \(3\.05, 3\) lies outside the source region"),
    ({"sources": {"S": "toaster"}}, r"world\.yaml: key 'sources\.S': source class 'toaster' has no object"),
    ({"sources": {"S": [1, 2, 3]}}, r"world\.yaml: field 'sources\.S' must have 2 entries"),
    ({"wind": {"speed": 0.2}}, r"world\.yaml: key 'wind\.windows' needs at least one inlet and one outlet"),
    ({"wind": {"sped": 0.2}}, r"world\.yaml: key 'wind': unknown key\(s\) \['sped'\]"),
    ({"wind": {"speed": 0.2, "windows": [{"role": "door", "from": [0, 0], "to": [1, 0]}]}},
     r"world\.yaml: key 'wind\.windows\[0\]\.role' must be 'inlet' or 'outlet'"),
    ({"wind": {"speed": 0.2, "windows": [{"role": "inlet", "from": [20, 20], "to": [21, 20]}]}},
     r"world\.yaml: key 'wind\.windows\[0\]': no cell of the map"),
    ({"wind": {"gaden_csv": ["none.csv"], "height": 0.5}}, r"key 'wind\.gaden_csv\[0\]' names .*none\.csv"),
    ({"builtin": "default_house"}, r"world\.yaml: key 'builtin' describes the house; remove key\(s\)"),
])
def test_every_bad_key_is_named(flat, change, message):
    (flat / "bad.yaml").write_text(yaml.safe_dump(world_dict(**change)).replace("bad.yaml", "world.yaml"))
    with pytest.raises(ValueError, match=message.replace("world\\.yaml", "bad\\.yaml")):
        load_world(flat / "bad.yaml")


def test_missing_required_keys(flat):
    data = world_dict()
    del data["rooms"]
    (flat / "bad.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(ValueError, match=r"bad\.yaml: missing required key 'rooms'"):
        load_world(flat / "bad.yaml")


def test_errors_inside_named_files_name_both(flat):
    (flat / "objects.yaml").write_text("objects:\n  - {class: oven, position: [1.0, 0.6], colour: red}\n")
    with pytest.raises(ValueError, match=r"world\.yaml: key 'objects': .*objects\.yaml: objects\[0\]: unknown key"):
        load_world(flat / "world.yaml")


def test_source_region_free_and_mask(flat):
    spec = load_world(flat / "world.yaml")
    house = spec.house()
    rooms = spec.region_mask(house)
    (flat / "w.yaml").write_text(yaml.safe_dump(world_dict(source_region="free")))
    free = load_world(flat / "w.yaml").region_mask(house)
    np.testing.assert_array_equal(free, house.grid.free)
    assert rooms.sum() <= free.sum()
    from PIL import Image

    img = np.zeros((80, 120), np.uint8)  # the fine map's frame, image row 0 at the top
    img[:, 60:] = 255  # the east half
    Image.fromarray(img).save(flat / "region.png")
    (flat / "w.yaml").write_text(yaml.safe_dump(world_dict(source_region="region.png", sources={"S": [4.0, 1.0]})))
    mask = load_world(flat / "w.yaml").region_mask(house)
    xs = house.grid.cell_centres()[..., 0]
    np.testing.assert_array_equal(mask, (xs > 3.0) & house.grid.free)


def test_gaden_wind_headers_and_snapshots(tmp_path):
    g = GridMap(np.zeros((3, 4), bool), 1.0)
    a = '"U [m/s]:0","U [m/s]:1","U [m/s]:2","Points:0","Points:1","Points:2"\n'
    rows = "".join(f"{0.1 * c},{0.2 * r},0,{c + 0.5},{r + 0.5},0.5\n" for r in range(3) for c in range(4))
    (tmp_path / "a.csv").write_text(a + rows)
    b = '"Points:2","Points:1","Points:0","p","U:2","U:1","U:0"\n'  # other order, no units, an extra column
    rows_b = "".join(f"0.5,{r + 0.5},{c + 0.5},1,0,{-0.2 * r},{-0.1 * c}\n" for r in range(3) for c in range(4))
    (tmp_path / "b.csv").write_text(b + rows_b)
    wa = read_gaden_wind_csv(tmp_path / "a.csv", like=g, height=0.5)
    rr, cc = np.mgrid[0:3, 0:4]
    np.testing.assert_allclose(wa.velocity, np.stack([0.1 * cc, 0.2 * rr], -1), rtol=1e-12)
    seq = read_gaden_wind_snapshots([tmp_path / "a.csv", tmp_path / "b.csv"], like=g, height=0.5, period=2.0)
    assert len(seq.snapshots) == 2 and seq.period == 2.0
    np.testing.assert_allclose(seq.at_time(2.5).velocity, -wa.velocity, rtol=1e-12)
    np.testing.assert_allclose(seq.mean().velocity, 0.0, atol=1e-15)


def test_world_file_with_gaden_wind(flat):
    grid = load_world(flat / "world.yaml").house().grid
    xy = grid.cell_centres().reshape(-1, 2)
    text = '"U:0","U:1","U:2","Points:0","Points:1","Points:2"\n' + "".join(
        f"0.3,0,0,{x},{y},0.5\n" for x, y in xy)
    (flat / "wind_0.csv").write_text(text)
    data = world_dict(wind={"gaden_csv": ["wind_0.csv"], "height": 0.5, "period": 1.0})
    (flat / "w.yaml").write_text(yaml.safe_dump(data))
    spec = load_world(flat / "w.yaml")
    assert spec.summary()["wind"] == {"kind": "gaden", "height": 0.5, "period": 1.0, "snapshots": 1}
    world = spec.make_world(seed=0, source="S1", warm_up=2.0)
    free = spec.house().grid.free  # no windows declared: the window cells of the other world stay walls
    np.testing.assert_allclose(world.wind_now().velocity[free], np.broadcast_to([0.3, 0.0], (free.sum(), 2)))
    assert free.sum() < grid.free.sum()


def test_default_world_is_the_embedded_house():
    spec = default_world()
    for seed in (0, 5):
        a, b = spec.house(seed), default_house(seed)
        np.testing.assert_array_equal(a.class_map, b.class_map)
    np.testing.assert_array_equal(spec.region_mask(spec.house(0)), default_house(0).grid.free)
    assert spec.summary()["sources"]["oven"]["room"] == "Kitchen"


# ---- the command ------------------------------------------------------------------------------------------
def test_world_check_prints_the_summary_and_draws(flat, capsys):
    assert main(["world", "check", str(flat / "world.yaml"), "--png", str(flat / "w.png")]) == 0
    out = capsys.readouterr().out
    assert "grid: 40 x 60 cells of 0.1 m" in out
    assert "objects per class: oven 1, refrigerator 1, couch 1" in out
    assert "source oven: (1.00, 0.60) in Kitchen" in out
    assert (flat / "w.png").stat().st_size > 10_000
    assert not list(flat.glob(".w.png*"))


def test_world_check_bad_file_one_line_exit_2_nothing_written(flat):
    (flat / "bad.yaml").write_text(yaml.safe_dump(world_dict(resolution=0.12)))
    proc = subprocess.run([sys.executable, "-m", "psgsl_pgm", "world", "check", str(flat / "bad.yaml"), "--png",
                           str(flat / "out.png")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "bad.yaml: key 'resolution'" in lines[0] and "Traceback" not in proc.stderr
    assert not (flat / "out.png").exists()


def test_world_check_refuses_an_unwritable_png_before_work(flat, capsys):
    assert main(["world", "check", str(flat / "world.yaml"), "--png", str(flat / "no" / "w.png")]) == 2
    assert "--png: directory" in capsys.readouterr().err


def test_the_world_figure_is_readable(flat):
    import matplotlib.pyplot as plt

    from psgsl_pgm.cli._world import plot_world
    from psgsl_pgm.sim import figure_problems

    for spec in (load_world(flat / "world.yaml"), default_world()):
        fig = plot_world(spec)
        assert figure_problems(fig) == []
        assert fig.axes[0].get_xlabel() == "x [m]" and fig.axes[0].get_ylabel() == "y [m]"
        plt.close(fig)


def test_duplicate_world_keys_are_errors(flat):
    text = (flat / "world.yaml").read_text()
    (flat / "dup.yaml").write_text(text + "resolution: 0.2\n")
    with pytest.raises(ValueError, match=r"dup\.yaml: duplicate key 'resolution'"):
        load_world(flat / "dup.yaml")
