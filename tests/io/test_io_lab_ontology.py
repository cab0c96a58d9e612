"""The lab's ontology formats (ontology.yaml with Gases, ObjectProbByRoom.yaml) and the COCO alias table."""

import numpy as np
import pytest

from psgsl_pgm import Ontology, semantic_source_probability
from psgsl_pgm.io._coco import COCO_CLASSES, canonical_class

from tests.sim.house_b import house_b_folder

SHARED = house_b_folder()

LAB = """Gases:
  - gas: smoke
    probs:
      oven: 0.4
      microwave: 0.3
      fridge: 0.1
      other: 0.2
  - gas: sewage
    probs:
      toilet: 0.5
      other: 0.5
"""
ROOMS = """number_classes: 10
room_categories:
  Kitchen:
    oven: 0.2
    bed: 0.1
  Bathroom:
    toilet: 0.3
"""


def test_coco_names_and_aliases():
    assert len(COCO_CLASSES) == 80 == len(set(COCO_CLASSES))
    assert canonical_class("Fridge") == "refrigerator"
    assert canonical_class("tvmonitor") == canonical_class("TV") == "tv"
    assert canonical_class("potted_plant") == "potted plant"
    assert canonical_class("countertop") == "countertop"
    with pytest.raises(TypeError, match="non-empty string"):
        canonical_class("  ")


def test_lab_format_read_as_the_lab_reads_it(tmp_path):
    (tmp_path / "o.yaml").write_text(LAB)
    ont = Ontology.from_yaml(tmp_path / "o.yaml")
    # classes in order of appearance, aliases mapped, the catch-all last
    assert ont.classes == ("oven", "microwave", "refrigerator", "toilet", "other")
    assert ont.gases == ("smoke", "sewage")
    prior = np.full(5, 0.2)  # no room file: uniform over the ontology's classes (the lab's setUpNoRooms)
    np.testing.assert_allclose(ont.class_prior, prior, rtol=1e-12)
    smoke = ont.source_likelihood("smoke")
    np.testing.assert_allclose(smoke[:3], [0.4, 0.3, 0.1], rtol=1e-12)
    # toilet is not listed for smoke: it belongs to smoke's "other" (0.2), split with "other" by the prior
    np.testing.assert_allclose(smoke[3:], [0.1, 0.1], rtol=1e-12)
    sewage = ont.source_likelihood("sewage")
    np.testing.assert_allclose(sewage, [0.125, 0.125, 0.125, 0.5, 0.125], rtol=1e-12)


def test_splitting_other_by_the_prior_gives_the_labs_lumped_semantic_term(tmp_path):
    """p(s | z) with toilet split out of smoke's 'other' equals p(s | z) with toilet lumped into 'other'."""
    (tmp_path / "o.yaml").write_text(LAB)
    ont = Ontology.from_yaml(tmp_path / "o.yaml")
    rng = np.random.default_rng(0)
    beliefs = rng.dirichlet(np.ones(5), size=(6, 7))
    split = semantic_source_probability(beliefs, ont.source_likelihood("smoke"), ont.class_prior)
    lumped_b = np.concatenate([beliefs[..., :3], beliefs[..., 3:].sum(-1, keepdims=True)], axis=-1)
    lumped = semantic_source_probability(lumped_b, [0.4, 0.3, 0.1, 0.2], [0.2, 0.2, 0.2, 0.4])
    np.testing.assert_allclose(split, lumped, rtol=1e-12)


def test_lab_values_are_normalised_by_their_sum(tmp_path):
    (tmp_path / "o.yaml").write_text("Gases:\n  - gas: g\n    probs: {oven: 2, other: 2}\n")
    np.testing.assert_allclose(Ontology.from_yaml(tmp_path / "o.yaml").source_likelihood("g"), [0.5, 0.5],
                               rtol=1e-12)


def test_room_classes_as_the_lab_finalises_rooms(tmp_path):
    (tmp_path / "o.yaml").write_text(LAB)
    (tmp_path / "r.yaml").write_text(ROOMS)
    ont = Ontology.from_yaml(tmp_path / "o.yaml", room_classes=tmp_path / "r.yaml")
    assert ont.rooms == ("Kitchen", "Bathroom")
    # class prior: 1 / number_classes per named class, "other" the rest
    np.testing.assert_allclose(ont.class_prior, [0.1, 0.1, 0.1, 0.1, 0.6], rtol=1e-12)
    kitchen = ont.room_likelihood("Kitchen")
    share = (1 - 0.3) / (10 - 2)  # every class the room does not list
    np.testing.assert_allclose(kitchen, [0.2, share, share, share, 1 - 0.2 - 3 * share], rtol=1e-12)
    bath = ont.room_likelihood("Bathroom")
    share = 0.7 / 9
    np.testing.assert_allclose(bath, [share, share, share, 0.3, 1 - 0.3 - 3 * share], rtol=1e-12)
    # the gas table's bundle now splits by the new prior: toilet gets 0.2 · 0.1 / 0.7 of smoke's "other"
    np.testing.assert_allclose(ont.source_likelihood("smoke")[3], 0.2 * 0.1 / 0.7, rtol=1e-12)


def test_room_classes_with_this_projects_format(tmp_path):
    (tmp_path / "o.yaml").write_text("classes: [oven, toilet]\nclass_prior: {oven: 0.2, toilet: 0.2}\n"
                                     "gases: {smoke: {oven: 1.0}}\n")
    (tmp_path / "r.yaml").write_text(ROOMS)
    ont = Ontology.from_yaml(tmp_path / "o.yaml", room_classes=tmp_path / "r.yaml")
    np.testing.assert_allclose(ont.class_prior, [0.2, 0.2, 0.6], rtol=1e-12)  # the file's own prior is kept
    np.testing.assert_allclose(ont.room_likelihood("Kitchen"), [0.2, 0.7 / 8, 1 - 0.2 - 0.7 / 8], rtol=1e-12)


@pytest.mark.parametrize("text, message", [
    ("Gases:\n  - gas: smoke\n    probs: {oven: x}\n", r"o\.yaml.*'Gases\[0\]\.probs\.oven' must be a number"),
    ("Gases:\n  - gas: smoke\n    prob: {oven: 1}\n", r"o\.yaml: key 'Gases\[0\]': unknown key\(s\) \['prob'\]; allowed keys are \['gas', 'probs'\]"),
    ("Gases:\n  - gas: smoke\n    probs: {oven: 1, stove: 1}\n", r"o\.yaml.*class 'oven' is listed twice"),
    ("Gases:\n  - gas: smoke\n    probs: {oven: -1}\n", r"o\.yaml: field 'Gases\[0\]\.probs\.oven' must be >= 0, got -1"),
    ("Gases: []\n", r"o\.yaml.*'Gases' must be a non-empty list"),
    ("Gases:\n  - {gas: a, probs: {oven: 1}}\nExtra: 1\n", r"o\.yaml.*unknown key\(s\) \['Extra'\]"),
    ("Gases:\n  - {gas: a, probs: {oven: 1}}\n  - {gas: a, probs: {oven: 1}}\n", r"gas 'a' is listed twice"),
])
def test_bad_lab_ontologies_name_the_file_and_key(tmp_path, text, message):
    (tmp_path / "o.yaml").write_text(text)
    with pytest.raises(ValueError, match=message):
        Ontology.from_yaml(tmp_path / "o.yaml")


@pytest.mark.parametrize("text, message", [
    ("room_categories: {K: {oven: 0.2}}\n", r"r\.yaml: missing required key\(s\) \['number_classes'\]"),
    ("number_classes: 10\nroom_categories: {K: {oven: 0.7, toilet: 0.7}}\n", r"r\.yaml.*'room_categories\.K' sums"),
    ("number_classes: 10\nroom_categories: {K: {other: 0.2}}\n", r"r\.yaml.*'room_categories\.K\.other'"),
    ("number_classes: 2\nroom_categories: {K: {oven: 0.2}}\n", r"r\.yaml.*'number_classes' is 2"),
    ("number_classes: 10\nroom_categoris: {}\n", r"r\.yaml: unknown key\(s\) \['room_categoris'\]"),
])
def test_bad_room_classes_name_the_file_and_key(tmp_path, text, message):
    (tmp_path / "o.yaml").write_text(LAB)
    (tmp_path / "r.yaml").write_text(text)
    with pytest.raises(ValueError, match=message):
        Ontology.from_yaml(tmp_path / "o.yaml", room_classes=tmp_path / "r.yaml")


def test_house_ontology_typo_gives_the_ontologys_message(monkeypatch):
    """The house's hand table is read by Ontology.from_dict: a misspelt class is named, not a KeyError."""
    pytest.importorskip("matplotlib", reason="the sim extra is not installed (pip install 'psgsl-pgm[sim]')")
    pytest.importorskip("PIL", reason="the sim extra is not installed (pip install 'psgsl-pgm[sim]')")
    from psgsl_pgm.sim import _house_ontology as mod

    real = mod.load_yaml
    monkeypatch.setattr(mod, "load_yaml",
                        lambda path: {"smoke": {"ovn": 1.0}} if "house_gases" in str(path) else real(path))
    mod._cached.cache_clear()
    try:
        with pytest.raises(ValueError, match=r"house_gases\.yaml: unknown class 'ovn' in gases\.smoke"):
            mod._cached((10_000,), 1.0)
    finally:
        mod._cached.cache_clear()


@pytest.mark.shared_data
def test_the_labs_own_files():
    if not SHARED.is_dir():
        pytest.skip("../shared/data/mapir_house_B is absent")
    ont = Ontology.from_yaml(SHARED / "ontology.yaml", room_classes=SHARED / "ObjectProbByRoom.yaml")
    smoke = ont.source_likelihood("smoke")
    oven, micro = smoke[ont.class_index("oven")], smoke[ont.class_index("microwave")]
    assert oven / micro == pytest.approx(0.4 / 0.3, rel=1e-12)
    assert ont.rooms == ("Kitchen", "Bathroom", "Bedroom")
    assert ont.room_likelihood("Kitchen")[ont.class_index("oven")] == pytest.approx(0.2, rel=1e-12)
    assert ont.class_prior[ont.class_index("oven")] == pytest.approx(1 / 81, rel=1e-12)
    assert ont.gases == ("smoke", "sewage")


def test_duplicate_keys_are_errors_not_last_wins(tmp_path):
    (tmp_path / "o.yaml").write_text("Gases:\n  - gas: smoke\n    probs:\n      oven: 0.4\n      oven: 0.3\n")
    with pytest.raises(ValueError, match=r"o\.yaml: duplicate key 'oven' at line 5 \(first at line 4\)"):
        Ontology.from_yaml(tmp_path / "o.yaml")
    (tmp_path / "o.yaml").write_text(LAB)
    (tmp_path / "r.yaml").write_text("number_classes: 10\nroom_categories:\n  Kitchen: {oven: 0.2}\n"
                                     "  Kitchen: {oven: 0.1}\n")
    with pytest.raises(ValueError, match=r"r\.yaml: duplicate key 'Kitchen'"):
        Ontology.from_yaml(tmp_path / "o.yaml", room_classes=tmp_path / "r.yaml")


def test_a_misspelt_lab_key_is_answered_in_the_labs_keys(tmp_path):
    (tmp_path / "o.yaml").write_text(LAB.replace("Gases:", "Gasses:"))
    with pytest.raises(ValueError, match=r"o\.yaml: expected key 'Gases' \(the lab's layout: .*\), got 'Gasses'") as e:
        Ontology.from_yaml(tmp_path / "o.yaml")
    assert "classes" not in str(e.value)  # not this project's keys
    (tmp_path / "p.yaml").write_text(LAB.replace("Gases:", "GASES:"))
    with pytest.raises(ValueError, match=r"expected key 'Gases'.*got 'GASES'"):
        Ontology.from_yaml(tmp_path / "p.yaml")
    # this project's layout with a typo is still answered in this project's keys
    (tmp_path / "q.yaml").write_text("clases: [oven]\ngases: {smoke: {oven: 1.0}}\n")
    with pytest.raises(ValueError, match=r"unknown ontology keys \['clases'\]; expected some of \['class_prior', "):
        Ontology.from_yaml(tmp_path / "q.yaml")


def test_a_misspelt_class_in_room_classes_is_an_error(tmp_path):
    (tmp_path / "o.yaml").write_text(LAB)
    (tmp_path / "r.yaml").write_text(ROOMS.replace("oven: 0.2", "ovne: 0.2"))
    with pytest.raises(ValueError, match=r"r\.yaml: key 'room_categories\.Kitchen': class neither the ontology nor "
                                         r"COCO names: 'ovne' — did you mean 'oven' or 'orange'\? "
                                         r"\(known: the ontology's oven, microwave, "
                                         r"refrigerator, toilet and the 80 COCO classes\)"):
        Ontology.from_yaml(tmp_path / "o.yaml", room_classes=tmp_path / "r.yaml")
    # COCO names the ontology lacks (bed) and aliases (fridge) are the lab's classes, not typos
    (tmp_path / "s.yaml").write_text(ROOMS.replace("oven: 0.2", "fridge: 0.2"))
    ont = Ontology.from_yaml(tmp_path / "o.yaml", room_classes=tmp_path / "s.yaml")
    assert ont.room_likelihood("Kitchen")[ont.class_index("refrigerator")] == pytest.approx(0.2, rel=1e-12)
