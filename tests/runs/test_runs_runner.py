"""The generic grid runner: one atomic file per job, resumable, refusals, failures, dead workers, Ctrl-C."""

from __future__ import annotations

import json
import os
import signal

import pytest

from psgsl_pgm.runs._runner import GridInterrupted, GridJob, atomic_write, run_grid


def _square(x):
    return {"x": x, "y": x * x, "pid": os.getpid()}


def _write(result, fh):
    fh.write(json.dumps(result).encode())


def _read(path):
    return json.loads(path.read_text())


def _fail_on(bad, x):
    if x == bad:
        raise ValueError(f"run {x} failed")
    return _square(x)


def _die_once(marker, x):
    """Kill the worker process the first time (as the OOM killer would), succeed when retried."""
    if not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(3)
    return _square(x)


def _interrupt(times, x):
    """Press Ctrl-C ``times`` times while "running" (in-process backend)."""
    for _ in range(times):
        os.kill(os.getpid(), signal.SIGINT)
    return _square(x)


def _jobs(tmp_path, fn=_square, n=4, extra=()):
    return [GridJob(tmp_path / f"r{x}.json", fn, (*extra, x)) for x in range(n)]


@pytest.mark.parametrize("workers", [1, 2])
def test_every_job_written_once_and_a_rerun_recomputes_nothing(tmp_path, workers):
    jobs = _jobs(tmp_path)
    report = run_grid(jobs, write=_write, workers=workers)
    assert (report.total, report.done_before, report.computed) == (4, 0, 4)
    for x in range(4):
        assert _read(tmp_path / f"r{x}.json")["y"] == x * x
    pids = {_read(j.path)["pid"] for j in jobs}
    assert (pids == {os.getpid()}) == (workers == 1)  # workers=1 runs here, the pool elsewhere
    stamps = {j.path: j.path.stat().st_mtime_ns for j in jobs}
    (tmp_path / "r2.json").unlink()
    report = run_grid(jobs, write=_write, workers=workers)
    assert (report.done_before, report.computed) == (3, 1)
    assert all(j.path.stat().st_mtime_ns == stamps[j.path] for j in jobs if j.path.name != "r2.json")
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"r{x}.json" for x in range(4)]  # no temporaries


def test_check_done_refuses_before_anything_runs(tmp_path):
    jobs = _jobs(tmp_path)
    (tmp_path / "r1.json").write_text("{}")

    def check(job):
        if _read(job.path) != {"x": 1}:
            raise ValueError(f"{job.path} was computed with another configuration")

    with pytest.raises(ValueError, match="r1.json was computed with another configuration"):
        run_grid(jobs, write=_write, check_done=check, workers=1)
    assert not (tmp_path / "r0.json").exists()


def test_bad_arguments_are_refused(tmp_path):
    job = GridJob(tmp_path / "a.json", _square, (1,))
    with pytest.raises(ValueError, match="distinct result paths"):
        run_grid([job, GridJob(tmp_path / "a.json", _square, (2,))], write=_write)
    with pytest.raises(ValueError, match="workers must be a positive integer, got 0"):
        run_grid([job], write=_write, workers=0)
    with pytest.raises(ValueError, match="scheduler must be 'local' or a dask scheduler address"):
        run_grid([job], write=_write, scheduler=" ")
    with pytest.raises(TypeError, match="GridJob"):
        run_grid([(tmp_path / "a.json", _square)], write=_write)
    with pytest.raises(TypeError, match="fn must be callable"):
        GridJob(tmp_path / "a.json", "not a function")


def test_a_failing_run_raises_after_keeping_the_finished_ones(tmp_path):
    jobs = _jobs(tmp_path, _fail_on, n=3, extra=(1,))
    with pytest.raises(ValueError, match="run 1 failed"):
        run_grid(jobs, write=_write, workers=1)
    assert _read(tmp_path / "r0.json")["y"] == 0 and not (tmp_path / "r1.json").exists()
    assert not (tmp_path / "r2.json").exists()  # nothing new is started after a failure


def test_a_dead_worker_process_is_replaced_and_its_run_retried(tmp_path):
    marker = tmp_path / "died"
    jobs = [GridJob(tmp_path / "r0.json", _die_once, (str(marker), 5)), GridJob(tmp_path / "r1.json", _square, (6,))]
    report = run_grid(jobs, write=_write, workers=2)
    assert marker.exists() and report.computed == 2
    assert _read(tmp_path / "r0.json")["y"] == 25 and _read(tmp_path / "r1.json")["y"] == 36


def test_first_ctrl_c_finishes_the_run_in_progress_then_stops(tmp_path):
    jobs = _jobs(tmp_path, _interrupt, n=3, extra=(1,))
    before = signal.getsignal(signal.SIGINT)  # default_int_handler, or SIG_IGN under a background shell
    with pytest.raises(GridInterrupted) as exc:
        run_grid(jobs, write=_write, workers=1)
    assert (exc.value.done, exc.value.total, exc.value.immediate) == (1, 3, False)
    assert [p.name for p in tmp_path.iterdir()] == ["r0.json"]
    assert signal.getsignal(signal.SIGINT) is before  # the handler is restored


def test_second_ctrl_c_abandons_the_run_in_progress_and_corrupts_nothing(tmp_path):
    (tmp_path / "r0.json").write_text(json.dumps(_square(0)))
    jobs = _jobs(tmp_path, _interrupt, n=3, extra=(2,))
    with pytest.raises(GridInterrupted) as exc:
        run_grid(jobs, write=_write, workers=1)
    assert (exc.value.done, exc.value.total, exc.value.immediate) == (1, 3, True)
    assert [p.name for p in tmp_path.iterdir()] == ["r0.json"]
    assert isinstance(exc.value, KeyboardInterrupt)  # a generic `except Exception` does not swallow it


def test_atomic_write_leaves_nothing_when_the_writer_fails(tmp_path):
    def broken(result, fh):
        fh.write(b"half")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        atomic_write(tmp_path / "a.npz", broken, None)
    assert list(tmp_path.iterdir()) == []
    atomic_write(tmp_path / "a.npz", lambda r, fh: fh.write(r), b"whole")
    assert (tmp_path / "a.npz").read_bytes() == b"whole"
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "a.npz").stat().st_mode & 0o777 == 0o666 & ~umask  # as open() would create it


# ---------------------------------------------------------------------------------------------- grid_folder


def _read_key(path):
    return json.loads(path.read_text()).get("key")


def _stored(out, name, key):
    (out / "runs").mkdir(parents=True, exist_ok=True)
    (out / "runs" / name).write_text(json.dumps({"key": key}))


def test_grid_folder_refuses_other_keys_naming_each_setting_and_creates_nothing(tmp_path):
    from psgsl_pgm.runs._runner import grid_folder

    out = tmp_path / "out"
    _stored(out, "a.json", {"speed": 0.2, "map": "sha256 " + "1a2b" * 16})
    before = sorted(p.name for p in out.rglob("*"))
    with pytest.raises(ValueError) as exc:
        with grid_folder(out, {"speed": 0.6, "map": "sha256 " + "9f8e" * 16}, read_key=_read_key, pattern="*.json"):
            raise AssertionError("entered a folder with runs of other settings")
    msg = str(exc.value)
    assert "speed: 0.2 → 0.6" in msg and "map: sha256 1a2b1a2b1a2b… → sha256 9f8e9f8e9f8e…" in msg
    assert "\n" not in msg and "a.json" in msg
    assert sorted(p.name for p in out.rglob("*")) == before  # no lock file, nothing
    (out / "runs" / "b.json").write_text("{}")  # a run without a key cannot be checked: refused as well
    with pytest.raises(ValueError, match="b.json was stored without a run key"):
        with grid_folder(out, {"speed": 0.2, "map": "sha256 " + "1a2b" * 16}, read_key=_read_key,
                         pattern="*.json"):
            pass
    # a folder that does not exist is created only once the checks pass
    fresh = tmp_path / "a" / "b"
    with grid_folder(fresh, {"speed": 0.2}, read_key=_read_key, pattern="*.json") as folder:
        assert folder == fresh and (fresh / "runs").is_dir()


def test_grid_folder_is_one_process_at_a_time_and_removes_temporaries(tmp_path):
    from psgsl_pgm.runs._runner import grid_folder

    out = tmp_path / "out"
    _stored(out, "a.json", {"x": 1})
    for name in ("runs/.a.json.1234abcd.part", "summary.json.part", "runs.csv.part", ".psgsl-probe-xyz"):
        (out / name).write_text("half")
    (out / "group").mkdir()
    (out / "group" / "summary.json.part").write_text("half")
    keep = {out / "runs" / "a.json", out / "notes.txt"}
    (out / "notes.txt").write_text("mine")
    with grid_folder(out, {"x": 1}, read_key=_read_key, pattern="*.json"):
        assert {p for p in out.rglob("*") if p.is_file()} == keep | {out / ".lock"}
        assert (out / ".lock").read_text().strip() == str(os.getpid())
        with pytest.raises(ValueError) as exc:  # a second opening (another open file description) is refused
            with grid_folder(out, {"x": 1}, read_key=_read_key, pattern="*.json"):
                pass
        assert str(exc.value) == (f"--out {out} is in use by another psgsl process (pid {os.getpid()}); wait for "
                                  "it to end, or use another --out")
    with grid_folder(out, {"x": 1}, read_key=_read_key, pattern="*.json"):  # released at the end of the block
        pass


def test_check_output_dir_creates_nothing(tmp_path):
    from psgsl_pgm.io._output import check_output_dir

    assert check_output_dir(tmp_path / "a" / "b", subdirs=("runs",)) == tmp_path / "a" / "b"
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "f").write_text("")
    with pytest.raises(ValueError, match="is not a directory"):
        check_output_dir(tmp_path / "f" / "out")
    with pytest.raises(ValueError, match="exists and is not a directory"):
        check_output_dir(tmp_path / "f")


def test_quiet_distributed_holds_back_warnings_during_the_block_and_restores_every_level():
    import logging

    from psgsl_pgm.runs._runner import _quiet_distributed

    records = []

    class Keep(logging.Handler):
        def emit(self, record):
            records.append((record.name, record.levelname))

    top = logging.getLogger("distributed")
    own = logging.getLogger("distributed.psgsl_test_own_level")  # a level of its own, as dask's config sets some
    inherits = logging.getLogger("distributed.psgsl_test_nanny")  # NOTSET: inherits from "distributed"
    handler = Keep(level=logging.DEBUG)
    top_level, own_level = top.level, own.level
    top.addHandler(handler)
    try:
        top.setLevel(logging.INFO)
        own.setLevel(logging.WARNING)
        with _quiet_distributed():
            inherits.warning("Worker process still alive after 4.0 seconds, killing")
            own.warning("held back too")
            own.error("an error still shows")
            inherits.critical("and so does this")
        assert records == [("distributed.psgsl_test_own_level", "ERROR"), ("distributed.psgsl_test_nanny", "CRITICAL")]
        assert (top.level, own.level, inherits.level) == (logging.INFO, logging.WARNING, logging.NOTSET)
        records.clear()
        inherits.info("shown again after the block")
        own.warning("so is this")
        assert records == [("distributed.psgsl_test_nanny", "INFO"), ("distributed.psgsl_test_own_level", "WARNING")]
    finally:
        top.removeHandler(handler)
        top.setLevel(top_level)
        own.setLevel(own_level)


def _blas_threads(x):
    """The threads of every BLAS/OpenMP library loaded in the process running the job, and its pid."""
    from threadpoolctl import threadpool_info

    return {"x": x, "threads": sorted({int(d["num_threads"]) for d in threadpool_info()}), "pid": os.getpid()}


@pytest.mark.parametrize("workers", [1, 2])
def test_every_run_computes_with_one_blas_thread_in_or_out_of_this_process(tmp_path, workers):
    """A threaded BLAS splits its sums differently (other last bits) and spins two threads on small sums: the
    runs of ``workers=1`` (here, in this process) get the one thread the pool's workers get."""
    pytest.importorskip("threadpoolctl")
    from threadpoolctl import threadpool_info, threadpool_limits

    with threadpool_limits(limits=2):  # this process as a user's shell leaves it: every core
        before = sorted({int(d["num_threads"]) for d in threadpool_info()})
        run_grid(_jobs(tmp_path, _blas_threads, n=2), write=_write, workers=workers)
        after = sorted({int(d["num_threads"]) for d in threadpool_info()})
    results = [_read(tmp_path / f"r{x}.json") for x in range(2)]
    assert all(r["threads"] == [1] for r in results), results
    assert after == before  # the limit is lifted after the runs
    assert (results[0]["pid"] == os.getpid()) == (workers == 1)


def test_without_threadpoolctl_a_single_worker_runs_here_on_the_process_s_blas(monkeypatch, tmp_path):
    """threadpoolctl (the sim extra) is what holds this process's loaded BLAS to one thread; without it the runs
    still happen here, as the Ctrl-C contract of ``workers=1`` says, on the BLAS threads the process has."""
    import sys

    monkeypatch.setitem(sys.modules, "threadpoolctl", None)  # import threadpoolctl -> ImportError
    report = run_grid(_jobs(tmp_path, n=2), write=_write, workers=1)
    assert {_read(tmp_path / f"r{x}.json")["pid"] for x in range(2)} == {os.getpid()}
    assert report
