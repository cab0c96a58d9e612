"""Confidence intervals of non-negative metrics (errors, spreads) respect the bound 0."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from psgsl_pgm.experiment._metrics import mean_ci


def test_lower_bound_cuts_only_the_lower_end():
    x = np.array([0.3, 2.9, 0.4])
    lo, hi = stats.t.interval(0.95, 2, loc=x.mean(), scale=stats.sem(x))
    assert lo < 0  # the plain Student-t interval of a mean distance goes negative here
    r = mean_ci(x, lower=0.0)
    assert r["ci95"][0] == 0.0 and r["ci95"][1] == pytest.approx(hi, rel=1e-12)
    assert r["mean"] == pytest.approx(x.mean(), rel=1e-14)


def test_lower_bound_leaves_intervals_above_it_and_arrays_alone():
    x = np.random.default_rng(1).normal(5.0, 0.5, size=(10, 3))
    plain, cut = mean_ci(x), mean_ci(x, lower=0.0)
    np.testing.assert_array_equal(plain["ci95"], cut["ci95"])
    wide = np.array([[0.1, 4.0], [3.0, 4.1], [0.2, 3.9]])
    r = mean_ci(wide, lower=0.0)
    assert r["ci95"][0][0] == 0.0 and r["ci95"][0][1] > 0
    assert np.isnan(mean_ci([1.0], lower=0.0)["ci95"]).all()  # one run: still no interval
