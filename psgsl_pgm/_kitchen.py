"""The paper's kitchen example, end to end on six cells (Sec. "Semantic Knowledge and Ontology")."""

from __future__ import annotations

import numpy as np

from ._fusion import fuse
from ._ontology import kitchen_ontology
from ._semantic import semantic_source_probability

__all__ = ["kitchen_example"]

#: Six cells of an industrial kitchen and the robot's class beliefs p(o_c | z_c) after a few camera frames,
#: over (oven, microwave, refrigerator, countertop, other). The last cell was never seen: it keeps the prior.
CELLS = ("oven", "microwave", "refrigerator", "countertop", "floor", "unseen")
BELIEFS = np.array(
    [
        [0.90, 0.06, 0.01, 0.02, 0.01],
        [0.08, 0.85, 0.02, 0.04, 0.01],
        [0.01, 0.02, 0.94, 0.02, 0.01],
        [0.01, 0.02, 0.01, 0.90, 0.06],
        [0.01, 0.01, 0.01, 0.02, 0.95],
        [0.20, 0.20, 0.20, 0.20, 0.20],
    ]
)
#: An olfactory estimate p(s | g) that smells smoke around the first two cells but cannot separate them.
OLFACTORY = np.array([0.3, 0.3, 0.1, 0.1, 0.1, 0.1])


def kitchen_example() -> dict:
    """Semantic term p(s | z) and fused p(s | g, z) for the six kitchen cells.

    Returns
    -------
    result : dict
        ``cells`` (names), ``class_probs`` (6, 5) p(o_c | z_c) over the ontology's classes, ``ontology``
        (:func:`kitchen_ontology`), ``semantic`` p(s_c | z), ``olfactory`` p(s_c | g), ``fused`` p(s_c | g, z), each
        a (6,) ndarray.

    Examples
    --------
    >>> from psgsl_pgm import kitchen_example
    >>> res = kitchen_example()
    >>> res["cells"][0], round(float(res["fused"][0]), 4)
    ('oven', 0.4633)
    """
    ont = kitchen_ontology()
    semantic = semantic_source_probability(BELIEFS, ont.source_likelihood("smoke"), ont.class_prior)
    return {"cells": CELLS, "class_probs": BELIEFS.copy(), "ontology": ont, "semantic": semantic,
            "olfactory": OLFACTORY.copy(), "fused": fuse(OLFACTORY, semantic)}
