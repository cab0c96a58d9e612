"""The lab's real house (../shared/data/mapir_house_B) as a world file written here, pointing at the lab's files.

Skipped when ../shared is absent; the lab's files are never copied into the project.
"""

from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.sim.house_b import house_b_folder

SHARED = house_b_folder()

pytestmark = [pytest.mark.shared_data,
              pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/mapir_house_B is absent")]

WINDOWS = [  # from the data README (the lab's outlet models)
    {"role": "inlet", "from": [-7.15, 3.42], "to": [-5.65, 3.42]},
    {"role": "inlet", "from": [-2.65, 3.42], "to": [-1.10, 3.42]},
    {"role": "outlet", "from": [-1.70, -7.88], "to": [-0.25, -7.88]},
    {"role": "outlet", "from": [-6.45, -7.88], "to": [-4.95, -7.88]},
]


def write_real_world(d: Path, **over) -> Path:
    """World file for the lab's house: walls-only map at 0.1 m, the lab's masks, ontology and room classes."""
    b1 = yaml.safe_load((SHARED / "simulations" / "B1.yaml").read_text())
    start = yaml.safe_load((SHARED / "basicSim" / "B1.yaml").read_text())["robots"][0]["position"]
    (d / "walls.yaml").write_text(yaml.safe_dump({
        "image": str(SHARED / "_occupancy_walls.pgm"), "resolution": 0.01, "origin": [-7.55, -7.88, 0.0],
        "negate": 0, "occupied_thresh": 0.9, "free_thresh": 0.1}))
    (d / "objects.yaml").write_text(yaml.safe_dump({"objects": [  # our own placement; the lab ships no list
        {"class": "oven", "position": [b1["source_x"], b1["source_y"]], "size": [0.6, 0.6], "height": [0.0, 0.9]},
        {"class": "microwave", "position": [-1.5, 2.6], "size": [0.5, 0.4], "height": [0.9, 1.2]},
        {"class": "fridge", "position": [0.4, 2.8], "size": [0.7, 0.7], "height": [0.0, 1.8]},
        {"class": "toilet", "position": [-0.4, -3.4], "size": [0.5, 0.6], "height": [0.0, 0.8]},
        {"class": "bed", "position": [-5.5, -5.5], "size": [1.6, 2.0], "height": [0.0, 0.6]},
    ]}))
    world = {
        "map": "walls.yaml", "resolution": 0.1,
        "rooms": str(SHARED / "room_categories" / "roomMasks.yaml"),
        "objects": "objects.yaml",
        "ontology": str(SHARED / "ontology.yaml"), "room_classes": str(SHARED / "ObjectProbByRoom.yaml"),
        "gas": "smoke", "source_region": "rooms",
        "wind": {"speed": 0.2, "windows": WINDOWS},
        "start": [float(start[0]), float(start[1])],
        "sources": {"B1": [b1["source_x"], b1["source_y"]], "oven": "oven"},
    }
    world.update(over)
    path = d / "world.yaml"
    path.write_text(yaml.safe_dump(world, sort_keys=False))
    return path


def test_world_check_on_the_real_house(tmp_path, capsys):
    from psgsl_pgm.cli._main import main
    from psgsl_pgm.sim import load_room_map, load_ros_map

    path = write_real_world(tmp_path)
    assert main(["world", "check", str(path), "--png", str(tmp_path / "house.png")]) == 0
    out = capsys.readouterr().out
    assert "grid: 114 x 87 cells of 0.1 m" in out
    assert "source B1: (-0.60, 1.95) in Kitchen" in out
    assert ("warning: p(o | room) omits room(s) Hallway, LivingRoom of the room map: they start at the class prior"
            in out)
    from psgsl_pgm import load_world

    summary = load_world(path).summary()
    fine = load_ros_map(tmp_path / "walls.yaml")
    labels, names = load_room_map(SHARED / "room_categories" / "roomMasks.yaml", like=fine)
    for i, name in enumerate(names):  # areas at 0.1 m (rooms by majority) within 5 % of the 1 cm masks
        assert summary["rooms"][name] == pytest.approx((labels == i).sum() * 1e-4, rel=0.05), name
    assert (tmp_path / "house.png").stat().st_size > 20_000


def test_the_real_house_world_builds_a_simulation(tmp_path):
    from psgsl_pgm import load_world

    spec = load_world(write_real_world(tmp_path))
    world = spec.make_world(seed=0, source="B1", warm_up=5.0)
    house = world.house
    assert house.room_names[int(house.room_of(world.source))] == "Kitchen"
    assert world.gas.n_released > 0
    onto = spec.ontology
    smoke = onto.source_likelihood("smoke")
    assert smoke[onto.class_index("oven")] / smoke[onto.class_index("microwave")] == pytest.approx(4 / 3, rel=1e-12)
    # the source region keeps p(s) off walls and outside the rooms
    region = spec.region_mask(house)
    assert not (region & house.grid.occupancy).any() and not (region & (house.room_labels < 0)).any()
    assert 0.5 < region.sum() / house.grid.free.sum() <= 1.0
    assert np.isfinite(world.wind_now().velocity).all()


@pytest.mark.slow
def test_experiment_on_the_real_house_two_seeds(tmp_path, capsys):
    """`psgsl experiment --world` on the lab's house: 2 seeds from source B1 finish and write their summaries."""
    import json

    from psgsl_pgm.cli._main import main
    from psgsl_pgm.experiment import VARIANTS

    path = write_real_world(tmp_path)
    out = tmp_path / "exp"
    assert main(["experiment", "--world", str(path), "--sources", "B1", "--seeds", "2", "--estimators",
                 "infotaxis", "--workers", "2", "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "B1-infotaxis" / "summary.json").read_text())
    assert summary["n_runs"] == 2 and summary["seeds"] == [0, 1]
    for name in VARIANTS:
        assert np.isfinite(summary[name]["final_error"]["mean"])
    for fig in ("error-chart.png", "progression.png", "room-types.png"):
        assert (out / "B1-infotaxis" / fig).stat().st_size > 0
    assert "B1/infotaxis" in json.loads((out / "summary.json").read_text())


def test_a_furniture_map_with_an_oven_at_b1_gives_found_runs(tmp_path, capsys):
    """The lab's `_occupancy.yaml` (furniture drawn): B1 lies in the oven's footprint, which is what counts as
    found — the point B1 itself is 0.52 m from the nearest drivable cell, out of the found radius."""
    from psgsl_pgm import load_world
    from psgsl_pgm.cli._main import main
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.search import findability, run_closed_loop
    from psgsl_pgm.search._space import FreeSpace
    from psgsl_pgm.sim import Camera

    (tmp_path / "furniture.yaml").write_text(yaml.safe_dump({
        "image": str(SHARED / "_occupancy.pgm"), "resolution": 0.01, "origin": [-7.55, -7.88, 0.0],
        "negate": 0, "occupied_thresh": 0.9, "free_thresh": 0.1}))
    path = write_real_world(tmp_path, map="furniture.yaml")
    spec = load_world(path)
    house = spec.house()
    nav = FreeSpace(house, Camera(), clearance=0.25).nav
    c = house.grid.cell_centres()[nav]
    assert np.hypot(c[:, 0] + 0.60, c[:, 1] - 1.95).min() == pytest.approx(0.52)  # the point: never within 0.5 m
    f = findability(spec)["B1"]
    assert f["object"] == "oven_0" and f["gap"] < 0.5 and f["findable"]
    assert main(["world", "check", str(path)]) == 0
    assert "source B1: (-0.60, 1.95) in Kitchen, object oven_0" in capsys.readouterr().out
    world = spec.make_world(0, "B1", warm_up=ExperimentConfig().warm_up)
    assert world.source_object is not None and world.source_object.name == "oven_0"
    run = run_closed_loop("B1", 0, "infotaxis", "olfaction", world_spec=spec, config=ExperimentConfig(gas="smoke"))
    assert run.found and run.time_to_find < 1000.0
    assert run.geodesic == pytest.approx(f["geodesic"], rel=1e-12)


def test_typos_in_the_labs_files_are_refused(tmp_path, capsys):
    """The lab's own files with one typo each: world check refuses them in one line, naming the close name."""
    from psgsl_pgm.cli._main import main

    rooms = (SHARED / "ObjectProbByRoom.yaml").read_text().replace("  Kitchen:", "  Kitchn:")
    (tmp_path / "rooms_typo.yaml").write_text(rooms)
    assert main(["world", "check", str(write_real_world(tmp_path, room_classes="rooms_typo.yaml"))]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'Kitchn' — did you mean 'Kitchen'?" in err
    onto = (SHARED / "ontology.yaml").read_text().replace("Gases:", "Gasses:")
    (tmp_path / "onto_typo.yaml").write_text(onto)
    assert main(["world", "check", str(write_real_world(tmp_path, ontology="onto_typo.yaml"))]) == 2
    assert "expected key 'Gases' (the lab's layout" in capsys.readouterr().err
    # a class spelled differently in the ontology and the room table: the room's 'microwave' would be an 'other'
    onto = (SHARED / "ontology.yaml").read_text().replace("microwave", "microwve")
    (tmp_path / "onto_microwve.yaml").write_text(onto)
    assert main(["world", "check", str(write_real_world(tmp_path, ontology="onto_microwve.yaml"))]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and ("key 'room_categories.Kitchen': class 'microwave' is not one of the ontology's "
                                     "classes, so it would count as 'other' — did you mean the ontology's 'microwve'?"
                                     in err)


def test_a_source_found_at_the_start_is_refused_by_check_and_search_alike(tmp_path, capsys):
    """B4 lies 0.2 m from the lab's start, within the 0.5 m found radius: world check and search refuse it in one
    line (a search would end before its first reading), and search writes nothing."""
    from psgsl_pgm.cli._main import main

    path = write_real_world(tmp_path, sources={"B4": [-3.2, -3.3]})
    out = tmp_path / "out"
    assert main(["world", "check", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "source 'B4' is found at the start: the start (-3, -3.3) is 0.20 m from it" in err[0]
    assert main(["search", "--world", str(path), "--sources", "B4", "--seeds", "1", "--policies", "greedy",
                 "--variants", "olfaction", "--workers", "1", "--quiet", "--out", str(out)]) == 2
    assert "is found at the start" in capsys.readouterr().err and not out.exists()
    # below the distance, it is a source like any other
    assert main(["world", "check", str(path), "--found-radius", "0.15"]) == 0


def test_the_example_world_file_of_house_b_checks(tmp_path, capsys):
    """examples/house_b: the world file, its walls map YAML and object list, pointed at the lab's folder (the
    prefix replaced as its README says), pass world check with every source; the folder holds none of the lab's
    files."""
    import shutil

    from psgsl_pgm.cli._main import main

    example = Path(__file__).resolve().parents[2] / "examples" / "house_b"
    assert sorted(p.name for p in example.iterdir()) == ["ABOUT.md", "objects.yaml", "walls.yaml", "world.yaml"]
    for name in ("world.yaml", "walls.yaml"):
        text = (example / name).read_text()
        assert "../../../shared/data/mapir_house_B" in text
        (tmp_path / name).write_text(text.replace("../../../shared/data/mapir_house_B", str(SHARED)))
    shutil.copy(example / "objects.yaml", tmp_path)
    assert main(["world", "check", str(tmp_path / "world.yaml")]) == 0
    out = capsys.readouterr().out
    assert "grid: 114 x 87 cells of 0.1 m" in out
    for name, room in (("B1", "Kitchen"), ("B2", "Bathroom"), ("B3", "LivingRoom")):
        assert f"source {name}: " in out and f"in {room}" in out.split(f"source {name}: ")[1].splitlines()[0]


def test_a_source_on_furniture_says_so_and_what_to_do(tmp_path, capsys):
    """The lab's furnished map draws furniture as occupied: B2 and B3 lie on it. The message says furniture (not
    a wall), names the room and offers the walls-only map with objects, or the nearest free cell."""
    from psgsl_pgm.cli._main import main

    path = write_real_world(tmp_path, map=str(SHARED / "_occupancy.yaml"), sources={"B2": [-0.4, -2.9]})
    assert main(["world", "check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert ("key 'sources.B2' (-0.4, -2.9) lies on furniture: an occupied cell of the map inside the room Bathroom"
            in err)
    assert "use a walls-only map with the furniture listed under 'objects'" in err
    near = [float(v) for v in err.rsplit("(", 1)[1].rstrip(")\n").split(", ")]
    from psgsl_pgm import load_world

    path = write_real_world(tmp_path, map=str(SHARED / "_occupancy.yaml"), sources={"B2": near})
    assert load_world(path).sources["B2"] == tuple(near) or list(load_world(path).sources["B2"]) == near


def _without_resolution(tmp_path):
    path = write_real_world(tmp_path)
    world = yaml.safe_load(path.read_text())
    del world["resolution"]  # the map's own 1-cm cells
    path.write_text(yaml.safe_dump(world, sort_keys=False))
    return path


def test_the_1cm_house_is_refused_by_the_runs_naming_resolution(tmp_path, capsys):
    from psgsl_pgm.cli._main import main

    path = _without_resolution(tmp_path)
    out = tmp_path / "out"
    assert main(["search", "--world", str(path), "--sources", "B1", "--seeds", "1", "--quiet", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "key 'resolution': 731,682 free cells of 0.01 m are more than the 60,000" in err[0]
    assert "set 'resolution: 0.04' (or coarser)" in err[0] and not out.exists()


@pytest.mark.slow
def test_world_check_of_the_1cm_house_stays_within_2_gb(tmp_path):
    """``world check`` at the lab's 1-cm cells runs (its found rule in bounded blocks), within 2 GB, and warns that
    the runs need a coarser resolution (about 2 minutes on a 2-core machine)."""
    import resource
    import subprocess
    import sys

    path = _without_resolution(tmp_path)
    repo = Path(__file__).resolve().parents[2]
    done = subprocess.run([sys.executable, "-m", "psgsl_pgm", "world", "check", str(path)], cwd=repo,
                          capture_output=True, text=True, env={**__import__("os").environ, "PYTHONPATH": str(repo)})
    assert done.returncode == 0, done.stderr
    assert "warning: 731,682 free cells: search, experiment, benchmark and replay refuse" in done.stdout
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024  # bytes (Linux reports KiB)
    assert peak < 2 * 2**30, f"peak {peak / 2**30:.2f} GiB"
