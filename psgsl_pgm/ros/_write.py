"""Writing an episode as a ROS 2 bag with the message types a robot publishes (read back by :func:`read_bag`).

Topics (all stamps = the episode's times from :data:`psgsl_pgm.ros._episode.START_NS`):

* ``/tf`` (``tf2_msgs/msg/TFMessage``): ``map`` -> ``base_link`` at every pose sample;
* ``/gas`` (``olfaction_msgs/msg/GasSensor``): ``raw`` in ppm (``raw_units`` = UNITS_PPM);
* ``/anemometer`` (``olfaction_msgs/msg/Anemometer``): speed, and the direction the wind comes from in
  ``base_link`` (GADEN's convention; float32);
* ``/wind`` (``geometry_msgs/msg/Vector3Stamped``): the same reading in ``map`` at full precision;
* ``/detections`` (``vision_msgs/msg/Detection3DArray``): one detection per cell reported as an object — class id,
  a cell-sized box, in ``base_link``;
* ``/map`` (``nav_msgs/msg/OccupancyGrid``): the occupancy grid (0 free, 100 occupied);
* ``/psgsl/episode`` (``std_msgs/msg/String``): JSON — world, source, seed, estimator, settings, threshold.

The Anemometer message holds float32 fields; ``/wind`` carries the reading at float64 so that a replay is exact
(the reader prefers it). The bag is written into a temporary folder beside the target and renamed into place:
a bag is there whole or not at all.
"""

from __future__ import annotations

import json
import os
import shutil
import uuid
from pathlib import Path

import numpy as np

from ._episode import START_NS, Episode, stamp_ns
from ._time import interpolate, wrap_angle
from ._types import ANEMOMETER, DETECTIONS, GAS_SENSOR, UNITS_PPM, typestore

__all__ = ["STORAGES", "replace_folder", "write_bag"]

#: Storage formats of :func:`write_bag`.
STORAGES = ("mcap", "sqlite3")


def replace_folder(path, write) -> Path:
    """Call ``write(tmp)`` for a temporary folder path beside ``path`` (not yet existing), then move it to ``path``
    (replacing an older one). An interruption leaves the old folder or the new one, never a half-written one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tag = uuid.uuid4().hex[:8]
    work = path.with_name(f".{path.name}.{tag}.part")  # a hidden folder beside the target
    old = path.with_name(f".{path.name}.{tag}.old")
    try:
        work.mkdir()
        tmp = work / path.name  # the folder keeps its final name inside (rosbags names its files after it)
        write(tmp)
        if path.exists():
            os.replace(path, old)
        os.replace(tmp, path)
    finally:
        for leftover in (work, old):
            if leftover.exists():
                shutil.rmtree(leftover, ignore_errors=True)
    return path


def write_bag(path, episode: Episode, *, storage: str = "mcap") -> Path:
    """Write ``episode`` as a ROS 2 bag folder at ``path`` (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The bag folder to create (replaced if it exists).
    episode : Episode
    storage : {"mcap", "sqlite3"}, keyword-only

    Returns
    -------
    Path

    Raises
    ------
    TypeError
        ``episode`` is not an :class:`Episode`.
    ValueError
        ``storage`` is neither ``"mcap"`` nor ``"sqlite3"``.
    ImportError
        The ``ros`` extra (rosbags) is not installed.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from psgsl_pgm import GridMap
    >>> from psgsl_pgm.ros import Episode, bag_topics, write_bag
    >>> t = np.arange(3.0)                                      # s
    >>> episode = Episode(grid=GridMap(np.zeros((10, 20), bool), 0.1), pose_t=t, pose=np.zeros((3, 3)) + 0.5,
    ...                   gas_t=t, gas=[0.0, 1.5, 3.0], wind_t=t, wind=np.zeros((3, 2)), frame_t=[], frame_cells=[],
    ...                   frame_labels=[])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = write_bag(Path(folder) / "room.bag", episode, storage="sqlite3")
    ...     print(path.name, sorted(p.suffix for p in path.iterdir()))
    ...     print([(topic, n) for topic, _, n, role in bag_topics(path) if role == "gas"])
    room.bag ['.db3', '.yaml']
    [('/gas', 3)]
    """
    if not isinstance(episode, Episode):
        raise TypeError(f"episode must be a psgsl_pgm.ros.Episode, got {type(episode).__name__}")
    if storage not in STORAGES:
        raise ValueError(f"storage must be one of {STORAGES}, got {storage!r}")
    return replace_folder(path, lambda tmp: _write(tmp, episode, storage))


def _write(folder: Path, ep: Episode, storage: str) -> None:
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = typestore()
    T = store.types
    Header, Time = T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    Vec3, Quat = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    Point, Pose = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Pose"]

    def header(t_ns: int, frame: str):
        return Header(stamp=Time(sec=int(t_ns // 1_000_000_000), nanosec=int(t_ns % 1_000_000_000)), frame_id=frame)

    def quat(yaw: float):
        return Quat(x=0.0, y=0.0, z=float(np.sin(yaw / 2)), w=float(np.cos(yaw / 2)))

    msgs = []  # (stamp, topic, type, message)
    pose_ns = stamp_ns(ep.pose_t)
    TS, Tr = T["geometry_msgs/msg/TransformStamped"], T["geometry_msgs/msg/Transform"]
    for t, (x, y, yaw) in zip(pose_ns, ep.pose):
        tr = TS(header=header(t, "map"), child_frame_id="base_link",
                transform=Tr(translation=Vec3(x=float(x), y=float(y), z=0.0), rotation=quat(yaw)))
        msgs.append((t, "/tf", "tf2_msgs/msg/TFMessage", T["tf2_msgs/msg/TFMessage"](transforms=[tr])))
    Gas = T[GAS_SENSOR]
    for t, v in zip(stamp_ns(ep.gas_t), ep.gas):
        msgs.append((t, "/gas", GAS_SENSOR, Gas(header=header(t, "base_link"), technology=51, manufacturer=0, mpn=0,
                                                raw=float(v), raw_units=UNITS_PPM, raw_air=0.0, calib_a=0.0,
                                                calib_b=0.0)))
    wind_ns = stamp_ns(ep.wind_t)
    yaw = interpolate(pose_ns, ep.pose[:, 2:], wind_ns, tolerance=0.0, where="episode pose at the wind readings")[:, 0]
    wind = np.asarray(ep.wind, dtype=np.float64)
    speed = np.hypot(wind[:, 0], wind[:, 1])
    upwind = wrap_angle(np.arctan2(wind[:, 1], wind[:, 0]) + np.pi - yaw)  # where it comes from, in base_link
    Anem, V3S = T[ANEMOMETER], T["geometry_msgs/msg/Vector3Stamped"]
    for t, s, d, (wx, wy) in zip(wind_ns, speed, upwind, wind):
        msgs.append((t, "/anemometer", ANEMOMETER, Anem(header=header(t, "base_link"), sensor_label="anemometer",
                                                        wind_speed=float(s), wind_direction=float(d))))
        msgs.append((t, "/wind", "geometry_msgs/msg/Vector3Stamped",
                     V3S(header=header(t, "map"), vector=Vec3(x=float(wx), y=float(wy), z=0.0))))
    frame_ns = stamp_ns(ep.frame_t)
    cam = interpolate(pose_ns, ep.pose, frame_ns, tolerance=0.0, where="episode pose at the camera frames")
    D3, DA = T["vision_msgs/msg/Detection3D"], T[DETECTIONS]
    OHP, OH = T["vision_msgs/msg/ObjectHypothesisWithPose"], T["vision_msgs/msg/ObjectHypothesis"]
    PWC, BB = T["geometry_msgs/msg/PoseWithCovariance"], T["vision_msgs/msg/BoundingBox3D"]
    res = float(ep.grid.resolution)
    for t, (cx, cy, cyaw), cells, labels in zip(frame_ns, cam, ep.frame_cells, ep.frame_labels):
        xy = ep.grid.cell_to_world(np.asarray(cells, dtype=np.int64).reshape(-1, 2)) - (cx, cy)
        c, s = np.cos(cyaw), np.sin(cyaw)
        local = np.stack([c * xy[:, 0] + s * xy[:, 1], -s * xy[:, 0] + c * xy[:, 1]], axis=-1)  # in base_link
        dets = []
        for (px, py), label in zip(local, labels):
            centre = Pose(position=Point(x=float(px), y=float(py), z=0.0), orientation=quat(0.0))
            hyp = OHP(hypothesis=OH(class_id=str(label), score=1.0),
                      pose=PWC(pose=centre, covariance=np.zeros(36)))
            dets.append(D3(header=header(t, "base_link"), results=[hyp],
                           bbox=BB(center=centre, size=Vec3(x=res, y=res, z=res)), id=""))
        msgs.append((t, "/detections", DETECTIONS, DA(header=header(t, "base_link"), detections=dets)))
    t0 = int(min([START_NS] + [m[0] for m in msgs]))
    msgs.append((t0, "/map", "nav_msgs/msg/OccupancyGrid", _occupancy(T, header(t0, "map"), ep.grid)))
    meta = dict(ep.meta, threshold=float(ep.threshold))
    msgs.append((t0, "/psgsl/episode", "std_msgs/msg/String", T["std_msgs/msg/String"](data=json.dumps(meta))))
    msgs.sort(key=lambda m: m[0])
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(folder, version=9, storage_plugin=plugin) as writer:
        conns = {}
        for t, topic, typ, msg in msgs:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, typ, typestore=store)
            writer.write(conns[topic], int(t), store.serialize_cdr(msg, typ))


def _occupancy(T, header, grid):
    info = T["nav_msgs/msg/MapMetaData"](
        map_load_time=header.stamp, resolution=float(grid.resolution), width=int(grid.shape[1]),
        height=int(grid.shape[0]),
        origin=T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=float(grid.origin[0]),
                                                                                   y=float(grid.origin[1]), z=0.0),
                                           orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)))
    data = np.where(grid.occupancy, 100, 0).astype(np.int8).ravel()
    return T["nav_msgs/msg/OccupancyGrid"](header=header, info=info, data=data)
