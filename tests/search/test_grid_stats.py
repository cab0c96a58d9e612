"""summary.json and paired.json of ``psgsl search`` on hand-made runs: each number against a hand computation
or the statistics module, so that a wrong step, an unweighted mean or a flipped sign fails."""

import json

import numpy as np
import pytest

from psgsl_pgm.search import SearchRun
from psgsl_pgm.search._grid import PRIMARY, _paired, _time_mean, summarize_runs, write_search_outputs
from psgsl_pgm.search._store import save_search_run
from psgsl_pgm.search._survival import holm, kaplan_meier, rmst

BUDGET = 100.0


def _run(seed, t_find, *, policy="infotaxis", variant="olfaction", source="oven", hits=None, levels=None,
         times=None, area=None, errors=None):
    found = t_find < BUDGET
    times = np.asarray(times if times is not None else [0.0, 25.0, 50.0, 75.0, min(t_find, 99.0)], float)
    n = times.size
    hits = np.asarray(hits if hits is not None else [True] * n, bool)
    levels = np.asarray(levels if levels is not None else np.linspace(0.9, 0.5, n), float)
    area = np.asarray(area if area is not None else np.linspace(10.0, 2.0, n), float)
    errors = np.asarray(errors if errors is not None else np.linspace(4.0, 1.0, n), float)
    config = {"experiment": {}, "search": {"time_budget": BUDGET}}
    z = np.zeros(n)
    return SearchRun(source, seed, policy, variant, "infotaxis", np.array([7.5, 0.5]), bool(found),
                     float(t_find), 5.0, 7.0, times, np.zeros((n, 2)), z, np.zeros(n, bool), z, errors, errors,
                     z, area, hits, np.zeros((2, 2)), np.full((3, 4), 1 / 12, np.float32), config, levels)


def test_time_mean_weights_each_value_by_how_long_it_held():
    # error 5 for 10 s, 1 for 30 s (the last value holds no time): (50 + 30) / 40 = 2, not the plain mean 3
    assert _time_mean(np.array([0.0, 10.0, 40.0]), np.array([5.0, 1.0, 3.0])) == 2.0


def test_summary_of_runs_by_hand():
    runs = [
        _run(0, 30.0, hits=[True, False, True, False, False], levels=[0.2, 0.3, 0.4, 0.5, 0.95],
             times=[0.0, 10.0, 15.0, 22.0, 30.0], area=[9.0, 8.0, 7.0, 6.0, 4.0],
             errors=[5.0, 1.0, 1.0, 1.0, 9.0]),
        _run(1, 100.0, hits=[False, True, True, True, True], levels=[0.9, 0.8, 0.7, 0.6, 0.1],
             times=[0.0, 20.0, 40.0, 80.0, 99.0], area=[9.0, 8.0, 7.0, 6.0, 2.0]),
        _run(2, 100.0, hits=[False, False, False, False, True], levels=[0.9, 0.9, 0.9, 0.9, 0.4]),
    ]
    s = summarize_runs(runs)
    # run 0 ends at 30 s: ¼ -> 7.5 s -> step 0 (hit), ½ -> 15 s -> step 2 (hit), ¾ -> 22.5 s -> step 3 (miss)
    # run 1 ends at 99 s: ¼ -> 24.75 s -> step 1 (hit), ½ -> step 2 (hit), ¾ -> 74.25 s -> step 2 (hit)
    # run 2 (25-s steps to 99 s): miss, miss, miss; every final step: miss, hit, hit
    assert s["coverage90"] == {"quarter": 2 / 3, "half": 2 / 3, "three_quarters": 1 / 3, "final": 2 / 3}
    assert s["region_area90"]["mean"] == pytest.approx((4.0 + 2.0 + 2.0) / 3, rel=1e-15)
    assert s["hpd_level"] == {"median": 0.4, "mean": pytest.approx((0.95 + 0.1 + 0.4) / 3, rel=1e-15)}
    t = np.array([30.0, 100.0, 100.0])
    assert s["rmst"]["value"] == pytest.approx(t.mean(), rel=1e-15) and s["rmst"]["tau"] == BUDGET
    assert s["rmst"]["ci95"] == rmst(t, t < BUDGET, BUDGET)["ci95"]
    assert s["km"] == kaplan_meier(t, t < BUDGET)
    assert s["km"]["survival"] == [1.0, pytest.approx(2 / 3, rel=1e-15), pytest.approx(2 / 3, rel=1e-15)]
    assert s["time_to_find"]["median"] is None and s["time_to_find"]["not_found"] == 2
    assert "mean" not in s["time_to_find"] and "ci95" not in s["time_to_find"]  # no t-interval on capped times
    assert s["success_rate"]["value"] == 1 / 3
    # run 0's error over time: 5 for 10 s, then 1 for 20 s -> 70/30; runs 1, 2: linspace(4, 1) on their steps
    expected = [70 / 30, _time_mean(runs[1].time, runs[1].error), _time_mean(runs[2].time, runs[2].error)]
    assert s["mean_error"]["mean"] == pytest.approx(np.mean(expected), rel=1e-14)
    assert s["final_error"]["mean"] == pytest.approx((9.0 + 1.0 + 1.0) / 3, rel=1e-15)


def test_kaplan_meier_median_when_reached():
    s = summarize_runs([_run(k, t) for k, t in enumerate((20.0, 40.0, 60.0, 100.0))])
    assert s["time_to_find"]["median"] == 40.0  # S(40) = ½


def _groups(source="oven"):
    fast = [12.0, 30.0, 100.0, 41.0, 18.0, 25.0]
    slow = [80.0, 100.0, 100.0, 39.0, 100.0, 70.0]
    tour = [60.0] * 6
    g = {"tour/olfaction": [_run(k, t, policy="tour", source=source) for k, t in enumerate(tour)],
         "infotaxis/olfaction": [_run(k, t, source=source) for k, t in enumerate(slow)],
         "infotaxis/semantics+rooms": [_run(k, t, variant="semantics+rooms", source=source)
                                       for k, t in enumerate(fast)]}
    return g, np.array(fast), np.array(slow), np.array(tour)


def test_paired_json_direction_primary_and_holm():
    g, fast, slow, tour = _groups()
    out = _paired(g, source="oven", estimator="infotaxis")
    key = PRIMARY["comparison"]
    assert key == "infotaxis/semantics+rooms - infotaxis/olfaction"
    assert set(out) == {key, "infotaxis/semantics+rooms - tour/olfaction", "infotaxis/olfaction - tour/olfaction"}
    primary = out[key]
    # A - B: semantics+rooms is faster, so the difference is negative (a sign flip makes it +41.67)
    assert primary["rmst_difference"]["value"] == pytest.approx(np.mean(fast - slow), rel=1e-14)
    assert primary["rmst_difference"]["value"] < 0 and primary["rmst_difference"]["ci95"][1] < 0
    assert primary["primary"] is True and primary["p_holm"] == primary["p_value"]
    assert primary["found"] == {"A": 5, "B": 3} and primary["n"] == 6
    # d = fast - slow = (-68, -70, 0, 2, -82, -45), |Σ d| = 263: reached when the four large terms share one sign
    # (2 ways), whatever the signs of 2 and 0 (2·2): 8 of 64 sign vectors
    assert primary["p_value"] == pytest.approx(8 / 64, abs=1e-15)
    secondary = [k for k in out if k != key]
    assert all(out[k]["primary"] is False for k in secondary)
    np.testing.assert_allclose([out[k]["p_holm"] for k in secondary], holm([out[k]["p_value"] for k in secondary]),
                               rtol=1e-15)
    vs_tour = out["infotaxis/olfaction - tour/olfaction"]["rmst_difference"]["value"]
    assert vs_tour == pytest.approx(np.mean(slow - tour), rel=1e-14) and vs_tour > 0


def test_only_the_declared_source_and_estimator_carry_the_primary_comparison():
    g, *_ = _groups("bed")
    assert not any(v["primary"] for v in _paired(g, source="bed", estimator="infotaxis").values())
    g, *_ = _groups()
    assert not any(v["primary"] for v in _paired(g, source="oven", estimator="analytic-plume").values())
    # with no primary comparison in the table, all three are Holm-adjusted together
    out = _paired(g, source="oven", estimator="analytic-plume")
    np.testing.assert_allclose([v["p_holm"] for v in out.values()], holm([v["p_value"] for v in out.values()]))


def test_runs_of_different_budgets_are_not_summarized_together():
    runs = [_run(0, 30.0), _run(1, 50.0)]
    runs[1].config["search"]["time_budget"] = 200.0
    with pytest.raises(ValueError, match="one time budget"):
        summarize_runs(runs)


def test_written_files_hold_the_statistics(tmp_path):
    g, fast, slow, _ = _groups()
    for runs in g.values():
        for r in runs:
            save_search_run(r, tmp_path / "runs" / f"{r.policy}-{r.variant}-{r.seed}.npz")
    top = write_search_outputs(tmp_path, figures=False)
    summary = json.loads((tmp_path / "oven-infotaxis" / "summary.json").read_text())
    paired = json.loads((tmp_path / "oven-infotaxis" / "paired.json").read_text())
    assert top == {"oven/infotaxis": summary}
    entry = summary["infotaxis/semantics+rooms"]
    assert {"rmst", "km", "coverage90", "region_area90", "hpd_level", "success_rate"} <= set(entry)
    assert set(entry["km"]) == {"t", "survival", "lower", "upper"}
    assert set(entry["coverage90"]) == {"quarter", "half", "three_quarters", "final"}
    assert entry["rmst"]["value"] == pytest.approx(fast.mean(), rel=1e-14)
    assert paired[PRIMARY["comparison"]]["primary"] is True
    assert paired[PRIMARY["comparison"]]["rmst_difference"]["value"] == pytest.approx(np.mean(fast - slow), rel=1e-14)
