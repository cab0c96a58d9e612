"""benchmarks/world_model_costs.py: the table of each world model's arms, the primary comparison's shift from the
ideal world, and the component that moved it most."""

from ._scripts import load_script


def _arm(rmst, found=20, n=20, cov=0.9, area=10.0):
    return {"rmst": {"value": rmst, "ci95": [rmst - 10, rmst + 10]}, "n_runs": n,
            "time_to_find": {"not_found": n - found}, "coverage90": {"final": cov}, "region_area90": {"mean": area}}


def _result(olf, sem, diff, p=0.01):
    return {"summary": {"infotaxis/olfaction": _arm(olf), "infotaxis/semantics+rooms": _arm(sem, found=17)},
            "paired": {"rmst_difference": {"value": diff, "ci95": [diff - 20, diff + 20]}, "p_value": p}}


def test_report_shifts_from_the_ideal_world_and_names_the_largest():
    module = load_script("world_model_costs")
    results = {"ideal": _result(175, 60, -115), "ideal+mox": _result(150, 70, -80),
               "ideal+pose": _result(300, 250, -50), "realistic": _result(320, 300, -20)}
    text = module.report(None, results, {}, first_seed=100, seeds=20, version="abc")
    assert "seeds 100–119 (development split), code abc" in text
    assert "| ideal+mox | infotaxis/semantics+rooms | 17/20 | 70 [60, 80] | 0.90 | 10.0 |" in text
    assert "| ideal+mox | -80 [-100, -60] | 0.01 | +35 |" in text
    assert "| realistic | -20 [-40, 0] | 0.01 | +95 |" in text
    # realistic is not a single component: the largest shift among the components alone is the pose's
    assert "moves the primary comparison most from the ideal world's: ideal+pose (+65 s)" in text


def test_report_without_the_ideal_run_has_no_shift():
    module = load_script("world_model_costs")
    text = module.report(None, {"ideal+mox": _result(150, 70, -80)}, {}, first_seed=0, seeds=2, version="x")
    assert "| ideal+mox | -80 [-100, -60] | 0.01 | n/a |" in text and "moves the primary" not in text
