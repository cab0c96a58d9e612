"""Fuzz the command line: hostile input files, option values and output paths.

Contract: exit code 0 (and the output exactly where ``--out`` says), or exit code 2 with ONE line
``psgsl <command>: error: ...`` on stderr and nothing written — never a traceback, never another code.
(argparse's own usage errors exit 2 through SystemExit with its usage line, which is also accepted.)
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from hostile import FUZZ, bounded, record

import psgsl_pgm.cli._main as cli
import psgsl_pgm.experiment  # noqa: F401 - imported here, not under the alarm of a timed call
from psgsl_pgm import kitchen_ontology

K = len(kitchen_ontology().classes)


def _run(argv, capsys):
    capsys.readouterr()
    try:
        with bounded():
            code = cli.main(argv)
    except SystemExit as exc:  # argparse: usage + one error line, exit 2
        assert exc.code == 2, exc.code
        err = capsys.readouterr().err
        assert "Traceback" not in err and "error:" in err, err
        record("refused")
        return 2, err
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


def _inputs(d: Path):
    ont = kitchen_ontology()
    ont.to_yaml(d / "o.yaml")
    np.save(d / "p.npy", np.full((3, 4, K), 1 / K))
    np.save(d / "g.npy", np.full((3, 4), 1 / 12))
    return {"--ontology": d / "o.yaml", "--class-probs": d / "p.npy", "--olfactory": d / "g.npy"}


def _argv(files, out, gas="smoke"):
    argv = ["estimate"]
    for k, v in files.items():
        argv += [k, str(v)]
    return argv + ["--gas", gas, "--out", str(out)]


@FUZZ
@given(data=st.data())
def test_estimate_with_hostile_arrays(capsys, data):
    d = Path(tempfile.mkdtemp(prefix="fuzz-cli-"))
    files = _inputs(d)
    which = data.draw(st.sampled_from(["--class-probs", "--olfactory"]), label="file")
    dtype = data.draw(hnp.floating_dtypes() | hnp.integer_dtypes() | hnp.boolean_dtypes()
                      | hnp.complex_number_dtypes() | hnp.unicode_string_dtypes() | hnp.byte_string_dtypes()
                      | hnp.datetime64_dtypes() | hnp.timedelta64_dtypes(), label="dtype")
    shape = data.draw(st.sampled_from([(3, 4, K), (3, 4)] if which == "--class-probs" else [(3, 4), (12,)])
                      | hnp.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=5), label="shape")
    arr = data.draw(hnp.arrays(dtype, shape), label="array")
    np.save(files[which], arr)
    out = d / "post.npy"
    code, err = _run(_argv(files, out), capsys)
    if dtype.kind not in "fiu":
        assert code == 2, f"{which} of dtype {dtype} accepted"
    if code == 2 and "--gas" not in err:
        assert which in err, err  # the option is named, not the library's argument
    if code == 2:
        assert not out.exists()
    else:
        post = np.load(out)
        assert post.shape == (3, 4) and np.isfinite(post).all() and abs(post.sum() - 1) < 1e-6


@FUZZ
@given(data=st.data())
def test_estimate_with_hostile_files_gas_and_out(capsys, data):
    d = Path(tempfile.mkdtemp(prefix="fuzz-cli-"))
    files = _inputs(d)
    (d / "adir").mkdir()
    what = data.draw(st.sampled_from(["file-bytes", "gas", "out"]), label="what")
    gas, out = "smoke", d / "post.npy"
    if what == "file-bytes":
        which = data.draw(st.sampled_from(sorted(files)), label="file")
        blob = files[which].read_bytes()
        cut = data.draw(st.integers(0, len(blob)), label="cut")
        files[which].write_bytes(blob[:cut] + data.draw(st.binary(max_size=32), label="tail"))
    elif what == "gas":
        gas = data.draw(st.text(max_size=12).filter(lambda t: not t.startswith("-")), label="gas")
    else:
        out = data.draw(st.sampled_from([d / "adir", Path("/dev/full"), Path("/dev/null"), Path("/proc/x.npy"),
                                         d / "no" / "x.npy", d / "post", d / "o.yaml"]), label="out")
    code, err = _run(_argv(files, out, gas), capsys)
    if what == "out" and out in (d / "adir", Path("/dev/full"), Path("/dev/null"), Path("/proc/x.npy"),
                                 d / "no" / "x.npy"):
        assert code == 2 and "--out" in err, err
    if what == "gas" and gas != "smoke":
        assert code == 2, f"--gas {gas!r} accepted"
    if code == 0:
        assert out.is_file() and np.load(out).shape == (3, 4)
        assert not (out.parent / (out.name + ".npy")).exists()


@FUZZ
@given(data=st.data())
def test_experiment_with_hostile_sources_and_out(capsys, data):
    d = Path(tempfile.mkdtemp(prefix="fuzz-cli-"))
    (d / "afile").write_text("x")
    source = data.draw(st.text(max_size=16).filter(lambda t: not t.startswith("-"))
                       | st.sampled_from(["oven", "5.0,6.0", "1e400,2", "nan,1", "-1,-1", "3,4,5", ",", "inf,inf",
                                          "toaster", "5.0, 6.0", " oven "]), label="source")
    out = data.draw(st.sampled_from([d / "o", d / "afile", Path("/proc/psgsl"), Path("/dev/full"), d]), label="out")
    seeds = data.draw(st.sampled_from(["1", "2", "0", "-1", "x", "1e3", str(10**30)]), label="seeds")
    argv = ["experiment", "--sources", source, "--seeds", seeds, "--workers", "1", "--quiet", "--out", str(out)]
    with pytest.MonkeyPatch.context() as mp:
        import psgsl_pgm.experiment as experiment

        mp.setattr(experiment, "run_experiment", lambda *a, **k: {})  # the pre-flight checks are what is fuzzed
        code, err = _run(argv, capsys)
    if out in (d / "afile", Path("/proc/psgsl"), Path("/dev/full")):
        assert code == 2
    if code == 0:  # the pre-flight check creates nothing (the grid creates --out once every check has passed)
        assert Path(out).is_dir() and os.access(out, os.W_OK) if Path(out).exists() else os.access(d, os.W_OK)
