"""The canonical example problems exported to ``networks/`` (the paper's kitchen, a 3×3 grid, gas types).

The kitchen's ontology and its illustrative cells, detector and olfaction come from the one kitchen module,
:mod:`psgsl_pgm.core._kitchen`.
"""

from __future__ import annotations

import numpy as np

from ..core._kitchen import ETHANOL, FOUR_CELL_OLFACTION, FOUR_CELLS, kitchen_ontology
from ..core._kitchen import detector_likelihood as _detector
from ..core._problem import SemanticGSLProblem

__all__ = ["gas_type_problem", "grid_problem", "kitchen_problem"]


def kitchen_problem() -> SemanticGSLProblem:
    """The paper's kitchen: four cells (2×2) holding an oven, a microwave, a refrigerator, a countertop.

    Ontology p(o | s) from the core's ``kitchen_ontology()`` (oven 0.4, microwave 0.25, refrigerator 0.3,
    countertop 0.05, other 0); background β uniform (0.2). Each cell is seen once by a detector that
    reports its object: p(z | o) = 0.7 for that class, 0.1 for each other class. Olfactory likelihood
    p(g | c) = (0.5, 1, 0.5, 1). Worked by hand (see ``tests/networks/test_networks_kitchen.py``): p(s | z) =
    (0.34, 0.25, 0.28, 0.13) and p(s | g, z) = (17, 25, 14, 13) / 69.
    """
    ontology = kitchen_ontology()
    classes = tuple(ontology.classes)
    return SemanticGSLProblem(
        ontology.source_likelihood("smoke"),
        np.full(len(classes), 1.0 / len(classes)),
        cells=("r0c0", "r0c1", "r1c0", "r1c1"),
        observation_cells=np.arange(4),
        observation_likelihoods=np.array([_detector(classes, o) for o in FOUR_CELLS]),
        olfactory_likelihood=FOUR_CELL_OLFACTION,
        class_names=classes,
        gas_names=("smoke",),
        shape=(2, 2),
    )


def grid_problem() -> SemanticGSLProblem:
    """A 3×3 kitchen grid (cells ``r{row}c{col}``) with camera detections, room evidence and a plume.

    Detections by the 0.7/0.1 detector: oven at r0c0, microwave at r0c2, countertop at r1c1 (twice) and at
    r2c2; every cell of the top row also has room evidence "kitchen wall" favouring appliances,
    p(z | o) = (1, 1, 1, 0.5, 0.5); r1c0, r1c2, r2c0, r2c1 are unobserved. Olfaction p(g | c) = exp(−d²/2),
    d the distance in cells to r0c1; uniform source prior; β uniform.
    """
    ontology = kitchen_ontology()
    classes = tuple(ontology.classes)
    cells = tuple(f"r{r}c{c}" for r in range(3) for c in range(3))
    seen = [(0, "oven"), (2, "microwave"), (4, "countertop"), (4, "countertop"), (8, "countertop")]
    wall = np.array([1.0, 1.0, 1.0, 0.5, 0.5])
    obs_cells = [c for c, _ in seen] + [0, 1, 2]
    obs = [_detector(classes, o) for _, o in seen] + [wall] * 3
    rows, cols = np.divmod(np.arange(9), 3)
    plume = np.exp(-((rows - 0) ** 2 + (cols - 1) ** 2) / 2.0)  # p(g | c), source-like peak at r0c1
    return SemanticGSLProblem(
        ontology.source_likelihood("smoke"), np.full(len(classes), 1.0 / len(classes)), cells=cells,
        observation_cells=obs_cells,
        observation_likelihoods=np.array(obs), olfactory_likelihood=plume, class_names=classes,
        gas_names=("smoke",), shape=(3, 3),
    )


def gas_type_problem() -> SemanticGSLProblem:
    """The gas-classification extension on the kitchen: γ ∈ {smoke, ethanol}, one classifier reading ζ.

    p(o | s, smoke) is the paper's kitchen row; p(o | s, ethanol) = (0.05, 0.05, 0.3, 0.5, 0.1) (spilled
    spirits on the countertop, bottles in the refrigerator). p(γ) uniform; p(ζ | γ) = (0.3, 0.6). Same
    cells, detections and olfaction as :func:`kitchen_problem`.
    """
    base = kitchen_problem()
    return SemanticGSLProblem(
        np.array([base.source_likelihood[0], ETHANOL]), base.background, cells=base.cell_names,
        observation_cells=base.observation_cells, observation_likelihoods=base.observation_likelihoods,
        olfactory_likelihood=base.olfactory_likelihood, gas_prior=[0.5, 0.5], gas_observations=[[0.3, 0.6]],
        class_names=base.class_names, gas_names=("smoke", "ethanol"), shape=base.shape,
    )
