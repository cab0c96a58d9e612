r"""Closed-loop search: policies that choose where to go and where to look with
:math:`\varphi(p) = \varphi_G(p) + \varphi_O(p)` (eq. (29), Sec. "Information Gain Optimization"), the closed loop in
the simulated house through the validation experiment's own per-step code, declarations with credible regions, the
open-space benchmark, and the many-house benchmark (:func:`run_benchmark`: generated homes, sources drawn from the
ontology, three ontology conditions), and the same estimators and policies live on a robot's ROS 2 topics
(:func:`run_live`).
"""

from ._benchmark import BENCHMARK_POLICIES, BENCHMARK_VARIANTS, run_benchmark
from ._demo import DEMO_BUDGET, DEMO_SEARCH_SEEDS, run_search_demo
from ._episodes import CONDITIONS, draw_episode, robot_ontology
from ._detection import DetectionModel
from ._figures import plot_paths, plot_survival
from ._findable import check_findable, findability
from ._grid import run_search_grid, summarize_runs, write_search_outputs
from ._live import LiveSession, run_live, write_live
from ._loop import SearchConfig, SearchRun, run_closed_loop
from ._metrics import credible_region, hpd_level, paired_difference, survival, wilson_interval
from ._several import match_declarations, more_sources_probability
from ._open_space import OPEN_SPACE_POLICIES, OpenSpaceSearch, grid_size, hit_probability, open_space_benchmark
from ._choose import choose
from ._policies import POLICIES, SCORES, Decision, Situation, score_per_time, travel_time
from ._space import FreeSpace
from ._store import load_search_run, save_search_run
from ._survival import holm, kaplan_meier, nested_bootstrap, paired_comparison, rmst, sign_flip_pvalue

__all__ = [
    "BENCHMARK_POLICIES",
    "BENCHMARK_VARIANTS",
    "CONDITIONS",
    "DEMO_BUDGET",
    "DEMO_SEARCH_SEEDS",
    "Decision",
    "DetectionModel",
    "FreeSpace",
    "LiveSession",
    "OPEN_SPACE_POLICIES",
    "OpenSpaceSearch",
    "POLICIES",
    "SCORES",
    "SearchConfig",
    "SearchRun",
    "Situation",
    "check_findable",
    "choose",
    "credible_region",
    "draw_episode",
    "findability",
    "grid_size",
    "hit_probability",
    "holm",
    "hpd_level",
    "kaplan_meier",
    "load_search_run",
    "match_declarations",
    "more_sources_probability",
    "nested_bootstrap",
    "open_space_benchmark",
    "paired_comparison",
    "paired_difference",
    "plot_paths",
    "plot_survival",
    "rmst",
    "robot_ontology",
    "run_benchmark",
    "run_closed_loop",
    "run_live",
    "run_search_demo",
    "run_search_grid",
    "save_search_run",
    "score_per_time",
    "sign_flip_pvalue",
    "summarize_runs",
    "survival",
    "travel_time",
    "wilson_interval",
    "write_live",
    "write_search_outputs",
]
