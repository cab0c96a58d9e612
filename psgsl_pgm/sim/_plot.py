"""Drawing the house, its wind and a gas snapshot with matplotlib (imported on call, never at import time)."""

from __future__ import annotations

import numpy as np

from ._classes import OTHER

__all__ = ["plot_house"]


def plot_house(house, *, ax=None, wind=None, concentration=None, source=None, rooms: bool = True,
               objects: bool = True, labels: bool = True, wind_stride: int = 4):
    """Draw a :class:`House`: rooms, walls, windows, objects, and optionally wind and gas.

    Parameters
    ----------
    house : House
    ax : matplotlib Axes, optional, keyword-only
        Drawn into; a new figure otherwise.
    wind : WindField, optional, keyword-only
        Drawn as arrows every ``wind_stride`` cells.
    concentration : (H, W) ndarray, optional, keyword-only
        Gas concentration (ppm), drawn with transparency over the rooms.
    source : (2,) array_like, optional, keyword-only
        Gas source position, drawn as a star.
    rooms, objects, labels : bool, keyword-only
        Shade rooms; fill object cells by class; write room and class names.
    wind_stride : int, keyword-only

    Returns
    -------
    matplotlib Axes
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 8))
    g = house.grid
    ext = g.extent
    if rooms:
        lab = np.ma.masked_less(house.room_labels, 0)
        ax.imshow(lab, origin="lower", extent=ext, cmap="Pastel2", alpha=0.6, interpolation="nearest",
                  vmin=0, vmax=max(len(house.room_names) - 1, 1))
    if objects and house.objects:
        cm = house.class_map
        other = house.classes.index(OTHER)
        obj = np.ma.masked_where(cm == other, cm)
        ax.imshow(obj, origin="lower", extent=ext, cmap="tab20", interpolation="nearest", vmin=0,
                  vmax=len(house.classes) - 1)
    if concentration is not None:
        c = np.asarray(concentration, dtype=np.float64)
        c = np.ma.masked_where(~np.isfinite(c) | (c <= 0), c)  # nan = not computed (strided field)
        ax.imshow(c, origin="lower", extent=ext, cmap="magma_r", alpha=0.7, interpolation="nearest")
    ax.imshow(np.ma.masked_where(~g.occupancy, g.occupancy), origin="lower", extent=ext,
              cmap=ListedColormap(["black"]), interpolation="nearest")
    for mask, colour in ((house.inlet, "tab:blue"), (house.outlet, "tab:red")):
        ax.imshow(np.ma.masked_where(~mask, mask), origin="lower", extent=ext, cmap=ListedColormap([colour]),
                  interpolation="nearest")
    if wind is not None:
        xy = g.cell_centres()[::wind_stride, ::wind_stride]
        v = wind.velocity[::wind_stride, ::wind_stride]
        keep = g.free[::wind_stride, ::wind_stride]
        ax.quiver(xy[..., 0][keep], xy[..., 1][keep], v[..., 0][keep], v[..., 1][keep], color="tab:blue",
                  angles="xy", scale_units="xy", scale=0.5, width=0.002)
    if labels:
        for i, name in enumerate(house.room_names):
            rr, cc = np.nonzero(house.room_labels == i)
            if rr.size:
                x, y = g.cell_to_world(np.array([int(np.median(rr)), int(np.median(cc))]))
                ax.text(x, y, name, ha="center", va="center", fontsize=9, alpha=0.6)
        if objects:
            for o in house.objects:
                x, y = o.center
                ax.text(x, y, o.class_name, ha="center", va="center", fontsize=6)
    if source is not None:
        sx, sy = np.asarray(source, dtype=float)[:2]
        ax.plot(sx, sy, marker="*", color="red", markersize=14, markeredgecolor="k")
    ax.set_xlim(ext[0], ext[1])
    ax.set_ylim(ext[2], ext[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return ax
