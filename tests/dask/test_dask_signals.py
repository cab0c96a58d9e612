"""SIGTERM and SIGKILL of a grid's client on dask: a LocalCluster's workers end with it; a remote cluster is left
running nothing of the grid.

The grid is :mod:`tests.runs.grid_child` with ``--scheduler`` (jobs that sleep), in a process of its own; the
signal goes to that process alone. Its LocalCluster's worker processes are read from ``/proc`` before the signal.
"""

from __future__ import annotations

import sys
import time

import pytest

from tests.runs.grid_child import (
    check_terminated,
    kill_grid,
    results,
    start,
    terminate_grid,
    wait_for,
)

from .dask_parts import worker_env

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the processes from Linux /proc")


def test_sigterm_ends_a_local_clusters_workers_and_exits_143(tmp_path):
    # the LocalCluster's worker processes are the client's children (their nannies live in the client)
    terminate_grid(tmp_path, "--scheduler", "local", env=worker_env())  # nothing on stderr: dask's chatter held back


def test_a_local_clusters_workers_end_when_the_client_is_killed(tmp_path):
    """SIGKILL: dask's own check (each worker process watches a pipe from its parent) ends the workers mid-run."""
    kill_grid(tmp_path, "--scheduler", "local", env=worker_env())


def test_sigterm_on_a_remote_cluster_leaves_it_running_nothing_of_the_grid(tmp_path, real_cluster):
    """The workers are not the client's to kill: the grid's queued runs are dropped (the stop event) and its
    futures released with the client, so the cluster is idle again once the runs in progress have ended."""
    from distributed import Client

    out, n = tmp_path / "grid", 40
    proc = start(out, 0.3, n, "--scheduler", real_cluster.address, env=worker_env())
    wait_for(lambda: len(results(out)) >= 1, 120, "written run", proc)
    check_terminated(proc, out, {}, n, quiet=False)
    with Client(real_cluster.address, timeout=30) as client:
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            tasks = client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks))
            if tasks == 0:
                break
            time.sleep(0.2)
        assert tasks == 0, f"the scheduler still holds {tasks} tasks of the terminated grid"
        assert not any(client.processing().values())
