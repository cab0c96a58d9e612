"""`psgsl experiment` keys its stored runs by content: an edited world is refused (naming each setting with both
values), never reused; another world never joins a folder; the top-level summary covers every stored run; a
refused command leaves no trace; the stored config records the start the robot used."""

from __future__ import annotations

import json

import yaml

from psgsl_pgm.cli._main import main
from psgsl_pgm.experiment import load_run

from ..core.key_worlds import sha
from .test_experiment_world import write_flat


def _args(world, out, *extra):
    return ["experiment", "--world", str(world), "--seeds", "2", "--estimators", "infotaxis", "--stops", "2",
            "--workers", "1", "--quiet", "--out", str(out), *extra]


def _tree(out):
    return {str(p.relative_to(out)): p.stat().st_mtime_ns for p in sorted(out.rglob("*"))}


def test_an_edited_world_is_refused_naming_each_setting(tmp_path, capsys):
    """The trial's case: wind speed 0.2 -> 0.6 and `objects:` removed, the same command again."""
    world = write_flat(tmp_path)
    out = tmp_path / "exp"
    assert main(_args(world, out)) == 0
    tree = _tree(out)
    objects = sha(tmp_path / "objects.yaml")
    data = yaml.safe_load(world.read_text())
    data["wind"]["speed"] = 0.6
    del data["objects"]
    data["sources"] = {"corner": [4.2, 0.6]}  # without objects the stove is gone
    world.write_text(yaml.safe_dump(data))
    capsys.readouterr()
    assert main(_args(world, out, "--sources", "corner")) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"psgsl experiment: error: --out {out} holds runs computed with other settings")
    assert "world.wind.speed: 0.2 → 0.6" in err[0]
    assert f"world.objects: sha256 {objects[:12]}… → (none)" in err[0]
    assert "world.sources.stove: oven → (none)" in err[0]
    assert _tree(out) == tree  # refused: nothing written, nothing recomputed


def test_an_option_is_refused_by_name_and_the_summary_covers_every_stored_run(tmp_path, capsys):
    world = write_flat(tmp_path)
    out = tmp_path / "exp"
    assert main(_args(world, out, "--sources", "stove")) == 0
    tree = _tree(out)
    capsys.readouterr()
    assert main(_args(world, out, "--sources", "stove", "--stops", "3")) == 2
    assert "experiment.stops: 2 → 3" in capsys.readouterr().err
    assert _tree(out) == tree
    # the same world and settings with another source join the folder; the summary describes both calls' runs
    assert main(_args(world, out, "--sources", "corner", "--seeds", "1")) == 0
    top = json.loads((out / "summary.json").read_text())
    assert set(top) == {"stove/infotaxis", "corner/infotaxis"}
    assert top["stove/infotaxis"]["n_runs"] == 2 and top["corner/infotaxis"]["n_runs"] == 1
    rows = (out / "metrics.csv").read_text().splitlines()[1:]
    assert {r.split(",")[0] for r in rows} == {"stove", "corner"}
    assert "stove/infotaxis" in capsys.readouterr().out  # the printed tables too


def test_a_refused_command_leaves_no_trace(tmp_path, capsys):
    world = write_flat(tmp_path)
    out = tmp_path / "exp"
    assert main(_args(world, out, "--sources", "toaster")) == 2  # refused before any run: no folder at all
    assert not out.exists()
    out.mkdir()
    assert main(_args(world, out, "--sources", "toaster")) == 2
    assert list(out.iterdir()) == []  # no runs/, no lock file


def test_the_stored_config_records_the_start_used(tmp_path):
    world = write_flat(tmp_path)
    out = tmp_path / "exp"
    assert main(_args(world, out, "--sources", "stove", "--seeds", "1")) == 0
    run = load_run(out / "runs" / "stove__infotaxis__seed0.npz")
    assert run.config["start"] == [float(v) for v in run.position[0]]
    assert abs(run.config["start"][0] - 1.5) <= 0.1 and abs(run.config["start"][1] - 1.5) <= 0.1
    assert run.config["key"]["world.start"] == [1.5, 1.5]
