"""One file per finished run (``.npz``, written atomically) — what makes ``psgsl experiment`` resumable."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io._npyfile import READ_ERRORS, load_npy
from ..runs._runner import atomic_write
from ._config import ESTIMATOR_NAMING, source_label, stored_estimator_name
from ._run import RunResult

__all__ = ["read_run_key", "load_run", "run_path", "save_run", "write_run"]


def run_path(directory, source, estimator: str, seed: int) -> Path:
    """``DIR/runs/<source>__<estimator>__seed<seed>.npz``."""
    return Path(directory) / "runs" / f"{source_label(source)}__{estimator}__seed{int(seed)}.npz"


def write_run(result: RunResult, fh) -> None:
    """Write ``result`` as an ``.npz`` archive to the binary file object ``fh`` (see :func:`save_run`)."""
    steps = np.array(sorted(result.snapshots), dtype=np.int64)
    snaps = np.stack([result.snapshots[s] for s in steps]) if len(steps) else np.zeros((0, 3, 0, 0))
    np.savez_compressed(
        fh, source=np.array(result.source), seed=np.array(result.seed), estimator=np.array(result.estimator),
        source_xy=result.source_xy, time=result.time, position=result.position, hit=result.hit,
        error=result.error, spread=result.spread, snapshot_steps=steps, snapshots=snaps,
        region_hit=result.region_hit, region_area=result.region_area, hpd_level=result.hpd_level,
        config=np.array(json.dumps(result.config, sort_keys=True)), estimator_naming=np.array(ESTIMATOR_NAMING),
    )


def save_run(result: RunResult, path) -> Path:
    """Write ``result`` to ``path`` atomically, as a ``.npz`` archive :func:`load_run` reads back.

    Written through :func:`psgsl_pgm.runs._runner.atomic_write` (a temporary file and ``os.replace``), so a
    killed run leaves no file; missing parent folders are made.

    Parameters
    ----------
    result : RunResult
        The run's per-step metrics, snapshots and configuration.
    path : str or path-like
        The file to write (``.npz``).

    Returns
    -------
    path : pathlib.Path
        The file written.

    Raises
    ------
    TypeError
        ``result`` holds a configuration that does not serialise to JSON.
    OSError
        The folder cannot be made or written.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.experiment import RunResult
    >>> def fake_run(seed, n=20):                # per-step metrics of a run, as run_search records them
    ...     rng = np.random.default_rng(seed)
    ...     return RunResult("oven", seed, "infotaxis", np.array([7.5, 0.5]), np.linspace(0, 600, n + 1),
    ...                      rng.uniform(0, 9, (n + 1, 2)), rng.random(n + 1) < 0.2, rng.uniform(0, 5, (n + 1, 3)),
    ...                      rng.uniform(0, 2, (n + 1, 3)), region_hit=rng.random((n + 1, 3)) < 0.6,
    ...                      region_area=rng.uniform(1, 30, (n + 1, 3)), hpd_level=rng.uniform(0, 1, (n + 1, 3)))
    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.experiment import load_run, save_run
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = load_run(save_run(fake_run(4), Path(folder) / "runs" / "a.npz"))
    >>> back.seed, bool(np.array_equal(back.error, fake_run(4).error))
    (4, True)
    """
    return atomic_write(path, write_run, result)


def load_run(path) -> RunResult:
    """Read a run written by :func:`save_run`.

    Parameters
    ----------
    path : str or path-like
        A ``.npz`` run file.

    Returns
    -------
    RunResult
        The run as it was saved (its estimator under its current name when stored under an older one).

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        The file is not a run file written by :func:`save_run` — truncated, corrupt, another archive, missing
        fields — naming the file.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.experiment import RunResult
    >>> def fake_run(seed, n=20):                # per-step metrics of a run, as run_search records them
    ...     rng = np.random.default_rng(seed)
    ...     return RunResult("oven", seed, "infotaxis", np.array([7.5, 0.5]), np.linspace(0, 600, n + 1),
    ...                      rng.uniform(0, 9, (n + 1, 2)), rng.random(n + 1) < 0.2, rng.uniform(0, 5, (n + 1, 3)),
    ...                      rng.uniform(0, 2, (n + 1, 3)), region_hit=rng.random((n + 1, 3)) < 0.6,
    ...                      region_area=rng.uniform(1, 30, (n + 1, 3)), hpd_level=rng.uniform(0, 1, (n + 1, 3)))
    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.experiment import load_run, save_run
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     run = load_run(save_run(fake_run(1), Path(folder) / "run.npz"))
    >>> run.source, run.estimator, run.error.shape
    ('oven', 'infotaxis', (21, 3))
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such run file")
    try:
        with load_npy(path, str(path)) as z:
            steps = z["snapshot_steps"]
            snaps = {int(s): z["snapshots"][i] for i, s in enumerate(steps)}
            estimator = stored_estimator_name(str(z["estimator"]), _naming(z))
            return RunResult(str(z["source"]), int(z["seed"]), estimator, z["source_xy"], z["time"],
                             z["position"], z["hit"], z["error"], z["spread"], snaps, json.loads(str(z["config"])),
                             z["region_hit"], z["region_area"], z["hpd_level"])
    except (*READ_ERRORS, KeyError, TypeError) as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise ValueError(f"{path} is not a run file written by psgsl ({reason}); delete it to recompute the run") from None


def _naming(z):
    """The file's ``estimator_naming`` (None for a run stored before the field existed)."""
    return int(z["estimator_naming"]) if "estimator_naming" in z.files else None


def read_run_key(path, *, kind: str = "run") -> dict | None:
    """The run key (:mod:`psgsl_pgm.runs._key`) stored with a run (of the experiment or the closed loop), read
    without loading its arrays; None for a run stored without one. ValueError naming the file if it is not a
    ``kind`` file written by psgsl, or if it is a run of the analytic-plume estimator stored under the name
    ``pmfs`` (a grid would otherwise take it for a run of PMFS as published)."""
    path = Path(path)
    try:
        with load_npy(path, str(path)) as z:
            config = json.loads(str(z["config"]))
            legacy = "estimator" in z.files and str(z["estimator"]) != stored_estimator_name(str(z["estimator"]),
                                                                                              _naming(z))
    except (*READ_ERRORS, KeyError, TypeError) as exc:
        raise ValueError(f"{path} is not a {kind} file written by psgsl ({' '.join(str(exc).split())}); delete it "
                         "to recompute the run") from None
    if legacy:
        raise ValueError(f"{path} is a run of the analytic-plume estimator stored when it was named 'pmfs'; "
                         "rename it with __analytic-plume__ in place of __pmfs__, or delete it to recompute the run")
    key = config.get("key") if isinstance(config, dict) else None
    return key if isinstance(key, dict) else None
