"""Bad bags: one ValueError naming the bag, the topic and the time; nothing is guessed or extrapolated."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from psgsl_pgm.ros import bag_topics, read_bag

from .bags import episode_bag, rewrite


def _storage_file(bag, suffix):
    (f,) = [p for p in bag.iterdir() if p.suffix == suffix]
    return f


@pytest.mark.parametrize("storage, suffix", [("mcap", ".mcap"), ("sqlite3", ".db3")])
def test_truncated_bag(tmp_path, storage, suffix):
    bag = episode_bag(tmp_path / "bag", storage)
    f = _storage_file(bag, suffix)
    data = f.read_bytes()
    f.write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match=re.escape(str(bag))):
        read_bag(bag)


def test_corrupt_sqlite3_bag(tmp_path):
    bag = episode_bag(tmp_path / "bag", "sqlite3")
    f = _storage_file(bag, ".db3")
    data = bytearray(f.read_bytes())
    data[:100] = b"\xff" * 100  # the sqlite header
    f.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"bag: not a readable ROS 2 bag"):
        read_bag(bag)


def test_not_a_bag(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="empty: not a readable ROS 2 bag"):
        read_bag(tmp_path / "empty")
    with pytest.raises(FileNotFoundError):
        read_bag(tmp_path / "nothing-here")


def test_missing_topic_and_wrong_type(tmp_path):
    bag = episode_bag(tmp_path / "bag")
    with pytest.raises(ValueError, match=r"topic /PID/gas \(given for gas\) is not in the bag; its topics: "):
        read_bag(bag, topics={"gas": "/PID/gas"})
    with pytest.raises(ValueError, match=r"topic /wind has type geometry_msgs/msg/Vector3Stamped, but gas needs"):
        read_bag(bag, topics={"gas": "/wind"})
    with pytest.raises(ValueError, match=r"unknown role\(s\) \['smell'\]"):
        read_bag(bag, topics={"smell": "/gas"})
    # no gas topic at all: named with what the bag has
    nogas = rewrite(bag, tmp_path / "nogas", keep=lambda topic, t, m: topic != "/gas")
    with pytest.raises(ValueError, match=r"nogas: no gas topic \(a topic of type olfaction_msgs/msg/GasSensor or"):
        read_bag(nogas)
    assert ("/tf", "tf2_msgs/msg/TFMessage", 10, "pose") in bag_topics(nogas)  # listing still works


def test_unknown_message_type(tmp_path):
    """A gas topic of a type neither rosbags, nor this package, nor the bag defines."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg("float64 ppm\n", "acme_msgs/msg/Smell"))
    with Writer(tmp_path / "acme", version=8) as w:  # version 8: no message definitions stored
        c = w.add_connection("/smell", "acme_msgs/msg/Smell", typestore=store)
        w.write(c, 1, store.serialize_cdr(store.types["acme_msgs/msg/Smell"](ppm=1.0), "acme_msgs/msg/Smell"))
    with pytest.raises(ValueError, match=r"acme: no pose topic .*'/smell \[acme_msgs/msg/Smell\]'"):
        read_bag(tmp_path / "acme")


def test_readings_outside_the_streams_overlap_are_skipped_and_counted(tmp_path):
    bag = episode_bag(tmp_path / "bag")
    start = 1_700_000_000 * 10**9
    cut = rewrite(bag, tmp_path / "cut", keep=lambda topic, t, m: topic != "/tf" or t < start + 6 * 10**9)
    data = read_bag(cut)  # /tf stops at 5 s: the gas and wind readings at 6-9 s have no pose
    np.testing.assert_array_equal(data.gas_t - start, np.arange(6) * 10**9)
    assert data.skipped == {"gas": 4, "wind": 4, "detections": 2}  # the frames at 6 and 9 s too
    # the case: the wind starts 10 ms before the first /tf, the last gas reading comes after the last wind
    def shift(topic, t, msg):
        if topic == "/wind" and t == start:
            stamp = dataclasses.replace(msg.header.stamp, sec=msg.header.stamp.sec - 1, nanosec=990_000_000)
            return dataclasses.replace(msg, header=dataclasses.replace(msg.header, stamp=stamp))
        return msg

    early = rewrite(bag, tmp_path / "early", change=shift, keep=lambda topic, t, m: topic != "/wind" or t < start + 9 * 10**9)
    data = read_bag(early)
    assert data.skipped == {"gas": 2, "wind": 1, "detections": 0}  # gas at 0 s (no wind before it) and at 9 s
    np.testing.assert_array_equal(data.gas_t - start, np.arange(1, 9) * 10**9)
    def apart(topic, t, m):  # the pose for 0-1 s, the wind from 3 s on: nothing overlaps
        return not (topic == "/tf" and t > start + 10**9 or topic == "/wind" and t < start + 3 * 10**9)

    nothing = rewrite(bag, tmp_path / "nothing", keep=apart)
    with pytest.raises(ValueError, match=r"nothing: topic /gas: no gas reading lies where the streams overlap \(gas "):
        read_bag(nothing)


def test_pose_gap_inside_the_overlap(tmp_path):
    bag = episode_bag(tmp_path / "bag")
    start = 1_700_000_000 * 10**9
    # a gap: samples 2 s apart around a reading are beyond a 0.5 s tolerance, within a 1.5 s one
    gap = rewrite(bag, tmp_path / "gap", keep=lambda topic, t, m: topic != "/tf" or t != start + 3 * 10**9)
    with pytest.raises(ValueError, match=r"gap: topic /tf .* t = 3.000 s into the bag .*1.000 s before and 1.000 s"):
        read_bag(gap)
    data = read_bag(gap, tolerance=1.5)
    np.testing.assert_allclose(data.gas_xy[3], (1.05 + 0.75, 6.05), rtol=0, atol=1e-12)  # linear in between


def test_times_going_backwards(tmp_path):
    bag = episode_bag(tmp_path / "bag")
    start = 1_700_000_000 * 10**9

    def swap(topic, t, msg):
        if topic == "/gas" and t == start + 5 * 10**9:  # stamped before the reading before it
            stamp = dataclasses.replace(msg.header.stamp, sec=msg.header.stamp.sec - 2)
            return dataclasses.replace(msg, header=dataclasses.replace(msg.header, stamp=stamp))
        return msg

    back = rewrite(bag, tmp_path / "back", change=swap)
    with pytest.raises(ValueError, match=r"back: topic /gas: time goes backwards at t = 3.000 s into the bag"):
        read_bag(back)


def test_bag_map_replaces_the_house(tmp_path):
    """--bag-map: the bag's OccupancyGrid is the house (no rooms: the prior is uniform on its free cells)."""
    from psgsl_pgm.experiment._replay import replay
    from psgsl_pgm.sim import default_house

    bag = episode_bag(tmp_path / "bag")
    res = replay(bag, bag_map=True, keep_posteriors=True)
    grid = default_house(0).grid
    np.testing.assert_array_equal(res.house.grid.occupancy, grid.occupancy)
    assert res.house.grid.resolution == grid.resolution and res.house.room_names == ()
    prior = res.posteriors[0][0]  # p(s) before any reading: uniform on the free cells
    np.testing.assert_allclose(prior[grid.free], 1.0 / grid.free.sum(), rtol=1e-12)
    assert (prior[~grid.free] == 0).all()
    nomap = rewrite(bag, tmp_path / "nomap", keep=lambda topic, t, m: topic != "/map")
    with pytest.raises(ValueError, match="nomap: the bag has no nav_msgs/msg/OccupancyGrid topic"):
        replay(nomap, bag_map=True)


def test_a_bare_mcap_file_and_the_foxglove_file(tmp_path):
    """A ROS 2 MCAP file without its metadata.yaml reads like its folder; the Foxglove file is refused with a hint."""
    import shutil

    from psgsl_pgm.ros import write_foxglove

    from .bags import synthetic_episode

    bag = episode_bag(tmp_path / "bag")
    bare = tmp_path / "bare.mcap"
    shutil.copy(_storage_file(bag, ".mcap"), bare)
    a, b = read_bag(bag), read_bag(bare)
    np.testing.assert_array_equal(a.gas_xy, b.gas_xy)
    np.testing.assert_array_equal(a.wind, b.wind)
    fox = write_foxglove(tmp_path / "run.mcap", synthetic_episode())
    with pytest.raises(ValueError, match=r"run.mcap: .*replay the .bag folder beside it"):
        read_bag(fox)


def test_writers_check_their_arguments(tmp_path):
    from psgsl_pgm.ros import write_bag, write_foxglove

    from .bags import synthetic_episode

    with pytest.raises(TypeError, match="episode must be a psgsl_pgm.ros.Episode, got dict"):
        write_bag(tmp_path / "b", {})
    with pytest.raises(TypeError, match="episode must be a psgsl_pgm.ros.Episode, got dict"):
        write_foxglove(tmp_path / "f.mcap", {})
    with pytest.raises(ValueError, match=r"storage must be one of \('mcap', 'sqlite3'\), got 'db3'"):
        write_bag(tmp_path / "b", synthetic_episode(), storage="db3")
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_bag_folder_is_written_whole_or_not_at_all(tmp_path):
    from psgsl_pgm.ros._write import replace_folder

    def fails(tmp):
        tmp.mkdir()
        (tmp / "half.mcap").write_bytes(b"abc")
        raise RuntimeError("killed")

    with pytest.raises(RuntimeError):
        replace_folder(tmp_path / "run.bag", fails)
    assert list(tmp_path.iterdir()) == []  # no bag, no temporary folder
    bag = episode_bag(tmp_path / "run.bag", n=4)
    with pytest.raises(RuntimeError):
        replace_folder(bag, fails)
    assert len(read_bag(bag).gas) == 4  # the old bag is still whole
    episode_bag(bag, n=6)  # a new recording replaces it
    assert len(read_bag(bag).gas) == 6 and [p.name for p in tmp_path.iterdir()] == ["run.bag"]
