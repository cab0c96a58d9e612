"""benchmarks/compare_benchmarks.py pairs one arm of two benchmark folders by (house, seed)."""

import json

import numpy as np
import pytest

from ._scripts import load_script


def _folder(tmp_path, name, budget=1000.0):
    d = tmp_path / name
    d.mkdir()
    (d / "summary.json").write_text(json.dumps({"settings": {"budget": budget, "name": name}}))
    return d


def _rows(times, arm="infotaxis/semantics+rooms", condition="right-ontology"):
    return [{"house": f"h{i // 2}", "seed": i % 2, "arm": arm, "condition": condition, "t": t, "found": t < 1000}
            for i, t in enumerate(times)]


@pytest.fixture
def script(monkeypatch):
    import psgsl_pgm.search._bench_report as report

    tables = {"A": _rows([100.0, 300.0, 1000.0, 50.0]) + _rows([1.0] * 4, arm="infotaxis/olfaction"),
              "B": _rows([200.0, 300.0, 400.0, 60.0, 70.0])}  # B has one episode A lacks
    monkeypatch.setattr(report, "_table", lambda folder, settings: tables[settings["name"]])
    return load_script("compare_benchmarks")


def test_the_difference_and_counts_of_paired_episodes(tmp_path, script):
    r = script.compare(_folder(tmp_path, "A"), _folder(tmp_path, "B"))
    assert r["episodes"] == 4 and r["houses"] == 2
    assert r["rmst"] == {"A": pytest.approx(362.5), "B": pytest.approx(240.0)}
    assert r["difference"]["value"] == pytest.approx(122.5)
    assert r["ratio"]["value"] == pytest.approx(362.5 / 240.0)
    lo, hi = r["difference"]["ci95"]
    assert lo <= 122.5 <= hi
    assert r["faster_slower_equal"] == [2, 1, 1]
    assert r["success"] == {"A": 0.75, "B": 1.0}
    assert np.isfinite(r["ratio"]["ci95"]).all()


def test_mismatched_folders_are_refused(tmp_path, script, capsys):
    with pytest.raises(ValueError, match="budgets differ"):
        script.compare(_folder(tmp_path, "A"), _folder(tmp_path, "B", budget=500.0))
    with pytest.raises(ValueError, match="fewer than 2 episodes of arm 'nearest-object/semantics\\+rooms'"):
        script.compare(tmp_path / "A", tmp_path / "A", arm="nearest-object/semantics+rooms")
    assert script.main([str(tmp_path / "nowhere"), str(tmp_path / "A")]) == 2
    assert "not a benchmark folder" in capsys.readouterr().err


def test_two_arms_of_one_folder_and_the_time_to_every_source(tmp_path, monkeypatch):
    import psgsl_pgm.search._bench_report as report

    rows = _rows([100.0, 200.0, 300.0, 400.0]) + _rows([150.0, 150.0, 350.0, 1000.0], arm="infotaxis/olfaction")
    for i, r in enumerate(rows):
        r["several"] = {"t_all": r["t"] + 10 * i, "all": r["t"] < 1000}
    monkeypatch.setattr(report, "_table", lambda folder, settings: rows)
    script = load_script("compare_benchmarks")
    d = _folder(tmp_path, "A")
    r = script.compare(d, d, arm_b="infotaxis/olfaction")
    assert r["difference"]["value"] == pytest.approx(250.0 - 412.5)
    assert r["faster_slower_equal"] == [3, 1, 0]
    r = script.compare(d, d, arm_b="infotaxis/olfaction", time="all")
    assert r["rmst"]["A"] == pytest.approx(250.0 + 15.0) and r["rmst"]["B"] == pytest.approx(412.5 + 55.0)
    for x in rows:
        del x["several"]
    with pytest.raises(ValueError, match="needs a several-source benchmark"):
        script.compare(d, d, arm_b="infotaxis/olfaction", time="all")
