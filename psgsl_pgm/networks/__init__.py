"""The paper's Bayesian networks in pgmpy: exact inference on small grids, checks of the closed form.

* :class:`SemanticGSLProblem` — one problem description (ontology, background, evidence, priors) with the
  closed form through the core library (:meth:`SemanticGSLProblem.closed_form_posterior`);
* :func:`build_network_a` — Network A, one discrete source variable S over the cells;
* :func:`build_network_b` — Network B, binary S_i with the exactly-one constraint α ("chain" or "table");
* :func:`exact_source_posterior`, :func:`exact_gas_posterior`, :func:`exact_information_gain` — exact
  queries with pgmpy's VariableElimination;
* :func:`export` — the canonical networks (:data:`CANONICAL`, :func:`canonical_network`) as XMLBIF, BIF and
  PNG files (``psgsl export-networks DIR``; the files under ``networks/``), drawn by :func:`draw_network`.

pgmpy is imported only here (``import psgsl_pgm`` stays light); it comes with the ``networks`` extra,
``pip install "psgsl-pgm[networks]"``. :class:`SemanticGSLProblem` itself is pure numpy and lives in the core
(``psgsl_pgm.core._problem``); it is re-exported here, where its networks are.
"""

try:  # first: pgmpy imported without its import-time warnings; pgmpy is this subpackage's optional dependency
    from . import _quiet_import  # noqa: F401
except ModuleNotFoundError as err:
    if not (err.name or "").split(".")[0] == "pgmpy":
        raise
    raise ImportError('psgsl_pgm.networks needs pgmpy (the "networks" extra): pip install "psgsl-pgm[networks]"') from err

from ..core._problem import SemanticGSLProblem
from ._cpds import check_normalised
from ._draw import draw_network
from ._export import CANONICAL, canonical_network, export
from ._inference import (
    exact_gas_posterior,
    exact_information_gain,
    exact_source_posterior,
    network_evidence,
    network_kind,
)
from ._network_a import build_network_a
from ._network_b import MAX_TABLE_CELLS, build_network_b
from ._underflow import MIN_EVIDENCE, log_evidence

__all__ = [
    "CANONICAL",
    "MAX_TABLE_CELLS",
    "MIN_EVIDENCE",
    "SemanticGSLProblem",
    "build_network_a",
    "build_network_b",
    "canonical_network",
    "check_normalised",
    "draw_network",
    "exact_gas_posterior",
    "exact_information_gain",
    "exact_source_posterior",
    "export",
    "log_evidence",
    "network_evidence",
    "network_kind",
]
