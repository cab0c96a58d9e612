"""`psgsl search` keys its stored runs by content: each file the world names, edited by one byte, makes the stored
runs refused (naming the file's key and both hashes), never reused; restored, they resume. Options and the world's
settings likewise. Nothing is created by a refused command; paired.json only when something is paired; the
stored config records the start the robot used."""

from __future__ import annotations

import json

import yaml

from psgsl_pgm.cli._main import main
from psgsl_pgm.search import load_search_run

from ..core.key_worlds import one_byte_edit, sha, write_full_world


def _args(world, out, *extra):
    return ["search", "--world", str(world), "--sources", "stove", "--seeds", "1", "--policies", "tour",
            "--variants", "olfaction", "--budget", "20", "--workers", "1", "--no-figures", "--quiet",
            "--out", str(out), *extra]


def _tree(out):
    return {str(p.relative_to(out)): p.stat().st_mtime_ns for p in sorted(out.rglob("*"))}


def test_each_named_file_edited_by_one_byte_is_refused_never_reused(tmp_path, capsys):
    world, files = write_full_world(tmp_path / "w")
    out = tmp_path / "out"
    assert main(_args(world, out)) == 0
    tree = _tree(out)
    assert len(files) == 12  # map + image, rooms + 2 masks, objects, ontology, room table, region, beliefs, 2 CSVs
    for label, path in files.items():
        old = one_byte_edit(path)
        capsys.readouterr()
        assert main(_args(world, out)) == 2, label
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1, err
        assert f"world.{label}: sha256 {sha(old)[:12]}… → sha256 {sha(path)[:12]}…" in err[0], (label, err[0])
        assert err[0].count("→") == 1, err[0]  # only that file differs
        assert _tree(out) == tree, label  # nothing written, nothing recomputed
        path.write_bytes(old)
    assert main(_args(world, out)) == 0  # restored: the stored run resumes
    runs = sorted((out / "runs").glob("*.npz"))
    assert [p.name for p in runs] == ["stove__tour__olfaction__infotaxis__seed0.npz"]
    assert runs[0].stat().st_mtime_ns == tree["runs/stove__tour__olfaction__infotaxis__seed0.npz"]


def test_options_and_world_settings_are_refused_with_both_values(tmp_path, capsys):
    world, files = write_full_world(tmp_path / "w", beliefs=False)
    out = tmp_path / "out"
    assert main(_args(world, out)) == 0
    tree = _tree(out)
    capsys.readouterr()
    assert main(_args(world, out, "--budget", "40")) == 2
    assert "search.time_budget: 20 → 40" in capsys.readouterr().err
    data = yaml.safe_load(world.read_text())
    data["wind"]["period"] = 3.0
    data["start"] = [1.5, 1.2]
    world.write_text(yaml.safe_dump(data))
    assert main(_args(world, out)) == 2
    err = capsys.readouterr().err
    assert "world.start: [1.5, 1.5] → [1.5, 1.2]; world.wind.period: 2 → 3" in err
    assert _tree(out) == tree


def test_no_empty_paired_json_and_the_start_used_is_stored(tmp_path):
    world, _ = write_full_world(tmp_path / "w", beliefs=False)
    out = tmp_path / "out"
    assert main(_args(world, out, "--seeds", "2")) == 0
    group = out / "stove-infotaxis"
    assert not (group / "paired.json").exists()  # one policy/variant: nothing is paired, no file
    (path,) = sorted((out / "runs").glob("*seed0.npz"))
    run = load_search_run(path)
    assert run.config["search"]["start"] == [1.5, 1.5]  # the world's start, not SearchConfig's default
    assert run.config["key"]["search.start"] == [0.8, 6.0]  # the option as given is part of the key
    assert run.position[0] == __import__("pytest").approx([1.5, 1.5], abs=0.1)
    assert main(_args(world, out, "--seeds", "2", "--policies", "tour", "greedy")) == 0
    paired = json.loads((group / "paired.json").read_text())
    assert set(paired) == {"greedy/olfaction - tour/olfaction"}


def test_off_ontology_is_part_of_the_key_and_reaches_the_robot(tmp_path, capsys):
    """--off-ontology ε: stored in the run's experiment config and its key; another ε in the same folder is
    refused with both values; ε = 0 keys the runs as before the option existed."""
    world, _ = write_full_world(tmp_path / "w", beliefs=False)
    out = tmp_path / "out"
    assert main(_args(world, out, "--variants", "semantics", "--off-ontology", "0.1")) == 0
    (path,) = sorted((out / "runs").glob("*.npz"))
    run = load_search_run(path)
    assert run.config["experiment"]["off_ontology"] == 0.1
    assert run.config["key"]["experiment.off_ontology"] == 0.1
    tree = _tree(out)
    capsys.readouterr()
    assert main(_args(world, out, "--variants", "semantics", "--off-ontology", "0.2")) == 2
    assert "experiment.off_ontology: 0.1 → 0.2" in capsys.readouterr().err
    assert _tree(out) == tree
    plain = tmp_path / "plain"
    assert main(_args(world, plain, "--off-ontology", "0")) == 0
    (path,) = sorted((plain / "runs").glob("*.npz"))
    assert not any("off_ontology" in k for k in load_search_run(path).config["key"])


def test_missed_hit_rate_is_part_of_the_key_and_bad_values_are_one_line(tmp_path, capsys):
    """--missed-hit-rate δ: stored in the run's experiment config and its key; another δ in the same folder is
    refused with both values; δ = 0 keys the runs as before the option existed; δ = 1 or not a number is one line
    and exit 2."""
    world, _ = write_full_world(tmp_path / "w", beliefs=False)
    out = tmp_path / "out"
    assert main(_args(world, out, "--missed-hit-rate", "0.01")) == 0
    (path,) = sorted((out / "runs").glob("*.npz"))
    run = load_search_run(path)
    assert run.config["experiment"]["missed_hit_rate"] == 0.01
    assert run.config["key"]["experiment.missed_hit_rate"] == 0.01
    tree = _tree(out)
    capsys.readouterr()
    assert main(_args(world, out, "--missed-hit-rate", "0.02")) == 2
    assert "experiment.missed_hit_rate: 0.01 → 0.02" in capsys.readouterr().err
    assert _tree(out) == tree
    plain = tmp_path / "plain"
    assert main(_args(world, plain, "--missed-hit-rate", "0")) == 0
    (path,) = sorted((plain / "runs").glob("*.npz"))
    assert not any("missed_hit_rate" in k for k in load_search_run(path).config["key"])
    for bad in ("1", "-0.1", "nan", "abc", "1e999"):
        capsys.readouterr()
        assert main(_args(world, tmp_path / "bad", "--missed-hit-rate", bad)) == 2, bad
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"psgsl search: error: --missed-hit-rate must be a number in [0, 1), got {bad!r}"]
        assert not (tmp_path / "bad").exists()
