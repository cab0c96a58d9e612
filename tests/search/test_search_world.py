"""`psgsl search --world`: the closed-loop grid on a world file (its sources, its house, its content in the
stored run key, so that runs of another world in the same output directory are refused)."""

import json
from pathlib import Path

import yaml

import psgsl_pgm
from psgsl_pgm.cli._main import main

HOUSE = Path(psgsl_pgm.__file__).parent / "data" / "worlds" / "house.yaml"


def write_world(d, **over):
    """The packaged embedded house with its own source names."""
    world = yaml.safe_load(HOUSE.read_text())
    world["sources"] = {"stove": "oven"}
    world.update(over)
    d.mkdir(parents=True, exist_ok=True)
    (d / "world.yaml").write_text(yaml.safe_dump(world))
    return d / "world.yaml"


def _args(world, out, *extra):
    return ["search", "--world", str(world), "--seeds", "1", "--policies", "tour", "--variants", "olfaction",
            "--budget", "30", "--workers", "1", "--no-figures", "--quiet", "--out", str(out), *extra]


def test_search_command_with_a_world(tmp_path, capsys):
    world = write_world(tmp_path / "w1")
    out = tmp_path / "out"
    assert main(_args(world, out)) == 0  # without --sources: the world's sources
    top = json.loads((out / "summary.json").read_text())
    assert set(top) == {"stove/infotaxis"}
    assert set(top["stove/infotaxis"]) == {"tour/olfaction"}
    assert top["stove/infotaxis"]["tour/olfaction"]["n_runs"] == 1
    stamps = {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()}
    # runs are keyed by content: a copy of the same world elsewhere is the same world and resumes ...
    copy = write_world(tmp_path / "w2")
    assert main(_args(copy, out)) == 0
    assert {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()} == stamps
    # ... a world with other sources is another world: refused, naming the setting and both values
    other = write_world(tmp_path / "w3", sources={"cooker": "oven"})
    capsys.readouterr()
    assert main(_args(other, out, "--sources", "cooker")) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "world.sources.stove: oven → (none)" in err[0]
    assert "world.sources.cooker: (none) → oven" in err[0]
    assert main(_args(world, out)) == 0  # the same world resumes
    assert {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()} == stamps


def test_a_bad_world_file_is_one_line_and_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("map: nowhere.yaml\n")
    out = tmp_path / "out"
    assert main(_args(bad, out)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.yaml" in err[0]
    assert not out.exists()


def test_an_unknown_source_name_is_refused_before_any_run(tmp_path, capsys):
    world = write_world(tmp_path)
    out = tmp_path / "out"
    assert main(_args(world, out, "--sources", "piano")) == 2
    assert "piano" in capsys.readouterr().err
    assert not out.exists()


def test_a_world_without_start_searches_from_its_default_start(tmp_path):
    """No `start:` in the world file: the closed loop starts where `world check` measures from (the navigable
    cell nearest the map's centre), not at the search settings' default start."""
    import numpy as np

    from psgsl_pgm.search import SearchConfig, run_closed_loop
    from psgsl_pgm.sim import load_world

    world = yaml.safe_load(HOUSE.read_text())
    del world["start"]
    path = tmp_path / "world.yaml"
    path.write_text(yaml.safe_dump(world))
    spec = load_world(path)
    run = run_closed_loop("oven", 0, "tour", "olfaction", search=SearchConfig(time_budget=5.0), world_spec=spec)
    want = spec.start_for(spec.house(0))
    assert not np.allclose(want, SearchConfig().start)
    np.testing.assert_array_equal(run.config["search"]["start"], want)
    assert np.linalg.norm(run.position[0] - want) <= spec.house(0).grid.resolution  # the start cell's centre
