"""The paper's validation figures: error-chart, progression, room-types (Sec. "Validation")."""

from __future__ import annotations

import numpy as np

from ._config import VARIANTS
from ._summary import aligned

__all__ = ["plot_error_chart", "plot_progression", "plot_room_types"]

_COLOURS = {"olfaction": "tab:grey", "semantics": "tab:blue", "semantics+rooms": "tab:orange"}


def _walls(ax, house):
    g = house.grid
    ax.imshow(np.ma.masked_where(~g.occupancy, g.occupancy), origin="lower", extent=g.extent, cmap="Greys",
              vmin=0, vmax=1, interpolation="nearest")


def _prob_map(ax, house, p, title, vmax=None):
    g = house.grid
    masked = np.ma.masked_where(g.occupancy, p)
    vmax = float(masked.max()) if vmax is None else float(vmax)
    im = ax.imshow(masked, origin="lower", extent=g.extent, cmap="viridis", interpolation="nearest",
                   vmin=0, vmax=vmax if vmax > 0 else 1.0)
    _walls(ax, house)
    ax.set_title(title, fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])
    return im


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
    """
    import matplotlib.pyplot as plt

    runs = list(runs)
    if ax is None:
        fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    else:
        fig = ax.figure
    grid = np.linspace(0.0, 1.0, points)
    err = aligned(runs, "error", grid).mean(axis=0)
    spr = aligned(runs, "spread", grid).mean(axis=0)
    minutes = np.mean([r.time[-1] for r in runs]) / 60
    for v, name in enumerate(VARIANTS):
        c = _COLOURS[name]
        ax.plot(grid, err[:, v], color=c, lw=1.8, label=name)
        ax.fill_between(grid, np.maximum(err[:, v] - spr[:, v], 0), err[:, v] + spr[:, v], color=c, alpha=0.15)
    ax.set_xlabel(f"fraction of the search (tour of ≈ {minutes:.0f} min)")
    ax.set_ylabel("‖E[s] − s_true‖  (m)")
    ax.set_xlim(0, 1)
    ax.set_ylim(bottom=0)
    ax.set_title(f"Source error, mean over {len(runs)} runs; bands ± std of p(s | ·)", fontsize=10)
    ax.legend(frameon=False)
    ax.grid(alpha=0.3)
    return fig


def plot_progression(run, house, tour, *, variants=("olfaction", "semantics+rooms")):
    """Fig. progression: the source distribution at the snapshot steps of ``run``, with the robot path.

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

    Returns
    -------
    matplotlib Figure
    """
    import matplotlib.pyplot as plt

    steps = sorted(run.snapshots)
    if not steps:
        raise ValueError("the run has no snapshots: call run_search(..., snapshot_at=[...])")
    fig, axes = plt.subplots(len(variants), len(steps), figsize=(2.3 * len(steps), 2.7 * len(variants)),
                             squeeze=False, layout="constrained")
    n = run.n_steps
    for i, name in enumerate(variants):
        v = VARIANTS.index(name)
        for j, s in enumerate(steps):
            ax = axes[i, j]
            _prob_map(ax, house, run.snapshots[s][v], f"{name}, {100 * s / n:.0f} %")
            if s > 0:
                reached = tour.path[: tour.path_index[s - 1] + 1]  # up to stop s (1-based steps)
                ax.plot(reached[:, 0], reached[:, 1], "w--", lw=0.8)
                ax.plot(*run.position[s], "wo", ms=3)
            ax.plot(*run.source_xy, marker="*", color="red", ms=9, mec="white", mew=0.5)
    fig.suptitle("p(s | ·) during the search (dashed: robot path; star: true source)", fontsize=10)
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
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(8.0, 4.6), layout="constrained")
    top = max(float(np.max(semantic_plain)), float(np.max(semantic_rooms)))  # one colour scale for both
    for ax, p, t in zip(axes, (semantic_plain, semantic_rooms),
                        ("(A) no previous information", "(B) room-category map")):
        im = _prob_map(ax, house, p, t, vmax=top)
        if source is not None:
            ax.plot(*source, marker="*", color="red", ms=9, mec="white", mew=0.5)
    fig.colorbar(im, ax=list(axes), shrink=0.8, label="p(s_c | ·)")
    fig.suptitle("Source distribution at the start of the search", fontsize=10)
    return fig
