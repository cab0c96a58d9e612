"""The closed-loop part of ``psgsl demo``: infotaxis with and without semantics, a few seeds, a short budget."""

from __future__ import annotations

from pathlib import Path

from ._grid import run_search_grid
from ._settings import SearchConfig

__all__ = ["DEMO_BUDGET", "DEMO_SEARCH_SEEDS", "run_search_demo"]

#: Seeds and time budget (s) of the demo's closed-loop comparison (``psgsl search`` reports ≥ 10 seeds, 1000 s).
DEMO_SEARCH_SEEDS = (0,)
DEMO_BUDGET = 300.0


def run_search_demo(out, *, seeds=DEMO_SEARCH_SEEDS, budget: float = DEMO_BUDGET, workers: int = 2,
                    progress: bool = True) -> dict:
    """``infotaxis/olfaction`` vs ``infotaxis/semantics+rooms``, smoke from the oven, in ``out`` (resumable).

    Returns ``{"<policy>/<variant>": summary}`` (see :func:`psgsl_pgm.search.summarize_runs`).

    Parameters
    ----------
    out : str or os.PathLike
        The output folder (:func:`run_search_grid`'s ``out``): runs already stored there are not redone.
    seeds : sequence of int, default :data:`DEMO_SEARCH_SEEDS`, keyword-only
        The house seeds.
    budget : float, default :data:`DEMO_BUDGET` (300 s), keyword-only
        Each run's time budget, s.
    workers : int, default 2, keyword-only
        Worker processes of the grid runner.
    progress : bool, default True, keyword-only
        Show a progress bar.

    Raises
    ------
    ValueError
        As :func:`run_search_grid` (e.g. no seed, or ``out`` holds runs of another configuration).

    Examples
    --------
    Its default (three seeds, 300 s each, two arms) takes minutes, and even one seed with a 20-s budget takes
    several seconds; ``psgsl demo`` ends with it (``docs/guide/closed-loop.md``). The summary it returns has the form
    of the stored closed-loop grid's, which ships with the package:

    >>> from psgsl_pgm.teaching import closed_loop_results
    >>> summary, _ = closed_loop_results(source="oven")
    >>> arm = summary["oven/infotaxis"]["infotaxis/semantics+rooms"]
    >>> sorted(k for k in arm if k in ("n_runs", "rmst", "success_rate"))
    ['n_runs', 'rmst', 'success_rate']
    """
    top = run_search_grid(["oven"], ["infotaxis"], ["olfaction", "semantics+rooms"], ["infotaxis"], seeds,
                          out=Path(out), workers=workers, search=SearchConfig(time_budget=float(budget)),
                          progress=progress)
    return top["oven/infotaxis"]
