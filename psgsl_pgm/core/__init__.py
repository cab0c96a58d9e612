"""The paper's estimator: the semantic term, fusion, information gain, class beliefs, the ontology, the problem.

* :func:`semantic_source_probability` — p(s_c | z) (eq. (20)), :func:`fuse` — p(s_c | g, z)
  (eq. (11)), :func:`semantic_information_gain` — I(S; O_n) (Sec. "Information Gain
  Optimization");
* :func:`update_class_probs`, :func:`room_evidence`, :class:`ClassBeliefMap` — the class beliefs p(o_c | z_c);
* :class:`GasBelief` — p(γ | ζ_1:t) from an electronic nose's classifications;
* :class:`Ontology` — p(o | s, γ), p(o), p(o | room); :func:`kitchen_ontology`, :func:`kitchen_example`;
  the closed-form problem behind the networks' checks (:mod:`psgsl_pgm.core._problem`).

Numpy arrays run through the compiled kernels, dask arrays chunk by chunk through the same kernels
(``_dask_arrays``); which path runs is decided once, at the public function.

May import: :mod:`psgsl_pgm.io`, :mod:`psgsl_pgm.geometry`, :mod:`psgsl_pgm._shared`, :mod:`psgsl_pgm.kernels`.
Everything here is re-exported by :mod:`psgsl_pgm`.
"""

from ._beliefs import room_evidence, update_class_probs
from ._class_beliefs import ClassBeliefMap
from ._fusion import fuse
from ._gas_belief import GasBelief
from ._infogain import semantic_information_gain
from ._kitchen import kitchen_example, kitchen_ontology
from ._ontology import Ontology
from ._semantic import semantic_source_probability

__all__ = [
    "ClassBeliefMap",
    "GasBelief",
    "Ontology",
    "fuse",
    "kitchen_example",
    "kitchen_ontology",
    "room_evidence",
    "semantic_information_gain",
    "semantic_source_probability",
    "update_class_probs",
]
