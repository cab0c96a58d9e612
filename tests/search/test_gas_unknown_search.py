"""A closed-loop search whose gas the robot is not told: its gas belief per stop, the stored run, the summary."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from psgsl_pgm.experiment import ExperimentConfig
from psgsl_pgm.search import SearchConfig, run_closed_loop
from psgsl_pgm.search._grid import gas_summary, summarize_runs
from psgsl_pgm.search._store import load_search_run, save_search_run


@pytest.fixture(scope="module")
def unknown_run():
    return run_closed_loop("oven", 3, "infotaxis", "semantics+rooms", config=ExperimentConfig(gas="unknown"),
                           search=SearchConfig(time_budget=100.0), gas_type="natural gas")


def test_the_robot_infers_the_gas_while_it_searches(unknown_run):
    run = unknown_run
    assert run.gas == "natural gas" and run.gas_unknown
    assert run.gas_names == ("smoke", "ethanol", "ammonia", "natural gas")
    assert run.gas_probs.shape == (len(run.time), 4)
    np.testing.assert_allclose(run.gas_probs[0], 0.25)                 # before the first reading: the prior
    np.testing.assert_allclose(run.gas_probs.sum(axis=1), 1.0, rtol=1e-12)
    assert run.gas_probs[-1, 3] > 0.9 and run.gas_identified            # beside the oven the e-nose names it
    t, reached = run.time_to_gas()
    assert reached and 0 < t <= 100.0 and t in run.time


def test_the_stored_run_keeps_the_gas_belief(unknown_run, tmp_path):
    back = load_search_run(save_search_run(unknown_run, tmp_path / "r.npz"))
    assert back.gas == unknown_run.gas and back.gas_names == unknown_run.gas_names
    np.testing.assert_array_equal(back.gas_probs, unknown_run.gas_probs)


def test_summary_gains_gas_identified_and_time_to_gas(unknown_run):
    lost = replace(unknown_run, seed=4, gas="smoke")  # the same beliefs, another truth: not identified, censored
    s = summarize_runs([unknown_run, lost])
    assert s["gas_identified"]["value"] == 0.5 and len(s["gas_identified"]["ci95"]) == 2
    tg = s["time_to_gas"]
    assert tg["reached"] == 1 and tg["tau"] == 100.0
    t, _ = unknown_run.time_to_gas()
    assert tg["value"] == pytest.approx((t + 100.0) / 2)               # RMST of one event and one censored run


def test_a_tie_is_no_identification(unknown_run):
    """A run that ended before any classified reading keeps the uniform prior: no gas is identified, even the
    first, and its time to the gas is censored at the budget."""
    early = replace(unknown_run, gas="smoke", time=unknown_run.time[:1], gas_probs=unknown_run.gas_probs[:1])
    assert not early.gas_identified and early.time_to_gas() == (100.0, False)


def test_a_told_run_has_no_gas_fields(tmp_path):
    run = run_closed_loop("oven", 3, "greedy", "olfaction", search=SearchConfig(time_budget=5.0))
    assert not run.gas_unknown and run.gas == "" and run.gas_probs.shape == (0, 0)
    assert gas_summary([run], 5.0) == {} and "gas_identified" not in summarize_runs([run])
    with pytest.raises(ValueError, match="gas: unknown"):
        run.time_to_gas()
    import zipfile

    path = save_search_run(run, tmp_path / "told.npz")
    assert not {"gas.npy", "gas_probs.npy"} & set(zipfile.ZipFile(path).namelist())  # written as before
    assert load_search_run(path).gas_names == ()
