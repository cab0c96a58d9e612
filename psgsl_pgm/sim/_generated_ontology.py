"""The ontology of generated homes: p(o | s, γ) by hand, p(o) and p(o | room) counted on reference houses."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..core._ontology import Ontology
from ._classes import HOUSE_CLASSES, HOUSE_ROOMS
from ._house_ontology import _reference_arguments

__all__ = ["GENERATOR_REFERENCE_SEEDS", "generated_ontology"]

#: Seeds of the generated reference houses whose floor plans give p(o) and p(o | room); a benchmark evaluates
#: other seeds (``psgsl benchmark`` refuses these).
GENERATOR_REFERENCE_SEEDS = tuple(range(1_000_000, 1_000_020))


@lru_cache(maxsize=2)
def _cached(seeds: tuple, pseudo_count: float) -> Ontology:
    from ._draw_house import draw_house
    from ._house_ontology import house_ontology

    k, r = len(HOUSE_CLASSES), len(HOUSE_ROOMS)
    counts = np.zeros((r, k))
    for s in seeds:
        h = draw_house(s)[0]  # the house generate_house(s) holds
        inside = h.room_labels >= 0
        rows = np.array([HOUSE_ROOMS.index(n) for n in h.room_names])[h.room_labels[inside]]
        np.add.at(counts, (rows, h.class_map[inside]), 1.0)  # cells of each class in each room type
    room_table = (counts + pseudo_count) / (counts + pseudo_count).sum(axis=1, keepdims=True)
    class_prior = (counts.sum(axis=0) + pseudo_count) / (counts.sum() + k * pseudo_count)
    hand = house_ontology()  # p(o | s, γ): the hand-written table of the simulated house (house_gases.yaml)
    return Ontology(HOUSE_CLASSES, hand.gases, hand.source_table, class_prior, rooms=HOUSE_ROOMS,
                    room_table=room_table)


def generated_ontology(*, reference_seeds=GENERATOR_REFERENCE_SEEDS, pseudo_count: float = 1.0) -> Ontology:
    """The ontology a robot brings to generated homes (as :func:`psgsl_pgm.experiment.house_ontology` for the embedded
    house).

    * p(o | s, γ): the hand-written table ``psgsl_pgm/data/house_gases.yaml`` (the same as the embedded house's);
    * p(o) = β and p(o | room): cell frequencies of each class in each room type over the generated houses of
      ``reference_seeds`` (never evaluated), with ``pseudo_count`` cells of every class added to every room.

    Parameters
    ----------
    reference_seeds : sequence of int, default seeds 1 000 000 – 1 000 019, keyword-only
        The generated homes the frequencies are counted on (:func:`generate_house` seeds); not the benchmark's.
    pseudo_count : float, default 1.0, keyword-only
        Cells of every class added to every room type before normalising (a Dirichlet prior), > 0, so that no class
        has probability 0 in any room.

    Returns
    -------
    Ontology
        Classes :data:`psgsl_pgm.sim.HOUSE_CLASSES`, rooms :data:`psgsl_pgm.sim.HOUSE_ROOMS`.

    Raises
    ------
    ValueError
        ``reference_seeds`` is empty or ``pseudo_count`` is not a positive finite number.

    Examples
    --------
    >>> from psgsl_pgm.sim import HOUSE_CLASSES, generated_ontology
    >>> ontology = generated_ontology(reference_seeds=(1_000_000,))      # counted on one home: a second or two
    >>> ontology.classes == tuple(HOUSE_CLASSES), ontology.room_table.shape[1] == len(HOUSE_CLASSES)
    (True, True)
    """
    return _cached(*_reference_arguments(reference_seeds, pseudo_count))
