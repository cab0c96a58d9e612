"""Small bags for the tests: a synthetic episode (no simulation) written by the project's writer, and a copier
that rewrites a bag message by message (to break it in one controlled way)."""

from __future__ import annotations

import numpy as np

from psgsl_pgm.ros import Episode, write_bag
from psgsl_pgm.ros._types import typestore
from psgsl_pgm.sim import default_house


def synthetic_episode(n: int = 10) -> Episode:
    """The robot drives along the hallway of the embedded house (seed 0) at 0.25 m/s, one gas and wind reading
    per second, a frame every third second with a tv reported 1 m ahead."""
    grid = default_house(0).grid
    t = np.arange(n, dtype=np.float64)
    pose = np.stack([1.05 + 0.25 * t, np.full(n, 6.05), np.zeros(n)], axis=-1)
    frame_t = t[::3]
    cells = [grid.world_to_cell(pose[int(k), :2] + (1.0, 0.0))[None] for k in frame_t]
    return Episode(grid=grid, pose_t=t, pose=pose, gas_t=t, gas=np.where(t % 2 == 0, 2.0, 0.5), wind_t=t,
                   wind=np.tile([0.2, -0.05], (n, 1)), frame_t=frame_t, frame_cells=cells,
                   frame_labels=[["tv"] for _ in frame_t], threshold=1.0, meta={"seed": 0})


def episode_bag(path, storage: str = "mcap", n: int = 10):
    return write_bag(path, synthetic_episode(n), storage=storage)


def rewrite(src, dst, *, keep=lambda topic, t, msg: True, change=lambda topic, t, msg: msg, storage="sqlite3"):
    """Copy the bag ``src`` to ``dst``, dropping messages where ``keep`` is false and replacing each by ``change``."""
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer

    store = typestore()
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Reader(src) as reader, Writer(dst, version=9, storage_plugin=plugin) as writer:
        conns = {}
        for conn, t, raw in reader.messages():
            msg = store.deserialize_cdr(raw, conn.msgtype)
            if not keep(conn.topic, t, msg):
                continue
            msg = change(conn.topic, t, msg)
            if conn.topic not in conns:
                conns[conn.topic] = writer.add_connection(conn.topic, conn.msgtype, typestore=store)
            writer.write(conns[conn.topic], t, store.serialize_cdr(msg, conn.msgtype))
    return dst
