"""ROS 2 over DDS without a ROS install: the message types as Cyclone DDS IDL structs, ROS 2's DDS naming, and a
participant that subscribes to a robot's topics and publishes on them.

A ROS 2 node with the Cyclone DDS middleware (``rmw_cyclonedds_cpp``, the default of ROS 2 Galactic and
selectable in every distribution) is a DDS participant. What it puts on the wire follows two naming rules and
the CDR encoding of the message's fields in their definition order:

* a ROS topic ``/name`` is the DDS topic ``rt/name`` (``ROS_TOPIC_PREFIX = "rt"`` in ``src/namespace_prefix.hpp``,
  ``make_fqtopic`` in ``src/rmw_node.cpp``);
* a message type ``pkg/msg/Type`` is the DDS type ``pkg::msg::dds_::Type_`` (``create_type_name`` in
  ``src/serdata.cpp``: the namespace, ``dds_::``, the name and a trailing underscore);
* the sample is XCDR1 little-endian (the ``0x0001`` encapsulation), fields in the ``.msg`` order; a ``.msg``
  constant is no field.

Checked against ``ros2/rmw_cyclonedds`` branches ``humble`` and ``jazzy`` (identical rules there and on
``rolling``), and the ``.msg`` definitions of ``ros2/common_interfaces`` and ``ros2/rcl_interfaces`` on the same
two branches (``std_msgs``, ``geometry_msgs``, ``nav_msgs``, ``tf2_msgs``, ``builtin_interfaces``), with
``vision_msgs`` 4.x (the Humble and Jazzy release) and the lab's ``olfaction_msgs`` (``GasSensor``,
``Anemometer``: :mod:`psgsl_pgm.ros._types`). The tests check every struct's bytes against the CDR that rosbags
writes into bags for the same message. From Iron on, a ROS 2 endpoint also announces its type's hash (RIHS01)
in the DDS USER_DATA QoS; the endpoints made here announce none, which ROS 2 treats as an unknown hash: topics
still match by name and type, only ``ros2 topic info --verbose`` shows no hash.

The messages decoded here have the attribute names of the ROS messages (``msg.header.stamp.sec``,
``msg.transforms[0].transform.rotation.w``), so the bag reader's conversions (:mod:`psgsl_pgm.ros._read`) read
them unchanged. cyclonedds is imported only inside these functions (the ``ros`` extra).
"""

# no "from __future__ import annotations": cyclonedds reads the structs' field annotations as types
import functools
import time

import numpy as np

__all__ = ["MISSING_DDS", "DdsEndpoint", "dds_topic", "dds_type_name", "message_types", "pose_stamped",
           "posterior_grid", "require_dds"]

#: The message when the Cyclone DDS binding is missing.
MISSING_DDS = 'psgsl live needs the Cyclone DDS Python binding (the "ros" extra): install psgsl-pgm[ros]'


def require_dds():
    """Import cyclonedds; ImportError with :data:`MISSING_DDS` when it is missing."""
    try:
        import cyclonedds.domain  # noqa: F401
        import cyclonedds.idl  # noqa: F401
    except ModuleNotFoundError as err:
        if (err.name or "").split(".")[0] != "cyclonedds":
            raise
        raise ImportError(MISSING_DDS) from err


def dds_topic(topic: str) -> str:
    """The DDS topic of a ROS 2 topic: ``"/tf"`` -> ``"rt/tf"``.

    >>> dds_topic("/PID/Sensor_reading")
    'rt/PID/Sensor_reading'
    """
    if not isinstance(topic, str) or not topic.startswith("/") or len(topic) < 2 or topic.endswith("/"):
        raise ValueError(f"a ROS 2 topic must be an absolute name like /tf, got {topic!r}")
    return "rt" + topic


def dds_type_name(msgtype: str) -> str:
    """The DDS type name of a ROS 2 message type: ``"pkg/msg/Type"`` -> ``"pkg::msg::dds_::Type_"``.

    >>> dds_type_name("geometry_msgs/msg/PoseStamped")
    'geometry_msgs::msg::dds_::PoseStamped_'
    """
    parts = msgtype.split("/") if isinstance(msgtype, str) else []
    if len(parts) != 3 or parts[1] != "msg" or not all(parts):
        raise ValueError(f"a ROS 2 message type must read pkg/msg/Type, got {msgtype!r}")
    return f"{parts[0]}::msg::dds_::{parts[2]}_"


@functools.lru_cache(maxsize=1)
def message_types() -> dict:
    """ROS 2 message type (``"pkg/msg/Type"``) -> its Cyclone DDS IDL struct (fields in the ``.msg`` order)."""
    require_dds()
    from dataclasses import dataclass

    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl import types as t

    from ._types import ANEMOMETER, DETECTIONS, GAS_SENSOR

    def name(msgtype):
        return dds_type_name(msgtype)

    @dataclass
    class Time(IdlStruct, typename=name("builtin_interfaces/msg/Time")):
        sec: t.int32
        nanosec: t.uint32

    @dataclass
    class Header(IdlStruct, typename=name("std_msgs/msg/Header")):
        stamp: Time
        frame_id: str

    @dataclass
    class Float32(IdlStruct, typename=name("std_msgs/msg/Float32")):
        data: t.float32

    @dataclass
    class Float64(IdlStruct, typename=name("std_msgs/msg/Float64")):
        data: t.float64

    @dataclass
    class String(IdlStruct, typename=name("std_msgs/msg/String")):
        data: str

    @dataclass
    class Vector3(IdlStruct, typename=name("geometry_msgs/msg/Vector3")):
        x: t.float64
        y: t.float64
        z: t.float64

    @dataclass
    class Point(IdlStruct, typename=name("geometry_msgs/msg/Point")):
        x: t.float64
        y: t.float64
        z: t.float64

    @dataclass
    class Quaternion(IdlStruct, typename=name("geometry_msgs/msg/Quaternion")):
        x: t.float64
        y: t.float64
        z: t.float64
        w: t.float64

    @dataclass
    class Pose(IdlStruct, typename=name("geometry_msgs/msg/Pose")):
        position: Point
        orientation: Quaternion

    @dataclass
    class PoseStamped(IdlStruct, typename=name("geometry_msgs/msg/PoseStamped")):
        header: Header
        pose: Pose

    @dataclass
    class PoseWithCovariance(IdlStruct, typename=name("geometry_msgs/msg/PoseWithCovariance")):
        pose: Pose
        covariance: t.array[t.float64, 36]

    @dataclass
    class PoseWithCovarianceStamped(IdlStruct, typename=name("geometry_msgs/msg/PoseWithCovarianceStamped")):
        header: Header
        pose: PoseWithCovariance

    @dataclass
    class Vector3Stamped(IdlStruct, typename=name("geometry_msgs/msg/Vector3Stamped")):
        header: Header
        vector: Vector3

    @dataclass
    class Transform(IdlStruct, typename=name("geometry_msgs/msg/Transform")):
        translation: Vector3
        rotation: Quaternion

    @dataclass
    class TransformStamped(IdlStruct, typename=name("geometry_msgs/msg/TransformStamped")):
        header: Header
        child_frame_id: str
        transform: Transform

    @dataclass
    class TFMessage(IdlStruct, typename=name("tf2_msgs/msg/TFMessage")):
        transforms: t.sequence[TransformStamped]

    @dataclass
    class GasSensor(IdlStruct, typename=name(GAS_SENSOR)):
        header: Header
        technology: t.uint8
        manufacturer: t.uint8
        mpn: t.uint8
        raw: t.float64
        raw_units: t.uint8
        raw_air: t.float64
        calib_a: t.float64
        calib_b: t.float64

    @dataclass
    class Anemometer(IdlStruct, typename=name(ANEMOMETER)):
        header: Header
        sensor_label: str
        wind_speed: t.float32
        wind_direction: t.float32

    @dataclass
    class ObjectHypothesis(IdlStruct, typename=name("vision_msgs/msg/ObjectHypothesis")):
        class_id: str
        score: t.float64

    @dataclass
    class ObjectHypothesisWithPose(IdlStruct, typename=name("vision_msgs/msg/ObjectHypothesisWithPose")):
        hypothesis: ObjectHypothesis
        pose: PoseWithCovariance

    @dataclass
    class BoundingBox3D(IdlStruct, typename=name("vision_msgs/msg/BoundingBox3D")):
        center: Pose
        size: Vector3

    @dataclass
    class Detection3D(IdlStruct, typename=name("vision_msgs/msg/Detection3D")):
        header: Header
        results: t.sequence[ObjectHypothesisWithPose]
        bbox: BoundingBox3D
        id: str

    @dataclass
    class Detection3DArray(IdlStruct, typename=name(DETECTIONS)):
        header: Header
        detections: t.sequence[Detection3D]

    @dataclass
    class MapMetaData(IdlStruct, typename=name("nav_msgs/msg/MapMetaData")):
        map_load_time: Time
        resolution: t.float32
        width: t.uint32
        height: t.uint32
        origin: Pose

    @dataclass
    class OccupancyGrid(IdlStruct, typename=name("nav_msgs/msg/OccupancyGrid")):
        header: Header
        info: MapMetaData
        data: t.sequence[t.int8]

    local = dict(locals())
    out = {}
    for cls in local.values():
        if isinstance(cls, type) and issubclass(cls, IdlStruct) and cls is not IdlStruct:
            pkg, _, _, typ = cls.__idl_typename__.split("::")
            out[f"{pkg}/msg/{typ[:-1]}"] = cls
    return out


def _header(T, t_ns: int, frame: str):
    return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](
        sec=int(t_ns // 1_000_000_000), nanosec=int(t_ns % 1_000_000_000)), frame_id=frame)


def pose_stamped(t_ns: int, frame: str, pose):
    """A ``geometry_msgs/msg/PoseStamped`` at ``pose`` = (x, y, yaw) (m, m, rad) in ``frame``, stamped ``t_ns``."""
    T = message_types()
    x, y, yaw = (float(v) for v in pose)
    q = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=float(np.sin(yaw / 2)), w=float(np.cos(yaw / 2)))
    return T["geometry_msgs/msg/PoseStamped"](
        header=_header(T, t_ns, frame),
        pose=T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0), orientation=q))


def posterior_grid(t_ns: int, frame: str, grid, posterior):
    """A ``nav_msgs/msg/OccupancyGrid`` of a posterior over ``grid``'s cells.

    Parameters
    ----------
    t_ns : int
        Stamp, ns.
    frame : str
    grid : psgsl_pgm.GridMap
        The map the posterior is defined on (origin, resolution; rows along y).
    posterior : (H, W) ndarray
        p(s | ·), summing to 1.

    Returns
    -------
    OccupancyGrid
        Cell value ``round(100 · p / max p)``: 100 at the most probable cell, 0 where p is below half a percent
        of it (the grid's row-major order, row 0 at the origin, as a map server publishes it).
    """
    T = message_types()
    p = np.asarray(posterior, dtype=np.float64)
    if p.shape != tuple(grid.shape):
        raise ValueError(f"posterior must have the grid's shape {tuple(grid.shape)}, got {p.shape}")
    top = float(p.max()) if p.size else 0.0
    if not (np.isfinite(p).all() and top > 0):
        raise ValueError("posterior must be finite with a positive maximum")
    data = np.rint(100.0 * p / top).astype(np.int8).ravel()
    head = _header(T, t_ns, frame)
    info = T["nav_msgs/msg/MapMetaData"](
        map_load_time=head.stamp, resolution=float(grid.resolution), width=int(grid.shape[1]),
        height=int(grid.shape[0]),
        origin=T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=float(grid.origin[0]), y=float(grid.origin[1]), z=0.0),
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)))
    return T["nav_msgs/msg/OccupancyGrid"](header=head, info=info, data=data.tolist())


class DdsEndpoint:
    """One DDS participant with readers on ROS 2 topics and writers to others.

    Parameters
    ----------
    subscriptions : dict
        ROS 2 topic -> message type (``"pkg/msg/Type"`` of :func:`message_types`).
    publications : dict
        ROS 2 topic -> message type.
    domain_id : int, keyword-only
        The DDS domain (ROS 2's ``ROS_DOMAIN_ID``), 0-232.
    reliable : bool, keyword-only
        Readers ask for reliable delivery (they then match reliable writers only, the ROS 2 default); False:
        best effort (they match every writer, ROS 2's sensor-data QoS too). ``/tf_static`` and the map are read
        transient-local either way, as ROS 2 latches them. Writers are reliable.
    depth : int, keyword-only
        Keep-last history depth of every endpoint.

    The network interface is Cyclone DDS's choice, or the ``CYCLONEDDS_URI`` configuration's.
    """

    #: Topics ROS 2 publishes transient-local (late joiners get the last message).
    LATCHED = ("/tf_static", "/map")

    def __init__(self, subscriptions: dict, publications: dict, *, domain_id: int = 0, reliable: bool = True,
                 depth: int = 1000):
        require_dds()
        from cyclonedds.qos import Policy, Qos
        from cyclonedds.domain import DomainParticipant
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic
        from cyclonedds.util import duration

        if isinstance(domain_id, bool) or not isinstance(domain_id, (int, np.integer)) or not 0 <= domain_id <= 232:
            raise ValueError(f"domain_id must be an integer in 0..232 (ROS_DOMAIN_ID), got {domain_id!r}")
        types = message_types()
        for role, table in (("subscriptions", subscriptions), ("publications", publications)):
            for topic, msgtype in table.items():
                dds_topic(topic)
                if msgtype not in types:
                    raise ValueError(f"{role}: topic {topic}: unknown message type {msgtype!r}; known: "
                                     f"{sorted(types)}")
        self.participant = DomainParticipant(int(domain_id))
        history = Policy.History.KeepLast(int(depth))
        rel = Policy.Reliability.Reliable(duration(seconds=1))
        self._readers, self._writers, self._types = {}, {}, {}
        self._topics = {}

        def topic_of(name, msgtype):
            if name not in self._topics:
                self._topics[name] = Topic(self.participant, dds_topic(name), types[msgtype])
            return self._topics[name]

        for name, msgtype in subscriptions.items():
            latched = name in self.LATCHED
            policies = [history, rel if (reliable or latched) else Policy.Reliability.BestEffort]
            if latched:
                policies.append(Policy.Durability.TransientLocal)
            self._readers[name] = DataReader(self.participant, topic_of(name, msgtype), qos=Qos(*policies))
            self._types[name] = msgtype
        for name, msgtype in publications.items():
            policies = [history, rel] + ([Policy.Durability.TransientLocal] if name in self.LATCHED else [])
            self._writers[name] = DataWriter(self.participant, topic_of(name, msgtype), qos=Qos(*policies))

    def take(self) -> list:
        """``[(topic, source stamp ns, message)]`` of every sample received since the last call, per topic in
        arrival order (the source stamp is the writer's time of the sample, as a bag records its receive time)."""
        out = []
        for name, reader in self._readers.items():
            while True:
                batch = reader.take(N=256)
                if not batch:
                    break
                for s in batch:
                    info = getattr(s, "sample_info", None)
                    if info is not None and not info.valid_data:
                        continue
                    out.append((name, int(info.source_timestamp) if info is not None else time.time_ns(), s))
        return out

    def publish(self, topic: str, message, *, t_ns: int | None = None) -> None:
        """Write ``message`` on ``topic`` (a publication), with source stamp ``t_ns`` (default: now)."""
        if topic not in self._writers:
            raise ValueError(f"topic must be one of the publications {sorted(self._writers)}, got {topic!r}")
        if t_ns is None:
            self._writers[topic].write(message)
        else:
            self._writers[topic].write(message, timestamp=int(t_ns))

    def matched(self, topic: str) -> int:
        """How many remote endpoints a reader or writer of ``topic`` is matched with."""
        ep = self._readers.get(topic) or self._writers.get(topic)
        if ep is None:
            raise ValueError(f"topic must be one of {sorted(self._readers) + sorted(self._writers)}, got {topic!r}")
        return len(ep.get_matched_publications() if topic in self._readers else ep.get_matched_subscriptions())

    def close(self) -> None:
        """Delete the participant and its endpoints."""
        self._readers.clear()
        self._writers.clear()
        self._topics.clear()
        self.participant = None
