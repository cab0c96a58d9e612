"""The core and the grid runner work without dask installed (dask is the extra psgsl-pgm[dask])."""

from __future__ import annotations

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent(
    """
    import sys

    class Block:  # as if dask, distributed and zarr were not installed
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in ("dask", "distributed", "zarr"):
                raise ModuleNotFoundError(f"No module named {name!r}")

    sys.meta_path.insert(0, Block())
    import numpy as np
    from psgsl_pgm import ClassBeliefMap, fuse, semantic_information_gain, semantic_source_probability
    from psgsl_pgm.runs._runner import GridJob, run_grid

    q = np.array([[0.9, 0.05, 0.025, 0.025], [0.25, 0.25, 0.25, 0.25]])
    lik, prior = [0.4, 0.25, 0.3, 0.05], np.full(4, 0.25)
    p = semantic_source_probability(q, lik, prior)
    print(p.round(4).tolist(), fuse(p, [0.5, 0.5]).round(4).tolist(),
          semantic_information_gain(q, lik, prior).shape)
    try:
        run_grid([GridJob("unused.json", print)], write=None, scheduler="local")
    except ValueError as exc:
        print(exc)
    m = ClassBeliefMap.from_prior((1, 2), prior, tuple("abcd"))
    m.update([[0, 0]], [lik])
    print(m.source_probability(lik, prior).round(4).tolist())
    try:
        ClassBeliefMap.from_prior((1, 2), prior, tuple("abcd"), chunks=1)
    except ModuleNotFoundError as exc:
        print(exc)
    assert not [m for m in sys.modules if m.split(".")[0] in ("dask", "distributed", "zarr")]
    """
)


def test_core_and_runner_import_and_run_without_dask(tmp_path):
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert lines[0] == "[0.604, 0.396] [0.604, 0.396] (2,)"
    assert lines[1] == "scheduler='local' needs dask.distributed: pip install 'psgsl-pgm[dask]'"
    assert lines[2] == "[[0.5575, 0.4425]]"  # w = 4 Σ lik² = 1.26 against 1
    assert lines[3] == "a chunked (dask-backed) class-belief map needs dask: pip install 'psgsl-pgm[dask]'"
