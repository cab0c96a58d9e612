"""Reliability of the hit model: predicted P(hit) against the observed hit frequency, binned."""

from __future__ import annotations

import numpy as np

from ..io._output import write_file_atomically

__all__ = ["plot_reliability", "reliability_table"]


def reliability_table(predicted, hits, *, bins=(0.0, 0.02, 0.05, 0.1, 0.2, 0.4, 0.6, 0.8, 1.0)) -> dict:
    """Bin readings by their predicted P(hit) and count the hits in each bin.

    Parameters
    ----------
    predicted : (n,) array_like of float
        The hit model's P(hit) of each reading, in [0, 1] (e.g. under the true source, on held-out runs).
    hits : (n,) array_like of bool
        What the sensor read.
    bins : (B + 1,) sequence of float, keyword-only
        Increasing bin edges covering [0, 1] (the last bin is closed).

    Returns
    -------
    dict
        ``edges`` (B + 1,), and per bin: ``n`` readings, ``hits``, ``mean_predicted`` (NaN where empty),
        ``observed`` = hits / n and its 95 % Wilson interval ``lower``, ``upper`` (NaN where empty).

    Raises
    ------
    TypeError
        ``hits`` are not booleans.
    ValueError
        ``predicted`` are not probabilities of ``hits``' shape, or ``bins`` are not increasing edges covering
        [0, 1].

    Examples
    --------
    >>> t = reliability_table([0.1, 0.1, 0.9, 0.9], [False, True, True, True], bins=(0.0, 0.5, 1.0))
    >>> t["n"].tolist(), t["observed"].tolist()
    ([2, 2], [0.5, 1.0])
    """
    from ._metrics import wilson_interval

    p = np.asarray(predicted, dtype=np.float64).ravel()
    g = np.asarray(hits).ravel()
    if g.dtype != bool:
        raise TypeError(f"hits must be booleans, got dtype {g.dtype}")
    if p.shape != g.shape or not np.isfinite(p).all() or (p < 0).any() or (p > 1).any():
        raise ValueError(f"predicted must be (n,) probabilities in [0, 1] like hits (n = {g.size}), got shape {p.shape}")
    edges = np.asarray(bins, dtype=np.float64)
    if edges.ndim != 1 or edges.size < 2 or not (np.diff(edges) > 0).all() or edges[0] > 0 or edges[-1] < 1:
        raise ValueError(f"bins must be increasing edges covering [0, 1], got {list(bins)}")
    idx = np.clip(np.searchsorted(edges, p, side="right") - 1, 0, edges.size - 2)
    n = np.bincount(idx, minlength=edges.size - 1)
    k = np.bincount(idx, weights=g.astype(np.float64), minlength=edges.size - 1).astype(np.int64)
    s = np.bincount(idx, weights=p, minlength=edges.size - 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_p = np.where(n > 0, s / n, np.nan)
        observed = np.where(n > 0, k / n, np.nan)
    ci = np.array([wilson_interval(int(a), int(b)) for a, b in zip(k, n)]).reshape(-1, 2)  # a handful of bins
    return {"edges": edges, "n": n, "hits": k, "mean_predicted": mean_p, "observed": observed,
            "lower": ci[:, 0], "upper": ci[:, 1]}


def plot_reliability(curves: dict, path=None, *, title: str = "Reliability of the hit model"):
    """Reliability diagram of the hit model: observed hit frequency against mean predicted P(hit), per bin.

    One curve per entry of ``curves``, each point with its 95 % Wilson interval and the number of readings in its
    bin beside it, and the diagonal (perfect calibration) for reference.

    Parameters
    ----------
    curves : dict of str to dict
        ``{label: reliability_table(...) result}``: per bin ``n``, ``mean_predicted``, ``observed``, ``lower``
        and ``upper`` (:func:`reliability_table`). Bins without readings are left out.
    path : str or path-like, optional
        Where to save the figure as PNG (written atomically); not saved when None.
    title : str, default "Reliability of the hit model", keyword-only
        The axes' title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (6 × 5.2 in), left open for the caller.

    Raises
    ------
    KeyError
        A curve lacks a key of :func:`reliability_table`'s result.
    OSError
        ``path`` cannot be written.

    Examples
    --------
    >>> from psgsl_pgm.experiment import plot_reliability, reliability_table
    >>> t = reliability_table([0.1, 0.1, 0.9, 0.9], [False, True, True, True], bins=(0.0, 0.5, 1.0))
    >>> fig = plot_reliability({"toy": t}, title="a toy hit model")
    >>> fig.axes[0].get_title()
    'a toy hit model'
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.0, 5.2), constrained_layout=True)
    ax.plot([0, 1], [0, 1], color="0.6", lw=1, ls="--", label="perfect calibration")
    for i, (label, t) in enumerate(curves.items()):
        ok = t["n"] > 0
        x, y = t["mean_predicted"][ok], t["observed"][ok]
        err = np.vstack([y - t["lower"][ok], t["upper"][ok] - y])
        shift = (i - (len(curves) - 1) / 2) * 0.006
        ax.errorbar(x + shift, y, yerr=err, marker="o", ms=4, capsize=3, lw=1.2, label=label)
        for xx, yy, nn in zip(x, y, t["n"][ok]):
            ax.annotate(f"{nn}", (xx + shift, yy), textcoords="offset points", xytext=(5, -10 + 14 * i), fontsize=7)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("predicted P(hit | true source), bin mean")
    ax.set_ylabel("observed hit frequency (95 % Wilson interval)")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize=8)
    if path is not None:
        write_file_atomically(path, lambda fh: fig.savefig(fh, format="png", dpi=130), option="path")
    return fig
