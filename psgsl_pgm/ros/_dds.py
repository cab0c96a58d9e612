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
writes into bags for the same message.

From Iron on, a ROS 2 endpoint also announces its type's hash in the DDS USER_DATA QoS, ``typehash=RIHS01_<sha256>;``
(``encode_type_hash_for_user_data_qos`` in ``ros2/rmw_dds_common``, ``jazzy``): the SHA-256 of the type's
description, its fields and those of the types it refers to, as ``rosidl_generator_type_description`` (``ros2/rosidl``,
``jazzy``) writes it (:func:`type_hash`). Every endpoint made here announces it; Humble's rmw_cyclonedds reads no
USER_DATA, and matching is by topic and type name in both.

The messages decoded here have the attribute names of the ROS messages (``msg.header.stamp.sec``,
``msg.transforms[0].transform.rotation.w``), so the bag reader's conversions (:mod:`psgsl_pgm.ros._read`) read
them unchanged. cyclonedds is imported only inside these functions (the ``ros`` extra).
"""

# no "from __future__ import annotations": cyclonedds reads the structs' field annotations as types
import functools
import time

import numpy as np

__all__ = ["DEFINITIONS", "MISSING_DDS", "DdsEndpoint", "dds_topic", "dds_type_name", "message_types",
           "pose_stamped", "posterior_grid", "require_dds", "type_description", "type_hash"]

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

    Parameters
    ----------
    topic : str
        An absolute ROS 2 topic name (``/tf``).

    Returns
    -------
    str

    Raises
    ------
    ValueError
        ``topic`` is not an absolute name.

    Examples
    --------
    >>> dds_topic("/PID/Sensor_reading")
    'rt/PID/Sensor_reading'
    """
    if not isinstance(topic, str) or not topic.startswith("/") or len(topic) < 2 or topic.endswith("/"):
        raise ValueError(f"a ROS 2 topic must be an absolute name like /tf, got {topic!r}")
    return "rt" + topic


def dds_type_name(msgtype: str) -> str:
    """The DDS type name of a ROS 2 message type: ``"pkg/msg/Type"`` -> ``"pkg::msg::dds_::Type_"``.

    Parameters
    ----------
    msgtype : str
        A ROS 2 message type, ``pkg/msg/Type``.

    Returns
    -------
    str

    Raises
    ------
    ValueError
        ``msgtype`` does not read ``pkg/msg/Type``.

    Examples
    --------
    >>> dds_type_name("geometry_msgs/msg/PoseStamped")
    'geometry_msgs::msg::dds_::PoseStamped_'
    """
    parts = msgtype.split("/") if isinstance(msgtype, str) else []
    if len(parts) != 3 or parts[1] != "msg" or not all(parts):
        raise ValueError(f"a ROS 2 message type must read pkg/msg/Type, got {msgtype!r}")
    return f"{parts[0]}::msg::dds_::{parts[2]}_"


#: ROS 2 message type -> its fields, as in its ``.msg`` file (comments left out), Humble and Jazzy alike; the
#: lab's olfaction_msgs and vision_msgs 4.x come from :mod:`psgsl_pgm.ros._types`.
DEFINITIONS = {
    "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec",
    "std_msgs/msg/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "std_msgs/msg/Float32": "float32 data",
    "std_msgs/msg/Float64": "float64 data",
    "std_msgs/msg/String": "string data",
    "geometry_msgs/msg/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/msg/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "geometry_msgs/msg/Pose": "Point position\nQuaternion orientation",
    "geometry_msgs/msg/PoseStamped": "std_msgs/Header header\nPose pose",
    "geometry_msgs/msg/PoseWithCovariance": "Pose pose\nfloat64[36] covariance",
    "geometry_msgs/msg/PoseWithCovarianceStamped": "std_msgs/Header header\nPoseWithCovariance pose",
    "geometry_msgs/msg/Vector3Stamped": "std_msgs/Header header\nVector3 vector",
    "geometry_msgs/msg/Transform": "Vector3 translation\nQuaternion rotation",
    "geometry_msgs/msg/TransformStamped": "std_msgs/Header header\nstring child_frame_id\nTransform transform",
    "tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms",
    "nav_msgs/msg/MapMetaData": "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\n"
                                "uint32 height\ngeometry_msgs/Pose origin",
    "nav_msgs/msg/OccupancyGrid": "std_msgs/Header header\nMapMetaData info\nint8[] data",
}

#: Field type ids of ``type_description_interfaces/msg/FieldType`` (REP-2011); a fixed array adds 48, a bounded
#: sequence 96, an unbounded one 144.
_TYPE_IDS = {"nested": 1, "int8": 2, "uint8": 3, "char": 3, "int16": 4, "uint16": 5, "int32": 6, "uint32": 7,
             "int64": 8, "uint64": 9, "float32": 10, "float64": 11, "bool": 15, "byte": 16, "string": 17}


def _all_definitions() -> dict:
    from ._types import _ANEMOMETER_MSG, _GAS_SENSOR_MSG, _VISION_MSGS, ANEMOMETER, GAS_SENSOR

    return DEFINITIONS | {GAS_SENSOR: _GAS_SENSOR_MSG, ANEMOMETER: _ANEMOMETER_MSG} | _VISION_MSGS


def _fields(msgtype: str, text: str) -> list:
    """``[(name, base, kind, size)]`` of a ``.msg`` text: base a primitive or a nested ``pkg/msg/Type``; kind
    ``""`` (single), ``"array"`` (fixed ``size``), ``"bounded"`` (``size``) or ``"sequence"``. Constants (``=``)
    are no fields; a default value after the name is left out."""
    pkg = msgtype.split("/")[0]
    out = []
    for line in text.splitlines():
        tokens = line.split("#")[0].split()
        if len(tokens) < 2 or "=" in tokens[1] or (len(tokens) > 2 and tokens[2].startswith("=")):
            continue  # empty, or a constant
        typ, name = tokens[:2]
        base, kind, size = typ, "", 0
        if "[" in typ:
            base, _, rest = typ.partition("[")
            rest = rest.rstrip("]")
            kind, size = ("sequence", 0) if rest == "" else (("bounded", int(rest[2:])) if rest.startswith("<=")
                                                            else ("array", int(rest)))
        if base not in _TYPE_IDS:
            p, _, t = base.rpartition("/")
            base = f"{p or pkg}/msg/{t}"
        out.append((name, base, kind, size))
    return out


def type_description(msgtype: str) -> dict:
    """The type description of ``msgtype`` that ROS 2 hashes (REP-2011, ``rosidl_generator_type_description``):
    its fields and those of every type it refers to (sorted by name), default values left out."""
    defs = _all_definitions()
    if msgtype not in defs:
        raise ValueError(f"unknown message type {msgtype!r}; known: {sorted(defs)}")

    def individual(name):
        fields = []
        for field, base, kind, size in _fields(name, defs[name]):
            nested = base not in _TYPE_IDS
            tid = _TYPE_IDS["nested" if nested else base] + {"": 0, "array": 48, "bounded": 96, "sequence": 144}[kind]
            fields.append({"name": field, "type": {"type_id": tid, "capacity": size, "string_capacity": 0,
                                                   "nested_type_name": base if nested else ""}})
        return {"type_name": name, "fields": fields}

    refs, queue = set(), [msgtype]
    while queue:
        for f in individual(queue.pop())["fields"]:
            n = f["type"]["nested_type_name"]
            if n and n not in refs:
                refs.add(n)
                queue.append(n)
    return {"type_description": individual(msgtype),
            "referenced_type_descriptions": [individual(n) for n in sorted(refs)]}


def type_hash(msgtype: str) -> str:
    """The RIHS01 hash ROS 2 (Iron, Jazzy and later) gives ``msgtype``: SHA-256 of its type description as
    compact JSON (``rosidl_generator_type_description.calculate_type_hash``).

    Parameters
    ----------
    msgtype : str
        A ROS 2 message type of :data:`DEFINITIONS` or the lab's messages, ``pkg/msg/Type``.

    Returns
    -------
    str
        ``"RIHS01_"`` and 64 hexadecimal digits.

    Raises
    ------
    ValueError
        ``msgtype`` is neither a ROS 2 type of :data:`DEFINITIONS` nor one of the lab's messages.

    Examples
    --------
    >>> type_hash("geometry_msgs/msg/PoseStamped")
    'RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8'
    """
    import hashlib
    import json

    text = json.dumps(type_description(msgtype), ensure_ascii=True, allow_nan=False, separators=(", ", ": "))
    return "RIHS01_" + hashlib.sha256(text.encode("utf-8")).hexdigest()


@functools.lru_cache(maxsize=1)
def message_types() -> dict:
    """ROS 2 message type (``"pkg/msg/Type"``) -> its Cyclone DDS IDL struct (fields in the ``.msg`` order), for
    every type of :data:`DEFINITIONS` and the lab's and vision types."""
    require_dds()
    import types as pytypes
    from dataclasses import dataclass

    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl import types as t

    prim = {"int8": t.int8, "uint8": t.uint8, "char": t.uint8, "byte": t.uint8, "int16": t.int16,
            "uint16": t.uint16, "int32": t.int32, "uint32": t.uint32, "int64": t.int64, "uint64": t.uint64,
            "float32": t.float32, "float64": t.float64, "bool": bool, "string": str}
    defs = _all_definitions()
    out: dict = {}

    def build(msgtype):
        if msgtype in out:
            return out[msgtype]
        annotations = {}
        for name, base, kind, size in _fields(msgtype, defs[msgtype]):
            typ = prim[base] if base in prim else build(base)
            if kind == "array":
                typ = t.array[typ, size]
            elif kind == "bounded":
                typ = t.sequence[typ, size]
            elif kind == "sequence":
                typ = t.sequence[typ]
            annotations[name] = typ
        short = msgtype.rsplit("/", 1)[1]
        cls = pytypes.new_class(short, (IdlStruct,), {"typename": dds_type_name(msgtype)},
                                lambda ns: ns.update(__annotations__=annotations, __module__=__name__))
        out[msgtype] = dataclass(cls)
        return out[msgtype]

    for msgtype in defs:
        build(msgtype)
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

        def announce(msgtype):  # what rmw_cyclonedds (Iron, Jazzy) puts in an endpoint's USER_DATA
            return Policy.Userdata(data=f"typehash={type_hash(msgtype)};".encode())

        for name, msgtype in subscriptions.items():
            latched = name in self.LATCHED
            policies = [history, rel if (reliable or latched) else Policy.Reliability.BestEffort, announce(msgtype)]
            if latched:
                policies.append(Policy.Durability.TransientLocal)
            self._readers[name] = DataReader(self.participant, topic_of(name, msgtype), qos=Qos(*policies))
            self._types[name] = msgtype
        for name, msgtype in publications.items():
            policies = [history, rel, announce(msgtype)]
            if name in self.LATCHED:
                policies.append(Policy.Durability.TransientLocal)
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
