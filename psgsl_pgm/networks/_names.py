"""Node and state names of Networks A and B (one naming convention, one place).

Every node and state name is a valid XMLBIF/BIF identifier (:func:`psgsl_pgm._shared._validate.identifier`): a letter
followed by letters, digits or underscores, so exported files load back unchanged. Plain strings, so the
convention lives in the core, beside :class:`psgsl_pgm.core._problem.SemanticGSLProblem` whose cell, class and gas
names it builds on; the pgmpy networks of ``psgsl_pgm.networks`` import it from here.
"""

from __future__ import annotations

__all__ = [
    "ALPHA",
    "ALPHA_STATES",
    "COUNTER_STATES",
    "EVIDENCE_STATES",
    "GAMMA",
    "G_NODE",
    "OBSERVED",
    "SOURCE",
    "SOURCE_STATES",
    "counter_node",
    "olfactory_node",
    "object_node",
    "observation_node",
    "source_node",
    "zeta_node",
]

#: Network A: the single source variable S over cells.
SOURCE = "S"
#: Network A: the olfactory evidence node G (child of S).
G_NODE = "G"
#: The gas type γ (present when the problem has m > 1 gases).
GAMMA = "gamma"
#: Network B: the exactly-one constraint α.
ALPHA = "alpha"

#: States of every evidence node (Z, G, G_i, ζ); the evidence is always ``OBSERVED``.
EVIDENCE_STATES = ("observed", "other")
OBSERVED = EVIDENCE_STATES[0]
#: States of a binary source variable S_i of Network B (``yes`` = cell i holds the source).
SOURCE_STATES = ("no", "yes")
#: States of a counter C_i = min(2, C_{i-1} + S_i) of the chain encoding.
COUNTER_STATES = ("none", "one", "many")
#: States of α; the constraint is enforced by the evidence α = ``true``.
ALPHA_STATES = ("false", "true")


def source_node(cell: str) -> str:
    """Network B's binary source variable S_i of cell ``cell``."""
    return f"S_{cell}"


def object_node(cell: str) -> str:
    """The object-class variable O_c of cell ``cell``."""
    return f"O_{cell}"


def observation_node(cell: str, j: int) -> str:
    """The j-th semantic observation Z of cell ``cell`` (child of O_c)."""
    return f"Z_{cell}_{j}"


def olfactory_node(cell: str) -> str:
    """Network B's per-cell olfactory evidence G_i (child of S_i)."""
    return f"G_{cell}"


def counter_node(cell: str) -> str:
    """The chain encoding's counter C_i after cell ``cell``."""
    return f"C_{cell}"


def zeta_node(j: int) -> str:
    """The j-th gas-classifier observation ζ (child of γ)."""
    return f"zeta_{j}"
