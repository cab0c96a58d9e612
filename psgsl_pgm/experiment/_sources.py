"""Checking source specifications against the house before any run starts (``psgsl experiment``)."""

from __future__ import annotations

import numpy as np

from ..sim import default_house
from ._config import parse_source

__all__ = ["check_sources"]


def check_sources(sources, *, seeds=(0,), house=None) -> list:
    """Refuse, before any search runs, a source the house cannot hold.

    A class name must have an object in the house; a position ``(x, y)`` must lie inside the map and in a
    free cell (an error that would otherwise surface in a worker, hours into a grid). The built-in house has
    the same walls and object classes for every seed (only the furniture moves), so the house of the first
    seed is checked.

    Parameters
    ----------
    sources : sequence
        Source specifications (see :func:`parse_source`).
    seeds : iterable of int, keyword-only
        The seeds of the grid; ``default_house`` of the first is checked. Ignored when ``house`` is given.
    house : psgsl_pgm.sim.House, optional, keyword-only
        One house to check against instead.

    Returns
    -------
    list
        The parsed specifications.

    Raises
    ------
    ValueError
        An unknown class (naming the classes present) or a position outside the map or in an occupied cell
        (naming the map's extent).

    Examples
    --------
    >>> from psgsl_pgm.experiment import check_sources
    >>> check_sources(["oven", (5.0, 6.0)])                    # a class of the house and a free position
    ['oven', (5.0, 6.0)]
    >>> try:
    ...     check_sources(["piano"])
    ... except ValueError as err:
    ...     print("piano" in str(err))
    True
    """

    specs = [parse_source(s) for s in sources]
    if house is None:
        first = next(iter(seeds), None)
        if first is None:
            raise ValueError("seeds must hold at least one seed")
        house = default_house(int(first))
    for spec in specs:
        _check(spec, house)
    return specs


def _check(spec, house) -> None:
    if isinstance(spec, str):
        if not house.objects_of_class(spec):
            present = sorted({o.class_name for o in house.objects})
            from .._shared._validate import did_you_mean as _did_you_mean

            raise ValueError(f"source {spec!r} is no object class of the house{_did_you_mean(spec, present)}; "
                             f"classes present: {present}")
        return
    grid = house.grid
    x, y = spec
    cell = grid.world_to_cell(np.array([x, y]))
    if not grid.contains(cell):
        x0, x1, y0, y1 = (float(v) for v in grid.extent)
        raise ValueError(f"source position ({x:g}, {y:g}) lies outside the map: x in [{x0:g}, {x1:g}], "
                         f"y in [{y0:g}, {y1:g}] metres")
    if grid.is_occupied(np.array([x, y])):
        raise ValueError(f"source position ({x:g}, {y:g}) lies in an occupied cell of the map (a wall); give a "
                         "position in free space")
