"""The declaration rule and its scoring, checked against the rule written out cell by cell."""

import numpy as np
import pytest

from psgsl_pgm.search import SearchConfig, run_closed_loop
from psgsl_pgm.search._declare import declaration_error, declared_region, propose_declaration
from psgsl_pgm.search._detection import DetectionModel
from psgsl_pgm.search._grid import summarize_runs
from psgsl_pgm.search._metrics import declaration_summary
from psgsl_pgm.search._store import load_search_run, save_search_run


@pytest.fixture(scope="module")
def detection(house_space):
    house, _ = house_space
    return DetectionModel.from_house(house, 0.5)


def _region_by_hand(detection, cell, radius):
    """D(c): every cell whose centre is within radius of a centre of R(c), one cell at a time."""
    pts = detection.centres[detection.region_mask(cell).ravel()]
    d = np.sqrt(((detection.centres[:, None, :] - pts[None, :, :]) ** 2).sum(-1)).min(axis=1)
    return (d <= radius + 1e-9).reshape(detection.shape)


@pytest.mark.parametrize("radius", [0.0, 0.3, 0.5])
def test_the_declared_region_is_the_found_region_widened_cell_by_cell(detection, house_space, radius):
    house, _ = house_space
    oven = next(o for o in house.objects if o.class_name == "oven")
    object_cell = int(np.flatnonzero(detection.owner == house.objects.index(oven))[0])
    floor_cell = int(np.flatnonzero(detection.owner < 0)[5000])
    for cell in (object_cell, floor_cell):
        np.testing.assert_array_equal(declared_region(detection, cell, radius),
                                      _region_by_hand(detection, cell, radius))
    # an object's region holds its whole footprint; a floor cell's a disc
    assert declared_region(detection, object_cell, 0.0).sum() == (detection.owner == detection.owner[object_cell]).sum()
    assert declared_region(detection, floor_cell, 0.0).sum() == 1


def test_the_proposal_is_the_map_cell_and_the_mass_of_its_declared_region(detection, house_space):
    rng = np.random.default_rng(0)
    post = rng.random(detection.shape) ** 8
    post /= post.sum()
    prop = propose_declaration(post, detection, radius=0.5)
    c = int(np.argmax(post))
    assert prop.cell == c
    np.testing.assert_array_equal(prop.xy, detection.centres[c])
    assert prop.mass == pytest.approx(float(post[_region_by_hand(detection, c, 0.5)].sum()), rel=1e-12)


def test_the_error_is_to_the_footprint_for_an_object_and_to_the_point_otherwise():
    footprint = np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.0]])
    assert declaration_error([0.2, 1.0], [0.1, 0.0], footprint) == pytest.approx(1.0)  # the nearest footprint point
    assert declaration_error([0.2, 1.0], [0.1, 0.0]) == pytest.approx(np.hypot(0.1, 1.0))


def test_found_here_keeps_exactly_the_hypotheses_first_within_reach_of_the_last_point(detection):
    path = np.array([[1.0, 6.0], [1.3, 6.0], [1.6, 6.0], [1.9, 6.0]])
    ll = detection.found_log_likelihood(path)
    last = detection.rows(path[-1:]).toarray()[0]
    earlier = detection.rows(path[:-1]).toarray().any(axis=0)
    np.testing.assert_array_equal(np.isfinite(ll), last & ~earlier)
    assert set(np.unique(ll[np.isfinite(ll)])) == {0.0}
    np.testing.assert_array_equal(np.isfinite(detection.found_log_likelihood(path[-1:])), last)


def test_a_wrong_declaration_ends_the_run_as_a_failure(house_space):
    _, space = house_space
    # a robot that declares on 1 % of the mass names a cell far from the bed, long before it gets there
    run = run_closed_loop("bed", 0, "infotaxis", "olfaction", search=SearchConfig(time_budget=200.0, declare_mass=0.01),
                          space=space)
    assert run.declared and not run.declared_correct and run.time_to_declare == run.time[-1]
    assert run.declared_error > 1.0 and run.false_declaration and not run.succeeded
    assert run.time_to_success == 200.0  # censored at the budget: no right declaration ever came
    s = summarize_runs([run])
    assert s["declared_success"]["value"] == 0.0 and s["false_declaration_rate"]["value"] == 1.0
    assert s["success_rate"]["value"] == 0.0 and s["rmst"]["value"] == pytest.approx(200.0)


def test_success_is_a_declaration_within_the_success_radius(house_space):
    _, space = house_space
    kw = dict(space=space)
    run = run_closed_loop("bed", 0, "infotaxis", "olfaction", search=SearchConfig(time_budget=200.0, declare_mass=0.01),
                          **kw)
    e = run.declared_error
    at = run_closed_loop("bed", 0, "infotaxis", "olfaction",
                         search=SearchConfig(time_budget=200.0, declare_mass=0.01, success_radius=e), **kw)
    below = run_closed_loop("bed", 0, "infotaxis", "olfaction",
                            search=SearchConfig(time_budget=200.0, declare_mass=0.01,
                                                success_radius=float(np.nextafter(e, 0))), **kw)
    assert at.declared_correct and at.succeeded and not below.declared_correct


def test_declarations_round_trip_through_the_run_file_and_old_files_read_as_undeclared(house_space, tmp_path):
    _, space = house_space
    run = run_closed_loop("bed", 0, "infotaxis", "olfaction", search=SearchConfig(time_budget=200.0, declare_mass=0.01),
                          space=space)
    back = load_search_run(save_search_run(run, tmp_path / "r.npz"))
    for k in ("declared", "time_to_declare", "declared_error", "declared_correct", "declared_mass"):
        assert getattr(back, k) == getattr(run, k)
    np.testing.assert_array_equal(back.declared_xy, run.declared_xy)
    with np.load(tmp_path / "r.npz") as z:  # a run stored before declarations: none of their keys
        old = {k: z[k] for k in z.files if not k.startswith("declared") and k != "time_to_declare"}
    np.savez(tmp_path / "old.npz", **old)
    o = load_search_run(tmp_path / "old.npz")
    assert not o.declared and np.isnan(o.time_to_declare)


def test_declaration_summary_counts_by_hand():
    s = declaration_summary([True, True, True, False], [True, True, False, False], [0.1, 0.3, 2.5, np.nan])
    assert s["declared"] == 3
    assert s["declared_success"]["value"] == 0.5
    assert s["false_declaration_rate"]["value"] == pytest.approx(1 / 3)
    assert s["declared_error"]["median"] == pytest.approx(0.3)
    assert s["declared_error"]["q90"] == pytest.approx(np.quantile([0.1, 0.3, 2.5], 0.9))
    lo, hi = s["false_declaration_rate"]["ci95"]
    assert 0 < lo < 1 / 3 < hi < 1
    none = declaration_summary([False, False], [False, False], [np.nan, np.nan])
    assert none["declared_error"] is None and none["false_declaration_rate"] is None
    assert none["declared_success"]["ci95"][1] > 0  # never a degenerate interval
