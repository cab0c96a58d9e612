"""An episode as MCAP in Foxglove's schemas (foxglove-sdk): open it in Foxglove and scrub through the search.

Channels (frame ``map``; log times = the episode's stamps, :data:`psgsl_pgm.ros._episode.START_NS` + t):

* ``/map`` (``foxglove.Grid``): occupancy (uint8: 0 free, 100 occupied), once;
* ``/objects`` (``foxglove.SceneUpdate``): one cube (footprint box, height) and label per object, once;
* ``/posterior/<variant>`` (``foxglove.Grid``): p(s | ...) of each variant (float32) after every step;
* ``/semantics/best_class`` (``foxglove.Grid``): the most likely class per cell (uint8; the channel's metadata
  ``classes`` names the values) after every step, when the variants keep class beliefs;
* ``/tf`` (``foxglove.FrameTransform``): ``map`` -> ``base_link`` at every pose sample;
* ``/robot/pose`` (``foxglove.PoseInFrame``): the robot's pose at every pose sample;
* ``/robot/path`` (``foxglove.PosesInFrame``): the path so far, after every step;
* ``/robot/next`` (``foxglove.PoseInFrame``): the pose chosen next (tour stop or policy choice);
* ``/gas`` (JSON): ``{"ppm": value, "hit": value >= threshold}`` per reading;
* ``/wind`` (``foxglove.SceneUpdate``): an arrow at the robot along the wind, length = speed (m/s).

The file is written to a temporary file beside the target and renamed into place (whole or not at all).
"""

from __future__ import annotations

import json

import numpy as np

from ..runs._runner import atomic_write
from ._episode import Episode, stamp_ns

__all__ = ["write_foxglove"]


def _require():
    try:
        import foxglove  # noqa: F401
    except ModuleNotFoundError as err:
        if (err.name or "").split(".")[0] != "foxglove":
            raise
        from ._types import MISSING_EXTRA

        raise ImportError(MISSING_EXTRA) from err


def _ts(t):
    from foxglove import messages as m

    t = int(t)
    return m.Timestamp(t // 1_000_000_000, t % 1_000_000_000)


def _quat(yaw):
    from foxglove import messages as m

    return m.Quaternion(x=0.0, y=0.0, z=float(np.sin(yaw / 2)), w=float(np.cos(yaw / 2)))


def _pose(x, y, yaw=0.0, z=0.0):
    from foxglove import messages as m

    return m.Pose(position=m.Vector3(x=float(x), y=float(y), z=float(z)), orientation=_quat(yaw))


def _grid_msg(grid, t, values, kind):
    """A ``foxglove.Grid`` of ``values`` (H, W) on ``grid``'s cells in ``map``, row by row from the origin."""
    from foxglove import messages as m

    values = np.ascontiguousarray(values)
    w = grid.shape[1]
    return m.Grid(timestamp=_ts(t), frame_id="map", pose=_pose(grid.origin[0], grid.origin[1]), column_count=w,
                  cell_size=m.Vector2(x=float(grid.resolution), y=float(grid.resolution)),
                  row_stride=w * values.itemsize, cell_stride=values.itemsize,
                  fields=[m.PackedElementField(name="value", offset=0, type=kind)], data=values.tobytes())


def write_foxglove(path, episode: Episode):
    """Write ``episode`` as a Foxglove MCAP file at ``path`` (see the module docstring), atomically.

    Parameters
    ----------
    path : str or path-like
        The ``.mcap`` file to write (missing parent folders are made).
    episode : Episode
        The robot's log (poses, gas, wind, frames) and, when it holds them, the posteriors and the source.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    TypeError
        ``episode`` is not an :class:`Episode`.
    ImportError
        The ``ros`` extra (foxglove-sdk) is not installed.

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
    >>> from psgsl_pgm.ros import write_foxglove
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = write_foxglove(Path(folder) / "room.mcap", episode)
    ...     print(path.name, path.stat().st_size > 0)
    room.mcap True
    """
    if not isinstance(episode, Episode):
        raise TypeError(f"episode must be a psgsl_pgm.ros.Episode, got {type(episode).__name__}")
    _require()
    return atomic_write(path, _write, episode)


def _write(ep: Episode, fh) -> None:
    import foxglove
    from foxglove import channels as ch
    from foxglove import messages as m

    ctx = foxglove.Context()
    writer = foxglove.open_mcap(fh, context=ctx)
    F = m.PackedElementFieldNumericType
    ts, quat, pose = _ts, _quat, _pose
    grid = ep.grid

    def grid_msg(t, values, kind):
        return _grid_msg(grid, t, values, kind)

    t0 = int(stamp_ns(0.0))
    ch.GridChannel("/map", context=ctx).log(grid_msg(t0, np.where(grid.occupancy, 100, 0).astype(np.uint8), F.Uint8),
                                            log_time=t0)
    entities = []
    for i, (cls, footprint, (z0, z1)) in enumerate(ep.objects):
        fp = np.asarray(footprint, dtype=np.float64)
        lo, hi = fp.min(axis=0), fp.max(axis=0)
        c = (lo + hi) / 2
        entities.append(m.SceneEntity(
            timestamp=ts(t0), frame_id="map", id=f"object-{i}",
            cubes=[m.CubePrimitive(pose=pose(c[0], c[1], 0.0, (z0 + z1) / 2),
                                   size=m.Vector3(x=float(hi[0] - lo[0]), y=float(hi[1] - lo[1]), z=float(z1 - z0)),
                                   color=m.Color(r=0.6, g=0.45, b=0.3, a=0.6))],
            texts=[m.TextPrimitive(pose=pose(c[0], c[1], 0.0, z1 + 0.1), billboard=True, font_size=12.0,
                                   scale_invariant=True, color=m.Color(r=1.0, g=1.0, b=1.0, a=1.0), text=cls)]))
    ch.SceneUpdateChannel("/objects", context=ctx).log(m.SceneUpdate(entities=entities), log_time=t0)

    pose_ns = stamp_ns(ep.pose_t)
    tf, robot = ch.FrameTransformChannel("/tf", context=ctx), ch.PoseInFrameChannel("/robot/pose", context=ctx)
    for t, (x, y, yaw) in zip(pose_ns, ep.pose):
        tf.log(m.FrameTransform(timestamp=ts(t), parent_frame_id="map", child_frame_id="base_link",
                                translation=m.Vector3(x=float(x), y=float(y), z=0.0), rotation=quat(yaw)), log_time=int(t))
        robot.log(m.PoseInFrame(timestamp=ts(t), frame_id="map", pose=pose(x, y, yaw)), log_time=int(t))
    gas = foxglove.Channel("/gas", schema={"type": "object", "properties": {"ppm": {"type": "number"},
                                                                              "hit": {"type": "boolean"}}},
                           message_encoding="json", context=ctx)
    for t, v in zip(stamp_ns(ep.gas_t), ep.gas):
        gas.log({"ppm": float(v), "hit": bool(v >= ep.threshold)}, log_time=int(t))
    wind = ch.SceneUpdateChannel("/wind", context=ctx)
    from ._time import interpolate

    wind_ns = stamp_ns(ep.wind_t)
    at = interpolate(pose_ns, ep.pose, wind_ns, tolerance=0.0, where="episode pose at the wind readings")
    for t, (wx, wy), (x, y, _) in zip(wind_ns, ep.wind, at):
        speed = float(np.hypot(wx, wy))
        arrow = m.ArrowPrimitive(pose=pose(x, y, float(np.arctan2(wy, wx)), 0.3), shaft_length=max(speed, 1e-3),
                                 shaft_diameter=0.03, head_length=0.1, head_diameter=0.08,
                                 color=m.Color(r=0.2, g=0.5, b=1.0, a=1.0))
        wind.log(m.SceneUpdate(entities=[m.SceneEntity(timestamp=ts(t), frame_id="map", id="wind", arrows=[arrow])]),
                 log_time=int(t))
    if ep.posteriors is not None and len(ep.step_t):
        step_ns = stamp_ns(ep.step_t)
        post = [ch.GridChannel(f"/posterior/{v}", context=ctx) for v in ep.variants]
        best = None if ep.best_class is None else ch.GridChannel(
            "/semantics/best_class", context=ctx, metadata={"classes": json.dumps(list(ep.classes))})
        path = ch.PosesInFrameChannel("/robot/path", context=ctx)
        nxt = ch.PoseInFrameChannel("/robot/next", context=ctx)
        for k, t in enumerate(step_ns):
            for c, p in zip(post, ep.posteriors[k]):
                c.log(grid_msg(t, np.asarray(p, dtype=np.float32), F.Float32), log_time=int(t))
            if best is not None:  # no class beliefs (the olfaction variant alone): no class grid
                best.log(grid_msg(t, ep.best_class[k], F.Uint8), log_time=int(t))
            done = ep.pose[pose_ns <= t]
            path.log(m.PosesInFrame(timestamp=ts(t), frame_id="map", poses=[pose(*q) for q in done]), log_time=int(t))
            if ep.chosen is not None and np.isfinite(ep.chosen[k]).all():
                nxt.log(m.PoseInFrame(timestamp=ts(t), frame_id="map", pose=pose(*ep.chosen[k])), log_time=int(t))
    writer.close()
