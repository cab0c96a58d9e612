"""The object classes and room categories of the simulated house — the one place they are listed.

Class names are COCO names as in the lab's ontology (``oven``, ``potted plant``, ...), plus ``countertop`` and
the catch-all ``other`` (free floor, walls, unlisted things). Room names follow the lab's room-category maps
(``Kitchen``, ``LivingRoom``, ...); :func:`match_names` aligns them with another spelling
(``"living room"`` -> ``"LivingRoom"``).
"""

from __future__ import annotations

import numpy as np

from .._shared._validate import names as _names

__all__ = ["HOUSE_CLASSES", "HOUSE_ROOMS", "OTHER", "match_names", "reindex"]

#: Catch-all class for cells that hold no listed object.
OTHER = "other"

#: Object classes of the default house, in the order used by its class maps.
HOUSE_CLASSES: tuple[str, ...] = (
    "oven",
    "microwave",
    "toaster",
    "refrigerator",
    "sink",
    "countertop",
    "toilet",
    "bed",
    "couch",
    "tv",
    "dining table",
    "chair",
    "potted plant",
    OTHER,
)

#: Room categories of the default house, in the order of its room labels.
HOUSE_ROOMS: tuple[str, ...] = ("Kitchen", "Bathroom", "Bedroom", "LivingRoom", "Hallway")


def _key(name: str) -> str:
    return "".join(ch for ch in str(name).lower() if ch.isalnum())


def match_names(names, targets) -> np.ndarray:
    """Index of each name in ``targets``, ignoring case, spaces and punctuation; -1 where absent.

    Parameters
    ----------
    names : sequence of str
        The names to look up (may repeat, may be empty).
    targets : sequence of str
        The names they are matched against; the first of several equal keys wins.

    Returns
    -------
    (len(names),) ndarray of int64
        The index into ``targets`` of each name, -1 where none matches.

    Raises
    ------
    TypeError
        ``names`` or ``targets`` is not a sequence of strings.

    Examples
    --------
    >>> match_names(["LivingRoom", "Garage"], ["kitchen", "living room"])
    array([ 1, -1])
    """
    names = _names(names, "names", allow_empty=True, unique=False)
    targets = _names(targets, "targets", allow_empty=True, unique=False)
    lookup = {}
    for i, t in enumerate(targets):
        lookup.setdefault(_key(t), i)
    return np.array([lookup.get(_key(n), -1) for n in names], dtype=np.int64)


def reindex(labels, names, targets, *, missing: int = -1) -> np.ndarray:
    """Relabel integer ``labels`` (indices into ``names``, -1 = none) as indices into ``targets``.

    Names absent from ``targets`` become ``missing``; the names are matched as :func:`match_names` matches them.

    Parameters
    ----------
    labels : array_like of int
        Any shape; each value an index into ``names``, or -1 for no label.
    names : sequence of str
        What the labels index now.
    targets : sequence of str
        What the result indexes.
    missing : int, default -1, keyword-only
        The label of a name ``targets`` lacks (and of -1).

    Returns
    -------
    ndarray of int
        ``labels``' shape, indices into ``targets``.

    Raises
    ------
    TypeError
        ``labels`` are not integers, or ``names`` / ``targets`` are not sequences of strings.
    ValueError
        A label lies outside [-1, len(names) − 1].

    Examples
    --------
    >>> reindex([0, 1, -1], ["Kitchen", "Hallway"], ["hallway", "kitchen"])
    array([ 1,  0, -1])
    """
    lab = np.asarray(labels)
    if not np.issubdtype(lab.dtype, np.integer):
        raise TypeError(f"labels must be integer indices, got dtype {lab.dtype}")
    idx = match_names(names, targets)
    idx = np.where(idx < 0, missing, idx)
    lut = np.append(idx, missing)  # label -1 -> last entry
    if lab.size and (lab.min() < -1 or lab.max() >= len(idx)):
        raise ValueError(f"labels must lie in [-1, {len(idx) - 1}], got [{lab.min()}, {lab.max()}]")
    return lut[lab]
