"""Maps over the cells of a grid (the simulated house), with walls drawn on top."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_cell_map"]


def plot_cell_map(values, *, house=None, ax=None, title=None, cmap="viridis", log=False, colorbar=True,
                  label=None):
    """Draw a value per cell (a probability map, an information-gain map) as an image.

    Parameters
    ----------
    values : (H, W) array_like
        One number per cell; row index ↔ y, column index ↔ x (the house's convention). NaN cells are left
        blank.
    house : psgsl_pgm.sim.House, optional, keyword-only
        Gives the extent in metres and the walls (drawn black). Without it, axes are in cells.
    ax : matplotlib Axes, optional, keyword-only
    title, label : str, optional, keyword-only
        Axes title, colour-bar label.
    cmap : str, keyword-only
    log : bool, keyword-only
        Logarithmic colour scale (positive values only; zeros are left blank).
    colorbar : bool, keyword-only

    Returns
    -------
    matplotlib Axes

    Raises
    ------
    ValueError
        ``values`` not 2-D, or not of the house's shape.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.teaching import plot_cell_map
    >>> ax = plot_cell_map(np.arange(12.0).reshape(3, 4), title="cells")
    >>> ax.get_title()
    'cells'
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap, LogNorm

    v = np.asarray(values, dtype=np.float64)
    if v.ndim != 2:
        raise ValueError(f"values must be an (H, W) map, got shape {v.shape}")
    if house is not None and v.shape != tuple(house.shape):
        raise ValueError(f"values must have the house's shape {tuple(house.shape)}, got {v.shape}")
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    extent = None if house is None else house.grid.extent
    blank = ~np.isfinite(v) | ((v <= 0) if log else False)
    shown = np.ma.masked_where(blank, v)
    norm = None
    if log and shown.count():
        norm = LogNorm(vmin=shown.min(), vmax=shown.max())
    image = ax.imshow(shown, origin="lower", extent=extent, cmap=cmap, norm=norm, interpolation="nearest")
    if house is not None:
        walls = house.grid.occupancy
        ax.imshow(np.ma.masked_where(~walls, walls), origin="lower", extent=extent,
                  cmap=ListedColormap(["black"]), interpolation="nearest")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    if colorbar:
        ax.figure.colorbar(image, ax=ax, shrink=0.8, label=label)
    if title is not None:
        ax.set_title(title)
    ax.set_aspect("equal")
    return ax
