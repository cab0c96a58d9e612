"""A closed-loop run stored when "pmfs" named the analytic-plume estimator reads under its current name, and a
grid does not resume from it."""

import io
from dataclasses import replace

import numpy as np
import pytest

from psgsl_pgm.search import SearchConfig, run_closed_loop
from psgsl_pgm.search._store import load_search_run, read_run_key, save_search_run


def test_a_search_run_stored_under_the_old_pmfs_name_reads_as_analytic_plume(tmp_path):
    run = run_closed_loop("oven", 0, "greedy", "olfaction", "analytic-plume", search=SearchConfig(time_budget=5.0))
    run = replace(run, estimator="pmfs")  # as stored before the names were revised
    path = save_search_run(run, tmp_path / "runs" / "oven__greedy__olfaction__pmfs__seed0.npz")
    assert load_search_run(path).estimator == "pmfs"  # written now, with the names' version: PMFS as published
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files if k != "estimator_naming"}
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    path.write_bytes(buf.getvalue())
    assert load_search_run(path).estimator == "analytic-plume"
    with pytest.raises(ValueError, match="analytic-plume estimator stored when it was named 'pmfs'"):
        read_run_key(path)
