"""SIGTERM to ``psgsl search --workers 2``: its workers end, finished runs are kept, one line, exit code 143.

The signal goes to the ``psgsl`` process alone (``kill PID``), not its process group: the workers must be ended by
the client. tests/runs/test_runs_signals.py covers the runner with fast jobs by default; this one runs real
closed-loop searches (slow).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from argparse import Namespace

import pytest

from psgsl_pgm.cli._grid import EXIT_INTERRUPTED, EXIT_TERMINATED, interrupted
from psgsl_pgm.runs._runner import GridInterrupted
from tests.runs.grid_child import children, gone, kill_survivors, wait_for

SEEDS = 6
GRID = ["search", "--sources", "oven", "--seeds", str(SEEDS), "--budget", "60", "--policies", "tour",
        "--variants", "olfaction", "--workers", "2", "--quiet", "--no-figures"]


@pytest.mark.parametrize("signum, code, what, how", [
    (signal.SIGINT, EXIT_INTERRUPTED, "interrupted", "runs in progress were finished"),
    (signal.SIGTERM, EXIT_TERMINATED, "terminated by SIGTERM", "in-progress runs abandoned"),
])
def test_the_line_and_exit_code_name_the_signal(capsys, signum, code, what, how):
    exc = GridInterrupted(2, 6, immediate=signum == signal.SIGTERM, signum=signum)
    args = Namespace(command="search", argv=["search", "--out", "my dir"])
    assert interrupted(args, exc, where="my dir/runs") == code == 128 + signum
    assert capsys.readouterr().err == (f"psgsl search: {what}: 2 of 6 runs done in my dir/runs ({how}); resume "
                                       "with: psgsl search --out 'my dir'\n")
    assert EXIT_TERMINATED == 143


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the processes from Linux /proc")
def test_sigterm_ends_the_workers_keeps_finished_runs_and_exits_143(tmp_path):
    from psgsl_pgm.search._store import load_search_run

    out = tmp_path / "search"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", MPLBACKEND="Agg")
    env.pop("PYTHONWARNINGS", None)
    proc = subprocess.Popen([sys.executable, "-m", "psgsl_pgm", *GRID, "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)
    runs = out / "runs"
    wait_for(lambda: len(list(runs.glob("*.npz"))) >= 1 and len(children(proc.pid)) >= 2, 300, "written run",
             proc)
    workers = children(proc.pid)
    try:
        os.kill(proc.pid, signal.SIGTERM)
        try:
            _, stderr = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            pytest.fail(f"psgsl search did not end within 30 s of SIGTERM: {proc.communicate()}")
        assert proc.returncode == 143, stderr
        lines = stderr.strip().splitlines()
        assert len(lines) == 1, stderr
        m = re.fullmatch(rf"psgsl search: terminated by SIGTERM: (\d+) of {SEEDS} runs done in (\S+) "
                         r"\(in-progress runs abandoned\); resume with: psgsl search .*", lines[0])
        assert m, lines[0]
        files = sorted(runs.glob("*.npz"))
        assert int(m.group(1)) == len(files) and 1 <= len(files) < SEEDS and m.group(2) == str(runs)
        assert not list(runs.glob(".*.part")), "a temporary file was left behind"
        for f in files:  # every finished file is complete and loadable
            run = load_search_run(f)
            assert run.policy == "tour" and run.time_to_find <= 60.0
        assert gone(workers) == [], "worker processes survived SIGTERM of psgsl search"
    finally:
        kill_survivors(workers)
