"""The command line: ``psgsl demo``, ``psgsl experiment`` (resumable), ``psgsl estimate``, and its errors."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import numpy as np
import pytest

from psgsl_pgm import Ontology, fuse, kitchen_ontology, semantic_source_probability
from psgsl_pgm.cli._main import main
from psgsl_pgm.experiment import VARIANTS, mean_ci


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    assert main(["demo", "--seeds", "2", "--workers", "2", "--out", str(out), "--quiet", "--no-search"]) == 0
    return out


@pytest.mark.slow  # the demo's fixture runs the whole small experiment on 2 workers (~11 s)
def test_demo_writes_every_output_and_a_consistent_summary(demo_dir):
    for name in ("summary.json", "summary.txt", "metrics.csv", "error-chart.png", "progression.png",
                 "room-types.png"):
        assert (demo_dir / name).stat().st_size > 0, name
    summary = json.loads((demo_dir / "summary.json").read_text())
    assert summary["n_runs"] == 2 and summary["seeds"] == [0, 1]
    with open(demo_dir / "metrics.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    for name in VARIANTS:
        assert set(summary[name]) >= {"early_error", "final_error"}
        assert set(summary[name]["final_error"]) == {"mean", "ci95"}
        finals = []
        for seed in (0, 1):
            mine = [r for r in rows if r["variant"] == name and int(r["seed"]) == seed]
            finals.append(float(max(mine, key=lambda r: int(r["step"]))["error_m"]))
        expected = mean_ci(finals, lower=0.0)  # errors are distances: the interval is cut at 0
        assert summary[name]["final_error"]["mean"] == pytest.approx(expected["mean"], abs=1e-5)  # CSV: 6 decimals
        np.testing.assert_allclose(summary[name]["final_error"]["ci95"], expected["ci95"], atol=1e-5)


def test_experiment_is_resumable(tmp_path, monkeypatch, capsys):
    """An experiment over a grid whose runs are on disk recomputes nothing."""
    import psgsl_pgm.experiment._run as run_module

    argv = ["experiment", "--sources", "oven", "--seeds", "2", "--estimators", "infotaxis", "--workers", "1",
            "--stops", "3", "--out", str(tmp_path), "--quiet"]
    assert main(argv) == 0

    def refuse(*args, **kwargs):
        raise AssertionError("a finished run was recomputed")

    monkeypatch.setattr(run_module, "run_search", refuse)
    capsys.readouterr()
    assert main(argv) == 0
    assert "oven/infotaxis" in capsys.readouterr().out
    nested = json.loads((tmp_path / "summary.json").read_text())
    assert nested["oven/infotaxis"]["n_runs"] == 2
    assert (tmp_path / "oven-infotaxis" / "error-chart.png").exists()


@pytest.mark.slow  # shares the demo's fixture
def test_stored_runs_with_another_configuration_are_refused(demo_dir):
    from psgsl_pgm.experiment import ExperimentConfig, run_experiment

    before = sorted(p.name for p in demo_dir.rglob("*"))
    with pytest.raises(ValueError, match="computed with other settings") as exc:
        run_experiment(["oven"], [0], ["infotaxis"], out=demo_dir, config=ExperimentConfig(encounter_scale=1.0),
                       progress=False, flat=True)
    default = ExperimentConfig().encounter_scale
    assert f"experiment.encounter_scale: {default!r} → 1)" in str(exc.value)
    # the demo's flat layout and an experiment's folders per source never share a directory
    with pytest.raises(ValueError, match="layout.flat: true → false"):
        run_experiment(["oven"], [0], ["infotaxis"], out=demo_dir, progress=False)
    assert sorted(p.name for p in demo_dir.rglob("*")) == before  # refused: nothing written


def test_estimate_on_user_arrays_equals_the_library(tmp_path):
    ont = kitchen_ontology()
    rng = np.random.default_rng(7)
    probs = rng.dirichlet(np.ones(len(ont.classes)), size=(6, 8))
    olf = rng.dirichlet(np.ones(48)).reshape(6, 8)
    np.save(tmp_path / "p.npy", probs)
    np.save(tmp_path / "g.npy", olf)
    ont.to_yaml(tmp_path / "o.yaml")
    code = main(["estimate", "--ontology", str(tmp_path / "o.yaml"), "--class-probs", str(tmp_path / "p.npy"),
                 "--olfactory", str(tmp_path / "g.npy"), "--gas", "smoke", "--out", str(tmp_path / "s.npy")])
    assert code == 0
    expected = fuse(olf, semantic_source_probability(probs, ont.source_likelihood("smoke"), ont.class_prior))
    np.testing.assert_allclose(np.load(tmp_path / "s.npy"), expected, rtol=1e-12)


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda d: d.update(ontology=d["dir"] / "missing.yaml"), "--ontology: no such file .*missing.yaml"),
        (lambda d: d["ontology"].write_text("classes: [oven\n"), "ontology"),
        (lambda d: np.save(d["probs"], np.ones((6, 8, 2)) / 2), "--class-probs must have shape"),
        (lambda d: np.save(d["olf"], np.ones((5, 8)) / 40), "--olfactory must have the map's shape"),
        (lambda d: np.save(d["olf"], -np.ones((6, 8))), "olfactory|posterior|negative"),
        (lambda d: d.update(gas="ammonia"), "ammonia"),
        (lambda d: d["probs"].write_bytes(b"garbage"), "is not a .npy array"),
    ],
)
def test_estimate_bad_input_is_one_line_and_exit_code_2(tmp_path, mutate, message):
    ont = kitchen_ontology()
    d = {"dir": tmp_path, "ontology": tmp_path / "o.yaml", "probs": tmp_path / "p.npy", "olf": tmp_path / "g.npy",
         "gas": "smoke"}
    ont.to_yaml(d["ontology"])
    np.save(d["probs"], np.full((6, 8, len(ont.classes)), 1 / len(ont.classes)))
    np.save(d["olf"], np.full((6, 8), 1 / 48))
    mutate(d)
    proc = subprocess.run(
        [sys.executable, "-m", "psgsl_pgm", "estimate", "--ontology", str(d["ontology"]), "--class-probs",
         str(d["probs"]), "--olfactory", str(d["olf"]), "--gas", d["gas"], "--out", str(tmp_path / "s.npy")],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert lines[0].startswith("psgsl estimate: error:")
    import re

    assert re.search(message, lines[0]), lines[0]
    assert not (tmp_path / "s.npy").exists()


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["demo", "--seeds", "0"])
    assert exc.value.code == 2
    assert "expected a positive integer" in capsys.readouterr().err
    assert main(["experiment", "--sources", "1,x", "--quiet"]) == 2
    assert "a source position must read" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["experiment", "--estimators", "kalman"])
    assert exc.value.code == 2


def test_experiment_runs_held_out_seeds_from_first_seed_and_resumes(tmp_path, monkeypatch):
    import psgsl_pgm.experiment._run as run_module
    from psgsl_pgm.experiment import load_run

    out = tmp_path / "e"
    argv = ["experiment", "--sources", "oven", "--seeds", "2", "--first-seed", "11", "--estimators", "infotaxis",
            "--stops", "2", "--workers", "1", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    assert sorted(load_run(p).seed for p in (out / "runs").iterdir()) == [11, 12]
    summary = json.loads((out / "summary.json").read_text())["oven/infotaxis"]
    assert summary["seeds"] == [11, 12]
    assert set(summary["semantics+rooms"]["coverage90"]) == {"quarter", "half", "three_quarters", "final"}

    def refuse(*args, **kwargs):
        raise AssertionError("a finished run was recomputed")

    monkeypatch.setattr(run_module, "run_search", refuse)
    assert main(argv) == 0  # resumed from the stored seeds 11 and 12
