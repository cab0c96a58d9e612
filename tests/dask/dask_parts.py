"""Real dask parts for the tests of this folder: a ``dask scheduler`` and worker processes on 127.0.0.1."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time

import pytest


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def worker_env() -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", MPLBACKEND="Agg")
    env.pop("PYTHONWARNINGS", None)
    return env


class RealCluster:
    """``dask scheduler`` + ``dask worker`` processes (no nanny: a worker's pid is the process that runs)."""

    def __init__(self, tmp_path, n_workers: int, memory_limit: str = "2GB"):
        self.address = f"tcp://127.0.0.1:{free_port()}"
        self.tmp = tmp_path
        self.memory_limit = memory_limit
        self.logs = []
        self.scheduler = self._spawn("scheduler", [sys.executable, "-m", "distributed.cli.dask_scheduler",
                                                   "--host", "127.0.0.1", "--port", self.address.rsplit(":", 1)[1],
                                                   "--no-dashboard"])
        self.workers = [self.add_worker(f"w{i}") for i in range(n_workers)]
        self.wait_for_workers(n_workers)

    def _spawn(self, name, cmd):
        log = open(self.tmp / f"{name}.log", "w")
        self.logs.append(log)
        return subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=worker_env(), start_new_session=True)

    def add_worker(self, name):
        return self._spawn(name, [sys.executable, "-m", "distributed.cli.dask_worker", self.address, "--name", name,
                                  "--nthreads", "1", "--no-nanny", "--no-dashboard",
                                  "--memory-limit", self.memory_limit, "--local-directory", str(self.tmp / name)])

    def wait_for_workers(self, n, timeout=120):
        from distributed import Client

        with Client(self.address, timeout=timeout) as client:
            client.wait_for_workers(n, timeout=timeout)

    def close(self):
        for proc in [*self.workers, self.scheduler]:
            if proc.poll() is None:
                proc.terminate()
        for proc in [*self.workers, self.scheduler]:
            try:
                proc.wait(timeout=5)  # they end in under 0.5 s; one that has not by then is killed
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        for log in self.logs:
            log.close()


def wait_until(predicate, timeout, what):
    t0 = time.monotonic()
    while not predicate():
        if time.monotonic() - t0 > timeout:
            pytest.fail(f"timed out waiting for {what}")
        time.sleep(0.05)
