"""The robot's ontology for the simulated house: p(o | s, γ) by hand, p(o) and p(o | room) from floor plans."""

from __future__ import annotations

from functools import lru_cache
from importlib import resources

import numpy as np

from ..core._ontology import Ontology
from ..io._yaml import load_yaml
from ._house import default_house

__all__ = ["house_ontology"]

#: Seeds of the reference houses whose floor plans give p(o) and p(o | room) (never used for evaluation).
REFERENCE_SEEDS = tuple(range(10_000, 10_010))


@lru_cache(maxsize=4)
def _cached(seeds: tuple, pseudo_count: float) -> Ontology:
    houses = [default_house(s) for s in seeds]
    classes = houses[0].classes
    rooms = houses[0].room_names
    k, r = len(classes), len(rooms)
    counts = np.zeros((r, k))
    for h in houses:
        inside = h.room_labels >= 0
        # counts[room, class] += number of room cells holding that class (np.add.at: no loop over cells)
        np.add.at(counts, (h.room_labels[inside], h.class_map[inside]), 1.0)
    room_table = (counts + pseudo_count) / (counts + pseudo_count).sum(axis=1, keepdims=True)  # p(o | room)
    class_prior = (counts.sum(axis=0) + pseudo_count) / (counts.sum() + k * pseudo_count)  # β = p(o | ¬s) ≈ p(o)
    # p(o | s, γ) from the hand-written table, read by the Ontology's own reader (a typo names the file and key)
    with resources.as_file(resources.files("psgsl_pgm") / "data" / "house_gases.yaml") as path:
        gases = load_yaml(path)  # the project's safe loader: a duplicated class names file, key and line
    try:
        hand = Ontology.from_dict({"classes": list(classes), "gases": gases})
    except (ValueError, TypeError) as exc:
        raise type(exc)(f"{path}: {exc}") from None
    table, gases = hand.source_table, hand.gases
    return Ontology(classes, gases, table, class_prior, rooms=rooms, room_table=room_table)


def house_ontology(*, reference_seeds=REFERENCE_SEEDS, pseudo_count: float = 1.0) -> Ontology:
    """The ontology the simulated robot brings to the house (paper Sec. "Semantic Knowledge and Ontology").

    * p(o | s, γ): written by hand in ``psgsl_pgm/data/house_gases.yaml`` (smoke: oven 0.40, toaster 0.20,
      microwave 0.15, ...; 5 % on ``other`` so that off-ontology sources stay possible; ethanol: countertop,
      dining table, refrigerator, sink, toilet, other; ammonia: toilet, sink, refrigerator, ...; natural gas:
      oven, countertop, other — the gases of the electronic nose, :class:`psgsl_pgm.sim.ElectronicNose`);
    * p(o) = β and p(o | room): cell frequencies of each class in each room category of *reference* houses
      (``default_house(seed)`` for seeds never used in the evaluation: the same floor plan family, other object
      positions), with ``pseudo_count`` cells of every class added to every room (Dirichlet smoothing: a toaster
      in a bedroom stays possible). β is the class frequency over all room cells, i.e. the background
      p(o | ¬s) of the exact closed form up to the one source cell in ~11 000.

    Parameters
    ----------
    reference_seeds : tuple of int, keyword-only
    pseudo_count : float, keyword-only
        Cells added to every (room, class) count, > 0.

    Returns
    -------
    Ontology
        Classes in the order of :data:`psgsl_pgm.sim.HOUSE_CLASSES`, rooms of :data:`psgsl_pgm.sim.HOUSE_ROOMS`.

    Raises
    ------
    ValueError
        ``reference_seeds`` is empty, or ``pseudo_count`` is not positive.

    Examples
    --------
    >>> ont = house_ontology()
    >>> ont.gases, ont.classes[0]
    (('smoke', 'ethanol', 'ammonia', 'natural gas'), 'oven')
    >>> kitchen, bedroom = ont.room_table[ont.rooms.index("Kitchen")], ont.room_table[ont.rooms.index("Bedroom")]
    >>> bool(kitchen[0] > 10 * bedroom[0])          # ovens are far likelier in a kitchen
    True
    """
    return _cached(*_reference_arguments(reference_seeds, pseudo_count))


def _reference_arguments(reference_seeds, pseudo_count) -> tuple[tuple, float]:
    """The checked arguments of an ontology counted on reference houses (:func:`house_ontology`,
    :func:`psgsl_pgm.sim.generated_ontology`): the seeds as a non-empty tuple of ints (hashable, for the cache) and
    the Dirichlet pseudo-count as a float > 0 (no seeds, or a count not > 0: a :class:`ValueError` naming it)."""
    seeds = tuple(int(s) for s in reference_seeds)
    if not seeds:
        raise ValueError("reference_seeds must name at least one reference house")
    if not (np.isfinite(pseudo_count) and pseudo_count > 0):
        raise ValueError(f"pseudo_count must be a positive number of cells, got {pseudo_count!r}")
    return seeds, float(pseudo_count)
