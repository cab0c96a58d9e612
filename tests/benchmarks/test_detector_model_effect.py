"""benchmarks/detector_model_effect.py pairs the two detector models' runs by seed and refuses an olfaction variant
that differs between them (it does not read the camera)."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from ._scripts import load_script


def _script():
    return load_script("detector_model_effect")


def _run(seed, final_semantics, *, olfaction=1.0, hit=True, area=2.0, level=0.5):
    error = np.full((5, 3), 3.0)
    error[-1] = olfaction, final_semantics, final_semantics + 1.0
    return SimpleNamespace(source="oven", estimator="infotaxis", seed=seed, error=error,
                           region_hit=np.full((5, 3), hit), region_area=np.full((5, 3), area),
                           hpd_level=np.full((5, 3), level))


def test_final_errors_are_paired_by_seed(monkeypatch):
    module = _script()
    est = {("oven", "infotaxis", s): _run(s, e) for s, e in zip(range(4), (1.0, 2.0, 0.5, 1.5))}
    sim = {("oven", "infotaxis", s): _run(s, e, hit=False, area=4.0, level=0.95)
           for s, e in zip(range(5), (0.5, 1.0, 0.5, 0.5, 9.0))}  # seed 4 has no partner: left out
    monkeypatch.setattr(module, "_runs", lambda folder: {"estimated": est, "simulator": sim}[folder])
    rows = module.compare({"estimated": "estimated", "simulator": "simulator"})
    assert [(r["variant"], r["n"]) for r in rows] == [("semantics", 4), ("semantics+rooms", 4)]
    diff = np.array([0.5, 1.0, 0.5, 0.5]) - np.array([1.0, 2.0, 0.5, 1.5])  # simulator − estimated, per seed
    ref = stats.ttest_rel(np.array([0.5, 1.0, 0.5, 0.5]), np.array([1.0, 2.0, 0.5, 1.5])).confidence_interval()
    mean_est, mean_sim, (d, ci) = rows[0]["final_error"]
    assert (mean_est, mean_sim) == pytest.approx((1.25, 0.625))
    assert d == pytest.approx(diff.mean()) and ci == pytest.approx((ref.low, ref.high), rel=1e-12)
    # the error over the search: 3 m at every step but the last, interpolated over 101 progress points
    assert rows[0]["mean_error"][0] == pytest.approx(np.mean([np.interp(np.linspace(0, 1, 101), np.arange(5) / 4,
                                                                        [3, 3, 3, 3, e]).mean()
                                                              for e in (1.0, 2.0, 0.5, 1.5)]))
    assert rows[0]["estimated"] == (1.0, 2.0, 0.5) and rows[0]["simulator"] == (0.0, 4.0, 0.95)


def test_an_olfaction_variant_that_reads_the_camera_is_refused(monkeypatch):
    module = _script()
    est = {("oven", "infotaxis", 0): _run(0, 1.0)}
    sim = {("oven", "infotaxis", 0): _run(0, 1.0, olfaction=1.5)}
    monkeypatch.setattr(module, "_runs", lambda folder: {"estimated": est, "simulator": sim}[folder])
    with pytest.raises(ValueError, match="olfaction differs"):
        module.compare({"estimated": "estimated", "simulator": "simulator"})
