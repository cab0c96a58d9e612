r"""psgsl_pgm — probabilistic semantic gas source localization (PSGSL).

The closed-form estimator of Ojeda, Monroy & Gonzalez-Jimenez, *PSGSL: A Probabilistic Framework Integrating
Semantic Scene Understanding and Gas Sensing for Gas Source Localization*, on full maps:

* :func:`semantic_source_probability` —
  :math:`p(s_c \mid z) \propto \sum_i p(o_{ci} \mid z_c) / p(o_{ci}) \cdot p(o_{ci} \mid s_c)`
  (eq. (20)), with gas mixtures (Sec. "Probabilistic Gas Classification") and voxel
  columns (Sec. "Voxelized Scene Representations");
* :func:`fuse` — :math:`p(s_c \mid g, z) \propto p(s_c \mid g) \cdot p(s_c \mid z)` (eq. (11));
* :func:`update_class_probs`, :func:`room_evidence` — building the class beliefs :math:`p(o_c \mid z_c)`;
  :class:`ClassBeliefMap` — the robot's dense class beliefs over cells or voxels, frame by frame;
* :func:`semantic_information_gain`, :func:`field_of_view`, :func:`view_information_gain` — :math:`I(S; O_n)`
  and :math:`\varphi_O(p)` (Sec. "Information Gain Optimization"); :class:`ViewCache` — the camera's line of
  sight cast once per cell of a map and reused for every pose;
* :class:`GridMap` — the occupancy grid every part of the package shares (frame, cell <-> world, coarsening,
  8-connected free-space graph, the one light-tight line of sight);
* :class:`Ontology` — :math:`p(o \mid s, \gamma)`, :math:`p(o)` and :math:`p(o \mid \text{room})`, from YAML,
  dicts or release counts;
  :func:`kitchen_ontology`, :func:`kitchen_example` — the paper's kitchen example (its ontology; the cells are
  illustrative).

Heavier parts are imported on demand: ``psgsl_pgm.networks`` (pgmpy Bayesian networks),
``psgsl_pgm.sim`` (simulated house), ``psgsl_pgm.olfaction`` (olfactory estimators :math:`p(s \mid g)`),
``psgsl_pgm.experiment`` (the paper's validation experiment), ``psgsl_pgm.teaching`` (notebook helpers).
"""

from .core._beliefs import room_evidence, update_class_probs
from .core._class_beliefs import ClassBeliefMap
from .core._fusion import fuse
from .core._gas_belief import GasBelief
from .core._infogain import semantic_information_gain
from .core._kitchen import kitchen_example, kitchen_ontology
from .core._ontology import Ontology
from .core._semantic import semantic_source_probability
from .geometry._fov import ViewCache, field_of_view, view_information_gain
from .geometry._grid import GridMap

__version__ = "0.1.0"


def load_world(path):
    """Load a world file (a user's house: map, rooms, objects, ontology, wind, sources); see
    :func:`psgsl_pgm.sim.load_world`. Needs the ``sim`` extra.

    Parameters
    ----------
    path : str or Path
        The world file (YAML); the files it names are read relative to its folder.

    Returns
    -------
    psgsl_pgm.sim.WorldSpec
        The checked world: house, ontology, source region, wind, named sources and start.

    Raises
    ------
    FileNotFoundError
        The world file does not exist.
    ValueError
        Any bad key or file (also a missing file the world file names), naming the world file and the key.

    Examples
    --------
    The world file the package ships (the simulated house of the validation experiment):

    >>> from importlib.resources import as_file, files
    >>> with as_file(files("psgsl_pgm") / "data" / "worlds" / "house.yaml") as path:
    ...     world = load_world(path)
    >>> world.summary()["grid"]["rows"], world.summary()["grid"]["resolution"]
    (120, 0.1)
    """
    from .sim import load_world as _load_world

    return _load_world(path)


__all__ = [
    "ClassBeliefMap",
    "GasBelief",
    "GridMap",
    "Ontology",
    "ViewCache",
    "field_of_view",
    "fuse",
    "kitchen_example",
    "kitchen_ontology",
    "load_world",
    "room_evidence",
    "semantic_information_gain",
    "semantic_source_probability",
    "update_class_probs",
    "view_information_gain",
]
