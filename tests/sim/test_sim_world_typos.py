"""Typos in the files a world names are errors with the close names, not a silent loss of evidence."""

import numpy as np
import pytest
import yaml

from psgsl_pgm import load_world
from psgsl_pgm.cli._main import main
from psgsl_pgm.sim import make_world

from .test_sim_worldfile import world_dict, write_house

ROOMS = "number_classes: 81\nroom_categories:\n  {kitchen}: {{oven: 0.2}}\n  LivingRoom: {{microwave: 0.01}}\n"


@pytest.fixture
def flat(tmp_path):
    write_house(tmp_path)
    return tmp_path


def _world(d, rooms_text=None, **over):
    if rooms_text is not None:
        (d / "room_p.yaml").write_text(rooms_text)
        over.setdefault("room_classes", "room_p.yaml")
    (d / "w.yaml").write_text(yaml.safe_dump(world_dict(**over)))
    return d / "w.yaml"


def test_a_misspelt_room_is_an_error_naming_the_close_names(flat, capsys):
    path = _world(flat, ROOMS.format(kitchen="Kitchn"))
    with pytest.raises(ValueError, match=r"w\.yaml: key 'room_classes': p\(o \| room\) is given for a room the room "
                                         r"map rooms\.yaml does not have: 'Kitchn' — did you mean 'Kitchen'\? "
                                         r"\(known: Kitchen, LivingRoom\)"):
        load_world(path)
    assert main(["world", "check", str(path)]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.count("\n") == 1 and "'Kitchn' — did you mean 'Kitchen'?" in cap.err
    # case and spaces are no typo: "kitchen" and "living room" are the map's rooms
    spec = load_world(_world(flat, ROOMS.format(kitchen="kitchen").replace("LivingRoom", "living room")))
    assert spec.summary()["ontology"]["rooms_at_class_prior"] == []


def test_this_projects_room_table_is_checked_too(flat):
    (flat / "onto.yaml").write_text("classes: [oven, microwave]\ngases: {smoke: {oven: 0.7, microwave: 0.3}}\n"
                                    "rooms: {Kitchen: {oven: 0.3}, Livingroom: {oven: 0.01}, Garage: {oven: 0.1}}\n")
    with pytest.raises(ValueError, match=r"key 'ontology': p\(o \| room\) is given for a room the room map "
                                         r"rooms\.yaml does not have: 'Garage' \(known: Kitchen, LivingRoom\)"):
        load_world(_world(flat, ontology="onto.yaml"))


def test_a_room_the_table_omits_keeps_the_class_prior_with_a_warning(flat, capsys):
    path = _world(flat, "number_classes: 81\nroom_categories:\n  Kitchen: {oven: 0.2}\n")
    assert main(["world", "check", str(path)]) == 0
    out = capsys.readouterr().out
    assert ("warning: p(o | room) omits room(s) LivingRoom of the room map: they start at the class prior (no room "
            "evidence)") in out
    assert load_world(path).summary()["ontology"]["rooms_at_class_prior"] == ["LivingRoom"]


def test_world_semantic_map_refuses_a_misspelt_room_name():
    w = make_world(seed=0, warm_up=0.0)
    prior = np.full(len(w.detector.classes), 1 / len(w.detector.classes))
    table = np.tile(prior, (2, 1))
    with pytest.raises(ValueError, match=r"room_names: room the house does not have: 'Kitchn' — did you mean "
                                         r"'Kitchen'\?"):
        w.semantic_map(prior, room_table=table, room_names=["Kitchn", "Bathroom"])
    m = w.semantic_map(prior, room_table=table, room_names=["kitchen", "Bathroom"])  # case is no typo
    assert m.probs.shape[:2] == w.house.shape


def test_a_world_files_semantic_map_with_a_misspelt_class(flat):
    rng = np.random.default_rng(5)
    np.savez(flat / "b.npz", probs=rng.dirichlet(np.ones(3), size=(40, 60)),
             classes=np.array(["ovne", "microwave", "background"]))
    with pytest.raises(ValueError, match=r"w\.yaml: key 'semantic_map': .*b\.npz: array 'classes': class the "
                                         r"ontology does not list: 'ovne' — did you mean 'oven'\?"):
        load_world(_world(flat, semantic_map="b.npz"))
    spec = load_world(_world(flat, semantic_map="b.npz", other_classes="lump"))
    assert spec.class_beliefs.shape == (40, 60, 3)
    with pytest.raises(ValueError, match=r"key 'other_classes' must be 'error' or 'lump', got 'yes'"):
        load_world(_world(flat, semantic_map="b.npz", other_classes="yes"))
    with pytest.raises(ValueError, match=r"key 'other_classes' applies to a 'semantic_map'"):
        load_world(_world(flat, other_classes="lump"))
