"""The command line's one error mechanism: one line on stderr, exit 2, outputs checked before any work."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest

import psgsl_pgm.cli._main as cli
from psgsl_pgm import kitchen_ontology
from psgsl_pgm.io._output import check_output_file, prepare_output_dir, write_file_atomically


def _error_line(capsys, command):
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"psgsl {command}: error: "), lines[0]
    return lines[0]


@pytest.mark.parametrize(
    "exc, shown",
    [
        (ValueError("x must be positive,\n got [[1]\n [2]]"), "x must be positive, got [[1] [2]]"),
        (TypeError("y must be a number, got 'a'"), "y must be a number, got 'a'"),
        (FileNotFoundError(2, "No such file or directory", "a.npy"), "'a.npy': No such file or directory"),
        (OSError(28, "No space left on device"), "No space left on device"),
        (PermissionError("denied here"), "denied here"),
    ],
)
def test_every_input_error_of_any_command_is_one_line_and_exit_2(monkeypatch, capsys, exc, shown):
    def boom(args):
        raise exc

    parser = cli.build_parser()
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    parser.set_defaults(func=boom)
    for action in parser._subparsers._group_actions[0].choices.values():  # every registered subcommand
        action.set_defaults(func=boom)
    assert cli.main(["kitchen"]) == 2
    assert _error_line(capsys, "kitchen") == f"psgsl kitchen: error: {shown}"


def test_a_bug_is_not_disguised_as_an_input_error(monkeypatch):
    parser = cli.build_parser()
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    parser._subparsers._group_actions[0].choices["kitchen"].set_defaults(func=lambda a: {}["missing"])
    with pytest.raises(KeyError):
        cli.main(["kitchen"])


@pytest.fixture
def estimate_inputs(tmp_path):
    ont = kitchen_ontology()
    ont.to_yaml(tmp_path / "o.yaml")
    k = len(ont.classes)
    np.save(tmp_path / "p.npy", np.full((3, 4, k), 1 / k))
    np.save(tmp_path / "g.npy", np.full((3, 4), 1 / 12))
    return ["estimate", "--ontology", str(tmp_path / "o.yaml"), "--class-probs", str(tmp_path / "p.npy"),
            "--olfactory", str(tmp_path / "g.npy"), "--gas", "smoke"]


def test_estimate_writes_exactly_the_out_path_and_prints_it(tmp_path, estimate_inputs, capsys):
    out = tmp_path / "posterior"  # no .npy suffix: np.save(path) would have written posterior.npy
    assert cli.main(estimate_inputs + ["--out", str(out)]) == 0
    assert out.is_file() and not (tmp_path / "posterior.npy").exists()
    assert np.load(out).shape == (3, 4)
    assert f"-> {out};" in capsys.readouterr().out
    assert not [p for p in os.listdir(tmp_path) if p.endswith(".part") or p.startswith(".psgsl")]


@pytest.mark.parametrize("spoil, message", [
    (lambda d, k: np.save(d / "p.npy", np.full(k, 1 / k)), r"--olfactory must have the map's shape \(\) \(the cells of "
                                                          r"--class-probs\), got \(3, 4\)"),
    (lambda d, k: (d / "p.npy").write_bytes((d / "p.npy").read_bytes()[:40] + b"\x00" * 40 + b"["),
     r"--class-probs: '.*p\.npy' is not a \.npy array"),  # a header numpy's parser fails on with a TokenError
])
def test_estimate_names_the_file_of_a_mismatch_or_a_garbled_header(tmp_path, estimate_inputs, capsys, spoil, message):
    spoil(tmp_path, len(kitchen_ontology().classes))
    assert cli.main(estimate_inputs + ["--out", str(tmp_path / "post.npy")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(message, err[0]), err


@pytest.mark.parametrize(
    "out, message",
    [
        ("adir", "--out: '.*adir' is a directory; give the file to write"),
        ("/dev/full", "--out: '/dev/full' is not a regular file"),
        ("/proc/p.npy", "--out: cannot write in '/proc'"),
        ("nofolder/p.npy", "--out: the folder '.*nofolder' of .* does not exist"),
    ],
)
def test_estimate_refuses_an_unwritable_out_before_reading_anything(tmp_path, estimate_inputs, capsys, monkeypatch,
                                                                      out, message):
    (tmp_path / "adir").mkdir()
    import psgsl_pgm

    monkeypatch.setattr(psgsl_pgm.Ontology, "from_yaml", lambda p: pytest.fail("work started before --out check"))
    target = out if out.startswith("/") else str(tmp_path / out)
    assert cli.main(estimate_inputs + ["--out", target]) == 2
    import re

    assert re.search(message, _error_line(capsys, "estimate"))


def test_write_file_atomically_leaves_nothing_on_failure(tmp_path):
    out = tmp_path / "x.bin"
    out.write_bytes(b"old")

    def fail(fh):
        fh.write(b"new, half")
        raise OSError(28, "No space left on device")

    with pytest.raises(ValueError, match=r"--out: cannot write '.*x\.bin' \(No space left on device\)"):
        write_file_atomically(out, fail)
    assert out.read_bytes() == b"old" and os.listdir(tmp_path) == ["x.bin"]
    write_file_atomically(out, lambda fh: fh.write(b"new"))
    assert out.read_bytes() == b"new" and oct(out.stat().st_mode & 0o777) != oct(0o600)
    with pytest.raises(TypeError, match="--out must be a path"):
        check_output_file(3)
    with pytest.raises(ValueError, match="--out must be a path, got an empty string"):
        check_output_file(" ")


def test_prepare_output_dir_creates_checks_and_refuses(tmp_path):
    assert prepare_output_dir(tmp_path / "a" / "b", subdirs=("runs",)) == tmp_path / "a" / "b"
    assert (tmp_path / "a" / "b" / "runs").is_dir() and os.listdir(tmp_path / "a" / "b") == ["runs"]
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="exists and is not a directory"):
        prepare_output_dir(tmp_path / "f")
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "runs").write_text("x")
    with pytest.raises(ValueError, match=r"'.*d/runs' exists and is not a directory"):
        prepare_output_dir(tmp_path / "d", subdirs=("runs",))
    with pytest.raises(ValueError, match="cannot create the directory '/proc/psgsl'"):
        prepare_output_dir("/proc/psgsl")


@pytest.mark.skipif(not os.path.isfile("/proc/self/status"), reason="needs Linux procfs")
def test_an_existing_directory_nobody_can_write_in_is_refused():
    # procfs: a directory that exists and in which no process, root included (as in CI), can create a file
    with pytest.raises(ValueError, match=r"^--out: cannot write in '/proc' \("):
        prepare_output_dir("/proc")
    with pytest.raises(ValueError, match=r"^--out: cannot write in '/proc' \("):
        check_output_file("/proc/x.npy")


def test_a_directory_the_os_refuses_to_write_in_is_refused(tmp_path, monkeypatch):
    # a read-only folder as a non-root user sees it: the probe's file creation fails with EACCES (chmod cannot
    # make that happen for root, so the refusal is produced at the boundary the code checks: creating a file)
    import errno
    import tempfile

    def refuse(*args, dir=None, **kwargs):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), os.path.join(dir, "probe"))

    ro = tmp_path / "ro"
    ro.mkdir()
    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    with pytest.raises(ValueError, match=r"^--out: cannot write in '.*/ro' \(Permission denied\)$"):
        prepare_output_dir(ro)
    with pytest.raises(ValueError, match=r"^--map-out: cannot write in '.*/ro' \(Permission denied\)$"):
        check_output_file(ro / "x.npy", option="--map-out")
    assert list(ro.iterdir()) == []


@pytest.fixture
def no_runs(monkeypatch):
    """Any search run is a failure: the errors below must come before work starts."""
    import psgsl_pgm.experiment._run as run_module

    monkeypatch.setattr(run_module, "run_search", lambda *a, **k: pytest.fail("a run started"))


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--sources", "toaster2"], "source 'toaster2' is no object class of the house — did you mean 'toaster'\\?; "
                                    "classes present: .*'oven'"),
        (["--sources", "100,100"], r"source position \(100, 100\) lies outside the map: x in \[0, 10\]"),
        (["--sources", "0.01,0.01"], r"source position \(0.01, 0.01\) lies in an occupied cell"),
        (["--sources", "1,x"], "a source position must read 'x,y' in metres"),
        (["--out", "/proc/psgsl-out"], "--out: cannot create the directory '/proc/psgsl-out'"),
        (["--out", "{file}"], "--out: '.*afile' exists and is not a directory"),
    ],
)
def test_experiment_bad_source_or_out_is_one_line_before_any_run(tmp_path, capsys, no_runs, extra, message):
    (tmp_path / "afile").write_text("x")
    extra = [e.replace("{file}", str(tmp_path / "afile")) for e in extra]
    args = ["experiment", "--seeds", "1", "--workers", "1", "--quiet", "--out", str(tmp_path / "o")] + extra
    assert cli.main(args) == 2
    import re

    assert re.search(message, _error_line(capsys, "experiment"))


@pytest.mark.parametrize("command", ["experiment", "search"])
def test_a_world_file_naming_no_sources_wants_sources(tmp_path, capsys, monkeypatch, no_runs, command):
    from types import SimpleNamespace

    import psgsl_pgm.sim as sim

    monkeypatch.setattr(sim, "load_world", lambda path: SimpleNamespace(sources={}, gas=None))
    args = [command, "--world", str(tmp_path / "w.yaml"), "--seeds", "1", "--workers", "1", "--quiet", "--out",
            str(tmp_path / "o")]
    assert cli.main(args) == 2
    assert _error_line(capsys, command).endswith("w.yaml: the world file names no 'sources'; give --sources")
    assert not (tmp_path / "o").exists()


def test_grid_sources_are_the_given_ones_else_the_embedded_houses():
    from argparse import Namespace

    from psgsl_pgm.cli._grid import world_sources
    from psgsl_pgm.experiment import parse_source

    spec, names, sources = world_sources(Namespace(world=None, sources=None))
    assert spec is None and names == ["oven", "bed", "5.0,6.0"]
    assert sources == [parse_source("oven"), parse_source("bed"), parse_source("5.0,6.0")]
    assert world_sources(Namespace(world=None, sources=["bed", "1,2"]))[1:] == (["bed", "1,2"],
                                                                               [parse_source("bed"), (1.0, 2.0)])


@pytest.mark.parametrize("command", ["demo", "experiment", "search", "benchmark"])
def test_every_grid_command_takes_the_same_workers_option(monkeypatch, capsys, command):
    parser, default = cli.build_parser(), min(2, os.cpu_count() or 1)
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    one_core = cli.build_parser()
    assert parser.parse_args([command]).workers == default
    assert one_core.parse_args([command]).workers == 1
    assert parser.parse_args([command, "--workers", "1024"]).workers == 1024
    for bad in ("0", "1025"):
        with pytest.raises(SystemExit) as info:
            parser.parse_args([command, "--workers", bad])
        assert info.value.code == 2
    assert "argument --workers: expected a positive integer of at most 1024, got '1025'" in capsys.readouterr().err


def test_demo_refuses_a_device_as_out(capsys, no_runs):
    assert cli.main(["demo", "--out", "/dev/full", "--quiet"]) == 2
    assert "--out: '/dev/full' exists and is not a directory" in _error_line(capsys, "demo")


def test_a_corrupt_run_file_is_one_line_naming_it(tmp_path, capsys, no_runs):
    from psgsl_pgm.experiment._store import run_path

    bad = run_path(tmp_path, "oven", "infotaxis", 0)
    bad.parent.mkdir(parents=True)
    bad.write_bytes(b"PK\x03\x04 truncated zip")
    assert cli.main(["experiment", "--sources", "oven", "--seeds", "1", "--estimators", "infotaxis", "--workers", "1",
                     "--quiet", "--out", str(tmp_path)]) == 2
    line = _error_line(capsys, "experiment")
    assert f"{bad} is not a run file written by psgsl" in line and "delete it to recompute" in line


def test_no_traceback_through_the_real_entry_point(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "psgsl_pgm", "experiment", "--sources", "nothing", "--seeds", "1",
                           "--out", str(tmp_path / "o"), "--quiet"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert not (tmp_path / "o").exists()  # the source is refused before the output directory is made
