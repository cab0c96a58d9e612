"""Whether the robot can find each source of a world: the closed loop's found rule on its drivable cells.

``psgsl world check`` and ``psgsl search`` refuse a source no robot could ever find before any run: the rule is
:class:`DetectionModel`'s (within ``found_radius`` of the emitting object's footprint, or of the cell holding a
point source), the drivable cells and geodesic distances :class:`FreeSpace`'s.
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_findable", "findability"]


def findability(world, seed: int = 0, *, found_radius: float | None = None, clearance: float | None = None,
                sources=None) -> dict:
    """For every source: how far the robot drives to find it, and whether it can at all.

    A source counts as found by the closed loop's own rule, :class:`psgsl_pgm.search.DetectionModel`: when the
    robot comes within ``found_radius`` of its found region — the emitting object's whole footprint when there
    is one (:meth:`psgsl_pgm.sim.WorldSpec.source_target`), else the centre of the cell holding it. The
    robot's cells are :class:`psgsl_pgm.search.FreeSpace`'s (free, not furniture or a window, more than
    ``clearance`` from each), the geodesic distances its free-space graph's.

    Parameters
    ----------
    world : psgsl_pgm.sim.WorldSpec
        The world (:func:`psgsl_pgm.sim.load_world`).
    seed : int
        The house's seed (only the built-in house varies).
    found_radius : float, optional, keyword-only
        m; default: the closed loop's, :class:`psgsl_pgm.search.SearchConfig` (0.5 m).
    clearance : float, optional, keyword-only
        m; default: the world file's ``clearance`` (0.25 m unless it says otherwise).
    sources : sequence, optional, keyword-only
        Source specs (names, classes or positions); default: the world file's ``sources``.

    Returns
    -------
    dict
        Name -> ``{"object": object name or None, "target_cells": int, "gap": m from the nearest drivable
        cell to what counts as found, "geodesic": m from the start to the nearest drivable cell within
        found_radius (inf: none is reachable), "findable": bool, "at_start": m from the start to what counts as
        found when that is within found_radius (the robot finds the source where it starts), else None}``.

    Raises
    ------
    ValueError
        ``found_radius`` or ``clearance`` is not a positive number, no cell of the map is drivable, or a source
        names no object or position of the world.

    Examples
    --------
    >>> from psgsl_pgm.search import findability
    >>> from psgsl_pgm.sim import default_world
    >>> f = findability(default_world())
    >>> sorted(f), f["oven"]["findable"], round(f["oven"]["gap"], 2)    # gap: m from the nearest drivable cell
    (['bed', 'hallway', 'oven'], True, 0.3)
    """
    from scipy import ndimage as ndi

    from .._shared._validate import positive
    from ..sim._camera import Camera
    from ._detection import DetectionModel
    from ._settings import SearchConfig
    from ._space import FreeSpace

    defaults = SearchConfig()
    r = defaults.found_radius if found_radius is None else positive(found_radius, "found_radius", "metres")
    clearance = world.clearance if clearance is None else positive(clearance, "clearance", "metres")
    house = world.house(seed)
    g = house.grid
    space = FreeSpace(house, Camera(), clearance=clearance)
    if not space.nav.any():
        raise ValueError(f"{world.path}: no cell of the map is drivable (free, not furniture or a window, more "
                         f"than clearance {clearance:g} m from each)")
    start = np.asarray(world.start_for(house), dtype=np.float64)
    d_start = space.distances(space.snap(start)).reshape(g.shape)
    out = {}
    detection = DetectionModel.from_house(house, r)
    nav_centres = space.centres[space.nav.ravel()]
    for name in (world.sources if sources is None else sources):
        xy, obj = world.source_target(name, house)
        hypothesis = detection.source_cell(xy, obj, house)
        region = detection.region_mask(hypothesis)
        dist = ndi.distance_transform_edt(~region) * g.resolution  # centre to the region's centres (exact)
        gap = float(dist[space.nav].min())
        near = np.zeros(g.shape, dtype=bool)
        near[space.nav] = detection.found(nav_centres, hypothesis)  # the closed loop's own rule
        cells = int(region.sum()) if obj is not None else 0
        geo = float(d_start[near].min()) if near.any() else float("inf")
        at_start = None
        if detection.found(start[None], hypothesis)[0]:  # the loop's rule at the start itself
            at_start = float(np.sqrt(((space.centres[region.ravel()] - start) ** 2).sum(axis=-1).min()))
        out[str(name) if isinstance(name, str) else f"{xy[0]:g},{xy[1]:g}"] = {
            "object": None if obj is None else obj.name, "target_cells": cells, "gap": gap,
            "geodesic": geo, "findable": bool(np.isfinite(geo)), "at_start": at_start}
    return out

def check_findable(world, seed: int = 0, *, found_radius: float | None = None, clearance: float | None = None,
                   sources=None) -> dict:
    """:func:`findability`, refusing (ValueError naming the source and the gap) a source never found, and a source
    found where the robot starts (a search would end before its first reading: nothing to measure).

    Parameters
    ----------
    world : psgsl_pgm.sim.WorldSpec
        The world (:func:`psgsl_pgm.sim.load_world`).
    seed : int, default 0
        The house's seed (only the built-in house varies).
    found_radius : float, optional, keyword-only
        m, > 0; a source counts as found within this distance of its found region. Default: the closed loop's,
        :class:`psgsl_pgm.search.SearchConfig` (0.5 m).
    clearance : float, optional, keyword-only
        m, > 0; the robot's cells keep more than this from furniture and windows. Default: the world file's
        ``clearance`` (0.25 m unless it says otherwise).
    sources : sequence, optional, keyword-only
        Source specs (names, classes or positions); default: the world file's ``sources``.

    Returns
    -------
    dict
        :func:`findability`'s result, when every source passes.

    Raises
    ------
    ValueError
        A source is found at the start (within ``found_radius`` of it), or can never be found (no drivable cell
        within ``found_radius`` of it, or none connected to the start); no cell of the map is drivable; or
        ``found_radius`` or ``clearance`` is not positive (:func:`findability`).

    Examples
    --------
    >>> from psgsl_pgm.search import check_findable
    >>> from psgsl_pgm.sim import default_world
    >>> check_findable(default_world())["oven"]["findable"]
    True
    >>> try:
    ...     check_findable(default_world(), found_radius=0.1)     # the oven stands 0.3 m from the nearest drivable cell
    ... except ValueError as err:
    ...     print("can never be found" in str(err))
    True
    """
    from ._settings import SearchConfig

    clearance_used = world.clearance if clearance is None else clearance
    found_radius = SearchConfig().found_radius if found_radius is None else found_radius
    result = findability(world, seed, found_radius=found_radius, clearance=clearance, sources=sources)
    for name, f in result.items():
        what = f"the footprint of {f['object']!r}" if f["object"] else "it"
        if f["at_start"] is not None:
            start = world.start_for(world.house(seed))
            raise ValueError(
                f"{world.path}: source {name!r} is found at the start: the start ({start[0]:g}, {start[1]:g}) is "
                f"{f['at_start']:.2f} m from {what}, within the found radius {found_radius:g} m, so a search would "
                f"end before its first reading; move the start (key 'start') or the source, or lower the found "
                f"radius (--found-radius) below {f['at_start']:.2f} m")
        if f["findable"]:
            continue
        if f["gap"] > found_radius:
            raise ValueError(
                f"{world.path}: source {name!r} can never be found: the nearest drivable cell is {f['gap']:.2f} m "
                f"from {what}, farther than the found radius {found_radius:g} m (a gap of "
                f"{f['gap'] - found_radius:.2f} m); raise found_radius (--found-radius) to at least "
                f"{f['gap']:.2f} m, lower clearance (--clearance, now {clearance_used:g} m) or move the source")
        raise ValueError(
            f"{world.path}: source {name!r} can never be found: the drivable cells within {found_radius:g} m of "
            f"{what} are not connected to the start (clearance {clearance_used:g} m)")
    return result
