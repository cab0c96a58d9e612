"""Fixtures of the dask tests; every test here is skipped (with the reason) when dask.distributed is missing."""

from __future__ import annotations

import pytest
from .dask_parts import RealCluster

pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install 'psgsl-pgm[dask]')")


@pytest.fixture
def real_cluster(tmp_path):
    """A scheduler and two single-threaded workers on free ports of 127.0.0.1."""
    cluster = RealCluster(tmp_path, 2)
    try:
        yield cluster
    finally:
        cluster.close()
