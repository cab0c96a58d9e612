"""The paper's validation experiment in the simulated house (Sec. "Validation", Figs. error-chart, progression,
room-types).

One robot follows one exploration tour (:func:`exploration_tour`) and collects one stream of gas readings and
camera frames; three variants turn it into a source distribution (:data:`VARIANTS`):

* ``olfaction`` — the olfactory estimator p(s | g) alone (:mod:`psgsl_pgm.olfaction`);
* ``semantics`` — fused with the semantic term p(s | z) of class beliefs built from the camera;
* ``semantics+rooms`` — the same, with class beliefs that start from the room-category map.

:func:`replay` runs a robot's ROS 2 bag through the same per-step code (``psgsl replay``).
:func:`run_search` runs one search (its per-step code, :class:`VariantPosteriors` and :func:`visit`, is also
the closed loop's, :mod:`psgsl_pgm.search`); :func:`run_experiment` a grid of sources × seeds × estimators (parallel,
resumable); :func:`run_demo` the command ``psgsl demo``.
"""

from ..sim._house_ontology import house_ontology
from ._calibration import (CALIBRATION_RUNS, COVERAGE_RUNS, GRID_AXES, GRID_CALIBRATION_RUNS, Calibration,
                           CoverageTempering, calibrate, calibrate_encounter_scale, calibration_runs,
                           coverage_tempering, coverage_threshold, coverage_thresholds, parameter_grid_weights,
                           tempered_posterior)
from ._config import ESTIMATORS, PARAMETER_GRID, UNKNOWN_GAS, VARIANTS, ExperimentConfig, parse_source
from ._driver import DEMO_SEEDS, run_demo, run_experiment, write_outputs
from ._figures import plot_error_chart, plot_progression, plot_room_types
from ._metrics import error_and_spread, mean_ci
from ._robot_models import robot_gas_confusion
from ._reliability import plot_reliability, reliability_table
from ._replay import ReplayResult, replay, write_replay
from ._run import RunResult, run_search
from ._sources import check_sources
from ._step import VariantPosteriors, visit
from ._store import load_run, save_run
from ._summary import format_table, summarize
from ._tour import Tour, exploration_tour

__all__ = [
    "CALIBRATION_RUNS",
    "COVERAGE_RUNS",
    "CoverageTempering",
    "GRID_AXES",
    "GRID_CALIBRATION_RUNS",
    "Calibration",
    "DEMO_SEEDS",
    "ESTIMATORS",
    "PARAMETER_GRID",
    "ExperimentConfig",
    "ReplayResult",
    "RunResult",
    "Tour",
    "UNKNOWN_GAS",
    "VARIANTS",
    "VariantPosteriors",
    "calibrate",
    "calibrate_encounter_scale",
    "calibration_runs",
    "check_sources",
    "coverage_tempering",
    "coverage_threshold",
    "coverage_thresholds",
    "error_and_spread",
    "exploration_tour",
    "format_table",
    "house_ontology",
    "robot_gas_confusion",
    "load_run",
    "mean_ci",
    "parameter_grid_weights",
    "parse_source",
    "plot_error_chart",
    "plot_progression",
    "plot_reliability",
    "plot_room_types",
    "reliability_table",
    "replay",
    "run_demo",
    "run_experiment",
    "run_search",
    "save_run",
    "tempered_posterior",
    "summarize",
    "visit",
    "write_outputs",
    "write_replay",
]
