"""Episodes of the many-house benchmark: sources drawn as sources occur, and the robot's ontology per condition.

**Sources.** Per episode (house h, seed s) one generator, ``numpy.random.default_rng([h, s, 0x5_0E_CE])``, draws

1. a gas γ uniformly from ``gases``;
2. with probability ``off_rate`` an **off-ontology** source: a point source in a uniformly drawn floor cell of the
   source region (free, in a room, not under an object or in a window) that the robot can find (a drivable cell
   reachable from the start lies within ``found_radius`` of it);
3. otherwise an object class o from p(o | s, γ) of the *world's* ontology, restricted to the classes with at
   least one object in the house and renormalised (the table's ``other`` mass is what step 2 replaces at the
   stated rate), then one instance of that class uniformly; the source is the instance's footprint centre.

Every drawn source is findable by the closed loop's rule (:func:`psgsl_pgm.search.check_findable`); an object
that is not (never in a generated home) is left out of the draw.

**Conditions** (:data:`CONDITIONS`), the robot's ontology against the world's:

* ``right-ontology`` — the world's own;
* ``wrong-ontology`` — the world's p(o | s, γ) with the values of the object classes (all but ``other``)
  permuted by a random derangement drawn per house, ``default_rng([h, 0x3A0])``: every class gets the
  probability of another class, ``other`` keeps its own; p(o) and p(o | room) stay right (the robot knows its
  rooms and furniture, not where sources are);
* ``no-rooms`` — the world's ontology without p(o | room): every room starts at the class prior, so the
  ``semantics+rooms`` variant has no room evidence.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

from .._shared._validate import one_of
from ..core._ontology import Ontology
from ..sim._classes import OTHER

__all__ = ["CONDITIONS", "draw_episode", "draw_sources", "findable_sources", "robot_ontology"]

#: The benchmark's conditions (module docstring).
CONDITIONS = ("right-ontology", "wrong-ontology", "no-rooms")
_SOURCE_TAG = 0x5_0E_CE
_WRONG_TAG = 0x3A0


def check_condition(condition) -> str:
    """``condition`` if it is one of :data:`CONDITIONS`; ValueError (TypeError) naming them otherwise."""
    return one_of(condition, "condition", CONDITIONS)


def _derangement(rng, n: int) -> np.ndarray:
    while True:  # a uniform permutation without fixed points: accept with probability ≈ 1/e
        perm = rng.permutation(n)
        if n < 2 or not (perm == np.arange(n)).any():
            return perm


def robot_ontology(ontology: Ontology, condition: str, *, house: int) -> Ontology:
    """The robot's ontology in ``condition`` (module docstring) for house number ``house``.

    Parameters
    ----------
    ontology : psgsl_pgm.core.Ontology
        The world's ontology.
    condition : str
        One of :data:`CONDITIONS`: ``"right-ontology"`` (``ontology`` itself), ``"wrong-ontology"`` (the object
        classes' source probabilities deranged) or ``"no-rooms"`` (without p(o | room)).
    house : int, keyword-only
        The house's number; seeds the derangement of ``"wrong-ontology"``, ``default_rng([house, 0x3A0])``.

    Returns
    -------
    psgsl_pgm.core.Ontology
        The robot's ontology.

    Raises
    ------
    TypeError
        ``condition`` is not a string.
    ValueError
        ``condition`` is not one of :data:`CONDITIONS`.

    Examples
    --------
    >>> from psgsl_pgm.experiment import house_ontology
    >>> from psgsl_pgm.search import robot_ontology
    >>> ontology = house_ontology()
    >>> robot_ontology(ontology, "right-ontology", house=0) is ontology
    True
    >>> robot_ontology(ontology, "no-rooms", house=0).rooms
    ()
    >>> wrong = robot_ontology(ontology, "wrong-ontology", house=0)
    >>> bool(wrong.source_likelihood("smoke")[0] != ontology.source_likelihood("smoke")[0])   # the oven's moved
    True
    """
    check_condition(condition)
    if condition == "right-ontology":
        return ontology
    if condition == "no-rooms":
        return Ontology(ontology.classes, ontology.gases, ontology.source_table, ontology.class_prior)
    objects = np.array([i for i, c in enumerate(ontology.classes) if c != OTHER])
    perm = _derangement(np.random.default_rng([int(house), _WRONG_TAG]), objects.size)
    table = np.array(ontology.source_table)
    table[:, objects] = table[:, objects[perm]]
    rooms = ontology.rooms
    return Ontology(ontology.classes, ontology.gases, table, ontology.class_prior, rooms=rooms,
                    room_table=ontology.room_table if rooms else None)


def findable_sources(world, *, found_radius: float = 0.5, seed: int = 0) -> dict:
    """What a source may be in a world: ``{"objects": [SceneObject, ...] findable, "floor": (m,) flat cells}``.

    Objects are checked with :func:`psgsl_pgm.search.findability` (the closed loop's rule); floor cells are the
    source region's free cells under no object and in no window whose centre lies within ``found_radius`` of a
    drivable cell connected to the start (the rule for a point source).
    """
    from ..sim._camera import Camera
    from ._findable import findability
    from ._space import FreeSpace

    house = world.house(seed)
    objs = list(house.objects)
    found = findability(world, seed, found_radius=found_radius, sources=[tuple(o.center) for o in objs]) if objs else {}
    keep = [o for o, f in zip(objs, found.values()) if f["findable"]]
    space = FreeSpace(house, Camera(), clearance=world.clearance)
    d = space.distances(space.snap(world.start_for(house))).reshape(house.shape)
    reach = space.nav & np.isfinite(d)
    near = ndi.distance_transform_edt(~reach) * house.grid.resolution <= found_radius
    floor = world.region_mask(house) & ~house.furniture & ~house.inlet & ~house.outlet & near
    return {"objects": keep, "floor": np.flatnonzero(floor)}


def draw_episode(world, house: int, seed: int, *, gases, off_rate: float, sources: dict, draw: int = 0) -> dict:
    """One episode's gas and source (module docstring).

    Parameters
    ----------
    world : WorldSpec
        The world (its ontology is the world's).
    house, seed : int
        The episode's house number and seed.
    gases : sequence of str
    off_rate : float
        Probability of an off-ontology source, in [0, 1].
    sources : dict
        :func:`findable_sources` of the world.
    draw : int, keyword-only
        0: the episode's (first) source; k ≥ 1: the k-th further draw of an episode with several sources
        (:func:`draw_sources`), from its own generator ``default_rng([h, s, 0x5_0E_CE, k])``.

    Returns
    -------
    dict
        ``{"gas", "kind": "object" | "off-ontology", "class", "object", "xy": [x, y]}`` (class and object None
        for an off-ontology source).

    Raises
    ------
    ValueError
        An off-ontology source is drawn (or no object class can hold the gas) and no floor cell can hold a
        findable source.

    Examples
    --------
    The sources the episode may draw from are the world's findable ones (``findable_sources``):

    >>> from psgsl_pgm.search import draw_episode
    >>> from psgsl_pgm.search._episodes import findable_sources
    >>> from psgsl_pgm.sim import default_world
    >>> world = default_world()
    >>> episode = draw_episode(world, 0, 0, gases=("smoke",), off_rate=0.0, sources=findable_sources(world))
    >>> episode["gas"], episode["kind"], episode["class"]
    ('smoke', 'object', 'toaster')
    >>> draw_episode(world, 0, 0, gases=("smoke",), off_rate=0.0, sources=findable_sources(world)) == episode
    True
    """
    from ..io._coco import canonical_class
    from ..sim._worldfile import _true_class

    rng = np.random.default_rng([int(house), int(seed), _SOURCE_TAG] + ([int(draw)] if draw else []))
    gas = str(gases[int(rng.integers(len(gases)))])
    ont = world.ontology
    row = ont.source_likelihood(gas)
    by_class: dict = {}
    for o in sources["objects"]:
        cls = canonical_class(_true_class(o))
        if cls in ont.classes and cls != OTHER:
            by_class.setdefault(cls, []).append(o)
    classes = [c for c in ont.classes if c in by_class and row[ont.class_index(c)] > 0]
    off = rng.random() < off_rate or not classes
    if off:
        cells = sources["floor"]
        if cells.size == 0:
            raise ValueError(f"{world.path}: no floor cell can hold a findable off-ontology source")
        c = int(cells[int(rng.integers(cells.size))])
        xy = world.house().grid.cell_centres().reshape(-1, 2)[c]
        return {"gas": gas, "kind": "off-ontology", "class": None, "object": None,
                "xy": [float(xy[0]), float(xy[1])]}
    p = np.array([row[ont.class_index(c)] for c in classes])
    cls = classes[int(rng.choice(len(classes), p=p / p.sum()))]
    obj = by_class[cls][int(rng.integers(len(by_class[cls])))]
    xy = obj.center
    return {"gas": gas, "kind": "object", "class": cls, "object": obj.name, "xy": [float(xy[0]), float(xy[1])]}


_COUNT_TAG = 0x5EC0


def draw_sources(world, house: int, seed: int, *, count, gases, off_rate: float, sources: dict,
                 min_distance: float = 2.0) -> dict:
    """An episode with several sources: the first as :func:`draw_episode` draws it (so an episode's first source is
    the one-source benchmark's), and ``"extra"``: the further ones, each drawn the same way (its own gas and
    place) from further generators, redrawn while it lies within ``min_distance`` m of a source already drawn
    (two sources that close would count as one declaration). The number of sources is ``count`` (an int in 1–3)
    or drawn uniformly from a range ``(lo, hi)`` with ``default_rng([h, s, 0x5EC0])``.

    Returns
    -------
    dict
        :func:`draw_episode`'s fields plus ``"n_sources"`` and ``"extra"`` (a list of :func:`draw_episode` dicts).
    """
    if isinstance(count, tuple):
        lo, hi = count
        n = int(np.random.default_rng([int(house), int(seed), _COUNT_TAG]).integers(lo, hi + 1))
    else:
        n = int(count)
    first = draw_episode(world, house, seed, gases=gases, off_rate=off_rate, sources=sources)
    chosen = [np.array(first["xy"])]
    extra, k = [], 1
    while len(extra) < n - 1:
        if k > 200:
            raise ValueError(f"{world.path}: cannot place {n} sources at least {min_distance:g} m apart")
        ep = draw_episode(world, house, seed, gases=gases, off_rate=off_rate, sources=sources, draw=k)
        k += 1
        if min(np.linalg.norm(np.array(ep["xy"]) - c) for c in chosen) >= min_distance:
            extra.append(ep)
            chosen.append(np.array(ep["xy"]))
    return first | {"n_sources": n, "extra": extra}
