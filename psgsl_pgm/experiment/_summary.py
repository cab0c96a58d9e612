"""Aggregation over runs: progress-aligned curves, ``summary.json``, the per-step CSV and the printed table."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from ..io._json import json_safe
from ..runs._runner import atomic_write
from ._config import VARIANTS
from ._metrics import calibration_summary, mean_ci

__all__ = ["EARLY", "aligned", "format_table", "summarize", "write_csv", "write_summary"]

#: The "early" point of the search: a quarter of the tour (paper Fig. error-chart's initial phase).
EARLY = 0.25


def aligned(runs, name: str, grid) -> np.ndarray:
    """(runs, len(grid), 3) metric ``name`` ("error" or "spread") at search progress ``grid`` ∈ [0, 1].

    Progress of step j in a run of n stops is j / n (tours differ by a few stops between seeds, because the
    furniture moves); values are linearly interpolated between steps.
    """
    grid = np.asarray(grid, dtype=np.float64)
    out = np.empty((len(runs), len(grid), len(VARIANTS)))
    for r, run in enumerate(runs):
        values = getattr(run, name)
        progress = np.arange(len(values)) / (len(values) - 1)
        for v in range(len(VARIANTS)):
            out[r, :, v] = np.interp(grid, progress, values[:, v])
    return out


def summarize(runs) -> dict:
    """Mean and 95 % CI over runs of the early and final error and spread, and the calibration of the 90 % region.

    Per variant: the Student-t interval over runs. Errors and spreads are distances (≥ 0): their intervals are the
    t-intervals intersected with [0, ∞) (``mean_ci(..., lower=0)``, which keeps the coverage). Paired
    differences can be negative and keep the plain t-interval.

    Parameters
    ----------
    runs : sequence of RunResult
        Runs of one source and estimator (:func:`run_search`, :func:`load_run`), each with the per-step error,
        spread and calibration arrays.

    Returns
    -------
    dict
        ``{"n_runs": n, "seeds": [...], "early_progress": 0.25, <variant>: {"early_error": {"mean", "ci95"},
        "final_error": ..., "mean_error": ..., "early_spread": ..., "final_spread": ..., "coverage90": {"quarter",
        "half", "three_quarters", "final"}, "region_area90": {"mean", "ci95"}, "hpd_level": {"median", "mean"}},
        "paired": {...}}`` (the calibration keys: :func:`calibration_summary`).
        ``mean_error`` is the error averaged over the whole search (101 equally spaced progress points: the
        area under the error curve, small when the error falls early). ``paired`` holds the mean and CI of
        per-run *differences* (e.g. olfaction − semantics), which is the right test of "lower than" when all
        variants share one observation stream.

    Raises
    ------
    ValueError
        ``runs`` is empty, or a run's metrics are not finite.

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
    >>> from psgsl_pgm.experiment import summarize
    >>> s = summarize([fake_run(0), fake_run(1), fake_run(2)])
    >>> s["n_runs"], s["seeds"], sorted(s["olfaction"]["final_error"])
    (3, [0, 1, 2], ['ci95', 'mean'])
    """
    runs = list(runs)
    if not runs:
        raise ValueError("summarize needs at least one run")
    err = aligned(runs, "error", [EARLY, 1.0])  # (runs, 2, 3)
    spr = aligned(runs, "spread", [EARLY, 1.0])
    area = aligned(runs, "error", np.linspace(0.0, 1.0, 101)).mean(axis=1)  # (runs, 3)
    out = {"n_runs": len(runs), "seeds": sorted({r.seed for r in runs}), "early_progress": EARLY}
    for v, name in enumerate(VARIANTS):
        out[name] = {
            "early_error": mean_ci(err[:, 0, v], lower=0.0),  # distances: intervals cut at 0
            "final_error": mean_ci(err[:, 1, v], lower=0.0),
            "mean_error": mean_ci(area[:, v], lower=0.0),
            "early_spread": mean_ci(spr[:, 0, v], lower=0.0),
            "final_spread": mean_ci(spr[:, 1, v], lower=0.0),
            **calibration_summary(runs, variant=v),
        }
    pairs = (("olfaction", "semantics"), ("olfaction", "semantics+rooms"), ("semantics", "semantics+rooms"))
    out["paired"] = {
        f"{a} - {b}": {
            "early_error": mean_ci(err[:, 0, VARIANTS.index(a)] - err[:, 0, VARIANTS.index(b)]),
            "final_error": mean_ci(err[:, 1, VARIANTS.index(a)] - err[:, 1, VARIANTS.index(b)]),
            "mean_error": mean_ci(area[:, VARIANTS.index(a)] - area[:, VARIANTS.index(b)]),
        }
        for a, b in pairs
    }
    return out


def write_summary(summary: dict, path) -> Path:
    """``summary`` as strict JSON (NaN -> null) at ``path``, written atomically."""
    text = json.dumps(json_safe(summary), indent=2, allow_nan=False) + "\n"
    return atomic_write(path, lambda t, fh: fh.write(t.encode("utf-8")), text)


def write_csv(runs, path) -> Path:
    """Long-format per-step metrics: one row per run, step and variant (written atomically)."""
    return atomic_write(path, _write_csv_rows, list(runs))


def _write_csv_rows(runs, raw) -> None:
    fh = io.TextIOWrapper(raw, encoding="utf-8", newline="")
    try:
        w = csv.writer(fh)
        w.writerow(["source", "estimator", "seed", "step", "progress", "time_s", "x", "y", "hit", "variant",
                    "error_m", "spread_m", "region90_hit", "region90_area_m2", "hpd_level"])
        for run in runs:
            n = run.n_steps
            for j in range(n + 1):
                for v, name in enumerate(VARIANTS):
                    w.writerow([run.source, run.estimator, run.seed, j, f"{j / n:.6f}", f"{run.time[j]:.3f}",
                                f"{run.position[j, 0]:.3f}", f"{run.position[j, 1]:.3f}", int(run.hit[j]), name,
                                f"{run.error[j, v]:.6f}", f"{run.spread[j, v]:.6f}", int(run.region_hit[j, v]),
                                f"{run.region_area[j, v]:.6g}", f"{run.hpd_level[j, v]:.6f}"])
    finally:
        fh.flush()
        fh.detach()  # the runner's file: it fsyncs and closes it


def _fmt(stat: dict) -> str:
    lo, hi = stat["ci95"]
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return f"{stat['mean']:5.2f}"
    return f"{stat['mean']:5.2f} [{lo:5.2f}, {hi:5.2f}]"


def format_table(summary: dict, *, title: str = "") -> str:
    """The summary as a plain-text table (metres; mean [95 % CI] over runs), then the calibration columns.

    Parameters
    ----------
    summary : dict
        What :func:`summarize` returns: ``n_runs``, ``seeds`` and one entry per variant of :data:`VARIANTS`.
    title : str, default "", keyword-only
        A first line above the table (none when empty).

    Returns
    -------
    table : str
        Lines of fixed-width columns, without a trailing newline.

    Raises
    ------
    KeyError
        ``summary`` lacks a key :func:`summarize` writes (a variant, ``n_runs``, an error or calibration entry).

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
    >>> from psgsl_pgm.experiment import format_table, summarize
    >>> print(format_table(summarize([fake_run(0), fake_run(1)]), title="two runs").splitlines()[0])
    two runs
    """
    head = (f"{'variant':<16} {'error at 1/4':>21} {'final error':>21} {'mean error':>21} "
            f"{'final spread':>21}")
    lines = [title] if title else []
    lines += [f"{summary['n_runs']} runs (seeds {summary['seeds']}); metres, mean [95 % CI: Student t, cut at 0]",
              head, "-" * len(head)]
    for name in VARIANTS:
        s = summary[name]
        lines.append(f"{name:<16} {_fmt(s['early_error']):>21} {_fmt(s['final_error']):>21} "
                     f"{_fmt(s['mean_error']):>21} {_fmt(s['final_spread']):>21}")
    head = (f"{'variant':<16} {'90 % region covers the source at 1/4, 1/2, 3/4, end':>52} "
            f"{'final area, m²':>21} {'HPD level: median':>18}")
    lines += ["", "calibration: runs whose 90 % credible region holds the source's cell (fraction); the source "
              "cell's HPD level", head, "-" * len(head)]
    for name in VARIANTS:
        s = summary[name]
        cov = "  ".join(f"{s['coverage90'][k]:.2f}" for k in ("quarter", "half", "three_quarters", "final"))
        lines.append(f"{name:<16} {cov:>52} {_fmt(s['region_area90']):>21} {s['hpd_level']['median']:18.3f}")
    return "\n".join(lines)
