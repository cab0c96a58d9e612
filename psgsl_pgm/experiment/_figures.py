"""The paper's validation figures: error-chart, progression, room-types (Sec. "Validation")."""

from __future__ import annotations

import numpy as np

from ..sim._plot import map_norm, plot_cell_map
from ._config import VARIANTS
from ._summary import aligned

__all__ = ["plot_error_chart", "plot_progression", "plot_room_types"]

_COLOURS = {"olfaction": "tab:grey", "semantics": "tab:blue", "semantics+rooms": "tab:orange"}
_STYLES = {"olfaction": "-", "semantics": "-", "semantics+rooms": "--"}


def _prob_map(ax, house, p, title, norm):
    """One panel of p(s | ·) through the package's one map plotter (the caller draws the shared colour bar)."""
    plot_cell_map(np.where(house.grid.occupancy, np.nan, p), house=house, ax=ax, norm=norm, colorbar=False,
                  title=title)
    ax.title.set_fontsize(9)
    return ax.images[0]


def plot_error_chart(runs, *, ax=None, points: int = 201):
    """Fig. error-chart: mean error over runs against search progress, ± the mean spread (the paper's bars).

    Parameters
    ----------
    runs : sequence of RunResult
    ax : matplotlib Axes, optional, keyword-only
    points : int, keyword-only
        Progress grid size.

    Returns
    -------
    matplotlib Figure

    Raises
    ------
    ValueError
        ``runs`` is empty (a mean over no runs is not a chart).

    Examples
    --------
    One short run (two stops of the tour, 5 s of gas before it):

    >>> import matplotlib.pyplot as plt
    >>> from psgsl_pgm.experiment import ExperimentConfig, plot_error_chart, run_search
    >>> run = run_search("oven", 0, config=ExperimentConfig(stops=2, warm_up=5.0))
    >>> fig = plot_error_chart([run])
    >>> fig.axes[0].get_ylabel()
    '‖E[s] − s_true‖  (m)'
    >>> plt.close(fig)
    """
    import matplotlib.pyplot as plt

    runs = list(runs)
    if not runs:
        raise ValueError("runs must hold at least one run, got an empty sequence")
    if ax is None:
        fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    else:
        fig = ax.figure
    grid = np.linspace(0.0, 1.0, points)
    err = aligned(runs, "error", grid).mean(axis=0)
    spr = aligned(runs, "spread", grid).mean(axis=0)
    minutes = np.mean([r.time[-1] for r in runs]) / 60
    for v, name in enumerate(VARIANTS):  # bands first, as outlines over a faint fill, so that none hides a curve
        c = _COLOURS[name]
        low, high = np.maximum(err[:, v] - spr[:, v], 0), err[:, v] + spr[:, v]
        ax.fill_between(grid, low, high, color=c, alpha=0.07, lw=0, zorder=1)
        for edge in (low, high):
            ax.plot(grid, edge, color=c, lw=0.8, ls=":", zorder=2)
    for v, name in enumerate(VARIANTS):  # the means on top; dashed where two variants may coincide
        ax.plot(grid, err[:, v], color=_COLOURS[name], lw=1.8, ls=_STYLES[name], label=name, zorder=3)
    ax.set_xlabel(f"fraction of the search (tour of ≈ {minutes:.0f} min)")
    ax.set_ylabel("‖E[s] − s_true‖  (m)")
    ax.set_xlim(0, 1)
    ax.set_ylim(bottom=0)
    ax.set_title(f"Source error, mean over {len(runs)} runs; dotted bands: ± the spread of p(s | ·)", fontsize=10)
    ax.legend(frameon=False)
    ax.grid(alpha=0.3)
    return fig


def plot_progression(run, house, tour, *, variants=("olfaction", "semantics+rooms"), dynamic_range=1e4,
                     scale="figure"):
    """Fig. progression: the source distribution at the snapshot steps of ``run``, with the robot path.

    One colour scale for the whole figure (``scale="figure"``: rows are compared with each other, one colour
    bar), or one per row (``scale="row"``, a colour bar per variant). The scale is logarithmic: as the search proceeds the mass concentrates on a few cells (at the end of an oven
    search ten cells can hold 90 % of it), and a linear scale would show the earlier, flatter snapshots of
    the same row as blank. Cells below ``max / dynamic_range`` get the lowest colour.

    Parameters
    ----------
    run : RunResult
        With ``snapshots`` (see ``run_search(snapshot_at=...)``).
    house : psgsl_pgm.sim.House
        The run's house (``default_house(run.seed)``).
    tour : Tour
        The run's tour (the path drawn dashed up to each snapshot).
    variants : sequence of str, keyword-only
        Rows of the figure.
    dynamic_range : float, default 1e4, keyword-only
        Decades shown by the log scale (vmin = vmax / dynamic_range).
    scale : {"figure", "row"}, keyword-only
        One colour scale for all panels, or one per row.

    Returns
    -------
    matplotlib Figure

    Raises
    ------
    ValueError
        ``run`` kept no snapshots, or ``scale`` is neither ``"figure"`` nor ``"row"``.

    Examples
    --------
    One short run (two stops of the tour) with the posteriors kept before the first stop and at the end:

    >>> import matplotlib.pyplot as plt
    >>> from psgsl_pgm.experiment import ExperimentConfig, exploration_tour, plot_progression, run_search
    >>> from psgsl_pgm.sim import default_house
    >>> run = run_search("oven", 0, config=ExperimentConfig(stops=2, warm_up=5.0), snapshot_at=(0.0, 1.0))
    >>> house = default_house(0)
    >>> fig = plot_progression(run, house, exploration_tour(house).first(2))
    >>> len(fig.axes)                                          # 2 variants x 2 snapshots, and the colour bar
    5
    >>> plt.close(fig)
    """
    import matplotlib.pyplot as plt

    steps = sorted(run.snapshots)
    if not steps:
        raise ValueError("the run has no snapshots: call run_search(..., snapshot_at=[...])")
    if scale not in ("figure", "row"):
        raise ValueError(f"scale must be 'figure' or 'row', got {scale!r}")
    fig, axes = plt.subplots(len(variants), len(steps), figsize=(2.3 * len(steps) + 1.2, 2.9 * len(variants)),
                             squeeze=False, layout="constrained", sharex=True, sharey=True)
    n = run.n_steps
    free = ~house.grid.occupancy
    shared = map_norm(*(run.snapshots[s][VARIANTS.index(name)][free] for s in steps for name in variants), log=True,
                      dynamic_range=dynamic_range)
    for i, name in enumerate(variants):
        v = VARIANTS.index(name)
        norm = shared if scale == "figure" else map_norm(*(run.snapshots[s][v][free] for s in steps), log=True,
                                                         dynamic_range=dynamic_range)
        for j, s in enumerate(steps):
            ax = axes[i, j]
            im = _prob_map(ax, house, np.maximum(run.snapshots[s][v], norm.vmin), f"{name}, {100 * s / n:.0f} %",
                           norm)
            if s > 0:
                reached = tour.path[: tour.path_index[s - 1] + 1]  # up to stop s (1-based steps)
                ax.plot(reached[:, 0], reached[:, 1], "w--", lw=0.8)
                ax.plot(*run.position[s], "wo", ms=3)
            ax.plot(*run.source_xy, marker="*", color="red", ms=9, mec="white", mew=0.5)
            if i < len(variants) - 1:
                ax.set_xlabel("")
            if j > 0:
                ax.set_ylabel("")
        if scale == "row":
            fig.colorbar(im, ax=list(axes[i]), shrink=0.9, label=f"p(s_c | ·), {name} (log)")
    if scale == "figure":
        fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.6, label="p(s_c | ·) per cell (log; one scale for all)")
    fig.suptitle("p(s | ·) during the search (dashed: robot path; white dot: robot; star: true source)",
                 fontsize=10)
    return fig


def plot_room_types(semantic_plain, semantic_rooms, house, *, source=None):
    """Fig. room-types: the source distribution at the start, (A) no prior information, (B) room categories.

    Parameters
    ----------
    semantic_plain, semantic_rooms : (H, W) ndarray
        p(s | ·) before the first reading without / with the room-category map.
    house : psgsl_pgm.sim.House
    source : (2,) array_like, optional, keyword-only
        Drawn as a star.

    Returns
    -------
    matplotlib Figure

    Examples
    --------
    Two made-up distributions over the free cells of the default house (uniform, and twice as likely in the
    kitchen):

    >>> import numpy as np
    >>> from psgsl_pgm.experiment import plot_room_types
    >>> from psgsl_pgm.sim import default_house
    >>> house = default_house(seed=0)
    >>> plain = (~house.grid.occupancy).astype(float); plain /= plain.sum()
    >>> rooms = plain * np.where(house.room_labels == house.room_names.index("Kitchen"), 2.0, 1.0); rooms /= rooms.sum()
    >>> fig = plot_room_types(plain, rooms, house, source=(7.0, 1.0))
    >>> [ax.get_title() for ax in fig.axes[:2]]
    ['(A) no previous information', '(B) room-category map']
    >>> import matplotlib.pyplot as plt; plt.close(fig)
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(8.0, 4.6), layout="constrained")
    free = ~house.grid.occupancy
    norm = map_norm(semantic_plain[free], semantic_rooms[free])  # one linear colour scale for both panels
    for ax, p, t in zip(axes, (semantic_plain, semantic_rooms),
                        ("(A) no previous information", "(B) room-category map")):
        im = _prob_map(ax, house, p, t, norm)
        if source is not None:
            ax.plot(*source, marker="*", color="red", ms=9, mec="white", mew=0.5)
    fig.colorbar(im, ax=list(axes), shrink=0.8, label="p(s_c | ·) per cell")
    fig.suptitle("Source distribution at the start of the search", fontsize=10)
    return fig
