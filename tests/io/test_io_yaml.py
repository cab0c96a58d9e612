"""The project's one safe YAML reader (psgsl_pgm.io._yaml) and the loaders that use it."""

import codecs
import functools

import numpy as np
import pytest

from psgsl_pgm import Ontology
from psgsl_pgm.io._yaml import MAX_INT_DIGITS, load_yaml, load_yaml_mapping, load_yaml_text
from psgsl_pgm.sim import GridMap, load_objects, load_ros_map, load_room_map


def test_plain_documents_read_as_safe_load_does():
    text = "a: 1\nb: [2.5, x, null, true]\nc: {d: -3}\n"
    assert load_yaml_text(text) == {"a": 1, "b": [2.5, "x", None, True], "c": {"d": -3}}
    assert load_yaml_text("") is None


@pytest.mark.parametrize(
    "text, key, lines",
    [
        ("a: 1\nb: 2\na: 3\n", "'a'", (3, 1)),
        ("top:\n  x: 1\n  y: 2\n  x: 3\n", "'x'", (4, 2)),
        ("1: a\n1.0: b\n", "1.0", (2, 1)),  # equal in Python: the second would overwrite the first
        ("- {k: 1, k: 2}\n", "'k'", (1, 1)),
    ],
)
def test_duplicate_keys_are_refused_naming_source_key_and_lines(text, key, lines):
    with pytest.raises(ValueError) as err:
        load_yaml_text(text, source="f.yaml")
    msg = str(err.value)
    assert msg.startswith("f.yaml: duplicate key " + key)
    assert f"at line {lines[0]} (first at line {lines[1]})" in msg


def test_merge_keys_may_still_be_overridden():
    assert load_yaml_text("b: &b {x: 1, y: 2}\nc:\n  <<: *b\n  x: 5\n")["c"] == {"x": 5, "y": 2}


def test_integers_too_large_for_a_float_are_refused_at_load_time():
    limit = float(np.finfo(np.float64).max)
    assert load_yaml_text(f"n: {int(limit)}")["n"] == int(limit)  # the largest float's integer still reads
    for text in (f"n: {int(limit) * 2}", "n: " + "9" * (MAX_INT_DIGITS + 1), "n: -" + "9" * 5000):
        with pytest.raises(ValueError, match=r"^g\.yaml: integer .* at line 1 is too large"):
            load_yaml_text(text, source="g.yaml")


def test_malformed_yaml_is_one_line_naming_source_and_position():
    for text, where in (("a: [1\n", "line 2"), ("a: b: c\n", "line 1"), ("a: 1\n---\nb: 2\n", "line 2")):
        with pytest.raises(ValueError) as err:
            load_yaml_text(text, source="h.yaml")
        assert str(err.value).startswith("h.yaml: not valid YAML") and where in str(err.value)
        assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match="h.yaml: nested deeper than 100 levels at line 1"):
        load_yaml_text("[" * 50_000, source="h.yaml")
    assert load_yaml_text("a: " + "[" * 99 + "]" * 99) == {"a": functools.reduce(lambda x, _: [x], range(98), [])}
    with pytest.raises(ValueError, match="h.yaml: not valid YAML: could not determine a constructor"):
        load_yaml_text("x: !!python/object/apply:os.system [ls]", source="h.yaml")
    with pytest.raises(TypeError, match="YAML text must be a str, got bytes"):
        load_yaml_text(b"a: 1")


def test_files_encodings_directories_and_missing_files(tmp_path):
    p = tmp_path / "o.yaml"
    for data in ("a: é\n".encode(), codecs.BOM_UTF8 + "a: é\n".encode(), "a: é\n".encode("utf-16")):
        p.write_bytes(data)
        assert load_yaml(p) == {"a": "é"}
    p.write_bytes("a: é\n".encode("latin-1"))
    with pytest.raises(ValueError, match=r"o\.yaml: not UTF-8 text: byte 0xe9 at offset 3 \(line 1\)"):
        load_yaml(p)
    with pytest.raises(ValueError, match="is a directory"):
        load_yaml(tmp_path)
    with pytest.raises(FileNotFoundError, match=r"none\.yaml: no such file"):
        load_yaml(tmp_path / "none.yaml")
    with pytest.raises(TypeError, match="path must be a file path"):
        load_yaml(None)
    p.write_text("- 1\n- 2\n")
    with pytest.raises(ValueError, match=r"o\.yaml: expected a YAML mapping at the top level, got list"):
        load_yaml_mapping(p)


def test_every_yaml_loader_refuses_duplicate_keys_and_huge_integers(tmp_path):
    """Ontology.from_yaml and the map / room / object loaders all read through the one safe loader."""
    grid = GridMap(np.zeros((4, 5), bool), 0.5, (0.0, 0.0))
    cases = {
        "ontology": ("classes: [a]\ngases: {g: {a: 1.0}}\nclasses: [b]\n", Ontology.from_yaml),
        "ros": ("image: m.pgm\nresolution: 0.1\nresolution: 0.2\n", load_ros_map),
        "rooms": ("image: s.pgm\nrooms: {1: A}\nrooms: {2: B}\n", lambda p: load_room_map(p, like=grid)),
        "objects": ("objects: []\nname: x\nobjects: []\n", load_objects),
    }
    for name, (text, loader) in cases.items():
        path = tmp_path / f"{name}.yaml"
        path.write_text(text)
        with pytest.raises(ValueError, match=rf"{name}\.yaml: duplicate key .* at line 3 \(first at line [12]\)"):
            loader(path)
    path = tmp_path / "big.yaml"
    path.write_text("classes: [a]\ngases: {g: {a: " + "1" * 400 + "}}\n")
    with pytest.raises(ValueError, match=r"big\.yaml: integer .* at line 2 is too large"):
        Ontology.from_yaml(path)
