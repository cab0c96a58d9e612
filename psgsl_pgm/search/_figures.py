"""Figures of the closed loop: Kaplan–Meier survival curves and the robots' paths over their final posteriors."""

from __future__ import annotations

import numpy as np

from ._survival import kaplan_meier, rmst

__all__ = ["plot_paths", "plot_survival"]


def plot_survival(groups: dict, *, title: str = ""):
    """Kaplan–Meier curves P(no success by t) with their 95 % pointwise bands, one per ``"<policy>/<variant>"``.

    Each curve is :func:`psgsl_pgm.search._survival.kaplan_meier` of the runs' times to find, censored at the
    budget; its band (log(−log) Greenwood) is shaded in the curve's colour, and the legend gives the RMST with
    its 95 % interval.

    Parameters
    ----------
    groups : dict
        ``{"<policy>/<variant>": [SearchRun, ...]}``; every run's configuration holds the time budget, s.
    title : str, default "", keyword-only
        A line written above the figure's own title; empty: none.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (needs the ``matplotlib`` extra).

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import SearchConfig, plot_survival, run_closed_loop
    >>> run = run_closed_loop("oven", 0, "greedy", "olfaction", config=ExperimentConfig(warm_up=5.0),
    ...                       search=SearchConfig(time_budget=20.0))
    >>> fig = plot_survival({"greedy/olfaction": [run]})
    >>> fig.axes[0].get_xlabel()
    'simulated time since the start, t [s]'
    >>> plt.close(fig)
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.4, 4.4 + 0.12 * len(groups)), layout="constrained")
    budget = max(r.config["search"]["time_budget"] for v in groups.values() for r in v)
    styles = {"olfaction": ":", "semantics": "--", "semantics+rooms": "-"}
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (key, runs) in enumerate(groups.items()):
        policy, variant = key.split("/")
        t = [r.time_to_success for r in runs]
        found = np.array([r.succeeded for r in runs])
        km = kaplan_meier(t, found)
        area = rmst(t, found, budget)
        x = np.append(km["t"], budget)  # the last step holds until the budget
        c = colours[i % len(colours)]
        lo, hi = area["ci95"]
        ax.step(x, np.append(km["survival"], km["survival"][-1]), where="post", color=c,
                ls=styles.get(variant, "-"), lw=1.6,
                label=f"{key} (n = {len(runs)}; RMST {area['value']:.0f} s [{lo:.0f}, {hi:.0f}])")
        ax.fill_between(x, np.append(km["lower"], km["lower"][-1]), np.append(km["upper"], km["upper"][-1]),
                        step="post", color=c, alpha=0.12, lw=0)
    ax.set_xlabel("simulated time since the start, t [s]")
    ax.set_ylabel("P(no success by t) [-], Kaplan–Meier")
    ax.set_xlim(0, budget)
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    fig.legend(fontsize=7, loc="outside lower center", ncols=2, frameon=False)
    ax.set_title((title + "\n" if title else "") + "survival with 95 % pointwise bands (log(−log) Greenwood); "
                 "runs without success censored at the budget", fontsize=8)
    return fig


def plot_paths(runs: dict, house, *, title: str = "", floor: float = 1e-6):
    """Each run's path over its final posterior, one panel per ``"<policy>/<variant>"``, one colour scale.

    The colour is log10 of the posterior per cell, on one scale for every panel (from ``floor`` to the largest
    value of any panel), with one colour bar; walls are dark grey; the path is white, the start a circle, the
    true source a star.

    Parameters
    ----------
    runs : dict
        ``{"<policy>/<variant>": SearchRun}``, one run per panel (each with its path, (k, 2) m, and its final
        posterior over the house's cells, (h, w)).
    house : psgsl_pgm.sim.House
        The house the runs drove in (its grid places the panels, in m, and draws the walls).
    title : str, default "", keyword-only
        The figure's title; empty: none.
    floor : float, default 1e-6, keyword-only
        The smallest posterior per cell shown: values below are drawn at ``floor`` (the log scale's lower end).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (needs the ``matplotlib`` extra).

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import SearchConfig, plot_paths, run_closed_loop
    >>> from psgsl_pgm.sim import default_house
    >>> run = run_closed_loop("oven", 0, "greedy", "olfaction", config=ExperimentConfig(warm_up=5.0),
    ...                       search=SearchConfig(time_budget=20.0))
    >>> fig = plot_paths({"greedy/olfaction": run}, default_house(0))
    >>> fig.axes[0].get_title().splitlines()[0], fig.axes[0].get_xlabel()
    ('greedy/olfaction', 'x [m]')
    >>> plt.close(fig)
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    keys = list(runs)
    n = len(keys)
    cols = min(n, 3)
    rows = int(np.ceil(n / cols))
    g = house.grid
    h, w = house.shape
    extent = (g.origin[0], g.origin[0] + w * g.resolution, g.origin[1], g.origin[1] + h * g.resolution)
    vmax = max(float(r.final_posterior.max()) for r in runs.values())
    norm = LogNorm(vmin=floor, vmax=max(vmax, floor * 10))
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols + 0.8, 3.9 * rows), squeeze=False, layout="constrained")
    walls = np.ma.masked_where(~g.occupancy, np.ones(house.shape))
    im = None
    for ax, key in zip(axes.ravel(), keys):
        r = runs[key]
        post = np.clip(r.final_posterior.astype(np.float64), floor, None)
        im = ax.imshow(post, origin="lower", extent=extent, norm=norm, cmap="viridis", interpolation="nearest")
        ax.imshow(walls, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.4, interpolation="nearest")
        ax.plot(r.path[:, 0], r.path[:, 1], color="white", lw=1.0)
        ax.plot(*r.path[0], "o", color="white", ms=5, mec="k")
        ax.plot(*r.source_xy, "*", color="red", ms=11, mec="k")
        if r.end == "declare":
            state = (f"declared at {r.time_to_declare:.0f} s, {r.declared_error:.1f} m off"
                     + ("" if r.declared_correct else " (wrong)") if r.declared else f"no declaration in "
                     f"{r.time_to_success:.0f} s")
        else:
            state = f"found at {r.time_to_find:.0f} s" if r.found else f"not found in {r.time_to_find:.0f} s"
        ax.set_title(f"{key}\n{state}, {r.driven:.1f} m", fontsize=8)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    cb = fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.8)
    cb.set_label("final posterior p(s) per cell [-] (log scale)")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig
