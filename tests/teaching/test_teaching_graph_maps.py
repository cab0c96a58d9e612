"""draw_network / network_layout and plot_cell_map."""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, build_network_b
from psgsl_pgm.sim import default_house
from psgsl_pgm.teaching import draw_network, plot_cell_map
from psgsl_pgm.networks._draw import network_layout


def _problem(m=1):
    return SemanticGSLProblem.random(np.random.default_rng(3), 4, 3, m, max_observations=2)


@pytest.mark.parametrize("build", [build_network_a, lambda p: build_network_b(p, "chain"),
                                   lambda p: build_network_b(p, "table")], ids=["A", "B-chain", "B-table"])
@pytest.mark.parametrize("m", [1, 2])
def test_layout_places_every_node_by_kind(build, m):
    problem = _problem(m)
    model = build(problem)
    pos = network_layout(model)
    assert set(pos) == set(model.nodes())
    assert len(set(pos.values())) == len(pos)  # no two nodes on top of each other
    for i, cell in enumerate(problem.cell_names):
        assert pos[f"O_{cell}"] == (float(i), -1.0)  # one column per cell, objects in one row
        for j in range(problem.observations_of(i).shape[0]):
            assert pos[f"Z_{cell}_{j}"][1] < -1.0  # observations below their object
    sources = [v for v in model.nodes() if v == "S" or v.startswith("S_")]
    assert all(pos[s][1] == 0.0 for s in sources)


def test_draw_network_draws_every_node_and_edge():
    model = build_network_b(_problem(2))
    ax = draw_network(model, title="B")
    offsets = [c.get_offsets() for c in ax.collections if len(c.get_offsets()) > 1]
    assert sum(len(o) for o in offsets) == model.number_of_nodes()
    assert ax.get_title() == "B"
    arrows = [p for p in ax.patches]
    assert len(arrows) == model.number_of_edges()


def test_layout_refuses_foreign_node_names():
    class Fake:
        def nodes(self):
            return ["O_c0", "weird"]

    with pytest.raises(ValueError, match="weird"):
        network_layout(Fake())


def test_plot_cell_map_on_the_house_and_errors():
    house = default_house(seed=0)
    values = np.random.default_rng(0).random(house.shape)
    values[0, 0] = 0.0
    ax = plot_cell_map(values, house=house, log=True, title="p")
    image = ax.images[0]
    assert image.get_extent() == list(house.grid.extent)
    assert np.ma.getmaskarray(image.get_array())[0, 0]  # zero hidden on a log scale
    assert len(ax.images) == 2  # values + walls
    with pytest.raises(ValueError, match="house's shape"):
        plot_cell_map(values[:-1], house=house)
    with pytest.raises(ValueError, match=r"\(H, W\)"):
        plot_cell_map(np.ones(5))
