"""Entrotaxis: the entropy of the predicted measurement of a stop, against infotaxis's expected information."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.special import entr

from psgsl_pgm import GridMap
from psgsl_pgm.search import DetectionModel, FreeSpace, Situation, choose, run_closed_loop
from psgsl_pgm.search._entrotaxis import entrotaxis_gain
from psgsl_pgm.sim import Camera

A, B = (10.55, 1.05), (10.55, 4.95)  # the two source hypotheses, far from the robot's candidates


@pytest.fixture(scope="module")
def room():
    occ = np.zeros((60, 120), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    grid = GridMap(occ, 0.1, (0.0, 0.0))
    return grid, FreeSpace(SimpleNamespace(grid=grid, robot_obstacles=occ), Camera())


class _Estimator:
    """A hit model P(hit at x | s) given as a function of the sensor position: ``rows(x) -> (H·W,)``."""

    def __init__(self, rows):
        self.rows = rows
        self.model = object()

    def hit_probability(self, positions):
        return np.stack([self.rows(p) for p in np.asarray(positions)])


def _situation(room, post, rows, *, detection=None, at=(5.05, 3.05)):
    grid, space = room
    beliefs = SimpleNamespace(estimator=_Estimator(rows))
    return Situation(post, beliefs, "olfaction", space, space.snap(at), 0.0, 0.25, 1.0, 1.0, 2.0, 0.5, {},
                     score="gain", detection=detection, far_spacing=None)


def _two_points(grid):
    post = np.zeros(grid.occupancy.shape)
    for xy in (A, B):
        post[tuple(grid.world_to_cell(np.array(xy)))] = 0.5
    return post


def test_entrotaxis_goes_where_the_reading_is_least_predictable_infotaxis_where_it_is_most_informative(room):
    grid, space = room
    post = _two_points(grid)
    a = np.ravel_multi_index(tuple(grid.world_to_cell(np.array(A))), post.shape)

    def rows(x):  # west of x = 5: pure noise, P = ½ whatever the source; east: a hit says "A" (P = 0.8 | A, 0 | B)
        row = np.zeros(post.size)
        if x[0] < 5.0:
            row[:] = 0.5
        else:
            row[a] = 0.8
        return row

    sit = _situation(room, post, rows)
    ent, info = choose("entrotaxis", sit), choose("infotaxis", _situation(room, post, rows))
    # the known answers: H(Z) = ln 2 (its maximum) in the noise, H_b(0.4) = 0.673 east; I(S; Z) = 0 in the noise,
    # H_b(0.4) − ½ H_b(0.8) = 0.423 east
    assert space.position(ent.cell)[0] < 5.0 and space.position(info.cell)[0] >= 5.0
    np.testing.assert_allclose(ent.score, np.log(2))
    np.testing.assert_allclose(info.score, entr(0.4) + entr(0.6) - 0.5 * (entr(0.8) + entr(0.2)))
    cells = space.candidates(sit.cell, 2.0)[0]
    east = space.position(cells)[:, 0] >= 5.0
    np.testing.assert_allclose(entrotaxis_gain(sit, cells)[east], entr(0.4) + entr(0.6))


def test_the_gain_is_the_entropy_of_found_hit_and_miss_under_the_detection_model(room):
    grid, space = room
    rng = np.random.default_rng(3)
    free = ~grid.occupancy
    post = np.where(free, rng.random(free.shape) ** 8, 0.0)
    post /= post.sum()
    table = {}

    def rows(x):  # a fixed random hit model per sensor cell
        key = tuple(np.round(x, 3))
        if key not in table:
            table[key] = rng.random(post.size)
        return table[key]

    det = DetectionModel(grid, 0.5, miss_probability=0.3)
    sit = _situation(room, post, rows, detection=det)
    cells = space.candidates(sit.cell, 2.0)[0]
    gain = entrotaxis_gain(sit, cells)
    p = post.ravel()
    for k, c in enumerate(cells):
        w = np.ones(p.size)
        w[det.cell_rows([c], space.position([c]))[0]] = 0.3  # "not found" keeps m = 0.3 of what the stop finds
        row = rows(space.position(c))
        q = np.array([p @ (1 - w), p @ (w * row), p @ (w * (1 - row))])  # found, hit, miss
        assert abs(q.sum() - 1) < 1e-12
        np.testing.assert_allclose(gain[k], entr(q).sum(), rtol=1e-10)
    assert np.all(gain <= np.log(3))


@pytest.mark.slow  # a house episode with semantics, ~15 s
def test_entrotaxis_runs_in_the_house_with_semantics():
    from psgsl_pgm.search import SearchConfig

    run = run_closed_loop("oven", 0, "entrotaxis", "semantics+rooms", search=SearchConfig(time_budget=40.0))
    assert run.policy == "entrotaxis" and run.n_steps >= 2 and np.isfinite(run.error).all()
