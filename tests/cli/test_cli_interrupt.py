"""Ctrl-C during ``psgsl experiment``: stop, keep every finished run, exit 130 with one line, resume.

The signal goes to the whole process group, as a terminal's Ctrl-C does (workers included). Marked slow (a few
grids of real runs in subprocesses); tests/runs/test_runs_runner.py covers the same logic in-process by default.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time

import pytest

from psgsl_pgm.experiment import load_run

STOPS = 24  # runs long enough to be in progress at a Ctrl-C, and still at a second one 0.3 s later
GRID = ["--sources", "oven", "--seeds", "3", "--estimators", "infotaxis", "analytic-plume", "--stops", str(STOPS), "--quiet"]
TOTAL = 6


def _env():
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", MPLBACKEND="Agg")
    env.pop("PYTHONWARNINGS", None)
    return env


def _start(out, *extra):
    return subprocess.Popen([sys.executable, "-m", "psgsl_pgm", "experiment", *GRID, "--out", str(out), *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(),
                            start_new_session=True)


def _wait_for_runs(out, proc, n=1, timeout=180.0):
    t0 = time.monotonic()
    while len(list((out / "runs").glob("*.npz"))) < n:
        if proc.poll() is not None:
            pytest.fail(f"the grid ended before any run was written: {proc.communicate()}")
        if time.monotonic() - t0 > timeout:
            proc.kill()
            pytest.fail("no run was written in time")
        time.sleep(0.05)


def _state(out):
    return {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in sorted((out / "runs").glob("*.npz"))}


def _check_interrupted(proc, out, timeout):
    try:
        stdout, stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail(f"psgsl experiment did not stop within {timeout} s of Ctrl-C")
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    m = re.fullmatch(rf"psgsl experiment: interrupted: (\d+) of {TOTAL} runs done in (\S+) \(.*\); "
                     r"resume with: psgsl experiment .*", lines[0])
    assert m, lines[0]
    files = sorted((out / "runs").glob("*.npz"))
    assert int(m.group(1)) == len(files) and m.group(2) == str(out / "runs")
    assert not list((out / "runs").glob("*.part")), "a temporary file was left behind"
    for f in files:  # every finished file is complete and loadable
        run = load_run(f)
        assert run.n_steps == STOPS
    return m, lines[0]


@pytest.mark.slow
def test_ctrl_c_keeps_finished_runs_exits_130_and_resumes_only_the_missing(tmp_path):
    out = tmp_path / "exp"
    proc = _start(out, "--workers", "2")
    _wait_for_runs(out, proc)
    os.killpg(proc.pid, signal.SIGINT)
    m, line = _check_interrupted(proc, out, timeout=120)
    assert "runs in progress were finished" in line
    done = int(m.group(1))
    assert 1 <= done < TOTAL, "the queued runs were not dropped (or the grid ended before Ctrl-C)"
    before = _state(out)

    # resume: the exact command of the hint, which computes only the missing runs
    resume = line.split("resume with: ", 1)[1].split()
    assert resume[:2] == ["psgsl", "experiment"]
    proc = subprocess.run([sys.executable, "-m", "psgsl_pgm", *resume[1:]], capture_output=True, text=True,
                          env=_env(), timeout=300)
    assert proc.returncode == 0, proc.stderr
    after = _state(out)
    assert len(after) == TOTAL
    for name, state in before.items():
        assert after[name] == state, f"{name} was recomputed or rewritten"


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir("/proc"), reason="needs Linux /proc to list the process group")
def test_second_ctrl_c_exits_at_once_without_corrupting(tmp_path):
    out = tmp_path / "exp"
    proc = _start(out, "--workers", "2")
    _wait_for_runs(out, proc)
    os.killpg(proc.pid, signal.SIGINT)
    time.sleep(0.3)
    os.killpg(proc.pid, signal.SIGINT)
    t_int = time.monotonic()
    _, line = _check_interrupted(proc, out, timeout=20)
    assert time.monotonic() - t_int < 10, "the second Ctrl-C did not exit at once"
    assert "in-progress runs abandoned" in line
    deadline = time.monotonic() + 10  # no worker process outlives its client (zombies are reaped by init)
    while _alive(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _alive(proc.pid), "worker processes survived the second Ctrl-C"


def _alive(pgid) -> bool:
    """Whether a non-zombie process of process group ``pgid`` exists (Linux /proc)."""
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            return True
    return False
