"""The MAPIRlab formats of an ontology: ``ontology.yaml`` (p(o | s, γ)) and ``ObjectProbByRoom.yaml`` (p(o | room)).

``ontology.yaml`` (the lab's ``gsl_server/resources``)::

    Gases:
      - gas: smoke
        probs: {oven: 0.4, microwave: 0.3, toaster: 0.2, refrigerator: 0.1, other: 0.005}

The lab reads it as follows (``ClassMap::parseOntology``) and so does :func:`lab_ontology`: the listed values
are normalised by their sum (``other`` included), and ``other`` is the catch-all class that stands for every
class the gas does not list — an object of an unlisted class *is* an ``other`` for that gas. With several gases
(this project keeps one class list for all of them), a class that one gas lists and another does not belongs
to the second gas's ``other``; its share of that ``other`` is proportional to the class prior, so that
p(o | s, γ) / p(o) is the same for every member of the bundle and p(s | z) is exactly what the lab's lumped
class gives.

``ObjectProbByRoom.yaml``::

    number_classes: 81          # classes of the detector, background included (COCO: 80 + 1)
    room_categories:
      Kitchen: {oven: 0.2, refrigerator: 0.1, microwave: 0.05, sink: 0.05}

read as the lab's ``ClassMap::Room::finalize`` does with an occupancy prior of 1 (the values are used as
p(o | room) directly): a listed class has its value, every class the room does not list gets an equal share
(1 − Σ listed) / (number_classes − listed), and ``other`` takes what is left (the unlisted classes outside the
ontology and the background). A class in a room row that is neither the ontology's nor a COCO class is a typo
and an error naming the close names. Rooms the file does not list (and cells outside every room) get the class prior
— the lab's "unknown" room. The class prior itself becomes 1 / number_classes for every named class, ``other``
the rest (the lab's ``classPrior``); without a room file it is uniform over the ontology's classes (the lab's
``setUpNoRooms``).

Class names go through :func:`psgsl_pgm.io._coco.canonical_class` (``fridge`` -> ``refrigerator``).
"""

from __future__ import annotations

import numpy as np

from .._shared._validate import check_keys, file_field
from ._coco import canonical_class

__all__ = ["is_lab_format", "lab_key_typo", "lab_ontology", "lab_room_table"]

OTHER = "other"


def is_lab_format(data) -> bool:
    """Whether a parsed YAML document is the lab's ontology layout (top-level ``Gases``)."""
    return isinstance(data, dict) and "Gases" in data


def lab_key_typo(data, own_keys) -> str | None:
    """The message for a lab-layout file whose ``Gases`` key is misspelt (``Gasses``), else None.

    A top-level key closer to the lab's ``Gases`` than to any key of this project's layout (``own_keys``)
    marks the file as the lab's: it is answered in the lab's keys, not this project's.
    """
    import difflib

    if not isinstance(data, dict) or "classes" in data or "gases" in data:
        return None
    vocabulary = ["Gases", *own_keys]
    for key in data:
        if not isinstance(key, str):
            continue
        best = difflib.get_close_matches(key, vocabulary, n=1, cutoff=0.6)
        if best == ["Gases"] or (not best and key.lower().startswith("gas")):
            return (f"expected key 'Gases' (the lab's layout: 'Gases: [{{gas: ..., probs: {{class: p, ...}}}}]'), "
                    f"got {key!r}")
    return None


def _class_row(where: str, key: str, probs) -> dict:
    if not isinstance(probs, dict) or not probs:
        raise ValueError(f"{where}: key '{key}' must be a non-empty mapping class -> probability, got {probs!r}")
    row: dict = {}
    for name, value in probs.items():
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"{where}: key '{key}' has a class name that is not a string: {name!r}")
        cname = canonical_class(name)
        if cname in row:
            raise ValueError(f"{where}: key '{key}.{name}': class {cname!r} is listed twice (aliases included)")
        row[cname] = file_field(where, f"{key}.{name}", value, nonnegative=True)
    return row


def _room_rows(room_data: dict, where: str):
    check_keys(where, room_data, required=("number_classes", "room_categories"))
    n = room_data["number_classes"]
    if isinstance(n, bool) or not isinstance(n, int) or n < 2:
        raise ValueError(f"{where}: key 'number_classes' must be an integer >= 2, got {n!r}")
    cats = room_data["room_categories"]
    if not isinstance(cats, dict) or not cats:
        raise ValueError(f"{where}: key 'room_categories' must be a non-empty mapping room -> classes, got {cats!r}")
    rows = {}
    for room, probs in cats.items():
        if not isinstance(room, str) or not room.strip():
            raise ValueError(f"{where}: key 'room_categories' has a room name that is not a string: {room!r}")
        row = _class_row(where, f"room_categories.{room}", probs)
        if OTHER in row:
            raise ValueError(f"{where}: key 'room_categories.{room}.{OTHER}': '{OTHER}' is the catch-all class and "
                             "may not be listed (the lab's rule)")
        total = sum(row.values())
        if total > 1 + 1e-6:
            raise ValueError(f"{where}: key 'room_categories.{room}' sums to {total:.6g} > 1")
        if len(row) >= n and total < 1 - 1e-6:
            raise ValueError(f"{where}: key 'room_categories.{room}' lists {len(row)} classes but number_classes is "
                             f"{n}: the remaining mass {1 - total:.3g} has no class to go to")
        rows[room] = row
    return n, rows


def lab_class_prior(classes, n_classes: int, where: str) -> np.ndarray:
    """The lab's p(o): 1 / ``n_classes`` for every named class, ``other`` (last) the rest."""
    k = len(classes)
    if k - 1 >= n_classes:
        raise ValueError(f"{where}: key 'number_classes' is {n_classes}, but the ontology already names {k - 1} "
                         "classes besides 'other'")
    prior = np.full(k, 1.0 / n_classes)
    prior[-1] = 1.0 - (k - 1) / n_classes
    return prior


def lab_room_table(classes, room_data: dict, where: str):
    """p(o | room) rows over ``classes`` (``other`` last) from an ``ObjectProbByRoom`` mapping.

    Returns
    -------
    n_classes : int
    rooms : list of str
    table : (r, k) ndarray
    """
    n, rows = _room_rows(room_data, where)
    k = len(classes)
    if k - 1 >= n:
        raise ValueError(f"{where}: key 'number_classes' is {n}, but the ontology names {k - 1} classes besides "
                         "'other'")
    from ._class_maps import unknown_names
    from ._coco import COCO_CLASSES

    known = list(dict.fromkeys([*classes[:-1], *COCO_CLASSES]))
    listed = f"the ontology's {', '.join(classes[:-1])} and the 80 COCO classes"
    for room, row in rows.items():  # a class neither the ontology nor COCO names is a typo ('ovne')
        odd = [c for c in row if c not in known]
        if odd:
            text = unknown_names(odd, known, "class", "neither the ontology nor COCO names", listed=listed)
            raise ValueError(f"{where}: key 'room_categories.{room}': {text}")
    _check_mismatch(classes, rows, where, COCO_CLASSES)
    table = np.zeros((len(rows), k))
    for r, row in enumerate(rows.values()):
        total = sum(row.values())
        share = (1.0 - total) / (n - len(row)) if n > len(row) else 0.0  # every class the room does not list
        for i, c in enumerate(classes[:-1]):
            table[r, i] = row.get(c, share)
        table[r, -1] = max(1.0 - table[r, :-1].sum(), 0.0)  # unlisted classes outside the ontology + background
        table[r] /= table[r].sum()
    return n, list(rows), table


def _check_mismatch(classes, rows: dict, where: str, coco) -> None:
    """A room-table class the ontology lacks while the ontology has a close name outside COCO ('microwave' in the
    room table, 'microwve' in the ontology) is a typo on one side: without this check the room's class would
    silently count as 'other'. ValueError with "did you mean"."""
    import difflib

    own = [c for c in classes[:-1] if c not in coco]  # the ontology's names a COCO detector never reports
    if not own:
        return
    for room, row in rows.items():
        for c in row:
            if c in classes:
                continue
            close = difflib.get_close_matches(c, own, n=1, cutoff=0.8)
            if close:
                raise ValueError(f"{where}: key 'room_categories.{room}': class {c!r} is not one of the ontology's "
                                 f"classes, so it would count as 'other' — did you mean the ontology's {close[0]!r}? "
                                 f"(fix the name in one of the two files)")


def lab_ontology(data: dict, where: str, *, room_data: dict | None = None, room_where: str | None = None):
    """Build the constructor arguments of :class:`~psgsl_pgm.Ontology` from the lab's ``ontology.yaml``.

    Parameters
    ----------
    data : dict
        The parsed ``ontology.yaml`` (top-level ``Gases``).
    where : str
        The file, for messages.
    room_data : dict, optional, keyword-only
        A parsed ``ObjectProbByRoom.yaml``: gives p(o | room) and the class prior (see the module docstring).
    room_where : str, optional, keyword-only

    Returns
    -------
    dict
        Keyword arguments ``classes, gases, source_table, class_prior, rooms, room_table``.
    """
    check_keys(where, data, required=("Gases",))
    entries = data["Gases"]
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{where}: key 'Gases' must be a non-empty list of {{gas, probs}} entries, got {entries!r}")
    gases, rows = [], []
    for i, entry in enumerate(entries):
        key = f"Gases[{i}]"
        check_keys(f"{where}: key '{key}'", entry, required=("gas", "probs"))
        gas = entry["gas"]
        if not isinstance(gas, str) or not gas.strip():
            raise ValueError(f"{where}: key '{key}.gas' must be a gas name, got {gas!r}")
        if gas in gases:
            raise ValueError(f"{where}: key '{key}.gas': gas {gas!r} is listed twice")
        row = _class_row(where, f"{key}.probs", entry["probs"])
        if sum(row.values()) <= 0:
            raise ValueError(f"{where}: key '{key}.probs' is all zero")
        gases.append(gas)
        rows.append(row)
    named = list(dict.fromkeys(c for row in rows for c in row if c != OTHER))
    classes = named + [OTHER]
    k = len(classes)
    rooms, room_table = [], None
    if room_data is not None:
        n, rooms, room_table = lab_room_table(classes, room_data, room_where or "room classes")
        prior = lab_class_prior(classes, n, room_where or "room classes")
    else:
        prior = np.full(k, 1.0 / k)
    table = np.zeros((len(gases), k))
    for g, row in enumerate(rows):
        z = sum(row.values())
        bundle = np.array([c not in row or c == OTHER for c in classes])  # this gas's "other"
        for i, c in enumerate(classes):
            if not bundle[i]:
                table[g, i] = row[c] / z
        table[g, bundle] = row.get(OTHER, 0.0) / z * prior[bundle] / prior[bundle].sum()
    return dict(classes=classes, gases=gases, source_table=table, class_prior=prior, rooms=rooms,
                room_table=room_table)
