"""``psgsl experiment --scheduler``: a real dask scheduler and workers, a killed worker, Ctrl-C, bit-identity."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys

import numpy as np
import pytest
from .dask_parts import free_port, wait_until, worker_env

from psgsl_pgm.cli._main import main
from psgsl_pgm.experiment import load_run

STOPS = 24  # a run long enough that the other worker is still in one when the first is written
GRID = ["--sources", "oven", "--seeds", "3", "--estimators", "infotaxis", "analytic-plume", "--quiet"]


def _experiment(out, *extra):
    return subprocess.Popen([sys.executable, "-m", "psgsl_pgm", "experiment", *GRID, "--out", str(out), *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=worker_env(),
                            start_new_session=True)


def _assert_bit_identical(a_dir, b_dir):
    a_files = sorted(p.name for p in (a_dir / "runs").glob("*.npz"))
    assert a_files == sorted(p.name for p in (b_dir / "runs").glob("*.npz")) and a_files
    for name in a_files:
        with np.load(a_dir / "runs" / name) as a, np.load(b_dir / "runs" / name) as b:
            assert a.files == b.files
            for key in a.files:
                assert a[key].dtype == b[key].dtype and a[key].shape == b[key].shape, (name, key)
                assert a[key].tobytes() == b[key].tobytes(), f"{name}: {key} differs"


def _stats(runs):
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in runs.glob("*.npz")}


@pytest.mark.slow
def test_a_grid_on_a_real_scheduler_survives_a_killed_worker_and_equals_the_local_pool(tmp_path, real_cluster):
    from distributed import Client

    remote, local = tmp_path / "remote", tmp_path / "local"
    runs = remote / "runs"
    first_seen = {}
    busy = []

    def sample():
        for name, st in _stats(runs).items():
            first_seen.setdefault(name, st)
        return proc.poll() is not None

    # The client watches before the grid starts: a run takes well under a second on a fast machine, so a client
    # connected only after the first run file appears can find every run already done.
    with Client(real_cluster.address, timeout=30) as client:
        pids = client.run(os.getpid)
        proc = _experiment(remote, "--stops", str(STOPS), "--scheduler", real_cluster.address)
        try:
            def a_run_done_and_a_worker_busy():
                done = sample()
                if first_seen:  # a worker that is running a run right now, after one run was written
                    busy[:] = [addr for addr, keys in client.processing().items() if keys]
                return bool(busy) or done

            wait_until(a_run_done_and_a_worker_busy, 300, "the first run")
            assert busy, "the grid finished before a worker could be killed in the middle of a run"
            victim = pids[busy[0]]
            assert victim in [w.pid for w in real_cluster.workers]
            os.kill(victim, signal.SIGKILL)
            wait_until(sample, 600, "the grid to finish")
            stdout, stderr = proc.communicate()
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.communicate()
    assert proc.returncode == 0, stderr
    assert "Traceback" not in stderr, stderr
    final = _stats(runs)
    assert len(final) == 6 and final == {n: first_seen[n] for n in final}, "a run file was written twice"
    assert not list(runs.glob("*.part")) and not list(runs.glob(".*.part"))

    assert main(["experiment", *GRID, "--stops", str(STOPS), "--out", str(local), "--workers", "2"]) == 0
    _assert_bit_identical(remote, local)


@pytest.mark.slow
def test_local_cluster_equals_the_local_pool_bit_for_bit(tmp_path):
    pool, cluster = tmp_path / "pool", tmp_path / "cluster"
    grid = ["experiment", "--sources", "oven", "--seeds", "2", "--estimators", "infotaxis", "--stops", "3",
            "--quiet"]
    assert main([*grid, "--out", str(pool), "--workers", "2"]) == 0
    assert main([*grid, "--out", str(cluster), "--workers", "2", "--scheduler", "local"]) == 0
    _assert_bit_identical(pool, cluster)


def test_an_unreachable_scheduler_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch):
    import psgsl_pgm.runs._runner as runner

    monkeypatch.setattr(runner, "CONNECT_TIMEOUT", 1.0)

    code = main(["experiment", *GRID, "--stops", "2", "--out", str(tmp_path), "--scheduler",
                 f"tcp://127.0.0.1:{free_port()}"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("psgsl experiment: error: scheduler: cannot connect"), err


@pytest.mark.slow
def test_ctrl_c_on_a_local_cluster_keeps_finished_runs_and_resumes(tmp_path):
    out = tmp_path / "exp"
    proc = _experiment(out, "--stops", str(STOPS), "--scheduler", "local", "--workers", "2")
    wait_until(lambda: list((out / "runs").glob("*.npz")) or proc.poll() is not None, 300, "the first run")
    os.killpg(proc.pid, signal.SIGINT)  # workers included, as from a terminal
    stdout, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 130, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    m = re.fullmatch(r"psgsl experiment: interrupted: (\d+) of 6 runs done in \S+ \(runs in progress were "
                     r"finished\); resume with: psgsl experiment .*", lines[0])
    assert m, lines[0]
    done = sorted((out / "runs").glob("*.npz"))
    assert int(m.group(1)) == len(done) and 1 <= len(done) < 6
    for f in done:
        assert load_run(f).n_steps == STOPS
    before = _stats(out / "runs")
    assert main(["experiment", *GRID, "--stops", str(STOPS), "--out", str(out), "--workers", "2", "--scheduler",
                 "local"]) == 0
    after = _stats(out / "runs")
    assert len(after) == 6 and all(after[n] == st for n, st in before.items())
