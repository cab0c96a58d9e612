"""Every figure of psgsl_pgm.teaching, psgsl_pgm.sim and the experiment has labelled axes and its colour bars.

The rules are :func:`psgsl_pgm.teaching.figure_problems` (tested first on figures built to break them); the
notebooks' figures are held to the same rules by ``tests/test_notebooks.py``.
"""

from __future__ import annotations

from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np
import pytest

from psgsl_pgm.experiment import plot_error_chart, plot_progression, plot_room_types
from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, build_network_b
from psgsl_pgm.sim import default_house, plot_house, potential_flow
from psgsl_pgm.teaching import draw_network, figure_problems, map_norm, plot_cell_map


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def house():
    return default_house(seed=0)


# ------------------------------------------------------------------------------------------ the rules
def test_unlabelled_axes_and_a_bare_value_image_are_problems():
    fig, ax = plt.subplots()
    ax.imshow(np.arange(6.0).reshape(2, 3))
    assert figure_problems(fig) == ["axes 0 (untitled): no x label", "axes 0 (untitled): no y label",
                                    "axes 0 (untitled): image 0 carries values but has no colour bar"]


def test_a_scatter_coloured_by_value_needs_a_colour_bar_with_a_label():
    fig, ax = plt.subplots()
    ax.set(xlabel="x [m]", ylabel="y [m]")
    sc = ax.scatter([0, 1, 2], [0, 1, 0], c=[0.1, 0.5, 0.9])
    assert figure_problems(fig) == ["axes 0 (untitled): collection 0 carries values but has no colour bar"]
    fig.colorbar(sc, ax=ax)
    assert figure_problems(fig) == ["colour bar of <colorbar>: no label"]


def test_masks_categories_and_shared_scales_are_fine():
    fig, axes = plt.subplots(1, 2, sharey=True)
    norm = map_norm([0.0, 1.0])
    first = axes[0].imshow([[0.0, 1.0]], norm=norm)
    axes[1].imshow([[0.5, 0.2]], norm=norm)  # same scale: the one bar serves both panels
    axes[1].imshow(np.ma.masked_equal([[1, 0]], 0), cmap="autumn")  # a one-valued mask
    axes[1].imshow([[0, 3]], cmap="tab20")  # categories (classes, rooms) are named by text, not a bar
    fig.colorbar(first, ax=list(axes), label="p")
    for ax in axes:
        ax.set_xlabel("x [m]")
    axes[0].set_ylabel("y [m]")  # shared with axes[1]
    assert figure_problems(fig) == []
    axes[1].imshow([[0.5, 0.2]])  # its own, different scale and no bar
    assert figure_problems(fig) == ["axes 1 (untitled): image 3 carries values but has no colour bar"]


def test_a_value_image_on_an_axes_without_axes_is_a_problem():
    fig, ax = plt.subplots()
    fig.colorbar(ax.imshow([[0.0, 1.0]]), ax=ax, label="v")
    ax.set_axis_off()
    assert figure_problems(fig) == ["axes 0 (untitled): image 0 carries values on an axes drawn without axes"]


# ------------------------------------------------------------------------------- the package's figures
def test_cell_maps_with_and_without_a_house(house):
    values = np.random.default_rng(0).random(house.shape)
    for kwargs in ({"house": house}, {"house": house, "log": True}, {}):
        ax = plot_cell_map(values, label="p", **kwargs)
        assert figure_problems(ax.figure) == [], kwargs
    ax = plot_cell_map(values, house=house)
    assert ax.get_xlabel() == "x [m]" and ax.images[0].colorbar.ax.get_ylabel() == "value per cell"


def test_plot_house_with_gas_and_wind(house):
    conc = np.where(house.grid.free, np.random.default_rng(1).random(house.shape), 0.0)
    ax = plot_house(house, wind=potential_flow(house.grid, house.inlet, house.outlet), concentration=conc,
                    source=(7.7, 0.5))
    assert figure_problems(ax.figure) == []
    assert ax.images[2].colorbar.ax.get_ylabel() == "gas concentration [ppm]"


@pytest.mark.parametrize("build", [build_network_a, build_network_b, lambda p: build_network_b(p, "table")],
                         ids=["A", "B-chain", "B-table"])
def test_network_drawings(build):
    problem = SemanticGSLProblem.random(np.random.default_rng(3), 3, 3, 2, max_observations=2)
    ax = draw_network(build(problem))
    assert figure_problems(ax.figure) == [] and ax.get_legend() is not None


def _fake_run(house, n_steps=8, seed=0):
    """A run with the attributes the figures read; posteriors concentrating on one cell over the steps."""
    rng = np.random.default_rng(seed)
    free = house.grid.free
    flat = free / free.sum()
    peak = np.zeros(house.shape)
    peak[10, 80] = 1.0
    snapshots = {s: np.stack([(1 - w) * flat + w * peak for w in (s / n_steps * 0.5, s / n_steps * 0.9,
                                                                     s / n_steps * 0.99)])
                 for s in (0, n_steps // 2, n_steps)}
    error = np.abs(rng.normal(2.0, 1.0, (n_steps + 1, 3)))
    return SimpleNamespace(snapshots=snapshots, n_steps=n_steps, position=rng.uniform(1, 5, (n_steps + 1, 2)),
                           source_xy=np.array([8.0, 1.0]), error=error, spread=error / 2,
                           time=np.arange(n_steps + 1) * 6.0, seed=seed)


def test_experiment_figures(house):
    run = _fake_run(house)
    tour = SimpleNamespace(path=np.column_stack([np.linspace(1, 5, 20), np.full(20, 3.0)]),
                           path_index=np.arange(0, 20, 2))
    fig = plot_progression(run, house, tour, variants=("olfaction", "semantics", "semantics+rooms"), scale="row")
    assert figure_problems(fig) == []
    for row in np.asarray(fig.axes[:9]).reshape(3, 3):  # one colour scale per row, shared by its panels
        assert len({id(ax.images[0].norm) for ax in row}) == 1
    assert len({id(ax.images[0].norm) for ax in fig.axes[:9]}) == 3
    bars = [ax for ax in fig.axes[9:]]
    assert len(bars) == 3 and all("log" in b.get_ylabel() for b in bars)
    fig = plot_progression(run, house, tour, variants=("olfaction", "semantics", "semantics+rooms"))
    assert figure_problems(fig) == []
    assert len({id(ax.images[0].norm) for ax in fig.axes[:9]}) == 1  # rows are compared: one scale for all
    assert len(fig.axes) == 10 and "log" in fig.axes[9].get_ylabel()  # and one colour bar
    with pytest.raises(ValueError, match="scale"):
        plot_progression(run, house, tour, scale="column")
    fig = plot_room_types(run.snapshots[0][1], run.snapshots[0][2], house, source=run.source_xy)
    assert figure_problems(fig) == []
    assert fig.axes[0].images[0].norm is fig.axes[1].images[0].norm  # (A) and (B) on one scale
    assert figure_problems(plot_error_chart([run, _fake_run(house, seed=1)])) == []
