"""Generated homes: :func:`generate_house` draws a floor plan, furniture and wind from one seed.

Each house is a world of the same type a world file loads (:class:`WorldSpec`, :meth:`GeneratedHouse.world`)
and can be written as a world file (:meth:`GeneratedHouse.write`: ROS map, room masks, object list, ontology,
wind windows, start) that :func:`load_world` reads back to the same house, so ``psgsl world check`` and every
command with ``--world`` run on it.

The generative model (one ``numpy.random.default_rng([seed, 0x40_05E])``):

* rooms: ``n_rooms`` uniform in {3, …, 8} unless given; types :func:`room_type_sequence` unless given;
* area: uniform in [max(40, 14 n), 200] m² unless given (outline, walls included);
* plan: :func:`psgsl_pgm.sim._floorplan.draw_plan` (rooms, 0.2-m walls, 0.9-m doors, one inlet and one outlet
  window); furniture: :func:`psgsl_pgm.sim._furnish.furnish` from the generator's p(o | room) table;
* wind: potential flow between the windows, mean speed uniform in [0.1, 0.3] m/s, perturbation 0.3;
* the robot's start: the centre of the living room (the largest room when there is none).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.ndimage as ndi
import yaml

from .._shared._validate import index, real_number
from ..geometry._grid import GridMap
from ._classes import HOUSE_CLASSES, HOUSE_ROOMS
from ._floorplan import RES, ROOM_TYPES, draw_plan, room_type_sequence
from ._furnish import furnish
from ._house import House, segment_mask
from ._objects import save_objects
from ._roommap import save_room_map
from ._rosmap import save_ros_map

__all__ = ["AREA_RANGE", "GeneratedHouse", "ROOM_RANGE", "generate_house"]

#: Smallest and largest floor area of a generated home, m² (outline, walls included).
AREA_RANGE = (40.0, 200.0)
#: Fewest and most rooms.
ROOM_RANGE = (3, 8)
#: m² of outline per room at least (a room's inside is at least 1.9 m × 1.9 m, plus walls and doors).
AREA_PER_ROOM = 14.0
_WINDOW_WIDTH = 0.06  # m: exactly the two cells of the outer wall across the window segment (0.05 m from it)
_ATTEMPTS = 200
_TAG = 0x40_05E


@dataclass(frozen=True, eq=False)
class GeneratedHouse:
    """A generated home.

    Attributes
    ----------
    seed : int
    house : House
        Grid (windows open), room labels over the room types present, objects, inlet and outlet.
    rooms : tuple of (type, (x0, x1, y0, y1))
        Each room's rectangle in metres, walls included (rooms of one type share a label in ``house``).
    doors : tuple of (x0, x1, y0, y1)
        Door openings, m.
    windows : tuple of dict
        ``{"role", "from", "to", "width", "cells"}`` as a world file declares them.
    wind_speed, perturbation : float
        Mean wind speed (m/s) and eddy strength (fraction of it).
    start : (2,) ndarray
        The robot's start, m.
    """

    seed: int
    house: House
    rooms: tuple
    doors: tuple
    windows: tuple
    wind_speed: float
    perturbation: float
    start: np.ndarray

    @property
    def area(self) -> float:
        """Floor area of the outline, m²."""
        h, w = self.house.shape
        return h * w * RES * RES

    @property
    def n_rooms(self) -> int:
        return len(self.rooms)

    def world(self, ontology=None, *, gas: str = "smoke", sources=None):
        """This house as a world (:class:`WorldSpec`, the type :func:`load_world` returns).

        Parameters
        ----------
        ontology : psgsl_pgm.Ontology, optional
            The robot's ontology; default :func:`generated_ontology` (the generator's reference houses). Its
            p(o | room) is kept for the room types this house has (a world file lists no other room).
        gas : str, keyword-only
        sources : dict, optional, keyword-only
            Name -> object class or (x, y), as a world file's ``sources``.
        """
        from ._generated_ontology import generated_ontology
        from ._worldfile import WorldSpec, _check_positions, _load_sources

        ontology = _rooms_present(generated_ontology() if ontology is None else ontology, self.house.room_names)
        if gas not in ontology.gases:
            raise ValueError(f"gas must be a gas of the ontology {list(ontology.gases)}, got {gas!r}")
        where = f"generated house {self.seed}"
        src = _load_sources(where, {} if sources is None else {k: (list(v) if not isinstance(v, str) else v)
                                                                for k, v in sources.items()})
        spec = WorldSpec(Path(where), ontology, gas, {"kind": "potential", "speed": self.wind_speed,
                                                       "perturbation": self.perturbation},
                         self.start.copy(), src, "rooms", None, self.windows, self.house, None, 0.25,
                         tuple(dict.fromkeys(o.class_name for o in self.house.objects)), None)
        _check_positions(where, spec, self.house)
        return spec

    def write(self, folder, *, ontology=None, gas: str = "smoke", sources=None, name: str = "world.yaml") -> Path:
        """Write this house as a world file and the files it names into ``folder`` (created; files replaced).

        Files: ``map.yaml`` + ``map.pgm`` (walls, windows closed: the world file opens them), ``rooms.yaml`` +
        one PNG per room type, ``objects.yaml``, ``ontology.yaml`` (``ontology``, default
        :func:`generated_ontology`) and ``name``. Each file is written beside its final name and renamed into
        place (the world file last), so a reader never sees a half-written file.

        Returns
        -------
        Path
            The world file.
        """
        from ._generated_ontology import generated_ontology

        ontology = _rooms_present(generated_ontology() if ontology is None else ontology, self.house.room_names)
        self.world(ontology, gas=gas, sources=sources)  # the same checks as a loaded world, before writing
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        h = self.house
        closed = h.grid.with_occupancy(h.grid.occupancy | h.inlet | h.outlet)
        _atomic_files(folder, lambda tmp: save_ros_map(closed, tmp / "map.yaml"))
        _atomic_files(folder, lambda tmp: save_room_map(h.room_labels, h.room_names, tmp / "rooms.yaml"))
        _atomic_files(folder, lambda tmp: save_objects(h.objects, tmp / "objects.yaml"))
        _atomic_text(folder / "ontology.yaml", ontology.to_yaml())
        world = {
            "map": "map.yaml", "rooms": "rooms.yaml", "objects": "objects.yaml", "ontology": "ontology.yaml",
            "gas": gas, "source_region": "rooms", "clearance": 0.25,
            "wind": {"speed": float(self.wind_speed), "perturbation": float(self.perturbation),
                     "windows": [{"role": w["role"], "from": [float(v) for v in w["from"]],
                                  "to": [float(v) for v in w["to"]], "width": float(w["width"])}
                                 for w in self.windows]},
            "start": [float(v) for v in self.start],
        }
        if sources:
            world["sources"] = {k: (v if isinstance(v, str) else [float(x) for x in v]) for k, v in sources.items()}
        header = (f"# Generated home: psgsl_pgm.sim.generate_house(seed={self.seed}), {self.n_rooms} rooms "
                  f"({', '.join(t for t, _ in self.rooms)}), {self.area:g} m².\n")
        path = folder / name
        _atomic_text(path, header + yaml.safe_dump(world, sort_keys=False))
        return path


def _rooms_present(ontology, names):
    """``ontology`` with p(o | room) only for the room types the house has (a world file's rule: every room of
    the table must be a room of the map)."""
    from ..core._ontology import Ontology
    from ._classes import match_names

    if not ontology.rooms:
        return ontology
    keep = [i for i, j in enumerate(match_names(ontology.rooms, names)) if j >= 0]
    if len(keep) == len(ontology.rooms):
        return ontology
    return Ontology(ontology.classes, ontology.gases, ontology.source_table, ontology.class_prior,
                    rooms=[ontology.rooms[i] for i in keep], room_table=ontology.room_table[keep] if keep else None)


def _atomic_text(path: Path, text: str) -> None:
    from ..io._output import write_file_atomically

    write_file_atomically(path, lambda fh: fh.write(text.encode("utf-8")), option="folder")


def _atomic_files(folder: Path, write) -> None:
    """Run ``write(tmp)`` in a fresh temporary folder inside ``folder``, then rename each file it made into
    ``folder`` (one rename per file)."""
    import shutil
    import tempfile

    tmp = Path(tempfile.mkdtemp(prefix=".part-", dir=folder))
    try:
        write(tmp)
        for f in sorted(tmp.iterdir()):
            f.replace(folder / f.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _check_request(seed, n_rooms, area, room_types):
    index(seed, "seed")
    if room_types is not None:
        if isinstance(room_types, str) or not hasattr(room_types, "__iter__"):
            raise TypeError(f"room_types must be a list of room types of {ROOM_TYPES}, got {room_types!r}")
        room_types = tuple(room_types)
        bad = [t for t in room_types if t not in ROOM_TYPES]
        if bad:
            raise ValueError(f"room_types must name types of {ROOM_TYPES}, got {bad}")
    if n_rooms is not None:
        n_rooms = index(n_rooms, "n_rooms")
        if not ROOM_RANGE[0] <= n_rooms <= ROOM_RANGE[1]:
            raise ValueError(f"n_rooms must be in [{ROOM_RANGE[0]}, {ROOM_RANGE[1]}], got {n_rooms}")
    if room_types is not None:
        if n_rooms is not None and len(room_types) != n_rooms:
            raise ValueError(f"room_types must give one type per room: n_rooms is {n_rooms}, got "
                             f"{len(room_types)} types {list(room_types)}")
        if not ROOM_RANGE[0] <= len(room_types) <= ROOM_RANGE[1]:
            raise ValueError(f"room_types must name {ROOM_RANGE[0]} to {ROOM_RANGE[1]} rooms, got "
                             f"{len(room_types)}: {list(room_types)}")
    if area is not None:
        area = real_number(area, "area", unit="m²")
        if not AREA_RANGE[0] <= area <= AREA_RANGE[1]:
            raise ValueError(f"area must be in [{AREA_RANGE[0]:g}, {AREA_RANGE[1]:g}] m², got {area:g}")
        n_check = n_rooms if n_rooms is not None else (len(room_types) if room_types is not None else None)
        if n_check is not None and area < AREA_PER_ROOM * n_check:
            raise ValueError(f"area must be at least {AREA_PER_ROOM:g} m² per room: {n_check} rooms need "
                             f">= {AREA_PER_ROOM * n_check:g} m², got {area:g}")
    return n_rooms, area, room_types


def generate_house(seed: int, *, n_rooms: int | None = None, area: float | None = None, room_types=None,
                   wind_speed: float | None = None) -> GeneratedHouse:
    """A generated home (module docstring): floor plan, furniture, windows and wind, all from ``seed``.

    Parameters
    ----------
    seed : int
        ≥ 0; the same seed (and options) gives the same house.
    n_rooms : int, optional, keyword-only
        3 to 8 (default: drawn).
    area : float, optional, keyword-only
        Outline area in m², within :data:`AREA_RANGE` and ≥ :data:`AREA_PER_ROOM` per room (default: drawn).
        The drawn plan's sides are whole cells: its area is within one cell row of ``area``.
    room_types : sequence of str, optional, keyword-only
        One type of :data:`ROOM_TYPES` per room (default: :func:`room_type_sequence`).
    wind_speed : float, optional, keyword-only
        Mean wind speed, m/s (default: drawn).

    Returns
    -------
    GeneratedHouse

    Raises
    ------
    TypeError, ValueError
        An impossible request (2 rooms, a room count that differs from the number of types, an area outside
        the range or too small for the rooms, an unknown room type), naming the argument.

    Examples
    --------
    >>> g = generate_house(3, n_rooms=4, area=60.0)
    >>> g.n_rooms, 59.0 <= g.area <= 61.0
    (4, True)
    """
    n_rooms, area, room_types = _check_request(seed, n_rooms, area, room_types)
    if wind_speed is not None:
        wind_speed = real_number(wind_speed, "wind_speed", unit="m/s")
        if wind_speed <= 0:
            raise ValueError(f"wind_speed must be positive (m/s), got {wind_speed:g}")
    rng = np.random.default_rng([int(seed), _TAG])
    if room_types is None:
        n = int(rng.integers(ROOM_RANGE[0], ROOM_RANGE[1] + 1)) if n_rooms is None else n_rooms
        room_types = room_type_sequence(n)
    n = len(room_types)
    if area is None:
        area = float(rng.uniform(max(AREA_RANGE[0], AREA_PER_ROOM * n), AREA_RANGE[1]))
    speed = float(rng.uniform(0.1, 0.3)) if wind_speed is None else wind_speed
    for _ in range(_ATTEMPTS):
        plan = draw_plan(rng, area, room_types)
        if plan is None:
            continue
        house, windows, start = _assemble(rng, plan)
        if house is not None:
            break
    else:  # pragma: no cover - the checked request ranges always admit a plan
        raise RuntimeError(f"no floor plan of {n} rooms in {area:g} m² after {_ATTEMPTS} draws (seed {seed})")
    rooms = tuple((t, (c0 * RES, c1 * RES, r0 * RES, r1 * RES)) for t, (c0, c1, r0, r1) in plan.rooms)
    doors = tuple((c0 * RES, c1 * RES, r0 * RES, r1 * RES) for c0, c1, r0, r1 in plan.doors)
    return GeneratedHouse(int(seed), house, rooms, doors, windows, speed, 0.3, start)


def _assemble(rng, plan):
    """The House of a plan (room labels, furniture, opened windows), its windows and the robot's start; house
    None when the furniture leaves a room unreachable (never expected: the placement checks it)."""
    rows, cols = plan.shape
    grid = GridMap(plan.walls, RES)
    inlet = np.zeros(plan.shape, bool)
    outlet = np.zeros(plan.shape, bool)
    windows = []
    for role, p0, p1 in plan.windows:
        m = segment_mask(grid, p0, p1, width=_WINDOW_WIDTH)
        (inlet if role == "inlet" else outlet)[...] |= m
        windows.append({"role": role, "from": tuple(float(v) for v in p0), "to": tuple(float(v) for v in p1),
                        "width": _WINDOW_WIDTH, "cells": int(m.sum())})
    present = [t for t in HOUSE_ROOMS if any(r[0] == t for r in plan.rooms)]
    labels = np.full(plan.shape, -1, dtype=np.int64)
    for t, (c0, c1, r0, r1) in plan.rooms:
        block = labels[r0:r1, c0:c1]
        block[~plan.walls[r0:r1, c0:c1]] = present.index(t)
    # doorways: the room of the nearest labelled cell (as the embedded house)
    inside = labels >= 0
    _, (ri, ci) = ndi.distance_transform_edt(~inside, return_indices=True)
    door = ~plan.walls & ~inside
    labels[door] = labels[ri[door], ci[door]]
    labels[plan.walls] = -1
    living = [r for t, r in plan.rooms if t == "LivingRoom"] or [max((r for _, r in plan.rooms),
                                                                     key=lambda r: (r[1] - r[0]) * (r[3] - r[2]))]
    c0, c1, r0, r1 = living[0]
    start = np.array([(c0 + c1) // 2 + 0.5, (r0 + r1) // 2 + 0.5]) * RES  # a cell centre
    objects = furnish(rng, plan, inlet | outlet, start)
    opened = grid.with_occupancy(plan.walls & ~inlet & ~outlet)
    house = House(opened, labels, tuple(present), tuple(objects), inlet, outlet, HOUSE_CLASSES)
    return house, tuple(windows), start
