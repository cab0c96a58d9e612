"""Scene objects (class, footprint, height) and object lists in YAML.

Object-list YAML::

    objects:
      - class: oven
        position: [x, y]          # footprint centre in metres (a third entry, z, is ignored)
        size: [sx, sy]            # optional box size in metres (default: one cell of the map)
        yaw: 0.0                  # optional box rotation in radians, counter-clockwise, |yaw| <= 2π
        height: [z_min, z_max]    # optional vertical extent in metres above the floor (default [0, 1])
        name: oven_1              # optional
      - class: couch
        footprint: [[x0, y0], [x1, y1], [x2, y2], ...]   # polygon, instead of position/size/yaw
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from .._shared._validate import as_float_array, check_keys, real_number, real_pair
from ..geometry._grid import GridMap
from ._fileio import number, number_list, read_yaml_mapping

__all__ = ["SceneObject", "box_footprint", "load_objects", "save_objects"]


def box_footprint(center, size, yaw: float = 0.0) -> np.ndarray:
    """(4, 2) corners of a rectangle of ``size`` (sx, sy) centred at ``center``, rotated by ``yaw``.

    Parameters
    ----------
    center : (2,) array_like of float
        (x, y) of the rectangle's centre, metres.
    size : (2,) array_like of float
        (sx, sy) side lengths before the rotation, metres, both positive.
    yaw : float
        Rotation about the centre, radians, counter-clockwise from the x axis.

    Returns
    -------
    (4, 2) ndarray of float64
        The corners, counter-clockwise, metres; a footprint for :class:`SceneObject`.

    Raises
    ------
    TypeError, ValueError
        ``center`` or ``size`` not a pair of finite numbers, a side not positive, or ``yaw`` not a finite number.

    Examples
    --------
    >>> box_footprint((1.0, 2.0), (0.6, 0.4)).tolist()
    [[0.7, 1.8], [1.3, 1.8], [1.3, 2.2], [0.7, 2.2]]
    """
    cx, cy = real_pair(center, "center", "an (x, y)", "metres")
    sx, sy = real_pair(size, "size", "an (sx, sy)", "metres")
    if not (sx > 0 and sy > 0):
        raise ValueError(f"size must be positive (sx, sy) in metres, got {size!r}")
    yaw = real_number(yaw, "yaw", unit="radians")
    half = np.array([[-sx, -sy], [sx, -sy], [sx, sy], [-sx, sy]]) / 2
    c, s = np.cos(yaw), np.sin(yaw)
    return half @ np.array([[c, s], [-s, c]]) + (cx, cy)


@dataclass(frozen=True, eq=False)
class SceneObject:
    """A piece of furniture or an appliance.

    Parameters
    ----------
    class_name : str
        Object class (COCO names, e.g. ``"oven"``; see :data:`HOUSE_CLASSES`).
    footprint : (n, 2) ndarray
        Polygon (x, y) in metres, n >= 3.
    z_range : (2,) tuple of float
        (z_min, z_max) in metres above the floor.
    name : str
        Instance name (defaults to the class name).
    """

    class_name: str
    footprint: np.ndarray
    z_range: tuple[float, float] = (0.0, 1.0)
    name: str = field(default="")

    def __post_init__(self):
        if not isinstance(self.name, str):
            raise TypeError(f"name must be a string, got {type(self.name).__name__} {self.name!r}")
        if not isinstance(self.class_name, str) or not self.class_name:
            raise TypeError(f"class_name must be a non-empty string, got {self.class_name!r}")
        fp = np.array(as_float_array(self.footprint, "footprint", dtype=np.float64))
        if fp.ndim != 2 or fp.shape[1] != 2 or fp.shape[0] < 3 or not np.all(np.isfinite(fp)):
            raise ValueError(f"footprint must be a finite (n >= 3, 2) polygon, got shape {fp.shape}")
        fp.flags.writeable = False
        z0, z1 = (float(v) for v in real_pair(self.z_range, "z_range", "a (z_min, z_max)", "metres"))
        if not z0 < z1:
            raise ValueError(f"z_range must be (z_min, z_max) with z_min < z_max, got {self.z_range!r}")
        object.__setattr__(self, "footprint", fp)
        object.__setattr__(self, "z_range", (z0, z1))
        object.__setattr__(self, "name", self.name or self.class_name)

    @property
    def center(self) -> np.ndarray:
        """(2,) centroid of the footprint vertices, metres."""
        return self.footprint.mean(axis=0)

    def mask(self, grid: GridMap) -> np.ndarray:
        """(H, W) bool: cells whose centre lies inside the footprint (at least the cell of the centre)."""
        from matplotlib.path import Path as MplPath

        h, w = grid.shape
        lo = grid.world_to_cell(self.footprint.min(axis=0))
        hi = grid.world_to_cell(self.footprint.max(axis=0))
        r0, c0 = max(lo[0], 0), max(lo[1], 0)
        r1, c1 = min(hi[0], h - 1), min(hi[1], w - 1)
        out = np.zeros((h, w), dtype=bool)
        if r0 <= r1 and c0 <= c1:
            rr, cc = np.mgrid[r0 : r1 + 1, c0 : c1 + 1]
            pts = grid.cell_to_world(np.stack([rr.ravel(), cc.ravel()], axis=-1))
            inside = MplPath(self.footprint).contains_points(pts)
            out[rr.ravel()[inside], cc.ravel()[inside]] = True
        if not out.any():
            rc = grid.world_to_cell(self.center)
            if grid.contains(rc):
                out[rc[0], rc[1]] = True
        return out

    def __repr__(self) -> str:
        x, y = self.center
        return f"SceneObject({self.name!r}, class={self.class_name!r}, center=({x:.2f}, {y:.2f}), z={self.z_range})"


_KEYS = ("class", "position", "size", "yaw", "height", "name", "footprint")
_UNITS = {
    "position": "position: [x, y] of the footprint centre in metres, map frame",
    "size": "size: [sx, sy] of the box in metres",
    "yaw": "yaw: the box's rotation in radians, counter-clockwise from the x axis",
    "height": "height: [z_min, z_max] in metres above the floor, e.g. [0.0, 0.9]",
}


def _unit(read, where, field, value, unit, **kw):
    """``read(where, field, value, **kw)``, its error ending with the field's units."""
    try:
        return read(where, field, value, **kw)
    except ValueError as exc:
        raise ValueError(f"{exc} ({unit})") from None


def load_objects(yaml_path, *, like: GridMap | None = None, classes=None) -> list[SceneObject]:
    r"""Load an object list (see the module docstring for the layout).

    Parameters
    ----------
    yaml_path : str or Path
    like : GridMap, optional, keyword-only
        If given, every object's footprint centre must lie inside this map, and the default box size is one
        of its cells (otherwise 0.1 m).
    classes : sequence of str, optional, keyword-only
        Allowed class names; an object of another class is an error.

    Returns
    -------
    list of SceneObject

    Raises
    ------
    FileNotFoundError
        No such file.
    TypeError
        ``like`` is not a GridMap, ``classes`` is not a list of names.
    ValueError
        Unknown keys, non-numeric values, unknown classes, objects outside the map — naming the file and field.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import load_objects
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = Path(d) / "objects.yaml"
    ...     _ = path.write_text("objects:\n  - {class: oven, position: [1.0, 2.0], size: [0.6, 0.6]}\n")
    ...     objects = load_objects(path)
    >>> objects[0].class_name, objects[0].center.round(2).tolist()
    ('oven', [1.0, 2.0])
    """
    if like is not None and not isinstance(like, GridMap):
        raise TypeError(f"like must be a GridMap (or None), got {type(like).__name__} {like!r}")
    if classes is not None and (isinstance(classes, (str, bytes, dict)) or not hasattr(classes, "__iter__")):
        raise TypeError(f"classes must be a list of class names, got {type(classes).__name__} {classes!r}")
    path, data = read_yaml_mapping(yaml_path)
    where = str(path)
    check_keys(where, data, required=("objects",))
    items = data["objects"]
    if not isinstance(items, list):
        raise ValueError(f"{where}: field 'objects' must be a list, got {type(items).__name__}")
    allowed = None if classes is None else set(classes)
    if allowed is not None and not all(isinstance(c, str) for c in allowed):
        raise TypeError(f"classes must hold class names (str), got {sorted(map(repr, allowed))}")
    cell = like.resolution if like is not None else 0.1
    out = []
    for i, it in enumerate(items):
        f = f"objects[{i}]"
        check_keys(f"{where}: {f}", it, required=("class",), optional=_KEYS[1:])
        cls = it["class"]
        if not isinstance(cls, str) or not cls:
            raise ValueError(f"{where}: field '{f}.class' must be a class name, got {cls!r}")
        if allowed is not None and cls not in allowed:
            raise ValueError(f"{where}: field '{f}.class': unknown class {cls!r}; known classes are {sorted(allowed)}")
        if "footprint" in it:
            if any(k in it for k in ("position", "size", "yaw")):
                raise ValueError(f"{where}: field '{f}': give either 'footprint' or 'position'/'size'/'yaw', not both")
            pts = it["footprint"]
            if not isinstance(pts, list) or len(pts) < 3:
                raise ValueError(f"{where}: field '{f}.footprint' must be a list of >= 3 [x, y] points, got {pts!r}")
            fp = np.array([number_list(where, f"{f}.footprint[{j}]", p, length=2) for j, p in enumerate(pts)])
        else:
            if "position" not in it:
                raise ValueError(f"{where}: field '{f}': needs 'position' (with optional 'size', 'yaw') or 'footprint'")
            pos = _unit(number_list, where, f"{f}.position", it["position"], _UNITS["position"], length=(2, 3))
            size = _unit(number_list, where, f"{f}.size", it["size"], _UNITS["size"], length=2) if "size" in it \
                else [cell, cell]
            if min(size) <= 0:
                raise ValueError(f"{where}: field '{f}.size' must be positive, got {it['size']!r} ({_UNITS['size']})")
            yaw = _unit(number, where, f"{f}.yaw", it["yaw"], _UNITS["yaw"]) if "yaw" in it else 0.0
            if abs(yaw) > 2 * np.pi + 1e-9:  # 90 is a rotation in degrees: a silent 90 rad would be wrong
                raise ValueError(f"{where}: field '{f}.yaw' is {yaw:g}, beyond ±2π ({_UNITS['yaw']}; {yaw:g}° is "
                                 f"{np.deg2rad(yaw):.4f} rad)")
            fp = box_footprint(pos[:2], size, yaw)
        z = _unit(number_list, where, f"{f}.height", it["height"], _UNITS["height"], length=2) if "height" in it \
            else [0.0, 1.0]
        if z[0] >= z[1]:
            raise ValueError(f"{where}: field '{f}.height' must have z_min < z_max, got {z} ({_UNITS['height']})")
        name = it.get("name", "")
        if not isinstance(name, str):
            raise ValueError(f"{where}: field '{f}.name' must be a string, got {name!r}")
        obj = SceneObject(cls, fp, (z[0], z[1]), name)
        if like is not None and not like.contains(like.world_to_cell(obj.center)):
            x, y = obj.center
            raise ValueError(f"{where}: field '{f}': object centre ({x:.3f}, {y:.3f}) lies outside the map {like.extent}")
        out.append(obj)
    return out


def save_objects(objects, yaml_path) -> Path:
    """Write objects as an object-list YAML (polygon footprints), readable by :func:`load_objects`.

    Parameters
    ----------
    objects : iterable of SceneObject
        The objects: class name, name, footprint polygon (metres) and height range (metres) of each.
    yaml_path : str or path-like
        The file to write (replaced if it exists).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    TypeError
        An element of ``objects`` is not a :class:`SceneObject`.
    OSError
        The file cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import default_house, load_objects, save_objects
    >>> house = default_house(seed=0)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = load_objects(save_objects(house.objects[:3], Path(folder) / "objects.yaml"))
    >>> [o.class_name for o in back] == [o.class_name for o in house.objects[:3]]
    True
    """
    items = []
    for o in objects:
        if not isinstance(o, SceneObject):
            raise TypeError(f"objects must be SceneObject instances, got {type(o).__name__}")
        items.append(
            {
                "class": o.class_name,
                "name": o.name,
                "footprint": [[float(x), float(y)] for x, y in o.footprint],
                "height": [float(o.z_range[0]), float(o.z_range[1])],
            }
        )
    yp = Path(yaml_path)
    yp.write_text(yaml.safe_dump({"objects": items}, sort_keys=False))
    return yp
