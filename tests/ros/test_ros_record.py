"""--record through the grids: every stored run gets ``runs/<run>.bag/`` and ``runs/<run>.mcap`` beside it; the
experiment's bag replays to the run's stored final posteriors; the closed loop's bag holds the path it drove."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from psgsl_pgm.experiment import ExperimentConfig, load_run, run_experiment
from psgsl_pgm.experiment._replay import replay
from psgsl_pgm.ros import read_bag


def test_experiment_record_writes_a_replayable_bag_beside_each_run(tmp_path):
    config = ExperimentConfig(stops=4, warm_up=5.0)
    run_experiment(("oven",), (3,), ("analytic-plume",), out=tmp_path, workers=1, config=config, progress=False, record=True)
    runs = tmp_path / "runs"
    assert sorted(p.name for p in runs.iterdir()) == ["oven__analytic-plume__seed3.bag", "oven__analytic-plume__seed3.mcap",
                                                      "oven__analytic-plume__seed3.npz"]
    stored = load_run(runs / "oven__analytic-plume__seed3.npz")
    res = replay(runs / "oven__analytic-plume__seed3.bag")  # world, source, seed, estimator and config from the bag
    assert res.run.estimator == "analytic-plume" and res.run.seed == 3
    np.testing.assert_allclose(res.final, stored.snapshots[stored.n_steps], rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(res.run.error, stored.error, rtol=1e-12)


@pytest.mark.slow
def test_closed_loop_record_holds_the_driven_path(tmp_path):
    from mcap.reader import make_reader

    from psgsl_pgm.search import SearchConfig
    from psgsl_pgm.search._grid import closed_loop_in_world

    run = closed_loop_in_world("oven", 0, "infotaxis", "semantics+rooms", "infotaxis",
                               config=ExperimentConfig(warm_up=5.0), search=SearchConfig(time_budget=40.0),
                               record=str(tmp_path / "run"))
    data = read_bag(tmp_path / "run.bag")
    assert len(data.gas) == run.n_steps
    np.testing.assert_array_equal(data.gas_xy, run.position[1:])  # every stop the policy chose, exactly
    assert data.meta["policy"] == "infotaxis" and data.meta["variant"] == "semantics+rooms"
    with open(tmp_path / "run.mcap", "rb") as fh:
        counts = make_reader(fh).get_summary().statistics.channel_message_counts
    with open(tmp_path / "run.mcap", "rb") as fh:
        topics = {c.id: c.topic for c in make_reader(fh).get_summary().channels.values()}
    counts = {topics[k]: v for k, v in counts.items()}
    assert counts["/posterior/semantics+rooms"] == run.n_steps + 1
    assert counts["/robot/next"] == run.n_steps  # the pose chosen after every step but the last


def test_closed_loop_record_of_the_olfaction_variant_has_no_class_grid(tmp_path):
    """The olfaction variant keeps no class beliefs: its episode records without a best-class grid (it once ended
    in StopIteration), and the bag still holds every reading."""
    from mcap.reader import make_reader

    from psgsl_pgm.search import SearchConfig
    from psgsl_pgm.search._grid import closed_loop_in_world

    run = closed_loop_in_world("oven", 0, "infotaxis", "olfaction", "infotaxis",
                               config=ExperimentConfig(warm_up=5.0), search=SearchConfig(time_budget=15.0),
                               record=str(tmp_path / "run"))
    data = read_bag(tmp_path / "run.bag")
    assert len(data.gas) == run.n_steps > 0
    with open(tmp_path / "run.mcap", "rb") as fh:
        topics = {c.topic for c in make_reader(fh).get_summary().channels.values()}
    assert "/posterior/olfaction" in topics and "/semantics/best_class" not in topics
