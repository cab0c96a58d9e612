"""A live run streamed to Foxglove through foxglove-sdk's WebSocket server (``psgsl live --foxglove``).

Open Foxglove, "Open connection", ``ws://HOST:PORT``. The channels are those of a recorded episode
(:mod:`psgsl_pgm.ros._foxglove`), in frame ``map``, logged as each step is assimilated:

* ``/map`` (``foxglove.Grid``): the occupancy grid (uint8: 0 free, 100 occupied), at the start and after every
  step (so a client that connects late sees it);
* ``/posterior/<variant>`` (``foxglove.Grid``): each variant's p(s | ·) (float32) after every step;
* ``/robot/pose`` (``foxglove.PoseInFrame``): where the robot took the reading;
* ``/robot/path`` (``foxglove.PosesInFrame``): the readings so far;
* ``/robot/next`` (``foxglove.PoseInFrame``): the goal the node published.

Log times are the readings' stamps. foxglove-sdk is imported only here (the ``ros`` extra).
"""

from __future__ import annotations

import numpy as np

from ._foxglove import _grid_msg, _pose, _require, _ts

__all__ = ["FoxgloveStream"]


class FoxgloveStream:
    """A foxglove-sdk WebSocket server with the live channels (module docstring).

    Parameters
    ----------
    grid : psgsl_pgm.GridMap
        The map the posteriors are on.
    variants : sequence of str
        Names of the posteriors, in the order :meth:`step` receives them.
    host : str, keyword-only
        Address to bind (default: loopback only).
    port : int, keyword-only
        TCP port; 0 picks a free one (:attr:`port` tells which).
    """

    def __init__(self, grid, variants, *, host: str = "127.0.0.1", port: int = 8765):
        _require()
        import foxglove
        from foxglove import channels as ch

        if isinstance(port, bool) or not isinstance(port, (int, np.integer)) or not 0 <= port <= 65535:
            raise ValueError(f"port must be an integer in 0..65535, got {port!r}")
        self.grid = grid
        self.variants = tuple(variants)
        self._ctx = foxglove.Context()
        self._server = foxglove.start_server(name="psgsl live", host=host, port=int(port), context=self._ctx)
        self.port = int(self._server.port)
        self._map = ch.GridChannel("/map", context=self._ctx)
        self._post = [ch.GridChannel(f"/posterior/{v}", context=self._ctx) for v in self.variants]
        self._robot = ch.PoseInFrameChannel("/robot/pose", context=self._ctx)
        self._path_ch = ch.PosesInFrameChannel("/robot/path", context=self._ctx)
        self._next = ch.PoseInFrameChannel("/robot/next", context=self._ctx)
        self._path: list = []

    def step(self, t_ns: int, position, heading: float, posteriors, goal) -> None:
        """Log one step: the reading at ``position`` (2,) m with the robot's ``heading`` (rad), ``posteriors``
        (V, H, W) in the order of ``variants``, the ``goal`` (3,) = (x, y, yaw) chosen next."""
        from foxglove import messages as m

        F = m.PackedElementFieldNumericType
        t = int(t_ns)
        post = np.asarray(posteriors)
        if post.shape != (len(self.variants), *self.grid.shape):
            raise ValueError(f"posteriors must have shape {(len(self.variants), *self.grid.shape)}, got {post.shape}")
        occupancy = np.where(self.grid.occupancy, 100, 0).astype(np.uint8)
        self._map.log(_grid_msg(self.grid, t, occupancy, F.Uint8), log_time=t)
        for c, p in zip(self._post, post):
            c.log(_grid_msg(self.grid, t, np.asarray(p, dtype=np.float32), F.Float32), log_time=t)
        here = _pose(position[0], position[1], float(heading))
        self._path.append(here)
        self._robot.log(m.PoseInFrame(timestamp=_ts(t), frame_id="map", pose=here), log_time=t)
        self._path_ch.log(m.PosesInFrame(timestamp=_ts(t), frame_id="map", poses=list(self._path)), log_time=t)
        self._next.log(m.PoseInFrame(timestamp=_ts(t), frame_id="map", pose=_pose(*goal)), log_time=t)

    def close(self) -> None:
        """Stop the server."""
        if self._server is not None:
            self._server.stop()
            self._server = None
