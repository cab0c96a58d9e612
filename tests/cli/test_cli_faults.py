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
EXPERIMENT = ["experiment", "--sources", "oven", "--seeds", "4", "--estimators", "infotaxis", "--stops", "6",
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


def _count(out):
    return len(list((out / "runs").glob("*.npz")))


@pytest.mark.slow
@pytest.mark.parametrize("argv", [SEARCH, EXPERIMENT], ids=["search", "experiment"])
def test_kill_9_at_random_moments_then_resume_gives_the_uninterrupted_summaries(tmp_path, argv):
    """Ten seeded kill points: the even ones at a uniform time over the whole command (start-up, runs, summaries,
    figures), the odd ones a uniform fraction of a run's time after the k-th run is stored (k uniform), so that
    some kills surely land between runs and inside one."""
    ref = tmp_path / "reference"
    t0 = time.monotonic()
    proc = _start(argv, ref)
    seen = {}
    while proc.poll() is None:
        seen.setdefault(_count(ref), time.monotonic() - t0)
        time.sleep(0.01)
    _, err = proc.communicate()
    duration = time.monotonic() - t0
    assert proc.returncode == 0, err
    total = _count(ref)
    expected = _summaries(ref)
    assert total >= 4 and any(name.endswith("summary.json") for name in expected)
    per_run = max((seen.get(total, duration) - seen.get(1, 0.0)) / (total - 1), 0.05)
    rng = np.random.default_rng(23)
    stored = []
    for i in range(KILL_POINTS):
        out = tmp_path / f"killed{i}"
        proc = _start(argv, out)
        if i % 2 == 0:
            time.sleep(rng.uniform(0.0, 1.05 * duration))
        else:
            k, pause = int(rng.integers(1, total)), rng.uniform(0.0, per_run)
            while _count(out) < k and proc.poll() is None:
                time.sleep(0.005)
            time.sleep(pause)
        _kill(proc)  # kill -9: no handler runs, files are left as they are
        stored.append(_count(out))
        code, _, err = _run(argv, out)
        assert code == 0, (i, err)
        assert _summaries(out) == expected, i
        left = [p for p in out.rglob("*") if p.name.endswith(".part") or p.name.startswith(".psgsl-probe")]
        assert not left, (i, left)
    assert any(0 < n < total for n in stored), stored  # some kills did land in the middle of the grid


@pytest.mark.slow  # ~25 s; tests/runs/test_runs_runner.py checks the lock in-process by default
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
