"""Resampling a fine map (e.g. a 1 cm ROS map) and its room labels to a coarser working resolution."""

from __future__ import annotations

import numpy as np

from ..geometry._grid import GridMap, block_mean

__all__ = ["coarsen_factor", "coarsen_labels", "coarsen_occupancy"]


def coarsen_factor(fine: float, coarse: float, *, where: str = "resolution") -> int:
    """The integer block size turning cells of ``fine`` metres into cells of ``coarse`` metres.

    Raises
    ------
    ValueError
        ``coarse`` is finer than ``fine`` or not an integer multiple of it (relative tolerance 1e-6).
    """
    ratio = coarse / fine
    factor = int(round(ratio))
    if factor < 1 or abs(ratio - factor) > 1e-6 * ratio:
        raise ValueError(f"{where}: a working resolution of {coarse:g} m must be a whole multiple (1, 2, ...) of the "
                         f"map's {fine:g} m cells, got {ratio:g} times")
    return factor


def coarsen_occupancy(grid: GridMap, factor: int) -> GridMap:
    """Block-reduce: a coarse cell is occupied when ANY of its fine cells is (thin walls stay closed).

    Rows/columns that do not fill a whole block are padded as occupied. Same origin, resolution × factor.
    """
    if factor == 1:
        return grid
    return grid.coarsen(factor, occupied_fraction="any")


def coarsen_labels(labels: np.ndarray, n_labels: int, factor: int) -> np.ndarray:
    """Block-reduce integer labels (-1 = none, 0..n_labels-1) by majority: the most frequent label of the block.

    "No room" (-1) takes part in the vote, so a block that is mostly outside every room stays -1; ties go to
    the lower label (-1 first). Cost: one block sum per label, O(n_labels · H · W), no loop over cells.

    Returns
    -------
    (ceil(H / factor), ceil(W / factor)) ndarray of int64
    """
    lab = np.asarray(labels)
    if factor == 1:
        return lab.astype(np.int64)
    votes = np.stack([block_mean((lab == k).astype(np.float64), factor, pad_value=1.0 if k == -1 else 0.0)
                      for k in range(-1, n_labels)])
    return votes.argmax(axis=0).astype(np.int64) - 1
