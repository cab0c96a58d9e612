"""benchmarks/benchmark_missed_hits.py re-runs stored benchmark runs with a missed-hit rate, pairs them with the
stored ones on the same episodes, and resumes."""

import numpy as np
import pytest

from ._scripts import load_script


def _script():
    return load_script("benchmark_missed_hits")


@pytest.mark.slow
def test_a_vanishing_rate_gives_back_the_stored_runs_and_a_second_call_resumes(tmp_path, capsys):
    from psgsl_pgm.cli._main import main

    out = tmp_path / "bench"
    assert main(["benchmark", "--houses", "2", "--seeds", "1", "--policies", "infotaxis", "--variants", "olfaction",
                 "--conditions", "right-ontology", "--budget", "60", "--area", "60", "--workers", "1", "--quiet",
                 "--no-figures", "--out", str(out)]) == 0
    stored = sorted((out / "runs").glob("*.npz"))
    assert len(stored) == 2
    script = _script()
    # δ = 1e-300 caps a miss at 690 nats: no reading of these runs comes near it, so every decision is the stored one
    script.main([str(out), "--delta", "1e-300", "--arms", "infotaxis/olfaction", "--workers", "1"])
    table = capsys.readouterr().out.splitlines()
    row = next(line for line in table if line.startswith("| infotaxis/olfaction |"))
    assert row.startswith("| infotaxis/olfaction | 2 | ") and "| 1.000 [1.000, 1.000] |" in row
    assert "+0.0 [+0.0, +0.0], p = 1.000" in row
    again = out / "missed-hits-1e-300"
    for p in stored:
        a, b = np.load(p), np.load(again / p.name)
        assert float(a["time_to_find"]) == float(b["time_to_find"]) and bool(a["found"]) == bool(b["found"])
        np.testing.assert_allclose(b["hpd_level"], a["hpd_level"], rtol=1e-12, atol=1e-15)
    stamps = {p.name: p.stat().st_mtime_ns for p in again.iterdir()}
    script.main([str(out), "--delta", "1e-300", "--arms", "infotaxis/olfaction", "--workers", "1"])
    assert {p.name: p.stat().st_mtime_ns for p in again.iterdir()} == stamps  # resumed: nothing re-run
