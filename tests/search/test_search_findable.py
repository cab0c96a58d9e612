"""Reachable, findable sources: the emitting object's footprint in the success rule, and `world check`'s refusal
of a source the robot can never find (geodesic from the start, gap from the nearest drivable cell)."""

import numpy as np
import pytest
import yaml

from psgsl_pgm import load_world
from psgsl_pgm.cli._main import main
from psgsl_pgm.search import SearchConfig, check_findable, findability, run_closed_loop
from psgsl_pgm.search._space import FreeSpace
from psgsl_pgm.sim import Camera, SceneObject, box_footprint, default_house, make_world, save_objects

from ..sim.test_sim_worldfile import world_dict, write_house


@pytest.fixture
def flat(tmp_path):
    write_house(tmp_path)
    (tmp_path / "world.yaml").write_text(yaml.safe_dump(world_dict()))
    return tmp_path


def _world_file(d, **over):
    path = d / "w.yaml"
    path.write_text(yaml.safe_dump(world_dict(**over)))
    return path


def test_a_position_inside_a_footprint_carries_that_object():
    house = default_house(0)
    oven = house.objects_of_class("oven")[0]
    inside = oven.center + (0.2, -0.1)
    w = make_world(house, source=inside, warm_up=0.0)
    assert w.source_object is oven  # the oven lies inside a countertop: the object the class map shows there
    np.testing.assert_array_equal(w.source, inside)  # the source stays where it was given
    assert make_world(house, source=(5.0, 6.0), warm_up=0.0).source_object is None  # open floor: a point
    counter = house.objects_of_class("countertop")[0]
    assert make_world(house, source=(6.1, 0.3), warm_up=0.0).source_object is counter
    assert make_world(house, source=oven, warm_up=0.0).source_object is oven
    with pytest.raises(ValueError, match="not one of the house's objects"):
        make_world(default_house(1), source=oven, warm_up=0.0)


def test_world_file_sources_carry_their_object(flat):
    spec = load_world(_world_file(flat, sources={"S1": [4.0, 1.0], "oven": "oven", "B": [1.2, 0.7]}))
    for name, obj in (("oven", "oven_0"), ("B", "oven_0"), ("S1", None)):
        w = spec.make_world(0, name, warm_up=0.0)
        assert (None if w.source_object is None else w.source_object.name) == obj, name
    np.testing.assert_array_equal(spec.make_world(0, "B", warm_up=0.0).source, [1.2, 0.7])
    np.testing.assert_allclose(spec.make_world(0, "oven", warm_up=0.0).source, [1.0, 0.6], atol=1e-12)
    # a class names its object even where a later object (drawn over it) covers the object's centre
    save_objects([SceneObject("oven", box_footprint((1.0, 0.6), (0.6, 0.6)), (0.0, 0.9)),
                  SceneObject("microwave", box_footprint((1.0, 0.6), (0.3, 0.3)), (0.9, 1.2))], flat / "o2.yaml")
    spec = load_world(_world_file(flat, objects="o2.yaml", sources={"oven": "oven", "C": [1.0, 0.6]}))
    assert spec.make_world(0, "oven", warm_up=0.0).source_object.class_name == "oven"
    assert spec.make_world(0, "C", warm_up=0.0).source_object.class_name == "microwave"  # the one on top there


def test_gap_and_geodesic_against_brute_force_and_the_loop(flat):
    (flat / "rooms_p.yaml").write_text("number_classes: 81\nroom_categories:\n  Kitchen: {oven: 0.2}\n"
                                       "  LivingRoom: {microwave: 0.01}\n")
    spec = load_world(_world_file(flat, room_classes="rooms_p.yaml"))
    f = findability(spec)
    house = spec.house()
    g = house.grid
    space = FreeSpace(house, Camera(), clearance=0.25)
    nav_xy = g.cell_centres()[space.nav]
    oven = [o for o in house.objects if o.class_name == "oven"][0]
    fp_xy = g.cell_to_world(np.argwhere(oven.mask(g)))
    d = np.sqrt(((nav_xy[:, None, :] - fp_xy[None, :, :]) ** 2).sum(-1))  # every pair
    assert f["oven"]["gap"] == pytest.approx(d.min(), rel=1e-12)
    assert f["oven"]["target_cells"] == len(fp_xy) == 36 and f["oven"]["object"] == "oven_0"
    cx, cy = g.cell_to_world(g.world_to_cell(np.array([4.0, 1.0])))  # a point source: the centre of its cell
    s1 = np.hypot(nav_xy[:, 0] - cx, nav_xy[:, 1] - cy).min()
    assert f["S1"]["gap"] == pytest.approx(s1, rel=1e-12) and f["S1"]["object"] is None
    # the closed loop's own geodesic (computed before its first stop) is the one world check reports
    for name in ("oven", "S1"):
        run = run_closed_loop(name, 0, "tour", "olfaction", world_spec=spec,
                              search=SearchConfig(time_budget=1.0))
        assert f[name]["geodesic"] == pytest.approx(run.geodesic, rel=1e-12), name
        assert np.isfinite(run.geodesic)


def test_world_check_refuses_a_source_out_of_reach(flat, capsys):
    path = flat / "world.yaml"
    gap = findability(load_world(path))["oven"]["gap"]
    assert 0.2 < gap < 0.5
    assert main(["world", "check", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"source oven: (1.00, 0.60) in Kitchen, object oven_0 (36 cells);" in out
    assert f"nearest drivable cell {gap:.2f} m from it" in out
    assert main(["world", "check", str(path), "--found-radius", "0.2"]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.count("\n") == 1
    assert (f"source 'oven' can never be found: the nearest drivable cell is {gap:.2f} m from the footprint of "
            "'oven_0', farther than the found radius 0.2 m") in cap.err
    # a wider robot: the gap grows with the clearance, and 0.5 m no longer reaches the oven
    path = _world_file(flat, sources={"oven": "oven"})
    assert main(["world", "check", str(path), "--clearance", "0.5"]) == 2
    assert "clearance (--clearance, now 0.5 m)" in capsys.readouterr().err
    assert main(["world", "check", str(path), "--clearance", "0.5", "--found-radius", "0.52"]) == 0


def test_a_source_behind_a_door_too_narrow_for_the_robot(flat):
    """The 1 m door: with 0.55 m clearance no drivable cell connects the kitchen (start) to the living room."""
    spec = load_world(flat / "world.yaml")
    f = findability(spec, clearance=0.55, found_radius=1.0)
    assert f["S1"]["gap"] <= 1.0 and f["S1"]["geodesic"] == np.inf and not f["S1"]["findable"]
    with pytest.raises(ValueError, match=r"source 'S1' can never be found: the drivable cells within 1 m of it are "
                                         r"not connected to the start \(clearance 0\.55 m\)"):
        check_findable(spec, clearance=0.55, found_radius=1.0)


def test_search_refuses_before_any_run(flat, tmp_path, capsys):
    out = tmp_path / "s"
    assert main(["search", "--world", str(flat / "world.yaml"), "--sources", "oven", "--found-radius", "0.2",
                 "--seeds", "1", "--out", str(out), "--quiet"]) == 2
    assert "source 'oven' can never be found" in capsys.readouterr().err
    assert not out.exists()


def test_search_options_reach_the_runs(flat, tmp_path):
    import json

    (flat / "rp.yaml").write_text("number_classes: 81\nroom_categories:\n  Kitchen: {oven: 0.2}\n"
                                  "  LivingRoom: {microwave: 0.01}\n")
    path = _world_file(flat, room_classes="rp.yaml", sources={"oven": "oven"})
    out = tmp_path / "s"
    assert main(["search", "--world", str(path), "--found-radius", "0.8", "--clearance", "0.3", "--seeds", "1",
                 "--policies", "tour", "--variants", "olfaction", "--budget", "5", "--out", str(out), "--quiet",
                 "--no-figures", "--workers", "1"]) == 0
    (run,) = sorted((out / "runs").glob("*.npz"))
    with np.load(run) as z:
        search = json.loads(str(z["config"]))["search"]
        geodesic = float(z["geodesic"])
    assert (search["found_radius"], search["clearance"]) == (0.8, 0.3)
    f = findability(load_world(path), found_radius=0.8, clearance=0.3)["oven"]
    assert geodesic == pytest.approx(f["geodesic"], rel=1e-12)


def test_a_world_without_room_classes_runs_the_closed_loop(flat):
    """No p(o | room): every room at the class prior, so semantics+rooms is semantics, run for run."""
    spec = load_world(flat / "world.yaml")
    assert spec.ontology.rooms == ()
    runs = [run_closed_loop("oven", 0, "tour", v, world_spec=spec, search=SearchConfig(time_budget=40.0))
            for v in ("semantics", "semantics+rooms")]
    np.testing.assert_array_equal(runs[0].final_posterior, runs[1].final_posterior)
    np.testing.assert_array_equal(runs[0].error, runs[1].error)
    assert runs[0].n_steps >= 2
