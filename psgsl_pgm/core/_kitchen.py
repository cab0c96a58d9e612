"""The paper's kitchen example, in one place (Sec. "Semantic Knowledge and Ontology").

The paper gives only the ontology: a robot looks for the source of smoke in an industrial kitchen whose
semantic map holds ovens, microwaves, refrigerators and countertops, with p(o_ci | s_c) = (oven 0.4,
microwave 0.25, refrigerator 0.3, countertop 0.05) (:func:`kitchen_ontology`, from
``psgsl_pgm/data/kitchen_smoke.yaml``; "other" is appended with 0). Everything else here — cells, class
beliefs, detector, olfactory estimates, the ethanol row — is *illustrative*, chosen by this package to
exercise the formulas; the paper has no such numbers.

Two illustrations share that ontology:

* :func:`kitchen_example` — six cells with class beliefs p(o_c | z_c) and an olfactory estimate p(s | g)
  (``psgsl kitchen``, notebook 02);
* the four-cell 2×2 kitchen of the exported networks (``psgsl_pgm.networks`` builds ``kitchen_a`` and
  ``gas_type_a`` from :data:`FOUR_CELLS`, :func:`detector_likelihood`, :data:`FOUR_CELL_OLFACTION` and
  :data:`ETHANOL`; notebook 05; worked by hand in ``tests/test_networks_kitchen.py``).
"""

from __future__ import annotations

from importlib import resources

import numpy as np

from ._fusion import fuse
from ._ontology import Ontology
from ._semantic import semantic_source_probability

__all__ = ["ETHANOL", "FOUR_CELLS", "FOUR_CELL_OLFACTION", "detector_likelihood", "kitchen_example",
           "kitchen_ontology"]

#: Six cells and the robot's class beliefs p(o_c | z_c) after a few camera frames (illustrative), over
#: (oven, microwave, refrigerator, countertop, other). The last cell was never seen: it keeps the prior.
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
#: An illustrative olfactory estimate p(s | g) that smells smoke around the first two cells but cannot
#: separate them.
OLFACTORY = np.array([0.3, 0.3, 0.1, 0.1, 0.1, 0.1])

#: The 2×2 kitchen of the exported networks: the object of each cell (cells r0c0, r0c1, r1c0, r1c1).
FOUR_CELLS = ("oven", "microwave", "refrigerator", "countertop")
#: Its olfactory likelihood p(g | c) (illustrative).
FOUR_CELL_OLFACTION = (0.5, 1.0, 0.5, 1.0)
#: An illustrative second gas for Sec. "Probabilistic Gas Classification": p(o | s, ethanol) over
#: (oven, microwave, refrigerator, countertop, other) — spilled spirits on the countertop, bottles in the
#: refrigerator.
ETHANOL = (0.05, 0.05, 0.3, 0.5, 0.1)


def kitchen_ontology() -> Ontology:
    """The paper's kitchen/smoke ontology (Sec. "Semantic Knowledge and Ontology"), shipped with the package.

    Returns
    -------
    Ontology
        Classes (oven, microwave, refrigerator, countertop, other), gas "smoke", uniform class prior.

    Examples
    --------
    >>> from psgsl_pgm import kitchen_ontology
    >>> kitchen_ontology().source_likelihood("smoke")
    array([0.4 , 0.25, 0.3 , 0.05, 0.  ])
    """
    with resources.as_file(resources.files("psgsl_pgm") / "data" / "kitchen_smoke.yaml") as path:
        return Ontology.from_yaml(path)


def detector_likelihood(classes, seen: str, *, hit: float = 0.7, miss: float = 0.1) -> np.ndarray:
    """p(z = "detected ``seen``" | o) of the illustrative detector: ``hit`` for ``seen``, ``miss`` otherwise.

    Parameters
    ----------
    classes : sequence of str
        The class order of the returned vector.
    seen : str
        The class the detector reported (one of ``classes``).
    hit, miss : float, keyword-only

    Returns
    -------
    (k,) ndarray

    Examples
    --------
    >>> from psgsl_pgm.core._kitchen import detector_likelihood
    >>> detector_likelihood(["oven", "sink", "other"], "sink")
    array([0.1, 0.7, 0.1])
    """
    classes = list(classes)
    if seen not in classes:
        raise ValueError(f"seen must be one of the classes {classes}, got {seen!r}")
    return np.where(np.array(classes) == seen, float(hit), float(miss))


def kitchen_example() -> dict:
    """Semantic term p(s | z) and fused p(s | g, z) for the six illustrative kitchen cells.

    The ontology is the paper's; the beliefs (:data:`BELIEFS`) and p(s | g) (:data:`OLFACTORY`) are
    illustrative.

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
