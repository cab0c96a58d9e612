"""World files: a user's house (map, rooms, objects, ontology, wind, start, sources) in one YAML file.

A world file names the files a GSL lab already has; relative paths resolve against the world file's folder::

    map: house.yaml              # ROS map_server YAML + PGM/PNG (resolution, origin, negate, thresholds)
    resolution: 0.1              # working cell size (default: the map's): a coarse cell is occupied when any
                                 # fine cell is, rooms by majority; must be a whole multiple of the map's cells
    rooms: roomMasks.yaml        # one mask image per category, or a segmented image + grey-level table
    objects: objects.yaml        # optional: object list (psgsl_pgm.sim.load_objects)
    ontology: ontology.yaml      # this project's format or the lab's (top-level Gases)
    room_classes: ObjectProbByRoom.yaml   # optional: the lab's p(o | room)
    gas: smoke                   # optional: target gas (default: the experiment's, else the ontology's first);
                                 # 'unknown': each episode's gas is drawn from the ontology's, not told to the robot
    model: realistic             # optional: the world model, ideal (default) or realistic, or ideal+COMPONENT...
                                 # (psgsl_pgm.sim.WorldModel: CFD wind, MOX sensor, occluding camera, pose error)
    source_region: rooms         # where a source may be: rooms (default), free, or a mask image (white = may)
    semantic_map: beliefs.npz    # optional: a mapper's class beliefs instead of the simulated camera
                                 # (.npy/.npz dense beliefs or Voxeland's instance-map JSON)
    other_classes: error         # optional: a semantic_map class the ontology lacks is an error (default), or
                                 # "lump": added to "other" (a mapper with more classes than the ontology)
    clearance: 0.25              # optional: the robot's distance from walls, furniture and windows, m
    wind:                        # potential flow between windows ...
      speed: 0.2                 # mean speed, m/s
      perturbation: 0.3          # optional: slow eddies, fraction of speed (default 0.3)
      windows:
        - {role: inlet,  from: [-7.15, 3.42], to: [-5.65, 3.42]}   # optional width: m (default 0.15)
        - {role: outlet, from: [-1.70, -7.88], to: [-0.25, -7.88]}
      # ... or GADEN's CFD export: gaden_csv: [w_0.csv, w_1.csv], height: 0.5, period: 1.0 (s per snapshot);
      #     windows are then optional (outlets still let filaments leave)
    start: [-3.0, -3.3]          # robot start; default: the navigable cell nearest the map's centre
    sources: {B1: [-0.60, 1.95], oven: oven}   # named positions (m) or an object class

Object classes are matched to the ontology's through the COCO alias table (``fridge`` = ``refrigerator``);
an object whose class the ontology does not list is an ``other`` for the semantic term (the lab's rule), and
keeps its own class name for drawing and for ``sources``.

The embedded house is the world file ``psgsl_pgm/data/worlds/house.yaml`` (``builtin: default_house``: the
floor plan is generated per seed, ``ontology: house`` is :func:`psgsl_pgm.experiment.house_ontology`), so the
experiment has one code path.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from .._shared._memo import ContentCache, content_digest
from .._shared._validate import check_keys, positive
from .._shared._validate import did_you_mean as _did_you_mean
from ..core._ontology import Ontology
from ..geometry._grid import GridMap
from ..io._class_maps import read_class_beliefs
from ..io._coco import canonical_class
from ._fileio import number, number_list, read_grey_image, read_yaml_mapping, resolve
from ._house import House, default_house, segment_mask
from ._house_ontology import house_ontology
from ._objects import SceneObject, load_objects
from ._resample import coarsen_factor, coarsen_labels, coarsen_occupancy
from ._roommap import load_room_map
from ._rosmap import load_ros_map
from ._world_model import WorldModel

__all__ = ["MAX_FREE_CELLS", "MAX_WIND_SPEED", "WorldSpec", "check_free_cells", "default_world", "default_world_path",
           "load_world", "navigable", "world_files"]

#: The most free cells of a world whose estimators and closed loop run (search, experiment, benchmark, replay).
#: Measured with ``psgsl search`` (one worker, the lab's house B, found radius 0.5 m): 28 909 free cells (0.05 m)
#: peak at 0.6 GB, 80 148 (0.03 m) at 1.8 GB, 182 188 (0.02 m) fail beyond 3.7 GB; memory grows with the free
#: cells times the cells within the found radius. 60 000 keeps a run within 2 GB. ``psgsl world check`` runs on
#: finer maps and warns.
MAX_FREE_CELLS = 60_000

#: Fastest mean indoor wind a world file may declare, m/s. Indoor air moves at a few tenths of a metre per second
#: (ASHRAE Standard 55 counts speeds above 0.2 m/s as "elevated air speed"); 5 m/s is a gentle breeze outdoors
#: (Beaufort force 3, 3.4-5.4 m/s; WMO Manual on Codes, WMO-No. 306). A larger value is a unit or typing slip.
MAX_WIND_SPEED = 5.0

_KEYS = ("map", "resolution", "rooms", "objects", "ontology", "room_classes", "gas", "source_region",
         "semantic_map", "wind", "start", "sources", "builtin", "clearance", "other_classes", "model")
_WIND_POTENTIAL = ("speed", "perturbation", "windows")
_WIND_GADEN = ("gaden_csv", "height", "period", "windows")
_REGIONS = ("rooms", "free")


def navigable(house: House, clearance: float = 0.25) -> np.ndarray:
    """(H, W) bool: free cells at least ``clearance`` metres from walls, furniture and windows (the tour's rule).

    Parameters
    ----------
    house : House
        The house; its ``robot_obstacles`` (walls, furniture the robot cannot cross, windows) are kept clear of.
    clearance : float, default 0.25
        The least distance, metres (>= 0), from a cell's centre to the nearest obstacle cell.

    Returns
    -------
    (H, W) ndarray of bool
        True where the robot may stand.

    Raises
    ------
    TypeError
        ``house`` is not a :class:`House`, or ``clearance`` is not a real number.
    ValueError
        ``clearance`` is negative or not finite.

    Examples
    --------
    >>> from psgsl_pgm.sim import default_house, navigable
    >>> house = default_house(seed=0)
    >>> free = navigable(house)
    >>> free.shape == house.grid.shape, bool((free <= house.grid.free).all())
    (True, True)
    """
    from scipy import ndimage as ndi

    if not isinstance(house, House):
        raise TypeError(f"house must be a House, got {type(house).__name__}")
    clearance = positive(clearance, "clearance", "metres", allow_zero=True)
    blocked = house.robot_obstacles
    return ~blocked & (ndi.distance_transform_edt(~blocked) * house.grid.resolution > clearance)


@dataclass(frozen=True, eq=False)
class WorldSpec:
    """A loaded world file (see the module docstring); :meth:`~WorldSpec.house` and :meth:`~WorldSpec.make_world`
    build the simulation.

    Attributes
    ----------
    path : Path
        The world file.
    ontology : psgsl_pgm.Ontology
    gas : str or None
        Target gas named by the file; ``"unknown"``: each episode's gas is drawn from the ontology's gases and the
        robot is not told it (it carries an electronic nose, :class:`psgsl_pgm.sim.ElectronicNose`).
    wind : dict
        ``{"kind": "potential", "speed", "perturbation"}`` or ``{"kind": "gaden", "sequence": WindSequence}``.
    start : (2,) ndarray or None
        Robot start (None: the house's default, see :meth:`start_for`).
    sources : dict
        Name -> object class (str) or (x, y) position.
    source_region : str or (H, W) ndarray of bool
        ``"rooms"``, ``"free"`` or a mask on the working grid.
    class_beliefs : (H, W, k) or (H, W, L, k) ndarray or None
        A mapper's class beliefs in the ontology's class order (``semantic_map``).
    windows : tuple of dict
        The declared windows (role, from, to, width), for summaries and figures.
    model : str
        The world model's name (:class:`WorldModel`): ``ideal`` unless the file says otherwise.
    """

    path: Path
    ontology: object
    gas: str | None
    wind: dict
    start: np.ndarray | None
    sources: dict
    source_region: object
    class_beliefs: np.ndarray | None
    windows: tuple
    fixed_house: House | None = None
    builtin: str | None = None
    clearance: float = 0.25
    object_classes: tuple = ()
    map_path: Path | None = None
    model: str = "ideal"
    _notes: dict = field(default_factory=dict, repr=False)

    # --- the house ---------------------------------------------------------------------------------------
    def house(self, seed: int = 0) -> House:
        """The house of run ``seed`` (a file-defined house is the same for every seed)."""
        if self.fixed_house is not None:
            return self.fixed_house
        return default_house(int(seed))

    def start_for(self, house: House) -> np.ndarray:
        """(2,) robot start: the file's ``start``, else the navigable cell nearest the map's centre."""
        if self.start is not None:
            return self.start.copy()
        nav = navigable(house, self.clearance)
        if not nav.any():
            raise ValueError(f"{self.path}: the map has no navigable cell (free, {self.clearance} m from obstacles)")
        x0, x1, y0, y1 = house.grid.extent
        centres = house.grid.cell_centres()[nav]
        return centres[np.argmin(np.hypot(centres[:, 0] - (x0 + x1) / 2, centres[:, 1] - (y0 + y1) / 2))]

    def region_mask(self, house: House) -> np.ndarray:
        """(H, W) bool: cells where a source may be (``source_region``), always within free space."""
        if isinstance(self.source_region, np.ndarray):
            return self.source_region & house.grid.free
        if self.source_region == "free":
            return house.grid.free.copy()
        return (house.room_labels >= 0) & house.grid.free

    def source_spec(self, name):
        """A world source name -> its class or position; other strings / pairs pass through (class or 'x,y')."""
        if isinstance(name, str) and name in self.sources:
            return self.sources[name]
        return name

    def resolve_source(self, spec, house: House) -> np.ndarray:
        """(2,) position of a source spec (a world source name, an object class or a position)."""
        return self.source_target(spec, house)[0]

    def source_target(self, spec, house: House):
        """Where a source spec emits and what counts as finding it.

        Returns
        -------
        xy : (2,) ndarray
            The source position, m (an object's footprint centre when named by class).
        obj : SceneObject or None
            The emitting object: the first object of the named class, or the object whose footprint holds the
            position; None for a position in open space. The closed loop counts the robot as having found the
            source within ``found_radius`` of this object's footprint (:meth:`SceneObject.mask`).
        """
        from ._world import object_at

        named = isinstance(spec, str) and spec in self.sources
        spec = self.source_spec(spec)
        if isinstance(spec, str):
            objs = [o for o in house.objects if _true_class(o) == canonical_class(spec)]
            if not objs:
                present = sorted({_true_class(o) for o in house.objects})
                names = list(self.sources)
                if names and not named:  # a world with named sources: the name was most likely meant as one
                    objects = f"object classes present: {present}" if present else "the house has no objects"
                    raise ValueError(f"source {spec!r} is neither a source of the world nor an object class of the "
                                     f"house{_did_you_mean(spec, names + present)}; the world's sources: {names}; "
                                     f"{objects}")
                raise ValueError(f"source class {spec!r} has no object in the house{_did_you_mean(spec, present)}; "
                                 f"classes present: {present}")
            return objs[0].center.copy(), objs[0]
        xy = np.asarray(spec, dtype=np.float64)
        return xy, object_at(house, xy)

    def make_world(self, seed: int = 0, source="oven", *, warm_up: float = 60.0, model=None, **kwargs):
        """The running simulation (:func:`psgsl_pgm.sim.make_world`) of this world for one seed and source.

        ``model`` (a :class:`WorldModel` or its name; default: the file's ``model``) chooses the world's parts;
        parts given in ``kwargs`` win. A world whose wind is a GADEN CFD export keeps it under ``cfd-wind``.
        """
        from ._world import make_world

        wm = WorldModel.parse(self.model if model is None else model)
        house = self.house(seed)
        spec = self.source_spec(source)
        spec = self._resolve_source(spec, house)
        if kwargs.get("extra_sources"):  # several sources: each resolved as the first
            kwargs["extra_sources"] = [self._resolve_source(self.source_spec(x), house)
                                       for x in kwargs["extra_sources"]]
        if self.wind["kind"] == "gaden":
            kwargs.setdefault("wind", self.wind["sequence"])
            wm = WorldModel(tuple(c for c in wm.components if c != "cfd-wind"))  # the file's CFD is the CFD wind
        for key, value in wm.world_kwargs(house, wind_speed=self.wind.get("speed", 0.2)).items():
            kwargs.setdefault(key, value)
        if "wind" not in kwargs:  # the potential flow (a given wind, GADEN's or the CFD's, leaves these unused)
            kwargs.setdefault("mean_speed", self.wind["speed"])
            kwargs.setdefault("perturbation", self.wind["perturbation"])
        return make_world(house, source=spec, seed=int(seed), warm_up=warm_up, **kwargs)

    def _resolve_source(self, spec, house: House):
        if self.fixed_house is not None or not isinstance(spec, str):
            # object classes may be lumped into "other": resolve here, to the emitting object when there is one
            xy, obj = self.source_target(spec, house)
            spec = obj if isinstance(spec, str) else xy  # a position stays where it is (make_world finds its object)
        return spec

    def windows_of(self, house: House) -> tuple:
        """The windows: as declared, or (built-in house) each window mask's extent as a segment."""
        if self.windows or self.fixed_house is not None:
            return self.windows
        out = []
        for role, mask in (("inlet", house.inlet), ("outlet", house.outlet)):
            if mask.any():
                xy = house.grid.cell_centres()[mask]
                lo, hi = xy.min(axis=0), xy.max(axis=0)
                out.append({"role": role, "from": (float(lo[0]), float(lo[1])), "to": (float(hi[0]), float(hi[1])),
                            "width": house.grid.resolution, "cells": int(mask.sum())})
        return tuple(out)

    # --- summary -----------------------------------------------------------------------------------------
    def summary(self, seed: int = 0) -> dict:
        """What ``psgsl world check`` prints of the world itself: grid, rooms and areas, objects per class,
        windows, sources (position, room and emitting object). Whether the robot can find each source is the search's question:
        :func:`psgsl_pgm.search.findability`."""
        house = self.house(seed)
        g = house.grid
        cell_area = g.resolution ** 2
        rooms = {}
        for i, name in enumerate(house.room_names):
            rooms[name] = rooms.get(name, 0.0) + float((house.room_labels == i).sum()) * cell_area
        objects: dict = {}
        for o in house.objects:
            c = _true_class(o)
            objects[c] = objects.get(c, 0) + 1
        start = self.start_for(house)
        region = self.region_mask(house)
        sources = {}
        for name in self.sources:
            xy, obj = self.source_target(name, house)
            room = int(house.room_of(xy))
            sources[name] = {"position": [float(xy[0]), float(xy[1])],
                             "room": house.room_names[room] if room >= 0 else None,
                             "object": None if obj is None else obj.name}
        ont = self.ontology
        # rooms without p(o | room) in the ontology start from the class prior (no room evidence)
        no_rooms = [r for r in dict.fromkeys(house.room_names) if not any(_same(r, o) for o in ont.rooms)]
        return {
            "world": str(self.path),
            "grid": {"rows": g.shape[0], "cols": g.shape[1], "resolution": g.resolution,
                     "extent": [float(v) for v in g.extent], "free_cells": int(g.free.sum())},
            "rooms": rooms,
            "objects": objects,
            "unlisted_classes": sorted(set(objects) - set(ont.classes)),
            "windows": [{"role": w["role"], "from": list(w["from"]), "to": list(w["to"]),
                         "cells": int(w["cells"])} for w in self.windows_of(house)],
            "wind": {k: v for k, v in self.wind.items() if k != "sequence"}
            | ({"snapshots": len(self.wind["sequence"].snapshots)} if self.wind["kind"] == "gaden" else {}),
            "start": [float(start[0]), float(start[1])],
            "sources": sources,
            "source_region": self.source_region if isinstance(self.source_region, str) else "mask",
            "source_region_area": float(region.sum()) * cell_area,
            "ontology": {"classes": list(ont.classes), "gases": list(ont.gases), "rooms": list(ont.rooms),
                         "rooms_at_class_prior": no_rooms},
            "gas": self.gas,
            "model": self.model,
            "semantic_map": None if self.class_beliefs is None else list(self.class_beliefs.shape),
        }


def _same(a: str, b: str) -> bool:
    from ._classes import _key

    return _key(a) == _key(b)


def _true_class(o: SceneObject) -> str:
    """An object's own class (objects lumped into ``other`` keep it in their name, ``class#name``)."""
    if o.class_name == "other" and "#" in o.name:
        return o.name.split("#", 1)[0]
    return o.class_name


def default_world() -> WorldSpec:
    """The embedded house as a world (``psgsl_pgm/data/worlds/house.yaml``); read once per process and file
    content (a WorldSpec is immutable), so the runs of a grid share it.

    Examples
    --------
    >>> from psgsl_pgm.sim import default_world
    >>> spec = default_world()
    >>> spec.path.name, spec.gas, sorted(spec.sources)
    ('house.yaml', 'smoke', ['bed', 'hallway', 'oven'])
    >>> default_world() is spec                               # read once per process
    True
    """
    with resources.as_file(resources.files("psgsl_pgm") / "data" / "worlds" / "house.yaml") as path:
        return _DEFAULT_WORLDS.get(content_digest(Path(path).read_bytes()), lambda: load_world(path))


_DEFAULT_WORLDS = ContentCache(maxsize=1)


def default_world_path() -> Path:
    """The embedded house's world file, ``psgsl_pgm/data/worlds/house.yaml`` (a file of the installed package)."""
    return Path(str(resources.files("psgsl_pgm") / "data" / "worlds" / "house.yaml"))


#: World keys whose value names a file (unless it is one of the listed built-in words).
_FILE_KEYS = {"map": (), "rooms": (), "objects": (), "ontology": ("house",), "room_classes": (),
              "source_region": _REGIONS, "semantic_map": ()}


def world_files(path) -> dict:
    """Every file a world file names, directly or through a file it names: ``{label: path}``.

    Labels are the world key (``map``, ``rooms``, ``objects``, ``ontology``, ``room_classes``,
    ``source_region``, ``semantic_map``, ``wind.gaden_csv`` or ``wind.gaden_csv[i]``) and, for a file named
    inside another, that file's label and field: ``map/image`` (the map's PGM/PNG), ``rooms/image`` or
    ``rooms/categories[i].mask`` (the room images). Paths resolve as :func:`load_world` resolves them. Values
    that name no file (``ontology: house``, ``source_region: rooms``) are left out; a malformed entry is left
    out too (:func:`load_world` is the judge of the file; this function only lists what it would read).

    Raises
    ------
    FileNotFoundError, ValueError
        The world file itself cannot be read as a YAML mapping.
    """
    wpath, data = read_yaml_mapping(path)
    out = {}
    for key, words in _FILE_KEYS.items():
        name = data.get(key)
        if isinstance(name, str) and name.strip() and name not in words:
            out[key] = resolve(wpath, name, key)
    wind = data.get("wind")
    csv = wind.get("gaden_csv") if isinstance(wind, dict) else None
    if isinstance(csv, str) and csv.strip():
        out["wind.gaden_csv"] = resolve(wpath, csv, "wind.gaden_csv")
    elif isinstance(csv, list):
        for i, name in enumerate(csv):
            if isinstance(name, str) and name.strip():
                out[f"wind.gaden_csv[{i}]"] = resolve(wpath, name, f"wind.gaden_csv[{i}]")
    for key, fields in (("map", ("image",)), ("rooms", ("image", "categories"))):
        inner = out.get(key)
        try:
            ipath, idata = read_yaml_mapping(inner) if inner is not None and inner.is_file() else (None, {})
        except (ValueError, FileNotFoundError, TypeError):
            continue
        for f in fields:
            value = idata.get(f)
            if f == "categories" and isinstance(value, list):
                for i, entry in enumerate(value):
                    mask = entry.get("mask") if isinstance(entry, dict) else None
                    if isinstance(mask, str) and mask.strip():
                        out[f"{key}/categories[{i}].mask"] = resolve(ipath, mask, f"categories[{i}].mask")
            elif isinstance(value, str) and value.strip():
                out[f"{key}/{f}"] = resolve(ipath, value, f)
    return out


def load_world(path) -> WorldSpec:
    r"""Load and check a world file (see the module docstring): every file it names and every key.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    WorldSpec

    Raises
    ------
    FileNotFoundError
        The world file does not exist.
    ValueError
        Any bad key or file (also a missing file the world file names): the message starts with the world file
        and names the key (and, for errors inside a named file, that file and its field).

    Examples
    --------
    A world file that uses the embedded floor plan (``builtin``) with one named source:

    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import load_world
    >>> text = ("builtin: default_house\nontology: house\ngas: smoke\nwind: {speed: 0.2}\n"
    ...         "sources: {hallway: [5.0, 6.0]}\n")
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = Path(d) / "world.yaml"
    ...     _ = path.write_text(text)
    ...     spec = load_world(path)
    >>> spec.gas, spec.sources
    ('smoke', {'hallway': (5.0, 6.0)})
    """
    wpath, data = read_yaml_mapping(path)
    where = str(wpath)
    check_keys(where, data, optional=_KEYS)
    try:
        return _load(wpath, where, data)
    except FileNotFoundError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _file(wpath: Path, data: dict, key: str) -> Path:
    p = resolve(wpath, data[key], key)
    if not p.is_file():
        raise ValueError(f"{wpath}: key '{key}' names {p}, which does not exist")
    return p


def _inner(where: str, key: str, exc: Exception) -> ValueError:
    """An error inside a file named by ``key``: keep the file's own message, prefixed by the world key."""
    return ValueError(f"{where}: key '{key}': {exc}")


def _load(wpath: Path, where: str, data: dict) -> WorldSpec:
    builtin = data.get("builtin")
    if builtin is not None:
        if builtin != "default_house":
            raise ValueError(f"{where}: key 'builtin' must be 'default_house', got {builtin!r}")
        clash = sorted(k for k in ("map", "resolution", "rooms", "objects", "semantic_map") if k in data)
        if clash:
            raise ValueError(f"{where}: key 'builtin' describes the house; remove key(s) {clash}")
    else:
        for key in ("map", "rooms", "ontology", "wind"):
            if key not in data:
                raise ValueError(f"{where}: missing required key '{key}'")
    clearance = number(where, "clearance", data.get("clearance", 0.25), positive=True)

    # ontology
    if "ontology" not in data:
        raise ValueError(f"{where}: missing required key 'ontology'")
    if data["ontology"] == "house":
        if "room_classes" in data:
            raise ValueError(f"{where}: key 'room_classes' cannot refine the built-in 'house' ontology")
        ontology = house_ontology()
    else:
        opath = _file(wpath, data, "ontology")
        rpath = _file(wpath, data, "room_classes") if "room_classes" in data else None
        try:
            ontology = Ontology.from_yaml(opath, room_classes=rpath)
        except (ValueError, TypeError, FileNotFoundError) as exc:
            raise _inner(where, "ontology" if rpath is None else "ontology/room_classes", exc) from None
    gas = data.get("gas")
    if gas is not None and gas not in ontology.gases and gas != "unknown":
        raise ValueError(f"{where}: key 'gas': {gas!r} is not a gas of the ontology {list(ontology.gases)} nor "
                         "'unknown'")

    # the house
    house, object_classes, map_path = None, (), None
    if builtin is None:
        house, object_classes, map_path = _load_house(wpath, where, data, ontology)
    probe = house if house is not None else default_house(0)

    windows = ()
    wind = _load_wind(wpath, where, data.get("wind", {}), probe, builtin is not None)
    if house is not None:
        house, windows = _open_windows(where, house, data.get("wind", {}), wind)
        if wind["kind"] == "gaden":
            wind["sequence"] = _gaden(wpath, where, data["wind"], house.grid)
        elif not (house.inlet.any() and house.outlet.any()):
            raise ValueError(f"{where}: key 'wind.windows' needs at least one inlet and one outlet for the potential "
                             "flow")
        probe = house

    # where a source may be
    region = data.get("source_region", "rooms")
    if isinstance(region, str) and region in _REGIONS:
        region_value = region
    elif isinstance(region, str) and builtin is None:
        p = _file(wpath, data, "source_region")
        grey = read_grey_image(p, where=where, field="source_region")
        region_value = _mask_to_grid(where, "source_region", grey, house, map_path)
    else:
        raise ValueError(f"{where}: key 'source_region' must be 'rooms', 'free' or a mask image, got {region!r}")

    # start and sources
    start = None
    if "start" in data:
        start = np.array(number_list(where, "start", data["start"], length=2))
    sources = _load_sources(where, data.get("sources", {}))

    beliefs = None
    if "semantic_map" in data:

        p = _file(wpath, data, "semantic_map")
        lump = data.get("other_classes", "error")
        if lump not in ("error", "lump"):
            raise ValueError(f"{where}: key 'other_classes' must be 'error' or 'lump', got {lump!r}")
        try:
            beliefs = read_class_beliefs(p, ontology.classes, grid=house.grid, class_prior=ontology.class_prior,
                                         other_classes=lump)
        except (ValueError, TypeError) as exc:
            raise _inner(where, "semantic_map", exc) from None
        if beliefs.shape[:2] != house.grid.shape:
            raise ValueError(f"{where}: key 'semantic_map': beliefs of shape {beliefs.shape} do not cover the "
                             f"working grid {house.grid.shape}")

    if "other_classes" in data and "semantic_map" not in data:
        raise ValueError(f"{where}: key 'other_classes' applies to a 'semantic_map', and the file names none")
    if house is not None and data["ontology"] != "house" and ontology.rooms:
        _check_rooms(where, "room_classes" if "room_classes" in data else "ontology", ontology.rooms, house,
                     data["rooms"])

    model = data.get("model", "ideal")
    try:
        model = WorldModel.parse(model).name
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{where}: key 'model': {exc}") from None
    spec = WorldSpec(wpath, ontology, gas, wind, start, sources, region_value, beliefs, windows, house, builtin,
                     clearance, object_classes, map_path, model)
    _check_positions(where, spec, probe)
    return spec


def _check_rooms(where: str, key: str, rooms, house: House, room_map) -> None:
    """Every room of p(o | room) must be a room of the room map (case and spaces ignored): a misspelt room
    would leave the map's room at the class prior without a word. Rooms of the map the table omits entirely
    start at the class prior (``world check`` warns)."""
    from ..io._class_maps import unknown_names
    from ._classes import match_names

    missing = [r for r, i in zip(rooms, match_names(rooms, house.room_names)) if i < 0]
    if missing:
        text = unknown_names(missing, house.room_names, "room", f"the room map {room_map} does not have")
        raise ValueError(f"{where}: key '{key}': p(o | room) is given for {'a ' if len(missing) == 1 else ''}{text}")


def _load_house(wpath: Path, where: str, data: dict, ontology):
    mpath = _file(wpath, data, "map")
    try:
        fine = load_ros_map(mpath)
    except (ValueError, FileNotFoundError) as exc:
        raise _inner(where, "map", exc) from None
    rpath = _file(wpath, data, "rooms")
    try:
        fine_labels, names = load_room_map(rpath, like=fine)
    except (ValueError, FileNotFoundError) as exc:
        raise _inner(where, "rooms", exc) from None
    res = number(where, "resolution", data["resolution"], positive=True) if "resolution" in data else fine.resolution
    factor = coarsen_factor(fine.resolution, res, where=f"{where}: key 'resolution'")
    grid = coarsen_occupancy(fine, factor)
    labels = coarsen_labels(fine_labels, len(names), factor)
    _check_rooms_kept(where, fine_labels, labels, names, fine.resolution, res)
    objects, classes_seen = [], []
    if "objects" in data:
        opath = _file(wpath, data, "objects")
        try:
            raw = load_objects(opath, like=grid)
        except (ValueError, FileNotFoundError) as exc:
            raise _inner(where, "objects", exc) from None
        known = set(ontology.classes)
        for i, o in enumerate(raw):
            cls = canonical_class(o.class_name)
            classes_seen.append(cls)
            name = o.name if o.name != o.class_name else f"{cls}_{i}"
            if cls in known:
                objects.append(SceneObject(cls, o.footprint, o.z_range, name))
            else:  # the lab's rule: a class the ontology does not list is an "other"; keep the class in the name
                objects.append(SceneObject("other", o.footprint, o.z_range, f"{cls}#{name}"))
    empty = np.zeros(grid.shape, bool)
    house = House(grid, labels, tuple(names), tuple(objects), empty, empty, tuple(ontology.classes))
    return house, tuple(dict.fromkeys(classes_seen)), mpath


def _check_rooms_kept(where: str, fine_labels, labels, names, fine_res: float, res: float) -> None:
    """ValueError naming ``resolution`` when a room of the room map keeps no cell of the working grid: the cells are
    coarser than the rooms (every later check — windows, sources — would fail for that reason)."""
    lost = [n for i, n in enumerate(names) if (fine_labels == i).any() and not (labels == i).any()]
    if not lost:
        return
    areas = {n: float((fine_labels == i).sum()) * fine_res**2 for i, n in enumerate(names) if (fine_labels == i).any()}
    small = min(areas.values())
    side = max(fine_res, np.floor(np.sqrt(small) / 3 / fine_res) * fine_res)  # three cells across the smallest
    side = float(np.format_float_positional(side, precision=6))
    raise ValueError(f"{where}: key 'resolution': cells of {res:g} m are coarser than the rooms: "
                     f"{', '.join(lost)} keep{'s' if len(lost) == 1 else ''} no cell (the smallest room has "
                     f"{small:.2f} m²); use a resolution of at most {side:g} m")


def _load_wind(wpath: Path, where: str, wind, probe: House, builtin: bool) -> dict:
    if not isinstance(wind, dict):
        raise ValueError(f"{where}: key 'wind' must be a mapping (speed + windows, or gaden_csv + height), got {wind!r}")
    if "gaden_csv" in wind:
        check_keys(f"{where}: key 'wind'", wind, required=("gaden_csv", "height"), optional=_WIND_GADEN)
        number(where, "wind.height", wind["height"])
        if "period" in wind:
            number(where, "wind.period", wind["period"], positive=True)
        if builtin:
            raise ValueError(f"{where}: key 'wind.gaden_csv' is not available with 'builtin'")
        return {"kind": "gaden", "height": float(wind["height"]), "period": float(wind.get("period", 1.0))}
    allowed = _WIND_POTENTIAL if not builtin else ("speed", "perturbation")
    check_keys(f"{where}: key 'wind'", wind, required=("speed",), optional=allowed)
    speed = number(where, "wind.speed", wind["speed"], positive=True)
    if speed > MAX_WIND_SPEED:
        raise ValueError(f"{where}: key 'wind.speed': {speed:g} m/s is no indoor wind (at most {MAX_WIND_SPEED:g} m/s; "
                         "indoor air moves at tenths of a metre per second): give the mean speed in m/s")
    pert = number(where, "wind.perturbation", wind.get("perturbation", 0.3), nonnegative=True)
    return {"kind": "potential", "speed": speed, "perturbation": pert}


def _open_windows(where: str, house: House, wind: dict, spec: dict):
    items = wind.get("windows", [])
    if not isinstance(items, list):
        raise ValueError(f"{where}: key 'wind.windows' must be a list of {{role, from, to}}, got {items!r}")
    inlet = np.zeros(house.shape, bool)
    outlet = np.zeros(house.shape, bool)
    out = []
    for i, w in enumerate(items):
        key = f"wind.windows[{i}]"
        check_keys(f"{where}: key '{key}'", w, required=("role", "from", "to"), optional=("width",))
        role = w["role"]
        if role not in ("inlet", "outlet"):
            raise ValueError(f"{where}: key '{key}.role' must be 'inlet' or 'outlet', got {role!r}")
        p0 = number_list(where, f"{key}.from", w["from"], length=2)
        p1 = number_list(where, f"{key}.to", w["to"], length=2)
        width = number(where, f"{key}.width", w.get("width", 0.15), positive=True)
        mask = segment_mask(house.grid, p0, p1, width=max(width, 0.5 * house.grid.resolution))
        if not mask.any():
            raise ValueError(f"{where}: key '{key}': no cell of the map lies within {width} m of the segment "
                             f"{p0} -> {p1} (the map spans {house.grid.extent})")
        target = inlet if role == "inlet" else outlet
        other = outlet if role == "inlet" else inlet
        if (mask & other).any():
            raise ValueError(f"{where}: key '{key}': the window overlaps a window of the other role")
        target |= mask
        out.append({"role": role, "from": tuple(p0), "to": tuple(p1), "width": width, "cells": int(mask.sum())})
    grid = house.grid.with_occupancy(house.grid.occupancy & ~inlet & ~outlet)
    opened = House(grid, house.room_labels, house.room_names, house.objects, inlet, outlet, house.classes)
    return opened, tuple(out)


def _gaden(wpath: Path, where: str, wind: dict, grid: GridMap):
    from ._cfd import read_gaden_wind_snapshots

    names = wind["gaden_csv"]
    names = [names] if isinstance(names, str) else names
    if not isinstance(names, list) or not names:
        raise ValueError(f"{where}: key 'wind.gaden_csv' must be a CSV file or a list of them, got {names!r}")
    paths = []
    for i, n in enumerate(names):
        p = resolve(wpath, n, f"wind.gaden_csv[{i}]")
        if not p.is_file():
            raise ValueError(f"{where}: key 'wind.gaden_csv[{i}]' names {p}, which does not exist")
        paths.append(p)
    try:
        return read_gaden_wind_snapshots(paths, like=grid, height=float(wind["height"]),
                                         period=float(wind.get("period", 1.0)))
    except (ValueError, FileNotFoundError) as exc:
        raise _inner(where, "wind.gaden_csv", exc) from None


def _mask_to_grid(where: str, key: str, grey: np.ndarray, house: House, map_path) -> np.ndarray:
    """A mask image in the map's pixel frame (fine or working grid) -> (H, W) bool on the working grid."""
    fine = load_ros_map(map_path)
    img = grey[::-1] > 127
    if img.shape == house.grid.shape:
        return img
    if img.shape != fine.shape:
        raise ValueError(f"{where}: key '{key}': the mask is {img.shape[1]} x {img.shape[0]} pixels; expected the "
                         f"map's {fine.shape[1]} x {fine.shape[0]} or the working grid's "
                         f"{house.grid.shape[1]} x {house.grid.shape[0]}")
    factor = coarsen_factor(fine.resolution, house.grid.resolution)
    return coarsen_labels(img.astype(np.int64) - 1, 1, factor) == 0  # majority of fine pixels


def _load_sources(where: str, sources) -> dict:
    if not isinstance(sources, dict):
        raise ValueError(f"{where}: key 'sources' must be a mapping name -> [x, y] or object class, got {sources!r}")
    out = {}
    for name, value in sources.items():
        if not isinstance(name, str) or not name.strip() or "," in name:
            raise ValueError(f"{where}: key 'sources' has an invalid name {name!r} (a non-empty string without ',')")
        if isinstance(value, str):
            if not value.strip():
                raise ValueError(f"{where}: key 'sources.{name}' must be an object class or [x, y], got {value!r}")
            out[name] = canonical_class(value)
        else:
            out[name] = tuple(number_list(where, f"sources.{name}", value, length=2))
    return out


def check_free_cells(spec: WorldSpec, seed: int = 0, *, limit: int = MAX_FREE_CELLS) -> None:
    """ValueError naming the world's ``resolution`` when its house has more free cells than ``limit``
    (:data:`MAX_FREE_CELLS`: the estimators and the closed loop would need more than 2 GB), with the resolution
    that fits.

    Parameters
    ----------
    spec : WorldSpec
        The world (its map and ``resolution``).
    seed : int
        The seed of the house to count (a world file's house is the same for every seed).
    limit : int, keyword-only
        The most free cells allowed.

    Raises
    ------
    ValueError
        More free cells than ``limit``; the message names ``resolution`` and a value that fits.

    Examples
    --------
    >>> from psgsl_pgm.sim import check_free_cells, default_world
    >>> spec = default_world()
    >>> check_free_cells(spec) is None                        # the embedded house fits
    True
    >>> try:
    ...     check_free_cells(spec, limit=1000)
    ... except ValueError as err:
    ...     print("set 'resolution: 0.4'" in str(err))          # the message names a resolution that fits
    True
    """
    house = spec.house(seed)
    g = house.grid
    free = int(g.free.sum())
    if free <= limit:
        return
    factor = int(np.ceil(np.sqrt(free / limit)))
    while free / factor**2 > limit:
        factor += 1
    raise ValueError(f"{spec.path}: key 'resolution': {free:,} free cells of {g.resolution:g} m are more than the "
                     f"{limit:,} the estimators and the closed loop run on within 2 GB of memory; set 'resolution: "
                     f"{float(np.format_float_positional(g.resolution * factor, precision=6)):g}' (or coarser) in the "
                     "world file")


def _on_furniture(where: str, name: str, xy, house: House, region) -> str:
    """The message for a source on an occupied cell inside a room: furniture the map draws as occupied."""
    import scipy.ndimage as ndi

    g = house.grid
    rc = g.world_to_cell(xy)
    room = house.room_names[int(house.room_labels[rc[0], rc[1]])]
    _, (ri, ci) = ndi.distance_transform_edt(~region, return_indices=True)
    near = g.cell_to_world(np.array([[ri[rc[0], rc[1]], ci[rc[0], rc[1]]]]))[0]
    return (f"{where}: key 'sources.{name}' ({xy[0]:g}, {xy[1]:g}) lies on furniture: an occupied cell of the "
            f"map inside the room {room} (the map draws furniture as occupied, and a source must lie in a free "
            f"cell); use a walls-only map with the furniture listed under 'objects' (then 'sources.{name}' may name "
            f"the emitting object's class), or move the source to the nearest free cell of the source region, "
            f"({near[0]:.2f}, {near[1]:.2f})")


def _check_positions(where: str, spec: WorldSpec, house: House) -> None:
    g = house.grid
    start = spec.start_for(house)
    nav = navigable(house, spec.clearance)
    rc = g.world_to_cell(start)
    if not g.contains(rc) or not nav[rc[0], rc[1]]:
        why = "outside the map" if not g.contains(rc) else f"not navigable (free and {spec.clearance} m from walls, " \
                                                          "furniture and windows)"
        raise ValueError(f"{where}: key 'start' ({start[0]:g}, {start[1]:g}) is {why}")
    region = spec.region_mask(house)
    if not region.any():
        raise ValueError(f"{where}: key 'source_region' allows no free cell")
    for name in spec.sources:
        try:
            xy = spec.resolve_source(name, house)
        except ValueError as exc:
            raise ValueError(f"{where}: key 'sources.{name}': {exc}") from None
        rc = g.world_to_cell(xy)
        if not g.contains(rc):
            raise ValueError(f"{where}: key 'sources.{name}' ({xy[0]:g}, {xy[1]:g}) lies outside the map {g.extent}")
        if not region[rc[0], rc[1]] and g.occupancy[rc[0], rc[1]] and house.room_labels[rc[0], rc[1]] >= 0:
            raise ValueError(_on_furniture(where, name, xy, house, region))
        if not region[rc[0], rc[1]]:
            raise ValueError(f"{where}: key 'sources.{name}' ({xy[0]:g}, {xy[1]:g}) lies outside the source region "
                             f"({spec.source_region if isinstance(spec.source_region, str) else 'mask'}) or on a wall")
