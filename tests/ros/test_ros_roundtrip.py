"""The exact round trip: a simulated episode recorded as a ROS 2 bag and replayed gives the episode's posteriors.

Both storage formats (MCAP, sqlite3); the Foxglove MCAP of the same episode holds every step's posteriors.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from psgsl_pgm.experiment import VARIANTS, ExperimentConfig, run_search
from psgsl_pgm.experiment._record import EpisodeRecorder
from psgsl_pgm.experiment._replay import replay
from psgsl_pgm.ros import read_bag, write_bag, write_foxglove

#: A short episode (10 stops, the first a four-heading look-around) with a short warm-up: a few seconds.
CONFIG = ExperimentConfig(stops=10, warm_up=5.0)
SEED = 2


@pytest.fixture(scope="module")
def episode():
    rec = EpisodeRecorder(keep="float64")
    run = run_search("oven", SEED, "infotaxis", config=CONFIG, recorder=rec)
    meta = {"world": None, "source": "oven", "seed": SEED, "estimator": "infotaxis", "config": run.config}
    return run, rec, rec.episode(variants=VARIANTS, meta=meta)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_recorded_episode_replays_to_the_same_posteriors(episode, storage, tmp_path):
    run, rec, ep = episode
    bag = write_bag(tmp_path / "episode.bag", ep, storage=storage)
    assert any(p.suffix == (".mcap" if storage == "mcap" else ".db3") for p in bag.iterdir())
    res = replay(bag, keep_posteriors=True)
    assert len(res.posteriors) == len(rec.posteriors) == CONFIG.stops + 1
    assert res.n_frames == len(ep.frame_t) > CONFIG.stops  # the look-around's four frames and one per other stop
    for k, (got, want) in enumerate(zip(res.posteriors, rec.posteriors)):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-300, err_msg=f"step {k}")
    # the camera mattered: the semantic variants moved away from p(s | g)
    assert np.abs(res.final[1] - res.final[0]).max() > 1e-3
    np.testing.assert_allclose(res.run.error, run.error, rtol=1e-12)
    np.testing.assert_allclose(res.run.spread, run.spread, rtol=1e-12)
    np.testing.assert_array_equal(res.run.hit, run.hit)
    np.testing.assert_array_equal(res.run.position, run.position)
    # a replayed step's time is its gas reading's stamp (from the first reading), to the nanosecond
    np.testing.assert_allclose(res.run.time[1:], ep.gas_t - ep.gas_t[0], rtol=0, atol=2e-9)


def test_anemometer_message_gives_the_wind_in_the_map_frame(episode, tmp_path):
    """The lab's Anemometer (float32 speed, direction the wind comes from, in base_link) read back and rotated into
    the map: the simulated anemometer's vector to float32 precision."""
    _, _, ep = episode
    bag = write_bag(tmp_path / "episode.bag", ep)
    data = read_bag(bag, topics={"wind": "/anemometer"})
    assert data.topics["wind"] == "/anemometer"
    np.testing.assert_allclose(data.wind, ep.wind, rtol=0, atol=1e-6 * np.abs(ep.wind).max())
    assert np.abs(ep.wind).max() > 0.05  # a real wind, not zeros that any rotation maps to zeros
    full = read_bag(bag)  # by default the float64 Vector3Stamped
    assert full.topics["wind"] == "/wind"
    np.testing.assert_array_equal(full.wind, ep.wind)


def test_foxglove_mcap_holds_every_step(episode, tmp_path):
    from mcap.reader import make_reader

    _, rec, ep = episode
    path = write_foxglove(tmp_path / "episode.mcap", ep)
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        schemas = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
        counts = {summary.channels[k].topic: v for k, v in summary.statistics.channel_message_counts.items()}
        posts = [m.data for _, c, m in reader.iter_messages(topics=["/posterior/semantics"])]
    assert schemas["/map"] == schemas["/posterior/olfaction"] == "foxglove.Grid"
    assert schemas["/objects"] == schemas["/wind"] == "foxglove.SceneUpdate"
    assert schemas["/robot/pose"] == "foxglove.PoseInFrame" and schemas["/robot/path"] == "foxglove.PosesInFrame"
    assert schemas["/tf"] == "foxglove.FrameTransform"
    for v in VARIANTS:
        assert counts[f"/posterior/{v}"] == CONFIG.stops + 1
    assert counts["/gas"] == len(ep.gas) == CONFIG.stops
    # each Grid carries the step's posterior as raw float32 cells, row by row
    for k in (0, CONFIG.stops):
        assert np.asarray(rec.posteriors[k][1], dtype=np.float32).tobytes() in posts[k]
