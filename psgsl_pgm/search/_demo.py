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
    """
    top = run_search_grid(["oven"], ["infotaxis"], ["olfaction", "semantics+rooms"], ["infotaxis"], seeds,
                          out=Path(out), workers=workers, search=SearchConfig(time_budget=float(budget)),
                          progress=progress)
    return top["oven/infotaxis"]
