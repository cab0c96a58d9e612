"""A bag written here with rosbags directly (not by the project's writer) is read correctly.

The robot drives straight along the hallway of the embedded house (x = 1 + 0.2 t, y = 6, yaw 0). The bag has:
jittered header stamps; gas (the lab's GasSensor) at 10 Hz; detections at 1 Hz in a camera frame; the
Anemometer at 4 Hz in a sensor frame turned by 90°; the pose as map -> odom (static, rotated) -> base_link
(10 Hz); and a second robot's frame in /tf that must not be taken for ours. Everything the replay should get out
is computed here from those definitions.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from rosbags.rosbag2 import StoragePlugin, Writer

from psgsl_pgm.experiment._replay import replay, replay_frames, replay_steps
from psgsl_pgm.ros import read_bag
from psgsl_pgm.ros._types import typestore
from psgsl_pgm.sim import Camera, DetectorModel, default_house

T0 = 1_750_000_000 * 10**9
WIND = np.array([0.3, -0.1])
ODOM = np.array([0.5, -0.3, 0.2])  # map -> odom
CAMERA = np.array([0.2, 0.0, 0.0])  # base_link -> camera_link
ANEMOMETER_YAW = np.pi / 2  # base_link -> anemometer_frame
VALUES = (1.0, 0.9999, 2.5, 0.2)  # ppm: a hit exactly at the 1 ppm threshold, a miss just below it


def truth(t):
    t = np.asarray(t, dtype=np.float64)
    return np.stack([1.0 + 0.2 * t, np.full_like(t, 6.0), np.zeros_like(t)], axis=-1)


def compose(a, b):
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([a[..., 0] + c * b[..., 0] - s * b[..., 1], a[..., 1] + s * b[..., 0] + c * b[..., 1],
                     a[..., 2] + b[..., 2]], axis=-1)


def inverse(a):
    c, s = np.cos(a[2]), np.sin(a[2])
    return np.array([-(c * a[0] + s * a[1]), s * a[0] - c * a[1], -a[2]])


def ns(t):
    return T0 + np.round(np.asarray(t) * 1e9).astype(np.int64)


def make_bag(path, storage):
    rng = np.random.default_rng(7)
    store = typestore()  # the message types the library registers (lab's olfaction_msgs, vision_msgs 4.x)
    T = store.types

    def header(t, frame):
        return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=int(t // 10**9),
                                                                               nanosec=int(t % 10**9)), frame_id=frame)

    def quat(yaw):
        return T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=float(np.sin(yaw / 2)), w=float(np.cos(yaw / 2)))

    def transform(t, parent, child, p):
        return T["geometry_msgs/msg/TransformStamped"](
            header=header(t, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](x=float(p[0]), y=float(p[1]), z=0.0), rotation=quat(p[2])))

    msgs = []  # (receive time, topic, type, message)
    tf = "tf2_msgs/msg/TFMessage"
    static = [transform(T0, "map", "odom", ODOM), transform(T0, "base_link", "camera_link", CAMERA),
              transform(T0, "base_link", "anemometer_frame", (0.0, 0.0, ANEMOMETER_YAW))]
    msgs.append((T0, "/tf_static", tf, T[tf](transforms=static)))
    pose_t = -0.05 + 0.1 * np.arange(153) + rng.uniform(-0.02, 0.02, 153)
    for t, p in zip(pose_t, compose(inverse(ODOM)[None], truth(pose_t))):  # odom -> base_link
        other = transform(ns(t), "map", "robot2/base_link", (8.0 + 0.1 * t, 8.0, 1.0))
        msgs.append((ns(t) + 3_000_000, "/tf", tf, T[tf](transforms=[transform(ns(t), "odom", "base_link", p), other])))
    amcl_t = -0.1 + 0.2 * np.arange(77) + rng.uniform(-0.02, 0.02, 77)  # a 5 Hz localisation, map -> base_link
    for t, p in zip(amcl_t, truth(amcl_t)):
        pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=float(p[0]), y=float(p[1]), z=0.0),
                                           orientation=quat(p[2]))
        m = T["geometry_msgs/msg/PoseWithCovarianceStamped"](
            header=header(ns(t), "map"), pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose,
                                                                                         covariance=np.zeros(36)))
        msgs.append((ns(t) + 8_000_000, "/amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped", m))
    gas_t = 0.1 * np.arange(1, 141) + rng.uniform(-0.02, 0.02, 140)
    gas = np.array([VALUES[k % 4] for k in range(140)])
    for t, v in zip(gas_t, gas):
        m = T["olfaction_msgs/msg/GasSensor"](header=header(ns(t), "pid_link"), technology=51, manufacturer=50, mpn=70,
                                               raw=float(v), raw_units=3, raw_air=0.0, calib_a=0.0, calib_b=0.0)
        msgs.append((ns(t) + 5_000_000, "/PID/Sensor_reading", "olfaction_msgs/msg/GasSensor", m))
    wind_t = 0.05 + 0.25 * np.arange(57) + rng.uniform(-0.02, 0.02, 57)
    upwind = np.arctan2(WIND[1], WIND[0]) + np.pi - (0.0 + ANEMOMETER_YAW)  # robot yaw 0, sensor turned by 90°
    for t in wind_t:
        m = T["olfaction_msgs/msg/Anemometer"](header=header(ns(t), "anemometer_frame"), sensor_label="windsonic",
                                                wind_speed=float(np.hypot(*WIND)), wind_direction=float(upwind))
        msgs.append((ns(t) + 4_000_000, "/Anemometer/WindSensor_reading", "olfaction_msgs/msg/Anemometer", m))
    det_t = 0.5 + np.arange(14) + rng.uniform(-0.02, 0.02, 14)
    for t in det_t:
        dets = []
        for cls, (x, y) in (("tv", (1.0, 0.35)), ("person", (1.5, -0.45))):
            centre = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.5),
                                                 orientation=quat(0.0))
            hyp = T["vision_msgs/msg/ObjectHypothesisWithPose"](
                hypothesis=T["vision_msgs/msg/ObjectHypothesis"](class_id=cls, score=0.8),
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=centre, covariance=np.zeros(36)))
            dets.append(T["vision_msgs/msg/Detection3D"](
                header=header(ns(t), "camera_link"), results=[hyp],
                bbox=T["vision_msgs/msg/BoundingBox3D"](center=centre,
                                                        size=T["geometry_msgs/msg/Vector3"](x=0.05, y=0.05, z=0.3)),
                id=cls))
        msgs.append((ns(t) + 30_000_000, "/detections", "vision_msgs/msg/Detection3DArray",
                     T["vision_msgs/msg/Detection3DArray"](header=header(ns(t), "camera_link"), detections=dets)))
    msgs.sort(key=lambda m: m[0])
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conns = {}
        for t, topic, typ, msg in msgs:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=store)
            w.write(conns[topic], int(t), store.serialize_cdr(msg, typ))
    return {"gas_t": gas_t, "gas": gas, "det_t": det_t}


@pytest.fixture(scope="module", params=["sqlite3", "mcap"])
def bag(request, tmp_path_factory):
    path = tmp_path_factory.mktemp("foreign") / "robot_bag"
    return path, make_bag(path, request.param)


def test_streams_are_found_by_type_and_aligned(bag):
    path, want = bag
    data = read_bag(path)
    assert data.topics == {"pose": "/tf", "gas": "/PID/Sensor_reading", "wind": "/Anemometer/WindSensor_reading",
                           "detections": "/detections", "map": None}
    np.testing.assert_array_equal(data.gas_t, ns(want["gas_t"]))
    np.testing.assert_array_equal(data.gas, want["gas"])
    # the robot's position at each reading's own stamp, through map -> odom -> base_link, never robot2's
    np.testing.assert_allclose(data.gas_xy, truth(want["gas_t"])[:, :2], rtol=0, atol=1e-9)
    # the Anemometer (float32, upwind, in a sensor frame turned by 90°) in the map frame
    np.testing.assert_allclose(data.wind, np.broadcast_to(WIND, data.wind.shape), rtol=0, atol=1e-6)
    assert len(data.detections) == 14
    for d, t in zip(data.detections, want["det_t"]):
        cam = compose(truth(t), CAMERA)
        np.testing.assert_allclose(d.camera, cam, rtol=0, atol=1e-9)
        np.testing.assert_allclose(d.centre[0], cam[:2] + (1.0, 0.35), rtol=0, atol=1e-9)
        assert d.class_id == ("tv", "person")


def test_pose_from_a_pose_topic(bag):
    """--topics pose=/amcl_pose: the robot's pose from a PoseWithCovarianceStamped (5 Hz), the sensors still placed
    by /tf_static; the odom chain in /tf is not used for the robot."""
    path, want = bag
    data = read_bag(path, topics={"pose": "/amcl_pose"})
    assert data.topics["pose"] == "/amcl_pose"
    np.testing.assert_allclose(data.gas_xy, truth(want["gas_t"])[:, :2], rtol=0, atol=1e-9)
    np.testing.assert_allclose(data.wind, np.broadcast_to(WIND, data.wind.shape), rtol=0, atol=1e-6)
    np.testing.assert_allclose(data.detections[3].camera, compose(truth(want["det_t"][3]), CAMERA), atol=1e-9)


def test_steps_hits_and_frames(bag):
    path, want = bag
    house = default_house(0)
    detector = DetectorModel.default(house.classes)
    data = read_bag(path)
    frames, skipped = replay_frames(data, house, detector, Camera())
    assert skipped == 14  # "person" is not a class of the detector: skipped, counted
    steps = replay_steps(data, frames, threshold=1.0, tolerance=0.5)
    assert len(steps) == 140
    np.testing.assert_array_equal([s[2] for s in steps], want["gas"] >= 1.0)  # value >= threshold is a hit
    assert [s[2] for s in steps[:4]] == [True, False, True, False]
    # each detection array goes to the step of the last gas reading at or before its stamp
    owner = [k for k, s in enumerate(steps) for _ in s[5]]
    np.testing.assert_array_equal(owner, np.searchsorted(want["gas_t"], want["det_t"], side="right") - 1)
    tv = detector.labels.index("tv")
    for (t, frame), td in zip(frames, want["det_t"]):
        cam = compose(truth(td), CAMERA)
        cell = tuple(house.grid.world_to_cell(cam[:2] + (1.0, 0.35)))
        at = np.flatnonzero((frame.cells == cell).all(axis=1))
        assert len(at) == 1 and frame.labels[at[0]] == tv
        assert (np.delete(frame.labels, at) == detector.nothing).all()  # the rest of the view: "nothing"
        assert len(frame.cells) > 100  # the camera's field of view, not just the detections


def test_replay_runs_every_reading(bag, tmp_path):
    path, want = bag
    res = replay(path, config=None, tolerance=0.5)
    assert res.run.n_steps == 140 and res.n_frames == 14
    np.testing.assert_array_equal(res.run.hit[1:], want["gas"] >= 1.0)
    np.testing.assert_allclose(res.run.time[1:], want["gas_t"] - want["gas_t"][0], atol=2e-9)
    assert np.isnan(res.run.error).all()  # no source given: no error, but spreads and regions
    assert np.isfinite(res.run.spread).all() and (res.run.region_area > 0).all()
    # the readings moved p(s | g) away from the prior
    assert np.abs(np.diff(res.run.spread[:, 0])).max() > 1e-3
