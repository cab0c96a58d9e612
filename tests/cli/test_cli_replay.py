"""``psgsl replay``: --list, a replay's outputs, bad bags as one line + exit 2 with nothing written; the ros extra
is needed only there (and by --record)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import psgsl_pgm.cli._main as cli

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from tests.ros.bags import episode_bag


def _error_line(capsys):
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith("psgsl replay: error: "), lines[0]
    return lines[0]


def test_list_names_topics_types_counts_and_roles(tmp_path, capsys):
    bag = episode_bag(tmp_path / "bag")
    assert cli.main(["replay", str(bag), "--list"]) == 0
    out = capsys.readouterr().out.splitlines()
    rows = {line.split()[0]: line.split()[1:] for line in out[1:]}
    assert rows["/gas"] == ["olfaction_msgs/msg/GasSensor", "10", "gas"]
    assert rows["/tf"] == ["tf2_msgs/msg/TFMessage", "10", "pose"]
    assert rows["/wind"] == ["geometry_msgs/msg/Vector3Stamped", "10", "wind"]
    assert rows["/anemometer"] == ["olfaction_msgs/msg/Anemometer", "10", "-"]
    assert rows["/detections"] == ["vision_msgs/msg/Detection3DArray", "4", "detections"]
    assert rows["/map"] == ["nav_msgs/msg/OccupancyGrid", "1", "map"]


def test_replay_writes_one_runs_outputs(tmp_path, capsys):
    bag = episode_bag(tmp_path / "bag", "sqlite3")
    out = tmp_path / "out"
    assert cli.main(["replay", str(bag), "--source", "6.0,6.0", "--topics", "wind=/anemometer", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "10 gas readings (5 hits at >= 1 ppm), 4 detection frames" in text
    assert "wind=/anemometer" in text
    names = {p.name for p in out.iterdir()}
    assert names == {"run.npz", "metrics.csv", "summary.json", "posterior-olfaction.npy", "posterior-semantics.npy",
                     "posterior-semantics+rooms.npy", "posterior.png", "error-chart.png"}
    final = np.load(out / "posterior-semantics.npy")
    assert final.shape == (120, 100) and abs(final.sum() - 1) < 1e-12
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 10 and summary["frames"] == 4 and summary["skipped_detections"] == 0


def test_threshold_option_changes_the_hits(tmp_path, capsys):
    bag = episode_bag(tmp_path / "bag")
    assert cli.main(["replay", str(bag), "--threshold", "3", "--out", str(tmp_path / "o")]) == 0
    assert "10 gas readings (0 hits at >= 3 ppm)" in capsys.readouterr().out


@pytest.mark.parametrize("args, message", [
    (["--topics", "gas=/nope"], "topic /nope (given for gas) is not in the bag"),
    (["--tolerance", "-1"], "tolerance must be a non-negative number of seconds, got -1.0"),
    (["--threshold", "0"], "threshold must be a positive number of ppm, got 0.0"),
])
def test_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path, capsys, args, message):
    bag = episode_bag(tmp_path / "bag")
    out = tmp_path / "out"
    assert cli.main(["replay", str(bag), *args, "--out", str(out)]) == 2
    assert message in _error_line(capsys)
    assert not out.exists()


def test_truncated_bag_on_the_command_line(tmp_path, capsys):
    bag = episode_bag(tmp_path / "bag")
    (f,) = bag.glob("*.mcap")
    f.write_bytes(f.read_bytes()[:2000])
    assert cli.main(["replay", str(bag), "--out", str(tmp_path / "out")]) == 2
    assert str(bag) in _error_line(capsys)
    assert not (tmp_path / "out").exists()


def test_out_is_required_without_list(tmp_path, capsys):
    bag = episode_bag(tmp_path / "bag")
    assert cli.main(["replay", str(bag)]) == 2
    assert "--out is required" in _error_line(capsys)


def test_the_extra_is_named_when_missing(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "rosbags", None)  # as if not installed
    monkeypatch.setitem(sys.modules, "rosbags.rosbag2", None)
    assert cli.main(["replay", str(tmp_path), "--list"]) == 2
    assert 'the "ros" extra): pip install "psgsl-pgm[ros]"' in _error_line(capsys)
    assert cli.main(["experiment", "--record", "--seeds", "1", "--stops", "1", "--out", str(tmp_path / "e")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("psgsl experiment: error: --record: ") and "psgsl-pgm[ros]" in err
    assert not (tmp_path / "e").exists()


def test_core_and_simulator_never_import_the_ros_packages():
    code = ("import sys, psgsl_pgm, psgsl_pgm.sim, psgsl_pgm.experiment, psgsl_pgm.search, psgsl_pgm.ros, "
            "psgsl_pgm.cli._main; bad = sorted(m for m in sys.modules if m.split('.')[0] in "
            "('rosbags', 'mcap', 'foxglove')); print(bad); sys.exit(1 if bad else 0)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stdout + res.stderr


@pytest.mark.parametrize("command, module, function", [
    (["experiment", "--sources", "oven", "--seeds", "1"], "psgsl_pgm.experiment", "run_experiment"),
    (["search", "--sources", "oven", "--seeds", "1", "--no-figures"], "psgsl_pgm.search._grid", "run_search_grid"),
])
def test_record_reaches_the_grid(monkeypatch, tmp_path, command, module, function):
    """--record is handed to the grid (which writes the episodes; tests/ros/test_ros_record.py); without it, not."""
    import importlib

    seen = []

    def fake(*args, **kwargs):
        seen.append(kwargs.get("record"))
        raise ValueError("stop here")

    monkeypatch.setattr(importlib.import_module(module), function, fake)
    for extra, want in (([], False), (["--record"], True)):
        assert cli.main([*command, *extra, "--out", str(tmp_path / "o")]) == 2
        assert seen[-1] is want


def test_a_bag_without_wind_replays_and_says_what_it_assumes(tmp_path, capsys):
    from tests.ros.bags import rewrite

    bag = episode_bag(tmp_path / "bag")
    calm = rewrite(bag, tmp_path / "calm", keep=lambda topic, t, m: topic not in ("/wind", "/anemometer"))
    out = tmp_path / "out"
    assert cli.main(["replay", str(calm), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "10 gas readings (5 hits at >= 1 ppm)" in text and "wind=" not in text
    assert "no wind readings: the estimators assume still air" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["assumptions"] and summary["assumptions"][0].startswith("no wind readings")
    assert summary["outside_overlap"] == {"gas": 0, "wind": 0, "detections": 0}
    # the same bag with its wind replays to other posteriors: the wind is used when it is there
    assert cli.main(["replay", str(bag), "--out", str(tmp_path / "windy")]) == 0
    assert "assume still air" not in capsys.readouterr().out
    assert not np.array_equal(np.load(out / "posterior-olfaction.npy"),
                              np.load(tmp_path / "windy" / "posterior-olfaction.npy"))


def _in_units(bag, dst, units, factor):
    """``bag`` with its GasSensor readings multiplied by ``factor`` and labelled with ``raw_units`` ``units``."""
    import dataclasses

    from tests.ros.bags import rewrite

    def change(topic, t, msg):
        if topic == "/gas":
            return dataclasses.replace(msg, raw=msg.raw * factor, raw_units=units)
        return msg

    return rewrite(bag, dst, change=change)


def test_gas_units_are_read_from_the_message(tmp_path, capsys):
    bag = episode_bag(tmp_path / "bag")
    ohms = _in_units(bag, tmp_path / "mox", 5, 10_000.0)  # a MOX sensor's resistance: 20 000 and 5 000 ohm
    assert cli.main(["replay", str(ohms), "--out", str(tmp_path / "o1")]) == 2
    line = _error_line(capsys)
    assert "topic /gas: the readings are in ohm (the GasSensor's raw_units), not ppm" in line
    assert "--gas-conversion SCALE[,OFFSET]" in line and not (tmp_path / "o1").exists()
    # with the user's conversion: ppm = 1e-4 × raw gives the original readings back, so the original hits
    assert cli.main(["replay", str(ohms), "--gas-conversion", "1e-4", "--out", str(tmp_path / "o2"), "--quiet"]) == 0
    assert "10 gas readings (5 hits at >= 1 ppm)" in capsys.readouterr().out
    ppb = _in_units(bag, tmp_path / "ppb", 4, 1000.0)  # ppb: converted exactly, no option needed
    assert cli.main(["replay", str(ppb), "--out", str(tmp_path / "o3"), "--quiet"]) == 0
    assert "10 gas readings (5 hits at >= 1 ppm)" in capsys.readouterr().out


def test_replay_shows_a_progress_bar_unless_quiet(tmp_path, capsys):
    bag = episode_bag(tmp_path / "bag")
    assert cli.main(["replay", str(bag), "--out", str(tmp_path / "o")]) == 0
    assert "psgsl replay: gas readings: 100%" in capsys.readouterr().err
    assert cli.main(["replay", str(bag), "--out", str(tmp_path / "q"), "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_the_posterior_figure_is_labelled(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from psgsl_pgm.experiment._replay import replay, replay_figure

    res = replay(episode_bag(tmp_path / "bag"), source="6.0,6.0")
    fig = replay_figure(res)
    try:
        panels = [ax for ax in fig.axes if ax.get_title()]
        bars = [ax for ax in fig.axes if ax.get_ylabel() == "p(s | …) per cell"]
        assert len(panels) == 3 and len(bars) == 3  # a colour bar beside each variant's panel
        assert all(ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)" for ax in panels)
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        assert labels == ["90 % credible region", "path (from its start)", "walls and furniture", "true source"]
    finally:
        plt.close(fig)


def test_gas_readings_that_change_unit_are_refused(tmp_path, capsys):
    import dataclasses

    from tests.ros.bags import rewrite

    bag = episode_bag(tmp_path / "bag")
    start = 1_700_000_000 * 10**9
    mixed = rewrite(bag, tmp_path / "mixed", change=lambda topic, t, m: dataclasses.replace(m, raw_units=4)
                    if topic == "/gas" and t >= start + 5 * 10**9 else m)
    assert cli.main(["replay", str(mixed), "--out", str(tmp_path / "o")]) == 2
    line = _error_line(capsys)
    assert "topic /gas: the readings change unit at t = 5.000 s into the bag" in line
    assert "raw_units ppm from t = 0.000 s into the bag" in line
    assert line.endswith("then ppb") and not (tmp_path / "o").exists()


def test_a_float_gas_topic_is_taken_as_ppm_and_the_replay_says_so(tmp_path, capsys):
    """A std_msgs/Float64 carries no unit: its values are taken as ppm, and the printout says so."""
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer

    from psgsl_pgm.ros._types import typestore

    src = episode_bag(tmp_path / "bag")
    store = typestore()
    dst = tmp_path / "floats"
    with Reader(src) as reader, Writer(dst, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
        conns = {}
        for conn, t, raw in reader.messages():
            topic, typ = conn.topic, conn.msgtype
            msg = store.deserialize_cdr(raw, typ)
            if topic == "/gas":  # the reading as a bare Float64 (received at its stamp)
                topic, typ, msg = "/ppm", "std_msgs/msg/Float64", store.types["std_msgs/msg/Float64"](data=msg.raw)
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, typ, typestore=store)
            writer.write(conns[topic], t, store.serialize_cdr(msg, typ))
    assert cli.main(["replay", str(dst), "--quiet", "--out", str(tmp_path / "o")]) == 0
    text = capsys.readouterr().out
    assert "10 gas readings (5 hits at >= 1 ppm)" in text and "gas=/ppm" in text
    assert "the gas topic's /ppm messages carry no unit: their values are taken as ppm" in text
