"""ROS ``map_server`` occupancy maps (YAML + PGM/PNG): loading and saving.

The YAML keys are those of ROS 1 ``map_server`` / ROS 2 ``nav2_map_server``: ``image``, ``resolution``,
``origin`` ([x, y, yaw]), ``negate``, ``occupied_thresh``, ``free_thresh`` and optionally ``mode``
(``trinary``, ``scale`` or ``raw``). A pixel of grey level v has occupancy probability
p = (255 - v) / 255 (p = v / 255 when ``negate`` is 1); p > occupied_thresh is occupied, p < free_thresh free,
anything in between unknown. In ``raw`` mode the pixel value is the occupancy in percent (compared with
100 x the thresholds).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from .._shared._validate import check_keys
from ..geometry._grid import GridMap
from ._fileio import number, number_list, read_grey_image, read_yaml_mapping, resolve

__all__ = ["load_ros_map", "save_ros_map"]

_REQUIRED = ("image", "resolution", "origin", "occupied_thresh", "free_thresh")
_OPTIONAL = ("negate", "mode")


def load_ros_map(yaml_path, *, unknown: str = "occupied") -> GridMap:
    """Load a ROS ``map_server`` map as a :class:`GridMap` (row 0 at the map's lowest y).

    Parameters
    ----------
    yaml_path : str or Path
        The map's YAML file; its ``image`` is resolved relative to the YAML's folder.
    unknown : {"occupied", "free"}, keyword-only
        How cells whose occupancy probability lies between the thresholds are treated.

    Returns
    -------
    GridMap

    Raises
    ------
    FileNotFoundError
        The YAML or its image does not exist.
    ValueError
        Unknown or missing keys, non-numeric values, thresholds out of order, a rotated origin (yaw != 0),
        an unreadable image — the message names the file and the field.

    Examples
    --------
    A round trip through :func:`save_ros_map`:

    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import GridMap, load_ros_map, save_ros_map
    >>> occ = np.zeros((3, 4), bool); occ[0, :] = True          # a wall along the lowest row
    >>> with tempfile.TemporaryDirectory() as d:
    ...     back = load_ros_map(save_ros_map(GridMap(occ, 0.05, (1.0, 2.0)), Path(d) / "map.yaml"))
    >>> bool(np.array_equal(back.occupancy, occ)), back.resolution, back.origin
    (True, 0.05, (1.0, 2.0))
    """
    if unknown not in ("occupied", "free"):
        raise ValueError(f"unknown must be 'occupied' or 'free', got {unknown!r}")
    path, data = read_yaml_mapping(yaml_path)
    where = str(path)
    check_keys(where, data, required=_REQUIRED, optional=_OPTIONAL)
    resolution = number(where, "resolution", data["resolution"], positive=True)
    origin = number_list(where, "origin", data["origin"], length=(2, 3))
    if len(origin) == 3 and origin[2] != 0.0:
        raise ValueError(f"{where}: field 'origin' has yaw {origin[2]!r}; rotated maps are not supported")
    occ_t = number(where, "occupied_thresh", data["occupied_thresh"])
    free_t = number(where, "free_thresh", data["free_thresh"])
    if not 0.0 <= free_t <= occ_t <= 1.0:
        raise ValueError(
            f"{where}: fields 'free_thresh' ({free_t}) and 'occupied_thresh' ({occ_t}) must satisfy "
            "0 <= free_thresh <= occupied_thresh <= 1"
        )
    negate = data.get("negate", 0)
    if isinstance(negate, bool):
        negate = int(negate)
    if negate not in (0, 1):
        raise ValueError(f"{where}: field 'negate' must be 0 or 1, got {negate!r}")
    mode = data.get("mode", "trinary")
    if mode not in ("trinary", "scale", "raw"):
        raise ValueError(f"{where}: field 'mode' must be 'trinary', 'scale' or 'raw', got {mode!r}")

    grey = read_grey_image(resolve(path, data["image"], "image"), where=where, field="image")
    if mode == "raw":  # map_server raw: the pixel value is the occupancy in percent
        occupied = grey >= 100 * occ_t
        unknown_mask = (grey > 100 * free_t) & ~occupied
    else:
        p = grey.astype(np.float64) / 255.0
        if not negate:
            p = 1.0 - p  # dark = occupied
        occupied = p > occ_t
        unknown_mask = ~occupied & ~(p < free_t)
    if unknown == "occupied":
        occupied = occupied | unknown_mask
    return GridMap(occupied[::-1], resolution, (origin[0], origin[1]))  # image row 0 is the top (max y)


def save_ros_map(grid: GridMap, yaml_path, *, image: str | None = None) -> Path:
    """Write ``grid`` as a ROS ``map_server`` map: a PGM (occupied 0, free 254) and its YAML.

    Parameters
    ----------
    grid : GridMap
    yaml_path : str or Path
        Where to write the YAML.
    image : str, optional, keyword-only
        Image file name, relative to the YAML's folder; defaults to the YAML's stem + ``.pgm``.

    Returns
    -------
    Path
        The YAML path.

    Raises
    ------
    TypeError
        ``grid`` is not a :class:`GridMap`.

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import GridMap, save_ros_map
    >>> with tempfile.TemporaryDirectory() as d:
    ...     yaml_path = save_ros_map(GridMap(np.zeros((3, 4), bool), 0.05), Path(d) / "map.yaml")
    ...     print(sorted(p.name for p in Path(d).iterdir()))
    ['map.pgm', 'map.yaml']
    """
    from PIL import Image

    if not isinstance(grid, GridMap):
        raise TypeError(f"grid must be a GridMap, got {type(grid).__name__}")
    yp = Path(yaml_path)
    name = image if image is not None else yp.stem + ".pgm"
    pixels = np.where(grid.occupancy[::-1], 0, 254).astype(np.uint8)
    Image.fromarray(pixels).save(yp.parent / name)
    meta = {
        "image": name,
        "resolution": float(grid.resolution),
        "origin": [float(grid.origin[0]), float(grid.origin[1]), 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    yp.write_text(yaml.safe_dump(meta, sort_keys=False))
    return yp
