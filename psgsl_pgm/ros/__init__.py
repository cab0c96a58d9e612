"""A robot's data in and out: ROS 2 bags (sqlite3 and MCAP storage) and Foxglove MCAP, without a ROS install.

* :func:`read_bag` / :func:`bag_topics` — pose (``/tf`` or a pose topic), gas (``olfaction_msgs/GasSensor`` or a
  Float), wind (``olfaction_msgs/Anemometer`` or a ``Vector3Stamped``), detections (``vision_msgs/
  Detection3DArray``) and the map (``nav_msgs/OccupancyGrid``), found by type, time-aligned to the pose
  (:mod:`psgsl_pgm.ros._time`);
* :func:`write_bag` — an :class:`Episode` as a ROS 2 bag with those message types;
* :func:`write_foxglove` — an :class:`Episode` as MCAP in Foxglove's schemas (grids, scene updates, poses);
* :class:`DdsEndpoint` — live ROS 2 topics over DDS (Cyclone DDS) under ROS 2's names, types and type hashes
  (:func:`dds_topic`, :func:`dds_type_name`, :func:`type_hash`), for ``psgsl live``.

The format code lives here; ``psgsl replay`` and ``--record`` (:mod:`psgsl_pgm.experiment`) drive it.
rosbags, mcap, foxglove-sdk and cyclonedds come with the ``ros`` extra (``pip install "psgsl-pgm[ros]"``); they are
imported only when a bag or MCAP file is read or written or a DDS endpoint made, and a missing one is an ImportError
naming the extra.
"""

from ._dds import DdsEndpoint, dds_topic, dds_type_name, type_hash
from ._episode import START_NS, Episode
from ._foxglove import write_foxglove
from ._read import META_TOPIC, ROLES, BagData, Detections, bag_topics, read_bag
from ._time import DEFAULT_TOLERANCE
from ._types import MISSING_EXTRA, require
from ._write import STORAGES, write_bag

__all__ = [
    "DEFAULT_TOLERANCE",
    "META_TOPIC",
    "MISSING_EXTRA",
    "ROLES",
    "START_NS",
    "STORAGES",
    "BagData",
    "DdsEndpoint",
    "Detections",
    "Episode",
    "bag_topics",
    "dds_topic",
    "dds_type_name",
    "read_bag",
    "require",
    "type_hash",
    "write_bag",
    "write_foxglove",
]
