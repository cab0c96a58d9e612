"""Run keys (psgsl_pgm.runs._key): every file a world names is listed and hashed, the world's settings by content,
and differences named with both values."""

from __future__ import annotations

import shutil
import sys
from importlib.util import find_spec
from pathlib import Path

import pytest
import yaml

from psgsl_pgm import load_world
from psgsl_pgm.runs._key import digest, file_sha256, key_differences, run_key, world_key
from psgsl_pgm.experiment import ExperimentConfig
from psgsl_pgm.sim._worldfile import world_files

from ..core.key_worlds import one_byte_edit, sha, write_full_world

#: The world files of these tests are written with the simulator's writers (map images, objects: the sim extra).
needs_sim = pytest.mark.skipif(any(find_spec(m) is None for m in ("PIL", "matplotlib")),
                               reason="the sim extra is not installed (pip install 'psgsl-pgm[sim]')")

_OPENED: list = []
_RECORDING = [False]


def _audit(event, args):
    if _RECORDING[0] and event == "open" and isinstance(args[0], (str, bytes, Path)):
        _OPENED.append(Path(args[0] if not isinstance(args[0], bytes) else args[0].decode()))


sys.addaudithook(_audit)  # audit hooks cannot be removed: it records only while _RECORDING is set


@pytest.fixture
def full(tmp_path):
    return write_full_world(tmp_path)


@needs_sim
def test_world_files_lists_every_file_the_loader_opens(full):
    """The list is what the test wrote — and, independently, every file load_world opens (Python's audit hook
    sees each open) is either the world file or in the list."""
    world, files = full
    assert world_files(world) == files
    _OPENED.clear()
    _RECORDING[0] = True
    try:
        load_world(world)
    finally:
        _RECORDING[0] = False
    folder = world.parent.resolve()
    opened = {p.resolve() for p in _OPENED if p.resolve().parent == folder}
    assert opened == {world.resolve(), *(p.resolve() for p in files.values())}


@needs_sim
def test_world_files_of_the_segmented_room_layout_and_a_single_csv(tmp_path):
    world, files = write_full_world(tmp_path, beliefs=False)
    (tmp_path / "rooms.yaml").write_text(yaml.safe_dump({"image": "Kitchen.pgm", "rooms": {255: "Kitchen"}}))
    data = yaml.safe_load(world.read_text())
    data["wind"]["gaden_csv"] = "wind_0.csv"
    data["ontology"], data["source_region"] = "ontology.yaml", "free"
    world.write_text(yaml.safe_dump(data))
    assert world_files(world) == {"map": files["map"], "map/image": files["map/image"], "rooms": files["rooms"],
                                  "rooms/image": tmp_path / "Kitchen.pgm", "objects": files["objects"],
                                  "ontology": files["ontology"], "room_classes": files["room_classes"],
                                  "wind.gaden_csv": files["wind.gaden_csv[0]"]}


@needs_sim
def test_world_key_hashes_every_file_and_one_byte_changes_it(full):
    world, files = full
    key = world_key(world)
    for label, path in files.items():
        assert key[f"world.{label}"] == f"sha256 {sha(path)}"
    for label, path in files.items():
        old = one_byte_edit(path)
        edited = world_key(world)
        assert [k for k in key if key[k] != edited[k]] == [f"world.{label}"], label
        path.write_bytes(old)
    assert world_key(world) == key


@needs_sim
def test_the_world_enters_by_content_not_by_path_layout_or_comments(full, tmp_path):
    world, _ = full
    copy = tmp_path / "elsewhere"
    shutil.copytree(world.parent, copy)
    assert world_key(copy / "world.yaml") == world_key(world)  # a copied world is the same world
    data = yaml.safe_load(world.read_text())
    data["wind"]["height"] = 1  # an int where the file had 0.5 ... and reordered keys, a comment
    text = "# my flat\n" + yaml.safe_dump(dict(reversed(list(data.items()))))
    (copy / "world.yaml").write_text(text)
    diff = key_differences(world_key(world), world_key(copy / "world.yaml"))
    assert diff == ["world.wind.height: 0.5 → 1"]
    data["wind"]["height"] = 0.5
    (copy / "world.yaml").write_text("# my flat\n" + yaml.safe_dump(dict(reversed(list(data.items())))))
    assert world_key(copy / "world.yaml") == world_key(world)
    (copy / "world.yaml").write_text(text.replace("height: 1", "height: 1.0"))
    assert world_key(copy / "world.yaml")["world.wind.height"] == 1  # 1 and 1.0 are one number


@needs_sim
def test_key_differences_name_each_setting_with_both_values(full):
    world, files = full
    a = run_key("experiment", world_key(world), experiment=ExperimentConfig())
    data = yaml.safe_load(world.read_text())
    del data["objects"]
    data["sources"] = {"corner": [4.2, 0.6]}
    world.write_text(yaml.safe_dump(data))
    b = run_key("experiment", world_key(world), experiment=ExperimentConfig(stops=20, speed=0.5))
    h = sha(files["objects"])
    assert key_differences(a, b) == [
        "experiment.speed: 0.25 → 0.5", "experiment.stops: null → 20",
        f"world.objects: sha256 {h[:12]}… → (none)", "world.sources.stove: oven → (none)"]
    assert key_differences(a, a) == [] and digest(a) != digest(b)
    assert key_differences({"x": [1.5, 1.5]}, {"x": [1.5, 1.4]}) == ["x: [1.5, 1.5] → [1.5, 1.4]"]


def test_file_sha256_of_a_missing_file(tmp_path):
    assert file_sha256(tmp_path / "nothing") == "missing file"
    (tmp_path / "f").write_bytes(b"abc")
    assert file_sha256(tmp_path / "f") == "sha256 ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"


def test_the_embedded_house_has_a_key_with_its_settings():
    key = world_key(None)
    assert key["world.builtin"] == "default_house" and key["world.wind.speed"] == 0.2
    assert not any(v.startswith("sha256") for v in key.values() if isinstance(v, str))  # it names no file


def test_file_hash_reads_the_whole_file(tmp_path):
    """Two files equal in their first MiB and different after it hash differently; the hash is the whole file's."""
    import hashlib

    head = bytes(range(256)) * 4096  # exactly 1 MiB
    a, b = tmp_path / "a.bin", tmp_path / "b.bin"
    a.write_bytes(head + b"tail one")
    b.write_bytes(head + b"tail two")
    assert file_sha256(a) != file_sha256(b)
    assert file_sha256(a) == "sha256 " + hashlib.sha256(a.read_bytes()).hexdigest()
