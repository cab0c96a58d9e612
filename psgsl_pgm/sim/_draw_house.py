"""A generated home's house drawn from its seed: the floor plan, furniture, windows and the wind speed.

:func:`draw_house` is the generative model of :func:`psgsl_pgm.sim.generate_house` without the world around it,
so the generator's ontology (:mod:`psgsl_pgm.sim._generated_ontology`, which counts reference houses) and the
generated homes' worlds (:mod:`psgsl_pgm.sim._generate`, which take that ontology as their default) import it
without importing each other.
"""

from __future__ import annotations

import numpy as np
import scipy.ndimage as ndi

from .._shared._validate import index, real_number
from ..geometry._grid import GridMap
from ._classes import HOUSE_CLASSES, HOUSE_ROOMS
from ._floorplan import RES, ROOM_TYPES, draw_plan, room_type_sequence
from ._furnish import furnish
from ._house import House, segment_mask

__all__ = ["AREA_PER_ROOM", "AREA_RANGE", "ROOM_RANGE", "check_request", "draw_house"]

#: Smallest and largest floor area of a generated home, m² (outline, walls included).
AREA_RANGE = (40.0, 200.0)
#: Fewest and most rooms.
ROOM_RANGE = (3, 8)
#: m² of outline per room at least (a room's inside is at least 1.9 m × 1.9 m, plus walls and doors).
AREA_PER_ROOM = 14.0
_WINDOW_WIDTH = 0.06  # m: exactly the two cells of the outer wall across the window segment (0.05 m from it)
_ATTEMPTS = 200
_TAG = 0x40_05E


def check_request(seed, n_rooms, area, room_types):
    """Validated ``(n_rooms, area, room_types)`` of a request (None: drawn); TypeError/ValueError naming the
    argument."""
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


def draw_house(seed: int, *, n_rooms=None, area=None, room_types=None, wind_speed=None) -> tuple:
    """The drawn parts of :func:`psgsl_pgm.sim.generate_house` (its parameters and its one random generator, so
    the same seed draws the same house).

    Returns
    -------
    house : House
        Grid (windows open), room labels, objects, inlet and outlet.
    rooms : tuple of (type, (x0, x1, y0, y1))
        Each room's rectangle, m.
    doors : tuple of (x0, x1, y0, y1)
        Door openings, m.
    windows : tuple of dict
        As a world file declares them.
    speed : float
        Mean wind speed, m/s.
    start : (2,) ndarray
        The robot's start, m.
    """
    n_rooms, area, room_types = check_request(seed, n_rooms, area, room_types)
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
    return house, rooms, doors, windows, speed, start




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
