"""Helpers of the teaching notebooks (``notebooks/01_…`` – ``07_…``): drawings, maps and small experiments.

Private to the notebooks (not part of the estimator's API); every function here is tested in
``tests/teaching``. (The ontology of the simulated house is the experiment's,
:func:`psgsl_pgm.experiment.house_ontology`.)

* :func:`draw_network` — the layered drawing of Network A or B (networkx + matplotlib), from
  :mod:`psgsl_pgm.networks` (the drawer of the exported PNGs too);
* :func:`plot_cell_map`, :func:`map_norm` — the package's one map plotter (:mod:`psgsl_pgm.sim`), re-exported:
  a value per cell with its colour bar, and one colour scale across compared panels; :func:`figure_problems`,
  what a figure lacks for a reader (axis labels, colour bars) — every notebook figure is checked with it;
* :func:`approximation_error` — mean total-variation error of the paper's approximation
  p(o_ni | s_c) ≈ p(o_ni) against the exact posterior, versus the number of cells;
* :func:`survey` — class beliefs after camera frames from a list of poses;
* :func:`candidate_poses` — a lattice of camera poses on the free floor, for φ_O(p);
* :func:`closed_loop_results` — the stored closed-loop grid (summaries and paired comparisons) notebook 08 reads.
"""

from psgsl_pgm.sim import figure_problems, map_norm, plot_cell_map

from ._approximation import approximation_error
from ._results import closed_loop_results
from ._views import candidate_poses, survey

__all__ = [
    "approximation_error",
    "candidate_poses",
    "closed_loop_results",
    "draw_network",
    "figure_problems",
    "map_norm",
    "plot_cell_map",
    "survey",
]


def __getattr__(name):
    """``draw_network`` is :mod:`psgsl_pgm.networks`' (pgmpy, the networks extra), imported when first asked for,
    so that a notebook that only reads or plots results does not load pgmpy."""
    if name == "draw_network":
        from psgsl_pgm.networks import draw_network

        return draw_network
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
