r"""The environment's observation arrays, computed from the robot's side only (its posterior, pose and map).

* :func:`downsample_belief` — the posterior p(s | ·) over the H × W cells of the map as the probability mass of each
  of S × S blocks (a fixed size whatever the house).
* :func:`candidate_table` — the next stops the planner offers (:meth:`psgsl_pgm.search.FreeSpace.candidates`: the
  ``spacing`` lattice within the horizon and the ``far_spacing`` lattice beyond it), ranked by the probability of
  finding the source there per second of travel and cut to a fixed number of slots, with one row of features each.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CANDIDATE_FEATURES", "Candidates", "candidate_table", "downsample_belief"]

#: The columns of the candidate table (:func:`candidate_table`).
CANDIDATE_FEATURES = ("dx", "dy", "drive", "p_found", "valid")


def downsample_belief(posterior, size: int) -> np.ndarray:
    """The mass of the posterior in each of ``size`` × ``size`` blocks of the map.

    Row r of the map falls in block row ⌊r·S/H⌋, column c in block column ⌊c·S/W⌋, so every cell belongs to
    exactly one block and the blocks' masses sum to the posterior's (1); a map smaller than S along an axis
    leaves some blocks empty.

    Parameters
    ----------
    posterior : (H, W) array_like
        A probability map (non-negative, finite).
    size : int
        S.

    Returns
    -------
    (S, S) ndarray of float64

    Raises
    ------
    ValueError
        ``posterior`` is not a finite, non-negative (H, W) map, or ``size`` is not an integer >= 1.

    Examples
    --------
    >>> p = np.full((4, 6), 1 / 24)
    >>> downsample_belief(p, 2)
    array([[0.25, 0.25],
           [0.25, 0.25]])
    """
    p = np.asarray(posterior, dtype=np.float64)
    if p.ndim != 2:
        raise ValueError(f"posterior must be an (H, W) map, got shape {p.shape}")
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 1:
        raise ValueError(f"size must be an integer >= 1, got {size!r}")
    if not np.all(np.isfinite(p)) or np.any(p < 0):
        raise ValueError("posterior must be finite and non-negative")
    h, w = p.shape
    rows = (np.arange(h) * size) // h
    cols = (np.arange(w) * size) // w
    blocks = (rows[:, None] * size + cols[None, :]).ravel()
    return np.bincount(blocks, weights=p.ravel(), minlength=size * size).reshape(size, size)


@dataclass(frozen=True)
class Candidates:
    """The candidate stops of one decision, in slot order.

    Attributes
    ----------
    cells : (K,) ndarray of int
        Flat cells, K ≤ the number of slots.
    drive : (K,) ndarray
        Geodesic distances from the robot, m.
    p_found : (K,) ndarray
        P_f: the probability of finding the source at the stop under the robot's detection model
        (:meth:`psgsl_pgm.search.DetectionModel.found_probability`).
    pred : (H·W,) ndarray
        Dijkstra predecessors from the robot's cell (:meth:`psgsl_pgm.search.FreeSpace.path`).
    table : (N, 5) ndarray of float32
        One row per slot, :data:`CANDIDATE_FEATURES`: dx, dy (the stop minus the robot's position, over the map's
        diagonal L), the drive over L, P_f, and 1 (0 on the rows of empty slots, all zero).
    mask : (N,) ndarray of bool
        Which slots hold a candidate (the first K).
    """

    cells: np.ndarray
    drive: np.ndarray
    p_found: np.ndarray
    pred: np.ndarray
    table: np.ndarray
    mask: np.ndarray


def candidate_table(situation, *, slots: int) -> Candidates:
    """The candidates of ``situation`` (a :class:`psgsl_pgm.search.Situation`), ranked and cut to ``slots``.

    The rank is P_f / τ, τ = d/v + t_sense the time to drive there and read (s): the candidates with the most
    probability of finding the source per second come first, ties in the planner's order (near lattice first).
    The first ``slots`` of them fill the slots.

    Parameters
    ----------
    situation : Situation
    slots : int, keyword-only
        N, the number of slots.

    Returns
    -------
    Candidates

    Examples
    --------
    The situation of a closed-loop episode after its first stop:

    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.gym import candidate_table
    >>> from psgsl_pgm.search._stepper import ClosedLoopEpisode
    >>> episode = ClosedLoopEpisode("oven", 0, None, "semantics+rooms", config=ExperimentConfig(warm_up=5.0))
    >>> episode.take(episode.first_move())
    >>> c = candidate_table(episode.situation(), slots=4)
    >>> c.table.shape, c.mask.tolist()                          # one row of features per slot, all filled
    ((4, 5), [True, True, True, True])
    """
    sit = situation
    space = sit.space
    cells, drive, pred = space.candidates(sit.cell, sit.horizon, sit.far_spacing)
    xy = space.position(cells)
    rows = sit.detection.cell_rows(cells, xy)
    p_f = np.asarray(sit.detection.found_probability(sit.posterior, rows), dtype=np.float64)
    tau = drive / sit.speed + sit.sense_time
    order = np.argsort(-(p_f / tau), kind="stable")[:slots]
    cells, drive, p_f, xy = cells[order], drive[order], p_f[order], xy[order]
    extent = np.asarray(space.nav.shape, dtype=np.float64) * space.resolution
    diag = float(np.hypot(*extent))
    here = space.position(sit.cell)
    table = np.zeros((slots, len(CANDIDATE_FEATURES)), dtype=np.float32)
    k = len(cells)
    table[:k, 0:2] = (xy - here[None]) / diag
    table[:k, 2] = drive / diag
    table[:k, 3] = p_f
    table[:k, 4] = 1.0
    mask = np.zeros(slots, dtype=bool)
    mask[:k] = True
    return Candidates(np.asarray(cells), np.asarray(drive, dtype=np.float64), p_f, pred, table, mask)
