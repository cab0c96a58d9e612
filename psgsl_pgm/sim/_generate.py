"""Generated homes: :func:`generate_house` draws a floor plan, furniture and wind from one seed.

Each house is a world of the same type a world file loads (:class:`WorldSpec`, :meth:`GeneratedHouse.world`)
and can be written as a world file (:meth:`GeneratedHouse.write`: ROS map, room masks, object list, ontology,
wind windows, start) that :func:`load_world` reads back to the same house, so ``psgsl world check`` and every
command with ``--world`` run on it.

The generative model (one ``numpy.random.default_rng([seed, 0x40_05E])``):

* rooms: ``n_rooms`` uniform in {3, …, 8} unless given; types ``room_type_sequence`` unless given;
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
import yaml

from ._draw_house import AREA_PER_ROOM, AREA_RANGE, ROOM_RANGE, check_request, draw_house
from ._floorplan import RES
from ._house import House
from ._objects import save_objects
from ._roommap import save_room_map
from ._rosmap import save_ros_map

__all__ = ["AREA_PER_ROOM", "AREA_RANGE", "GeneratedHouse", "ROOM_RANGE", "check_request", "generate_house"]


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
        One type of ``ROOM_TYPES`` per room (default: ``room_type_sequence``).
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
    house, rooms, doors, windows, speed, start = draw_house(seed, n_rooms=n_rooms, area=area,
                                                            room_types=room_types, wind_speed=wind_speed)
    return GeneratedHouse(int(seed), house, rooms, doors, windows, speed, 0.3, start)
