"""The stored closed-loop grid that notebook 08 reads, shipped with the package.

``psgsl_pgm/data/closed_loop/`` holds a copy of the results page's ``docs/results/closed-loop/summary.json`` and
``paired.json``, so that the notebook runs from an installed package as well as from a clone
(``tests/teaching/test_teaching_results.py`` keeps the two copies equal).
"""

from __future__ import annotations

import json
from importlib import resources

__all__ = ["closed_loop_results"]

#: The tables the shipped grid holds, one per source and estimator.
_FILES = ("summary.json", "paired.json")


def closed_loop_results(*, source=None):
    """The stored closed-loop grid of ``psgsl search``: per-arm summaries and paired comparisons.

    The grid: held-out seeds 100-119, a 1000-s budget, three sources (the oven, the bed, the free hallway
    position ``"5,6"``), the Infotaxis estimator, the policies ``tour``, ``infotaxis`` and
    ``space-aware-infotaxis`` with the variants ``olfaction``, ``semantics`` and ``semantics+rooms``
    (``docs/results/closed-loop.md`` gives the command that re-makes it).

    Parameters
    ----------
    source : str, optional, keyword-only
        One table, ``"oven"``, ``"bed"`` or ``"5,6"``; all three when None.

    Returns
    -------
    summary : dict
        ``{"<source>/infotaxis": {"<policy>/<variant>": arm}}``; each arm holds ``n_runs``, ``seeds``,
        ``success_rate`` (``value`` and its Wilson ``ci95``), ``km`` (the Kaplan-Meier curve of P(not yet found
        by t): ``t`` in s, ``survival``, its 95 % band ``lower`` and ``upper``), ``rmst`` (``value`` and ``ci95``
        in s, ``tau`` the budget in s), ``time_to_find`` and ``final_error`` (m), among others.
    paired : dict
        ``{"<source>/infotaxis": {"<arm A> - <arm B>": comparison}}``: the paired RMST difference in s on
        common seeds (``rmst_difference`` with its bootstrap ``ci95``), ``n``, ``p_holm`` and whether it is
        the ``primary`` comparison declared before the runs.

    Raises
    ------
    TypeError
        ``source`` is not a string.
    ValueError
        ``source`` names no table of the grid.

    Examples
    --------
    >>> from psgsl_pgm.teaching import closed_loop_results
    >>> summary, paired = closed_loop_results(source="oven")
    >>> list(summary)
    ['oven/infotaxis']
    >>> summary["oven/infotaxis"]["tour/olfaction"]["rmst"]["tau"]
    1000.0
    """
    folder = resources.files("psgsl_pgm") / "data" / "closed_loop"
    summary, paired = (json.loads((folder / name).read_text(encoding="utf-8")) for name in _FILES)
    if source is None:
        return summary, paired
    if not isinstance(source, str):
        raise TypeError(f"source: expected a string or None, got {type(source).__name__}")
    key = f"{source}/infotaxis"
    if key not in summary:
        names = sorted(k.split("/")[0] for k in summary)
        raise ValueError(f"source: expected one of {names}, got {source!r}")
    return {key: summary[key]}, ({key: paired[key]} if key in paired else {})
