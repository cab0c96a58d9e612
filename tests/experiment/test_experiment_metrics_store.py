"""Metrics, confidence intervals, run files and summaries of the validation experiment."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats

from psgsl_pgm.experiment import RunResult, VARIANTS, error_and_spread, load_run, mean_ci, save_run, summarize
from psgsl_pgm.experiment._summary import aligned, write_csv, write_summary


def test_error_and_spread_equal_explicit_sums():
    rng = np.random.default_rng(3)
    h, w = 7, 9
    p = rng.dirichlet(np.ones(h * w), size=4).reshape(4, h, w)
    centres = np.stack(np.meshgrid(0.1 * np.arange(w) + 0.05, 0.1 * np.arange(h) + 0.05, indexing="xy"), axis=-1)
    truth = np.array([0.3, 0.2])
    err, spread = error_and_spread(p, centres, truth)
    for k in range(4):
        mx = sum(p[k, r, c] * centres[r, c] for r in range(h) for c in range(w))
        var = sum(p[k, r, c] * np.sum((centres[r, c] - mx) ** 2) for r in range(h) for c in range(w))
        assert err[k] == pytest.approx(np.linalg.norm(mx - truth), rel=1e-12)
        assert spread[k] == pytest.approx(np.sqrt(var), rel=1e-10)


def test_error_and_spread_are_the_same_bits_with_any_blas_thread_count():
    """A grid's workers run the BLAS on one thread, a run in the main process on several: the metrics of a
    posterior may not depend on it (a threaded GEMV moved the spread of a 200 000-cell posterior by 4e-15 m), nor
    on whether it is computed alone or in a batch."""
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(5)
    h, w = 400, 500
    p = rng.dirichlet(np.ones(h * w), size=3).reshape(3, h, w)
    centres = rng.uniform(0.0, 30.0, (h, w, 2))
    batch, single = [], []
    for threads in (1, 2, 4):
        with threadpool_limits(limits=threads, user_api="blas"):
            batch.append(error_and_spread(p, centres, (3.0, 4.0)))
            single.append(error_and_spread(p[1], centres, (3.0, 4.0)))
    for got in batch[1:]:
        assert all(np.array_equal(a, b) for a, b in zip(batch[0], got))
    for got in single[1:]:
        assert all(np.array_equal(a, b) for a, b in zip(single[0], got))
    assert (single[0][0], single[0][1]) == (batch[0][0][1], batch[0][1][1])


def test_mean_ci_is_the_student_t_interval():
    x = np.random.default_rng(0).normal(2.0, 1.5, size=12)
    lo, hi = stats.t.interval(0.95, len(x) - 1, loc=x.mean(), scale=stats.sem(x))
    r = mean_ci(x)
    assert r["mean"] == pytest.approx(x.mean(), rel=1e-14)
    np.testing.assert_allclose(r["ci95"], [lo, hi], rtol=1e-12)
    one = mean_ci([1.0])
    assert one["mean"] == 1.0 and all(np.isnan(one["ci95"]))


def test_metrics_of_huge_coordinates_are_the_scaled_metrics_or_refused():
    """Squares of numbers near 1e154 overflow float64; the results do not, so they are computed (no warning)."""
    rng = np.random.default_rng(4)
    p = rng.dirichlet(np.ones(12), size=2).reshape(2, 3, 4)
    centres = np.stack(np.meshgrid(np.arange(4) + 0.5, np.arange(3) + 0.5, indexing="xy"), axis=-1)
    err, spread = error_and_spread(p, centres, (1.0, 2.0))
    for scale in (1e154, 1e300):
        big_err, big_spread = error_and_spread(p, centres * scale, (scale, 2.0 * scale))
        np.testing.assert_allclose(big_err, err * scale, rtol=1e-12)
        np.testing.assert_allclose(big_spread, spread * scale, rtol=1e-9)
    with pytest.raises(ValueError, match="centres and truth: the error or the spread exceeds the float64 range"):
        error_and_spread(p, centres * 5e307, (-1.7e308, 0.0))

    x = np.array([[1.0, 0.0], [3.0, 2e154], [2.0, 2e154]])
    r, small = mean_ci(x), mean_ci(x[:, 0])
    assert r["mean"][0] == small["mean"] and [b[0] for b in r["ci95"]] == small["ci95"]  # columns stay apart
    np.testing.assert_allclose([r["mean"][1]] + [b[1] for b in r["ci95"]],
                               np.array([mean_ci([0.0, 2.0, 2.0])["mean"]] + mean_ci([0.0, 2.0, 2.0])["ci95"]) * 1e154,
                               rtol=1e-12)
    with pytest.raises(ValueError, match="values: the mean or its confidence interval exceeds the float64 range"):
        mean_ci([-1.7e308, 1.7e308, 1.7e308])


def _fake_run(seed, n, rng):
    t = np.linspace(0, 600, n + 1)
    err = rng.uniform(0, 5, size=(n + 1, 3))
    return RunResult("oven", seed, "infotaxis", np.array([7.5, 0.5]), t, rng.uniform(0, 9, (n + 1, 2)),
                     rng.random(n + 1) < 0.2, err, rng.uniform(0, 2, size=(n + 1, 3)),
                     {0: rng.dirichlet(np.ones(12), size=3).reshape(3, 3, 4)}, {"gas": "smoke", "speed": 0.25},
                     rng.random((n + 1, 3)) < 0.6, rng.uniform(1, 30, (n + 1, 3)), rng.uniform(0, 1, (n + 1, 3)))


def test_run_files_round_trip_and_bad_files_are_named(tmp_path):
    run = _fake_run(4, 20, np.random.default_rng(1))
    path = save_run(run, tmp_path / "runs" / "a.npz")
    back = load_run(path)
    for name in ("source_xy", "time", "position", "hit", "error", "spread", "region_hit", "region_area", "hpd_level"):
        np.testing.assert_array_equal(getattr(back, name), getattr(run, name))
    assert (back.source, back.seed, back.estimator) == ("oven", 4, "infotaxis")
    assert back.config == {"gas": "smoke", "speed": 0.25}
    np.testing.assert_array_equal(back.snapshots[0], run.snapshots[0])
    assert not list((tmp_path / "runs").glob("*.part"))
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(ValueError, match="bad.npz is not a run file"):
        load_run(bad)


def test_summary_aligns_runs_of_different_length_by_search_progress(tmp_path):
    rng = np.random.default_rng(2)
    runs = [_fake_run(s, n, rng) for s, n in zip(range(5), (8, 12, 16, 9, 20))]
    s = summarize(runs)
    assert s["n_runs"] == 5 and s["seeds"] == [0, 1, 2, 3, 4] and s["early_progress"] == 0.25
    for v, name in enumerate(VARIANTS):
        early = [np.interp(0.25, np.arange(r.n_steps + 1) / r.n_steps, r.error[:, v]) for r in runs]
        final = [r.error[-1, v] for r in runs]
        assert s[name]["early_error"] == mean_ci(early, lower=0.0)  # distances: intervals cut at 0
        assert s[name]["final_error"] == mean_ci(final, lower=0.0)
        grid = np.linspace(0, 1, 101)
        area = [np.mean(np.interp(grid, np.arange(r.n_steps + 1) / r.n_steps, r.error[:, v])) for r in runs]
        np.testing.assert_allclose(s[name]["mean_error"]["mean"], np.mean(area), rtol=1e-12)
        # calibration: the hit at the step in effect at ¼, ½, ¾ of the run's time and at the last step
        for key, f in (("quarter", 0.25), ("half", 0.5), ("three_quarters", 0.75), ("final", 1.0)):
            steps = [int(np.flatnonzero(r.time <= f * r.time[-1] * (1 + 1e-12))[-1]) for r in runs]
            assert s[name]["coverage90"][key] == np.mean([r.region_hit[j, v] for r, j in zip(runs, steps)])
        assert s[name]["region_area90"] == mean_ci([r.region_area[-1, v] for r in runs], lower=0.0)
        levels = [r.hpd_level[-1, v] for r in runs]
        assert s[name]["hpd_level"] == {"median": np.median(levels), "mean": np.mean(levels)}
    d = s["paired"]["olfaction - semantics"]["final_error"]
    assert d == mean_ci([r.error[-1, 0] - r.error[-1, 1] for r in runs])
    # a run with n = 8 has step 2 exactly at a quarter
    np.testing.assert_allclose(aligned(runs[:1], "error", [0.25])[0, 0], runs[0].error[2], rtol=0, atol=0)
    data = json.loads(write_summary(s, tmp_path / "s.json").read_text())
    assert set(data["semantics+rooms"]["final_error"]) == {"mean", "ci95"}
    assert set(data["olfaction"]["coverage90"]) == {"quarter", "half", "three_quarters", "final"}
    lines = write_csv(runs, tmp_path / "m.csv").read_text().splitlines()
    assert len(lines) == 1 + 3 * sum(r.n_steps + 1 for r in runs)
    assert lines[0].startswith("source,estimator,seed,step,progress,time_s")


def test_summarize_needs_runs():
    with pytest.raises(ValueError, match="at least one run"):
        summarize([])


def test_coverage_is_read_at_the_end_of_the_run_not_at_its_start():
    """A region that holds the source only at the first step: final coverage 0 (and 1 where only the last holds)."""
    from psgsl_pgm.experiment._metrics import calibration_summary

    rng = np.random.default_rng(5)
    runs = [_fake_run(s, 8, rng) for s in range(4)]
    for r in runs:
        r.region_hit[:] = False
        r.region_hit[0] = True
    c = calibration_summary(runs, variant=1)["coverage90"]
    assert c == {"quarter": 0.0, "half": 0.0, "three_quarters": 0.0, "final": 0.0}
    for r in runs:
        r.region_hit[:] = False
        r.region_hit[-1] = True
    assert calibration_summary(runs, variant=1)["coverage90"]["final"] == 1.0


def test_at_fractions_takes_the_step_in_effect():
    from psgsl_pgm.experiment._metrics import at_fractions

    t = np.array([0.0, 10.0, 30.0, 31.0, 40.0])
    np.testing.assert_array_equal(at_fractions(t, np.arange(5), [0.0, 0.24, 0.25, 0.5, 0.77, 0.775, 1.0]),
                                  [0, 0, 1, 1, 2, 3, 4])


def test_hpd_level_by_hand_with_ties_and_against_brute_force():
    from psgsl_pgm.experiment._metrics import credible_region, hpd_level

    p = np.array([0.4, 0.2, 0.2, 0.2])
    assert hpd_level(p, 0) == pytest.approx(0.4, rel=1e-15)
    assert hpd_level(p, 2) == 1.0  # tied cells count in full: a region holds the cell only with its equals
    assert hpd_level(np.full((3, 4), 1 / 12), 5) == pytest.approx(1.0, rel=1e-15)
    rng = np.random.default_rng(9)
    for _ in range(30):
        q = rng.dirichlet(np.full(20, 0.4)).reshape(4, 5)
        cell = int(rng.integers(20))
        flat = q.ravel()
        brute = sum(flat[k] for k in range(20) if flat[k] >= flat[cell])
        level = hpd_level(q, cell)
        assert level == pytest.approx(brute, rel=1e-12)
        for mass in (0.3, 0.5, 0.8, 0.9, 0.95):
            # no ties: the fewest cells reaching α hold the cell exactly when the more probable ones stay below α
            hit = credible_region(q, mass).ravel()[cell]
            assert hit == (level - flat[cell] < mass)
            assert hit or level > mass
    # rounding is not a ranking: a cell a few ulps below its equals keeps their level
    r = np.array([0.3, 0.3, 0.2, 0.2])
    r[1] = np.nextafter(np.nextafter(0.3, 0), 0)
    assert hpd_level(r, 1) == pytest.approx(0.6, rel=1e-15) and hpd_level(r, 0) == pytest.approx(0.6, rel=1e-15)
    r32 = np.array([0.3, 0.3, 0.2, 0.2], np.float32)
    r32[0] = np.nextafter(np.float32(0.3), np.float32(1))
    assert hpd_level(r32, 1) == pytest.approx(0.6, rel=1e-6)
    assert hpd_level(np.array([0.3, 0.3 * (1 - 1e-9), 0.4 + 0.3e-9]), 1) == pytest.approx(1.0)  # a real difference
    assert hpd_level(np.array([0.3, 0.3 * (1 - 1e-9), 0.4 + 0.3e-9]), 0) == pytest.approx(0.7)
    with pytest.raises(ValueError, match="cell must be a flat index"):
        hpd_level(p, 4)
