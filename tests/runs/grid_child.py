"""A small grid in a process of its own, for the tests that signal or kill a grid's client (SIGTERM, SIGKILL).

``python -m tests.runs.grid_child OUT SECONDS N [--scheduler local]`` runs N jobs of :func:`nap` (each sleeps
SECONDS, then returns its number, its square and a 1000-entry payload) on a grid of two workers, writing
``OUT/rN.json``. When the grid is stopped it prints ``{"done", "total", "immediate", "signum"}`` of the
:class:`~psgsl_pgm.runs._runner.GridInterrupted` as JSON on stdout and exits with 128 + the signal, as ``psgsl``
does. The helpers below read Linux ``/proc``: a process's parent and start time, its children, whether it lives.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]  # the folder holding tests/: the children import tests.runs.grid_child
PAYLOAD = list(range(1000))


def nap(seconds: float, x: int) -> dict:
    """One job: sleep ``seconds`` (a worker busy with a run), then the result. With ``GRID_CHILD_STARTED`` set
    in the environment, first create the file ``$GRID_CHILD_STARTED/<x>``: the run has started."""
    started = os.environ.get("GRID_CHILD_STARTED")
    if started:
        Path(started, str(x)).touch()
    time.sleep(seconds)
    return {"x": x, "y": x * x, "pid": os.getpid(), "payload": PAYLOAD}


def write(result, fh) -> None:
    fh.write(json.dumps(result).encode())


def complete(path) -> bool:
    """Whether ``path`` holds a whole result of :func:`nap` (a cut-short file is not valid JSON)."""
    r = json.loads(Path(path).read_text())
    return r["y"] == r["x"] ** 2 and r["payload"] == PAYLOAD and path.name == f"r{r['x']}.json"


def start(out, seconds: float, n: int, *extra, env=None) -> subprocess.Popen:
    """Start the grid of this module in a new session (a signal to it reaches no other test process)."""
    return subprocess.Popen([sys.executable, "-m", "tests.runs.grid_child", str(out), str(seconds), str(n), *extra],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ if env is None else env), start_new_session=True)


def _stat(pid: int):
    """(state, parent pid, start time in clock ticks) of a process, or None when there is none."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            fields = fh.read().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return fields[0], int(fields[1]), int(fields[19])


def children(pid: int) -> dict:
    """``{child pid: start time}`` of the processes whose parent is ``pid`` now (zombies left out)."""
    out = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            st = _stat(int(entry))
            if st is not None and st[1] == pid and st[0] != "Z":
                out[int(entry)] = st[2]
    return out


def survivors(procs: dict) -> list:
    """The processes of ``{pid: start time}`` still running (a zombie, or a new process that reuses a pid, is
    not a survivor)."""
    alive = []
    for pid, started in procs.items():
        st = _stat(pid)
        if st is not None and st[2] == started and st[0] != "Z":
            alive.append(pid)
    return alive


def kill_survivors(procs: dict) -> None:
    """SIGKILL the processes of ``procs`` ({pid: start time}) still running: a failed test leaves none behind."""
    import signal

    for pid in survivors(procs):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def wait_for(predicate, timeout: float, what: str, proc=None) -> None:
    """Poll ``predicate`` every 20 ms until true; fail naming ``what`` after ``timeout`` s, or when ``proc``
    ended first."""
    import pytest

    t0 = time.monotonic()
    while not predicate():
        if proc is not None and proc.poll() is not None:
            pytest.fail(f"the grid ended before {what}: {proc.communicate()}")
        if time.monotonic() - t0 > timeout:
            if proc is not None:
                proc.kill()
            pytest.fail(f"no {what} within {timeout} s")
        time.sleep(0.02)


def results(out) -> list:
    """The result files of the grid in ``out``."""
    return sorted(Path(out).glob("r*.json"))


def gone(procs: dict, timeout: float = 10.0) -> list:
    """Wait until none of ``procs`` ({pid: start time}) runs; the survivors after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while survivors(procs) and time.monotonic() < deadline:
        time.sleep(0.05)
    return survivors(procs)


def check_terminated(proc, out, workers: dict, n: int, *, quiet: bool = True, timeout: float = 30.0) -> dict:
    """SIGTERM to the client ``proc`` alone; then: exit code 143, a GridInterrupted(immediate, SIGTERM) whose
    count is the result files on disk, every file complete, no temporary file left, nothing on stderr (``quiet``;
    else no traceback), and none of ``workers`` ({pid: start time}) alive. Survivors are killed in any case."""
    import signal

    import pytest

    try:
        os.kill(proc.pid, signal.SIGTERM)
        t0 = time.monotonic()
        try:
            stdout, stderr = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            pytest.fail(f"the grid did not end within {timeout} s of SIGTERM: {proc.communicate()}")
        assert proc.returncode == 128 + signal.SIGTERM == 143, (proc.returncode, stdout, stderr)
        assert time.monotonic() - t0 < timeout
        report, files = json.loads(stdout), results(out)
        want = {"done": len(files), "total": n, "immediate": True, "signum": signal.SIGTERM}
        assert report == want, (report, want, stderr)
        assert 1 <= len(files) < n, f"the grid ended before the signal (or wrote nothing): {len(files)} of {n}"
        assert all(complete(f) for f in files), "a result file is not complete"
        assert not list(Path(out).glob(".*.part")), "a temporary file was left behind"
        assert (stderr == "") if quiet else ("Traceback" not in stderr), stderr
        left = gone(workers)
        assert left == [], f"worker processes survived SIGTERM of their client: {left}"
        return report
    finally:
        kill_survivors(workers)


def terminate_grid(tmp_path, *extra, env=None, n: int = 40, quiet: bool = True, timeout: float = 120.0):
    """Start a grid of ``n`` runs of 0.3 s (``extra``: e.g. ``--scheduler local``), wait for a written run and two
    children, record the children, then :func:`check_terminated`. Returns the report, the children and the
    result folder."""
    out = Path(tmp_path) / "grid"
    proc = start(out, 0.3, n, *extra, env=env)
    wait_for(lambda: len(results(out)) >= 1 and len(children(proc.pid)) >= 2, timeout, "written run", proc)
    workers = children(proc.pid)
    return check_terminated(proc, out, workers, n, quiet=quiet), workers, out


def kill_grid(tmp_path, *extra, env=None, timeout: float = 120.0) -> dict:
    """Start a grid of runs of two minutes, wait until two have started, record the client's children, SIGKILL
    the client alone; assert that every child has ended within 15 s (an orphan would still be in its run) and
    that no result was written. Returns the children."""
    import signal

    out, started = Path(tmp_path) / "grid", Path(tmp_path) / "started"
    started.mkdir()
    proc = start(out, 120.0, 4, *extra, env=dict(os.environ if env is None else env, GRID_CHILD_STARTED=str(started)))
    wait_for(lambda: len(list(started.iterdir())) >= 2, timeout, "two started runs", proc)
    workers = children(proc.pid)
    try:
        assert len(workers) >= 2, workers
        os.kill(proc.pid, signal.SIGKILL)
        assert proc.wait(timeout=10) == -signal.SIGKILL  # not communicate(): an orphan would hold the pipes
        left = gone(workers, timeout=15.0)
        assert left == [], f"workers of a killed client kept running: {left}"
        assert results(out) == []
        return workers
    finally:
        kill_survivors(workers)
        proc.stdout.close()
        proc.stderr.close()


def main(argv=None) -> int:
    from psgsl_pgm.runs._runner import GridInterrupted, GridJob, run_grid

    args = sys.argv[1:] if argv is None else list(argv)
    out, seconds, n = Path(args[0]), float(args[1]), int(args[2])
    scheduler = args[4] if args[3:4] == ["--scheduler"] else None
    jobs = [GridJob(out / f"r{x}.json", nap, (seconds, x)) for x in range(n)]
    try:
        run_grid(jobs, write=write, workers=2, scheduler=scheduler)
    except GridInterrupted as exc:
        print(json.dumps({"done": exc.done, "total": exc.total, "immediate": exc.immediate, "signum": exc.signum}))
        return 128 + exc.signum
    return 0


if __name__ == "__main__":
    sys.exit(main())
