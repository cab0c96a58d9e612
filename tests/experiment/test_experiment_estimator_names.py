"""Estimator names: pmfs is PMFS as published, analytic-plume the analytic PMFS-family estimator; runs stored when
"pmfs" named the analytic one are read under its current name, and a grid does not resume from them."""

import io

import numpy as np
import pytest

from psgsl_pgm.experiment import ESTIMATORS, ExperimentConfig
from psgsl_pgm.experiment._config import stored_estimator_name
from psgsl_pgm.experiment._run import RunResult
from psgsl_pgm.experiment._step import make_estimator
from psgsl_pgm.experiment._store import load_run, read_run_key, save_run
from psgsl_pgm.olfaction import FilamentPMFS, GrGSL, PlumeModel, PMFSEstimator


def test_each_name_makes_its_estimator():
    model = PlumeModel(np.zeros((8, 10), bool), resolution=0.2)
    cfg = ExperimentConfig()
    assert {"analytic-plume", "pmfs", "grgsl"} <= set(ESTIMATORS)
    assert type(make_estimator("analytic-plume", model, cfg)) is PMFSEstimator
    est = make_estimator("pmfs", model, cfg, seed=7)
    assert type(est) is FilamentPMFS and est.seed == 7 and est.diffusivity == model.diffusivity
    assert est.tempering == cfg.filament_pmfs_tempering
    assert "filament_pmfs_tempering" not in cfg.to_dict()  # a default that leaves stored run keys as they were
    assert ExperimentConfig(filament_pmfs_tempering=0.5).to_dict()["filament_pmfs_tempering"] == 0.5
    assert type(make_estimator("grgsl", model, cfg)) is GrGSL
    with pytest.raises(ValueError, match="analytic-plume"):
        make_estimator("pmfs-style", model, cfg)


def test_stored_names():
    assert stored_estimator_name("pmfs", None) == "analytic-plume"  # stored before the names were revised
    assert stored_estimator_name("pmfs", 2) == "pmfs"
    assert stored_estimator_name("infotaxis", None) == "infotaxis"


def _run(estimator):
    n = 3
    return RunResult("oven", 1, estimator, np.array([1.0, 2.0]), np.arange(n, dtype=float), np.zeros((n, 2)),
                     np.zeros(n, bool), np.zeros((n, 3)), np.zeros((n, 3)), {}, {"key": {"command": "experiment"}},
                     np.zeros((n, 3), bool), np.zeros((n, 3)), np.zeros((n, 3)))


def _strip_naming(path):
    """Rewrite a stored run as it was written before the ``estimator_naming`` field."""
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files if k != "estimator_naming"}
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    path.write_bytes(buf.getvalue())


def test_a_run_stored_under_the_old_name_is_read_as_analytic_plume_and_not_resumed(tmp_path):
    path = save_run(_run("pmfs"), tmp_path / "runs" / "oven__pmfs__seed1.npz")
    assert load_run(path).estimator == "pmfs"  # written now: PMFS as published
    assert read_run_key(path) == {"command": "experiment"}
    _strip_naming(path)
    assert load_run(path).estimator == "analytic-plume"
    with pytest.raises(ValueError, match="analytic-plume estimator stored when it was named 'pmfs'") as err:
        read_run_key(path)
    assert "\n" not in str(err.value)
    other = save_run(_run("infotaxis"), tmp_path / "runs" / "oven__infotaxis__seed1.npz")
    _strip_naming(other)
    assert load_run(other).estimator == "infotaxis" and read_run_key(other) == {"command": "experiment"}
