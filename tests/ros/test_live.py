"""psgsl live over a real DDS participant on the loopback interface.

A publisher participant plays a bag written by the project's writer (the synthetic hallway episode of
``tests/ros/bags.py``) message by message under ROS 2's DDS names and types; the node, in another participant of
the same domain, must assimilate exactly the offline replay's steps: the same posteriors bit for bit, the same
goals as a session fed from the bag, and on the wire a PoseStamped and an OccupancyGrid per step that a third
participant receives. Each test has its own domain id; the Cyclone DDS configuration keeps the traffic on lo.
"""

from __future__ import annotations

import builtins
import os
import threading
import time
import zlib

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")
pytest.importorskip("cyclonedds", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from psgsl_pgm.cli._main import main
from psgsl_pgm.experiment._replay import replay, replay_steps
from psgsl_pgm.experiment import VARIANTS
from psgsl_pgm.ros import read_bag
from psgsl_pgm.ros._dds import (DdsEndpoint, dds_topic, dds_type_name, message_types, pose_stamped,
                                posterior_grid)
from psgsl_pgm.ros._types import typestore
from psgsl_pgm.search._live import LiveSession, live_subscriptions, run_live, write_live

from .bags import episode_bag

LOOPBACK = """<CycloneDDS><Domain Id="any"><General><Interfaces><NetworkInterface name="lo"/></Interfaces>
<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex>
<MaxAutoParticipantIndex>30</MaxAutoParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery>
</Domain></CycloneDDS>"""

POLICY = "greedy"  # the cheapest policy: the goals' equality is about the stream, not the policy's cost


@pytest.fixture()
def domain(tmp_path, monkeypatch, request):
    """A domain id of this test alone (from its name and the process), with Cyclone DDS held to 127.0.0.1 / lo."""
    cfg = tmp_path / "cyclonedds.xml"
    cfg.write_text(LOOPBACK)
    monkeypatch.setenv("CYCLONEDDS_URI", cfg.as_uri())
    return 1 + (zlib.crc32(request.node.name.encode()) + os.getpid()) % 200


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    return episode_bag(tmp_path_factory.mktemp("live") / "episode.bag", n=6)


def _bag_messages(path, topics):
    """(topic, receive stamp, message type, CDR bytes) of the bag's ``topics`` in bag order."""
    from rosbags.rosbag2 import Reader

    with Reader(path) as reader:
        conns = [c for c in reader.connections if c.topic in topics]
        return [(c.topic, int(t), c.msgtype, bytes(raw)) for c, t, raw in reader.messages(connections=conns)]


def _wait_matched(endpoint, topics, timeout=5.0):
    end = time.monotonic() + timeout
    while any(endpoint.matched(t) == 0 for t in topics):
        if time.monotonic() > end:
            raise AssertionError(f"no DDS match on {[t for t in topics if endpoint.matched(t) == 0]}")
        time.sleep(0.01)


def _offline_goals(bag, session):
    data = read_bag(bag)
    frames, _ = session.frames(data.detections)
    steps = replay_steps(data, frames, threshold=session.threshold, tolerance=0.5)
    yaw = dict(zip(data.pose_t.tolist(), data.pose[:, 2].tolist()))
    return [session.observe(s, yaw[s[0]]) for s in steps]


def test_ros2_naming_as_rmw_cyclonedds_spells_it():
    assert dds_topic("/tf") == "rt/tf"
    assert dds_topic("/robot1/goal_pose") == "rt/robot1/goal_pose"
    assert dds_type_name("tf2_msgs/msg/TFMessage") == "tf2_msgs::msg::dds_::TFMessage_"
    assert message_types()["olfaction_msgs/msg/GasSensor"].__idl_typename__ == "olfaction_msgs::msg::dds_::GasSensor_"
    for bad in ("tf", "/tf/", ""):
        with pytest.raises(ValueError, match="absolute name"):
            dds_topic(bad)
    with pytest.raises(ValueError, match="pkg/msg/Type"):
        dds_type_name("geometry_msgs/PoseStamped")


#: RIHS01 hashes of ROS 2 Jazzy's generated type descriptions, as other ROS 2 client projects pin them in their tests
JAZZY_HASHES = {
    "geometry_msgs/msg/PoseStamped": "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8",
    "geometry_msgs/msg/PoseWithCovarianceStamped":
        "RIHS01_26432f9803e43727d3c8f668d1fdb3c630f548af631e2f4e31382371bfea3b6e",
    "std_msgs/msg/String": "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
    "rosgraph_msgs/msg/Clock": "RIHS01_692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564",
}


def test_type_hashes_are_ros2_jazzys(monkeypatch):
    from psgsl_pgm.ros import _dds

    monkeypatch.setitem(_dds.DEFINITIONS, "rosgraph_msgs/msg/Clock", "builtin_interfaces/Time clock")
    for msgtype, expected in JAZZY_HASHES.items():
        assert _dds.type_hash(msgtype) == expected, msgtype
    # a field renamed, retyped or moved is another type
    monkeypatch.setitem(_dds.DEFINITIONS, "rosgraph_msgs/msg/Clock", "builtin_interfaces/Time clocks")
    assert _dds.type_hash("rosgraph_msgs/msg/Clock") != JAZZY_HASHES["rosgraph_msgs/msg/Clock"]
    desc = _dds.type_description("geometry_msgs/msg/PoseWithCovariance")
    cov = desc["type_description"]["fields"][1]
    assert cov == {"name": "covariance", "type": {"type_id": 59, "capacity": 36, "string_capacity": 0,
                                                  "nested_type_name": ""}}
    assert [d["type_name"] for d in desc["referenced_type_descriptions"]] == [
        "geometry_msgs/msg/Point", "geometry_msgs/msg/Pose", "geometry_msgs/msg/Quaternion"]
    with pytest.raises(ValueError, match="unknown message type"):
        _dds.type_hash("std_msgs/msg/Int32")


def test_endpoints_announce_the_type_hash_as_rmw_cyclonedds_does(domain):
    from cyclonedds.qos import Policy

    node = DdsEndpoint({"/goal_pose": "geometry_msgs/msg/PoseStamped"}, {}, domain_id=domain)
    player = DdsEndpoint({}, {"/goal_pose": "geometry_msgs/msg/PoseStamped"}, domain_id=domain)
    _wait_matched(player, ["/goal_pose"])
    reader = node._readers["/goal_pose"]
    data = reader.get_matched_publication_data(reader.get_matched_publications()[0])
    expected = f"typehash={JAZZY_HASHES['geometry_msgs/msg/PoseStamped']};".encode()
    assert data.qos[Policy.Userdata].data == expected
    assert data.topic_name == "rt/goal_pose" and data.type_name == "geometry_msgs::msg::dds_::PoseStamped_"
    for e in (node, player):
        e.close()


def test_every_struct_is_the_cdr_rosbags_writes(bag):
    """Field order and widths: each recorded message decodes into the DDS struct and re-encodes to the same bytes;
    the published types encode as rosbags encodes them."""
    rows = _bag_messages(bag, {"/tf", "/gas", "/wind", "/anemometer", "/detections", "/map", "/psgsl/episode"})
    T = message_types()
    seen = set()
    for topic, _, msgtype, raw in rows:
        msg = T[msgtype].deserialize(raw)
        assert bytes(msg.serialize()) == raw, topic
        seen.add(msgtype)
    assert len(seen) == 7
    store = typestore()
    S = store.types
    head = S["std_msgs/msg/Header"](stamp=S["builtin_interfaces/msg/Time"](sec=5, nanosec=7), frame_id="odom")
    pose = S["geometry_msgs/msg/Pose"](position=S["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=3.0),
                                       orientation=S["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.6, w=0.8))
    others = {"std_msgs/msg/Float32": S["std_msgs/msg/Float32"](data=np.float32(0.1)),
              "std_msgs/msg/Float64": S["std_msgs/msg/Float64"](data=0.1),
              "geometry_msgs/msg/PoseStamped": S["geometry_msgs/msg/PoseStamped"](header=head, pose=pose),
              "geometry_msgs/msg/PoseWithCovarianceStamped": S["geometry_msgs/msg/PoseWithCovarianceStamped"](
                  header=head, pose=S["geometry_msgs/msg/PoseWithCovariance"](pose=pose,
                                                                              covariance=np.arange(36.0)))}
    for msgtype, msg in others.items():
        raw = bytes(store.serialize_cdr(msg, msgtype))
        assert bytes(T[msgtype].deserialize(raw).serialize()) == raw, msgtype
    back = T["geometry_msgs/msg/PoseWithCovarianceStamped"].deserialize(
        bytes(store.serialize_cdr(others["geometry_msgs/msg/PoseWithCovarianceStamped"],
                                  "geometry_msgs/msg/PoseWithCovarianceStamped")))
    assert list(back.pose.covariance) == list(range(36)) and back.header.frame_id == "odom"
    goal = pose_stamped(1_700_000_000_123_456_789, "map", (1.5, -2.0, 0.7))
    back = store.deserialize_cdr(bytes(goal.serialize()), "geometry_msgs/msg/PoseStamped")
    assert (back.header.stamp.sec, back.header.stamp.nanosec) == (1_700_000_000, 123_456_789)
    assert (back.pose.position.x, back.pose.position.y) == (1.5, -2.0)
    assert np.isclose(2 * np.arctan2(back.pose.orientation.z, back.pose.orientation.w), 0.7)
    from psgsl_pgm.sim import default_house

    grid = default_house(0).grid
    p = np.zeros(grid.shape)
    p[3, 4], p[5, 6] = 0.75, 0.25
    occ = store.deserialize_cdr(bytes(posterior_grid(0, "map", grid, p).serialize()), "nav_msgs/msg/OccupancyGrid")
    data = np.asarray(occ.data).reshape(occ.info.height, occ.info.width)
    assert data[3, 4] == 100 and data[5, 6] == 33 and data.sum() == 133
    assert np.isclose(occ.info.resolution, grid.resolution) and occ.info.origin.position.x == grid.origin[0]


def test_the_node_on_dds_equals_the_offline_replay(bag, domain, tmp_path):
    """A publisher plays the bag at its own pace while the node runs; posteriors, goals and the messages on the
    wire match the offline replay's."""
    roles, subs = live_subscriptions()
    node = DdsEndpoint(subs, {"/goal_pose": "geometry_msgs/msg/PoseStamped",
                              "/psgsl/posterior": "nav_msgs/msg/OccupancyGrid"}, domain_id=domain)
    rows = _bag_messages(bag, set(subs))
    player = DdsEndpoint({}, {t: m for t, _, m, _ in rows}, domain_id=domain)
    listener = DdsEndpoint({"/goal_pose": "geometry_msgs/msg/PoseStamped",
                            "/psgsl/posterior": "nav_msgs/msg/OccupancyGrid"}, {}, domain_id=domain)
    _wait_matched(player, {t for t, _, _, _ in rows})
    _wait_matched(node, ["/goal_pose", "/psgsl/posterior"])
    T = message_types()
    finished = threading.Event()

    def play():
        for topic, t, msgtype, raw in rows:
            player.publish(topic, T[msgtype].deserialize(raw), t_ns=t)
            time.sleep(0.003)
        finished.set()

    session = LiveSession(policy=POLICY)
    thread = threading.Thread(target=play)
    thread.start()
    quiet = []

    def stop():  # a second after the last message: everything sent has arrived
        if finished.is_set() and not quiet:
            quiet.append(time.monotonic())
        return bool(quiet) and time.monotonic() - quiet[0] > 1.0

    result = run_live(node, session, roles=roles, subs=subs, stop=stop, poll=0.01)
    thread.join()
    offline = replay(bag, keep_posteriors=True)
    steps = result["steps"]
    assert len(steps) == offline.run.n_steps == 6 and result["pending"] == 0
    for k, s in enumerate(steps):
        assert np.array_equal(s.posteriors, offline.posteriors[k + 1]), k
        assert np.array_equal(s.position, offline.run.position[k + 1])
        assert s.hit == offline.run.hit[k + 1]
    reference = _offline_goals(bag, LiveSession(policy=POLICY))
    assert [tuple(s.goal) for s in steps] == [tuple(s.goal) for s in reference]
    time.sleep(0.3)
    got = listener.take()
    goals = [m for t, _, m in got if t == "/goal_pose"]
    grids = [m for t, _, m in got if t == "/psgsl/posterior"]
    assert len(goals) == len(grids) == 6
    v = VARIANTS.index(session.variant)
    for s, g, o, p in zip(reference, goals, grids, offline.posteriors[1:]):
        assert (g.pose.position.x, g.pose.position.y) == tuple(s.goal[:2]) and g.header.frame_id == "map"
        assert g.header.stamp.sec * 10**9 + g.header.stamp.nanosec == s.t_ns
        assert list(o.data) == list(posterior_grid(s.t_ns, "map", session.house.grid, p[v]).data)
    # the recorded run replays offline to the same final posteriors
    written = write_live(result, session, tmp_path / "out", subs=subs)
    assert {p.name for p in written} >= {"live.bag", "steps.csv", "posterior-semantics+rooms.npy"}
    again = replay(tmp_path / "out" / "live.bag", keep_posteriors=False)
    assert np.array_equal(again.final, offline.final)
    for e in (node, player, listener):
        e.close()


def test_a_reading_waits_for_its_pose_and_the_next_reading(bag, domain):
    """Readings whose pose has not come yet stay pending (never extrapolated); the last waits for the end."""
    roles, subs = live_subscriptions()
    node = DdsEndpoint(subs, {"/goal_pose": "geometry_msgs/msg/PoseStamped",
                              "/psgsl/posterior": "nav_msgs/msg/OccupancyGrid"}, domain_id=domain)
    rows = [r for r in _bag_messages(bag, set(subs))]
    t_gas = [t for topic, t, _, _ in rows if topic == "/gas"]
    rows = [r for r in rows if not (r[0] == "/tf" and r[1] > t_gas[2])]  # the pose stops at the third reading
    player = DdsEndpoint({}, {t: m for t, _, m, _ in rows}, domain_id=domain)
    _wait_matched(player, {t for t, _, _, _ in rows})
    T = message_types()
    for topic, t, msgtype, raw in rows:
        player.publish(topic, T[msgtype].deserialize(raw), t_ns=t)
    result = run_live(node, LiveSession(policy=POLICY), roles=roles, subs=subs, duration=1.0, poll=0.01)
    assert len(result["steps"]) == 3 and result["pending"] == 3
    for e in (node, player):
        e.close()


def test_unknown_topic_types_and_roles_are_refused():
    with pytest.raises(ValueError, match="gas: unknown topic type 'std_msgs/msg/Int32'"):
        live_subscriptions(types={"gas": "std_msgs/msg/Int32"})
    with pytest.raises(ValueError, match="unknown role"):
        live_subscriptions(topics={"camera": "/cam"})
    with pytest.raises(ValueError, match="unknown message type"):
        DdsEndpoint({"/gas": "std_msgs/msg/Int32"}, {})
    with pytest.raises(ValueError, match="domain_id"):
        DdsEndpoint({}, {}, domain_id=300)


def test_cli_without_cyclonedds_says_what_to_install(monkeypatch, capsys):
    real = builtins.__import__

    def no_dds(name, *args, **kwargs):
        if name.split(".")[0] == "cyclonedds":
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dds)
    message_types.cache_clear()
    try:
        assert main(["live", "--duration", "1"]) == 2
    finally:
        message_types.cache_clear()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "install psgsl-pgm[ros]" in err[0]


def test_cli_refuses_an_unknown_topic_type_in_one_line(capsys):
    assert main(["live", "--types", "wind=geometry_msgs/msg/Twist", "--duration", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "wind: unknown topic type 'geometry_msgs/msg/Twist'" in err[0]


def test_until_declared_stops_at_the_closed_loops_first_declaration(bag, domain):
    from psgsl_pgm.search import SearchConfig

    roles, subs = live_subscriptions()
    node = DdsEndpoint(subs, {"/goal_pose": "geometry_msgs/msg/PoseStamped",
                              "/psgsl/posterior": "nav_msgs/msg/OccupancyGrid"}, domain_id=domain)
    rows = _bag_messages(bag, set(subs))
    player = DdsEndpoint({}, {t: m for t, _, m, _ in rows}, domain_id=domain)
    _wait_matched(player, {t for t, _, _, _ in rows})
    T = message_types()
    for topic, t, msgtype, raw in rows:
        player.publish(topic, T[msgtype].deserialize(raw), t_ns=t)
    kappa = 0.017  # the hallway episode's masses are 0.016, 0.0175, …: the second step declares
    session = LiveSession(policy=POLICY, search=SearchConfig(declare_mass=kappa))
    result = run_live(node, session, roles=roles, subs=subs, until_declared=True, duration=5.0, poll=0.01)
    masses = [s.declaration.mass for s in result["steps"]]
    assert result["declared"] and len(masses) == 2 and masses[0] < kappa <= masses[1]
    assert result["steps"][-1].declared and not result["steps"][0].declared
    with pytest.raises(ValueError, match="needs an end"):
        run_live(node, session, roles=roles, subs=subs)
    for e in (node, player):
        e.close()


def test_cli_runs_the_node_and_records_it(bag, domain, tmp_path, capsys):
    rows = _bag_messages(bag, {"/tf", "/gas", "/wind", "/detections"})
    player = DdsEndpoint({}, {t: m for t, _, m, _ in rows}, domain_id=domain)
    T = message_types()

    def play():
        _wait_matched(player, {t for t, _, _, _ in rows}, timeout=8.0)
        for topic, t, msgtype, raw in rows:
            player.publish(topic, T[msgtype].deserialize(raw), t_ns=t)

    thread = threading.Thread(target=play)
    thread.start()
    out = tmp_path / "run"
    code = main(["live", "--domain-id", str(domain), "--duration", "3", "--policy", POLICY, "--out", str(out),
                 "--foxglove", "0"])
    thread.join()
    player.close()
    text = capsys.readouterr().out
    assert code == 0, text
    assert "psgsl live: 6 steps" in text and text.count(" goal (") == 6
    assert "psgsl live: Foxglove on ws://127.0.0.1:" in text
    assert sorted(p.name for p in out.iterdir()) == ["live.bag", "posterior-olfaction.npy",
                                                     "posterior-semantics+rooms.npy", "posterior-semantics.npy",
                                                     "steps.csv"]
    offline = replay(bag)
    final = np.load(out / "posterior-semantics+rooms.npy")
    assert np.array_equal(final, offline.final[VARIANTS.index("semantics+rooms")])
    table = (out / "steps.csv").read_text().splitlines()
    assert len(table) == 7 and table[0].endswith("declare_x,declare_y,declare_mass,declared")


class _Playback:
    """An endpoint that hands the node one message per poll, in bag order, and keeps what the node publishes."""

    def __init__(self, rows):
        self.rows, self.i, self.published, self.T = rows, 0, [], message_types()

    def take(self):
        if self.i >= len(self.rows):
            return []
        topic, t, msgtype, raw = self.rows[self.i]
        self.i += 1
        return [(topic, t, self.T[msgtype].deserialize(raw))]

    def publish(self, topic, message):
        self.published.append((topic, message))


@pytest.mark.parametrize("pose", [("/tf", "tf2_msgs/msg/TFMessage"),
                                  ("/amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped")])
def test_message_by_message_a_robots_bag_gives_the_replays_posteriors(tmp_path, pose):
    """The foreign bag's first 6 s (jittered stamps, map -> odom -> base_link or a 5 Hz localisation, 10 Hz gas,
    a 4 Hz anemometer turned by 90°, detections in a camera frame, another robot's frames) fed one message at a
    time: every reading becomes a step as soon as the next one and its pose and wind have come, from a window of
    the messages, and the posteriors are the offline replay's bit for bit."""
    from .bags import rewrite
    from .test_ros_foreign_bag import T0, make_bag

    make_bag(tmp_path / "robot_bag", "mcap")
    path = rewrite(tmp_path / "robot_bag", tmp_path / "first_6s",  # the last reading between two wind samples
                   keep=lambda topic, t, msg: t <= T0 + (5.6 if topic == "/PID/Sensor_reading" else 6.0) * 1e9)
    roles, subs = live_subscriptions(topics={"gas": "/PID/Sensor_reading", "wind": "/Anemometer/WindSensor_reading",
                                             "pose": pose[0]},
                                     types={"wind": "olfaction_msgs/msg/Anemometer", "pose": pose[1]})
    rows = _bag_messages(path, set(subs))
    feed = _Playback(rows)
    session = LiveSession(policy=POLICY)
    taken_at = []
    result = run_live(feed, session, roles=roles, subs=subs, latency=0.0, poll=0.0,
                      stop=lambda: feed.i >= len(rows), on_step=lambda s: taken_at.append(feed.i))
    offline = replay(path, tolerance=0.5, keep_posteriors=True, topics={"pose": pose[0]})
    n = offline.run.n_steps
    assert len(result["steps"]) == n and n >= 55
    for k, s in enumerate(result["steps"]):
        assert np.array_equal(s.posteriors, offline.posteriors[k + 1]), k
    assert result["skipped_detections"] == offline.n_frames == 6  # "person" is no class of the detector
    assert sum(i < len(rows) for i in taken_at) >= n - 5  # live: all but the last few before the bag ended
    assert [t for t, _ in feed.published[::2]] == ["/goal_pose"] * n


def test_a_detection_array_after_its_step_is_dropped_and_counted(bag, tmp_path):
    from .bags import rewrite

    rows = _bag_messages(bag, {"/tf", "/gas", "/wind", "/detections"})
    dets = [r for r in rows if r[0] == "/detections"]
    assert len(dets) == 2
    late = dets[1]  # the array at t = 3 s comes last, after the steps at 3 and 4 s were taken
    feed = _Playback([r for r in rows if r is not late] + [late])
    roles, subs = live_subscriptions()
    result = run_live(feed, LiveSession(policy=POLICY), roles=roles, subs=subs, latency=0.0, poll=0.0,
                      stop=lambda: feed.i >= len(feed.rows))
    assert result["late_detections"] == 1 and len(result["steps"]) == 6
    without = rewrite(bag, tmp_path / "without", keep=lambda topic, t, msg: not (topic == "/detections"
                                                                                and t == late[1]))
    offline = replay(without, keep_posteriors=True)
    for k, s in enumerate(result["steps"]):
        assert np.array_equal(s.posteriors, offline.posteriors[k + 1]), k
