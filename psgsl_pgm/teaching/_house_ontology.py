"""An ontology for the simulated house: p(o | s, γ) for two smells, p(o) and p(o | room) by counting.

The paper (Sec. "Semantic Knowledge and Ontology") allows the probabilities to come "from data on known
releases with a frequentist approach, or simply ... the judgment of an expert". Here the source rows are an
illustrative expert judgement (:data:`HOUSE_GASES`); the class prior and the room table are frequencies of the
classes over the free cells of a house (Dirichlet-smoothed), i.e. what a mapped house like this one shows.
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

__all__ = ["HOUSE_GASES", "house_ontology"]

#: p(o | s, γ) over the default house's classes (illustrative; each row sums to 1, unlisted classes 0).
HOUSE_GASES = MappingProxyType({
    "smoke": MappingProxyType({"oven": 0.40, "toaster": 0.25, "microwave": 0.20, "tv": 0.05,
                               "countertop": 0.05, "other": 0.05}),
    "ethanol": MappingProxyType({"countertop": 0.30, "dining table": 0.20, "refrigerator": 0.15, "sink": 0.15,
                                 "toilet": 0.10, "other": 0.10}),
})


def house_ontology(house, *, concentration=1.0):
    """Ontology of a :class:`psgsl_pgm.sim.House`: its classes, :data:`HOUSE_GASES`, frequencies of classes.

    * p(o) (``class_prior``): (n_i + a) / (N + k a), n_i the number of free cells of class i in the house;
    * p(o | room) (``room_table``): the same over the free cells of each room category;
    * p(o | s, γ): :data:`HOUSE_GASES`.

    Parameters
    ----------
    house : psgsl_pgm.sim.House
    concentration : float, default 1.0, keyword-only
        Dirichlet pseudo-count a > 0 per class (keeps every class possible in every room, so
        p(o | room) / p(o) is defined and no belief is ever exactly zero).

    Returns
    -------
    psgsl_pgm.Ontology
        Classes in ``house.classes`` order, gases ``("smoke", "ethanol")``, rooms in ``house.room_names``
        order (so ``house.room_labels`` index the rows of ``room_table``).

    Raises
    ------
    TypeError, ValueError
        ``house`` not a House, a non-positive ``concentration``, or a house lacking a class of
        :data:`HOUSE_GASES`.

    Examples
    --------
    >>> from psgsl_pgm.sim import default_house
    >>> from psgsl_pgm.teaching import house_ontology
    >>> ont = house_ontology(default_house(seed=1))
    >>> ont.rooms[0], bool(ont.room_likelihood("Kitchen")[0] > ont.class_prior[0])   # ovens: kitchens
    ('Kitchen', True)
    """
    from psgsl_pgm import Ontology
    from psgsl_pgm.sim import House

    if not isinstance(house, House):
        raise TypeError(f"house must be a psgsl_pgm.sim.House, got {type(house).__name__}")
    a = float(concentration)
    if not (np.isfinite(a) and a > 0):
        raise ValueError(f"concentration must be a positive finite number, got {concentration!r}")
    classes = tuple(house.classes)
    k = len(classes)
    missing = sorted({c for row in HOUSE_GASES.values() for c in row} - set(classes))
    if missing:
        raise ValueError(f"the house lacks classes {missing} of HOUSE_GASES; its classes are {classes}")
    table = np.zeros((len(HOUSE_GASES), k))
    for g, row in enumerate(HOUSE_GASES.values()):
        for name, p in row.items():
            table[g, classes.index(name)] = p

    free = house.grid.free
    class_map = house.class_map[free]  # true class of every free cell
    rooms = house.room_labels[free]
    n_rooms = len(house.room_names)
    counts = np.zeros((n_rooms + 1, k))
    np.add.at(counts, (np.where(rooms < 0, n_rooms, rooms), class_map), 1.0)  # one row per room, last: no room
    prior = (counts.sum(axis=0) + a) / (counts.sum() + k * a)  # p(o) = (n_i + a) / (N + k a)
    room_table = (counts[:n_rooms] + a) / (counts[:n_rooms].sum(axis=1, keepdims=True) + k * a)  # p(o | room)
    return Ontology(classes, tuple(HOUSE_GASES), table, prior, rooms=house.room_names, room_table=room_table)
