"""benchmarks/benchmark_cpu.py: two benchmark folders of one grid, run by run — the same bits? and the CPU per run."""

import json

import numpy as np
import pytest

from ._scripts import load_script


def _run(folder, name, cpu, *, path=(0.0, 1.0), t=np.nan):
    (folder / "runs").mkdir(parents=True, exist_ok=True)
    config = json.dumps({"benchmark": {"cpu_seconds": cpu}})
    np.savez(folder / "runs" / name, config=np.array(config), path=np.array(path), time_to_find=np.array(t))


@pytest.fixture
def script():
    return load_script("benchmark_cpu")


def test_same_runs_and_cpu_per_arm(tmp_path, script, capsys):
    a, b = tmp_path / "a", tmp_path / "b"
    names = ["h00000__right-ontology__infotaxis__olfaction__infotaxis__seed0.npz",
             "h00000__right-ontology__infotaxis__olfaction__infotaxis__seed1.npz",
             "h00000__no-rooms__tour__olfaction__infotaxis__seed0.npz"]
    for name, before, after in zip(names, (2.0, 4.0, 1.0), (1.0, 1.0, 1.5)):
        _run(a, name, before)  # NaN times equal NaN times: not a difference
        _run(b, name, after)
    r = script.compare(a, b)
    assert r["runs"] == 3 and r["differing"] == []
    info = r["arms"]["infotaxis/olfaction"]
    assert info["n"] == 2 and info["median_before"] == 3.0 and info["median_after"] == 1.0
    assert info["median_ratio"] == pytest.approx(0.375)  # median of 0.5 and 0.25
    assert r["arms"]["all runs"]["mean_before"] == pytest.approx(7 / 3)
    _run(b, names[2], 1.5, path=(0.0, 2.0))  # another path: the run differs
    assert script.compare(a, b)["differing"] == [names[2]]
    assert script.main([str(a), str(b)]) == 0
    assert "3 runs; 1 differ" in capsys.readouterr().out


def test_bad_folders_give_one_line_and_exit_2(tmp_path, script, capsys):
    a = tmp_path / "a"
    _run(a, "h00000__right-ontology__infotaxis__olfaction__infotaxis__seed0.npz", 1.0)
    assert script.main([str(a), str(tmp_path / "missing")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("benchmark_cpu:") and "has no run" in err and "\n" not in err
    assert script.main([str(tmp_path / "missing"), str(a)]) == 2
    assert "not a benchmark folder" in capsys.readouterr().err
    _run(tmp_path / "c", "badname.npz", 1.0)
    with pytest.raises(ValueError, match="not a benchmark run file"):
        script.compare(tmp_path / "c", tmp_path / "c")
