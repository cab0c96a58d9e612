"""Geometry every part of the package shares: the occupancy grid, the one line of sight, the field of view.

* :class:`GridMap` — frame, cell <-> world, coarsening, the 8-connected free-space graph;
* the light-tight line of sight (``_sight``) and the camera's field of view and φ_O (``_fov``:
  :func:`field_of_view`, :func:`view_information_gain`, :class:`ViewCache`).

May import: :mod:`psgsl_pgm._shared`, :mod:`psgsl_pgm.kernels`. Re-exported by :mod:`psgsl_pgm`.
"""

from ._fov import ViewCache, field_of_view, view_information_gain
from ._grid import GridMap

__all__ = ["GridMap", "ViewCache", "field_of_view", "view_information_gain"]
