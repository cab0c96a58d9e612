"""Field of view and φ_O; the ontology's YAML round trip, name look-ups and the Dirichlet estimate."""

import numpy as np
import pytest

from psgsl_pgm import Ontology, field_of_view, kitchen_ontology, view_information_gain


def room_with_pillar():
    occ = np.zeros((21, 21), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[9:12, 14] = True  # a pillar east of the centre
    return occ


def test_fov_sees_walls_but_never_behind_them():
    occ = room_with_pillar()
    seen = field_of_view(occ, (10.5, 10.5, 0.0), max_range=30, half_angle=np.pi)
    assert seen[10, 14] and not seen[10, 15:20].any()  # the pillar hides its shadow
    assert not seen[10, 20]  # nor the wall behind the pillar
    assert seen[0, 10] and seen[20, 10]  # outer walls are surfaces: seen
    # every visible free cell has a clear straight line: brute-force check along a fine ray
    for r, c in zip(*np.nonzero(seen & ~occ)):
        t = np.linspace(0, 1, 400)[:-1]
        rr = np.floor(10.5 + t * (r + 0.5 - 10.5)).astype(int)
        cc = np.floor(10.5 + t * (c + 0.5 - 10.5)).astype(int)
        assert not occ[rr, cc].any(), (r, c)


def test_fov_respects_range_and_angle():
    occ = np.zeros((41, 41), bool)
    seen = field_of_view(occ, (20.5, 20.5, np.pi / 2), max_range=10, half_angle=np.pi / 6, min_range=2)
    rows, cols = np.nonzero(seen)
    dx, dy = cols + 0.5 - 20.5, rows + 0.5 - 20.5
    dist = np.hypot(dx, dy)
    assert np.all((dist >= 2) & (dist <= 10))
    assert np.all(np.abs(np.arctan2(dx, dy)) <= np.pi / 6 + 1e-12)  # heading +y: angle from the +row axis
    assert seen[30, 20] and not seen[10, 20]
    # metres: same geometry at 0.1 m cells with an origin offset
    metric = field_of_view(occ, (20.5 * 0.1 - 3, 20.5 * 0.1 + 1, np.pi / 2), max_range=1.0, half_angle=np.pi / 6,
                           min_range=0.2, resolution=0.1, origin=(-3, 1))
    np.testing.assert_array_equal(metric, seen)


def test_view_information_gain_sums_over_the_visible_cells():
    occ = room_with_pillar()
    gain = np.random.default_rng(0).random(occ.shape)
    pose = (10.5, 10.5, 0.3)
    fov = dict(max_range=8, half_angle=0.8)
    seen = field_of_view(occ, pose, **fov)
    assert view_information_gain(gain, occ, pose, **fov) == pytest.approx(gain[seen].sum(), rel=1e-15)
    many = view_information_gain(gain, occ, [pose, (5.5, 5.5, 2.0)], **fov)
    assert many.shape == (2,) and many[0] == pytest.approx(gain[seen].sum(), rel=1e-15)


def test_kitchen_ontology_is_the_papers_table():
    ont = kitchen_ontology()
    assert ont.classes == ("oven", "microwave", "refrigerator", "countertop", "other")
    np.testing.assert_array_equal(ont.source_likelihood("smoke"), [0.4, 0.25, 0.3, 0.05, 0.0])
    np.testing.assert_allclose(ont.class_prior, 0.2)


def test_yaml_round_trip_and_partial_rows(tmp_path):
    ont = Ontology.from_dict({
        "classes": ["oven", "sink", "toilet"],
        "class_prior": {"oven": 0.1, "sink": 0.1},  # toilet and other share the remaining 0.8 equally
        "gases": {"smoke": {"oven": 0.9}, "sewage": {"sink": 0.5, "toilet": 0.5}},
        "rooms": {"kitchen": {"oven": 0.3, "sink": 0.2}},
    })
    np.testing.assert_allclose(ont.class_prior, [0.1, 0.1, 0.4, 0.4])
    np.testing.assert_allclose(ont.source_likelihood("smoke"), [0.9, 0.1 * 0.1 / 0.9, 0.1 * 0.4 / 0.9, 0.1 * 0.4 / 0.9])
    np.testing.assert_allclose(ont.room_likelihood("kitchen"), [0.3, 0.2, 0.25, 0.25])
    assert ont.source_likelihood(["sewage", "smoke"]).shape == (2, 4)
    path = tmp_path / "o.yaml"
    ont.to_yaml(path)
    assert Ontology.from_yaml(path) == ont
    np.testing.assert_allclose(ont.marginal_class_prior(10, "smoke"), 0.1 * ont.source_likelihood("smoke") + 0.9 * ont.class_prior)


def test_from_counts_is_the_dirichlet_posterior_mean():
    ont = Ontology.from_counts({"smoke": {"oven": 7, "toaster": 2}}, classes=["oven", "toaster", "sink"], concentration=0.5)
    np.testing.assert_allclose(ont.source_likelihood("smoke"), np.array([7.5, 2.5, 0.5, 0.5]) / 11.0)
    mle = Ontology.from_counts({"smoke": {"oven": 3, "toaster": 1}}, classes=["oven", "toaster"], concentration=0)
    np.testing.assert_allclose(mle.source_likelihood("smoke"), [0.75, 0.25, 0.0])
    with pytest.raises(ValueError, match="non-negative whole number"):
        Ontology.from_counts({"smoke": {"oven": 1.5}}, classes=["oven"])


@pytest.mark.shared_data
def test_reads_the_labs_room_table_as_partial_rows():
    """The lab's ObjectProbByRoom.yaml lists a few classes per room; read as partial p(o | room) rows."""
    import yaml
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "mapir_house_B" / "ObjectProbByRoom.yaml"
    if not path.exists():
        pytest.skip("../shared/data is absent")
    rooms = yaml.safe_load(path.read_text())["room_categories"]
    classes = sorted({c for row in rooms.values() for c in row})
    ont = Ontology.from_dict({"classes": classes, "gases": {"smoke": {"oven": 1.0}}, "rooms": rooms})
    assert ont.rooms == ("Kitchen", "Bathroom", "Bedroom")
    assert ont.room_likelihood("Kitchen")[ont.class_index("oven")] == pytest.approx(0.2)


def test_off_ontology_likelihood_mixes_in_the_background_and_refuses_a_bad_rate():
    ont = kitchen_ontology()
    plain = ont.source_likelihood("smoke")
    assert np.array_equal(ont.source_likelihood("smoke", off_ontology=0), plain)  # ε = 0: the same bits
    mixed = ont.source_likelihood(off_ontology=0.25)  # every gas, (m, k)
    np.testing.assert_allclose(mixed, 0.75 * ont.source_table + 0.25 * ont.class_prior, rtol=1e-15)
    np.testing.assert_allclose(mixed.sum(axis=1), 1.0, rtol=1e-15)
    np.testing.assert_array_equal(ont.source_likelihood(["smoke"], off_ontology=1.0), ont.class_prior[None])
    for bad in (-0.1, 1.5, float("nan"), float("inf")):
        with pytest.raises(ValueError, match=r"off_ontology must"):
            ont.source_likelihood("smoke", off_ontology=bad)
    for bad in (True, "0.1", 0.1j, None):
        with pytest.raises(TypeError, match="off_ontology"):
            ont.source_likelihood("smoke", off_ontology=bad)
