"""SIGTERM and SIGKILL of a grid's client, with real processes: no worker outlives the client.

SIGTERM goes to the client alone (not its process group), as ``kill PID`` or a batch system's first signal does:
the client must end its workers itself. The grid is :mod:`tests.runs.grid_child` (jobs that sleep), started in a
process of its own; its worker processes are read from ``/proc`` before the signal.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time

import pytest

from .grid_child import (
    check_terminated,
    children,
    gone,
    kill_survivors,
    results,
    start,
    wait_for,
)

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the processes from Linux /proc")


def test_sigterm_ends_the_workers_keeps_finished_runs_and_exits_143(tmp_path):
    out, n = tmp_path / "grid", 40
    proc = start(out, 0.3, n)
    # two workers alive and at least one run written (the pool's workers and the resource tracker are children)
    wait_for(lambda: len(results(out)) >= 1 and len(children(proc.pid)) >= 2, 60, "written run", proc)
    workers = children(proc.pid)
    check_terminated(proc, out, workers, n)
    ran = {json.loads(f.read_text())["pid"] for f in results(out)}
    assert ran <= set(workers), "the runs were computed by processes that were not recorded as the grid's children"


def test_workers_of_a_killed_client_end_by_themselves(tmp_path):
    """SIGKILL cannot be handled: each worker notices that its parent is gone and exits mid-run."""
    out, started = tmp_path / "grid", tmp_path / "started"
    started.mkdir()
    env = dict(os.environ, GRID_CHILD_STARTED=str(started))
    proc = start(out, 120.0, 4, env=env)  # runs of two minutes: an orphan would be alive long after the check
    wait_for(lambda: len(list(started.iterdir())) >= 2, 60, "two started runs", proc)
    workers = children(proc.pid)
    try:
        assert len(workers) >= 2
        os.kill(proc.pid, signal.SIGKILL)
        assert proc.wait(timeout=10) == -signal.SIGKILL  # not communicate(): an orphan would hold the pipes
        assert gone(workers, timeout=10.0) == [], "workers of a killed client kept running"
        assert results(out) == []
    finally:
        kill_survivors(workers)
        proc.stdout.close()
        proc.stderr.close()


def _terminate(x):
    """SIGTERM to this process while "running" (in-process backend: the client itself)."""
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(5)  # not reached: the handler raises at once
    return {"x": x}


def _write(result, fh):
    fh.write(json.dumps(result).encode())


def test_sigterm_in_process_stops_at_once_and_restores_the_handlers(tmp_path):
    from psgsl_pgm.runs._runner import GridInterrupted, GridJob, run_grid

    (tmp_path / "r0.json").write_text("{}")
    jobs = [GridJob(tmp_path / f"r{x}.json", _terminate, (x,)) for x in range(3)]
    before = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
    t0 = time.monotonic()
    with pytest.raises(GridInterrupted) as exc:
        run_grid(jobs, write=_write, workers=1)
    assert time.monotonic() - t0 < 4
    assert (exc.value.done, exc.value.total, exc.value.immediate, exc.value.signum) == (1, 3, True, signal.SIGTERM)
    assert str(exc.value) == "stopped by SIGTERM: 1 of 3 runs done"
    assert [p.name for p in tmp_path.iterdir()] == ["r0.json"]
    assert (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)) == before
