"""Camera field of view on an occupancy grid, and φ_O(p) = Σ_{n ∈ F_p} I(S; O_n) (Sec. "Information Gain
Optimization")."""

from __future__ import annotations

import hashlib
import math
from collections import OrderedDict

import numpy as np

from .._shared._validate import as_float_array, bool_mask, describe, flag, positive, real_pair
from ._sight import visible_from

__all__ = ["ViewCache", "field_of_view", "view_information_gain"]


def _occupancy(occupancy) -> np.ndarray:
    try:
        return bool_mask(occupancy, "occupancy")
    except TypeError:
        shown = describe(occupancy) if isinstance(occupancy, np.ndarray) else type(occupancy).__name__
        raise TypeError(f"occupancy must be boolean (True = occupied) or 0/1, got {shown}") from None


def field_of_view(occupancy, pose, *, max_range, half_angle, min_range=0.0, resolution=1.0, origin=(0.0, 0.0)):
    r"""Cells seen by a camera at ``pose``: the set :math:`F_p` of Sec. "Information Gain Optimization".

    A cell is visible when its centre lies within ``[min_range, max_range]`` of the camera and within
    ``half_angle`` of its heading, and the segment from the centre of the camera's cell to that centre
    touches no occupied cell other than the target itself (so walls and objects are seen, but nothing behind
    them). This is the package's one line-of-sight rule (:mod:`psgsl_pgm.geometry._sight`, the gas model's too): an
    occupied cell blocks even where the segment only touches its corner, so a wall of cells that touch only
    at their corners is light-tight. (Occlusion is traced from the camera cell's centre, range and angle from
    the pose itself; on the robot's tour the camera stands at cell centres.)

    Cost: shadow casting ring by ring around the camera cell (:func:`psgsl_pgm.geometry._sight.visible_from`), time
    O(A log B) and memory O(H W / 8 + one ring + B) — A the cells within the rings up to where the shadows
    close the view (in a room: about the room's cells, at most the cells within ``max_range``), B the number
    of disjoint shadows; not range × rays. A full circle of 4 m on a 1 cm 1140 × 870 map stays within a few
    MB. ``max_range`` beyond the map costs nothing more than the map.

    Parameters
    ----------
    occupancy : (H, W) array_like of bool
        True = occupied. Row index ↔ y, column index ↔ x; cell (r, c) has its centre at
        ``(origin[0] + (c + 0.5) * resolution, origin[1] + (r + 0.5) * resolution)``.
    pose : (3,) array_like
        Camera ``(x, y, heading)``; heading in radians, 0 along +x (+column), π/2 along +y (+row).
    max_range, min_range : float
        Range limits, in the units of ``pose``.
    half_angle : float
        Half the horizontal opening angle, radians, in (0, π].
    resolution : float, default 1.0
        Cell size in the units of ``pose``.
    origin : (2,) array_like, default (0, 0)
        World coordinates of the lower-left corner of cell (0, 0).

    Returns
    -------
    visible : (H, W) ndarray of bool

    Raises
    ------
    TypeError
        ``occupancy`` is not boolean (or 0/1).
    ValueError
        ``pose`` is not a finite (x, y, heading) inside the map; ``max_range``, ``min_range``, ``half_angle`` or
        ``resolution`` is not a number in its range (``min_range`` ≤ ``max_range``, ``half_angle`` in (0, π]).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import field_of_view
    >>> occ = np.zeros((5, 7), bool); occ[:, 3] = True               # a wall at column 3
    >>> seen = field_of_view(occ, (1.5, 2.5, 0.0), max_range=10, half_angle=np.pi)
    >>> bool(seen[2, 3]), bool(seen[2, 4:].any())                     # the wall, not what is behind it
    (True, False)
    """
    occ = _occupancy(occupancy)
    cam = _camera(occ, pose, max_range=max_range, half_angle=half_angle, min_range=min_range,
                  resolution=resolution, origin=origin)
    return visible_from(occ, cam.cell, reach=cam.reach, camera=cam)


class _Camera:
    """A validated camera pose on a grid: its cell, its continuous grid position and its cone test."""

    __slots__ = ("col0", "row0", "heading", "half_angle", "min_range", "max_range", "res", "cell", "reach",
                 "offset")

    def in_cone(self, rows, cols):
        """Cells whose centre is within [min_range, max_range] of the pose and within half_angle of its
        heading (range and angle from the pose itself): :func:`psgsl_pgm.kernels._view.cone_mask`."""
        from ..kernels._view import cone_mask  # compiled on first use (numba)

        return cone_mask(rows, cols, col0=self.col0, row0=self.row0, res=self.res, heading=self.heading,
                         half_angle=self.half_angle, min_range=self.min_range, max_range=self.max_range)


class _Options:
    """Validated camera options of :func:`field_of_view` (everything but the pose)."""

    __slots__ = ("max_range", "min_range", "half_angle", "res", "origin")

    def __init__(self, *, max_range, half_angle, min_range=0.0, resolution=1.0, origin=(0.0, 0.0)):
        self.max_range = float(positive(max_range, "max_range"))
        self.min_range = float(positive(min_range, "min_range", allow_zero=True))
        self.half_angle = float(positive(half_angle, "half_angle"))
        if self.half_angle > np.pi:
            raise ValueError(f"half_angle must be at most π, got {self.half_angle}")
        if self.min_range > self.max_range:
            raise ValueError(f"min_range ({self.min_range}) must not exceed max_range ({self.max_range})")
        self.res = float(positive(resolution, "resolution"))
        org = real_pair(origin, "origin", "an (x, y)", "units of pose")
        self.origin = (float(org[0]), float(org[1]))

    def key(self) -> tuple:
        return self.max_range, self.min_range, self.half_angle, self.res, self.origin

    def reach(self, shape) -> int:
        """Largest Chebyshev distance (cells) of a cell in range of a camera anywhere in its cell."""
        return int(min(math.ceil(min(self.max_range / self.res, 2.0**62)) + 1, max(shape)))


def _pose(p) -> np.ndarray:
    p = as_float_array(p, "pose", dtype=np.float64, ndim=1)
    if p.shape != (3,):
        raise ValueError(f"pose must be (x, y, heading), got {describe(p)}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"pose must be finite, got {p.tolist()}")
    return p


def _place(shape, p, opt: _Options) -> _Camera:
    """The camera of options ``opt`` at the validated pose ``p`` on a map of ``shape``."""
    h, w = shape
    x, y, heading = (float(v) for v in p)
    col0, row0 = (x - opt.origin[0]) / opt.res, (y - opt.origin[1]) / opt.res  # continuous grid coordinates
    if not (0 <= col0 < w and 0 <= row0 < h):
        raise ValueError(f"pose ({x}, {y}) lies outside the map (extent {w * opt.res} × {h * opt.res} from "
                         f"origin {list(opt.origin)})")
    cam = _Camera()
    cam.col0, cam.row0, cam.heading, cam.half_angle = col0, row0, heading, opt.half_angle
    cam.min_range, cam.max_range, cam.res = opt.min_range, opt.max_range, opt.res
    r0, c0 = int(row0), int(col0)
    cam.cell = (r0, c0)
    cam.reach = opt.reach(shape)
    cam.offset = math.hypot(col0 - c0 - 0.5, row0 - r0 - 0.5)  # camera to its cell centre, in cells
    return cam


def _camera(occ, pose, **fov) -> _Camera:
    """Validate the options of :func:`field_of_view` for one pose on ``occ`` (already validated)."""
    p = _pose(pose)
    return _place(occ.shape, p, _Options(**fov))


class ViewCache:
    """What a camera sees from the cells of one map: the line of sight cast once per camera cell, then reused
    for every pose in that cell, every heading and every call.

    Occlusion is traced from the centre of the camera's cell (:func:`field_of_view`), so it depends on the
    occupancy and that cell only; range and opening angle depend on the pose and are tested per pose on the
    cached cells. Every result equals :func:`field_of_view` (the same cells, gathered in the same row-major
    order, so sums over them are bitwise equal).

    Parameters
    ----------
    occupancy : (H, W) array_like of bool
        True = occupied; copied.
    max_range, half_angle, min_range, resolution, origin
        The camera, as for :func:`field_of_view`.
    max_bytes : int, keyword-only, default 64 MiB
        Memory bound of the cached cell lists; the least recently used camera cells are dropped beyond it.

    Notes
    -----
    Cost: the first use of a camera cell is one shadow cast over the cells within ``max_range`` (plus one cell)
    of it (:func:`psgsl_pgm.geometry._sight.visible_from`, full circle); every pose after that costs one compiled
    range-and-angle test over the cells in sight (:mod:`psgsl_pgm.kernels._view`) and, for the gain, one sum.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import ViewCache, field_of_view
    >>> occ = np.zeros((5, 7), bool); occ[:, 3] = True
    >>> views = ViewCache(occ, max_range=10, half_angle=np.pi / 4)
    >>> bool((views.field_of_view((1.5, 2.5, 0.0)) == field_of_view(occ, (1.5, 2.5, 0.0), max_range=10,
    ...                                                             half_angle=np.pi / 4)).all())
    True
    >>> views.information_gain(np.ones((5, 7)), [(1.5, 2.5, 0.0), (1.5, 2.5, np.pi)])
    array([7., 4.])
    """

    _SHARED: OrderedDict = OrderedDict()  # (occupancy digest, shape, options) -> ViewCache, see shared()
    _SHARED_MAX = 4

    def __init__(self, occupancy, *, max_range, half_angle, min_range=0.0, resolution=1.0, origin=(0.0, 0.0),
                 max_bytes=64 * 2**20):
        occ = _occupancy(occupancy).copy()
        occ.flags.writeable = False
        self.occupancy = occ
        self._opt = _Options(max_range=max_range, half_angle=half_angle, min_range=min_range,
                             resolution=resolution, origin=origin)
        self.max_bytes = int(positive(max_bytes, "max_bytes"))
        self._sight: OrderedDict = OrderedDict()
        self._bytes = 0

    @classmethod
    def shared(cls, occupancy, **fov) -> "ViewCache":
        """The process-wide cache for this map and camera (the same occupancy content and options give the same
        object; at most four maps are kept, least recently used dropped)."""
        occ = np.ascontiguousarray(_occupancy(occupancy))
        key = (hashlib.sha1(occ.tobytes()).hexdigest(), occ.shape, _Options(**fov).key())
        hit = cls._SHARED.get(key)
        if hit is None:
            hit = cls(occ, **fov)
            if len(cls._SHARED) >= cls._SHARED_MAX:
                cls._SHARED.popitem(last=False)
            cls._SHARED[key] = hit
        else:
            cls._SHARED.move_to_end(key)
        return hit

    def sight(self, cell):
        """Cells in line of sight of the centre of ``cell`` that a camera anywhere in it could have in range.

        Parameters
        ----------
        cell : (2,) int
            (row, col) of the camera cell.

        Returns
        -------
        rows, cols : (m,) ndarray of int32
            In row-major order; read-only.
        """
        key = (int(cell[0]), int(cell[1]))
        hit = self._sight.get(key)
        if hit is not None:
            self._sight.move_to_end(key)
            return hit
        occ, opt = self.occupancy, self._opt
        reach = opt.reach(occ.shape)
        disc = min(opt.max_range / opt.res, 2.0**62) + 0.75  # a pose is within √2/2 cell of its cell's centre
        rows, cols = np.nonzero(visible_from(occ, key, reach=reach, disc=disc))
        hit = (rows.astype(np.int32), cols.astype(np.int32))
        for a in hit:
            a.flags.writeable = False
        self._sight[key] = hit
        self._bytes += rows.size * 8
        while self._bytes > self.max_bytes and len(self._sight) > 1:
            _, (r, _c) = self._sight.popitem(last=False)
            self._bytes -= r.size * 8
        return hit

    def _cameras(self, pose):
        poses = as_float_array(pose, "pose", dtype=np.float64)
        single = poses.ndim == 1
        if single:
            poses = _pose(poses)[None, :]
        elif poses.ndim != 2 or poses.shape[1] != 3:
            raise ValueError(f"pose must be (3,) or (P, 3), got {describe(poses)}")
        elif not np.all(np.isfinite(poses)):
            bad = int(np.flatnonzero(~np.isfinite(poses).all(axis=1))[0])
            raise ValueError(f"pose[{bad}] must be finite, got {poses[bad].tolist()}")
        return single, [_place(self.occupancy.shape, p, self._opt) for p in poses]

    def cone(self, pose, rows, cols, *, any_heading=False):
        """Which cells are within the camera's range and opening angle from ``pose`` (occlusion not tested).

        Parameters
        ----------
        pose : (3,) array_like
            (x, y, heading), inside the map.
        rows, cols : (m,) array_like of int
        any_heading : bool, keyword-only
            Test the range only (a full circle).

        Returns
        -------
        inside : (m,) ndarray of bool
        """
        _, (cam,) = self._cameras(_pose(pose))
        if flag(any_heading, "any_heading"):
            cam.half_angle = np.pi
        return cam.in_cone(np.asarray(rows), np.asarray(cols))

    def in_view(self, cam: _Camera):
        """(rows, cols) of the cells the camera ``cam`` sees."""
        rows, cols = self.sight(cam.cell)
        keep = cam.in_cone(rows, cols)
        return rows[keep], cols[keep]

    def field_of_view(self, pose) -> np.ndarray:
        r""":math:`F_p` as an (H, W) bool mask, equal to :func:`field_of_view` with this cache's camera."""
        _, (cam,) = self._cameras(_pose(pose))
        seen = np.zeros(self.occupancy.shape, dtype=bool)
        seen[self.in_view(cam)] = True
        return seen

    def information_gain(self, information_gain, pose):
        r""":math:`\varphi_O(p) = \sum_{n \in F_p} I(S; O_n)` for one pose or each of P poses (see
        :func:`view_information_gain`).

        Parameters
        ----------
        information_gain : (H, W) array_like
            :math:`I(S; O_n)` per cell, finite.
        pose : (3,) or (P, 3) array_like

        Returns
        -------
        phi : float or (P,) ndarray
        """
        gain = as_float_array(information_gain, "information_gain", dtype=np.float64, ndim=2)
        if gain.shape != self.occupancy.shape:
            raise ValueError(f"information_gain must have the occupancy's shape {self.occupancy.shape}, got "
                             f"{describe(gain)}")
        if not np.all(np.isfinite(gain)):
            raise ValueError("information_gain must be finite")
        single, cams = self._cameras(pose)
        from ..kernels._view import cone_values  # compiled on first use (numba)

        phi = np.empty(len(cams))
        for i, cam in enumerate(cams):  # loop over poses (tens); the same cells in the same order as field_of_view
            rows, cols = self.sight(cam.cell)
            phi[i] = cone_values(rows, cols, gain, col0=cam.col0, row0=cam.row0, res=cam.res, heading=cam.heading,
                                 half_angle=cam.half_angle, min_range=cam.min_range,
                                 max_range=cam.max_range).sum()
        return float(phi[0]) if single else phi


def view_information_gain(information_gain, occupancy, pose, **fov):
    r"""Semantic information gain of a camera pose, :math:`\varphi_O(p)`.

    Eq. (31) of the paper: the information gains of the cells in the camera's field of view :math:`F_p`
    (:func:`field_of_view`) at pose :math:`p`, summed,

    .. math:: \varphi_O(p) = \sum_{n \in F_p} I(S; O_n)

    Parameters
    ----------
    information_gain : (H, W) array_like
        :math:`I(S; O_n)` per cell, e.g. from :func:`semantic_information_gain`.
    occupancy : (H, W) array_like of bool
        As for :func:`field_of_view`.
    pose : (3,) or (P, 3) array_like
        One camera pose (x, y, heading), or P candidate poses.
    **fov
        Keyword options of :func:`field_of_view` (``max_range``, ``half_angle`` are required).

    Returns
    -------
    phi : float or (P,) ndarray
        :math:`\varphi_O` for the pose, or for each candidate pose.

    Raises
    ------
    TypeError
        ``occupancy`` is not boolean (as for :func:`field_of_view`), or ``max_range`` or ``half_angle`` is missing.
    ValueError
        A pose or an option is refused as by :func:`field_of_view`, or ``information_gain`` is not finite or not of
        the map's shape.

    Notes
    -----
    The line of sight from each camera cell does not depend on the heading or the exact pose in the cell: it
    is cast once per cell and kept in the process-wide :meth:`ViewCache.shared` cache of this map and camera,
    so a planner that scores many headings, or the same places at every step, pays for the shadow casts once.
    Equal to the per-pose sum over :func:`field_of_view`, bit for bit.

    Examples
    --------
    A wall at column 3; only the cells right of it are worth looking at:

    >>> import numpy as np
    >>> from psgsl_pgm import view_information_gain
    >>> occ = np.zeros((5, 7), bool); occ[:, 3] = True
    >>> gain = np.zeros((5, 7)); gain[:, 4:] = 0.1                  # I(S; O_n), nats; 15 cells right of the wall
    >>> view_information_gain(gain, occ, [(1.5, 2.5, 0.0), (5.5, 2.5, np.pi)], max_range=10, half_angle=np.pi).round(2)
    array([0. , 1.5])
    """
    return ViewCache.shared(occupancy, **fov).information_gain(information_gain, pose)
