"""``--gas unknown`` on ``psgsl search``, ``psgsl experiment`` and ``psgsl benchmark``; ``gas: unknown`` in a world
file; a gas the ontology lacks is one line and exit 2."""

from __future__ import annotations

import json

import pytest
import yaml

from psgsl_pgm.cli._main import main
from psgsl_pgm.sim import load_world
from psgsl_pgm.sim._worldfile import default_world_path


@pytest.mark.parametrize("command", ["search", "experiment"])
def test_a_gas_the_ontology_lacks_is_one_line_and_exit_2(tmp_path, capsys, command):
    out = tmp_path / "o"
    assert main([command, "--gas", "chlorine", "--seeds", "1", "--workers", "1", "--quiet", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--gas chlorine: not a gas of the ontology" in err[0] and "'unknown'" in err[0]
    assert not (out / "runs").exists() or not any((out / "runs").iterdir())


def test_a_world_file_may_leave_the_gas_unknown(tmp_path):
    data = yaml.safe_load(default_world_path().read_text())
    data["gas"] = "unknown"
    (tmp_path / "w.yaml").write_text(yaml.safe_dump(data))
    assert load_world(tmp_path / "w.yaml").gas == "unknown"
    data["gas"] = "chlorine"
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(ValueError, match="key 'gas': 'chlorine' is not a gas of the ontology .* nor 'unknown'"):
        load_world(tmp_path / "bad.yaml")


def test_search_with_the_gas_unknown_reports_gas_identification(tmp_path):
    out = tmp_path / "s"
    argv = ["search", "--gas", "unknown", "--sources", "oven", "--policies", "greedy", "--variants",
            "semantics+rooms", "--seeds", "1", "--budget", "15", "--workers", "1", "--quiet", "--no-figures",
            "--out", str(out)]
    assert main(argv) == 0
    entry = json.loads((out / "summary.json").read_text())["oven/infotaxis"]["greedy/semantics+rooms"]
    assert set(entry["gas_identified"]) == {"value", "ci95"}
    assert entry["time_to_gas"]["tau"] == 15.0 and entry["time_to_gas"]["n_runs"] == 1


def test_benchmark_gas_choice_is_checked(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:  # argparse's own choice check: usage and one error line, exit 2
        main(["benchmark", "--houses", "1", "--seeds", "1", "--gas", "maybe", "--out", str(tmp_path / "b")])
    assert stop.value.code == 2 and "argument --gas: invalid choice: 'maybe'" in capsys.readouterr().err
    assert not (tmp_path / "b").exists()


def test_benchmark_with_the_gas_unknown_reports_gas_identification(tmp_path):
    out = tmp_path / "b"
    argv = ["benchmark", "--gas", "unknown", "--houses", "1", "--seeds", "1", "--rooms", "3", "--area", "45",
            "--policies", "greedy", "--variants", "semantics+rooms", "--conditions", "right-ontology",
            "--budget", "10", "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv) == 0
    episodes = json.loads((out / "episodes.json").read_text())
    assert len(episodes) == 1
    summary = json.dumps(json.loads((out / "summary.json").read_text()))
    assert '"gas_identified"' in summary and '"time_to_gas"' in summary
