"""A class-belief map larger than a worker's memory: 1e8 cells × 40 classes of float32 in zarr (16 GB on disk),
processed by dask workers limited to 2 GB each. Slow (minutes): ``python -m pytest -q -m slow -s tests/dask``
prints the measured times and peak memory.
"""

from __future__ import annotations

import os
import shutil
import threading
import time

import numpy as np
import pytest

N_CELLS, N_CLASSES, CHUNK = 10**8, 40, 500_000
MEMORY_LIMIT = 2 * 10**9


def _write_beliefs(path, zarr):
    """Random normalised float32 beliefs, written chunk by chunk (a loop over 200 chunks, not over cells)."""
    kwargs = dict(shape=(N_CELLS, N_CLASSES), chunks=(CHUNK, N_CLASSES), dtype="float32")
    if hasattr(zarr, "create_array"):  # zarr 3
        store = zarr.create_array(str(path), compressors=None, **kwargs)  # random data does not compress
    else:
        store = zarr.open_array(str(path), mode="w", compressor=None, **kwargs)
    rng = np.random.default_rng(0)
    for start in range(0, N_CELLS, CHUNK):
        block = rng.random((CHUNK, N_CLASSES), dtype=np.float32) ** 4  # peaked beliefs
        block /= block.sum(axis=1, keepdims=True)
        store[start:start + CHUNK] = block


class _PeakRSS(threading.Thread):
    def __init__(self, pids):
        import psutil

        super().__init__(daemon=True)
        self.procs = [psutil.Process(p) for p in pids]
        self.peak = {p: 0 for p in pids}
        self.running = True

    def run(self):
        while self.running:
            for proc in self.procs:
                try:
                    self.peak[proc.pid] = max(self.peak[proc.pid], proc.memory_info().rss)
                except Exception:  # noqa: BLE001 - a process that just ended
                    pass
            time.sleep(0.2)


@pytest.mark.slow
@pytest.mark.huge
def test_a_zarr_map_larger_than_worker_memory_streams_in_bounded_memory(tmp_path):
    zarr = pytest.importorskip("zarr", reason="zarr is not installed (pip install 'psgsl-pgm[dask]')")
    pytest.importorskip("psutil", reason="psutil measures the workers' memory")
    import dask.array as da
    from distributed import Client, LocalCluster

    from psgsl_pgm import fuse, semantic_information_gain, semantic_source_probability

    free = shutil.disk_usage(tmp_path).free
    need = N_CELLS * N_CLASSES * 4 + N_CELLS * 4 * 2
    if free < need * 1.2:
        pytest.skip(f"needs {need / 1e9:.0f} GB of free disk, {free / 1e9:.0f} GB available")
    rng = np.random.default_rng(1)
    lik = rng.dirichlet(np.ones(N_CLASSES))
    prior = rng.dirichlet(np.full(N_CLASSES, 5.0))
    beliefs, posterior = tmp_path / "beliefs.zarr", tmp_path / "posterior.zarr"
    try:
        t0 = time.perf_counter()
        _write_beliefs(beliefs, zarr)
        t_write = time.perf_counter() - t0
        with LocalCluster(n_workers=2, threads_per_worker=1, memory_limit=MEMORY_LIMIT, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            pids = client.run(os.getpid)
            monitor = _PeakRSS([*pids.values(), os.getpid()])
            monitor.start()
            dq = da.from_zarr(str(beliefs))
            assert dq.nbytes == 16 * 10**9 and dq.nbytes > 4 * MEMORY_LIMIT

            t0 = time.perf_counter()
            olfactory = da.full((N_CELLS,), 1.0 / N_CELLS, chunks=CHUNK)
            post = fuse(olfactory, semantic_source_probability(dq, lik, prior))
            assert isinstance(post, da.Array) and post.dtype == np.float64
            da.to_zarr(post, str(posterior))
            t_posterior = time.perf_counter() - t0

            t0 = time.perf_counter()
            gain = semantic_information_gain(dq, lik, prior, predictive="exact")
            best, top = da.compute(gain.argmax(), gain.max())
            t_gain = time.perf_counter() - t0
            monitor.running = False
            monitor.join()
            assert client.run(os.getpid) == pids, "a worker was restarted (memory limit exceeded?)"

        out = da.from_zarr(str(posterior))
        total = float(out.sum(dtype=np.float64).compute(scheduler="synchronous"))
        chunk = np.asarray(zarr.open_array(str(beliefs), mode="r")[:CHUNK])
        w = semantic_source_probability(chunk, lik, prior, normalize=False)
        ratio = np.asarray(zarr.open_array(str(posterior), mode="r")[:CHUNK]) / w
        peak_workers = max(monitor.peak[p] for p in pids.values())
        print(f"\n1e8 cells x 40 classes float32 ({dq.nbytes / 1e9:.0f} GB zarr), 2 workers x 1 thread, "
              f"memory limit {MEMORY_LIMIT / 1e9:.0f} GB each: write {t_write:.0f} s; p(s|z) + fuse -> zarr "
              f"{t_posterior:.0f} s; I(S;O_n) argmax {t_gain:.0f} s; peak RSS per worker "
              f"{peak_workers / 1e9:.2f} GB, client {monitor.peak[os.getpid()] / 1e9:.2f} GB")
        assert abs(total - 1.0) < 1e-9
        # one global normaliser for every cell (p(s|z) is float32 for float32 beliefs: one float32 rounding)
        np.testing.assert_allclose(ratio, ratio[0], rtol=1e-6)
        assert 0 <= best < N_CELLS and top > 0 and np.isfinite(top)
        assert peak_workers < MEMORY_LIMIT
    finally:
        shutil.rmtree(beliefs, ignore_errors=True)
        shutil.rmtree(posterior, ignore_errors=True)
