"""The canonical networks as XMLBIF / BIF text (the files under ``networks/`` are this, written out)."""

from __future__ import annotations

from pgmpy.readwrite import BIFWriter, XMLBIFWriter

from ._canonical import gas_type_problem, grid_problem, kitchen_problem
from ._network_a import build_network_a
from ._network_b import build_network_b

__all__ = ["CANONICAL", "canonical_network", "network_text"]

#: name → (problem factory, network builder, one-line description)
CANONICAL = {
    "kitchen_a": (kitchen_problem, build_network_a, "the paper's kitchen example, Network A"),
    "grid3x3_a": (grid_problem, build_network_a, "a 3×3 kitchen grid, Network A"),
    "grid3x3_b_chain": (grid_problem, lambda p: build_network_b(p, "chain"), "the 3×3 grid, Network B (chain)"),
    "gas_type_a": (gas_type_problem, build_network_a, "gas classification (γ, ζ) on the kitchen, Network A"),
}


def canonical_network(name: str):
    """(problem, model) of canonical network ``name`` (a key of :data:`CANONICAL`), model named ``name``."""
    if name not in CANONICAL:
        raise ValueError(f"unknown canonical network {name!r}; expected one of {sorted(CANONICAL)}")
    factory, builder, _ = CANONICAL[name]
    problem = factory()
    model = builder(problem)
    model.name = name
    return problem, model


def network_text(model, fmt: str) -> str:
    """The model serialised as ``"xmlbif"`` or ``"bif"`` text by pgmpy's writers (full float precision)."""
    if fmt == "xmlbif":
        return str(XMLBIFWriter(model))
    if fmt == "bif":
        return str(BIFWriter(model))
    raise ValueError(f"fmt must be 'xmlbif' or 'bif', got {fmt!r}")
