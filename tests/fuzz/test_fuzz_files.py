"""Fuzz every file loader with malformed, truncated, re-encoded and hostile files.

Contract (docs/guide/bad-input.md): a loader returns a valid result, or raises ValueError/TypeError (FileNotFoundError
for a missing file) whose message names the file — never another exception type, never a hang. Some mutations
must be refused outright: duplicate keys, bytes that are not UTF-8, a cut image, an integer no float holds, an
image header larger than the pixel limit.
"""

from __future__ import annotations

import json
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st
from PIL import Image

from hostile import FUZZ, HUGE, bounded, record

from psgsl_pgm import Ontology, kitchen_ontology
from psgsl_pgm.io._yaml import load_yaml
from psgsl_pgm.experiment import load_run, save_run
from psgsl_pgm.experiment._run import RunResult
from psgsl_pgm.sim import (GridMap, load_objects, load_ros_map, load_room_map, read_gaden_config,
                           read_gaden_wind_csv)
from psgsl_pgm.sim._fileio import MAX_IMAGE_PIXELS

LIKE = GridMap(np.zeros((6, 8), bool), 0.5, (0.0, 0.0))


def _pgm(pixels: np.ndarray) -> bytes:
    h, w = pixels.shape
    return f"P5\n{w} {h}\n255\n".encode() + pixels.astype(np.uint8).tobytes()


def _png(pixels: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    Image.fromarray(pixels.astype(np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


SEGMENTED = np.where(np.arange(8)[None, :] < 4, 50, 91).repeat(6, axis=0)
SEGMENTED[0, 0] = 0


def _run_bytes() -> bytes:
    rng = np.random.default_rng(3)
    run = RunResult("oven", 1, "infotaxis", np.array([1.0, 2.0]), np.linspace(0, 10, 4), rng.uniform(0, 5, (4, 2)),
                    np.array([False, True, False, True]), rng.uniform(0, 3, (4, 3)), rng.uniform(0, 1, (4, 3)),
                    {0: rng.dirichlet(np.ones(6), size=3).reshape(3, 2, 3)}, {"gas": "smoke"})
    with tempfile.TemporaryDirectory() as d:
        return save_run(run, Path(d) / "r.npz").read_bytes()


#: loader name -> (files {name: bytes}, the file handed to the loader, loader(path) -> result)
FILE_SETS = {
    "ontology": ({"o.yaml": kitchen_ontology().to_yaml().encode()}, "o.yaml", Ontology.from_yaml),
    "ros_map": ({"m.yaml": b"image: m.pgm\nresolution: 0.05\norigin: [1.0, -2.0, 0.0]\nnegate: 0\n"
                           b"occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n",
                 "m.pgm": _pgm(np.where(np.eye(6, 8, dtype=bool), 0, 254))}, "m.yaml", load_ros_map),
    "room_segmented": ({"r.yaml": b"image: s.pgm\nrooms:\n  50: Kitchen\n  91: Bedroom\nbackground: [0]\n",
                        "s.pgm": _pgm(SEGMENTED)}, "r.yaml", lambda p: load_room_map(p, like=LIKE)),
    "room_masks": ({"k.yaml": b"categories:\n  - name: Kitchen\n    mask: k.png\n  - name: Bath\n    mask: b.png\n",
                    "k.png": _png(np.where(SEGMENTED == 50, 255, 0)), "b.png": _png(np.where(SEGMENTED == 91, 255, 0))},
                   "k.yaml", lambda p: load_room_map(p, like=LIKE)),
    "objects": ({"o.yaml": b"objects:\n  - class: oven\n    position: [1.0, 1.5]\n    size: [0.5, 0.4]\n    yaw: 0.2\n"
                           b"    height: [0.0, 0.9]\n    name: oven_1\n  - class: couch\n"
                           b"    footprint: [[2.0, 1.0], [3.0, 1.0], [3.0, 2.0]]\n"},
                "o.yaml", lambda p: load_objects(p, like=LIKE, classes=["oven", "couch"])),
    "gaden_config": ({"g.yaml": b"source_x: 1.5\nsource_y: 2.0\nsource_z: 0.5\nppm_filament_center: 10\n"
                                b"filament_initial_std: 5\nfilament_growth_gamma: 10\nfilament_noise_std: 0.02\n"
                                b"num_filaments_sec: 10\ntime_step: 0.1\n"}, "g.yaml", read_gaden_config),
    "gaden_csv": ({"w.csv": b'"U:0","U:1","U:2","p","Points:0","Points:1","Points:2"\n'
                            + b"".join(f"{0.1 * i},{-0.05 * i},0,1,{0.25 + 0.5 * (i % 8)},{0.25 + 0.5 * (i // 8)},0.5\n"
                                       .encode() for i in range(48))},
                  "w.csv", lambda p: read_gaden_wind_csv(p, like=LIKE, height=0.5)),
    "run_file": ({"r.npz": _run_bytes()}, "r.npz", load_run),
}
SETS = sorted(FILE_SETS)


def _write(d: Path, files: dict) -> None:
    for name, data in files.items():
        (d / name).write_bytes(data)


def _load(name: str, files: dict):
    """Write ``files`` to a fresh folder and load; returns (result or exception, folder)."""
    _, target, loader = FILE_SETS[name]
    d = Path(tempfile.mkdtemp(prefix="fuzz-"))
    _write(d, files)
    try:
        with bounded():
            return loader(d / target), d
    except (ValueError, TypeError, FileNotFoundError) as exc:
        return exc, d


def _outcome(out, files, what: str) -> None:
    """Record a load's outcome: a result, or an error of one line naming one of ``files``."""
    if not isinstance(out, Exception):
        record("accepted")
        return
    msg = str(out)
    assert any(n in msg for n in files), f"{what}: the message names none of the files {sorted(files)}: {msg!r}"
    assert "\n" not in msg.strip() or isinstance(out, FileNotFoundError), f"{what}: message of several lines"
    record("refused")


@pytest.mark.parametrize("name", SETS)
def test_the_valid_files_load(name):
    out, _ = _load(name, FILE_SETS[name][0])
    assert not isinstance(out, Exception), out


# ------------------------------------------------------------------------------------------ byte mutations
def _mutate(data: bytes, how: str, i: int, b: int, chunk: bytes) -> bytes:
    i = i % (len(data) + 1)
    if how == "truncate":
        return data[:i]
    if how == "flip":
        return data[:i] + bytes([b]) + data[i + 1:] if i < len(data) else data + bytes([b])
    if how == "insert":
        return data[:i] + chunk + data[i:]
    if how == "delete":
        return data[:i] + data[i + len(chunk) + 1:]
    if how == "empty":
        return b""
    raise AssertionError(how)


@pytest.mark.parametrize("name", SETS)
@FUZZ
@given(data=st.data())
def test_corrupted_bytes_give_a_result_or_an_error_naming_the_file(name, data):
    files = dict(FILE_SETS[name][0])
    victim = data.draw(st.sampled_from(sorted(files)), label="file")
    how = data.draw(st.sampled_from(["truncate", "flip", "insert", "delete", "empty"]), label="mutation")
    files[victim] = _mutate(files[victim], how, data.draw(st.integers(0, 10**6), label="at"),
                            data.draw(st.integers(0, 255), label="byte"),
                            data.draw(st.binary(min_size=1, max_size=64), label="chunk"))
    out, _ = _load(name, files)
    _outcome(out, files, f"{name}: {how} {victim}")


# ------------------------------------------------------------------------------------------- text mutations
TEXT_SETS = [n for n in SETS if FILE_SETS[n][1].endswith((".yaml", ".csv"))]


@pytest.mark.parametrize("name", TEXT_SETS)
@FUZZ
@given(data=st.data())
def test_other_encodings_are_read_or_refused_naming_the_file(name, data):
    files = dict(FILE_SETS[name][0])
    target = FILE_SETS[name][1]
    text = files[target].decode()
    enc = data.draw(st.sampled_from(["latin-1", "cp1252", "utf-16-le", "utf-16", "utf-32", "utf-8-sig"]),
                    label="encoding")
    if enc in ("latin-1", "cp1252"):  # an accented name: bytes that are not UTF-8
        text = text.replace("\n", " # café\n", 1)
    files[target] = text.encode(enc)
    out, _ = _load(name, files)
    if enc in ("utf-16", "utf-8-sig") and target.endswith(".yaml"):  # byte-order marks are read
        assert not isinstance(out, Exception), out
        record("accepted")
        return
    if enc in ("latin-1", "cp1252", "utf-16-le", "utf-32"):
        assert isinstance(out, Exception), f"{name}: {enc} bytes read as if they were UTF-8"
    _outcome(out, files, f"{name}: {enc}")


_NUMBER = re.compile(rb"(?<![\w.])-?\d+(\.\d+)?(?![\w.])")
HOSTILE_NUMBERS = [str(HUGE).encode(), b"-" + str(HUGE).encode(), b"1.0e+400", b".nan", b"-.inf", b"'0.5'",
                   b'"3"', b"true", b"[]", b"{}", b"null", b"0x1F", b"1_000", b"300", b"-1", b"1e400", b"~"]


@pytest.mark.parametrize("name", [n for n in TEXT_SETS if n not in ("gaden_csv", "room_masks")])  # numbers to spoil
@FUZZ
@given(data=st.data())
def test_hostile_numbers_in_yaml_fields_are_refused_or_read_cleanly(name, data):
    files = dict(FILE_SETS[name][0])
    target = FILE_SETS[name][1]
    text = files[target]
    spans = [m.span() for m in _NUMBER.finditer(text)]
    lo, hi = data.draw(st.sampled_from(spans), label="number")
    new = data.draw(st.sampled_from(HOSTILE_NUMBERS), label="replacement")
    files[target] = text[:lo] + new + text[hi:]
    out, _ = _load(name, files)
    if new in (str(HUGE).encode(), b"-" + str(HUGE).encode(), b".nan", b"-.inf", b"1.0e+400", b"'0.5'", b'"3"'):
        assert isinstance(out, Exception), f"{name}: {new[:20]!r} in a number field accepted silently"
    _outcome(out, files, f"{name}: {new[:20]!r}")


@pytest.mark.parametrize("name", [n for n in TEXT_SETS if n != "gaden_csv"])
@FUZZ
@given(data=st.data())
def test_a_repeated_key_is_refused_naming_file_key_and_line(name, data):
    files = dict(FILE_SETS[name][0])
    target = FILE_SETS[name][1]
    lines = files[target].decode().splitlines(keepends=True)
    keyed = [i for i, ln in enumerate(lines) if re.match(r"^\s*[A-Za-z_][\w ]*:", ln) and not ln.lstrip().startswith("-")]
    i = data.draw(st.sampled_from(keyed), label="line")
    key = lines[i].split(":")[0].strip()
    lines.insert(i, lines[i] if not lines[i].rstrip().endswith(":") else lines[i].rstrip() + " {}\n")  # before it
    files[target] = "".join(lines).encode()
    out, _ = _load(name, files)
    assert isinstance(out, ValueError), f"{name}: key {key!r} twice accepted (the last one silently wins)"
    assert re.search(rf"{re.escape(target)}: duplicate key '{re.escape(key)}' at line {i + 2} \(first at line "
                     rf"{i + 1}\)", str(out)), str(out)
    record("refused")


# ------------------------------------------------------------------------------------------ image headers
@pytest.mark.parametrize("name", ["ros_map", "room_segmented"])
@FUZZ
@given(data=st.data())
def test_image_headers_that_lie_are_refused_naming_the_image(name, data):
    files = dict(FILE_SETS[name][0])
    image = next(n for n in files if n.endswith(".pgm"))
    w = data.draw(st.sampled_from([0, 1, 7, 9, 100, 10**5, 2**31 - 1]) | st.integers(0, 10**6), label="width")
    h = data.draw(st.sampled_from([0, 1, 5, 6, 100, 10**5]) | st.integers(0, 10**6), label="height")
    maxval = data.draw(st.sampled_from([255, 65535, 1, 0]), label="maxval")
    body = files[image].split(b"\n", 3)[3]
    files[image] = f"P5\n{w} {h}\n{maxval}\n".encode() + body
    out, _ = _load(name, files)
    consistent = (w * h == len(body) or (name == "ros_map" and 0 < w * h <= len(body))) and 0 < maxval < 256
    if w * h > MAX_IMAGE_PIXELS and maxval == 255:
        assert isinstance(out, ValueError) and f"{MAX_IMAGE_PIXELS}" in str(out), out
    elif not consistent:
        assert isinstance(out, Exception), f"{name}: a {w} x {h} (max {maxval}) header over {len(body)} bytes accepted"
    _outcome(out, files, f"{name}: header {w} x {h}")


def test_a_room_background_level_out_of_range_is_refused():
    files = dict(FILE_SETS["room_segmented"][0])
    for bad in (b"[300]", b"[-1]", b"256", b"[0, 2.5]", b"['0']"):
        files["r.yaml"] = FILE_SETS["room_segmented"][0]["r.yaml"].replace(b"[0]", bad)
        out, _ = _load("room_segmented", files)
        assert isinstance(out, ValueError) and "r.yaml: field 'background" in str(out), (bad, out)
        record("refused")


def test_yaml_bombs_and_deep_nesting_stay_clean(tmp_path):
    p = tmp_path / "b.yaml"
    p.write_text("a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [*{p_}, *{p_}, *{p_}, *{p_}, *{p_}, *{p_}, *{p_}, *{p_}, *{p_}]\n"
        for p_, c in zip("abcdefgh", "bcdefghi")) + "classes: *i\ngases: {g: {x: 1}}\n")
    with bounded(), pytest.raises((ValueError, TypeError), match="b.yaml"):
        Ontology.from_yaml(p)
    p.write_text("classes: " + "[" * 20000 + "]" * 20000 + "\n")
    with bounded(), pytest.raises(ValueError, match="b.yaml: nested deeper than 100 levels"):
        load_yaml(p)
    record("refused")
    record("refused")


def test_a_run_file_that_is_another_archive_is_named(tmp_path):
    np.savez(tmp_path / "x.npz", a=np.zeros(3))
    with pytest.raises(ValueError, match=r"x\.npz is not a run file written by psgsl"):
        load_run(tmp_path / "x.npz")
    np.save(tmp_path / "y.npz", np.zeros(3))  # a .npy under an .npz name
    with pytest.raises(ValueError, match=r"y\.npz\.npy|y\.npz is not a run file"):
        load_run(tmp_path / "y.npz.npy")
    (tmp_path / "j.npz").write_text(json.dumps({"a": 1}))
    with pytest.raises(ValueError, match=r"j\.npz is not a run file"):
        load_run(tmp_path / "j.npz")
    with pytest.raises(FileNotFoundError, match=r"none\.npz"):
        load_run(tmp_path / "none.npz")
    record("refused")
