"""The networks' node and state names: the core's naming convention (:mod:`psgsl_pgm._network_names`)."""

from __future__ import annotations

from .._network_names import (
    ALPHA,
    ALPHA_STATES,
    COUNTER_STATES,
    EVIDENCE_STATES,
    GAMMA,
    G_NODE,
    OBSERVED,
    SOURCE,
    SOURCE_STATES,
    counter_node,
    object_node,
    observation_node,
    olfactory_node,
    source_node,
    zeta_node,
)

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
