"""Reading a ROS 2 bag (sqlite3 or MCAP storage) into the arrays the estimators need.

Topics are found by message type (:data:`ROLES`), or named per role (``topics={"gas": "/PID/Sensor_reading"}``):

* ``pose``: ``tf2_msgs/msg/TFMessage`` on ``/tf`` (with ``/tf_static``), else
  ``geometry_msgs/msg/PoseWithCovarianceStamped`` or ``PoseStamped`` — the robot frame's pose in the map frame;
* ``gas``: ``olfaction_msgs/msg/GasSensor`` (field ``raw``, its unit from ``raw_units``), else
  ``std_msgs/msg/Float32`` / ``Float64`` (no unit in the message) — the reading at its header stamp (a Float has
  none: the bag's receive time);
* ``wind`` (optional): ``geometry_msgs/msg/Vector3Stamped``, else ``olfaction_msgs/msg/Anemometer`` — the wind
  vector in the map frame: a Vector3 rotated from its frame; an Anemometer's speed and direction (the direction
  the wind comes FROM, in the sensor frame, as GADEN publishes it). A bag without one (or with an empty one) has
  no wind readings;
* ``detections`` (optional): ``vision_msgs/msg/Detection3DArray`` — per detection its best class id, score, box;
* ``map`` (optional): ``nav_msgs/msg/OccupancyGrid`` — the first map.

Frames: every pose is the 2-D pose (x, y, yaw) of a frame in ``map_frame``, composed along the transform tree of
``/tf`` and ``/tf_static`` (other robots' frames in ``/tf`` are simply not on the chain). A sensor's header frame
is used when the tree connects it to the map, else the robot frame (a sensor at the robot's centre). Dynamic
transforms are aligned to each reading by :func:`psgsl_pgm.ros._time.interpolate` (exact stamps exactly,
otherwise linear within the tolerance, never extrapolated).

Streams start and stop at different times. A reading outside the overlap of the streams it needs — a wind
sample or a detection array before the first or after the last transform of its frame's chain, a gas reading
outside its frame's transforms or outside the wind samples — is skipped and counted (:attr:`BagData.skipped`),
never extrapolated. Inside the overlap, a gap longer than the tolerance is still an error.

Every failure — a file that is no bag, a truncated or corrupt one, a missing topic, an unknown message type, a
reading no pose covers, stamps going backwards — is a ValueError that names the bag, the topic and the time.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..geometry._grid import GridMap
from ._time import DEFAULT_TOLERANCE, check_increasing, interpolate
from ._types import ANEMOMETER, DETECTIONS, GAS_SENSOR, UNIT_NAMES, typestore

__all__ = ["META_TOPIC", "ROLES", "BagData", "Detections", "bag_topics", "decode_messages", "read_bag"]

TF = "tf2_msgs/msg/TFMessage"
POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
VECTOR3 = "geometry_msgs/msg/Vector3Stamped"
OCCUPANCY = "nav_msgs/msg/OccupancyGrid"
STRING = "std_msgs/msg/String"

#: Role -> accepted message types, most preferred first.
ROLES = {
    "pose": (TF, POSE_COV, POSE_STAMPED),
    "gas": (GAS_SENSOR, "std_msgs/msg/Float32", "std_msgs/msg/Float64"),
    "wind": (VECTOR3, ANEMOMETER),
    "detections": (DETECTIONS,),
    "map": (OCCUPANCY,),
}
_REQUIRED = ("pose", "gas")

#: Fastest wind reading a bag may hold, m/s: beyond a category-5 hurricane (sustained winds of 70 m/s and more on
#: the Saffir-Simpson scale, NOAA National Hurricane Center). A faster reading is a unit or encoding slip (and
#: would overflow the wind estimate's sums of squares).
MAX_WIND_READING = 100.0

#: A JSON std_msgs/String the project's writer adds: the episode's world, source, seed and estimator.
META_TOPIC = "/psgsl/episode"


@dataclass(frozen=True, eq=False)
class Detections:
    """One Detection3DArray in the map frame.

    Attributes
    ----------
    t_ns : int
    camera : (3,) ndarray
        (x, y, yaw) of the array's header frame in the map: where the camera looked from.
    centre : (n, 2) ndarray
        Box centres in the map frame, m.
    half_size : (n, 2) ndarray
        Half the box's x and y size, m.
    yaw : (n,) ndarray
        Box orientation in the map frame.
    class_id : tuple of str
        Best hypothesis of each detection (highest score).
    score : (n,) ndarray
    """

    t_ns: int
    camera: np.ndarray
    centre: np.ndarray
    half_size: np.ndarray
    yaw: np.ndarray
    class_id: tuple
    score: np.ndarray


@dataclass(frozen=True, eq=False)
class BagData:
    """What :func:`read_bag` takes from a bag (times are integer nanoseconds).

    Attributes
    ----------
    path : Path
    topics : dict
        Role -> topic used (None: an optional role the bag lacks).
    start_ns : int
        The bag's first stamp; times in messages are "s into the bag" from here.
    pose_t : (p,) int64 ndarray, pose : (p, 3) ndarray
        Robot pose samples (x, y, yaw) in the map frame.
    gas_t : (m,) int64 ndarray, gas : (m,) ndarray, gas_xy : (m, 2) ndarray
        Gas readings as the messages hold them (in ``gas_units``) and where they were taken.
    wind_t : (w,) int64 ndarray, wind : (w, 2) ndarray
        Wind readings in the map frame, m/s.
    detections : list of Detections
    grid : GridMap or None
        The bag's OccupancyGrid (occupied: ≥ 50 or unknown).
    meta : dict
        The project's episode metadata (:data:`META_TOPIC`), or {}.
    skipped : dict
        Role -> number of its messages skipped for lying outside the overlap of the streams
        (``{"gas": 0, "wind": 0, "detections": 0}``; see the module docstring).
    """

    path: Path
    topics: dict
    start_ns: int
    pose_t: np.ndarray
    pose: np.ndarray
    gas_t: np.ndarray
    gas: np.ndarray
    gas_xy: np.ndarray
    wind_t: np.ndarray
    wind: np.ndarray
    detections: list = field(default_factory=list)
    grid: GridMap | None = None
    meta: dict = field(default_factory=dict)
    skipped: dict = field(default_factory=dict)
    gas_units: str | None = None
    """The gas messages' unit (:data:`psgsl_pgm.ros._types.UNIT_NAMES`), None when the type has none (a Float)."""

    def describe(self, t_ns: int) -> str:
        """A time for messages: seconds into the bag and the stamp."""
        return f"t = {(t_ns - self.start_ns) * 1e-9:.3f} s into the bag (stamp {t_ns * 1e-9:.9f})"


def _open(path):
    """A rosbags Reader on ``path`` (a bag folder, or a file inside one); ValueError naming the bag."""
    from rosbags.rosbag2 import Reader

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(2, "No such file or directory", str(path))
    if path.is_dir() or not (path.parent / "metadata.yaml").is_file():
        folder = path  # a bag folder, or a bare .mcap file (rosbags reads its own summary)
    else:
        folder = path.parent  # a storage file inside a bag folder
    try:
        reader = Reader(folder)
        reader.open()
    except Exception as exc:  # noqa: BLE001 - a file that is no bag: rosbags raises many kinds; one message here
        hint = ("; a Foxglove .mcap written by --record is for viewing: replay the .bag folder beside it"
                if path.suffix == ".mcap" else "")
        raise ValueError(f"{path}: not a readable ROS 2 bag ({_reason(exc)}){hint}") from None
    return folder, reader


def _reason(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def bag_topics(path) -> list:
    """Every topic of a bag, with its message type, its message count and the role it would fill.

    The roles are those :func:`read_bag` fills (pose, gas, wind, detections, map, …, :data:`ROLES`), chosen as
    :func:`read_bag` chooses them without ``topics``: a way to see what a robot's bag holds before reading it.

    Parameters
    ----------
    path : str or path-like
        A ROS 2 bag: its folder (sqlite3 or MCAP storage, with ``metadata.yaml``) or an ``.mcap`` file.

    Returns
    -------
    list of (str, str, int, str or None)
        ``(topic, message type, message count, role or None)``, sorted by topic.

    Raises
    ------
    FileNotFoundError
        No such file or folder.
    ValueError
        ``path`` is not a readable ROS 2 bag.
    ImportError
        The ``ros`` extra (rosbags) is not installed.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from psgsl_pgm import GridMap
    >>> from psgsl_pgm.ros import Episode
    >>> grid = GridMap(np.zeros((10, 20), bool), 0.1)           # a free 2 m × 1 m room, 0.1 m cells
    >>> t = np.arange(4.0)                                      # s
    >>> pose = np.stack([0.3 + 0.25 * t, np.full(4, 0.5), np.zeros(4)], axis=-1)   # x, y in m; yaw in rad
    >>> episode = Episode(grid=grid, pose_t=t, pose=pose, gas_t=t, gas=[2.0, 0.5, 2.0, 0.5],   # ppm
    ...                   wind_t=t, wind=np.tile([0.2, 0.0], (4, 1)), frame_t=[], frame_cells=[], frame_labels=[],
    ...                   threshold=1.0, meta={"seed": 0})
    >>> from psgsl_pgm.ros import bag_topics, write_bag
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     rows = bag_topics(write_bag(Path(folder) / "room.bag", episode))
    >>> [(topic, role) for topic, _, _, role in rows if role in ("gas", "wind")]
    [('/gas', 'gas'), ('/wind', 'wind')]
    """
    folder, reader = _open(path)
    try:
        chosen = _choose(folder, reader.connections, {}, strict=False)
        rows = []
        for c in sorted(reader.connections, key=lambda c: c.topic):
            role = next((r for r, t in chosen.items() if t == c.topic), None)
            rows.append((c.topic, c.msgtype, int(c.msgcount), role))
        return rows
    finally:
        reader.close()


def _choose(folder, connections, topics: dict, *, strict: bool = True) -> dict:
    """Role -> topic: the named ones (checked), the others by type preference; ValueError when ambiguous or a
    required role has no topic (``strict=False``: None for such a role, for listing)."""
    by_topic = {}
    for c in connections:
        by_topic.setdefault(c.topic, c.msgtype)
    bad = sorted(set(topics) - set(ROLES))
    if bad:
        raise ValueError(f"topics: unknown role(s) {bad}; roles are {list(ROLES)}")
    out = {}
    for role, types in ROLES.items():
        if topics.get(role) is not None:
            topic = topics[role]
            if topic not in by_topic:
                raise ValueError(f"{folder}: topic {topic} (given for {role}) is not in the bag; its topics: "
                                 f"{sorted(by_topic)}")
            if by_topic[topic] not in types:
                raise ValueError(f"{folder}: topic {topic} has type {by_topic[topic]}, but {role} needs one of "
                                 f"{list(types)}")
            out[role] = topic
            continue
        found = None
        for typ in types:
            cands = sorted(t for t, m in by_topic.items() if m == typ and not (typ == TF and t != "/tf"))
            if len(cands) == 1:
                found = cands[0]
                break
            if len(cands) > 1:
                if not strict:
                    break
                raise ValueError(f"{folder}: several {role} topics of type {typ}: {cands}; choose one with "
                                 f"--topics {role}=TOPIC")
        if found is None and role in _REQUIRED and strict:
            raise ValueError(f"{folder}: no {role} topic (a topic of type {' or '.join(types)}); the bag has "
                             f"{sorted(f'{t} [{m}]' for t, m in by_topic.items())}; name one with --topics {role}=TOPIC")
        out[role] = found
    return out


def _stamp(header) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _yaw(q) -> float:
    """Yaw of a quaternion (the rotation about z of its heading)."""
    return float(np.arctan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z)))


def _frame(name: str) -> str:
    return name.lstrip("/")


class _Tree:
    """The transform tree: dynamic edges (samples) and static ones, looked up as 2-D poses in the map frame."""

    def __init__(self, bag: str, describe, tolerance: float):
        self.parent: dict = {}  # child -> parent
        self.static: dict = {}  # child -> (3,)
        self.samples: dict = {}  # child -> ([t], [(x, y, yaw)], topic)
        self.bag, self.describe, self.tolerance = bag, describe, tolerance

    def add(self, parent: str, child: str, t_ns: int, pose, *, static: bool, topic: str) -> None:
        parent, child = _frame(parent), _frame(child)
        old = self.parent.get(child)
        if old is not None and old != parent:
            raise ValueError(f"{self.bag}: topic {topic} at {self.describe(t_ns)}: frame {child!r} has two parents, "
                             f"{old!r} and {parent!r}")
        self.parent[child] = parent
        if not np.isfinite(np.asarray(pose, dtype=np.float64)).all():
            raise ValueError(f"{self.bag}: topic {topic} at {self.describe(t_ns)}: the transform {parent} -> {child} "
                             f"holds a number that is not finite ({tuple(float(v) for v in pose)})")
        if static:
            self.static[child] = np.asarray(pose, dtype=np.float64)
        else:
            ts, ps, _ = self.samples.setdefault(child, ([], [], topic))
            ts.append(t_ns)
            ps.append(pose)

    def connected(self, frame: str, root: str) -> bool:
        frame, seen = _frame(frame), set()
        while frame != root:
            if frame in seen or frame not in self.parent:
                return False
            seen.add(frame)
            frame = self.parent[frame]
        return True

    def finish(self) -> None:
        for child, (ts, ps, topic) in list(self.samples.items()):
            t = np.asarray(ts, dtype=np.int64)
            check_increasing(t, f"{self.bag}: topic {topic} ({self.parent[child]} -> {child})",
                             describe=self.describe)
            self.samples[child] = (t, np.asarray(ps, dtype=np.float64), topic)

    def span(self, frame: str, root: str) -> tuple:
        """``(first, last)`` stamps (ns) at which every dynamic edge from ``root`` down to ``frame`` has samples on
        both sides or at the time (a chain of static edges only: all times)."""
        lo, hi = np.iinfo(np.int64).min, np.iinfo(np.int64).max
        f = _frame(frame)
        while f != root:
            if f in self.samples:
                t = self.samples[f][0]
                lo, hi = max(lo, int(t[0])), min(hi, int(t[-1]))
            f = self.parent[f]
        return lo, hi

    def inside(self, t_ns: np.ndarray, frames, root: str) -> np.ndarray:
        """(m,) bool: each time lies within :meth:`span` of its frame (``frames``: one name per time)."""
        t_ns = np.asarray(t_ns, dtype=np.int64)
        frames = np.asarray(frames, dtype=object)
        ok = np.ones(len(t_ns), dtype=bool)
        for f in dict.fromkeys(frames.tolist()):
            if f == root:
                continue
            lo, hi = self.span(f, root)
            sel = frames == f
            ok[sel] = (t_ns[sel] >= lo) & (t_ns[sel] <= hi)
        return ok

    def lookup(self, frame: str, root: str, t_ns) -> np.ndarray:
        """(m, 3) poses of ``frame`` in ``root`` at the times ``t_ns``."""
        t_ns = np.asarray(t_ns, dtype=np.int64)
        chain, f = [], _frame(frame)
        while f != root:
            chain.append(f)
            f = self.parent[f]
        pose = np.zeros((len(t_ns), 3))  # the identity: composing with it is exact
        for child in reversed(chain):  # from the root down: pose = pose ∘ edge
            if child in self.samples:
                t, p, topic = self.samples[child]
                edge = interpolate(t, p, t_ns, tolerance=self.tolerance, angle_columns=(2,), describe=self.describe,
                                   where=f"{self.bag}: topic {topic} ({self.parent[child]} -> {child})")
            else:
                edge = np.broadcast_to(self.static[child], (len(t_ns), 3))
            c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
            pose = np.stack([pose[:, 0] + c * edge[:, 0] - s * edge[:, 1],
                             pose[:, 1] + s * edge[:, 0] + c * edge[:, 1], pose[:, 2] + edge[:, 2]], axis=-1)
        return pose


def read_bag(path, *, topics=None, map_frame: str = "map", robot_frame: str = "base_link",
             tolerance: float = DEFAULT_TOLERANCE) -> BagData:
    """Read the pose, gas, wind, detections and map of a ROS 2 bag (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The bag folder (``metadata.yaml`` with ``.db3`` or ``.mcap`` files), a file inside it, or a bare ROS 2
        ``.mcap`` file.
    topics : dict, optional, keyword-only
        Role -> topic, overriding the discovery by type (roles: :data:`ROLES`).
    map_frame, robot_frame : str, keyword-only
        The fixed frame and the robot's frame.
    tolerance : float, keyword-only
        Seconds: how far a pose or transform sample may lie from a reading it is interpolated to.

    Returns
    -------
    BagData

    Raises
    ------
    FileNotFoundError
        No such file or folder.
    ValueError
        ``path`` is not a readable ROS 2 bag; a topic of an unknown message type, or messages that cannot be
        decoded or aligned (the message names the bag and the topic); a negative ``tolerance``; a ``topics`` entry
        that is not a topic name.
    TypeError
        ``topics`` is not a dict.
    ImportError
        The ``ros`` extra (rosbags) is not installed.

    Examples
    --------
    A round trip through :func:`write_bag`:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from psgsl_pgm import GridMap
    >>> from psgsl_pgm.ros import Episode, read_bag, write_bag
    >>> t = np.arange(4.0)                                      # s
    >>> pose = np.stack([0.3 + 0.25 * t, np.full(4, 0.5), np.zeros(4)], axis=-1)   # x, y in m; yaw in rad
    >>> episode = Episode(grid=GridMap(np.zeros((10, 20), bool), 0.1), pose_t=t, pose=pose, gas_t=t,
    ...                   gas=[2.0, 0.5, 2.0, 0.5], wind_t=t, wind=np.tile([0.2, 0.0], (4, 1)), frame_t=[],
    ...                   frame_cells=[], frame_labels=[])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     data = read_bag(write_bag(Path(folder) / "room.bag", episode))
    >>> data.gas.tolist(), data.grid.shape
    ([2.0, 0.5, 2.0, 0.5], (10, 20))
    """
    from ._types import require

    require()
    if not (isinstance(tolerance, (int, float)) and np.isfinite(tolerance) and tolerance >= 0):
        raise ValueError(f"tolerance must be a non-negative number of seconds, got {tolerance!r}")
    if topics is not None and not isinstance(topics, dict):
        raise TypeError(f"topics must be a dict of role -> topic, got {type(topics).__name__}")
    topics = dict(topics or {})
    for role, topic in topics.items():
        if not isinstance(topic, str) or not topic.startswith("/"):
            raise ValueError(f"topics: the {role} topic must be a name starting with '/', got {topic!r}")
    map_frame, robot_frame = _frame(map_frame), _frame(robot_frame)
    _, reader = _open(path)
    name = str(path)
    try:
        chosen = _choose(name, reader.connections, topics)
        store = typestore(reader.connections)
        wanted = {t for t in chosen.values() if t is not None}
        tf_topics = {c.topic for c in reader.connections if c.msgtype == TF and c.topic in ("/tf", "/tf_static")}
        if any(c.topic == chosen["pose"] and c.msgtype == TF for c in reader.connections):
            tf_topics.add(chosen["pose"])  # a namespaced transform topic named with --topics pose=/robot1/tf
        wanted |= tf_topics
        if any(c.topic == "/tf_static" for c in reader.connections):
            wanted.add("/tf_static")
        if any(c.topic == META_TOPIC and c.msgtype == STRING for c in reader.connections):
            wanted.add(META_TOPIC)
        conns = [c for c in reader.connections if c.topic in wanted]
        for c in conns:
            if c.msgtype not in store.types:
                raise ValueError(f"{name}: topic {c.topic} has the unknown message type {c.msgtype} (neither a "
                                 "ROS 2 Humble type, nor olfaction_msgs / vision_msgs, nor defined in the bag)")
        raw = _messages(name, reader, conns, store)
    finally:
        reader.close()
    return decode_messages(name, chosen, raw, tf_topics=tf_topics, map_frame=map_frame, robot_frame=robot_frame,
                           tolerance=tolerance, path=Path(path))


def decode_messages(name: str, chosen: dict, raw: list, *, tf_topics, map_frame: str, robot_frame: str,
                    tolerance: float, path=None) -> BagData:
    """The arrays of :class:`BagData` from decoded messages, the one conversion of a bag and of a live stream.

    Parameters
    ----------
    name : str
        The source for messages (the bag, or the live node's domain).
    chosen : dict
        Role -> topic (every role of :data:`ROLES`; None: absent).
    raw : list of (topic, receive stamp ns, message)
        In receive order; a message is anything with the ROS message's attribute names (rosbags' classes, the
        Cyclone DDS structs of :mod:`psgsl_pgm.ros._dds`).
    tf_topics : set of str, keyword-only
        The transform topics (``/tf``, ``/tf_static``, a namespaced one).
    map_frame, robot_frame : str, keyword-only
    tolerance : float, keyword-only
        Seconds (:func:`psgsl_pgm.ros._time.interpolate`).
    path : Path, optional, keyword-only
        ``BagData.path`` (default: ``name``).

    Returns
    -------
    BagData
    """
    start = min((t for _, t, _ in raw), default=0)

    def describe(t_ns: int) -> str:
        return f"t = {(t_ns - start) * 1e-9:.3f} s into the bag (stamp {t_ns * 1e-9:.9f})"

    tree = _Tree(name, describe, tolerance)
    pose_is_tf = chosen["pose"] in tf_topics
    gas_t, gas_v, gas_frames, gas_units = [], [], [], {}
    wind_t, wind_v, wind_frames, wind_kind = [], [], [], None
    dets, grid, meta = [], None, {}
    for topic, t_recv, msg in raw:
        if topic in tf_topics:
            for tr in msg.transforms:
                if not pose_is_tf and _frame(tr.child_frame_id) == robot_frame:
                    continue  # the robot's pose comes from the pose topic; /tf still places the sensors
                q, v = tr.transform.rotation, tr.transform.translation
                tree.add(tr.header.frame_id, tr.child_frame_id, _stamp(tr.header), (v.x, v.y, _yaw(q)),
                         static=topic.endswith("tf_static"), topic=topic)
        elif topic == chosen["pose"]:
            p = msg.pose.pose if hasattr(msg.pose, "pose") else msg.pose
            tree.add(msg.header.frame_id, robot_frame, _stamp(msg.header), (p.position.x, p.position.y, _yaw(p.orientation)),
                     static=False, topic=topic)
        if topic == chosen["gas"]:
            if hasattr(msg, "header"):
                gas_t.append(_stamp(msg.header))
                gas_v.append(float(msg.raw))
                gas_frames.append(_frame(msg.header.frame_id))
                gas_units.setdefault(int(msg.raw_units), _stamp(msg.header))
            else:
                gas_t.append(t_recv)
                gas_v.append(float(msg.data))
                gas_frames.append(robot_frame)
        if topic == chosen["wind"]:
            wind_t.append(_stamp(msg.header))
            wind_frames.append(_frame(msg.header.frame_id))
            if hasattr(msg, "vector"):
                wind_kind = "vector"
                wind_v.append((msg.vector.x, msg.vector.y))
            else:
                wind_kind = "anemometer"
                wind_v.append((float(msg.wind_speed), float(msg.wind_direction)))
        if topic == chosen["detections"]:
            dets.append(msg)
        if topic == chosen["map"] and grid is None:
            grid = _grid(msg)
        if topic == META_TOPIC:
            try:
                meta = json.loads(msg.data)
            except ValueError:
                raise ValueError(f"{name}: topic {META_TOPIC} at {describe(t_recv)} is not JSON") from None
    tree.finish()
    if not tree.connected(robot_frame, map_frame):
        raise ValueError(f"{name}: topic {chosen['pose']}: no transform chain from {map_frame!r} to {robot_frame!r} "
                         f"(frames with a parent: {sorted(tree.parent)}); give --map-frame / --robot-frame")
    if not gas_t:
        raise ValueError(f"{name}: topic {chosen['gas']} holds no message")
    if chosen["wind"] is not None and not wind_t:
        chosen["wind"] = None  # an empty wind topic: a bag without wind

    def frame_of(f: str) -> str:
        return f if f and tree.connected(f, map_frame) else robot_frame

    skipped = {"gas": 0, "wind": 0, "detections": 0}
    wind_t = np.asarray(wind_t, dtype=np.int64)
    if chosen["wind"] is not None:
        check_increasing(wind_t, f"{name}: topic {chosen['wind']}", describe=describe)
    wv = np.asarray(wind_v, dtype=np.float64).reshape(-1, 2)
    speed = np.abs(wv[:, 0]) if wind_kind == "anemometer" else np.hypot(wv[:, 0], wv[:, 1])
    bad = np.flatnonzero(~np.isfinite(wv).all(axis=1) | ~(speed <= MAX_WIND_READING))
    if len(bad):
        raise ValueError(f"{name}: topic {chosen['wind']} at {describe(int(wind_t[bad[0]]))}: the reading "
                         f"{tuple(float(v) for v in wv[bad[0]])} is not a wind (finite, at most "
                         f"{MAX_WIND_READING:g} m/s)")
    frames = [f if f == map_frame else frame_of(f) for f in wind_frames]
    # wind samples the transforms of their frame cover (a map-frame sample: the robot's, for its pose)
    keep = tree.inside(wind_t, [robot_frame if f == map_frame else f for f in frames], map_frame)
    skipped["wind"] = int((~keep).sum())
    wind_t, wv, frames = wind_t[keep], wv[keep], [f for f, k in zip(frames, keep) if k]
    yaw = _per_frame(tree, wind_t, frames, map_frame)[:, 2]
    if wind_kind == "vector":
        c, s = np.cos(yaw), np.sin(yaw)
        wind = np.stack([c * wv[:, 0] - s * wv[:, 1], s * wv[:, 0] + c * wv[:, 1]], axis=-1)
    else:  # speed, and the direction the wind comes from in the sensor frame: blowing towards direction + π
        heading = wv[:, 1] + yaw + np.pi
        wind = wv[:, :1] * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    gas_t = np.asarray(gas_t, dtype=np.int64)
    check_increasing(gas_t, f"{name}: topic {chosen['gas']}", describe=describe)
    bad = np.flatnonzero(~np.isfinite(np.asarray(gas_v, dtype=np.float64)))
    if len(bad):
        raise ValueError(f"{name}: topic {chosen['gas']} at {describe(int(gas_t[bad[0]]))}: the reading "
                         f"{gas_v[bad[0]]} is not a finite number")
    gas_frames = [frame_of(f) for f in gas_frames]
    keep = tree.inside(gas_t, gas_frames, map_frame)
    if chosen["wind"] is not None:  # a gas reading needs the wind on both sides too
        keep &= (gas_t >= wind_t[0]) & (gas_t <= wind_t[-1]) if len(wind_t) else False
    skipped["gas"] = int((~keep).sum())
    if not keep.any():
        lo, hi = tree.span(robot_frame, map_frame)
        spans = [f"gas {describe(int(gas_t[0]))} to {describe(int(gas_t[-1]))}",
                 f"pose {describe(lo)} to {describe(hi)}"]
        if chosen["wind"] is not None:
            spans.append(f"wind {describe(int(wind_t[0]))} to {describe(int(wind_t[-1]))}" if len(wind_t)
                         else "no wind sample the pose covers")
        raise ValueError(f"{name}: topic {chosen['gas']}: no gas reading lies where the streams overlap "
                         f"({'; '.join(spans)})")
    gas_t, gas_v = gas_t[keep], np.asarray(gas_v, dtype=np.float64)[keep]
    if len(gas_units) > 1:
        (u0, t0), (u1, t1) = sorted(gas_units.items(), key=lambda kv: kv[1])[:2]
        raise ValueError(f"{name}: topic {chosen['gas']}: the readings change unit at {describe(t1)}: raw_units "
                         f"{UNIT_NAMES.get(u0, u0)} from {describe(t0)}, then {UNIT_NAMES.get(u1, u1)}")
    units = UNIT_NAMES.get(next(iter(gas_units)), f"raw_units {next(iter(gas_units))}") if gas_units else None
    gas_xy = _per_frame(tree, gas_t, [f for f, k in zip(gas_frames, keep) if k], map_frame)[:, :2]
    detections, skipped["detections"] = _detections(name, chosen["detections"], dets, tree, frame_of, map_frame,
                                                    robot_frame, describe)
    pose_t = np.unique(np.concatenate([gas_t, wind_t] + [[d.t_ns] for d in detections]))
    pose = tree.lookup(robot_frame, map_frame, pose_t)
    if not np.isfinite(gas_xy).all() or not np.isfinite(wind).all():
        raise ValueError(f"{name}: a gas or wind reading or its pose is not finite")
    return BagData(Path(name) if path is None else path, chosen, int(start), pose_t, pose, gas_t, np.asarray(gas_v),
                   gas_xy, wind_t, wind, detections, grid, meta, skipped, units)


def _per_frame(tree: _Tree, t_ns: np.ndarray, frames: list, map_frame: str) -> np.ndarray:
    """(m, 3) pose of each reading's frame at its time (readings grouped by frame)."""
    out = np.zeros((len(t_ns), 3))
    frames = np.asarray(frames, dtype=object)
    for f in dict.fromkeys(frames.tolist()):
        sel = frames == f
        out[sel] = 0.0 if f == map_frame else tree.lookup(f, map_frame, t_ns[sel])
    return out


def _messages(name: str, reader, conns, store) -> list:
    """``[(topic, receive time, message)]`` in bag order; a message that does not decode names its topic and time."""
    out = []
    it = reader.messages(connections=conns)
    while True:
        try:
            conn, t, data = next(it)
        except StopIteration:
            break
        except Exception as exc:  # noqa: BLE001 - a truncated or corrupt file: rosbags' storage errors vary
            where = f" after {out[-1][0]} at stamp {out[-1][1] * 1e-9:.9f}" if out else ""
            raise ValueError(f"{name}: the bag is truncated or corrupt{where} ({_reason(exc)})") from None
        try:
            msg = store.deserialize_cdr(data, conn.msgtype)
        except Exception as exc:  # noqa: BLE001 - a message that does not decode as its type
            raise ValueError(f"{name}: topic {conn.topic} at stamp {t * 1e-9:.9f}: the message does not decode as "
                             f"{conn.msgtype} ({_reason(exc)})") from None
        out.append((conn.topic, int(t), msg))
    return out


def _grid(msg) -> GridMap:
    """A GridMap from a nav_msgs/OccupancyGrid (occupied: ≥ 50, or unknown −1). Rotated maps are refused."""
    info = msg.info
    q = info.origin.orientation
    if abs(_yaw(q)) > 1e-9:
        raise ValueError(f"the OccupancyGrid's origin is rotated (yaw {_yaw(q):.3g} rad); only axis-aligned maps are read")
    data = np.asarray(msg.data, dtype=np.int16).reshape(int(info.height), int(info.width))
    occ = (data >= 50) | (data < 0)
    # the resolution is a float32 field: its shortest decimal (0.05, not 0.0500000007) is what the map meant
    res = float(np.format_float_positional(np.float32(info.resolution), unique=True))
    return GridMap(occ, res, (float(info.origin.position.x), float(info.origin.position.y)))


def _detections(name, topic, msgs, tree, frame_of, map_frame, robot_frame, describe) -> tuple:
    """``(detections, skipped)``: the arrays whose camera frame the transforms cover, and how many are not."""
    out = []
    if not msgs:
        return out, 0
    stamps = np.array([_stamp(m.header) for m in msgs], dtype=np.int64)
    check_increasing(stamps, f"{name}: topic {topic}", describe=describe)
    frames = []
    for m in msgs:
        f = _frame(m.header.frame_id)
        frames.append(map_frame if f == map_frame else frame_of(f))
    keep = tree.inside(stamps, [robot_frame if f == map_frame else f for f in frames], map_frame)
    for m, t, f, k in zip(msgs, stamps, frames, keep):
        if not k:
            continue
        cam = tree.lookup(robot_frame if f == map_frame else f, map_frame, [t])[0]  # where the camera looked from
        ref = np.zeros(3) if f == map_frame else cam  # the frame the boxes are given in
        n = len(m.detections)
        centre, half, yaw, cls, score = np.zeros((n, 2)), np.zeros((n, 2)), np.zeros(n), [], np.zeros(n)
        c, s = np.cos(ref[2]), np.sin(ref[2])
        for i, d in enumerate(m.detections):
            if not d.results:
                raise ValueError(f"{name}: topic {topic} at {describe(int(t))}: detection {i} has no hypothesis")
            best = max(d.results, key=lambda r: r.hypothesis.score)
            p = d.bbox.center.position
            centre[i] = (ref[0] + c * p.x - s * p.y, ref[1] + s * p.x + c * p.y)
            half[i] = (0.5 * d.bbox.size.x, 0.5 * d.bbox.size.y)
            yaw[i] = ref[2] + _yaw(d.bbox.center.orientation)
            cls.append(str(best.hypothesis.class_id))
            score[i] = float(best.hypothesis.score)
        out.append(Detections(int(t), cam, centre, half, yaw, tuple(cls), score))
    return out, int((~keep).sum())
