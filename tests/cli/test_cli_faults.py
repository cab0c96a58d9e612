"""Nothing lost under faults: ``kill -9`` of ``psgsl search`` / ``psgsl experiment`` at seeded random moments,
then the same command, gives the summaries of an uninterrupted run (no temporary file left); two processes on
one ``--out``: the second is refused in one line, and a killed process leaves no stale lock."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

SEARCH = ["search", "--sources", "oven", "--policies", "tour", "greedy", "--variants", "olfaction", "--seeds", "2",
          "--budget", "12", "--workers", "1", "--quiet", "--no-figures"]
EXPERIMENT = ["experiment", "--sources", "oven", "--seeds", "2", "--estimators", "infotaxis", "--stops", "3",
              "--workers", "1", "--quiet"]
KILL_POINTS = 10


def _env():
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", MPLBACKEND="Agg")
    env.pop("PYTHONWARNINGS", None)
    return env


def _start(argv, out):
    return subprocess.Popen([sys.executable, "-m", "psgsl_pgm", *argv, "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=_env(), start_new_session=True)


def _run(argv, out, timeout=300):
    proc = _start(argv, out)
    stdout, stderr = proc.communicate(timeout=timeout)
    return proc.returncode, stdout, stderr


def _summaries(out):
    """Every summary, table and CSV the command writes (figures are redrawn on every call and not compared)."""
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.suffix in (".json", ".csv", ".txt") and p.parent.name != "runs"}


def _kill(proc):
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.communicate()


@pytest.mark.slow
@pytest.mark.parametrize("argv", [SEARCH, EXPERIMENT], ids=["search", "experiment"])
def test_kill_9_at_random_moments_then_resume_gives_the_uninterrupted_summaries(tmp_path, argv):
    ref = tmp_path / "reference"
    t0 = time.monotonic()
    code, _, err = _run(argv, ref)
    duration = time.monotonic() - t0
    assert code == 0, err
    expected = _summaries(ref)
    assert any(name.endswith("summary.json") for name in expected)
    total = len(list((ref / "runs").glob("*.npz")))
    rng = np.random.default_rng(23)
    stored = []
    for i, at in enumerate(rng.uniform(0.0, 1.1 * duration, KILL_POINTS)):
        out = tmp_path / f"killed{i}"
        proc = _start(argv, out)
        time.sleep(at)
        _kill(proc)  # kill -9: no handler runs, files are left as they are
        stored.append(len(list((out / "runs").glob("*.npz"))))
        code, _, err = _run(argv, out)
        assert code == 0, (i, at, err)
        assert _summaries(out) == expected, (i, at)
        left = [p for p in out.rglob("*") if p.name.endswith(".part") or p.name.startswith(".psgsl-probe")]
        assert not left, (i, at, left)
    assert any(0 < n < total for n in stored), stored  # some kills did land in the middle of the grid


@pytest.mark.slow  # ~25 s; tests/core/test_grid_runner.py checks the lock in-process by default
def test_a_second_process_on_the_same_out_is_refused_and_a_killed_one_leaves_no_lock(tmp_path):
    out = tmp_path / "s"
    first = _start(SEARCH, out)
    t0 = time.monotonic()
    while not ((out / ".lock").exists() and (out / ".lock").read_text().strip() == str(first.pid)):
        if first.poll() is not None:
            pytest.fail(f"the first process ended before it took the lock: {first.communicate()}")
        if time.monotonic() - t0 > 120:
            _kill(first)
            pytest.fail("the first process never took the lock")
        time.sleep(0.02)
    try:
        code, _, err = _run(SEARCH, out)
        assert code == 2
        assert err.strip().splitlines() == [f"psgsl search: error: --out {out} is in use by another psgsl process "
                                             f"(pid {first.pid}); wait for it to end, or use another --out"]
    finally:
        _kill(first)  # kill -9 while it holds the lock: the operating system releases it
    code, _, err = _run(SEARCH, out)
    assert code == 0, err
    assert len(list((out / "runs").glob("*.npz"))) == 4
