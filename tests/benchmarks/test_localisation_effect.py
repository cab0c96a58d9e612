"""benchmarks/localisation_effect.py pairs the searches by seed and names the searches whose source the robot
ruled out from where it believed it was."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from ._scripts import load_script


def test_summary_pairs_by_seed():
    module = load_script("localisation_effect")
    rows = [{"seed": 0, "ideal": (True, 50.0), "error": (True, 60.0), "believed_within_reach": True},
            {"seed": 1, "ideal": (True, 40.0), "error": (False, 1000.0), "believed_within_reach": True},
            {"seed": 2, "ideal": (False, 1000.0), "error": (False, 1000.0), "believed_within_reach": False},
            {"seed": 3, "ideal": (True, 70.0), "error": (True, 65.0), "believed_within_reach": True}]
    s = module.summary(rows)
    assert s["n"] == 4 and s["success"] == (0.75, 0.5)
    assert s["rmst"] == pytest.approx((290.0, 531.25))
    ref = stats.ttest_rel([60.0, 1000.0, 1000.0, 65.0], [50.0, 40.0, 1000.0, 70.0]).confidence_interval()
    d, ci = s["rmst_difference"]
    assert d == pytest.approx(241.25) and ci == pytest.approx((ref.low, ref.high), rel=1e-12)
    assert s["unfound"] == [1, 2] and s["ruled_out"] == [1]
    assert np.isnan(module.paired([1.0], [2.0])[1][0])


def test_one_seed_runs_both_worlds():
    module = load_script("localisation_effect")
    args = SimpleNamespace(source="oven", policy="tour", variant="olfaction", estimator="infotaxis", budget=20.0,
                           miss_probability=0.0, sigma=0.1, heading_deg=3.0, tau=30.0)
    r = module.search_pair(0, args)
    assert set(r) == {"seed", "ideal", "error", "believed_within_reach"}
    assert r["ideal"] == (False, 20.0) and r["error"] == (False, 20.0)  # 20 s: the tour's first stops only
    assert r["believed_within_reach"] is False
