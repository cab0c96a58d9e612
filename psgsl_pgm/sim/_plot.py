"""The one map plotter: the house, any value per cell, and one colour scale across compared panels.

Every drawing of a grid map in the package goes through here — the simulator's :func:`plot_house`, the
teaching notebooks' maps (``psgsl_pgm.teaching.plot_cell_map`` is :func:`plot_cell_map`) and the validation
figures of ``psgsl_pgm.experiment`` (Fig. ``progression``, ``room-types``). matplotlib is imported inside
the functions, never when the package is imported.

Conventions: a map is an (H, W) array, row index ↔ y, column index ↔ x (the grid's convention), drawn with
``origin="lower"`` over the grid's extent in metres; axes are labelled ``x [m]`` / ``y [m]`` (``column`` /
``row`` in cells without a grid); colour that carries a value always gets a colour bar.
"""

from __future__ import annotations

import numpy as np

from ._classes import OTHER

__all__ = ["declutter", "draw_walls", "figure_problems", "map_norm", "object_label_positions", "plot_cell_map",
           "plot_house"]


def _grid_of(house, grid):
    if house is not None and grid is not None:
        raise ValueError("pass house= or grid=, not both")
    return house.grid if house is not None else grid


def map_norm(*maps, log: bool = False, dynamic_range: float | None = None):
    """One colour scale for several maps (panels that are compared must share it).

    Parameters
    ----------
    *maps : array_like
        The maps (any shapes); NaN and ±inf are ignored, and so are values <= 0 on a log scale.
    log : bool, default False, keyword-only
        A logarithmic scale (``LogNorm``) instead of a linear one from 0.
    dynamic_range : float, optional, keyword-only
        Log scale only: the lower end is at least ``vmax / dynamic_range`` (e.g. 1e4 shows four decades
        below the largest value; smaller values are drawn in the lowest colour).

    Returns
    -------
    matplotlib.colors.Normalize or matplotlib.colors.LogNorm
        Linear: [0, max] (or [min, max] when a value is negative). Log: [min positive, max].

    Raises
    ------
    ValueError
        No finite (positive, for ``log``) value in any map, or ``dynamic_range`` not > 1.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.sim import map_norm
    >>> n = map_norm(np.array([0.0, 0.2]), np.array([0.5, np.nan]))
    >>> float(n.vmin), float(n.vmax)
    (0.0, 0.5)
    >>> n = map_norm(np.array([1e-9, 1e-2]), log=True, dynamic_range=1e3)
    >>> float(n.vmin), float(n.vmax)
    (1e-05, 0.01)
    """
    from matplotlib.colors import LogNorm, Normalize

    if dynamic_range is not None and not (np.isfinite(dynamic_range) and dynamic_range > 1):
        raise ValueError(f"dynamic_range must be a finite number > 1, got {dynamic_range!r}")
    values = np.concatenate([np.asarray(m, dtype=np.float64).ravel() for m in maps]) if maps else np.empty(0)
    keep = np.isfinite(values) & ((values > 0) if log else True)
    if not keep.any():
        raise ValueError("map_norm needs at least one finite" + (" positive" if log else "") + " value")
    lo, hi = float(values[keep].min()), float(values[keep].max())
    if log:
        if dynamic_range is not None:
            lo = max(lo, hi / dynamic_range)
        return LogNorm(vmin=lo, vmax=hi if hi > lo else lo * 10)
    lo = min(lo, 0.0)
    return Normalize(vmin=lo, vmax=hi if hi > lo else lo + 1.0)


def draw_walls(ax, grid, *, colour: str = "black"):
    """Draw the occupied cells of ``grid`` (walls) in one colour on top of ``ax``; return the image."""
    from matplotlib.colors import ListedColormap

    occ = np.asarray(grid.occupancy, dtype=bool)
    return ax.imshow(np.ma.masked_where(~occ, occ), origin="lower", extent=grid.extent,
                     cmap=ListedColormap([colour]), interpolation="nearest")


def _label_axes(ax, grid):
    if grid is None:
        ax.set_xlabel("column (cell)")
        ax.set_ylabel("row (cell)")
    else:
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")


def plot_cell_map(values, *, house=None, grid=None, ax=None, title=None, cmap="viridis", log=False, norm=None,
                  colorbar=True, label="value per cell", walls=True, objects=False):
    """Draw one number per cell (a probability map, an information-gain map) as an image.

    Parameters
    ----------
    values : (H, W) array_like
        One number per cell; row index ↔ y, column index ↔ x. NaN cells are left blank.
    house : psgsl_pgm.sim.House, optional, keyword-only
        Gives the extent in metres and the walls (drawn black). Without it (and without ``grid``) the axes
        are in cells.
    grid : GridMap, optional, keyword-only
        Instead of ``house``.
    ax : matplotlib Axes, optional, keyword-only
    title : str, optional, keyword-only
    cmap : str, keyword-only
    log : bool, keyword-only
        Logarithmic colour scale (values <= 0 are left blank). Ignored when ``norm`` is given.
    norm : matplotlib Normalize, optional, keyword-only
        A colour scale shared with other panels (:func:`map_norm`); default: this map's own range.
    colorbar : bool, keyword-only
        Draw a colour bar (pass False only when a shared bar is drawn by the caller).
    label : str, keyword-only
        Colour-bar label (say what the value is, with units).
    walls : bool, keyword-only
        Draw the walls of ``house``/``grid`` on top.
    objects : bool, keyword-only
        Write each object's class name on its visible part (needs ``house``; :func:`object_label_positions`).

    Returns
    -------
    matplotlib Axes
        With the value image as ``ax.images[0]``.

    Raises
    ------
    ValueError
        ``values`` not 2-D, or not of the grid's shape; ``objects`` without ``house``.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.sim import plot_cell_map
    >>> ax = plot_cell_map(np.arange(12.0).reshape(3, 4), title="cells", label="index")
    >>> ax.get_title(), ax.get_xlabel(), ax.images[0].colorbar.ax.get_ylabel()
    ('cells', 'column (cell)', 'index')
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    g = _grid_of(house, grid)
    v = np.asarray(values, dtype=np.float64)
    if v.ndim != 2:
        raise ValueError(f"values must be an (H, W) map, got shape {v.shape}")
    if g is not None and v.shape != tuple(g.shape):
        raise ValueError(f"values must have the house's shape {tuple(g.shape)}, got {v.shape}")
    if objects and house is None:
        raise ValueError("objects=True needs house= (the objects to label)")
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    log = isinstance(norm, LogNorm) if norm is not None else log
    shown = np.ma.masked_where(~np.isfinite(v) | ((v <= 0) if log else False), v)
    if norm is None and shown.count():
        norm = map_norm(shown.compressed(), log=log)
    extent = None if g is None else g.extent
    image = ax.imshow(shown, origin="lower", extent=extent, cmap=cmap, norm=norm, interpolation="nearest")
    if g is not None and walls:
        draw_walls(ax, g)
    if objects:
        _label_objects(ax, house)  # black on the white backing (white text on it could not be read)
    _label_axes(ax, g)
    if colorbar:
        ax.figure.colorbar(image, ax=ax, shrink=0.8, label=label)
    if title is not None:
        ax.set_title(title)
    ax.set_aspect("equal")
    return ax


def object_label_positions(house) -> np.ndarray:
    """(n_objects, 2) a point (metres) inside the *visible* part of each object, for its label.

    An object drawn over another (the oven standing in a countertop) hides part of it; the label of each
    object goes to the visible cell deepest inside what is visible of it (largest distance to its border),
    so no label sits on another object. An object with no visible cell keeps its centroid.
    """
    g = house.grid
    owner = np.full(house.shape, -1, dtype=np.int64)
    for i, m in enumerate(house.object_masks):  # later objects are drawn over earlier ones (as in class_map)
        owner[m] = i
    centres = g.cell_centres()
    out = np.empty((len(house.objects), 2))
    for i, o in enumerate(house.objects):  # one distance transform per object
        visible = owner == i
        out[i] = _deepest(visible, centres, o.center) if visible.any() else o.center
    return out


#: A text's backing: labels stay readable over walls, furniture and arrows.
LABEL_BOX = {"boxstyle": "round,pad=0.15", "facecolor": "white", "edgecolor": "none", "alpha": 0.8}


def _label_objects(ax, house, *, colour="black", fontsize=6):
    """Write every object's class name at its :func:`object_label_positions` point (clipped to the axes)."""
    def own(o):  # an object lumped into "other" keeps its own class in its name ("bed#bed_4")
        return o.name.split("#", 1)[0] if o.class_name == OTHER and "#" in o.name else o.class_name

    return [ax.text(x, y, own(o), ha="center", va="center", fontsize=fontsize, color=colour, clip_on=True,
                    bbox=LABEL_BOX, zorder=5)
            for o, (x, y) in zip(house.objects, object_label_positions(house))]


def declutter(ax, texts, *, avoid=(), marker_size: float = 14.0, tries: int = 12) -> int:
    """Move texts so that no two overlap: each in turn, by steps of its own height, alternately down and up.

    Parameters
    ----------
    ax : matplotlib Axes
    texts : sequence of matplotlib Text
        In order of priority (earlier texts stay where they are).
    avoid : sequence of (x, y), keyword-only
        Marker positions (data coordinates) that no text may cover.
    marker_size : float, keyword-only
        Their size, points.
    tries : int, keyword-only
        Positions tried per text before it is left where it overlaps least.

    Returns
    -------
    int
        Texts that still overlap another (0: none).
    """
    fig = ax.figure
    fig.draw_without_rendering()  # final layout: extents in display units
    renderer = fig.canvas.get_renderer()
    to_data = ax.transData.inverted()
    from matplotlib.transforms import Bbox

    half = marker_size / 2 * fig.dpi / 72
    placed, left = [], 0
    for px, py in (ax.transData.transform(np.asarray(p, dtype=float)) for p in avoid):
        placed.append(Bbox([[px - half, py - half], [px + half, py + half]]))
    for t in texts:  # a handful of labels
        x0, y0 = t.get_position()
        box = t.get_window_extent(renderer)
        step = box.height * 1.05
        best, best_hits = (x0, y0), None
        for k in range(tries + 1):
            dy = 0.0 if k == 0 else step * ((k + 1) // 2) * (1 if k % 2 else -1)
            base = ax.transData.transform((x0, y0))
            x, y = to_data.transform((base[0], base[1] + dy))
            t.set_position((x, y))
            moved = t.get_window_extent(renderer)
            hits = sum(moved.overlaps(b) for b in placed)
            if best_hits is None or hits < best_hits:
                best, best_hits = (x, y), hits
            if hits == 0:
                break
        t.set_position(best)
        left += best_hits > 0
        placed.append(t.get_window_extent(renderer))
    return left


def _nice(v: float) -> float:
    """1, 2 or 5 × 10^k nearest below ``v`` (> 0): a round reference length."""
    e = np.floor(np.log10(v))
    m = v / 10**e
    return float((5 if m >= 5 else 2 if m >= 2 else 1) * 10**e)


def _deepest(mask, centres, target):
    """Centre of the cell of ``mask`` farthest from its border (ties: nearest ``target``); NaN if empty."""
    import scipy.ndimage as ndi

    if not mask.any():
        return np.full(2, np.nan)
    depth = ndi.distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
    near = -np.linalg.norm(centres - target, axis=-1) * 1e-6
    return centres[np.unravel_index(np.argmax(np.where(mask, depth + near, -np.inf)), mask.shape)]


def _room_label_positions(house, objects: bool) -> np.ndarray:
    """(n_rooms, 2) a point on the open floor of each room: off the map's occupied cells (walls and any furniture
    the map draws) and off the objects when they are drawn; deepest inside that floor."""
    centres = house.grid.cell_centres()
    open_floor = house.grid.free & (~house.furniture if objects and house.objects else True)
    out = np.empty((len(house.room_names), 2))
    for i in range(len(house.room_names)):  # one distance transform per room
        room = house.room_labels == i
        target = centres[room].mean(axis=0) if room.any() else np.zeros(2)
        out[i] = _deepest(room & open_floor, centres, target) if (room & open_floor).any() else \
            _deepest(room, centres, target)
    return out


def plot_house(house, *, ax=None, wind=None, concentration=None, source=None, rooms: bool = True,
               objects: bool = True, labels: bool = True, wind_stride: int = 4, colorbar: bool = True):
    """Draw a :class:`House`: rooms, walls, windows, objects, and optionally wind and gas.

    Parameters
    ----------
    house : House
    ax : matplotlib Axes, optional, keyword-only
        Drawn into; a new figure otherwise.
    wind : WindField, optional, keyword-only
        Drawn as arrows every ``wind_stride`` cells.
    concentration : (H, W) ndarray, optional, keyword-only
        Gas concentration (ppm), drawn with transparency over the rooms, with a colour bar.
    source : (2,) array_like, optional, keyword-only
        Gas source position, drawn as a red star.
    rooms, objects, labels : bool, keyword-only
        Shade rooms; fill object cells by class; write room and object class names (each object's name on
        its visible part, :func:`object_label_positions`; room names on open floor; on a white backing, moved
        apart by :func:`declutter` where they would overlap).
    wind_stride : int, keyword-only
        Arrows every this many cells; one scale for all (the 95th-percentile speed spans 90 % of the arrow
        spacing), stated by a key above the axes.
    colorbar : bool, keyword-only
        Colour bar of ``concentration``.

    Returns
    -------
    matplotlib Axes

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from psgsl_pgm.sim import default_house, plot_house
    >>> ax = plot_house(default_house(seed=0), labels=False)
    >>> ax.get_xlabel(), ax.get_ylabel()
    ('x [m]', 'y [m]')
    >>> plt.close(ax.figure)
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
        im = ax.imshow(c, origin="lower", extent=ext, cmap="magma_r", alpha=0.7, interpolation="nearest")
        if colorbar:
            ax.figure.colorbar(im, ax=ax, shrink=0.7, label="gas concentration [ppm]")
    draw_walls(ax, g)
    for mask, colour in ((house.inlet, "tab:blue"), (house.outlet, "tab:red")):
        ax.imshow(np.ma.masked_where(~mask, mask), origin="lower", extent=ext, cmap=ListedColormap([colour]),
                  interpolation="nearest")
    if wind is not None:
        xy = g.cell_centres()[::wind_stride, ::wind_stride]
        v = wind.velocity[::wind_stride, ::wind_stride]
        keep = g.free[::wind_stride, ::wind_stride]
        speed = np.hypot(v[..., 0], v[..., 1])[keep]
        # one scale for the figure: the 95th-percentile speed spans 90 % of the arrow spacing; a key states it
        ref = float(np.percentile(speed, 95)) if speed.size and speed.max() > 0 else 1.0
        spacing = wind_stride * g.resolution
        q = ax.quiver(xy[..., 0][keep], xy[..., 1][keep], v[..., 0][keep], v[..., 1][keep], color="tab:blue",
                      angles="xy", scale_units="xy", scale=ref / (0.9 * spacing), width=0.002)
        key = _nice(ref)
        ax.quiverkey(q, 0.0, 1.015, key, f"wind {key:g} m/s", labelpos="E", coordinates="axes",
                     fontproperties={"size": 8})
    texts = []
    if labels:
        for name, (x, y) in zip(house.room_names, _room_label_positions(house, objects)):
            if np.isfinite(x):
                texts.append(ax.text(x, y, name, ha="center", va="center", fontsize=9, clip_on=True,
                                     bbox=LABEL_BOX, zorder=6))
        if objects and house.objects:
            texts += _label_objects(ax, house)
    if source is not None:
        sx, sy = np.asarray(source, dtype=float)[:2]
        ax.plot(sx, sy, marker="*", color="red", markersize=14, markeredgecolor="k")
    ax.set_xlim(ext[0], ext[1])
    ax.set_ylim(ext[2], ext[3])
    ax.set_aspect("equal")
    _label_axes(ax, g)
    if texts:
        declutter(ax, texts)  # no label over another
    return ax


#: Colour maps whose colours name categories (rooms, object classes), not values: they need text labels or a
#: legend, not a colour bar.
QUALITATIVE_CMAPS = frozenset({"Pastel1", "Pastel2", "Paired", "Accent", "Dark2", "Set1", "Set2", "Set3", "tab10",
                               "tab20", "tab20b", "tab20c"})


def _carries_values(mappable) -> bool:
    """True when the colour of ``mappable`` (an image or a coloured collection) encodes a number."""
    data = mappable.get_array()
    if data is None:
        return False
    cmap = mappable.get_cmap()
    if cmap.name in QUALITATIVE_CMAPS or cmap.N <= 1:
        return False
    values = np.ma.masked_invalid(np.ma.asarray(data, dtype=np.float64)).compressed()
    return np.unique(values).size > 1  # a one-valued layer (walls, a field-of-view mask) is a mask


def figure_problems(fig) -> list:
    """What a reader would miss in ``fig``: unlabelled axes, value colours without a colour bar.

    The rules the package's figures (and its notebooks' figures) are held to:

    * every visible Axes has an x and a y label (its own, one of an Axes it shares that axis with, or the
      figure's ``supxlabel``/``supylabel``); Axes drawn with the axis off (network drawings) are exempt;
    * every image or coloured collection whose colour carries a value (not a one-valued mask, not a
      qualitative colour map of categories) has a colour bar — its own, or that of a mappable with the same
      norm (one scale shared by compared panels); no such image on an Axes with the axis off;
    * every colour bar has a label.

    Parameters
    ----------
    fig : matplotlib Figure

    Returns
    -------
    list of str
        One line per problem; empty when the figure is readable.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from psgsl_pgm.sim import figure_problems
    >>> fig, ax = plt.subplots()
    >>> _ = ax.imshow([[0.0, 1.0]])
    >>> figure_problems(fig)                                       # doctest: +NORMALIZE_WHITESPACE
    ['axes 0 (untitled): no x label', 'axes 0 (untitled): no y label',
     'axes 0 (untitled): image 0 carries values but has no colour bar']
    >>> plt.close(fig)
    """
    problems = []
    mappables = [m for ax in fig.axes for m in (*ax.images, *ax.collections)]
    with_bar = [m for m in mappables if getattr(m, "colorbar", None) is not None]
    bar_axes = {m.colorbar.ax for m in with_bar}
    shared_norms = {id(m.norm) for m in with_bar}
    for cb_ax in bar_axes:
        if not (cb_ax.get_ylabel() or cb_ax.get_xlabel()):
            problems.append(f"colour bar of {cb_ax.get_label() or 'an image'}: no label")
    sup_x = bool(fig.get_supxlabel()) if hasattr(fig, "get_supxlabel") else False
    sup_y = bool(fig.get_supylabel()) if hasattr(fig, "get_supylabel") else False
    for a, ax in enumerate(x for x in fig.axes if x not in bar_axes):
        name = f"axes {a} ({ax.get_title() or 'untitled'})"
        if ax.axison:
            xs = [ax, *ax.get_shared_x_axes().get_siblings(ax)]
            ys = [ax, *ax.get_shared_y_axes().get_siblings(ax)]
            if not (sup_x or any(s.get_xlabel() for s in xs)):
                problems.append(f"{name}: no x label")
            if not (sup_y or any(s.get_ylabel() for s in ys)):
                problems.append(f"{name}: no y label")
        for kind, items in (("image", ax.images), ("collection", ax.collections)):
            for i, m in enumerate(items):
                if not _carries_values(m):
                    continue
                if not ax.axison:
                    problems.append(f"{name}: {kind} {i} carries values on an axes drawn without axes")
                elif getattr(m, "colorbar", None) is None and id(m.norm) not in shared_norms:
                    problems.append(f"{name}: {kind} {i} carries values but has no colour bar")
    return problems
