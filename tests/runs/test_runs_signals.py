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

from .grid_child import kill_grid, terminate_grid

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the processes from Linux /proc")


def test_sigterm_ends_the_workers_keeps_finished_runs_and_exits_143(tmp_path):
    # the local pool: its two workers and multiprocessing's resource tracker are the client's children
    _, workers, out = terminate_grid(tmp_path)
    ran = {json.loads(f.read_text())["pid"] for f in out.glob("r*.json")}
    assert ran <= set(workers), "the runs were computed by processes that were not recorded as the grid's children"


def test_workers_of_a_killed_client_end_by_themselves(tmp_path):
    """SIGKILL cannot be handled: each worker notices that its parent is gone and exits mid-run."""
    kill_grid(tmp_path)


def _terminate(x):
    """SIGTERM to this process while "running" (in-process backend: the client itself)."""
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(5)  # not reached: the handler raises at once
    return {"x": x}


def _write(result, fh):
    fh.write(json.dumps(result).encode())


class _Unhandled(Exception):
    pass


def _fallback(signum, frame):
    raise _Unhandled("SIGTERM reached the test's own handler: run_grid installed none")


def test_sigterm_in_process_stops_at_once_and_restores_the_handlers(tmp_path):
    from psgsl_pgm.runs._runner import GridInterrupted, GridJob, run_grid

    (tmp_path / "r0.json").write_text("{}")
    jobs = [GridJob(tmp_path / f"r{x}.json", _terminate, (x,)) for x in range(3)]
    old = signal.signal(signal.SIGTERM, _fallback)  # were run_grid's handler missing, the test fails, pytest lives
    try:
        before = signal.getsignal(signal.SIGINT)
        t0 = time.monotonic()
        with pytest.raises(GridInterrupted) as exc:
            run_grid(jobs, write=_write, workers=1)
        assert time.monotonic() - t0 < 4
        assert (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)) == (_fallback, before)
    finally:
        signal.signal(signal.SIGTERM, old)
    assert (exc.value.done, exc.value.total, exc.value.immediate, exc.value.signum) == (1, 3, True, signal.SIGTERM)
    assert str(exc.value) == "stopped by SIGTERM: 1 of 3 runs done"
    assert [p.name for p in tmp_path.iterdir()] == ["r0.json"]


def _identity(x):
    return {"x": x}


def _write_then_terminate(result, fh):
    """Write the result, then SIGTERM this process while the file is still being made (before its rename)."""
    fh.write(json.dumps(result).encode())
    if result["x"] == 1:
        os.kill(os.getpid(), signal.SIGTERM)


def test_sigterm_while_a_result_is_written_counts_exactly_the_files_on_disk(tmp_path):
    """An abort that arrives while a finished run is written is held until the file is in place and counted: no
    finished run is lost, and the report's count is the files on disk whenever the signal comes (between the
    rename and the count, it would otherwise report one run fewer than the folder holds)."""
    from psgsl_pgm.runs._runner import GridInterrupted, GridJob, run_grid

    jobs = [GridJob(tmp_path / f"r{x}.json", _identity, (x,)) for x in range(4)]
    with pytest.raises(GridInterrupted) as exc:
        run_grid(jobs, write=_write_then_terminate, workers=1)
    files = sorted(p.name for p in tmp_path.iterdir())
    assert files == ["r0.json", "r1.json"], files  # the run being written is kept, whole; nothing after it runs
    assert json.loads((tmp_path / "r1.json").read_text()) == {"x": 1}
    assert (exc.value.done, exc.value.total, exc.value.immediate, exc.value.signum) == (2, 4, True, signal.SIGTERM)
