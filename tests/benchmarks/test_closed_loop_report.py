"""benchmarks/closed_loop_report.py pairs each closed-loop run's final credible region with the fixed tour's at the
same elapsed time, on the same seed, only while the tour is still searching."""

import numpy as np
import pytest

from ._scripts import load_script


def _script():
    return load_script("closed_loop_report")


def _run(runs, policy, seed, time, area, hit, *, found=True, estimator="analytic-plume", variant="olfaction"):
    np.savez(runs / f"oven__{policy}__{variant}__{estimator}__seed{seed}.npz", estimator=estimator, policy=policy,
             variant=variant, seed=seed, found=found, time_to_find=(time[-1] + 1.0) if found else 1000.0,
             time=np.asarray(time, float), region_area=np.asarray(area, float), region_hit=np.asarray(hit, bool))


def test_the_tour_is_read_at_its_last_stop_at_or_before_the_closed_loop_end(tmp_path):
    runs = tmp_path / "runs"
    runs.mkdir()
    tour_time, tour_area, tour_hit = [0, 10, 15, 30], [50, 40, 30, 20], [1, 1, 0, 0]
    for seed in (0, 1, 2):
        _run(runs, "tour", seed, tour_time, tour_area, tour_hit)  # found at 31 s
    _run(runs, "infotaxis", 0, [0, 5, 20], [60, 9, 3], [1, 0, 1])   # t = 20: the tour's stop at 15 s (30 m², miss)
    _run(runs, "infotaxis", 1, [0, 40], [60, 5], [1, 0])            # t = 40: the tour found it at 31 s, no pair
    _run(runs, "infotaxis", 2, [0, 10], [60, 7], [1, 1])            # t = 10 exactly: the tour's stop at 10 s (40 m²)
    _run(runs, "infotaxis", 0, [0, 20], [60, 100], [1, 0], estimator="infotaxis")  # another estimator: ignored
    _run(runs, "infotaxis", 0, [0, 20], [60, 100], [1, 0], variant="semantics")    # no semantic tour: no pair
    got = _script().matched_tour(runs, "analytic-plume")
    assert list(got) == [("oven", "infotaxis/olfaction")]
    m = got[("oven", "infotaxis/olfaction")]
    assert m["n"] == 2
    assert m["time_median"] == pytest.approx(15.0)
    assert m["area"] == pytest.approx((3 + 7) / 2) and m["coverage"] == pytest.approx(1.0)
    assert m["tour_area"] == pytest.approx((30 + 40) / 2) and m["tour_coverage"] == pytest.approx(0.5)
    assert _script().matched_tour(runs, "analytic-plume", min_pairs=3) == {}


def test_a_run_not_found_pairs_with_a_tour_still_searching(tmp_path):
    runs = tmp_path / "runs"
    runs.mkdir()
    _run(runs, "tour", 0, [0, 500, 990], [50, 20, 10], [0, 1, 1], found=False)
    _run(runs, "space-aware-infotaxis", 0, [0, 995], [60, 4], [1, 1], found=False)
    m = _script().matched_tour(runs, "analytic-plume")[("oven", "space-aware-infotaxis/olfaction")]
    assert (m["n"], m["tour_area"], m["tour_coverage"]) == (1, 10.0, 1.0)


def test_paired_lines_mark_exploratory_comparisons_and_flag_few_seeds():
    v = {"rmst_difference": {"value": -12.4, "ci95": [-30.0, 4.0]}, "p_value": 0.21, "p_holm": 0.42, "n": 20,
         "primary": False}
    line = _script().paired_line("infotaxis/semantics - infotaxis/olfaction", v)
    assert line.endswith("(n = 20) — exploratory") and "-12 s [-30, +4]" in line
    assert _script().paired_line("a - b", dict(v, primary=True)).endswith("(n = 20) — **primary**")
    few = _script().paired_line("a - b", dict(v, n=4))
    assert few.endswith("— exploratory — fewer than 20 paired seeds: the interval is unreliable")
