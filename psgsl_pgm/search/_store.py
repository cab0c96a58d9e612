"""One ``.npz`` file per finished closed-loop run, written atomically — what makes ``psgsl search`` resumable."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..experiment._config import ESTIMATOR_NAMING, source_label, stored_estimator_name
from ..experiment._store import _naming
from ..experiment._store import read_run_key as _read_run_key
from ..io._npyfile import READ_ERRORS, load_npy
from ..runs._runner import atomic_write
from ._settings import SearchRun

__all__ = ["read_run_key", "load_search_run", "save_search_run", "search_run_path", "write_search_run"]

_ARRAYS = ("source_xy", "time", "position", "heading", "hit", "path_length", "error", "map_error", "spread",
           "region_area", "region_hit", "hpd_level", "path", "final_posterior")
#: The declaration's scalars (:class:`SearchRun`), written by every run and absent from runs stored before
#: declarations (read as "no declaration": those runs ended with ``end="reach"``).
_DECLARATION = ("declared", "declared_xy", "time_to_declare", "declared_error", "declared_correct", "declared_mass")
#: The gas belief of a run whose gas the robot was not told (:class:`SearchRun`); written by those runs only.
_GAS = ("gas", "gas_names", "gas_probs")
#: The several-source fields (:class:`SearchRun`); written by runs with several sources or a robot that declares
#: them one by one only (runs without them read as one source).
_SEVERAL = ("sources_xy", "declarations", "declared_source", "more_probability")


def search_run_path(directory, source, policy: str, variant: str, estimator: str, seed: int) -> Path:
    """``DIR/runs/<source>__<policy>__<variant>__<estimator>__seed<seed>.npz``."""
    return Path(directory) / "runs" / f"{source_label(source)}__{policy}__{variant}__{estimator}__seed{int(seed)}.npz"


def write_search_run(run: SearchRun, fh) -> None:
    """Write ``run`` as an ``.npz`` archive to the binary file object ``fh`` (the grid runner's writer)."""
    np.savez_compressed(
        fh, source=np.array(run.source), seed=np.array(run.seed), policy=np.array(run.policy),
        variant=np.array(run.variant), estimator=np.array(run.estimator), found=np.array(run.found),
        time_to_find=np.array(run.time_to_find), geodesic=np.array(run.geodesic), driven=np.array(run.driven),
        config=np.array(json.dumps(run.config, sort_keys=True)), estimator_naming=np.array(ESTIMATOR_NAMING),
        **{k: getattr(run, k) for k in _ARRAYS},
        **{k: np.asarray(getattr(run, k)) for k in _DECLARATION},
        **({k: np.asarray(getattr(run, k)) for k in _GAS} if run.gas_unknown else {}),
        **({k: np.asarray(getattr(run, k)) for k in _SEVERAL} if run.several else {}))


def save_search_run(run: SearchRun, path) -> Path:
    """Write ``run`` to ``path`` atomically (:func:`psgsl_pgm.runs._runner.atomic_write`).

    Parameters
    ----------
    run : SearchRun
        The finished closed-loop run (:func:`psgsl_pgm.search.run_closed_loop`).
    path : str or os.PathLike
        The ``.npz`` file to write; it appears complete or not at all.

    Returns
    -------
    pathlib.Path
        The path written.

    Examples
    --------
    A round trip through :func:`load_search_run`:

    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import SearchConfig, load_search_run, run_closed_loop, save_search_run
    >>> run = run_closed_loop("oven", 0, "greedy", "olfaction", config=ExperimentConfig(warm_up=5.0),
    ...                       search=SearchConfig(time_budget=20.0))
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = load_search_run(save_search_run(run, Path(folder) / "run.npz"))
    >>> back.policy, back.variant, back.time_to_find == run.time_to_find
    ('greedy', 'olfaction', True)
    """

    return atomic_write(path, write_search_run, run)


def load_search_run(path) -> SearchRun:
    """Read a run written by :func:`save_search_run` (ValueError naming the file if it is not one).

    Parameters
    ----------
    path : str or os.PathLike
        An ``.npz`` file written by :func:`save_search_run` (or by the grid runner, :func:`run_search_grid`).
        Runs stored before declarations read as runs without one (``end="reach"``).

    Returns
    -------
    SearchRun
        The run, with its configuration.

    Raises
    ------
    ValueError
        The file cannot be read, or is not a search run file (a field is missing or of the wrong kind).

    Examples
    --------
    A round trip through :func:`save_search_run`:

    >>> import tempfile
    >>> from pathlib import Path
    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import SearchConfig, load_search_run, run_closed_loop, save_search_run
    >>> run = run_closed_loop("oven", 0, "greedy", "olfaction", config=ExperimentConfig(warm_up=5.0),
    ...                       search=SearchConfig(time_budget=20.0))
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = load_search_run(save_search_run(run, Path(folder) / "run.npz"))
    ...     _ = (Path(folder) / "notes.npz").write_text("not a run")
    ...     try:
    ...         load_search_run(Path(folder) / "notes.npz")
    ...     except ValueError as err:
    ...         print("is not a search run file" in str(err))
    True
    >>> back.source, back.seed, bool((back.path == run.path).all())
    ('oven', 0, True)
    """
    path = Path(path)
    try:
        with load_npy(path, str(path)) as z:
            arrays = {k: z[k] for k in _ARRAYS}
            names = set(z.files)
            if names & set(_DECLARATION):  # runs stored before declarations have none of them
                arrays |= {k: z[k] for k in _DECLARATION}
                arrays |= {k: bool(arrays[k]) for k in ("declared", "declared_correct")}
                arrays |= {k: float(arrays[k]) for k in ("time_to_declare", "declared_error", "declared_mass")}
            if "gas_probs" in names:  # a run whose gas the robot was not told
                arrays |= {"gas": str(z["gas"]), "gas_names": tuple(str(g) for g in z["gas_names"]),
                           "gas_probs": z["gas_probs"]}
            if "declarations" in names:  # several sources
                arrays |= {k: z[k] for k in _SEVERAL}
            return SearchRun(str(z["source"]), int(z["seed"]), str(z["policy"]), str(z["variant"]),
                             stored_estimator_name(str(z["estimator"]), _naming(z)), arrays.pop("source_xy"),
                             bool(z["found"]),
                             float(z["time_to_find"]), float(z["geodesic"]), float(z["driven"]),
                             config=json.loads(str(z["config"])), **arrays)
    except (*READ_ERRORS, KeyError, TypeError) as exc:
        raise ValueError(f"{path} is not a search run file written by psgsl ({' '.join(str(exc).split())})") from None


def read_run_key(path) -> dict | None:
    """The run key stored with a closed-loop run (:func:`psgsl_pgm.experiment._store.read_run_key`)."""
    return _read_run_key(path, kind="search run")
