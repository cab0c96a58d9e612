"""Fuzz the user's own files on the command line: world files (``psgsl world check``) and ROS 2 bags
(``psgsl replay``), each broken in one of the ways a hand-written or half-copied file is: truncated, duplicate
keys, wrong types, huge and non-finite numbers, time going backwards.

Contract: exit 0, or exit 2 with ONE line ``psgsl <command>: error: ...`` and nothing written (no figure, no
output folder) — never a traceback, never a warning before the error. The mutations that make a file wrong
(a duplicate key, a non-finite or huge number where a coordinate or speed goes, time going backwards, a bag cut
short) must be refused.
"""

from __future__ import annotations

import dataclasses
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from hostile import FUZZ, bounded, record

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot  # noqa: E402,F401 - imported here, not under the alarm of a timed call

import psgsl_pgm.cli._main as cli  # noqa: E402
import psgsl_pgm.experiment._replay  # noqa: E402,F401
from tests.sim.test_sim_worldfile import world_dict, write_house  # noqa: E402


def _run(argv, capsys, seconds: float = 10.0):
    """(exit code, stderr) of ``psgsl argv``, checking the one-line contract; warnings are errors."""
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning printed before a one-line error is a finding
        with bounded(seconds):
            code = cli.main(argv)
    out = capsys.readouterr()
    assert code in (0, 2), code
    if code == 2:
        lines = out.err.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in out.err, out.err
        assert lines[0].startswith(f"psgsl {argv[0]}: error: "), lines[0]
        record("refused")
    else:
        record("accepted")
    return code, out.err


# ---- world files ---------------------------------------------------------------------------------------------
_HOUSE = {}


def _flat() -> Path:
    """A fresh folder with the two-room flat's map, rooms, objects and ontology (written once, copied)."""
    import shutil

    if "dir" not in _HOUSE:
        _HOUSE["dir"] = Path(tempfile.mkdtemp(prefix="fuzz-house-"))
        write_house(_HOUSE["dir"])
    d = Path(tempfile.mkdtemp(prefix="fuzz-world-"))
    for f in _HOUSE["dir"].iterdir():
        shutil.copy(f, d)
    return d


#: Where a number of a world file goes, and how to put a value there.
_NUMBERS = {
    "resolution": lambda w, v: w.__setitem__("resolution", v),
    "wind.speed": lambda w, v: w["wind"].__setitem__("speed", v),
    "start.x": lambda w, v: w.__setitem__("start", [v, 2.0]),
    "sources.S1.y": lambda w, v: w["sources"].__setitem__("S1", [4.0, v]),
    "windows[0].to.x": lambda w, v: w["wind"]["windows"][0].__setitem__("to", [v, 2.5]),
    "clearance": lambda w, v: w.__setitem__("clearance", v),
}
#: Values no coordinate, speed or size may take (YAML text, so that .nan and a 400-digit integer reach the loader).
_BAD_NUMBERS = [".nan", ".inf", "-.inf", "1e400", "-1e400", "1" + "0" * 400, "1e30", "-1e30", "1e-320"]


@FUZZ
@given(data=st.data())
def test_world_check_on_hostile_world_files(capsys, data):
    d = _flat()
    world = world_dict()
    kind = data.draw(st.sampled_from(["truncated", "duplicate", "wrong-type", "number"]), label="kind")
    text = yaml.safe_dump(world, sort_keys=False)
    must_refuse = True
    if kind == "truncated":
        cut = data.draw(st.integers(0, len(text) - 1), label="cut")
        text = text[:cut]
        must_refuse = False  # a cut between keys can leave a shorter file that is still a valid world
    elif kind == "duplicate":
        key = data.draw(st.sampled_from(["map", "resolution", "start", "wind", "sources"]), label="key")
        text += yaml.safe_dump({key: world[key]}, sort_keys=False)
    elif kind == "wrong-type":
        key = data.draw(st.sampled_from(["resolution", "start", "wind", "sources", "rooms", "map", "clearance"]),
                        label="key")
        world[key] = data.draw(st.sampled_from([[1, 2, 3], "text", {"a": 1}, True, None, [[0.0]], -1]),
                               label="value")
        text = yaml.safe_dump(world, sort_keys=False)
        must_refuse = not (key == "clearance" and world[key] is None)
    else:
        where = data.draw(st.sampled_from(sorted(_NUMBERS)), label="where")
        value = data.draw(st.sampled_from(_BAD_NUMBERS), label="value")
        _NUMBERS[where](world, "@@")
        text = yaml.safe_dump(world, sort_keys=False).replace("'@@'", value)
        must_refuse = not (value == "1e-320" and where in ("sources.S1.y", "windows[0].to.x"))
    (d / "world.yaml").write_text(text)
    png = d / "house.png"
    code, err = _run(["world", "check", str(d / "world.yaml"), "--png", str(png)], capsys)
    if must_refuse:
        assert code == 2, f"{kind}: accepted:\n{text}"
    if code == 2:
        assert not png.exists() and not list(d.glob("*.tmp*")), "a refused world check wrote a figure"


# ---- bags ------------------------------------------------------------------------------------------------------
_BAG = {}


def _bag() -> Path:
    pytest.importorskip("rosbags", reason="the ros extra is not installed")
    from tests.ros.bags import episode_bag

    if "bag" not in _BAG:
        _BAG["bag"] = episode_bag(Path(tempfile.mkdtemp(prefix="fuzz-bag-")) / "bag", "sqlite3")
    return _BAG["bag"]


def _stamped(msg, seconds):
    stamp = dataclasses.replace(msg.header.stamp, sec=msg.header.stamp.sec + seconds)
    return dataclasses.replace(msg, header=dataclasses.replace(msg.header, stamp=stamp))


def _break_value(topic, msg, value):
    """The message with its reading (gas), vector (wind) or translation (/tf) set to ``value``."""
    if topic == "/gas":
        return dataclasses.replace(msg, raw=value)
    if topic == "/wind":
        return dataclasses.replace(msg, vector=dataclasses.replace(msg.vector, x=value))
    tr = msg.transforms[0]
    moved = dataclasses.replace(tr.transform, translation=dataclasses.replace(tr.transform.translation, x=value))
    return dataclasses.replace(msg, transforms=[dataclasses.replace(tr, transform=moved)])


@FUZZ
@given(data=st.data())
def test_replay_on_hostile_bags(capsys, data):
    from tests.ros.bags import rewrite

    src = _bag()
    d = Path(tempfile.mkdtemp(prefix="fuzz-replay-"))
    start = 1_700_000_000 * 10**9
    kind = data.draw(st.sampled_from(["truncated", "backwards", "number", "metadata"]), label="kind")
    k = data.draw(st.integers(1, 8), label="message")  # which reading (s into the episode)
    topic = data.draw(st.sampled_from(["/gas", "/wind", "/tf"]), label="topic")
    if kind == "truncated":
        import shutil

        bag = d / "bag"
        shutil.copytree(src, bag)
        db = next(bag.glob("*.db3"))
        blob = db.read_bytes()
        db.write_bytes(blob[: data.draw(st.integers(0, len(blob) - 1), label="cut")])
    elif kind == "backwards":  # one message stamped 3 s before its predecessor
        bag = rewrite(src, d / "bag", change=lambda t_, t, m: _stamped(m, -3) if t_ == topic and t == start + k * 10**9
                      and t_ != "/tf" else (dataclasses.replace(m, transforms=[
                          dataclasses.replace(m.transforms[0], header=_stamped(m.transforms[0], -3).header)])
                          if t_ == topic == "/tf" and t == start + k * 10**9 else m))
    elif kind == "number":
        value = data.draw(st.sampled_from([float("nan"), float("inf"), -float("inf"), 1e308, -1e308]), label="value")
        bag = rewrite(src, d / "bag", change=lambda t_, t, m: _break_value(t_, m, value)
                      if t_ == topic and t == start + k * 10**9 else m)
    else:  # metadata.yaml cut or with a duplicate key
        import shutil

        bag = d / "bag"
        shutil.copytree(src, bag)
        meta = (bag / "metadata.yaml").read_text()
        how = data.draw(st.sampled_from(["cut", "duplicate"]), label="how")
        meta = meta[: len(meta) // 2] if how == "cut" else meta + "rosbag2_bagfile_information: {}\n"
        (bag / "metadata.yaml").write_text(meta)
    out = d / "out"
    # an accepted bag replays whole and draws its figures: longer than a refusal (and traced by hypothesis)
    code, err = _run(["replay", str(bag), "--quiet", "--out", str(out)], capsys, seconds=90.0)
    if kind in ("backwards", "metadata") or (kind == "number" and topic != "/gas") or (
            kind == "number" and not np.isfinite(value)):
        assert code == 2, f"{kind} {topic} accepted"
    if code == 2:
        assert not out.exists(), "a refused replay wrote its output folder"
