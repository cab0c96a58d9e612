"""Tempering chosen for coverage: the tempered posterior from a record, one posterior's threshold, the quantile."""

import numpy as np
import pytest

from psgsl_pgm.experiment._calibration import (CHECKPOINTS, coverage_tempering, coverage_threshold,
                                               coverage_thresholds, tempered_posterior)
from psgsl_pgm.experiment._metrics import credible_region
from psgsl_pgm.olfaction import CalibrationRun, GridInfotaxis, PlumeFit, PlumeModel, PMFSEstimator


def test_tempered_posterior_is_the_normalised_prior_times_the_weighted_tempered_likelihoods():
    rng = np.random.default_rng(3)
    ell = rng.normal(-20.0, 3.0, size=(3, 40))
    prior = rng.uniform(0.5, 2.0, 40)
    prior[[0, 7]] = 0.0
    w = np.array([0.2, 0.5, 0.3])
    with np.errstate(divide="ignore"):
        got = tempered_posterior(np.log(prior / prior.sum()), ell, 0.37, weights=w * 4.0)  # weights normalised
    brute = prior * (w[:, None] * np.exp(0.37 * ell)).sum(axis=0)
    np.testing.assert_allclose(got, brute / brute.sum(), rtol=1e-12, atol=0)
    one = tempered_posterior(np.zeros(40), ell[1], 2.5)  # one component, uniform prior
    np.testing.assert_allclose(one, np.exp(2.5 * ell[1]) / np.exp(2.5 * ell[1]).sum(), rtol=1e-12)


def test_tempered_posterior_refuses_mismatched_shapes_and_bad_weights():
    with pytest.raises(ValueError, match="log_likelihoods"):
        tempered_posterior(np.zeros(5), np.zeros((2, 4)), 1.0)
    with pytest.raises(ValueError, match="weights"):
        tempered_posterior(np.zeros(4), np.zeros((2, 4)), 1.0, weights=[1.0, -1.0])
    with pytest.raises(ValueError, match="tempering"):
        tempered_posterior(np.zeros(4), np.zeros(4), 0.0)


@pytest.mark.parametrize("rank", [3, 10, 25])
def test_coverage_threshold_is_where_the_region_stops_holding_the_cell(rank):
    """Uniform prior, one component: the region holds the cell just below β* and not just above; a scan of β
    finds the same flip (brute force)."""
    rng = np.random.default_rng(rank)
    ell = rng.normal(0.0, 2.0, 60)
    cell = int(np.argsort(-ell)[rank])  # the rank-th most likely cell
    lp = np.full(60, -np.log(60))
    beta = coverage_threshold(lp, ell, cell, level=0.9)
    assert 1e-4 < beta < 10.0

    def covered(b):
        return bool(credible_region(tempered_posterior(lp, ell, b), 0.9)[cell])

    assert covered(beta * (1 - 1e-6)) and not covered(beta * (1 + 1e-6))
    grid = np.geomspace(1e-3, 10.0, 4001)
    flags = np.array([covered(b) for b in grid])
    assert flags[0] and not flags[-1] and np.all(np.diff(flags.astype(int)) <= 0)  # one flip, monotone
    first_out = grid[np.argmin(flags)]
    assert grid[np.argmin(flags) - 1] <= beta <= first_out


def test_coverage_threshold_at_the_bounds():
    ell = np.linspace(0.0, -5.0, 30)
    lp = np.full(30, -np.log(30))
    assert coverage_threshold(lp, ell, 0) == 10.0  # the most likely cell is always held
    assert coverage_threshold(lp, ell, 29, bounds=(1e-3, 10.0)) == 1e-3  # the least likely: never (level 0.9 < 1)


def test_coverage_tempering_is_the_target_quantile_of_the_thresholds():
    th = np.arange(1.0, 11.0)  # 10 posteriors, thresholds 1..10
    res = coverage_tempering(th, np.arange(10), target=0.9)
    assert res.tempering == pytest.approx(np.sqrt(2.0), rel=1e-14)  # between the 9th and 10th largest
    assert res.coverage == 0.9
    res = coverage_tempering(th, np.arange(10), target=0.65)  # k = ceil(6.5) = 7: between 4 and 3
    assert res.tempering == pytest.approx(np.sqrt(12.0), rel=1e-14) and res.coverage == 0.7
    lo, hi = res.interval
    assert lo <= res.tempering <= hi


def test_coverage_tempering_bootstrap_resamples_runs_and_is_seeded():
    rng = np.random.default_rng(0)
    th = rng.lognormal(0.0, 1.0, 80)
    groups = np.repeat(np.arange(20), 4)
    a = coverage_tempering(th, groups, n_boot=300, seed=4)
    b = coverage_tempering(th, groups, n_boot=300, seed=4)
    assert a.interval == b.interval and a.interval[0] < a.tempering < a.interval[1]


def test_coverage_tempering_refuses_bad_input():
    with pytest.raises(ValueError, match="thresholds"):
        coverage_tempering([1.0, -2.0], [0, 1])
    with pytest.raises(ValueError, match="thresholds"):
        coverage_tempering([1.0, 2.0], [0])
    with pytest.raises(ValueError, match="target"):
        coverage_tempering([1.0, 2.0], [0, 1], target=1.0)


def _run(seed):
    occ = np.zeros((16, 20), bool)
    occ[8, 3:15] = True
    wind = np.zeros((16, 20, 2))
    wind[..., 0] = 0.05
    source = (0.75, 0.45)
    truth = PlumeModel(occ, resolution=0.1, wind=wind, diffusivity=0.02, lifetime=60.0, encounter_scale=1.5)
    rng = np.random.default_rng(seed)
    free = np.argwhere(~occ)
    cells = free[rng.integers(0, len(free), 40)]
    hits = truth.sample_hits((cells[:, ::-1] + 0.5) * 0.1, source, rng=seed)
    return CalibrationRun(PlumeModel(occ, resolution=0.1, wind=wind), source, (cells[:, ::-1] + 0.5) * 0.1, hits)


@pytest.mark.parametrize("estimator", ["infotaxis", "analytic-plume"])
def test_coverage_thresholds_agree_with_the_estimators_own_tempered_update(estimator):
    """At β*(1 ∓ 1e-6) the estimator run *tempered* on the same readings holds / does not hold the source cell in
    its 90 % region (an independent path: the estimator's own update, not the recorded sum)."""
    run = _run(5)
    fit = PlumeFit(0.005, 40.0, 3.0, 0.0)  # a narrower plume than the truth: over-confident at β = 1
    th = coverage_thresholds([run], fit, estimator, false_hit_rate=0.01)
    assert th.shape == (1, len(CHECKPOINTS))
    model = PlumeModel(run.model.geometry.occupancy, resolution=0.1, wind=run.model.wind, diffusivity=0.005,
                       lifetime=40.0, encounter_scale=3.0)
    cell = model.cell_of(run.source)
    n = len(run.hits)
    checked = 0
    for i, f in enumerate(CHECKPOINTS):
        b = th[0, i]
        if not 1e-4 < b < 10.0:
            continue
        for factor, expect in ((1 - 1e-6, True), (1 + 1e-6, False)):
            est = (GridInfotaxis.from_model(model, tempering=min(b * factor, 1.0), false_hit_rate=0.01)
                   if estimator == "infotaxis" else PMFSEstimator.from_model(model, tempering=b * factor))
            if estimator == "infotaxis" and b * factor > 1.0:
                continue  # GridInfotaxis refuses β > 1
            for j in range(int(round(f * n))):
                est.update(run.positions[j], bool(run.hits[j]))
            assert bool(credible_region(est.posterior, 0.9)[cell]) is expect
            checked += 1
    assert checked >= 6
